// Pure-CPU tests of the render graph's plan: the exact barriers, their batching into dependency
// levels, culling, imported resources' initial/final states, and declaration errors.
#include <gtest/gtest.h>

#include "engine/render_graph.h"

using namespace canopy;
using namespace canopy::rg;

namespace {

constexpr VkPipelineStageFlags2 CS = VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT;
constexpr VkPipelineStageFlags2 FS = VK_PIPELINE_STAGE_2_FRAGMENT_SHADER_BIT;
constexpr VkPipelineStageFlags2 HOST = VK_PIPELINE_STAGE_2_HOST_BIT;
constexpr VkPipelineStageFlags2 COLOR = VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT;
constexpr VkAccessFlags2 SR = VK_ACCESS_2_SHADER_STORAGE_READ_BIT;
constexpr VkAccessFlags2 SW = VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT;
constexpr VkAccessFlags2 SAMPLED = VK_ACCESS_2_SHADER_SAMPLED_READ_BIT;
constexpr VkAccessFlags2 HR = VK_ACCESS_2_HOST_READ_BIT;
constexpr VkAccessFlags2 CW = VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT;
constexpr VkImageLayout UNDEF = VK_IMAGE_LAYOUT_UNDEFINED;
constexpr VkImageLayout GENERAL = VK_IMAGE_LAYOUT_GENERAL;
constexpr VkImageLayout SRO = VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL;
constexpr VkImageLayout CAO = VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL;

Barrier B(ResourceId r, VkPipelineStageFlags2 ss, VkAccessFlags2 sa, VkPipelineStageFlags2 ds, VkAccessFlags2 da,
          VkImageLayout o = UNDEF, VkImageLayout n = UNDEF) {
  return {r, ss, sa, ds, da, o, n};
}

PassFn noop() {
  return [](PassContext&) { return Status(); };
}

ImageDesc image64() {
  ImageDesc d;
  d.format = VK_FORMAT_R8G8B8A8_UNORM;
  d.width = d.height = 64;
  return d;
}

#define EXPECT_BARRIERS(actual, ...)                                                      \
  do {                                                                                     \
    std::vector<Barrier> expected_{__VA_ARGS__};                                           \
    EXPECT_EQ(actual.size(), expected_.size()) << g.describe();                           \
    for (size_t i_ = 0; i_ < std::min(actual.size(), expected_.size()); ++i_)               \
      EXPECT_EQ(actual[i_], expected_[i_]) << "barrier " << i_ << ": got " << toString(actual[i_]) \
                                           << ", want " << toString(expected_[i_]) << "\n" << g.describe(); \
  } while (0)

}  // namespace

// write -> read of a transient, result into an imported host-readable buffer.
TEST(RenderGraphBarriers, ReadAfterWriteChain) {
  RenderGraph g;
  auto t = g.createBuffer("t", {256});
  auto out = g.importBuffer("out", 16, {}, stateOf(Use::HostRead));
  g.addPass("produce", noop()).write(t, Use::ComputeStorageWrite);
  g.addPass("consume", noop()).read(t, Use::ComputeStorageRead).write(out, Use::ComputeStorageWrite);
  ASSERT_TRUE(g.compile().ok());
  ASSERT_EQ(g.steps().size(), 2u);
  EXPECT_EQ(g.steps()[0].passes, std::vector<uint32_t>{0});
  EXPECT_EQ(g.steps()[1].passes, std::vector<uint32_t>{1});
  // Frame N+1's write to the transient waits for frame N's read of it (execution dependency).
  EXPECT_BARRIERS(g.steps()[0].barriers, B(t, CS, 0, CS, SW));
  EXPECT_BARRIERS(g.steps()[1].barriers, B(t, CS, SW, CS, SR));
  EXPECT_BARRIERS(g.finalBarriers(), B(out, CS, SW, HOST, HR));
}

// A pass whose output nobody reads is culled, with the reads that fed only it; markOutput keeps it.
TEST(RenderGraphBarriers, CullsUnreadPasses) {
  for (bool keep : {false, true}) {
    RenderGraph g;
    auto a = g.createBuffer("a", {64});
    auto unused = g.createBuffer("unused", {64});
    auto b = g.createBuffer("b", {64});
    auto out = g.importBuffer("out", 64, {}, stateOf(Use::HostRead));
    g.addPass("make a", noop()).write(a, Use::ComputeStorageWrite);
    g.addPass("make b", noop()).write(b, Use::ComputeStorageWrite);
    g.addPass("dead end", noop()).read(b, Use::ComputeStorageRead).write(unused, Use::ComputeStorageWrite);
    g.addPass("final", noop()).read(a, Use::ComputeStorageRead).write(out, Use::ComputeStorageWrite);
    if (keep) g.markOutput(unused);
    ASSERT_TRUE(g.compile().ok());
    EXPECT_FALSE(g.isCulled(0));
    EXPECT_EQ(g.isCulled(1), !keep) << g.describe();
    EXPECT_EQ(g.isCulled(2), !keep) << g.describe();
    EXPECT_FALSE(g.isCulled(3));
    if (!keep) {
      ASSERT_EQ(g.steps().size(), 2u);
      EXPECT_BARRIERS(g.steps()[0].barriers, B(a, CS, 0, CS, SW));
      EXPECT_BARRIERS(g.steps()[1].barriers, B(a, CS, SW, CS, SR));
      for (const Step& s : g.steps())
        for (const Barrier& x : s.barriers) EXPECT_NE(x.resource, b) << "culled resource got a barrier";
    } else {
      // "make a" and "make b" are independent: one level, one barrier batch.
      ASSERT_EQ(g.steps().size(), 2u);
      EXPECT_EQ(g.steps()[0].passes, (std::vector<uint32_t>{0, 1}));
      EXPECT_EQ(g.steps()[1].passes, (std::vector<uint32_t>{2, 3}));
    }
  }
}

// Imported image: arrives as a colour attachment, is sampled by compute, must leave sampled by
// the host's fragment shader. The transition happens once; the final barrier orders the host's
// read after it.
TEST(RenderGraphBarriers, ImportedImageInitialAndFinalState) {
  RenderGraph g;
  auto img = g.importImage("host colour", image64(), stateOf(Use::ColorAttachmentWrite), stateOf(Use::FragmentSampled));
  auto out = g.importBuffer("out", 64, {}, stateOf(Use::HostRead));
  g.addPass("sample", noop()).read(img, Use::ComputeSampled).write(out, Use::ComputeStorageWrite);
  ASSERT_TRUE(g.compile().ok());
  ASSERT_EQ(g.steps().size(), 1u);
  EXPECT_BARRIERS(g.steps()[0].barriers, B(img, COLOR, CW, CS, SAMPLED, CAO, SRO));
  EXPECT_BARRIERS(g.finalBarriers(), B(img, CS, 0, FS, SAMPLED, SRO, SRO), B(out, CS, SW, HOST, HR));
}

// An imported image that arrives sampled by the fragment stage (the barrier that transitioned it
// named only that stage: a layer image at rest, a host's depth its own pass samples) and is read by
// compute: the read chains a barrier from the fragment stage, else the layout transition before it
// is not visible to compute (issue 68's first-frame SYNC-HAZARD-READ-AFTER-WRITE). A second read by
// the fragment stage needs none.
TEST(RenderGraphBarriers, AReadAtAnotherStageOfAnImportedReadStateChainsABarrier) {
  RenderGraph g;
  auto img = g.importImage("at rest", image64(), stateOf(Use::FragmentSampled), stateOf(Use::FragmentSampled));
  auto out = g.importBuffer("out", 64, {}, stateOf(Use::HostRead));
  g.addPass("fragment read", noop()).read(img, Use::FragmentSampled).sideEffect();
  g.addPass("compute read", noop()).read(img, Use::ComputeSampled).write(out, Use::ComputeStorageWrite);
  ASSERT_TRUE(g.compile().ok());
  ASSERT_EQ(g.steps().size(), 1u);
  EXPECT_BARRIERS(g.steps()[0].barriers, B(img, FS, 0, CS, SAMPLED, SRO, SRO));
}

// An imported image no pass touches still reaches its final layout.
TEST(RenderGraphBarriers, UntouchedImportGetsFinalTransition) {
  RenderGraph g;
  auto img = g.importImage("idle", image64(), stateOf(Use::ColorAttachmentWrite), stateOf(Use::FragmentSampled));
  auto out = g.importBuffer("out", 64, {}, stateOf(Use::HostRead));
  g.addPass("other", noop()).write(out, Use::ComputeStorageWrite);
  ASSERT_TRUE(g.compile().ok());
  EXPECT_BARRIERS(g.steps()[0].barriers);
  EXPECT_BARRIERS(g.finalBarriers(), B(img, COLOR, CW, FS, SAMPLED, CAO, SRO), B(out, CS, SW, HOST, HR));
}

// A graph used as one pass of a host's graph (Canopy's pass group, <canopy/canopy_graph.h>): the
// image arrives in the combined state of all its uses (the host's barrier made it so) and leaves
// in the same layout with no final barrier, the host's next barrier starting from that state. The
// internal transition to the sampled layout chains from the combined stages.
TEST(RenderGraphBarriers, CallerSynchronizedImportAndCombinedUse) {
  auto declare = [](RenderGraph& g, State initial, State final) {
    auto img = g.importImage("host colour", image64(), initial, final);
    auto out = g.importBuffer("out", 64, {}, stateOf(Use::HostRead));
    g.addPass("sample", noop()).read(img, Use::ComputeSampled).write(out, Use::ComputeStorageWrite);
    g.addPass("draw", noop()).read(out, Use::FragmentStorageRead).write(img, Use::ColorAttachmentWrite);
    return img;
  };
  RenderGraph probe;
  auto id = declare(probe, {}, stateOf(Use::ColorAttachmentWrite));
  ASSERT_TRUE(probe.compile().ok());
  const State use = probe.combinedUse(id);
  EXPECT_EQ(use.stage, CS | COLOR);
  EXPECT_EQ(use.access, SAMPLED | CW);
  EXPECT_EQ(use.layout, CAO);

  RenderGraph g;
  auto img = declare(g, {use.stage, 0, use.layout}, {0, 0, use.layout});
  ASSERT_TRUE(g.compile().ok());
  ASSERT_EQ(g.steps().size(), 2u);
  EXPECT_BARRIERS(g.steps()[0].barriers, B(img, CS | COLOR, 0, CS, SAMPLED, CAO, SRO));
  for (const Barrier& b : g.finalBarriers()) EXPECT_NE(b.resource, img) << toString(b);
}

// Two readers of one write in different stages share one level and one merged barrier.
TEST(RenderGraphBarriers, ReadersMergeIntoOneBarrier) {
  RenderGraph g;
  auto t = g.createBuffer("t", {64});
  auto o1 = g.importBuffer("o1", 64, {}, stateOf(Use::HostRead));
  auto o2 = g.importBuffer("o2", 64, {}, stateOf(Use::HostRead));
  g.addPass("w", noop()).write(t, Use::ComputeStorageWrite);
  g.addPass("r compute", noop()).read(t, Use::ComputeStorageRead).write(o1, Use::ComputeStorageWrite);
  g.addPass("r fragment", noop()).read(t, Use::FragmentStorageRead).write(o2, Use::ComputeStorageWrite);
  ASSERT_TRUE(g.compile().ok());
  ASSERT_EQ(g.steps().size(), 2u);
  EXPECT_EQ(g.steps()[1].passes, (std::vector<uint32_t>{1, 2}));
  EXPECT_BARRIERS(g.steps()[1].barriers, B(t, CS, SW, CS | FS, SR));
}

// Write-after-read: rewriting a buffer waits for its readers and the earlier writer.
TEST(RenderGraphBarriers, WriteAfterReadAndWrite) {
  RenderGraph g;
  auto t = g.createBuffer("t", {64});
  auto o1 = g.importBuffer("o1", 64, {}, stateOf(Use::HostRead));
  auto o2 = g.importBuffer("o2", 64, {}, stateOf(Use::HostRead));
  g.addPass("w1", noop()).write(t, Use::ComputeStorageWrite);
  g.addPass("r1", noop()).read(t, Use::FragmentStorageRead).write(o1, Use::ComputeStorageWrite);
  g.addPass("w2", noop()).write(t, Use::ComputeStorageWrite);
  g.addPass("r2", noop()).read(t, Use::ComputeStorageRead).write(o2, Use::ComputeStorageWrite);
  ASSERT_TRUE(g.compile().ok());
  ASSERT_EQ(g.steps().size(), 4u) << g.describe();
  EXPECT_BARRIERS(g.steps()[2].barriers, B(t, CS | FS, SW, CS, SW));
  EXPECT_BARRIERS(g.steps()[3].barriers, B(t, CS, SW, CS, SR));
}

// Persistent simulation state: imported read-write buffer updated in place by two passes.
TEST(RenderGraphBarriers, InPlaceReadWriteOfImportedState) {
  RenderGraph g;
  const State rw = stateOf(Use::ComputeStorageReadWrite);
  auto s = g.importBuffer("state", 64, rw, rw);
  g.addPass("step 1", noop()).write(s, Use::ComputeStorageReadWrite);
  g.addPass("step 2", noop()).write(s, Use::ComputeStorageReadWrite);
  ASSERT_TRUE(g.compile().ok());
  ASSERT_EQ(g.steps().size(), 2u);
  EXPECT_BARRIERS(g.steps()[0].barriers, B(s, CS, SW, CS, SR | SW));
  EXPECT_BARRIERS(g.steps()[1].barriers, B(s, CS, SW, CS, SR | SW));
  EXPECT_BARRIERS(g.finalBarriers(), B(s, CS, SW, CS, SR | SW));
}

// A transient image: first use transitions from UNDEFINED (contents discarded each frame); a
// later read in another layout is a transition too, ordered after the write.
TEST(RenderGraphBarriers, TransientImageLayouts) {
  RenderGraph g;
  auto img = g.createImage("layer", image64());
  auto out = g.importBuffer("out", 64, {}, stateOf(Use::HostRead));
  g.addPass("draw", noop()).write(img, Use::ColorAttachmentWrite);
  g.addPass("composite", noop()).read(img, Use::ComputeSampled).write(out, Use::ComputeStorageWrite);
  ASSERT_TRUE(g.compile().ok());
  ASSERT_EQ(g.steps().size(), 2u);
  EXPECT_BARRIERS(g.steps()[0].barriers, B(img, CS, 0, COLOR, CW, UNDEF, CAO));
  EXPECT_BARRIERS(g.steps()[1].barriers, B(img, COLOR, CW, CS, SAMPLED, CAO, SRO));
}

// Storage image written then read in GENERAL: a memory barrier without a layout change.
TEST(RenderGraphBarriers, StorageImageSameLayout) {
  RenderGraph g;
  auto img = g.createImage("field", image64());
  auto out = g.importBuffer("out", 64, {}, stateOf(Use::HostRead));
  g.addPass("write", noop()).write(img, Use::ComputeStorageWrite);
  g.addPass("read", noop()).read(img, Use::ComputeStorageRead).write(out, Use::ComputeStorageWrite);
  ASSERT_TRUE(g.compile().ok());
  EXPECT_BARRIERS(g.steps()[0].barriers, B(img, CS, 0, CS, SW, UNDEF, GENERAL));
  EXPECT_BARRIERS(g.steps()[1].barriers, B(img, CS, SW, CS, SR, GENERAL, GENERAL));
}

TEST(RenderGraphErrors, ReadBeforeWriteIsRefused) {
  RenderGraph g;
  auto t = g.createBuffer("never written", {64});
  auto out = g.importBuffer("out", 64, {}, stateOf(Use::HostRead));
  g.addPass("reader", noop()).read(t, Use::ComputeStorageRead).write(out, Use::ComputeStorageWrite);
  Status s = g.compile();
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.message().find("reader"), std::string::npos) << s.message();
  EXPECT_NE(s.message().find("never written"), std::string::npos) << s.message();
}

TEST(RenderGraphErrors, TwoLayoutsInOnePassAreRefused) {
  RenderGraph g;
  auto img = g.createImage("img", image64());
  g.addPass("confused", noop()).write(img, Use::ColorAttachmentWrite).read(img, Use::ComputeSampled).sideEffect();
  Status s = g.compile();
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.message().find("two layouts"), std::string::npos) << s.message();
}

TEST(RenderGraphErrors, ImportedImageNeedsFinalLayout) {
  RenderGraph g;
  g.importImage("host", image64(), stateOf(Use::ColorAttachmentWrite), State{});
  EXPECT_FALSE(g.compile().ok());
}

TEST(RenderGraphErrors, WrongDirectionIsRefused) {
  RenderGraph g;
  auto t = g.createBuffer("t", {64});
  g.addPass("p", noop()).read(t, Use::ComputeStorageWrite).sideEffect();
  EXPECT_FALSE(g.compile().ok());
}

// A conditional pass (when): in a frame where it is off, neither it nor its barriers are in the
// plan record() uses; on, the plan is compile()'s. Transients are refused for it.
TEST(RenderGraphBarriers, ConditionalPassesLeaveOutTheirBarriers) {
  RenderGraph g;
  const State rest = stateOf(Use::FragmentSampled);
  auto layers = g.importImage("layers", image64(), rest, rest);
  auto out = g.importBuffer("out", 64, {}, stateOf(Use::HostRead));
  bool on = false;
  g.addPass("redraw", noop()).write(layers, Use::ColorAttachmentWrite).when([&] { return on; });
  g.addPass("sample", noop()).read(layers, Use::ComputeSampled).write(out, Use::ComputeStorageWrite);
  ASSERT_TRUE(g.compile().ok());
  ASSERT_EQ(g.steps().size(), 2u);
  const RenderGraph::Plan& off = g.currentPlan();
  ASSERT_EQ(off.skipped, (std::vector<bool>{true, false}));
  EXPECT_BARRIERS(off.steps[0].barriers);
  // Only the read remains: the image arrives sampled by fragment shaders (the transition before
  // it was made visible to them alone), so compute's read chains a barrier from that stage, and
  // the final barrier hands the compute read back to the fragment stage the next frame starts from.
  EXPECT_BARRIERS(off.steps[1].barriers, B(layers, FS, 0, CS, SAMPLED, SRO, SRO));
  EXPECT_BARRIERS(off.final, B(layers, FS | CS, 0, FS, SAMPLED, SRO, SRO), B(out, CS, SW, HOST, HR));
  on = true;
  const RenderGraph::Plan& full = g.currentPlan();
  EXPECT_EQ(full.skipped, (std::vector<bool>{false, false}));
  EXPECT_BARRIERS(full.steps[0].barriers, B(layers, FS, 0, COLOR, CW, SRO, CAO));
  EXPECT_BARRIERS(full.steps[1].barriers, B(layers, COLOR, CW, CS, SAMPLED, CAO, SRO));
  EXPECT_BARRIERS(full.final, B(layers, CS, 0, FS, SAMPLED, SRO, SRO), B(out, CS, SW, HOST, HR));
  on = false;
  EXPECT_EQ(&g.currentPlan(), &g.currentPlan()) << "a combination is planned once";

  RenderGraph h;
  auto t = h.createBuffer("t", {64});
  auto o = h.importBuffer("o", 64, {}, stateOf(Use::HostRead));
  h.addPass("sometimes", noop()).write(t, Use::ComputeStorageWrite).when([] { return true; });
  h.addPass("read", noop()).read(t, Use::ComputeStorageRead).write(o, Use::ComputeStorageWrite);
  const Status s = h.compile();
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.message().find("transient 't'"), std::string::npos) << s.message();
}
