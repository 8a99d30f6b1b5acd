#include "render/cache_file.h"

#include <dirent.h>
#include <fcntl.h>
#include <limits.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstddef>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>

#include <canopy/canopy_core.h>

#include "engine/files.h"
#include "engine/hash.h"

namespace canopy {
namespace {

constexpr uint64_t kChecksumSeed = 0x243f6a8885a308d3ull;
constexpr int64_t kStaleTemporarySeconds = 3600;

uint64_t payloadChecksum(const void* data, uint64_t bytes) { return hashBytes(kChecksumSeed ^ 1, data, size_t(bytes)); }

std::string versionText(uint32_t v) {
  return std::to_string(v >> 22) + "." + std::to_string((v >> 12) & 0x3ff) + "." + std::to_string(v & 0xfff);
}

const char* kindName(uint32_t kind) {
  switch (kind) {
    case uint32_t(CacheKind::LeafRoots): return "leaf-root";
    case uint32_t(CacheKind::ImpostorViews): return "impostor-view";
    default: return "unknown";
  }
}

bool endsWith(const std::string& s, const std::string& tail) {
  return s.size() >= tail.size() && s.compare(s.size() - tail.size(), tail.size(), tail) == 0;
}

// A cache file's name, or a temporary of one ("<cache name>.tmp-...", engine/files.cpp).
bool isCacheName(const std::string& n) {
  return endsWith(n, ".leafroots") || endsWith(n, ".impostors");
}
bool isCacheTemporary(const std::string& n) {
  return n.find(".leafroots.tmp") != std::string::npos || n.find(".impostors.tmp") != std::string::npos;
}

// The path with links, "." and ".." resolved; for a name that does not exist (yet), its folder's.
std::string canonical(const std::string& path) {
  char resolved[PATH_MAX];
  if (realpath(path.c_str(), resolved)) return resolved;
  if (realpath(parentFolder(path).c_str(), resolved)) return std::string(resolved) + "/" + fileNameOf(path);
  if (!path.empty() && path[0] == '/') return path;
  char cwd[PATH_MAX];
  return getcwd(cwd, sizeof cwd) ? std::string(cwd) + "/" + path : path;
}

struct Entry {
  std::string name;
  uint64_t bytes = 0;
  struct timespec used {};
  bool regular = false;
  bool temporary = false;
};

// Canopy's entries of the folder (cache names and their temporaries; not directories).
Status listEntries(const std::string& folder, std::vector<Entry>* out) {
  out->clear();
  DIR* dir = ::opendir(folder.c_str());
  if (!dir) return Status::error(Result::FileError, "cache folder '" + folder + "': " + std::strerror(errno));
  const int dfd = ::dirfd(dir);
  while (const dirent* e = ::readdir(dir)) {
    const std::string n = e->d_name;
    const bool temporary = isCacheTemporary(n);
    if (!temporary && !isCacheName(n)) continue;
    struct stat st;
    if (::fstatat(dfd, n.c_str(), &st, AT_SYMLINK_NOFOLLOW) != 0 || S_ISDIR(st.st_mode)) continue;
    Entry en;
    en.name = n;
    en.regular = S_ISREG(st.st_mode);
    en.bytes = en.regular ? uint64_t(st.st_size) : 0;
    en.used = st.st_mtim;
    en.temporary = temporary;
    out->push_back(std::move(en));
  }
  ::closedir(dir);
  return Status();
}

bool removeEntry(const std::string& folder, const Entry& e, CacheFolderUsage* removed) {
  if (::unlink((folder + "/" + e.name).c_str()) != 0) return false;
  if (removed) {
    removed->files++;
    removed->bytes += e.bytes;
  }
  return true;
}

std::string mib(uint64_t bytes) {
  char b[32];
  std::snprintf(b, sizeof b, "%.1f MiB", double(bytes) / double(1 << 20));
  return b;
}

}  // namespace

uint64_t cacheHeaderChecksum(const CacheHeader& h) { return hashBytes(kChecksumSeed, &h, offsetof(CacheHeader, headerChecksum)); }

const char* cacheSuffix(CacheKind kind) { return kind == CacheKind::LeafRoots ? ".leafroots" : ".impostors"; }

std::string cacheFilePath(const std::string& modelPath, const std::string& folder, CacheKind kind) {
  const std::string model = canonical(modelPath);
  const std::string name = fileNameOf(model);
  if (canonical(folder) == parentFolder(model)) return folder + "/" + name + cacheSuffix(kind);
  char tag[24];
  std::snprintf(tag, sizeof tag, "-%016llx", (unsigned long long)hashBytes(0x13198a2e03707344ull, model.data(), model.size()));
  return folder + "/" + name + tag + cacheSuffix(kind);
}

bool readCacheFile(const std::string& path, CacheKind kind, uint64_t key, uint64_t payloadBytes, std::vector<uint8_t>* payload,
                   std::string* why) {
  payload->clear();
  OpenedFile f;
  FileReadOptions o;
  o.maxBytes = UINT64_MAX;  // sized against the header below, before anything is allocated
  o.followFinalLink = false;
  Status s = openFileForRead(path, o, &f);
  if (!s.ok()) {
    *why = s.message() == "cannot open: " + std::string(std::strerror(ENOENT)) ? "no cache file" : s.message();
    return false;
  }
  if (f.owner != uint32_t(::geteuid())) {
    *why = "owned by another user (uid " + std::to_string(f.owner) + "), not used";
    return false;
  }
  if (f.size < kCacheHeaderBytes) {
    *why = "truncated: " + std::to_string(f.size) + " bytes, shorter than the header";
    return false;
  }
  CacheHeader h;
  if (!(s = readExact(f, &h, sizeof h)).ok()) {
    *why = s.message();
    return false;
  }
  if (std::memcmp(h.magic, kCacheMagic, 8) != 0) {
    *why = "not a Canopy cache of this format (an older Canopy's file or another file)";
    return false;
  }
  if (h.headerChecksum != cacheHeaderChecksum(h)) {
    *why = "damaged: the header's checksum does not match";
    return false;
  }
  if (h.format != kCacheFormat || h.headerBytes != kCacheHeaderBytes) {
    *why = "format version " + std::to_string(h.format) + ", this Canopy reads " + std::to_string(kCacheFormat);
    return false;
  }
  if (h.canopyVersion != libraryVersion()) {
    *why = "made by Canopy " + versionText(h.canopyVersion) + ", this is " + versionText(libraryVersion());
    return false;
  }
  if (h.kind != uint32_t(kind)) {
    *why = std::string("a ") + kindName(h.kind) + " cache, not a " + kindName(uint32_t(kind)) + " cache";
    return false;
  }
  if (h.key != key || h.payloadBytes != payloadBytes) {
    *why = "made for other data (model, options, shaders or lighting changed)";
    return false;
  }
  const uint64_t expected = kCacheHeaderBytes + payloadBytes;
  if (f.size != expected) {
    *why = std::string(f.size < expected ? "truncated" : "oversized") + ": " + std::to_string(f.size) + " bytes, the header says " +
           std::to_string(expected);
    return false;
  }
  try {
    payload->resize(size_t(payloadBytes));
  } catch (const std::bad_alloc&) {
    *why = "no host memory for its " + std::to_string(payloadBytes) + " bytes";
    return false;
  }
  if (!(s = readExact(f, payload->data(), payload->size())).ok()) {
    payload->clear();
    *why = s.message();
    return false;
  }
  if (payloadChecksum(payload->data(), payloadBytes) != h.payloadChecksum) {
    payload->clear();
    *why = "damaged: the contents' checksum does not match";
    return false;
  }
  touchFile(f);
  return true;
}

Status writeCacheFile(const std::string& path, CacheKind kind, uint64_t key, const void* payload, uint64_t payloadBytes,
                      uint64_t capBytes, std::string* note) {
  if (capBytes && kCacheHeaderBytes + payloadBytes > capBytes)
    return Status::error(Result::FileError, "'" + path + "' (" + mib(kCacheHeaderBytes + payloadBytes) +
                                                ") would exceed the cache cap of " + mib(capBytes) + " by itself");
  CacheHeader h{};
  std::memcpy(h.magic, kCacheMagic, 8);
  h.format = kCacheFormat;
  h.kind = uint32_t(kind);
  h.canopyVersion = libraryVersion();
  h.headerBytes = uint32_t(kCacheHeaderBytes);
  h.key = key;
  h.payloadBytes = payloadBytes;
  h.payloadChecksum = payloadChecksum(payload, payloadBytes);
  h.headerChecksum = cacheHeaderChecksum(h);
  CANOPY_TRY(writeFileAtomically(path, {{&h, sizeof h}, {payload, size_t(payloadBytes)}}));
  if (capBytes) {
    CacheFolderUsage removed;
    const Status s = evictCacheFolder(parentFolder(path), capBytes, fileNameOf(path), &removed);
    if (note && removed.files)
      *note = "evicted " + std::to_string(removed.files) + " least recently used cache files (" + mib(removed.bytes) + ")";
    if (note && !s.ok()) *note = s.message();
  }
  return Status();
}

CacheFolderUsage cacheFolderUsage(const std::string& folder) {
  CacheFolderUsage u;
  std::vector<Entry> entries;
  if (!listEntries(folder, &entries).ok()) return u;
  for (const Entry& e : entries)
    if (e.regular && !e.temporary) {
      u.files++;
      u.bytes += e.bytes;
    }
  return u;
}

Status evictCacheFolder(const std::string& folder, uint64_t capBytes, const std::string& keepName, CacheFolderUsage* removed) {
  std::vector<Entry> entries;
  CANOPY_TRY(listEntries(folder, &entries));
  const int64_t now = int64_t(::time(nullptr));
  uint64_t total = 0;
  std::vector<const Entry*> caches;
  for (const Entry& e : entries) {
    if (e.temporary) {
      if (e.regular && now - int64_t(e.used.tv_sec) > kStaleTemporarySeconds) removeEntry(folder, e, removed);
      continue;
    }
    if (!e.regular) continue;
    total += e.bytes;
    if (e.name != keepName) caches.push_back(&e);
  }
  if (!capBytes || total <= capBytes) return Status();
  std::sort(caches.begin(), caches.end(), [](const Entry* a, const Entry* b) {
    return a->used.tv_sec != b->used.tv_sec ? a->used.tv_sec < b->used.tv_sec : a->used.tv_nsec < b->used.tv_nsec;
  });
  for (const Entry* e : caches) {
    if (total <= capBytes) break;
    if (removeEntry(folder, *e, removed)) total -= e->bytes;
  }
  return Status();
}

Status clearCacheFolder(const std::string& folder, CacheFolderUsage* removed) {
  std::vector<Entry> entries;
  CANOPY_TRY(listEntries(folder, &entries));
  for (const Entry& e : entries)
    if (!removeEntry(folder, e, removed))
      return Status::error(Result::FileError, "cannot remove '" + folder + "/" + e.name + "': " + std::strerror(errno));
  return Status();
}

Status clearCacheFolder(const std::string& folder, uint64_t* removedFiles, uint64_t* removedBytes) {
  try {
    CacheFolderUsage removed;
    const Status s = clearCacheFolder(folder, &removed);
    if (removedFiles) *removedFiles = removed.files;
    if (removedBytes) *removedBytes = removed.bytes;
    return s;
  } catch (const std::bad_alloc&) {
    return Status::error(Result::OutOfHostMemory, "clearCacheFolder: out of host memory");
  }
}

Status userCacheFolder(std::string* folder) {
  if (!folder) return Status::error(Result::InvalidArgument, "userCacheFolder: folder is null");
  folder->clear();
  try {
    // The XDG base directory rule: $XDG_CACHE_HOME if set to an absolute path, else $HOME/.cache.
    const char* xdg = std::getenv("XDG_CACHE_HOME");
    const char* home = std::getenv("HOME");
    std::string base;
    if (xdg && xdg[0] == '/') base = xdg;
    else if (home && home[0] == '/') base = std::string(home) + "/.cache";
    else
      return Status::error(Result::FileError, "no user cache folder: neither XDG_CACHE_HOME nor HOME is an absolute path");
    const std::string dir = base + "/canopy";
    for (const std::string& d : {base, dir}) {
      if (::mkdir(d.c_str(), 0700) != 0 && errno != EEXIST)
        return Status::error(Result::FileError, "cannot create the cache folder '" + d + "': " + std::strerror(errno));
    }
    // Canopy's own folder must be a real folder of this user: a link or another user's folder is
    // not used (XDG: the folder is created with mode 0700).
    struct stat st;
    if (::lstat(dir.c_str(), &st) != 0)
      return Status::error(Result::FileError, "cache folder '" + dir + "': " + std::strerror(errno));
    if (!S_ISDIR(st.st_mode))
      return Status::error(Result::FileError, "cache folder '" + dir + "' is not a folder (a link or a file): not used");
    if (st.st_uid != ::geteuid())
      return Status::error(Result::FileError, "cache folder '" + dir + "' belongs to uid " + std::to_string(st.st_uid) + ": not used");
    *folder = dir;
    return Status();
  } catch (const std::bad_alloc&) {
    return Status::error(Result::OutOfHostMemory, "userCacheFolder: out of host memory");
  }
}

}  // namespace canopy
