#pragma once
// The shared assets folder (../shared/assets, never copied into the repository): tests that read
// it skip with a message when it is absent.
#include <filesystem>
#include <string>

namespace canopy::test {
inline const std::string kAssets = CANOPY_SHARED_ASSETS;
}  // namespace canopy::test

#define REQUIRE_ASSETS()                                  \
  if (!std::filesystem::exists(canopy::test::kAssets))    \
  GTEST_SKIP() << "shared assets folder absent (" << canopy::test::kAssets << "): skipped"
