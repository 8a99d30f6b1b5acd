#pragma once
// The one way Canopy opens a file (docs/design.md "Files"). Reading is non-blocking and accepts
// only a regular file whose size is bounded before anything is allocated, so a FIFO, a device or a
// directory planted at a name is refused at once instead of hanging or being read as garbage;
// where the file must be Canopy's own (a cache), a final symbolic link is refused too. Writing
// never opens an existing name: it creates a new temporary file beside the target (exclusive,
// no-follow create, unique name, mode 0600), writes, flushes and renames it over the target, so a
// link planted at the target or at any temporary name is replaced, never followed, and a failure
// leaves no partial file. POSIX only (Linux).
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "engine/status.h"

namespace canopy {

struct FileReadOptions {
  uint64_t maxBytes = 0;        // larger files are refused before any allocation
  bool followFinalLink = true;  // false: a symbolic link at the path is refused (Canopy's own files)
};

// A regular file opened for reading (closed by the destructor).
struct OpenedFile {
  int fd = -1;
  uint64_t size = 0;       // at open time
  uint32_t owner = 0;      // st_uid
  OpenedFile() = default;
  OpenedFile(const OpenedFile&) = delete;
  OpenedFile& operator=(const OpenedFile&) = delete;
  ~OpenedFile();
};

// Opens `path` for reading under `options` (maxBytes included). The error names the reason only
// ("no such file", "a symbolic link", "a FIFO, not a regular file", ...); callers add the path.
// Result::FileError for every refusal.
Status openFileForRead(const std::string& path, const FileReadOptions& options, OpenedFile* out);
// Reads exactly `bytes` from the current position; a short file is an error.
Status readExact(OpenedFile& file, void* data, size_t bytes);
// openFileForRead + the whole file into `out`.
Status readWholeFile(const std::string& path, const FileReadOptions& options, std::vector<unsigned char>* out);
// Sets the file's access and modification times to now (a cache's last use; errors ignored).
void touchFile(OpenedFile& file);

struct ByteSpan {
  const void* data = nullptr;
  size_t size = 0;
};

// Writes the spans, in order, to `path` as described above. The error names the path and the
// reason (the errno text and how far it got); nothing is left behind on failure, and whatever was
// at `path` before stays as it was.
Status writeFileAtomically(const std::string& path, const std::vector<ByteSpan>& parts);

// The folder part of a path ("." for a bare name) and the last component.
std::string parentFolder(const std::string& path);
std::string fileNameOf(const std::string& path);

}  // namespace canopy
