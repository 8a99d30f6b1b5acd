// The scene-file parser under fuzzing (parseCanopyScene; docs/scene-files.md): any bytes either
// are refused with a message naming the file, or give a scene the renderer can trust. Built into
// canopy_scene_fuzz (libFuzzer, ASan + UBSan) by scripts/fuzz.sh scene.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>

#include <canopy/canopy.h>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace canopy;
  CanopyScene scene;
  const Status s = parseCanopyScene("fuzz.json", std::string(reinterpret_cast<const char*>(data), size), "scenes", &scene);
  if (!s.ok()) {
    if (s.message().rfind("'fuzz.json': ", 0) != 0 || !scene.species.empty() || !scene.instances.empty()) __builtin_trap();
    return 0;
  }
  if (scene.species.empty() || scene.species.size() > kMaxSceneSpecies || scene.instances.empty() ||
      scene.instances.size() > kMaxSceneInstances)
    __builtin_trap();
  for (const CanopySceneSpecies& sp : scene.species)
    if (sp.name.empty() || sp.gltf.empty() == sp.generated.empty() || !(sp.flexibility >= 0.0f && sp.flexibility <= 4.0f) ||
        !(sp.responseSpeed >= 0.25f && sp.responseSpeed <= 4.0f))
      __builtin_trap();
  for (const CanopySceneInstance& c : scene.instances) {
    if (c.species >= scene.species.size()) __builtin_trap();
    for (float v : c.placement.transform.m)
      if (!std::isfinite(v)) __builtin_trap();
  }
  return 0;
}
