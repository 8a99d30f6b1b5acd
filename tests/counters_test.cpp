// Work counted per pass (issue 56; engine/pass_counters.h): the render graph wraps each pass in a
// pipeline statistics query and states the bytes of its declared accesses. Where the counts can be
// known they are: N triangles tiling a rectangle whose edges lie on pixel edges (the whole target,
// then a part of it) report 3N vertex invocations and N primitives, and at least one fragment per
// covered pixel — not exactly one: a driver may count the helper lanes of the pixel blocks a
// triangle's edge crosses (lavapipe: 1600 for 960 pixels), so the test bounds them by twice the
// pixels; a compute pass of a known dispatch reports its workgroups times their size; the bytes
// are the resources' sizes (an attachment loaded is read too).
// Validation and synchronization validation on.
#include <gtest/gtest.h>

#include <cstdio>
#include <map>

#include "engine/graphics_pipeline.h"
#include "engine/pass_counters.h"
#include "engine/pipeline.h"
#include "engine/render_graph.h"
#include "engine/transfer.h"
#include "shaders/shared/example.h"
#include "tests/gpu_test.h"
#include "tools/test_shaders.h"

using namespace canopy;
using canopy::test::GpuTest;

namespace {

class CountersTest : public GpuTest {};

TEST_F(CountersTest, KnownDrawsAndDispatchesReportTheirWork) {
  if (!dev.pipelineStatistics) GTEST_SKIP() << "the device has no pipelineStatisticsQuery";
  const uint32_t W = 64, H = 48;
  GraphicsPipeline rect;
  GraphicsPipelineDesc gd;
  gd.vertexShader = "counters_rect.vert";
  gd.fragmentShader = "counters_rect.frag";
  gd.shaderLookup = &canopy_test::findEmbeddedShader;
  gd.pushConstantSize = 20;
  gd.colorFormats = {VK_FORMAT_R8G8B8A8_UNORM};
  gd.depthTest = gd.depthWrite = false;
  Status s = createGraphicsPipeline(dev, gd, &rect);
  ASSERT_TRUE(s.ok()) << s.message();
  ComputePipeline write;
  s = createComputePipeline(dev, {"example_write.comp", sizeof(gpu::ExampleWriteParams), {}, false, &canopy_test::findEmbeddedShader},
                            &write);
  ASSERT_TRUE(s.ok()) << s.message();
  PassCounters counters;
  s = counters.init(dev, 8);
  ASSERT_TRUE(s.ok()) << s.message();
  // A rectangle of 40 x 24 pixels (its edges on pixel edges) as 2 x 5 triangles; 1000 values
  // written by 64-wide workgroups (16 of them: 1024 invocations).
  const uint32_t cells = 5, values = 1000;
  const float x0 = -1.0f + 2.0f * 8.0f / W, x1 = -1.0f + 2.0f * 48.0f / W, y0 = -1.0f + 2.0f * 10.0f / H, y1 = -1.0f + 2.0f * 34.0f / H;
  rg::RenderGraph g;
  ImageDesc id;
  id.format = VK_FORMAT_R8G8B8A8_UNORM;
  id.width = W;
  id.height = H;
  const rg::ResourceId target = g.createImage("counted target", id);
  const rg::ResourceId buffer = g.createBuffer("counted values", {values * sizeof(float)});
  g.markOutput(target);
  g.markOutput(buffer);
  auto drawPass = [&](const char* name, uint32_t cellCount, bool clear) {
    g.addPass(name, [&, cellCount, clear](rg::PassContext& c) {
       VkRenderingAttachmentInfo a{VK_STRUCTURE_TYPE_RENDERING_ATTACHMENT_INFO};
       a.imageView = c.image(target).view;
       a.imageLayout = VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL;
       a.loadOp = clear ? VK_ATTACHMENT_LOAD_OP_CLEAR : VK_ATTACHMENT_LOAD_OP_LOAD;
       a.storeOp = VK_ATTACHMENT_STORE_OP_STORE;
       VkRenderingInfo ri{VK_STRUCTURE_TYPE_RENDERING_INFO};
       ri.renderArea = {{0, 0}, {W, H}};
       ri.layerCount = 1;
       ri.colorAttachmentCount = 1;
       ri.pColorAttachments = &a;
       dev.vk.CmdBeginRendering(c.cmd, &ri);
       setViewportScissor(dev, c.cmd, W, H);
       struct {
         float rect[4];
         uint32_t cells;
       } push{{cellCount == 1 ? -1.0f : x0, cellCount == 1 ? -1.0f : y0, cellCount == 1 ? 1.0f : x1, cellCount == 1 ? 1.0f : y1},
              cellCount};
       CANOPY_TRY(bindGraphics(dev, c.cmd, rect, {}, &push, sizeof push));
       dev.vk.CmdDraw(c.cmd, 6 * cellCount, 1, 0, 0);
       dev.vk.CmdEndRendering(c.cmd);
       return Status();
     }).write(target, clear ? rg::Use::ColorAttachmentWrite : rg::Use::ColorAttachmentReadWrite);
  };
  drawPass("draw: whole target", 1, true);
  drawPass("draw: rectangle", cells, false);
  g.addPass("dispatch: values", [&](rg::PassContext& c) {
     const gpu::ExampleWriteParams p{values, 7u, 1.0f};
     return dispatch(dev, c.cmd, write, values, 1, 1, {bindBuffer(c.buffer(buffer))}, p);
   }).write(buffer, rg::Use::ComputeStorageWrite);
  ASSERT_TRUE(g.compile().ok());
  ASSERT_TRUE(g.realize(dev).ok());
  s = submitAndWait(dev, [&](VkCommandBuffer cmd) {
    counters.reset(cmd);
    return g.record(cmd, nullptr, &counters);
  });
  ASSERT_TRUE(s.ok()) << s.message();
  std::vector<PassCounts> c;
  ASSERT_TRUE(counters.read(dev, &c).ok());
  ASSERT_EQ(c.size(), 3u);
  std::map<std::string, PassCounts> by;
  for (const PassCounts& p : c) {
    by[p.name] = p;
    std::printf("[ counters ] %-18s vertex %llu, primitives %llu, fragments %llu, compute %llu; bytes read %llu, written %llu\n",
                p.name.c_str(), (unsigned long long)p.vertexInvocations, (unsigned long long)p.clippingPrimitives,
                (unsigned long long)p.fragmentInvocations, (unsigned long long)p.computeInvocations, (unsigned long long)p.bytesRead,
                (unsigned long long)p.bytesWritten);
  }
  const PassCounts &whole = by["draw: whole target"], &part = by["draw: rectangle"], &comp = by["dispatch: values"];
  EXPECT_EQ(whole.vertexInvocations, 6u);
  EXPECT_EQ(whole.clippingPrimitives, 2u);
  EXPECT_GE(whole.fragmentInvocations, uint64_t(W) * H);
  EXPECT_LE(whole.fragmentInvocations, 2u * W * H);
  EXPECT_EQ(whole.computeInvocations, 0u);
  EXPECT_EQ(whole.bytesRead, 0u) << "cleared, not loaded";
  EXPECT_EQ(whole.bytesWritten, uint64_t(W) * H * 4);
  EXPECT_EQ(part.vertexInvocations, 6u * cells);
  EXPECT_EQ(part.clippingPrimitives, 2u * cells);
  EXPECT_GE(part.fragmentInvocations, 40u * 24u);
  EXPECT_LE(part.fragmentInvocations, 2u * 40u * 24u) << "helper lanes along the edges, not more";
  EXPECT_EQ(part.bytesRead, uint64_t(W) * H * 4) << "loaded, then written";
  EXPECT_EQ(comp.computeInvocations, 1024u);
  EXPECT_EQ(comp.vertexInvocations + comp.fragmentInvocations + comp.clippingPrimitives, 0u);
  EXPECT_EQ(comp.bytesWritten, uint64_t(values) * sizeof(float));
  EXPECT_EQ(comp.bytesRead, 0u);
  g.release(dev);
  counters.destroy(dev);
  destroyGraphicsPipeline(dev, rect);
  destroyComputePipeline(dev, write);
}

}  // namespace
