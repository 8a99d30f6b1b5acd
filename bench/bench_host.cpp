#include "bench/bench_host.h"

#include <chrono>

#include "engine/device.h"
#include "engine/timing.h"

namespace canopy::bench {

Status createHostTargets(Device& d, uint32_t w, uint32_t h, VkFormat format, HostTargets* t) {
  ImageDesc c;
  c.format = format;
  c.width = w;
  c.height = h;
  c.usage = VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | VK_IMAGE_USAGE_TRANSFER_DST_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT;
  CANOPY_TRY(createImage(d, c, &t->color, "bench host colour"));
  c.format = VK_FORMAT_D32_SFLOAT;
  c.usage = VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT | VK_IMAGE_USAGE_SAMPLED_BIT | VK_IMAGE_USAGE_TRANSFER_DST_BIT |
            VK_IMAGE_USAGE_TRANSFER_SRC_BIT;  // canopy-bench camera reads it back
  return createImage(d, c, &t->depth, "bench host depth");
}

void destroyHostTargets(Device& d, HostTargets& t) {
  destroyImage(d, t.color);
  destroyImage(d, t.depth);
}

Status buildHostGraph(Device& d, CanopyContext* ctx, HostTargets& t, bool withCanopy, rg::State colorFinal, rg::RenderGraph* g) {
  CompositeTargets ct;
  ct.color = g->importImage("host colour", descOf(t.color), {}, colorFinal);
  ct.depth = g->importImage("host depth", descOf(t.depth), {}, rg::stateOf(rg::Use::DepthAttachmentWrite));
  g->addPass("host clear", [ct](rg::PassContext& x) {
     const VkClearColorValue cv{{kHostClear[0], kHostClear[1], kHostClear[2], kHostClear[3]}};
     const VkClearDepthStencilValue dv{1.0f, 0};
     const VkImageSubresourceRange cr{VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, 1}, dr{VK_IMAGE_ASPECT_DEPTH_BIT, 0, 1, 0, 1};
     vkCmdClearColorImage(x.cmd, x.image(ct.color).image, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, &cv, 1, &cr);
     vkCmdClearDepthStencilImage(x.cmd, x.image(ct.depth).image, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, &dv, 1, &dr);
     return Status();
   })
      .write(ct.color, rg::Use::TransferDst)
      .write(ct.depth, rg::Use::TransferDst)
      .sideEffect();
  CANOPY_TRY(g->bindImage(ct.color, t.color));
  CANOPY_TRY(g->bindImage(ct.depth, t.depth));
  if (withCanopy) CANOPY_TRY(addCanopyPasses(ctx, *g, ct));
  CANOPY_TRY(g->compile());
  return g->realize(d);
}

Status sampleFrames(Device& d, CanopyContext* ctx, rg::RenderGraph& g, GpuTimer& timer,
                    const std::function<LayerView(int)>& viewOf, float dt, int frames, FrameSamples* out) {
  using clock = std::chrono::steady_clock;
  *out = FrameSamples{};
  // Frames alternate: one with timestamp queries around every pass (the per-pass figures), one
  // without (the wall clock: on lavapipe each query waits for the work before it, ~0.08 ms each,
  // which would otherwise be counted in the frame). Two warm-up frames.
  for (int i = 0; i < 2 * frames + 2; ++i) {
    const bool timed = (i & 1) != 0;
    if (ctx) {
      CanopyFrame f;
      f.camera = toCamera(viewOf(i));
      f.dt = dt;
      CANOPY_TRY(beginCanopyFrame(ctx, f));
    }
    const auto w0 = clock::now();
    CANOPY_TRY(submitAndWait(d, [&](VkCommandBuffer cmd) {
      if (timed) timer.reset(cmd);
      return g.record(cmd, timed ? &timer : nullptr);
    }));
    const double ms = std::chrono::duration<double, std::milli>(clock::now() - w0).count();
    if (i < 2) continue;  // warm-up
    if (!timed) {
      out->wallMs.push_back(ms);
      continue;
    }
    std::vector<PassTiming> t;
    CANOPY_TRY(timer.read(d, &t));
    for (const PassTiming& p : t) out->passMs[p.name].push_back(p.milliseconds);
  }
  return Status();
}

}  // namespace canopy::bench
