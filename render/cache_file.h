#pragma once
// Canopy's cache files: the leaf roots (render/leaf_roots.h) and the impostor views
// (render/impostor_gpu.cpp), docs/design.md "Files". A cache is never trusted: a 64-byte header
// (magic, format version, kind, Canopy's version, the key of everything the contents depend on,
// payload size, payload checksum, header checksum) is checked before the payload is allocated,
// the payload's checksum after it is read, and anything that does not match is ignored (the caller
// rebuilds, saying why). Files are opened through engine/files.h only: no link followed, no FIFO
// waited on, writes by temporary file + rename. The folder is the host's (CanopyDesc.rootCacheDir);
// after each write the least recently used cache files beyond its cap are removed.
#include <cstdint>
#include <string>
#include <vector>

#include "engine/status.h"

namespace canopy {

enum class CacheKind : uint32_t { LeafRoots = 1, ImpostorViews = 2 };

inline constexpr uint32_t kCacheFormat = 2;  // 1: the headerless files before issue 32
inline constexpr uint64_t kCacheHeaderBytes = 64;
inline constexpr char kCacheMagic[8] = {'C', 'N', 'P', 'Y', 'C', 'A', 'C', 'H'};

// A cache file's first 64 bytes, in this machine's byte order (a cache is only ever read where it
// was made, and another order fails the magic or the checksum).
struct CacheHeader {
  char magic[8];             // kCacheMagic
  uint32_t format;           // kCacheFormat
  uint32_t kind;             // CacheKind
  uint32_t canopyVersion;    // libraryVersion() of the writer (CANOPY_MAKE_VERSION)
  uint32_t headerBytes;      // kCacheHeaderBytes
  uint64_t key;              // everything the contents depend on (inputs, options, shaders)
  uint64_t payloadBytes;
  uint64_t payloadChecksum;  // engine/hash.h hashBytes of the payload
  uint64_t reserved;         // 0
  uint64_t headerChecksum;   // cacheHeaderChecksum(): of the 56 bytes before it
};
static_assert(sizeof(CacheHeader) == 64, "the cache header is 64 bytes");
uint64_t cacheHeaderChecksum(const CacheHeader& header);

// ".leafroots" or ".impostors".
const char* cacheSuffix(CacheKind kind);

// Where a model's cache of `kind` lives in `folder`: "<model file name><suffix>" when the folder is
// the model's own (the opt-in beside-the-model location), else "<model file name>-<16 hex digits
// of a hash of the model's canonical path><suffix>", so two models with the same file name in
// different folders never share a cache file.
std::string cacheFilePath(const std::string& modelPath, const std::string& folder, CacheKind kind);

// The payload of the cache at `path` if it was made by this Canopy for `kind` and `key` and holds
// exactly `payloadBytes`; false with the reason otherwise (absent, a link, not a regular file,
// another user's, damaged, truncated, oversized, another version or key). A hit marks the file
// as used now (least-recently-used order).
bool readCacheFile(const std::string& path, CacheKind kind, uint64_t key, uint64_t payloadBytes, std::vector<uint8_t>* payload,
                   std::string* why);

// Writes the cache atomically, then removes the folder's least recently used cache files beyond
// `capBytes` (0: no cap; the file just written stays). A payload over the cap is not written (an
// error saying so). `note` (optional) receives what the eviction removed, if anything.
Status writeCacheFile(const std::string& path, CacheKind kind, uint64_t key, const void* payload, uint64_t payloadBytes,
                      uint64_t capBytes, std::string* note = nullptr);

struct CacheFolderUsage {
  uint64_t files = 0;
  uint64_t bytes = 0;
};
// Canopy's cache files in `folder` (regular files named with a cache suffix; links are not counted).
CacheFolderUsage cacheFolderUsage(const std::string& folder);
// Removes least recently used cache files until those left fit `capBytes`, never `keepName`, and
// temporary files of writes interrupted over an hour ago.
Status evictCacheFolder(const std::string& folder, uint64_t capBytes, const std::string& keepName, CacheFolderUsage* removed);
// Removes every cache file and cache temporary of `folder` (a link or FIFO at such a name too,
// never what a link points to); other files and folders stay.
Status clearCacheFolder(const std::string& folder, CacheFolderUsage* removed);

}  // namespace canopy
