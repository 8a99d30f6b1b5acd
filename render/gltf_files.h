#pragma once
// The files a glTF model names, as the loader lets tinygltf read them (render/gltf_loader.cpp):
// external URIs resolve only to regular files inside the model's folder (no absolute paths, no ".."
// escapes, also through symbolic links, no directories, FIFOs or devices), sized before reading,
// or to files held in memory (loadGltfFromMemory).
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "engine/status.h"

namespace canopy {

// tinygltf's file-system callbacks' context.
struct FsContext {
  std::string baseDir;      // as passed to tinygltf ("" = current folder)
  std::string realBase;     // realpath of it
  uint64_t maxBytes = 0;
  std::string lastError;    // why the last path was refused
  // Files held in memory, by path relative to the model (loadGltfFromMemory): no disk access.
  const std::map<std::string, std::vector<unsigned char>>* memory = nullptr;
};

// A whole regular file of at most `maxBytes` (engine/files.h: opened non-blocking, sized first).
Status readFile(const std::string& path, uint64_t maxBytes, std::vector<unsigned char>* out);
// Whether `path` may be read for the model (c.lastError says why not).
bool checkPath(FsContext& c, const std::string& path);
// tinygltf's FsCallbacks over an FsContext (`user`): exists, expand (none), read, write (refused).
bool fsFileExists(const std::string& path, void* user);
std::string fsExpand(const std::string& path, void*);
bool fsRead(std::vector<unsigned char>* out, std::string* err, const std::string& path, void* user);
bool fsWrite(std::string*, const std::string&, const std::vector<unsigned char>&, void*);

}  // namespace canopy
