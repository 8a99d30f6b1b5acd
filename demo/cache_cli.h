#pragma once
// The cache options canopy-demo and canopy-layers share (docs/design.md "Files"): by default the
// caches go to the user's cache folder ($XDG_CACHE_HOME/canopy, else ~/.cache/canopy); nothing is
// written beside a model unless --cache-beside-model asks for it.
#include <sys/stat.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <string>

#include <canopy/canopy.h>

#include "demo/cli.h"
#include "engine/files.h"
#include "engine/status.h"

namespace canopy::cli {

struct CacheOptions {
  std::string dir;           // --cache-dir; empty: the user's cache folder
  bool besideModel = false;  // --cache-beside-model
  bool off = false;          // --no-cache
  bool clear = false;        // --clear-cache
  uint32_t maxMiB = 2048;    // --cache-max-mib (CanopyDesc.cacheMaxBytes; 0: no cap)
};

inline const char* cacheHelp() {
  return "  --cache-dir DIR     keep the leaf-root and impostor-view caches in DIR (created 0700 if missing;\n"
         "                      default: $XDG_CACHE_HOME/canopy, else ~/.cache/canopy)\n"
         "  --cache-beside-model  keep them beside the model instead (MODEL.leafroots, MODEL.impostors)\n"
         "  --no-cache          neither read nor write a cache\n"
         "  --cache-max-mib N   cap of the cache folder, MiB, [0, 1048576]; least recently used caches beyond it\n"
         "                      are removed (0: no cap; default 2048)\n"
         "  --clear-cache       remove Canopy's cache files from the cache folder the options above select, and exit\n";
}

// Takes argv[*i] if it is a cache option (advancing *i past its value): 1 taken, 0 not a cache
// option, -1 a bad value (the reason in *why).
inline int parseCacheOption(int argc, char** argv, int* i, CacheOptions* o, std::string* why) {
  const std::string a = argv[*i];
  const char* v = *i + 1 < argc ? argv[*i + 1] : nullptr;
  if (a == "--cache-dir") {
    if (!v || !*v) {
      *why = "--cache-dir needs a folder";
      return -1;
    }
    o->dir = v;
    ++*i;
  } else if (a == "--cache-beside-model") {
    o->besideModel = true;
  } else if (a == "--no-cache") {
    o->off = true;
  } else if (a == "--clear-cache") {
    o->clear = true;
  } else if (a == "--cache-max-mib") {
    if (!parseUint(v, 0, 1u << 20, &o->maxMiB)) {
      *why = "--cache-max-mib needs a whole number of MiB in [0, 1048576]";
      return -1;
    }
    ++*i;
  } else {
    return 0;
  }
  return 1;
}

// mkdir -p with mode 0700 for every folder it creates.
inline Status makePrivateFolder(const std::string& dir) {
  for (size_t at = 1; at <= dir.size(); ++at) {
    if (at < dir.size() && dir[at] != '/') continue;
    const std::string part = dir.substr(0, at);
    if (::mkdir(part.c_str(), 0700) != 0 && errno != EEXIST)
      return Status::error(Result::FileError, "cannot create the cache folder '" + part + "': " + std::strerror(errno));
  }
  struct stat st;
  if (::stat(dir.c_str(), &st) != 0 || !S_ISDIR(st.st_mode))
    return Status::error(Result::FileError, "the cache folder '" + dir + "' is not a folder");
  return Status();
}

// The folder the options select for `modelPath` ("" with --no-cache or for a generated scene).
// An error says why no cache can be used; the caller runs without one.
inline Status resolveCacheFolder(const CacheOptions& o, const std::string& modelPath, std::string* folder) {
  folder->clear();
  if (o.off) return Status();
  if (o.besideModel) {
    if (!modelPath.empty()) *folder = parentFolder(modelPath);
    return Status();
  }
  if (!o.dir.empty()) {
    CANOPY_TRY(makePrivateFolder(o.dir));
    *folder = o.dir;
    return Status();
  }
  return userCacheFolder(folder);
}

// --clear-cache: one line saying what was removed from where; the exit code.
inline int clearCacheCommand(const char* program, const CacheOptions& o, const std::string& modelPath) {
  std::string folder;
  Status s = resolveCacheFolder(o, modelPath, &folder);
  if (s.ok() && folder.empty()) s = Status::error("--clear-cache: no cache folder is selected (--no-cache, or --cache-beside-model without a model)");
  uint64_t files = 0, bytes = 0;
  if (s.ok()) s = clearCacheFolder(folder, &files, &bytes);
  if (!s.ok()) {
    std::fprintf(stderr, "%s: %s\n", program, s.message().c_str());
    return 1;
  }
  std::printf("removed %llu cache files (%.1f MiB) from %s\n", (unsigned long long)files, double(bytes) / double(1 << 20),
              folder.c_str());
  return 0;
}

}  // namespace canopy::cli
