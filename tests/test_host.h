#pragma once
// A host for GPU tests: its own colour and depth(-stencil) targets, command buffers and fences,
// `frames` recorded frames with at most `inFlight` submitted and not yet waited for; Canopy
// recorded by recordCanopy or as one pass of the host's render graph. Used by the embedding and
// parameter-fuzz tests.
#include <cmath>
#include <cstring>
#include <functional>
#include <vector>

#include <glm/gtc/packing.hpp>
#include <canopy/canopy_graph.h>

#include "engine/transfer.h"
#include "render/canopy.h"

namespace canopy::test {

const glm::vec4 kSky(0.45f, 0.6f, 0.8f, 1.0f);
constexpr uint8_t kStencil = 0x5a;

// A host with its own colour and depth-(stencil) targets and its own command buffers and fences:
// `frames` recorded frames, at most `inFlight` submitted and not yet waited for.
struct Host {
  Device* dev = nullptr;
  uint32_t w = 96, h = 64;
  VkFormat colorFormat = VK_FORMAT_R16G16B16A16_SFLOAT, depthFormat = VK_FORMAT_D32_SFLOAT;
  bool reverse = false;
  bool motion = false;  // a motion target (R16G16_SFLOAT, pixels) cleared to 0 each frame: CanopyDesc.motionFormat
  Image color, depth, motionImage;
  VkImageView depthOnly = VK_NULL_HANDLE;  // the depth aspect of a depth-stencil target
  VkCommandPool pool = VK_NULL_HANDLE;
  std::vector<VkCommandBuffer> cmds;
  std::vector<VkFence> fences;
  std::vector<bool> pending;
  bool first = true;  // the targets hold nothing yet (UNDEFINED)
  // Canopy as one pass of the host's graph (<canopy/canopy_graph.h>) instead of recordCanopy.
  bool passGroup = false;
  // Changes what the host declares of its images (CanopyImage) before Canopy sees them (tests of
  // the contract's checks); null: declared as create() made them.
  std::function<void(CanopyFrameInputs&)> declare;
  // The host's own passes on its targets before Canopy's (after the clear) and after them, in
  // graphs of their own (their barriers from the graph); null: none.
  std::function<void(rg::RenderGraph&, rg::ResourceId color, rg::ResourceId depth)> passesBefore, passesAfter;
  // Changes each context's camera as the host gives it (a viewport, a jitter, a GL clip depth); null: none.
  std::function<void(CanopyCamera&)> adjustCamera;
  // Recorded after the contexts, into the frame's command buffer (a shadow: recordCanopyShadow); null: none.
  std::function<Status(VkCommandBuffer)> recordAfter;

  Status create(Device& d, uint32_t inFlight) {
    dev = &d;
    ImageDesc c;
    c.format = colorFormat;
    c.width = w;
    c.height = h;
    c.usage = VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT | VK_IMAGE_USAGE_TRANSFER_DST_BIT;
    CANOPY_TRY(createImage(d, c, &color, "host colour"));
    if (motion) {
      c.format = VK_FORMAT_R16G16_SFLOAT;
      CANOPY_TRY(createImage(d, c, &motionImage, "host motion"));
    }
    c.format = depthFormat;
    c.usage = VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT | VK_IMAGE_USAGE_SAMPLED_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT |
              VK_IMAGE_USAGE_TRANSFER_DST_BIT;
    CANOPY_TRY(createImage(d, c, &depth, "host depth"));
    VkImageViewCreateInfo vi{VK_STRUCTURE_TYPE_IMAGE_VIEW_CREATE_INFO};
    vi.image = depth.image;
    vi.viewType = VK_IMAGE_VIEW_TYPE_2D;
    vi.format = depthFormat;
    vi.subresourceRange = {VK_IMAGE_ASPECT_DEPTH_BIT, 0, 1, 0, 1};
    CANOPY_VK(vkCreateImageView(d.device, &vi, nullptr, &depthOnly));
    VkCommandPoolCreateInfo pci{VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO};
    pci.flags = VK_COMMAND_POOL_CREATE_RESET_COMMAND_BUFFER_BIT;
    pci.queueFamilyIndex = d.queueFamily;
    CANOPY_VK(vkCreateCommandPool(d.device, &pci, nullptr, &pool));
    cmds.resize(inFlight);
    VkCommandBufferAllocateInfo ai{VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
    ai.commandPool = pool;
    ai.commandBufferCount = inFlight;
    CANOPY_VK(vkAllocateCommandBuffers(d.device, &ai, cmds.data()));
    fences.resize(inFlight);
    pending.assign(inFlight, false);
    for (VkFence& f : fences) {
      VkFenceCreateInfo fci{VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
      CANOPY_VK(vkCreateFence(d.device, &fci, nullptr, &f));
    }
    return Status();
  }
  void destroy() {
    (void)finish();  // best effort: destroy() runs after failures too
    for (VkFence f : fences) vkDestroyFence(dev->device, f, nullptr);
    if (pool) vkDestroyCommandPool(dev->device, pool, nullptr);
    if (depthOnly) vkDestroyImageView(dev->device, depthOnly, nullptr);
    destroyImage(*dev, color);
    destroyImage(*dev, depth);
    if (motion) destroyImage(*dev, motionImage);
  }
  Status wait(size_t slot) {
    if (!pending[slot]) return Status();
    CANOPY_VK(vkWaitForFences(dev->device, 1, &fences[slot], VK_TRUE, UINT64_MAX));
    CANOPY_VK(vkResetFences(dev->device, 1, &fences[slot]));
    pending[slot] = false;
    return Status();
  }
  Status finish() {
    for (size_t i = 0; i < fences.size(); ++i) CANOPY_TRY(wait(i));
    return Status();
  }
  // One host frame: clear colour, depth (far) and stencil, then every context, no wait.
  // With `refusal`, a context that refuses the frame (its Status stored there) leaves the frame to
  // the host, which still moves its images to where the next frame expects them and submits.
  Status frame(uint64_t number, const std::vector<CanopyContext*>& contexts, const LayerView& view, float dt,
               bool cut = false, const CanopyCamera* camera = nullptr, Status* refusal = nullptr) {
    const size_t slot = number % cmds.size();
    CANOPY_TRY(wait(slot));
    VkCommandBuffer cmd = cmds[slot];
    VkCommandBufferBeginInfo bi{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
    CANOPY_VK(vkBeginCommandBuffer(cmd, &bi));
    const rg::State colorRW = rg::stateOf(rg::Use::ColorAttachmentReadWrite), depthW = rg::stateOf(rg::Use::DepthAttachmentWrite),
                    src = rg::stateOf(rg::Use::TransferSrc), dst = rg::stateOf(rg::Use::TransferDst);
    rg::RenderGraph g;  // the host's own clear, its barriers from a graph too
    const rg::State before = first ? rg::State{} : src;  // as the previous frame left them
    first = false;
    std::vector<CanopyFrameInputs> inputs(contexts.size());
    for (size_t i = 0; i < contexts.size(); ++i) {
      CanopyFrameInputs& in = inputs[i];
      in.frame = makeCanopyFrame(view, dt, number);
      in.frame.cameraCut = cut;
      if (camera) in.frame.camera = *camera;
      if (reverse) {
        glm::mat4 mirror(1.0f);  // the same camera as a reverse-Z host writes it
        mirror[2][2] = -1.0f;
        mirror[3][2] = 1.0f;
        in.frame.camera.proj = toFloat4x4(mirror * view.proj);
      }
      const bool last = i + 1 == contexts.size();
      // Declared as create() made them (CanopyImage: Canopy checks the declaration).
      in.color = canopyImage(color.image, color.view, VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT | VK_IMAGE_USAGE_TRANSFER_DST_BIT, colorFormat,
                             i ? colorRW : dst, last ? src : colorRW);
      in.depth = canopyImage(depth.image, depthOnly, VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT | VK_IMAGE_USAGE_SAMPLED_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT | VK_IMAGE_USAGE_TRANSFER_DST_BIT,
                             depthFormat, i ? depthW : dst, last ? src : depthW);
      if (motion)
        in.motion = canopyImage(motionImage.image, motionImage.view, VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT | VK_IMAGE_USAGE_TRANSFER_DST_BIT,
                                VK_FORMAT_R16G16_SFLOAT, i ? colorRW : dst, last ? src : colorRW);
      if (adjustCamera) adjustCamera(in.frame.camera);
      if (declare) declare(in);
    }
    const auto c = g.importImage("host colour", descOf(color), before, passGroup ? src : dst);
    const auto d = g.importImage("host depth", descOf(depth), before, passGroup ? src : dst);
    const auto m = motion ? g.importImage("host motion", descOf(motionImage), before, dst) : rg::kInvalidResource;
    auto clear = g.addPass("host clear", [&](rg::PassContext& x) {
       VkClearColorValue cv{};
       std::memcpy(cv.float32, &kSky, sizeof kSky);
       const VkImageSubresourceRange cr{VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, 1};
       const VkImageSubresourceRange dr{aspectOf(depthFormat), 0, 1, 0, 1};
       vkCmdClearColorImage(x.cmd, x.image(c).image, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, &cv, 1, &cr);
       VkClearDepthStencilValue dv{reverse ? 0.0f : 1.0f, kStencil};
       vkCmdClearDepthStencilImage(x.cmd, x.image(d).image, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, &dv, 1, &dr);
       if (motion) {
         const VkClearColorValue zero{};
         vkCmdClearColorImage(x.cmd, x.image(m).image, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, &zero, 1, &cr);
       }
       return Status();
     })
        .write(c, rg::Use::TransferDst)
        .write(d, rg::Use::TransferDst);
    if (motion) {
      if (passGroup) return Status::error("the test host's motion target is for recordCanopy");
      clear.write(m, rg::Use::TransferDst);
    }
    if (passesBefore) passesBefore(g, c, d);
    for (size_t i = 0; passGroup && i < contexts.size(); ++i) {
      // Each context one pass of the host's graph, declared with the uses Canopy reports.
      std::vector<CanopyTargetUse> uses;
      CANOPY_TRY(canopyPassGroupUses(contexts[i], &uses));
      CanopyContext* ctx = contexts[i];
      const CanopyFrameInputs* in = &inputs[i];
      auto pass = g.addPass("canopy", [ctx, in](rg::PassContext& x) { return recordCanopyPassGroup(ctx, x.cmd, *in); });
      for (const CanopyTargetUse& u : uses) {
        if (u.target == CanopyTarget::Motion) return Status::error("the test host has no motion target");
        pass.access(u.target == CanopyTarget::Color ? c : d, u.state);
      }
    }
    CANOPY_TRY(g.bindImage(c, color));
    CANOPY_TRY(g.bindImage(d, depth));
    if (motion) CANOPY_TRY(g.bindImage(m, motionImage));
    CANOPY_TRY(g.compile());
    CANOPY_TRY(g.realize(*dev));  // no transients: nothing to release
    CANOPY_TRY(g.record(cmd));
    for (size_t i = 0; !passGroup && i < contexts.size(); ++i) {
      Status s = recordCanopy(contexts[i], cmd, inputs[i]);
      if (s.ok()) continue;
      if (!refusal || contexts.size() != 1) return s;
      *refusal = s;
      rg::RenderGraph after;  // what Canopy would have done to the images' states
      const auto ca = after.importImage("host colour", descOf(color), dst, src);
      const auto da = after.importImage("host depth", descOf(depth), dst, src);
      CANOPY_TRY(after.bindImage(ca, color));
      CANOPY_TRY(after.bindImage(da, depth));
      if (motion) CANOPY_TRY(after.bindImage(after.importImage("host motion", descOf(motionImage), dst, src), motionImage));
      CANOPY_TRY(after.compile());
      CANOPY_TRY(after.realize(*dev));  // no transients
      CANOPY_TRY(after.record(cmd));
    }
    if (recordAfter) CANOPY_TRY(recordAfter(cmd));
    if (passesAfter) {
      rg::RenderGraph after;
      const auto ca = after.importImage("host colour", descOf(color), src, src);
      const auto da = after.importImage("host depth", descOf(depth), src, src);
      passesAfter(after, ca, da);
      CANOPY_TRY(after.bindImage(ca, color));
      CANOPY_TRY(after.bindImage(da, depth));
      CANOPY_TRY(after.compile());
      CANOPY_TRY(after.realize(*dev));
      CANOPY_TRY(after.record(cmd));
    }
    CANOPY_VK(vkEndCommandBuffer(cmd));
    VkSubmitInfo si{VK_STRUCTURE_TYPE_SUBMIT_INFO};
    si.commandBufferCount = 1;
    si.pCommandBuffers = &cmd;
    CANOPY_VK(vkQueueSubmit(dev->queue, 1, &si, fences[slot]));
    pending[slot] = true;
    return Status();
  }
  // After finish(): the motion target, pixels (current minus previous position).
  Status readMotion(std::vector<glm::vec2>* out) {
    CANOPY_TRY(finish());
    std::vector<uint32_t> px(size_t(w) * h);
    CANOPY_TRY(readbackImage(*dev, motionImage, 0, 4, px.data(), rg::stateOf(rg::Use::TransferSrc)));
    out->clear();
    for (uint32_t v : px) out->push_back(glm::unpackHalf2x16(v));
    return Status();
  }
  // After finish(): colour as linear float, depth as float, stencil bytes (depth-stencil formats).
  Status read(std::vector<glm::vec4>* rgba, std::vector<float>* z, std::vector<uint8_t>* stencil = nullptr) {
    CANOPY_TRY(finish());
    const rg::State src = rg::stateOf(rg::Use::TransferSrc);
    const size_t n = size_t(w) * h;
    rgba->clear();
    if (colorFormat == VK_FORMAT_R16G16B16A16_SFLOAT) {
      std::vector<uint64_t> half(n);
      CANOPY_TRY(readbackImage(*dev, color, 0, 8, half.data(), src));
      for (uint64_t v : half) rgba->push_back(glm::unpackHalf4x16(v));
    } else if (colorFormat == VK_FORMAT_B10G11R11_UFLOAT_PACK32) {  // no alpha channel: reads as 1
      std::vector<uint32_t> packed(n);
      CANOPY_TRY(readbackImage(*dev, color, 0, 4, packed.data(), src));
      for (uint32_t v : packed) rgba->push_back(glm::vec4(glm::unpackF2x11_1x10(v), 1.0f));
    } else {  // 8-bit sRGB: decoded to linear
      std::vector<uint8_t> b(n * 4);
      CANOPY_TRY(readbackImage(*dev, color, 0, 4, b.data(), src));
      auto lin = [](uint8_t v) {
        const float c = v / 255.0f;
        return c <= 0.04045f ? c / 12.92f : std::pow((c + 0.055f) / 1.055f, 2.4f);
      };
      for (size_t i = 0; i < n; ++i) rgba->push_back({lin(b[4 * i]), lin(b[4 * i + 1]), lin(b[4 * i + 2]), b[4 * i + 3] / 255.0f});
    }
    Image depthAspect = depth;
    depthAspect.aspect = VK_IMAGE_ASPECT_DEPTH_BIT;
    std::vector<uint32_t> raw(n);
    CANOPY_TRY(readbackImage(*dev, depthAspect, 0, 4, raw.data(), src));
    z->resize(n);
    for (size_t i = 0; i < n; ++i) {
      if (depthFormat == VK_FORMAT_D24_UNORM_S8_UINT) (*z)[i] = float(raw[i] & 0xffffff) / float(0xffffff);
      else std::memcpy(&(*z)[i], &raw[i], 4);
    }
    if (stencil) {
      Image s = depth;
      s.aspect = VK_IMAGE_ASPECT_STENCIL_BIT;
      stencil->resize(n);
      CANOPY_TRY(readbackImage(*dev, s, 0, 1, stencil->data(), src));
    }
    return Status();
  }
};

inline float maxDiff(const glm::vec4& a, const glm::vec4& b) {
  const glm::vec4 d = glm::abs(a - b);
  return std::max(std::max(d.x, d.y), std::max(d.z, d.w));
}

// Share of pixels whose colour differs by more than `tol` (any channel).
inline double differing(const std::vector<glm::vec4>& a, const std::vector<glm::vec4>& b, float tol) {
  if (a.empty() || a.size() != b.size()) return 1.0;
  size_t n = 0;
  for (size_t i = 0; i < a.size(); ++i) n += maxDiff(a[i], b[i]) > tol;
  return double(n) / double(a.size());
}


// A context on `species` with `instances` (the wind's strength `wind`; `perVertex`: the per-vertex
// baseline draws it) for `host`'s targets, which are created here at host.w x host.h.
inline Status createHostContext(Device& dev, Host& host, const std::vector<SpeciesModel>& species,
                                const std::vector<CanopyInstance>& instances, float wind, bool perVertex, CanopyContext** ctx) {
  CANOPY_TRY(host.create(dev, 1));
  CanopyDesc d;
  d.width = host.w;
  d.height = host.h;
  d.colorFormat = host.colorFormat;
  d.instances = instances;
  d.params.windMode = WindMode::PlaneSides;  // the wind as the plane's sides (domain units/s)
  d.params.simulation.wind.strength = wind;
  d.allowPerVertex = perVertex;
  if (perVertex) d.params.animation = AnimationMode::PerVertex;
  return createCanopy(dev, species, d, ctx);
}

// `frames` frames at `view` of a context on `species` with `instances` in a 160x120 host (frame
// numbers from `frameNumber`, which never decreases on the device), read back; the context's
// statistics in *stats (optional); everything destroyed after.
inline Status renderHostFrames(Device& dev, uint64_t& frameNumber, const std::vector<SpeciesModel>& species,
                               const std::vector<CanopyInstance>& instances, const LayerView& view, int frames,
                               std::vector<glm::vec4>* color, std::vector<float>* depth, CanopyStats* stats = nullptr,
                               bool perVertex = false, float wind = 1.0f) {
  Host host;
  host.w = 160;
  host.h = 120;
  CanopyContext* ctx = nullptr;
  Status s = createHostContext(dev, host, species, instances, wind, perVertex, &ctx);
  for (int i = 0; s.ok() && i < frames; ++i) s = host.frame(++frameNumber, {ctx}, view, 1.0f / 30.0f);
  if (s.ok()) s = host.read(color, depth);
  if (s.ok() && stats) *stats = canopyStats(ctx);
  if (ctx) destroyCanopy(ctx);
  host.destroy();
  return s;
}

}  // namespace canopy::test
