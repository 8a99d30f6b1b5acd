#include "render/gltf_files.h"

#include <limits.h>
#include <sys/stat.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>

#include "engine/files.h"

namespace canopy {

// engine/files.h: opened non-blocking, so that a FIFO or a device (also behind a symbolic link)
// is refused by the regular-file check instead of blocking open() or read(); sized before reading.
// The model and its files may be links (checkPath keeps them inside the model's folder).
Status readFile(const std::string& path, uint64_t maxBytes, std::vector<unsigned char>* out) {
  FileReadOptions o;
  o.maxBytes = maxBytes;
  return readWholeFile(path, o, out);
}

// External URIs resolve only to regular files inside the model's folder: no absolute paths, no
// ".." escapes (also through symbolic links), no directories (tinygltf 2.7.0 would try to read one
// as a ~2^63-byte file).

bool checkPath(FsContext& c, const std::string& path) {
  std::string rel = path;
  if (!c.baseDir.empty()) {
    const std::string prefix = c.baseDir.back() == '/' ? c.baseDir : c.baseDir + "/";
    if (path.compare(0, prefix.size(), prefix) != 0) {
      // tinygltf retries each URI relative to "." after the model's folder: refuse, but keep the
      // reason given for the model-relative attempt.
      if (c.lastError.empty()) c.lastError = "'" + path + "' is outside the model's folder";
      return false;
    }
    rel = path.substr(prefix.size());
  }
  if (rel.empty()) {
    c.lastError = "an empty URI names no file";
    return false;
  }
  if (rel[0] == '/' || rel[0] == '\\' || (rel.size() > 1 && rel[1] == ':')) {
    c.lastError = "URI '" + rel + "' is an absolute path (only paths relative to the model are allowed)";
    return false;
  }
  int depth = 0;
  size_t start = 0;
  while (start <= rel.size()) {
    size_t end = rel.find_first_of("/\\", start);
    if (end == std::string::npos) end = rel.size();
    const std::string seg = rel.substr(start, end - start);
    if (seg == "..") {
      if (--depth < 0) {
        c.lastError = "URI '" + rel + "' leaves the model's folder";
        return false;
      }
    } else if (!seg.empty() && seg != ".") {
      ++depth;
    }
    start = end + 1;
  }
  if (c.memory) {
    if (c.memory->count(rel)) return true;
    c.lastError = "URI '" + rel + "': no such file";
    return false;
  }
  char resolved[PATH_MAX];
  if (!realpath(path.c_str(), resolved)) {
    c.lastError = "URI '" + rel + "': " + std::strerror(errno);
    return false;
  }
  const std::string real = resolved;
  if (real.compare(0, c.realBase.size() + 1, c.realBase + "/") != 0) {
    c.lastError = "URI '" + rel + "' resolves outside the model's folder";
    return false;
  }
  struct stat st;
  if (stat(resolved, &st) != 0 || !S_ISREG(st.st_mode)) {
    c.lastError = "URI '" + rel + "' is not a regular file";
    return false;
  }
  return true;
}

bool fsFileExists(const std::string& path, void* user) { return checkPath(*static_cast<FsContext*>(user), path); }
std::string fsExpand(const std::string& path, void*) { return path; }  // no ~ or $VAR expansion
bool fsRead(std::vector<unsigned char>* out, std::string* err, const std::string& path, void* user) {
  FsContext& c = *static_cast<FsContext*>(user);
  if (!checkPath(c, path)) {
    if (err) *err += c.lastError + "\n";
    return false;
  }
  Status s;
  if (c.memory) {
    const std::vector<unsigned char>& bytes = c.memory->at(c.baseDir.empty() ? path : path.substr(c.baseDir.size() + 1));
    if (bytes.size() > c.maxBytes) s = Status::error("file of " + std::to_string(bytes.size()) + " bytes exceeds the limit of " + std::to_string(c.maxBytes));
    else *out = bytes;
  } else {
    s = readFile(path, c.maxBytes, out);
  }
  if (!s.ok()) {
    c.lastError = "'" + path + "': " + s.message();
    if (err) *err += c.lastError + "\n";
    return false;
  }
  return true;
}
bool fsWrite(std::string*, const std::string&, const std::vector<unsigned char>&, void*) { return false; }

}  // namespace canopy
