#include "engine/files.h"

#include <fcntl.h>
#include <sys/random.h>
#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <ctime>

namespace canopy {
namespace {

std::string errnoText(int e) { return std::strerror(e); }

const char* kindOf(mode_t mode) {
  if (S_ISDIR(mode)) return "a directory";
  if (S_ISFIFO(mode)) return "a FIFO";
  if (S_ISCHR(mode)) return "a character device";
  if (S_ISBLK(mode)) return "a block device";
  if (S_ISSOCK(mode)) return "a socket";
  if (S_ISLNK(mode)) return "a symbolic link";
  return "not a plain file";
}

// A name no other writer uses: the process, a counter and 64 random bits.
std::string temporaryName(const std::string& name) {
  static std::atomic_uint64_t counter{0};
  uint64_t r = 0;
  if (getrandom(&r, sizeof r, GRND_NONBLOCK) != ssize_t(sizeof r)) r = uint64_t(uintptr_t(&r)) ^ uint64_t(::time(nullptr));
  char tail[64];
  std::snprintf(tail, sizeof tail, ".tmp-%d-%llu-%016llx", int(::getpid()), (unsigned long long)counter++,
                (unsigned long long)r);
  return name + tail;
}

struct Fd {
  int fd = -1;
  ~Fd() {
    if (fd >= 0) ::close(fd);
  }
};

}  // namespace

OpenedFile::~OpenedFile() {
  if (fd >= 0) ::close(fd);
}

Status openFileForRead(const std::string& path, const FileReadOptions& o, OpenedFile* out) {
  if (out->fd >= 0) ::close(out->fd);
  out->fd = -1;
  // Non-blocking: opening a FIFO for reading returns at once (and is refused below) instead of
  // waiting for a writer; regular files ignore the flag.
  int flags = O_RDONLY | O_CLOEXEC | O_NONBLOCK | O_NOCTTY;
  if (!o.followFinalLink) flags |= O_NOFOLLOW;
  const int fd = ::open(path.c_str(), flags);
  if (fd < 0) {
    const int e = errno;
    struct stat st;
    if (e == ELOOP && !o.followFinalLink && ::lstat(path.c_str(), &st) == 0 && S_ISLNK(st.st_mode))
      return Status::error(Result::FileError, "a symbolic link (not followed: only a file Canopy wrote is read here)");
    return Status::error(Result::FileError, "cannot open: " + errnoText(e));
  }
  out->fd = fd;
  struct stat st;
  if (::fstat(fd, &st) != 0) return Status::error(Result::FileError, "cannot stat: " + errnoText(errno));
  if (!S_ISREG(st.st_mode)) return Status::error(Result::FileError, std::string("not a regular file (") + kindOf(st.st_mode) + ")");
  out->size = uint64_t(st.st_size);
  out->owner = uint32_t(st.st_uid);
  if (out->size > o.maxBytes)
    return Status::error(Result::FileError, "file of " + std::to_string(out->size) + " bytes exceeds the limit of " +
                                                std::to_string(o.maxBytes));
  return Status();
}

Status readExact(OpenedFile& f, void* data, size_t bytes) {
  size_t got = 0;
  while (got < bytes) {
    const ssize_t r = ::read(f.fd, static_cast<char*>(data) + got, bytes - got);
    if (r < 0 && errno == EINTR) continue;
    if (r < 0) return Status::error(Result::FileError, "read error: " + errnoText(errno));
    if (r == 0) return Status::error(Result::FileError, "the file shrank while being read");
    got += size_t(r);
  }
  return Status();
}

Status readWholeFile(const std::string& path, const FileReadOptions& o, std::vector<unsigned char>* out) {
  out->clear();
  OpenedFile f;
  CANOPY_TRY(openFileForRead(path, o, &f));
  out->resize(size_t(f.size));
  Status s = readExact(f, out->data(), out->size());
  if (!s.ok()) out->clear();
  return s;
}

void touchFile(OpenedFile& f) {
  if (f.fd >= 0) (void)::futimens(f.fd, nullptr);
}

std::string parentFolder(const std::string& path) {
  const size_t slash = path.find_last_of('/');
  if (slash == std::string::npos) return ".";
  return slash == 0 ? "/" : path.substr(0, slash);
}

std::string fileNameOf(const std::string& path) {
  const size_t slash = path.find_last_of('/');
  return slash == std::string::npos ? path : path.substr(slash + 1);
}

Status writeFileAtomically(const std::string& path, const std::vector<ByteSpan>& parts) {
  const std::string folder = parentFolder(path), name = fileNameOf(path);
  auto fail = [&](const std::string& why) { return Status::error(Result::FileError, "cannot write '" + path + "': " + why); };
  if (name.empty() || name == "." || name == "..") return fail("not a file name");
  // Everything is done relative to the folder opened once, so the temporary file and the rename
  // stay in the same folder even if its path is changed meanwhile.
  Fd dir;
  dir.fd = ::open(folder.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (dir.fd < 0) return fail("its folder '" + folder + "': " + errnoText(errno));
  std::string tmp;
  Fd file;
  for (int attempt = 0; attempt < 16 && file.fd < 0; ++attempt) {
    tmp = temporaryName(name);
    // O_EXCL | O_NOFOLLOW: never an existing file, never through a link planted at the name.
    file.fd = ::openat(dir.fd, tmp.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC | O_NOCTTY, 0600);
    if (file.fd < 0 && errno != EEXIST) return fail("cannot create a temporary file in '" + folder + "': " + errnoText(errno));
  }
  if (file.fd < 0) return fail("no unused temporary name in '" + folder + "'");
  uint64_t total = 0, written = 0;
  for (const ByteSpan& p : parts) total += p.size;
  auto abandon = [&](const std::string& why) {
    ::close(file.fd);
    file.fd = -1;
    ::unlinkat(dir.fd, tmp.c_str(), 0);
    return fail(why + " (nothing was left behind)");
  };
  for (const ByteSpan& p : parts) {
    size_t done = 0;
    while (done < p.size) {
      const ssize_t w = ::write(file.fd, static_cast<const char*>(p.data) + done, p.size - done);
      if (w < 0 && errno == EINTR) continue;
      if (w <= 0) {
        const int e = w < 0 ? errno : EIO;
        return abandon(errnoText(e) + " after " + std::to_string(written) + " of " + std::to_string(total) + " bytes");
      }
      done += size_t(w);
      written += uint64_t(w);
    }
  }
  if (::fdatasync(file.fd) != 0) return abandon("flush: " + errnoText(errno));
  const int closed = ::close(file.fd);
  file.fd = -1;
  if (closed != 0) {
    const int e = errno;
    ::unlinkat(dir.fd, tmp.c_str(), 0);
    return fail("close: " + errnoText(e) + " (nothing was left behind)");
  }
  // rename replaces whatever entry has the name (a link or a FIFO is replaced, not followed); a
  // directory there makes it fail.
  if (::renameat(dir.fd, tmp.c_str(), dir.fd, name.c_str()) != 0) {
    const int e = errno;
    ::unlinkat(dir.fd, tmp.c_str(), 0);
    return fail(errnoText(e) + " (nothing was left behind)");
  }
  return Status();
}

}  // namespace canopy
