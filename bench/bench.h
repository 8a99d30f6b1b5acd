#pragma once
#include <cstdint>
#include <vector>

namespace canopy {
struct Device;
namespace bench {
int runSimBench(Device& dev, const std::vector<uint32_t>& sizes, int frames, bool detail);
}
}  // namespace canopy
