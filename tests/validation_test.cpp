// Proves the validation helper cannot pass silently: a deliberately missing barrier is reported
// by synchronization validation, and a plain API misuse by core validation.
#include <cstring>

#include "tools/example_passes.h"
#include "engine/memory.h"
#include "tests/gpu_test.h"

using namespace canopy;

namespace {
class ValidationHelper : public test::GpuTest {};

bool anyIdContains(const std::vector<test::ValidationMessage>& m, const char* what) {
  for (const auto& x : m)
    if (x.id.find(what) != std::string::npos || x.text.find(what) != std::string::npos) return true;
  return false;
}
}  // namespace

// The transform pass "forgets" to declare that it reads the values buffer, so the graph puts it
// in the same dependency level as the writer with no barrier between them: a read-after-write
// hazard that synchronization validation must report.
TEST_F(ValidationHelper, MissingBarrierIsReportedBySyncValidation) {
  ExamplePipelines pipes;
  ASSERT_TRUE(createExamplePipelines(dev, &pipes).ok());
  rg::RenderGraph g;
  const uint32_t W = 64, H = 64, N = W * H;
  auto values = g.createBuffer("values", {N * sizeof(float)});
  ImageDesc desc;
  desc.format = VK_FORMAT_R32_SFLOAT;
  desc.width = W;
  desc.height = H;
  auto image = g.createImage("image", desc);
  g.addPass("write", [&](rg::PassContext& c) {
     gpu::ExampleWriteParams pc{N, 1, 1.0f};
     return dispatch(dev, c.cmd, pipes.write, N, 1, 1, {bindBuffer(c.buffer(values))}, pc);
   }).write(values, rg::Use::ComputeStorageWrite);
  g.addPass("transform (read of 'values' not declared)", [&](rg::PassContext& c) {
     gpu::ExampleTransformParams pc{W, H, 1.0f, 0.0f};
     return dispatch(dev, c.cmd, pipes.transform, W, H, 1, {bindBuffer(c.buffer(values)), bindImage(c.image(image).view)}, pc);
   }).write(image, rg::Use::ComputeStorageWrite);
  g.markOutput(values);
  g.markOutput(image);
  ASSERT_TRUE(g.compile().ok());
  ASSERT_EQ(g.steps().size(), 1u) << "the undeclared read should leave both passes in one level\n" << g.describe();
  ASSERT_TRUE(g.realize(dev).ok());
  ASSERT_TRUE(submitAndWait(dev, [&](VkCommandBuffer cmd) { return g.record(cmd); }).ok());
  auto msgs = takeMessages();
  EXPECT_TRUE(anyIdContains(msgs, "SYNC-HAZARD-READ-AFTER-WRITE"))
      << "sync validation did not report the missing barrier; got:\n" << test::describe(msgs);

  // Same graph with the read declared: the graph inserts the barrier and validation is silent.
  g.release(dev);
  rg::RenderGraph ok;
  auto v2 = ok.createBuffer("values", {N * sizeof(float)});
  auto i2 = ok.createImage("image", desc);
  ok.addPass("write", [&](rg::PassContext& c) {
     gpu::ExampleWriteParams pc{N, 1, 1.0f};
     return dispatch(dev, c.cmd, pipes.write, N, 1, 1, {bindBuffer(c.buffer(v2))}, pc);
   }).write(v2, rg::Use::ComputeStorageWrite);
  ok.addPass("transform", [&](rg::PassContext& c) {
     gpu::ExampleTransformParams pc{W, H, 1.0f, 0.0f};
     return dispatch(dev, c.cmd, pipes.transform, W, H, 1, {bindBuffer(c.buffer(v2)), bindImage(c.image(i2).view)}, pc);
   })
      .read(v2, rg::Use::ComputeStorageRead)
      .write(i2, rg::Use::ComputeStorageWrite);
  ok.markOutput(i2);
  ASSERT_TRUE(ok.compile().ok());
  ASSERT_TRUE(ok.realize(dev).ok());
  ASSERT_TRUE(submitAndWait(dev, [&](VkCommandBuffer cmd) { return ok.record(cmd); }).ok());
  waitIdle();
  ok.release(dev);
  destroyExamplePipelines(dev, pipes);
  // TearDown() asserts that no further message arrived.
}

// Core validation errors reach the helper too (not only synchronization hazards).
TEST_F(ValidationHelper, ApiMisuseIsReported) {
  VkBufferCreateInfo ci{VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO};
  ci.size = 0;  // invalid: size must be > 0
  ci.usage = VK_BUFFER_USAGE_STORAGE_BUFFER_BIT;
  VkBuffer b = VK_NULL_HANDLE;
  VkResult r = vkCreateBuffer(dev.device, &ci, nullptr, &b);
  if (r == VK_SUCCESS && b) vkDestroyBuffer(dev.device, b, nullptr);
  auto msgs = takeMessages();
  EXPECT_TRUE(anyIdContains(msgs, "VUID-VkBufferCreateInfo-size")) << test::describe(msgs);
}
