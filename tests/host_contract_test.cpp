// The host contract (issue 35; docs/embedding.md): what a host learns from Canopy's answers rather
// than by trial. Requirements as data (a Vulkan 1.0 instance refused naming the version; the
// feature chain for the device's API version checked, and a 1.2 device made from it without a
// validation message) and the host's images checked against what they were declared with (a depth
// without SAMPLED refused naming the flag). Validation and synchronization validation are on.
#include <gtest/gtest.h>

#include <mutex>
#include <string>
#include <vector>

#include "engine/shader_registry.h"
#include "engine/transfer.h"
#include "tests/gpu_test.h"
#include "tests/host_device.h"
#include "tests/test_host.h"
#include "tools/leaf_cloud.h"

using namespace canopy;
using canopy::test::GpuTest;
using canopy::test::Host;
using canopy::test::HostDevice;

namespace {

// Every validation message of a host-made instance, for one test.
struct Messages {
  std::mutex mutex;
  std::vector<std::string> all;
  void attach(HostDevice& h) {
    h.sink = [this](bool, const char* id, const char* message) {
      std::lock_guard<std::mutex> lock(mutex);
      all.push_back(std::string(id) + ": " + message);
    };
  }
  std::string text() {
    std::lock_guard<std::mutex> lock(mutex);
    std::string s;
    for (const std::string& m : all) s += m + "\n";
    return s;
  }
};

TEST(HostContract, AVulkan10InstanceIsRefusedNamingTheVersion) {
  Messages messages;
  HostDevice h;
  messages.attach(h);
  ASSERT_TRUE(test::createHostInstance(&h, VK_API_VERSION_1_0).ok());
  uint32_t n = 1;
  VkPhysicalDevice pd = VK_NULL_HANDLE;
  vkEnumeratePhysicalDevices(h.instance, &n, &pd);
  ASSERT_NE(pd, VK_NULL_HANDLE);
  DeviceRequirements req;
  const Status s = queryDeviceRequirements(vkGetInstanceProcAddr, h.instance, VK_API_VERSION_1_0, pd, &req);
  EXPECT_FALSE(s.ok());
  EXPECT_EQ(s.code(), Result::UnsupportedDevice);
  EXPECT_NE(s.message().find("API version is 1.0"), std::string::npos) << s.message();
  EXPECT_NE(s.message().find("1.2 is required"), std::string::npos) << s.message();
  // The lists are filled all the same: exact names, instance and device apart, optional with reasons.
  EXPECT_TRUE(req.instanceExtensions.empty());
  ASSERT_EQ(req.optionalInstanceExtensions.size(), 1u);
  EXPECT_EQ(req.optionalInstanceExtensions[0].name, VK_EXT_DEBUG_UTILS_EXTENSION_NAME);
  EXPECT_FALSE(req.optionalInstanceExtensions[0].reason.empty());
  EXPECT_NE(std::find(req.deviceExtensions.begin(), req.deviceExtensions.end(), VK_KHR_PUSH_DESCRIPTOR_EXTENSION_NAME),
            req.deviceExtensions.end());
  for (const std::string& e : req.deviceExtensions) EXPECT_EQ(e.find(' '), std::string::npos) << "not an exact name: " << e;
  for (const OptionalRequirement& f : req.optionalFeatures) EXPECT_FALSE(f.reason.empty()) << f.name;
  // adoptDevice says the same before touching anything.
  AdoptDeviceDesc ad;
  ad.getInstanceProcAddr = vkGetInstanceProcAddr;
  ad.instance = h.instance;
  ad.instanceApiVersion = VK_API_VERSION_1_0;
  ad.physicalDevice = pd;
  ad.device = reinterpret_cast<VkDevice>(uintptr_t(1));  // never used: refused first
  ad.queue = reinterpret_cast<VkQueue>(uintptr_t(1));
  VkDeviceCreateInfo dci{VK_STRUCTURE_TYPE_DEVICE_CREATE_INFO};
  ad.deviceCreateInfo = &dci;
  Device* d = nullptr;
  const Status a = adoptDevice(ad, &d);
  EXPECT_FALSE(a.ok());
  EXPECT_NE(a.message().find("1.0"), std::string::npos) << a.message();
  test::destroyHostDevice(h);
  EXPECT_EQ(messages.text(), "") << "validation messages";
}

TEST(HostContract, EnableDeviceFeaturesForVulkan12MakesADeviceWithoutValidationMessages) {
  Messages messages;
  HostDevice h;
  messages.attach(h);
  // A 1.2 instance: the device runs 1.2 whatever the physical device supports.
  const Status made = test::createHostDevice(2, &h, VK_API_VERSION_1_2);
  ASSERT_TRUE(made.ok()) << made.message();
  EXPECT_NE(h.adopted, nullptr);
  DeviceRequirements req;
  ASSERT_TRUE(queryDeviceRequirements(vkGetInstanceProcAddr, h.instance, VK_API_VERSION_1_2, h.physical, &req).ok());
  EXPECT_EQ(req.featureStructs, (std::vector<std::string>{"VkPhysicalDeviceFeatures2", "VkPhysicalDeviceVulkan12Features",
                                                            "VkPhysicalDeviceSynchronization2Features",
                                                            "VkPhysicalDeviceDynamicRenderingFeatures"}));
  // What tripped VUID-VkDeviceCreateInfo-pNext-pNext: a 1.3 structure in a 1.2 device's chain.
  VkPhysicalDeviceVulkan13Features f13{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_3_FEATURES};
  VkPhysicalDeviceVulkan12Features f12{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_2_FEATURES, &f13};
  VkPhysicalDeviceFeatures2 f2{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_FEATURES_2, &f12};
  Status s = enableDeviceFeatures(vkGetInstanceProcAddr, h.instance, h.physical, VK_API_VERSION_1_2, &f2);
  EXPECT_FALSE(s.ok());
  EXPECT_NE(s.message().find("VkPhysicalDeviceVulkan13Features"), std::string::npos) << s.message();
  EXPECT_NE(s.message().find("VkPhysicalDeviceSynchronization2Features"), std::string::npos) << "names the fix: " << s.message();
  // A version below 1.2, and one above the physical device's.
  s = enableDeviceFeatures(vkGetInstanceProcAddr, h.instance, h.physical, VK_API_VERSION_1_1, &f2);
  EXPECT_NE(s.message().find("1.1"), std::string::npos) << s.message();
  s = enableDeviceFeatures(vkGetInstanceProcAddr, h.instance, h.physical, VK_MAKE_API_VERSION(0, 1, 9, 0), &f2);
  EXPECT_NE(s.message().find("above the physical device"), std::string::npos) << s.message();
  // A frame on the adopted device, then nothing said by the layers.
  CanopyContext* ctx = nullptr;
  CanopyDesc desc;
  desc.width = 96;
  desc.height = 64;
  desc.colorFormat = VK_FORMAT_R16G16B16A16_SFLOAT;
  ASSERT_TRUE(createCanopy(*h.adopted, makeLeafCloud(500, 3, true), desc, &ctx).ok());
  destroyCanopy(ctx);
  test::destroyHostDevice(h);
  EXPECT_EQ(messages.text(), "") << "validation messages";
}

// Issue 68's host: an engine on Vulkan 1.2 (synchronization2 as an extension) that never calls
// recordCanopyLoad, clears its 640x480 RGBA8 colour and D32 depth in its own classic render pass
// before Canopy and takes the colour over in TRANSFER_SRC. Its first frame slices the layers and
// composites them in one command buffer; synchronization validation must say nothing about it.
TEST(HostContract, AVulkan12HostWithoutTheLoadCallRendersItsFirstFramesWithoutAHazard) {
  Messages messages;
  HostDevice h;
  messages.attach(h);
  const Status made = test::createHostDevice(2, &h, VK_API_VERSION_1_2);
  ASSERT_TRUE(made.ok()) << made.message();
  Device& d = *h.adopted;
  const uint32_t w = 640, hgt = 480;
  Image color, depth;
  ImageDesc cd;
  cd.format = VK_FORMAT_R8G8B8A8_UNORM;
  cd.width = w;
  cd.height = hgt;
  cd.usage = VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT;
  ASSERT_TRUE(createImage(d, cd, &color, "host colour").ok());
  ImageDesc dd = cd;
  dd.format = VK_FORMAT_D32_SFLOAT;
  dd.usage = VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT | VK_IMAGE_USAGE_SAMPLED_BIT;
  ASSERT_TRUE(createImage(d, dd, &depth, "host depth").ok());
  // The host's render pass: clears both, leaves them as attachments. Its dependency waits for the
  // previous frame's use of the targets (Canopy's and the host's transfer).
  VkAttachmentDescription att[2] = {};
  att[0].format = cd.format;
  att[0].samples = VK_SAMPLE_COUNT_1_BIT;
  att[0].loadOp = VK_ATTACHMENT_LOAD_OP_CLEAR;
  att[0].storeOp = VK_ATTACHMENT_STORE_OP_STORE;
  att[0].stencilLoadOp = VK_ATTACHMENT_LOAD_OP_DONT_CARE;
  att[0].stencilStoreOp = VK_ATTACHMENT_STORE_OP_DONT_CARE;
  att[0].initialLayout = VK_IMAGE_LAYOUT_UNDEFINED;
  att[0].finalLayout = VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL;
  att[1] = att[0];
  att[1].format = dd.format;
  att[1].finalLayout = VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL;
  const VkAttachmentReference cref{0, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL};
  const VkAttachmentReference dref{1, VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL};
  VkSubpassDescription sub{};
  sub.pipelineBindPoint = VK_PIPELINE_BIND_POINT_GRAPHICS;
  sub.colorAttachmentCount = 1;
  sub.pColorAttachments = &cref;
  sub.pDepthStencilAttachment = &dref;
  VkSubpassDependency dep{};
  dep.srcSubpass = VK_SUBPASS_EXTERNAL;
  dep.dstSubpass = 0;
  dep.srcStageMask = VK_PIPELINE_STAGE_ALL_COMMANDS_BIT;
  dep.dstStageMask = VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT | VK_PIPELINE_STAGE_EARLY_FRAGMENT_TESTS_BIT |
                     VK_PIPELINE_STAGE_LATE_FRAGMENT_TESTS_BIT;
  dep.srcAccessMask = VK_ACCESS_MEMORY_WRITE_BIT;
  dep.dstAccessMask = VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT | VK_ACCESS_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT |
                      VK_ACCESS_DEPTH_STENCIL_ATTACHMENT_READ_BIT | VK_ACCESS_COLOR_ATTACHMENT_READ_BIT;
  VkRenderPassCreateInfo rpi{VK_STRUCTURE_TYPE_RENDER_PASS_CREATE_INFO};
  rpi.attachmentCount = 2;
  rpi.pAttachments = att;
  rpi.subpassCount = 1;
  rpi.pSubpasses = &sub;
  rpi.dependencyCount = 1;
  rpi.pDependencies = &dep;
  VkRenderPass pass = VK_NULL_HANDLE;
  ASSERT_EQ(vkCreateRenderPass(h.device, &rpi, nullptr, &pass), VK_SUCCESS);
  const VkImageView views[2] = {color.view, depth.view};
  VkFramebufferCreateInfo fbi{VK_STRUCTURE_TYPE_FRAMEBUFFER_CREATE_INFO};
  fbi.renderPass = pass;
  fbi.attachmentCount = 2;
  fbi.pAttachments = views;
  fbi.width = w;
  fbi.height = hgt;
  fbi.layers = 1;
  VkFramebuffer fb = VK_NULL_HANDLE;
  ASSERT_EQ(vkCreateFramebuffer(h.device, &fbi, nullptr, &fb), VK_SUCCESS);
  VkCommandPoolCreateInfo pci{VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO};
  pci.flags = VK_COMMAND_POOL_CREATE_RESET_COMMAND_BUFFER_BIT;
  pci.queueFamilyIndex = h.family;
  VkCommandPool pool = VK_NULL_HANDLE;
  ASSERT_EQ(vkCreateCommandPool(h.device, &pci, nullptr, &pool), VK_SUCCESS);
  VkCommandBufferAllocateInfo ai{VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
  ai.commandPool = pool;
  ai.commandBufferCount = 1;
  VkCommandBuffer cmd = VK_NULL_HANDLE;
  ASSERT_EQ(vkAllocateCommandBuffers(h.device, &ai, &cmd), VK_SUCCESS);

  const VegetationModel model = makeLeafCloud(3000, 3, false);
  CanopyDesc desc;
  desc.width = w;
  desc.height = hgt;
  desc.colorFormat = cd.format;
  desc.depthFormat = dd.format;
  CanopyContext* ctx = nullptr;
  const Status created = createCanopy(d, model, desc, &ctx);
  ASSERT_TRUE(created.ok()) << created.message();
  const LayerView view = orbitView(model.boundsMin, model.boundsMax, 20.0f, 10.0f, 40.0f, float(w) / float(hgt), 1.05f);
  const ResourceState colorAfterPass{VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT, VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT,
                                     VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL};
  const ResourceState depthAfterPass{VK_PIPELINE_STAGE_2_EARLY_FRAGMENT_TESTS_BIT | VK_PIPELINE_STAGE_2_LATE_FRAGMENT_TESTS_BIT,
                                     VK_ACCESS_2_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT, VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL};
  const ResourceState transferSrc{VK_PIPELINE_STAGE_2_COPY_BIT, VK_ACCESS_2_TRANSFER_READ_BIT, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL};
  for (uint64_t frame = 1; frame <= 3; ++frame) {
    VkCommandBufferBeginInfo bi{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
    ASSERT_EQ(vkBeginCommandBuffer(cmd, &bi), VK_SUCCESS);
    VkClearValue clears[2] = {};
    clears[0].color = {{0.45f, 0.6f, 0.8f, 1.0f}};
    clears[1].depthStencil = {1.0f, 0};
    VkRenderPassBeginInfo rb{VK_STRUCTURE_TYPE_RENDER_PASS_BEGIN_INFO};
    rb.renderPass = pass;
    rb.framebuffer = fb;
    rb.renderArea = {{0, 0}, {w, hgt}};
    rb.clearValueCount = 2;
    rb.pClearValues = clears;
    vkCmdBeginRenderPass(cmd, &rb, VK_SUBPASS_CONTENTS_INLINE);
    vkCmdEndRenderPass(cmd);
    CanopyFrameInputs in;
    in.frame = makeCanopyFrame(view, 1.0f / 30.0f, frame);
    in.color = canopyImage(color.image, color.view, cd.usage, cd.format, colorAfterPass, transferSrc);
    in.depth = canopyImage(depth.image, depth.view, dd.usage, dd.format, depthAfterPass, depthAfterPass);
    const Status s = recordCanopy(ctx, cmd, in);
    ASSERT_TRUE(s.ok()) << s.message();
    ASSERT_EQ(vkEndCommandBuffer(cmd), VK_SUCCESS);
    VkSubmitInfo si{VK_STRUCTURE_TYPE_SUBMIT_INFO};
    si.commandBufferCount = 1;
    si.pCommandBuffers = &cmd;
    ASSERT_EQ(vkQueueSubmit(h.queue, 1, &si, VK_NULL_HANDLE), VK_SUCCESS);
    ASSERT_EQ(vkQueueWaitIdle(h.queue), VK_SUCCESS);
    EXPECT_EQ(messages.text(), "") << "frame " << frame << " without recordCanopyLoad";
  }
  // The vegetation is in the picture: pixels other than the host's clear.
  std::vector<uint8_t> px(size_t(w) * hgt * 4);
  ASSERT_TRUE(readbackImage(d, color, 0, 4, px.data(), rg::stateOf(rg::Use::TransferSrc)).ok());
  size_t drawn = 0;
  for (size_t i = 0; i < size_t(w) * hgt; ++i) drawn += std::abs(int(px[4 * i + 2]) - 204) > 8;
  EXPECT_GT(drawn, size_t(w) * hgt / 50) << "the leaves were composited";
  destroyCanopy(ctx);
  vkDestroyCommandPool(h.device, pool, nullptr);
  vkDestroyFramebuffer(h.device, fb, nullptr);
  vkDestroyRenderPass(h.device, pass, nullptr);
  destroyImage(d, color);
  destroyImage(d, depth);
  test::destroyHostDevice(h);
  EXPECT_EQ(messages.text(), "") << "validation messages";
}

class HostContractTest : public GpuTest {};

// Vulkan cannot be asked for an image's usage: the host declares it, and Canopy refuses what it
// cannot use, naming the image, the missing flag and the fix, before any barrier or descriptor
// reaches the validation layers.
TEST_F(HostContractTest, HostImagesAreCheckedAgainstWhatTheyWereDeclaredWith) {
  const VegetationModel model = makeLeafCloud(500, 3, true);
  struct Case {
    const char* name;
    std::function<void(CanopyFrameInputs&)> declare;
    const char* expect;
  };
  const Case cases[] = {
      {"depth without SAMPLED", [](CanopyFrameInputs& in) { in.depth.usage = VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT; },
       "depth (VkImage 0x"},
      {"usage not declared", [](CanopyFrameInputs& in) { in.color.usage = 0; }, "usage is not declared"},
      {"another format", [](CanopyFrameInputs& in) { in.color.format = VK_FORMAT_R8G8B8A8_UNORM; }, "is not the CanopyDesc format"},
      {"multisampled", [](CanopyFrameInputs& in) { in.depth.samples = VK_SAMPLE_COUNT_4_BIT; }, "single-sampled"},
      {"a depth view with the stencil", [](CanopyFrameInputs& in) {
         in.depth.viewAspects = VK_IMAGE_ASPECT_DEPTH_BIT | VK_IMAGE_ASPECT_STENCIL_BIT;
       }, "depth aspect only"},
  };
  for (const Case& k : cases) {
    SCOPED_TRACE(k.name);
    Host host;
    host.declare = k.declare;
    ASSERT_TRUE(host.create(dev, 1).ok());
    CanopyDesc d;
    d.width = host.w;
    d.height = host.h;
    d.colorFormat = host.colorFormat;
    CanopyContext* ctx = nullptr;
    ASSERT_TRUE(createCanopy(dev, model, d, &ctx).ok());
    const LayerView view = orbitView(model.boundsMin, model.boundsMax, 20.0f, 10.0f, 40.0f, 1.5f, 1.05f);
    Status refusal;
    ASSERT_TRUE(host.frame(1, {ctx}, view, 1.0f / 30.0f, false, nullptr, &refusal).ok());
    EXPECT_FALSE(refusal.ok());
    EXPECT_EQ(refusal.code(), Result::InvalidArgument);
    EXPECT_NE(refusal.message().find(k.expect), std::string::npos) << refusal.message();
    EXPECT_EQ(canopyStats(ctx).frames, 0u) << "a refused frame steps and records nothing";
    if (std::string(k.name) == "depth without SAMPLED")
      EXPECT_NE(refusal.message().find("lacks VK_IMAGE_USAGE_SAMPLED_BIT"), std::string::npos) << refusal.message();
    ASSERT_TRUE(host.finish().ok());
    destroyCanopy(ctx);
    host.destroy();
  }
}

// A host whose own passes use the stencil of a combined depth-stencil target around Canopy's: a
// pass before writes 0x33 into a rectangle (stencil REPLACE), Canopy renders through a depth-only
// view, a pass after increments where the stencil still equals 0x33. Read back: 0x34 in the
// rectangle (the stencil survived Canopy's passes and the test passed), the clear value elsewhere;
// no validation message (Canopy's barriers name both aspects with the host's layout; docs/embedding.md).
TEST_F(HostContractTest, TheHostsStencilPassesAroundCanopysKeepTheirStencil) {
  const VegetationModel model = makeLeafCloud(1500, 3, true);
  const EmbeddedShader* vs = findEmbeddedShader("composite.vert");  // one triangle over the target
  ASSERT_NE(vs, nullptr);
  int tested = 0;
  uint64_t frameNumber = 0;  // the host's counter never decreases on one device
  for (VkFormat f : {VK_FORMAT_D24_UNORM_S8_UINT, VK_FORMAT_D32_SFLOAT_S8_UINT}) {
    VkFormatProperties fp;
    vkGetPhysicalDeviceFormatProperties(dev.physical, f, &fp);
    const VkFormatFeatureFlags need = VK_FORMAT_FEATURE_DEPTH_STENCIL_ATTACHMENT_BIT | VK_FORMAT_FEATURE_SAMPLED_IMAGE_BIT;
    if ((fp.optimalTilingFeatures & need) != need) {
      std::printf("format %d is not a sampled depth-stencil attachment on this device; not tested\n", int(f));
      continue;
    }
    tested++;
    SCOPED_TRACE("format " + std::to_string(int(f)));
    // The host's stencil pipelines: no colour, no depth test, the stencil only.
    VkShaderModuleCreateInfo mci{VK_STRUCTURE_TYPE_SHADER_MODULE_CREATE_INFO};
    mci.codeSize = vs->sizeBytes;
    mci.pCode = vs->code;
    VkShaderModule module = VK_NULL_HANDLE;
    ASSERT_EQ(vkCreateShaderModule(dev.device, &mci, nullptr, &module), VK_SUCCESS);
    VkPipelineLayoutCreateInfo lci{VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO};
    VkPipelineLayout layout = VK_NULL_HANDLE;
    ASSERT_EQ(vkCreatePipelineLayout(dev.device, &lci, nullptr, &layout), VK_SUCCESS);
    auto pipeline = [&](VkCompareOp compare, VkStencilOp pass) {
      VkPipelineShaderStageCreateInfo stage{VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO};
      stage.stage = VK_SHADER_STAGE_VERTEX_BIT;
      stage.module = module;
      stage.pName = "main";
      VkPipelineVertexInputStateCreateInfo vi{VK_STRUCTURE_TYPE_PIPELINE_VERTEX_INPUT_STATE_CREATE_INFO};
      VkPipelineInputAssemblyStateCreateInfo ia{VK_STRUCTURE_TYPE_PIPELINE_INPUT_ASSEMBLY_STATE_CREATE_INFO};
      ia.topology = VK_PRIMITIVE_TOPOLOGY_TRIANGLE_LIST;
      VkPipelineViewportStateCreateInfo vp{VK_STRUCTURE_TYPE_PIPELINE_VIEWPORT_STATE_CREATE_INFO};
      vp.viewportCount = vp.scissorCount = 1;
      VkPipelineRasterizationStateCreateInfo rs{VK_STRUCTURE_TYPE_PIPELINE_RASTERIZATION_STATE_CREATE_INFO};
      rs.polygonMode = VK_POLYGON_MODE_FILL;
      rs.cullMode = VK_CULL_MODE_NONE;
      rs.lineWidth = 1.0f;
      VkPipelineMultisampleStateCreateInfo ms{VK_STRUCTURE_TYPE_PIPELINE_MULTISAMPLE_STATE_CREATE_INFO};
      ms.rasterizationSamples = VK_SAMPLE_COUNT_1_BIT;
      VkPipelineDepthStencilStateCreateInfo ds{VK_STRUCTURE_TYPE_PIPELINE_DEPTH_STENCIL_STATE_CREATE_INFO};
      ds.stencilTestEnable = VK_TRUE;
      ds.front = {VK_STENCIL_OP_KEEP, pass, VK_STENCIL_OP_KEEP, compare, 0xff, 0xff, 0x33};
      ds.back = ds.front;
      VkPipelineColorBlendStateCreateInfo cb{VK_STRUCTURE_TYPE_PIPELINE_COLOR_BLEND_STATE_CREATE_INFO};
      const VkDynamicState dyn[] = {VK_DYNAMIC_STATE_VIEWPORT, VK_DYNAMIC_STATE_SCISSOR};
      VkPipelineDynamicStateCreateInfo dy{VK_STRUCTURE_TYPE_PIPELINE_DYNAMIC_STATE_CREATE_INFO};
      dy.dynamicStateCount = 2;
      dy.pDynamicStates = dyn;
      VkPipelineRenderingCreateInfo ri{VK_STRUCTURE_TYPE_PIPELINE_RENDERING_CREATE_INFO};
      ri.depthAttachmentFormat = f;
      ri.stencilAttachmentFormat = f;
      VkGraphicsPipelineCreateInfo gp{VK_STRUCTURE_TYPE_GRAPHICS_PIPELINE_CREATE_INFO, &ri};
      gp.stageCount = 1;
      gp.pStages = &stage;
      gp.pVertexInputState = &vi;
      gp.pInputAssemblyState = &ia;
      gp.pViewportState = &vp;
      gp.pRasterizationState = &rs;
      gp.pMultisampleState = &ms;
      gp.pDepthStencilState = &ds;
      gp.pColorBlendState = &cb;
      gp.pDynamicState = &dy;
      gp.layout = layout;
      VkPipeline p = VK_NULL_HANDLE;
      EXPECT_EQ(vkCreateGraphicsPipelines(dev.device, VK_NULL_HANDLE, 1, &gp, nullptr, &p), VK_SUCCESS);
      return p;
    };
    const VkPipeline write = pipeline(VK_COMPARE_OP_ALWAYS, VK_STENCIL_OP_REPLACE);
    const VkPipeline test = pipeline(VK_COMPARE_OP_EQUAL, VK_STENCIL_OP_INCREMENT_AND_CLAMP);
    Host host;
    host.depthFormat = f;
    const VkRect2D rect{{20, 12}, {40, 30}};
    // One stencil pass on the depth-stencil view (both aspects), the depth and stencil kept.
    auto stencilPass = [&](rg::RenderGraph& g, rg::ResourceId depth, VkPipeline p, const char* name) {
      g.addPass(name, [&, p, depth](rg::PassContext& x) {
         VkRenderingAttachmentInfo a{VK_STRUCTURE_TYPE_RENDERING_ATTACHMENT_INFO};
         a.imageView = host.depth.view;
         a.imageLayout = VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL;
         a.loadOp = VK_ATTACHMENT_LOAD_OP_LOAD;
         a.storeOp = VK_ATTACHMENT_STORE_OP_STORE;
         VkRenderingInfo ri{VK_STRUCTURE_TYPE_RENDERING_INFO};
         ri.renderArea = {{0, 0}, {host.w, host.h}};
         ri.layerCount = 1;
         ri.pDepthAttachment = &a;
         ri.pStencilAttachment = &a;
         x.device->cmdBeginRendering(x.cmd, &ri);
         const VkViewport v{0, 0, float(host.w), float(host.h), 0, 1};
         vkCmdSetViewport(x.cmd, 0, 1, &v);
         vkCmdSetScissor(x.cmd, 0, 1, &rect);
         vkCmdBindPipeline(x.cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, p);
         vkCmdDraw(x.cmd, 3, 1, 0, 0);
         x.device->cmdEndRendering(x.cmd);
         return Status();
       }).write(depth, rg::Use::DepthAttachmentWrite);
    };
    host.passesBefore = [&](rg::RenderGraph& g, rg::ResourceId, rg::ResourceId d) { stencilPass(g, d, write, "host: stencil write"); };
    host.passesAfter = [&](rg::RenderGraph& g, rg::ResourceId, rg::ResourceId d) { stencilPass(g, d, test, "host: stencil test"); };
    ASSERT_TRUE(host.create(dev, 2).ok());
    CanopyDesc d;
    d.width = host.w;
    d.height = host.h;
    d.colorFormat = host.colorFormat;
    d.depthFormat = f;
    CanopyContext* ctx = nullptr;
    ASSERT_TRUE(createCanopy(dev, model, d, &ctx).ok());
    const LayerView view = orbitView(model.boundsMin, model.boundsMax, 20.0f, 10.0f, 40.0f, float(host.w) / float(host.h), 1.05f);
    for (int frame = 0; frame < 3; ++frame) {
      const Status s = host.frame(++frameNumber, {ctx}, view, 1.0f / 30.0f);
      ASSERT_TRUE(s.ok()) << s.message();
    }
    std::vector<glm::vec4> color;
    std::vector<float> z;
    std::vector<uint8_t> stencil;
    ASSERT_TRUE(host.read(&color, &z, &stencil).ok());
    size_t inside = 0, insideKept = 0, outsideKept = 0, vegetation = 0;
    for (uint32_t y = 0; y < host.h; ++y)
      for (uint32_t x = 0; x < host.w; ++x) {
        const size_t i = size_t(y) * host.w + x;
        const bool in = x >= uint32_t(rect.offset.x) && x < rect.offset.x + rect.extent.width && y >= uint32_t(rect.offset.y) &&
                        y < rect.offset.y + rect.extent.height;
        inside += in;
        insideKept += in && stencil[i] == 0x34;
        outsideKept += !in && stencil[i] == test::kStencil;
        vegetation += z[i] < 1.0f;
      }
    EXPECT_EQ(insideKept, inside) << "the host's stencil test after Canopy found its 0x33 and incremented it";
    EXPECT_EQ(outsideKept, stencil.size() - inside) << "outside the rectangle the clear value stays";
    EXPECT_GT(vegetation, stencil.size() / 20) << "Canopy drew through the depth-only view";
    destroyCanopy(ctx);
    ASSERT_TRUE(host.finish().ok());
    host.destroy();
    vkDestroyPipeline(dev.device, write, nullptr);
    vkDestroyPipeline(dev.device, test, nullptr);
    vkDestroyPipelineLayout(dev.device, layout, nullptr);
    vkDestroyShaderModule(dev.device, module, nullptr);
  }
  EXPECT_GT(tested, 0) << "no combined depth-stencil format is a sampled attachment here";
}

}  // namespace
