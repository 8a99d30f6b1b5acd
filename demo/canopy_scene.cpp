// canopy-scene: generates one of the paper's test scenes (render/scene_generator.h) and prints its
// statistics and hash; with --out also writes it as .glb (loadable by canopy-demo --gltf).
//
//   canopy-scene [--scene shrub|tree|grass|kelp|field] [--faces N] [--seed S] [--texture PX]
//                [--threads T] [--out FILE.glb]
// Exit 0 on success, 1 on a failure, 2 on bad arguments.
#include <chrono>
#include <cstdio>
#include <string>

#include "demo/cli.h"
#include "demo/progress.h"
#include "tools/gltf_writer.h"
#include "tools/scene_generator.h"

using namespace canopy;

namespace {

void usage() {
  std::printf(
      "usage: canopy-scene [options]\n"
      "  --scene NAME   shrub, tree, grass, kelp or field (default shrub)\n"
      "  --faces N      total triangles, %llu..%llu, K/M suffixes allowed (default 80K)\n"
      "  --seed S       random seed, 0..4294967295 (default 1)\n"
      "  --texture PX   leaf texture side, power of two 16..2048 (default 128)\n"
      "  --threads T    worker threads, 0 = all (default 0)\n"
      "  --out FILE     also write the scene as binary glTF (.glb)\n",
      (unsigned long long)kMinSceneFaces, (unsigned long long)kMaxSceneFaces);
}

int fail(const std::string& why) {
  std::fprintf(stderr, "canopy-scene: %s\n", why.c_str());
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  SceneDesc desc;
  std::string out;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    const char* v = i + 1 < argc ? argv[i + 1] : nullptr;
    auto takes = [&]() { return v ? (++i, true) : false; };
    if (a == "--help" || a == "-h") {
      usage();
      return 0;
    } else if (a == "--scene") {
      if (!takes()) return fail("--scene needs a name (shrub, tree, grass, kelp, field)");
      const Status s = parseSceneKind(v, &desc.kind);
      if (!s.ok()) return fail(s.message());
    } else if (a == "--faces") {
      if (!takes() || !cli::parseCount(v, kMinSceneFaces, kMaxSceneFaces, &desc.faces))
        return fail("--faces needs a count in [" + std::to_string(kMinSceneFaces) + ", " + std::to_string(kMaxSceneFaces) + "]");
    } else if (a == "--seed") {
      if (!takes() || !cli::parseUint(v, 0, 0xffffffffull, &desc.seed)) return fail("--seed needs an integer in [0, 4294967295]");
    } else if (a == "--texture") {
      if (!takes() || !cli::parseUint(v, 16, 2048, &desc.textureSize) || (desc.textureSize & (desc.textureSize - 1)))
        return fail("--texture needs a power of two in [16, 2048]");
    } else if (a == "--threads") {
      if (!takes() || !cli::parseUint(v, 0, 1024, &desc.threads)) return fail("--threads needs an integer in [0, 1024]");
    } else if (a == "--out") {
      if (!takes()) return fail("--out needs a file name");
      out = v;
    } else {
      return fail("unknown argument '" + a + "' (see --help)");
    }
  }
  // About 80 bytes per face (render/scene_generator.h; 50M shrub faces peak at 3.9 GB): refuse what
  // cannot fit rather than be ended by the OOM killer, which no bad_alloc reports.
  constexpr uint64_t kPeakBytesPerFace = 90;
  const uint64_t available = cli::availableMemoryBytes();
  if (available > 0 && desc.faces * kPeakBytesPerFace > available) {
    std::fprintf(stderr, "canopy-scene: --faces %llu needs about %llu GiB of memory (about 90 bytes per face); this machine has %llu GiB available\n",
                 (unsigned long long)desc.faces, (unsigned long long)((desc.faces * kPeakBytesPerFace + (1ull << 29)) >> 30),
                 (unsigned long long)((available + (1ull << 29)) >> 30));
    return 1;
  }
  VegetationModel model;
  SceneStats st;
  cli::ProgressLine progress(std::string("generating ") + sceneName(desc.kind));
  const auto t0 = std::chrono::steady_clock::now();
  Status s = generateScene(desc, &model, &st, desc.faces >= 2'000'000 ? SceneProgress(std::ref(progress)) : SceneProgress());
  const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  if (!s.ok()) {
    std::fprintf(stderr, "canopy-scene: %s\n", s.message().c_str());
    return 1;
  }
  std::printf("%s seed %u: %llu faces (requested %llu): %llu rigid, %llu foliage in %llu leaves; %u plants, "
              "L-system depth %u; %zu vertices; generated in %.0f ms; hash %016llx\n",
              sceneName(desc.kind), desc.seed, (unsigned long long)st.faces, (unsigned long long)desc.faces,
              (unsigned long long)st.rigidFaces, (unsigned long long)st.leafFaces, (unsigned long long)st.leaves, st.plants,
              st.lsystemIterations, model.positions.size(), ms, (unsigned long long)modelHash(model));
  if (!out.empty()) {
    s = writeGlb(out, model);
    if (!s.ok()) {
      std::fprintf(stderr, "canopy-scene: %s\n", s.message().c_str());
      return 1;
    }
    std::printf("wrote %s\n", out.c_str());
  }
  return 0;
}
