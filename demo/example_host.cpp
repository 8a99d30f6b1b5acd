// canopy-example-host: a minimal "engine" embedding Canopy through the record() path.
//
// The host owns its colour + depth targets and its own pass order and barriers (it has no render
// graph of its own, like many engines). Per frame it draws a ground plane and a box, lets Canopy
// record the animated vegetation into the same command buffer (recordCanopy), then draws one more
// box after Canopy, depth-tested against the depth Canopy wrote. It checks its own result: the
// post-vegetation box must be hidden exactly where the vegetation is in front of it.
//
//   canopy-example-host [--frames N] [--out DIR] [--validate]
// Exit 0 when the check passes, 1 on a failure, 2 on bad arguments.
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include <glm/gtc/matrix_transform.hpp>

#include "demo/cli.h"
#include "engine/graphics_pipeline.h"
#include "engine/image_io.h"
#include "engine/shader_registry.h"
#include "engine/transfer.h"
#include "render/canopy.h"
#include "render/leaf_cloud.h"

namespace example_host {
const canopy::EmbeddedShader* findEmbeddedShader(const char* name);  // the host's own shaders
}

using namespace canopy;

namespace {

constexpr uint32_t kW = 320, kH = 240;

struct BoxPush {
  glm::mat4 mvp;
  glm::vec4 color;
};

// The host's own barrier helper (Canopy's passes get theirs from Canopy's graph).
void hostBarrier(Device& d, VkCommandBuffer cmd, VkImage image, VkImageAspectFlags aspect, VkImageLayout from,
                 VkImageLayout to, VkPipelineStageFlags2 srcStage, VkAccessFlags2 srcAccess, VkPipelineStageFlags2 dstStage,
                 VkAccessFlags2 dstAccess) {
  VkImageMemoryBarrier2 b{VK_STRUCTURE_TYPE_IMAGE_MEMORY_BARRIER_2};
  b.srcStageMask = srcStage;
  b.srcAccessMask = srcAccess;
  b.dstStageMask = dstStage;
  b.dstAccessMask = dstAccess;
  b.oldLayout = from;
  b.newLayout = to;
  b.srcQueueFamilyIndex = b.dstQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
  b.image = image;
  b.subresourceRange = {aspect, 0, 1, 0, 1};
  VkDependencyInfo di{VK_STRUCTURE_TYPE_DEPENDENCY_INFO};
  di.imageMemoryBarrierCount = 1;
  di.pImageMemoryBarriers = &b;
  d.cmdPipelineBarrier2(cmd, &di);
}

struct Host {
  Device* dev = nullptr;
  Image color, depth;
  GraphicsPipeline boxes;
  LayerView camera;
  glm::vec3 crownCentre{0.0f};
};

const VkPipelineStageFlags2 kColorStage = VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT;
const VkAccessFlags2 kColorAccess = VK_ACCESS_2_COLOR_ATTACHMENT_READ_BIT | VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT;
const VkPipelineStageFlags2 kDepthStage =
    VK_PIPELINE_STAGE_2_EARLY_FRAGMENT_TESTS_BIT | VK_PIPELINE_STAGE_2_LATE_FRAGMENT_TESTS_BIT;
const VkAccessFlags2 kDepthAccess =
    VK_ACCESS_2_DEPTH_STENCIL_ATTACHMENT_READ_BIT | VK_ACCESS_2_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT;

Status drawBoxes(Host& h, VkCommandBuffer cmd, bool clear, const std::vector<BoxPush>& boxes) {
  VkRenderingAttachmentInfo c{VK_STRUCTURE_TYPE_RENDERING_ATTACHMENT_INFO}, z{VK_STRUCTURE_TYPE_RENDERING_ATTACHMENT_INFO};
  c.imageView = h.color.view;
  c.imageLayout = VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL;
  c.loadOp = clear ? VK_ATTACHMENT_LOAD_OP_CLEAR : VK_ATTACHMENT_LOAD_OP_LOAD;
  c.storeOp = VK_ATTACHMENT_STORE_OP_STORE;
  c.clearValue.color = {{0.45f, 0.6f, 0.8f, 1.0f}};
  z.imageView = h.depth.view;
  z.imageLayout = VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL;
  z.loadOp = c.loadOp;
  z.storeOp = VK_ATTACHMENT_STORE_OP_STORE;
  z.clearValue.depthStencil = {1.0f, 0};
  VkRenderingInfo ri{VK_STRUCTURE_TYPE_RENDERING_INFO};
  ri.renderArea = {{0, 0}, {kW, kH}};
  ri.layerCount = 1;
  ri.colorAttachmentCount = 1;
  ri.pColorAttachments = &c;
  ri.pDepthAttachment = &z;
  h.dev->cmdBeginRendering(cmd, &ri);
  setViewportScissor(cmd, kW, kH);
  Status s;
  for (size_t i = 0; i < boxes.size() && s.ok(); ++i) {
    s = i == 0 ? bindGraphics(*h.dev, cmd, h.boxes, {}, boxes[i]) : pushGraphicsConstants(cmd, h.boxes, &boxes[i], sizeof(BoxPush));
    if (s.ok()) vkCmdDraw(cmd, 36, 1, 0, 0);
  }
  h.dev->cmdEndRendering(cmd);
  return s;
}

BoxPush box(const Host& h, glm::vec3 centre, glm::vec3 size, glm::vec3 color) {
  const glm::mat4 model = glm::scale(glm::translate(glm::mat4(1.0f), centre), size);
  return {h.camera.proj * h.camera.view * model, glm::vec4(color, 1.0f)};
}

// One host frame: its scene, then (optionally) Canopy, then (optionally) the post-vegetation box.
Status frame(Host& h, CanopyContext* ctx, bool withCanopy, bool withPostBox, float dt) {
  return submitAndWait(*h.dev, [&](VkCommandBuffer cmd) -> Status {
    hostBarrier(*h.dev, cmd, h.color.image, VK_IMAGE_ASPECT_COLOR_BIT, VK_IMAGE_LAYOUT_UNDEFINED,
                VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL, VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT, VK_ACCESS_2_NONE,
                kColorStage, kColorAccess);
    hostBarrier(*h.dev, cmd, h.depth.image, VK_IMAGE_ASPECT_DEPTH_BIT, VK_IMAGE_LAYOUT_UNDEFINED,
                VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL, VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT,
                VK_ACCESS_2_NONE, kDepthStage, kDepthAccess);
    const float groundY = -1.9f;
    CANOPY_TRY(drawBoxes(h, cmd, true,
                         {box(h, {0, groundY - 0.05f, 0}, {8, 0.1f, 8}, {0.3f, 0.45f, 0.2f}),
                          box(h, {1.6f, groundY + 0.4f, -0.8f}, {0.8f, 0.8f, 0.8f}, {0.6f, 0.6f, 0.65f})}));
    if (withCanopy) {
      // The host's images arrive as its scene pass left them and must come back the same way.
      CanopyFrameInputs in;
      in.frame.camera = h.camera;
      in.frame.dt = dt;
      in.color = {h.color.image, h.color.view, {kColorStage, kColorAccess, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL},
                  {kColorStage, kColorAccess, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL}};
      in.depth = {h.depth.image, h.depth.view,
                  {kDepthStage, kDepthAccess, VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL},
                  {kDepthStage, kDepthAccess, VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL}};
      CANOPY_TRY(recordCanopy(ctx, cmd, in));
    }
    if (withPostBox)
      CANOPY_TRY(drawBoxes(h, cmd, false, {box(h, h.crownCentre + glm::vec3(0.1f, -0.1f, 0.0f), {0.9f, 0.9f, 0.9f},
                                                 {1.0f, 0.0f, 0.0f})}));
    return Status();
  });
}

Status read(Host& h, std::vector<uint8_t>* rgba, std::vector<float>* z) {
  rgba->resize(size_t(kW) * kH * 4);
  z->resize(size_t(kW) * kH);
  CANOPY_TRY(readbackImage(*h.dev, h.color, 0, 4, rgba->data(),
                           {kColorStage, kColorAccess, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL}));
  return readbackImage(*h.dev, h.depth, 0, 4, z->data(),
                       {kDepthStage, kDepthAccess, VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL});
}

bool isPostBoxRed(const uint8_t* p) { return p[0] > 100 && p[1] < 20 && p[2] < 20; }

int run(int frames, const std::string& outDir, bool validate) {
  DeviceDesc dd;
  dd.applicationName = "canopy-example-host";
  int messages = 0;
  if (validate) {
    dd.enableValidation = dd.requireValidation = true;
    dd.validationSink = [&](VkDebugUtilsMessageSeverityFlagBitsEXT, const char* id, const char* text) {
      ++messages;
      std::fprintf(stderr, "validation: %s: %s\n", id ? id : "", text);
    };
  }
  Device dev;
  Status s = createDevice(dd, &dev);
  if (!s.ok()) {
    std::fprintf(stderr, "canopy-example-host: %s\n", s.message().c_str());
    return 1;
  }
  Host h;
  h.dev = &dev;
  CanopyContext* ctx = nullptr;
  int rc = 1;
  s = [&]() -> Status {
    ImageDesc c;
    c.format = VK_FORMAT_R8G8B8A8_UNORM;
    c.width = kW;
    c.height = kH;
    c.usage = VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT;
    CANOPY_TRY(createImage(dev, c, &h.color, "host colour"));
    c.format = VK_FORMAT_D32_SFLOAT;  // sampled: Canopy reads it to put the host's scene between layers
    c.usage = VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT | VK_IMAGE_USAGE_SAMPLED_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT;
    CANOPY_TRY(createImage(dev, c, &h.depth, "host depth"));
    GraphicsPipelineDesc pd;
    pd.vertexShader = "host_box.vert";
    pd.fragmentShader = "host_box.frag";
    pd.shaderLookup = &example_host::findEmbeddedShader;
    pd.pushConstantSize = sizeof(BoxPush);
    pd.colorFormats = {VK_FORMAT_R8G8B8A8_UNORM};
    pd.depthFormat = VK_FORMAT_D32_SFLOAT;
    CANOPY_TRY(createGraphicsPipeline(dev, pd, &h.boxes));

    const VegetationModel model = makeLeafCloud(6000, 21, true);
    h.crownCentre = glm::vec3(0.0f);  // the leaf cloud's crown is the unit sphere at the origin
    h.camera = orbitView(model.boundsMin, model.boundsMax, 25.0f, 12.0f, 45.0f, float(kW) / float(kH), 1.2f);
    CanopyDesc desc;
    desc.width = kW;
    desc.height = kH;
    desc.colorFormat = VK_FORMAT_R8G8B8A8_UNORM;
    desc.depthFormat = VK_FORMAT_D32_SFLOAT;
    desc.useRootCache = false;
    CANOPY_TRY(createCanopy(dev, model, desc, &ctx));
    CanopyParams p = canopyParams(ctx);
    p.simulation.wind.strength = 1.5f;
    CANOPY_TRY(setCanopyParams(ctx, p));

    // The frames the host would show, then the check on the last one: vegetation depth alone
    // (Canopy, no post box), the post box alone (no Canopy), and both.
    std::vector<uint8_t> both, tmp;
    std::vector<float> vegDepth, boxDepth, z;
    for (int i = 0; i < frames; ++i) CANOPY_TRY(frame(h, ctx, true, true, 1.0f / 30.0f));
    CANOPY_TRY(read(h, &both, &z));
    CANOPY_TRY(frame(h, ctx, true, false, 0.0f));  // dt = 0: the same vegetation pose
    CANOPY_TRY(read(h, &tmp, &vegDepth));
    CANOPY_TRY(frame(h, ctx, false, true, 0.0f));
    CANOPY_TRY(read(h, &tmp, &boxDepth));
    std::vector<float> sceneDepth;
    CANOPY_TRY(frame(h, ctx, false, false, 0.0f));
    CANOPY_TRY(read(h, &tmp, &sceneDepth));
    size_t hidden = 0, shown = 0, wrong = 0;
    for (size_t i = 0; i < vegDepth.size(); ++i) {
      if (!(boxDepth[i] < sceneDepth[i])) continue;  // the post box is not drawn here
      const bool red = isPostBoxRed(&both[i * 4]);
      if (vegDepth[i] < boxDepth[i]) {
        hidden++;
        wrong += red;  // vegetation in front: the box must be hidden
      } else {
        shown++;
        wrong += !red;
      }
    }
    std::printf("canopy-example-host: %ux%u, %d frames; post-vegetation box: %zu px behind vegetation (hidden), "
                "%zu px in front (shown), %zu px wrong\n",
                kW, kH, frames, hidden, shown, wrong);
    if (!outDir.empty()) {
      std::filesystem::create_directories(outDir);
      for (size_t i = 3; i < both.size(); i += 4) both[i] = 255;
      CANOPY_TRY(writePng(outDir + "/example_host.png", kW, kH, both));
      std::printf("wrote %s/example_host.png\n", outDir.c_str());
    }
    if (hidden == 0 || shown == 0) return Status::error("the check needs the box both behind and in front of leaves");
    if (wrong > (hidden + shown) / 100)
      return Status::error(std::to_string(wrong) + " pixels of the post box disagree with the vegetation's depth");
    rc = 0;
    return Status();
  }();
  if (!s.ok()) std::fprintf(stderr, "canopy-example-host: %s\n", s.message().c_str());
  vkDeviceWaitIdle(dev.device);
  destroyCanopy(ctx);
  destroyGraphicsPipeline(dev, h.boxes);
  destroyImage(dev, h.color);
  destroyImage(dev, h.depth);
  destroyDevice(dev);
  if (messages > 0) {
    std::fprintf(stderr, "canopy-example-host: %d validation messages\n", messages);
    return 1;
  }
  return s.ok() ? rc : 1;
}

}  // namespace

int main(int argc, char** argv) {
  uint32_t frames = 10;
  std::string out;
  bool validate = false;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto next = [&]() -> const char* { return i + 1 < argc ? argv[++i] : nullptr; };
    if (a == "--help" || a == "-h") {
      std::printf("usage: canopy-example-host [--frames N (1..1000, default 10)] [--out DIR] [--validate]\n");
      return 0;
    }
    if (a == "--frames") {
      if (!cli::parseUint(next(), 1, 1000, &frames)) {
        std::fprintf(stderr, "canopy-example-host: --frames needs an integer in [1, 1000]\n");
        return 2;
      }
    } else if (a == "--out") {
      const char* v = next();
      if (!v) {
        std::fprintf(stderr, "canopy-example-host: --out needs a folder\n");
        return 2;
      }
      out = v;
    } else if (a == "--validate") {
      validate = true;
    } else {
      std::fprintf(stderr, "canopy-example-host: unknown argument '%s'\n", a.c_str());
      return 2;
    }
  }
  return run(int(frames), out, validate);
}
