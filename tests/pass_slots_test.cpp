// A pass's descriptors declared once (engine/pass_slots.h): the slot list gives both the pass's
// graph uses (so its barriers) and its bind list, and a slot that does not fit the descriptor
// type the SPIR-V declares for its binding is refused naming both. Pure CPU: the graph's plan and
// the bind lists built against stand-in handles (nothing is recorded).
#include <gtest/gtest.h>

#include "engine/pass_slots.h"

using namespace canopy;
using namespace canopy::rg;

namespace {

// Stand-in handles: bind lists are only built, never pushed.
VkBuffer fakeBuffer(uintptr_t n) { return reinterpret_cast<VkBuffer>(n); }
VkImageView fakeView(uintptr_t n) { return reinterpret_cast<VkImageView>(n); }
VkSampler fakeSampler(uintptr_t n) { return reinterpret_cast<VkSampler>(n); }

ImageDesc image64() {
  ImageDesc d;
  d.format = VK_FORMAT_R16G16B16A16_SFLOAT;
  d.width = d.height = 64;
  return d;
}

// A graph with a buffer and an image bound to stand-in handles (0x10, view 0x20), and a context
// over it, as a pass's record sees it.
struct BoundGraph {
  RenderGraph graph;
  ResourceId buf, img;
  PassContext context;
  BoundGraph(const char* bufferName, const char* imageName) {
    const State rest = stateOf(Use::ComputeStorageRead);
    buf = graph.importBuffer(bufferName, 256, rest, rest);
    img = graph.importImage(imageName, image64(), stateOf(Use::ComputeSampled), stateOf(Use::ComputeSampled));
    Image image;
    image.view = fakeView(0x20);
    EXPECT_TRUE(graph.bindBuffer(buf, fakeBuffer(0x10)).ok());
    EXPECT_TRUE(graph.bindImage(img, image).ok());
    context.graph = &graph;
  }
};

bool hasBarrierOn(const RenderGraph& g, ResourceId id) {
  for (const Step& s : g.steps())
    for (const Barrier& b : s.barriers)
      if (b.resource == id) return true;
  return false;
}

}  // namespace

// The slots' uses are the pass's declared accesses: a written slot orders the reader after it, an
// untouched slot declares nothing (no barrier), an image slot's layout is its use's.
TEST(PassSlots, SlotsDeclareThePassUses) {
  RenderGraph g;
  const State rest = stateOf(Use::ComputeStorageRead);
  const ResourceId a = g.importBuffer("a", 64, rest, rest), b = g.importBuffer("b", 64, rest, rest),
                   spare = g.importBuffer("spare", 64, rest, rest);
  const ResourceId img = g.importImage("img", image64(), stateOf(Use::FragmentSampled), stateOf(Use::FragmentSampled));
  auto noop = [](PassContext&, const Slots&) { return Status(); };
  addSlotPass(g, "write", {slot(a, Use::ComputeStorageRead), slot(b, Use::ComputeStorageWrite), untouched(spare),
                           slot(img, Use::ComputeStorageWrite)}, noop);
  addSlotPass(g, "read", {slot(b, Use::ComputeStorageRead), untouched(spare), slot(img, Use::ComputeSampled, fakeSampler(9))},
              noop)
      .sideEffect();  // kept: its effect is outside this graph
  ASSERT_TRUE(g.compile().ok()) << g.describe();
  EXPECT_TRUE(hasBarrierOn(g, b)) << g.describe();        // write -> read
  EXPECT_TRUE(hasBarrierOn(g, img)) << g.describe();      // GENERAL (storage write) -> SHADER_READ_ONLY (sampled)
  EXPECT_FALSE(hasBarrierOn(g, spare)) << g.describe();   // bound, never accessed
  EXPECT_FALSE(hasBarrierOn(g, a)) << g.describe();       // read from its resting read state
  // The image goes from the storage write's GENERAL to the sampled read's SHADER_READ_ONLY.
  bool transition = false;
  for (const Step& st : g.steps())
    for (const Barrier& x : st.barriers)
      transition = transition || (x.resource == img && x.oldLayout == VK_IMAGE_LAYOUT_GENERAL &&
                                  x.newLayout == VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL &&
                                  (x.srcAccess & VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT) != 0);
  EXPECT_TRUE(transition) << g.describe();
}

// The bind list comes from the same slots: the graph's buffers and views (an image in its use's
// layout, with its sampler), an object outside the graph as given, a buffer whole.
TEST(PassSlots, BindListFollowsTheSlots) {
  BoundGraph bg("buf", "img");
  const ResourceId buf = bg.buf, img = bg.img;
  const PassContext& c = bg.context;
  const Slots slots = {slot(buf, Use::ComputeStorageRead), slot(img, Use::ComputeSampled, fakeSampler(0x30)),
                       outsideGraph(bindBuffer(fakeBuffer(0x40))), slot(img, Use::ComputeStorageWrite)};
  const std::vector<VkDescriptorType> types = {VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER,
                                               VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, VK_DESCRIPTOR_TYPE_STORAGE_IMAGE};
  std::vector<Binding> b;
  ASSERT_TRUE(slotBindings(c, slots, types, "test pass", &b).ok());
  ASSERT_EQ(b.size(), 4u);
  EXPECT_EQ(b[0].buffer, fakeBuffer(0x10));
  EXPECT_EQ(b[0].offset, 0u);
  EXPECT_EQ(b[0].range, VK_WHOLE_SIZE);
  EXPECT_EQ(b[1].view, fakeView(0x20));
  EXPECT_EQ(b[1].layout, VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL);
  EXPECT_EQ(b[1].sampler, fakeSampler(0x30));
  EXPECT_EQ(b[2].buffer, fakeBuffer(0x40));
  EXPECT_EQ(b[3].layout, VK_IMAGE_LAYOUT_GENERAL);
}

// A slot list that drifts from the shader fails when the pass is recorded, naming the binding, the
// resource and both kinds; a count that differs names both counts.
TEST(PassSlots, DriftFromTheSpirVIsRefused) {
  BoundGraph bg("velocity", "layer colour");
  const ResourceId buf = bg.buf, img = bg.img;
  const PassContext& c = bg.context;
  std::vector<Binding> b;
  // A buffer slot where the shader samples an image.
  Status s = slotBindings(c, {slot(buf, Use::ComputeStorageRead)}, {VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER}, "pass 'p'", &b);
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.message().find("binding 0"), std::string::npos) << s.message();
  EXPECT_NE(s.message().find("'velocity'"), std::string::npos) << s.message();
  EXPECT_NE(s.message().find("ComputeStorageRead"), std::string::npos) << s.message();
  // A sampled slot where the shader writes a storage image.
  s = slotBindings(c, {slot(img, Use::ComputeSampled, fakeSampler(1))}, {VK_DESCRIPTOR_TYPE_STORAGE_IMAGE}, "pass 'p'", &b);
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.message().find("'layer colour'"), std::string::npos) << s.message();
  // A sampled slot without its sampler.
  s = slotBindings(c, {slot(img, Use::ComputeSampled)}, {VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER}, "pass 'p'", &b);
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.message().find("no sampler"), std::string::npos) << s.message();
  // One slot too few.
  s = slotBindings(c, {slot(buf, Use::ComputeStorageRead)},
                   {VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER}, "pass 'p'", &b);
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.message().find("1 slots declared, the SPIR-V has 2 bindings"), std::string::npos) << s.message();
}
