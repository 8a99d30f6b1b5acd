// The C++/GLSL shared-struct rule, checked on the device: every field of a struct using all the
// allowed member types is pushed from C++ and read back by a shader, slot by slot.
#include <cstring>

#include "engine/memory.h"
#include "engine/pipeline.h"
#include "engine/render_graph.h"
#include "engine/transfer.h"
#include "shaders/shared/interop_probe.h"
#include "tests/gpu_test.h"
#include "tools/test_shaders.h"

using namespace canopy;

namespace {
class Interop : public test::GpuTest {};
}

TEST_F(Interop, PushConstantLayoutMatchesCpp) {
  gpu::InteropProbe probe{};
  probe.a = 1.5f;
  probe.b = {2.0f, 3.0f, 4.0f};
  probe.c = 5;
  probe.d = {6.0f, 7.0f};
  probe.e = {-8, 9, -10, 11};
  for (int c = 0; c < 4; ++c)
    for (int r = 0; r < 4; ++r) probe.m[c][r] = float(100 + c * 4 + r);
  std::vector<float> expected = {1.5f, 2, 3, 4, 5, 6, 7, -8, 9, -10, 11};
  for (int i = 0; i < 16; ++i) expected.push_back(float(100 + i));

  ComputePipeline pipe;
  Status s = createComputePipeline(dev, {"interop_probe.comp", sizeof probe, {}, false, &canopy_test::findEmbeddedShader}, &pipe);
  ASSERT_TRUE(s.ok()) << s.message();
  Buffer out;
  ASSERT_TRUE(createBuffer(dev, expected.size() * sizeof(float), VK_BUFFER_USAGE_STORAGE_BUFFER_BIT |
                           VK_BUFFER_USAGE_TRANSFER_SRC_BIT, MemoryUsage::DeviceLocal, &out, "probe out").ok());
  rg::RenderGraph g;
  auto id = g.importBuffer("probe out", out.size, {}, rg::stateOf(rg::Use::ComputeStorageWrite));
  g.addPass("probe", [&](rg::PassContext& c) {
     return dispatch(dev, c.cmd, pipe, 1, 1, 1, {bindBuffer(c.buffer(id))}, probe);
   }).write(id, rg::Use::ComputeStorageWrite);
  ASSERT_TRUE(g.compile().ok());
  ASSERT_TRUE(g.realize(dev).ok());
  ASSERT_TRUE(g.bindBuffer(id, out.buffer).ok());
  s = submitAndWait(dev, [&](VkCommandBuffer cmd) { return g.record(cmd); });
  ASSERT_TRUE(s.ok()) << s.message();
  std::vector<float> got(expected.size());
  s = readbackBuffer(dev, out, got.data(), out.size, rg::stateOf(rg::Use::ComputeStorageWrite));
  ASSERT_TRUE(s.ok()) << s.message();
  for (size_t i = 0; i < expected.size(); ++i) EXPECT_EQ(got[i], expected[i]) << "slot " << i;
  destroyBuffer(dev, out);
  destroyComputePipeline(dev, pipe);
}

// dispatch() checks the push-constant size against the pipeline and records nothing on mismatch.
TEST_F(Interop, DispatchRefusesWrongPushSize) {
  ComputePipeline pipe;
  ASSERT_TRUE(createComputePipeline(dev, {"interop_probe.comp", sizeof(gpu::InteropProbe), {}, false,
                                          &canopy_test::findEmbeddedShader}, &pipe).ok());
  struct Wrong { float x[3]; } wrong{};
  Status s = submitAndWait(dev, [&](VkCommandBuffer cmd) {
    return dispatch(dev, cmd, pipe, 1, 1, 1, {bindBuffer(VkBuffer(VK_NULL_HANDLE))}, wrong);
  });
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.message().find("push constants are 12 bytes"), std::string::npos) << s.message();
  destroyComputePipeline(dev, pipe);
}

TEST_F(Interop, UnknownShaderIsAnError) {
  ComputePipeline pipe;
  Status s = createComputePipeline(dev, {"no_such.comp", 0}, &pipe);
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.message().find("no_such.comp"), std::string::npos);
}
