// The foundation's lavapipe test: a 3-pass compute graph (write -> transform -> reduce) recorded
// through the render graph, checked against the CPU reference, validation-clean.
#include <cmath>
#include <cstring>

#include "tools/example_passes.h"
#include "engine/memory.h"
#include "engine/transfer.h"
#include "tests/gpu_test.h"

using namespace canopy;

namespace {

class ComputeGraph : public test::GpuTest, public ::testing::WithParamInterface<std::pair<uint32_t, uint32_t>> {};

}  // namespace

// Tolerances: transformed texels within 1e-6 relative (GPU may fuse gain*v+bias into an fma);
// sum within 1e-5 relative of the double-precision CPU sum (float accumulation over <=1M
// terms in 256 strided partial sums); min/max exact up to 1e-6.
TEST_P(ComputeGraph, WriteTransformReduceMatchesCpu_tol1e5) {
  ExampleParams prm;
  prm.width = GetParam().first;
  prm.height = GetParam().second;
  ExamplePipelines pipes;
  ASSERT_TRUE(createExamplePipelines(dev, &pipes).ok());
  Buffer result;
  ASSERT_TRUE(createBuffer(dev, sizeof(gpu::ExampleResult), VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, MemoryUsage::Readback,
                           &result, "result").ok());
  {
    ExampleGraph eg;
    Status s = buildExampleGraph(dev, pipes, prm, result, &eg);
    ASSERT_TRUE(s.ok()) << s.message();
    // Compiled once, recorded for several frames (the second frame exercises the transient
    // resources' frame-to-frame barriers).
    for (int frame = 0; frame < 3; ++frame) {
      std::memset(result.allocation.mapped, 0, sizeof(gpu::ExampleResult));
      s = submitAndWait(dev, [&](VkCommandBuffer cmd) { return eg.graph.record(cmd); });
      ASSERT_TRUE(s.ok()) << s.message();
      const ExampleReference ref = exampleReference(prm);
      gpu::ExampleResult r;
      std::memcpy(&r, result.allocation.mapped, sizeof r);
      EXPECT_EQ(r.count, prm.width * prm.height);
      EXPECT_NEAR(r.sum, ref.sum, 1e-5 * std::max(1.0, std::fabs(ref.sum)));
      EXPECT_NEAR(r.minValue, ref.minValue, 1e-6);
      EXPECT_NEAR(r.maxValue, ref.maxValue, 1e-6);
    }
    // The intermediate image, read back through a graph-synchronized copy.
    std::vector<float> img(size_t(prm.width) * prm.height);
    // Last written by "transform" (storage write); that is the state the copy must wait for.
    s = readbackImage(dev, eg.graph.image(eg.image), 0, 4, img.data(), rg::stateOf(rg::Use::ComputeStorageWrite));
    ASSERT_TRUE(s.ok()) << s.message();
    const ExampleReference ref = exampleReference(prm);
    size_t bad = 0;
    for (size_t i = 0; i < img.size(); ++i)
      if (std::fabs(img[i] - ref.image[i]) > 1e-6f * std::max(1.0f, std::fabs(ref.image[i]))) ++bad;
    EXPECT_EQ(bad, 0u) << "texels differing from the CPU reference";
    eg.graph.release(dev);
  }
  destroyBuffer(dev, result);
  destroyExamplePipelines(dev, pipes);
}

INSTANTIATE_TEST_SUITE_P(Sizes, ComputeGraph,
                         ::testing::Values(std::make_pair(256u, 256u), std::make_pair(300u, 77u),
                                           std::make_pair(1u, 1u)),
                         [](const auto& info) {
                           return std::to_string(info.param.first) + "x" + std::to_string(info.param.second);
                         });
