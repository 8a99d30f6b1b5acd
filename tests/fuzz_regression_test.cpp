// Replays every kept fuzz input (tests/fuzz/regressions: crashes a fuzz run found, and the
// hand-made files of the defect classes fixed at their root) through the fuzz target's own
// harness, under this build's ASan + UBSan: a crash, a sanitizer report or a broken invariant
// fails the run.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <iterator>

#include "tests/fuzz/gltf_fuzz.h"

TEST(FuzzRegressions, EveryKeptInputRunsCleanly) {
  const std::filesystem::path dir = CANOPY_FUZZ_REGRESSIONS;
  ASSERT_TRUE(std::filesystem::is_directory(dir)) << dir;
  int n = 0;
  for (const auto& e : std::filesystem::directory_iterator(dir)) {
    if (!e.is_regular_file()) continue;
    std::ifstream f(e.path(), std::ios::binary);
    const std::string bytes((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
    SCOPED_TRACE(e.path().filename().string());
    EXPECT_EQ(canopy::fuzz::runGltfInput(reinterpret_cast<const uint8_t*>(bytes.data()), bytes.size()), 0);
    ++n;
  }
  std::printf("  %d kept fuzz inputs replayed\n", n);
  EXPECT_GE(n, 6);
}
