#include "demo/demo_app.h"

#include "tools/fault_loader.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <functional>

#include "demo/cli.h"
#include "demo/progress.h"
#include "render/gltf_loader.h"
#include "tools/param_table.h"
#include "engine/graphics_pipeline.h"
#include "engine/shader_registry.h"
#include <glm/gtc/matrix_transform.hpp>

// canopy-demo's own shaders (demo/shaders; CMakeLists.txt canopy_demo_shaders).
namespace canopy_demo {
const canopy::EmbeddedShader* findEmbeddedShader(const char* name);
}

namespace canopy::demo {

// ---- scene and camera -------------------------------------------------------------------------

namespace {
// A scene file's species (each loaded or generated once) and copies; `model` gets the copies'
// world bounds for the camera.
Status loadSceneFile(const Options& o, VegetationModel* model, std::string* label, SceneCopies* out) {
  const auto t0 = std::chrono::steady_clock::now();
  CanopyScene scene;
  CANOPY_TRY(readCanopyScene(o.sceneFile, &scene));
  *out = SceneCopies{};
  out->models.resize(scene.species.size());
  uint64_t triangles = 0;
  for (size_t i = 0; i < scene.species.size(); ++i) {
    const CanopySceneSpecies& sp = scene.species[i];
    VegetationModel& m = out->models[i];
    if (!sp.gltf.empty()) {
      CANOPY_TRY(loadGltf(sp.gltf, {}, &m).context(o.sceneFile + ": species '" + sp.name + "'"));
      for (const std::string& w : m.warnings) std::fprintf(stderr, "  warning: %s: %s\n", sp.name.c_str(), w.c_str());
    } else {
      SceneDesc d;
      CANOPY_TRY(parseSceneKind(sp.generated, &d.kind).context(o.sceneFile + ": species '" + sp.name + "'"));
      if (sp.faces) d.faces = sp.faces;
      d.seed = sp.seed;
      SceneStats st;
      CANOPY_TRY(generateScene(d, &m, &st).context(o.sceneFile + ": species '" + sp.name + "'"));
    }
    triangles += m.triangleCount();
    const glm::vec3 size = m.boundsMax - m.boundsMin;
    std::fprintf(stderr, "  species '%s': %zu triangles, %.2f x %.2f x %.2f (x y z) from %.2f %.2f %.2f, flexibility %.2f, "
                         "response speed %.2f\n",
                 sp.name.c_str(), m.triangleCount(), size.x, size.y, size.z, m.boundsMin.x, m.boundsMin.y, m.boundsMin.z,
                 sp.flexibility, sp.responseSpeed);
  }
  for (size_t i = 0; i < scene.species.size(); ++i)
    out->species.push_back({&out->models[i], scene.species[i].flexibility, scene.species[i].responseSpeed});
  *model = VegetationModel{};
  model->path = o.sceneFile;
  model->boundsMin = glm::vec3(INFINITY);
  model->boundsMax = glm::vec3(-INFINITY);
  std::vector<Float3> lo, hi;
  for (const VegetationModel& m : out->models) {
    lo.push_back(toFloat3(m.boundsMin));
    hi.push_back(toFloat3(m.boundsMax));
  }
  CANOPY_TRY(sceneCopies(scene, lo, hi, &out->instances));
  uint64_t placed = 0;
  for (const CanopyInstance& c : out->instances) {
    const VegetationModel& m = out->models[c.species];
    placed += m.triangleCount();
    const glm::mat4 t = toGlm(c.transform);
    for (int k = 0; k < 8; ++k) {
      const glm::vec3 p((k & 1) ? m.boundsMax.x : m.boundsMin.x, (k & 2) ? m.boundsMax.y : m.boundsMin.y,
                        (k & 4) ? m.boundsMax.z : m.boundsMin.z);
      const glm::vec3 w(t * glm::vec4(p, 1.0f));
      model->boundsMin = glm::min(model->boundsMin, w);
      model->boundsMax = glm::max(model->boundsMax, w);
    }
  }
  const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::fprintf(stderr, "scene %s: %zu species (%llu triangles stored), %zu copies (%llu triangles placed, world bounds %.1f %.1f %.1f .. "
                       "%.1f %.1f %.1f) in %.2f s\n",
               o.sceneFile.c_str(), scene.species.size(), (unsigned long long)triangles, out->instances.size(),
               (unsigned long long)placed, model->boundsMin.x, model->boundsMin.y, model->boundsMin.z, model->boundsMax.x,
               model->boundsMax.y, model->boundsMax.z, s);
  *label = o.sceneFile;
  return Status();
}
}  // namespace

Status loadScene(const Options& o, VegetationModel* model, std::string* label, SceneCopies* copies) {
  if (!o.sceneFile.empty()) return loadSceneFile(o, model, label, copies);
  const auto t0 = std::chrono::steady_clock::now();
  auto seconds = [&]() { return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(); };
  if (!o.gltf.empty()) {
    std::fprintf(stderr, "loading %s ...\n", o.gltf.c_str());
    CANOPY_TRY(loadGltf(o.gltf, {}, model));
    const double s = seconds();
    std::fprintf(stderr, "loaded %s: %zu triangles, %zu materials in %.2f s (%.2fM triangles/s)\n", o.gltf.c_str(),
                 model->triangleCount(), model->materials.size(), s, double(model->triangleCount()) / std::max(s, 1e-6) / 1e6);
    for (const std::string& w : model->warnings) std::fprintf(stderr, "  warning: %s\n", w.c_str());
    *label = o.gltf;
    return Status();
  }
  // Generating and preparing a scene peaks at 144 bytes per face for the 50M shrub (VmHWM of
  // `canopy-demo --scene shrub --faces 50M`: 6.70 GiB) and 203 for 10M (1.89 GiB: a resident mesh
  // counts twice on a CPU driver, whose GPU buffers are host memory); 350 keeps a margin for other
  // scenes and drivers. Refuse what cannot fit instead of being killed by the OOM killer half-way.
  constexpr uint64_t kPeakBytesPerFace = 350;
  const uint64_t available = cli::availableMemoryBytes();
  if (available > 0 && o.faces * kPeakBytesPerFace > available)
    return Status::error("--faces " + std::to_string(o.faces) + " needs about " +
                         std::to_string((o.faces * kPeakBytesPerFace + (1ull << 29)) >> 30) +
                         " GiB of memory to generate and prepare (about 350 bytes per face); this machine has " +
                         std::to_string((available + (1ull << 29)) >> 30) + " GiB available");
  SceneDesc d;
  d.kind = o.scene;
  d.faces = o.faces;
  d.seed = o.seed;
  d.hierarchy = bothMethods(o);
  d.boxes = withImpostors(o);
  SceneStats st;
  cli::ProgressLine progress(std::string("generating ") + sceneName(o.scene));
  CANOPY_TRY(generateScene(d, model, &st, o.faces >= 1'000'000 ? SceneProgress(std::ref(progress)) : SceneProgress()));
  std::fprintf(stderr, "generated %s: %llu faces (%llu rigid, %llu leaves) in %.2f s\n", sceneName(o.scene),
               (unsigned long long)st.faces, (unsigned long long)st.rigidFaces, (unsigned long long)st.leaves, seconds());
  *label = std::string(sceneName(o.scene)) + " " + std::to_string(st.faces) + " faces";
  return Status();
}

CanopyPusher pusherAt(PusherPath path, const glm::vec3& lo, const glm::vec3& hi, const glm::vec3& cameraRight, uint32_t i,
                      uint32_t frames, float fps, float windStrength) {
  // A sphere a twelfth of the scene's width across, half sunk into the ground, walking over the
  // written frames: along the camera's right through the centre, or once around a circle.
  const glm::vec3 c = 0.5f * (lo + hi);
  const float extent = std::max(hi.x - lo.x, hi.z - lo.z);
  const float radius = extent / 24.0f;
  const float t = frames > 1 ? float(i) / float(frames - 1) : 0.0f, seconds = float(std::max(frames, 2u) - 1) / fps;
  glm::vec3 right(cameraRight.x, 0.0f, cameraRight.z);
  right = glm::length(right) > 1e-6f ? glm::normalize(right) : glm::vec3(1.0f, 0.0f, 0.0f);
  glm::vec3 p, v;
  if (path == PusherPath::Circle) {
    const glm::vec3 fwd = glm::cross(glm::vec3(0.0f, 1.0f, 0.0f), right);
    const float a = 6.2831853f * t, r = 0.3f * extent;
    p = c + r * (std::cos(a) * right + std::sin(a) * fwd);
    v = (r * 6.2831853f / seconds) * (-std::sin(a) * right + std::cos(a) * fwd);
  } else {
    p = c + (0.8f * t - 0.4f) * extent * right;
    v = (0.8f * extent / seconds) * right;
  }
  p.y = lo.y + 0.5f * radius;
  CanopyPusher out;
  out.a = out.b = toFloat3(p);
  out.radius = radius;
  out.velocity = toFloat3(v);
  // Twice as far as the demo's wind (--strength, domain units/s) bends the grass: bend 1 is 0.5 of them.
  out.bend = std::clamp(4.0f * windStrength, 1.0f, 16.0f);
  return out;
}

std::string windText(const Options& o) {
  char t[256];
  if (o.planeSides)
    std::snprintf(t, sizeof t, "plane sides %u at %.2f domain units/s, %.2f Hz (modulation %.2f, gust %.2f)", o.windSides,
                  double(o.windStrength), double(o.windFrequency), double(o.windModulation), double(o.windGust));
  else
    std::snprintf(t, sizeof t, "%.2f m/s toward (%.2f, %.2f, %.2f), gusts %.2f at %.2f Hz, turbulence %.2f", double(o.windSpeed),
                  double(o.windDirection.x), double(o.windDirection.y), double(o.windDirection.z), double(o.gustIntensity),
                  double(o.gustFrequency), double(o.turbulence));
  return t;
}

float domainWindSpeed(const Options& o) {
  return o.planeSides ? o.windStrength : o.windSpeed / WorldWind{}.tileMetres;
}

CameraRig defaultRig(const Options& o) {
  CameraRig r;
  r.yaw += o.yawDegrees;
  if (!o.sceneFile.empty()) {
    r.pitch = 14.0f;
    r.distance = 0.7f;
  } else if (o.gltf.empty()) {
    switch (o.scene) {
      case SceneKind::GrassField: r.pitch = 28.0f; r.distance = 0.75f; break;
      case SceneKind::Field: r.pitch = 22.0f; r.distance = 0.8f; break;
      case SceneKind::Kelp: r.pitch = 8.0f; r.distance = 0.8f; break;
      default: r.distance = 0.7f; break;
    }
  }
  return r;
}

LayerView cameraView(const CameraRig& rig, const VegetationModel& m, uint32_t w, uint32_t h) {
  return orbitView(m.boundsMin, m.boundsMax, rig.yaw, rig.pitch, rig.fov, float(w) / float(h), rig.distance);
}

CameraPath cameraPathOf(const Options& o, const CameraRig& rig) {
  CameraPath p;
  p.motion = o.camera;
  p.degreesPerFrame = o.degreesPerFrame;
  if (o.camera == CameraMotion::Orbit && !o.degreesGiven)
    p.degreesPerFrame = o.frames > 1 ? o.orbitDegrees / float(o.frames - 1) : 0.0f;
  p.radiiPerFrame = o.radiiPerFrame;
  p.amplitudeDegrees = o.swingDegrees;
  p.yaw = rig.yaw;
  p.pitch = rig.pitch;
  p.fovY = rig.fov;
  p.distanceScale = rig.distance;
  return p;
}

glm::vec3 skySrgb(const Options& o) {
  return o.gltf.empty() && o.sceneFile.empty() && o.scene == SceneKind::Kelp ? glm::vec3(0.12f, 0.32f, 0.45f)  // water
                                                      : glm::vec3(0.62f, 0.75f, 0.88f);
}

CanopyParams paramsFrom(const Options& o, const CanopyParams& base) {
  CanopyParams p = base;
  if (!parseLayerLayout(o.layout, &p.layers.layout).ok()) p.layers.layout = base.layers.layout;  // checked by parseOptions
  p.windMode = o.planeSides ? WindMode::PlaneSides : WindMode::World;
  p.wind.direction = o.windDirection;
  p.wind.speed = o.windSpeed;
  p.wind.gustIntensity = o.gustIntensity;
  p.wind.gustFrequency = o.gustFrequency;
  p.wind.turbulence = o.turbulence;
  p.wind.sway = o.sway;
  p.simulation.wind.sides = o.windSides;
  p.simulation.wind.strength = o.windStrength;
  p.simulation.wind.frequency = o.windFrequency;
  p.simulation.wind.modulation = o.windModulation;
  p.simulation.wind.gust = o.windGust;
  p.dynamics.delay = o.delay;
  p.animation = o.method;
  p.perVertex.wind = o.perVertexWind;
  p.layers.rebuildBudgetMs = o.rebuildBudgetMs;
  p.layers.errorThresholdPixels = o.resliceErrorPixels;
  p.layers.halfResolutionLayers = uint32_t(o.halfResolutionLayers);
  p.composite.depthSearchSteps = uint32_t(o.depthSearchSteps);
  p.layers.policy = o.reslice;
  p.layers.lightDirection = o.light;
  p.layers.lightColor = o.lightColor;
  p.layers.ambient = o.ambient;
  p.layers.leafRefractiveIndex = o.leafIor;
  p.layers.leafRoughness = o.leafRoughness;
  p.layers.overrideLeafRoughness = o.overrideLeafRoughness;
  p.layers.leafTransmission = o.leafTransmission;
  p.layers.translucency = o.translucency;
  p.layers.rigidMotion = o.rigidMotion;
  p.layers.impostors.mode = o.impostors;
  p.layers.impostors.switchPixels = o.impostorPixels;
  p.layers.impostors.debugView = o.impostorDebug;
  p.layers.impostors.shape = o.impostorShape;
  p.composite.debugView = o.debug;
  p.composite.bilinear = o.bilinear;
  p.composite.sharpness = o.sharpness;
  p.dynamics.maxStretch = o.maxStretch;
  p.composite.debugVelocityScale = std::max(0.05f, domainWindSpeed(o));
  return p;
}

// ---- host ---------------------------------------------------------------------------------------

namespace {

Status buildGraph(Host& h) {
  h.graph.release(*h.device);
  h.graph = rg::RenderGraph();
  rg::RenderGraph& g = h.graph;
  h.presentTarget = rg::kInvalidResource;
  h.readbackId = rg::kInvalidResource;
  const rg::State colorAfter = h.wantsReadback || h.presentFormat != VK_FORMAT_UNDEFINED
                                   ? rg::stateOf(rg::Use::TransferSrc)
                                   : rg::stateOf(rg::Use::ColorAttachmentReadWrite);
  CompositeTargets t;
  // They arrive as the previous frame (maybe still executing) left them: its last accesses are
  // ordered before this frame's clear (createTargets put them in these states once).
  const rg::State depthAfter = rg::stateOf(rg::Use::DepthAttachmentWrite);
  t.color = g.importImage("demo colour", descOf(h.color), colorAfter, colorAfter);
  t.depth = g.importImage("demo depth", descOf(h.depth), depthAfter, depthAfter);
  const glm::vec4 clear = h.clear;
  g.addPass("demo: clear", [t, clear](rg::PassContext& x) {
     const VkClearColorValue cv{{clear.r, clear.g, clear.b, clear.a}};
     const VkClearDepthStencilValue dv{1.0f, 0};
     const VkImageSubresourceRange cr{VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, 1}, dr{VK_IMAGE_ASPECT_DEPTH_BIT, 0, 1, 0, 1};
     vkCmdClearColorImage(x.cmd, x.image(t.color).image, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, &cv, 1, &cr);
     vkCmdClearDepthStencilImage(x.cmd, x.image(t.depth).image, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, &dv, 1, &dr);
     return Status();
   })
      .write(t.color, rg::Use::TransferDst)
      .write(t.depth, rg::Use::TransferDst)
      .sideEffect();
  CANOPY_TRY(g.bindImage(t.color, h.color));
  CANOPY_TRY(g.bindImage(t.depth, h.depth));
  if (h.shadow.on) {
    // The ground under the vegetation, lit through the shadow map Canopy drew after the previous
    // frame (the map rests sampled; recordCanopyShadow leaves it so).
    const rg::State sampled = rg::stateOf(rg::Use::FragmentSampled);
    const auto map = g.importImage("demo: shadow map", descOf(h.shadow.map), sampled, sampled);
    CANOPY_TRY(g.bindImage(map, h.shadow.map));
    Host* hp = &h;
    g.addPass("demo: ground", [hp, t](rg::PassContext& x) {
       beginHostRendering(x, t, hp->width, hp->height, false);
       const Host::Shadow& sh = hp->shadow;
       Status st = bindGraphics(*x.device, x.cmd, sh.ground,
                                {bindBuffer(sh.groundFrame.buffer),
                                 bindImage(sh.map.view, VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL, sh.sampler)},
                                sh.viewProj);
       if (st.ok()) vkCmdDraw(x.cmd, 6, 1, 0, 0);
       x.device->cmdEndRendering(x.cmd);
       return st;
     })
        .write(t.color, rg::Use::ColorAttachmentReadWrite)
        .write(t.depth, rg::Use::DepthAttachmentWrite)
        .read(map, rg::Use::FragmentSampled)
        .sideEffect();
  }
  CANOPY_TRY(addCanopyPasses(h.canopy, g, t));
  if (h.presentFormat != VK_FORMAT_UNDEFINED) {
    // The swapchain image arrives undefined (its old contents are not needed) and leaves ready to present.
    const rg::State present{VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT, VK_ACCESS_2_NONE, VK_IMAGE_LAYOUT_PRESENT_SRC_KHR};
    ImageDesc pd;
    pd.format = h.presentFormat;
    pd.width = h.width;
    pd.height = h.height;
    pd.usage = VK_IMAGE_USAGE_TRANSFER_DST_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT;
    h.presentTarget = g.importImage("swapchain image", pd, {}, present);
    const uint32_t w = h.width, ht = h.height;
    const rg::ResourceId dst = h.presentTarget;
    g.addPass("demo: blit to swapchain", [t, dst, w, ht](rg::PassContext& x) {
       VkImageBlit b{};
       b.srcSubresource = b.dstSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1};
       b.srcOffsets[1] = b.dstOffsets[1] = {int32_t(w), int32_t(ht), 1};
       vkCmdBlitImage(x.cmd, x.image(t.color).image, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, x.image(dst).image,
                      VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, 1, &b, VK_FILTER_NEAREST);
       return Status();
     })
        .read(t.color, rg::Use::TransferSrc)
        .write(dst, rg::Use::TransferDst)
        .sideEffect();
  }
  if (h.wantsReadback) {
    const rg::State hostRead = rg::stateOf(rg::Use::HostRead);
    const auto rb = g.importBuffer("demo readback", h.readback[0].size, hostRead, hostRead);
    h.readbackId = rb;  // bound per frame to its slot's buffer
    const uint32_t w = h.width, ht = h.height;
    // From the swapchain image when there is one (the window's screenshot is what was presented).
    const rg::ResourceId src = h.presentTarget != rg::kInvalidResource ? h.presentTarget : t.color;
    g.addPass("demo: copy to host", [src, rb, w, ht](rg::PassContext& x) {
       VkBufferImageCopy r{};
       r.imageSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1};
       r.imageExtent = {w, ht, 1};
       vkCmdCopyImageToBuffer(x.cmd, x.image(src).image, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, x.buffer(rb), 1, &r);
       return Status();
     })
        .read(src, rg::Use::TransferSrc)
        .write(rb, rg::Use::TransferDst)
        .sideEffect();
  }
  CANOPY_TRY(g.compile());
  CANOPY_TRY(g.realize(*h.device));
  h.graphGeneration = canopyResourceGeneration(h.canopy);
  return Status();
}

}  // namespace

namespace {

// The host's own colour (sRGB: the layers hold linear colour, so the PNG bytes and the swapchain
// show the colours the textures were painted with), depth and read-back buffer at the host's size.
Status createTargets(Host& host) {
  Device& d = *host.device;
  ImageDesc c;
  c.format = VK_FORMAT_R8G8B8A8_SRGB;
  c.width = host.width;
  c.height = host.height;
  c.usage = VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT | VK_IMAGE_USAGE_TRANSFER_DST_BIT;
  CANOPY_TRY(createImage(d, c, &host.color, "demo colour"));
  c.format = VK_FORMAT_D32_SFLOAT;
  c.usage = VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT | VK_IMAGE_USAGE_SAMPLED_BIT | VK_IMAGE_USAGE_TRANSFER_DST_BIT;
  CANOPY_TRY(createImage(d, c, &host.depth, "demo depth"));
  if (host.wantsReadback)
    for (Buffer& b : host.readback)
      CANOPY_TRY(createBuffer(d, VkDeviceSize(host.width) * host.height * 4, VK_BUFFER_USAGE_TRANSFER_DST_BIT,
                              MemoryUsage::Readback, &b, "demo readback"));
  // Once, at creation: the targets go into the states every frame's graph imports them in.
  const bool copies = host.wantsReadback || host.presentFormat != VK_FORMAT_UNDEFINED;
  rg::RenderGraph g;
  const auto ci = g.importImage("demo colour", descOf(host.color), {},
                               rg::stateOf(copies ? rg::Use::TransferSrc : rg::Use::ColorAttachmentReadWrite));
  const auto zi = g.importImage("demo depth", descOf(host.depth), {}, rg::stateOf(rg::Use::DepthAttachmentWrite));
  g.addPass("demo: first clear", [ci, zi](rg::PassContext& x) {
     const VkClearColorValue cv{};
     const VkClearDepthStencilValue dv{1.0f, 0};
     const VkImageSubresourceRange cr{VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, 1}, dr{VK_IMAGE_ASPECT_DEPTH_BIT, 0, 1, 0, 1};
     vkCmdClearColorImage(x.cmd, x.image(ci).image, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, &cv, 1, &cr);
     vkCmdClearDepthStencilImage(x.cmd, x.image(zi).image, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, &dv, 1, &dr);
     return Status();
   })
      .write(ci, rg::Use::TransferDst)
      .write(zi, rg::Use::TransferDst);
  CANOPY_TRY(g.bindImage(ci, host.color));
  CANOPY_TRY(g.bindImage(zi, host.depth));
  CANOPY_TRY(g.compile());
  CANOPY_TRY(g.realize(d));
  return submitAndWait(d, [&](VkCommandBuffer cmd) { return g.record(cmd); });
}

void destroyTargets(Host& h) {
  Device& d = *h.device;
  h.graph.release(d);
  h.graph = rg::RenderGraph();
  h.graphGeneration = ~0ull;
  destroyImage(d, h.color);
  destroyImage(d, h.depth);
  for (Buffer& b : h.readback) destroyBuffer(d, b);
}

}  // namespace

namespace {

// --shadows: the ground under the scene's bounds (wide enough for the shadow of its height), the sun's
// orthographic view around the ground and the vegetation, the shadow map, the ground's pipeline and
// (with a read-back) the map's copy per slot.
Status createShadow(Host& host, const VegetationModel& model, const Options& o) {
  Device& d = *host.device;
  Host::Shadow& sh = host.shadow;
  sh.on = true;
  sh.readback = host.wantsReadback;
  const glm::vec3 lo = model.boundsMin, hi = model.boundsMax, ext = hi - lo;
  sh.groundCenter = glm::vec3(0.5f * (lo.x + hi.x), lo.y, 0.5f * (lo.z + hi.z));
  sh.groundHalf = 0.5f * std::max(ext.x, ext.z) + ext.y;
  glm::vec3 l(o.light.x, o.light.y, o.light.z);
  l = glm::length(l) > 0.0f ? glm::normalize(l) : glm::vec3(0, 1, 0);
  const glm::vec3 centre(sh.groundCenter.x, lo.y + 0.5f * ext.y, sh.groundCenter.z);
  const float reach = glm::length(glm::vec3(sh.groundHalf, ext.y, sh.groundHalf));
  const glm::mat4 view = glm::lookAt(centre + l * (2.0f * reach), centre, std::abs(l.y) > 0.99f ? glm::vec3(0, 0, 1) : glm::vec3(0, 1, 0));
  // The map spans the casters only (the ground outside it reads the cleared edge: lit), so its
  // texels go to the vegetation.
  glm::vec3 vlo(INFINITY), vhi(-INFINITY);
  for (int k = 0; k < 8; ++k) {
    const glm::vec3 p(k & 1 ? hi.x : lo.x, k & 2 ? hi.y : lo.y, k & 4 ? hi.z : lo.z);
    const glm::vec3 q(view * glm::vec4(p, 1.0f));
    vlo = glm::min(vlo, q);
    vhi = glm::max(vhi, q);
  }
  const glm::vec2 pad = 0.02f * glm::vec2(vhi - vlo);
  sh.light = glm::orthoRH_ZO(vlo.x - pad.x, vhi.x + pad.x, vlo.y - pad.y, vhi.y + pad.y, -vhi.z - 0.01f * reach, -vlo.z + 0.01f * reach) * view;
  ImageDesc m;
  m.format = VK_FORMAT_D32_SFLOAT;
  m.width = m.height = Host::Shadow::kSize;
  m.usage = VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT | VK_IMAGE_USAGE_SAMPLED_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT |
            VK_IMAGE_USAGE_TRANSFER_DST_BIT;
  CANOPY_TRY(createImage(d, m, &sh.map, "demo: shadow map"));
  VkSamplerCreateInfo si{VK_STRUCTURE_TYPE_SAMPLER_CREATE_INFO};
  si.magFilter = si.minFilter = VK_FILTER_NEAREST;
  si.addressModeU = si.addressModeV = si.addressModeW = VK_SAMPLER_ADDRESS_MODE_CLAMP_TO_EDGE;
  CANOPY_VK(vkCreateSampler(d.device, &si, nullptr, &sh.sampler));
  struct GroundFrame {
    glm::mat4 light;
    glm::vec4 origin, u, v, albedo, lightTexel;
  } gf{sh.light, glm::vec4(sh.groundCenter, 1.0f), glm::vec4(sh.groundHalf, 0, 0, 0), glm::vec4(0, 0, sh.groundHalf, 0),
       glm::vec4(0.45f, 0.45f, 0.45f, 0.35f), glm::vec4(l, 1.0f / float(Host::Shadow::kSize))};
  CANOPY_TRY(createBuffer(d, sizeof gf, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, MemoryUsage::Upload, &sh.groundFrame, "demo: ground"));
  void* mapped = hostCoherentPointer(d, sh.groundFrame.allocation);
  if (!mapped) return Status::error("demo: the ground's buffer is not host-visible");
  std::memcpy(mapped, &gf, sizeof gf);
  GraphicsPipelineDesc gp;
  gp.vertexShader = "demo_ground.vert";
  gp.fragmentShader = "demo_ground.frag";
  gp.shaderLookup = canopy_demo::findEmbeddedShader;
  gp.pushConstantSize = sizeof(glm::mat4);
  gp.colorFormats = {VK_FORMAT_R8G8B8A8_SRGB};
  gp.depthFormat = VK_FORMAT_D32_SFLOAT;
  CANOPY_TRY(createGraphicsPipeline(d, gp, &sh.ground));
  // Once: the map cleared (nothing casts yet) into the state every frame imports it in.
  {
    rg::RenderGraph g;
    const auto mi = g.importImage("demo: shadow map", descOf(sh.map), {}, rg::stateOf(rg::Use::FragmentSampled));
    g.addPass("demo: shadow map's first clear", [mi](rg::PassContext& x) {
       const VkClearDepthStencilValue dv{1.0f, 0};
       const VkImageSubresourceRange dr{VK_IMAGE_ASPECT_DEPTH_BIT, 0, 1, 0, 1};
       vkCmdClearDepthStencilImage(x.cmd, x.image(mi).image, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, &dv, 1, &dr);
       return Status();
     }).write(mi, rg::Use::TransferDst);
    CANOPY_TRY(g.bindImage(mi, sh.map));
    CANOPY_TRY(g.compile());
    CANOPY_TRY(g.realize(d));
    CANOPY_TRY(submitAndWait(d, [&](VkCommandBuffer cmd) { return g.record(cmd); }));
  }
  if (!sh.readback) return Status();
  const VkDeviceSize bytes = VkDeviceSize(Host::Shadow::kSize) * Host::Shadow::kSize * 4;
  for (Buffer& b : sh.mapReadback)
    CANOPY_TRY(createBuffer(d, bytes, VK_BUFFER_USAGE_TRANSFER_DST_BIT, MemoryUsage::Readback, &b, "demo: shadow map read-back"));
  rg::RenderGraph& g = sh.copy;
  const rg::State sampled = rg::stateOf(rg::Use::FragmentSampled), hostRead = rg::stateOf(rg::Use::HostRead);
  const auto mi = g.importImage("demo: shadow map", descOf(sh.map), sampled, sampled);
  sh.copyTarget = g.importBuffer("demo: shadow map read-back", bytes, hostRead, hostRead);
  const rg::ResourceId rb = sh.copyTarget;
  g.addPass("demo: shadow map to host", [mi, rb](rg::PassContext& x) {
     VkBufferImageCopy r{};
     r.imageSubresource = {VK_IMAGE_ASPECT_DEPTH_BIT, 0, 0, 1};
     r.imageExtent = {Host::Shadow::kSize, Host::Shadow::kSize, 1};
     vkCmdCopyImageToBuffer(x.cmd, x.image(mi).image, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, x.buffer(rb), 1, &r);
     return Status();
   })
      .read(mi, rg::Use::TransferSrc)
      .write(rb, rg::Use::TransferDst)
      .sideEffect();
  CANOPY_TRY(g.bindImage(mi, sh.map));
  CANOPY_TRY(g.bindBuffer(rb, sh.mapReadback[0].buffer));
  CANOPY_TRY(g.compile());
  return g.realize(d);
}

void destroyShadow(Host& h) {
  Device& d = *h.device;
  Host::Shadow& sh = h.shadow;
  sh.copy.release(d);
  for (Buffer& b : sh.mapReadback) destroyBuffer(d, b);
  destroyGraphicsPipeline(d, sh.ground);
  destroyBuffer(d, sh.groundFrame);
  if (sh.sampler) vkDestroySampler(d.device, sh.sampler, nullptr);
  destroyImage(d, sh.map);
  sh = Host::Shadow{};
}

}  // namespace

Status createHost(Device& d, const VegetationModel& model, const Options& o, uint32_t w, uint32_t h, bool readback,
                  VkFormat presentFormat, Host* out) {
  Host& host = *out;
  host.device = &d;
  host.width = w;
  host.height = h;
  host.wantsReadback = readback;
  host.presentFormat = presentFormat;
  auto linear = [](float c) { return c <= 0.04045f ? c / 12.92f : std::pow((c + 0.055f) / 1.055f, 2.4f); };
  const glm::vec3 sky = skySrgb(o);
  host.clear = glm::vec4(linear(sky.r), linear(sky.g), linear(sky.b), 1.0f);
  host.clearSrgb = sky;
  CANOPY_TRY(createTargets(host));
  for (GpuTimer& t : host.timer) CANOPY_TRY(t.init(d, 64));
  CanopyDesc desc;
  desc.width = w;
  desc.height = h;
  desc.colorFormat = VK_FORMAT_R8G8B8A8_SRGB;
  // A generated scene has no file to key a cache by. A loaded model's caches go to the folder
  // main() resolved (the user's cache folder unless the options say otherwise).
  LayerLayout layout;
  if (parseLayerLayout(o.layout, &layout).ok()) desc.maxLayers = std::max(desc.maxLayers, layout.count());
  desc.rootCacheDir = o.cacheFolder;
  desc.cacheMaxBytes = uint64_t(o.cache.maxMiB) << 20;
  desc.split = o.split;
  desc.roots.attachRoots = o.attachRoots;
  desc.deviceMemoryBudget = uint64_t(double(o.deviceBudgetMiB) * double(1 << 20));
  desc.guardBand = o.guardBand;
  desc.meshStagingRingBytes = uint64_t(double(o.ringMiB) * double(1 << 20));
  desc.allowPerVertex = bothMethods(o);
  desc.impostors.enable = withImpostors(o);
  desc.impostors.views = o.impostorViews;
  // The preparation's own peak above what is resident before it (the model): issue 16's
  // "bytes per face" of preparation, printed below.
  const uint64_t residentBefore = cli::residentBytes();
  const bool peakReset = cli::resetPeakResident();
  const auto t0 = std::chrono::steady_clock::now();
  cli::ProgressLine progress("preparing");
  if (model.triangleCount() >= 1'000'000) {
    std::fprintf(stderr, "preparing %zu triangles (material split, leaf roots, GPU upload) ...\n", model.triangleCount());
    desc.progress = std::ref(progress);
  }
  // A scene file's species in one vegetation, its copies placed (docs/scene-files.md).
  const SceneCopies* copies = o.copies.get();
  if (copies) desc.instances = copies->instances;
  auto create = [&]() {
    return copies ? createCanopy(d, copies->species, desc, &host.canopy) : createCanopy(d, model, desc, &host.canopy);
  };
  Status made = create();
  if (!made.ok() && desc.allowPerVertex && o.method != AnimationMode::PerVertex) {
    // The window offers both methods; a mesh the baseline cannot keep resident runs 2D only.
    std::fprintf(stderr, "canopy-demo: the per-vertex baseline is off for this scene (%s)\n", made.message().c_str());
    desc.allowPerVertex = false;
    made = create();
  }
  if (!made.ok())
    return made.context(std::to_string(w) + "x" + std::to_string(h) + " frame, " + std::to_string(desc.maxLayers) + " layers at most");
  const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (model.triangleCount() >= 1'000'000)
    std::fprintf(stderr, "prepared %zu triangles (material split, leaf roots, GPU upload) in %.2f s (%.2fM/s)\n",
                 model.triangleCount(), s, double(model.triangleCount()) / std::max(s, 1e-6) / 1e6);
  if (peakReset) {
    const uint64_t peak = cli::procKilobytes("/proc/self/status", "VmHWM");
    const double faces = double(std::max<size_t>(model.triangleCount(), 1));
    std::fprintf(stderr,
                 "preparation memory: model %.2f GiB resident before (%.1f bytes per face), peak %.2f GiB above it "
                 "(%.1f bytes per face), %.1f bytes per face kept after it\n",
                 double(residentBefore) / double(1ull << 30), double(residentBefore) / faces,
                 double(peak - std::min(peak, residentBefore)) / double(1ull << 30),
                 double(peak - std::min(peak, residentBefore)) / faces,
                 double(cli::residentBytes() - std::min(cli::residentBytes(), residentBefore)) / faces);
  }
  if (!desc.rootCacheDir.empty() && !model.path.empty()) {
    // What became of the caches, why one was not used (a line each).
    const CanopyStats st = canopyStats(host.canopy);
    std::printf("cache: leaf roots: %s\n", st.layers.rootCacheNote.c_str());
    if (desc.impostors.enable) std::printf("cache: impostor views: %s\n", st.layers.impostorCacheNote.c_str());
  }
  CANOPY_TRY(setCanopyParams(host.canopy, paramsFrom(o, canopyParams(host.canopy))));
  if (o.shadows) CANOPY_TRY(createShadow(host, model, o));
  return Status();
}

Status resizeHost(Host& host, uint32_t width, uint32_t height, VkFormat presentFormat) {
  vkDeviceWaitIdle(host.device->device);
  destroyTargets(host);
  host.width = width;
  host.height = height;
  host.presentFormat = presentFormat;
  CANOPY_TRY(createTargets(host));
  return resizeCanopy(host.canopy, width, height);
}

void destroyHost(Host& h) {
  if (!h.device) return;
  Device& d = *h.device;
  vkDeviceWaitIdle(d.device);
  destroyTargets(h);
  for (GpuTimer& t : h.timer) t.destroy(d);
  if (h.shadow.on) destroyShadow(h);
  destroyCanopy(h.canopy);
  h.canopy = nullptr;
  h.device = nullptr;
}

Status recordHostFrame(Host& h, VkCommandBuffer cmd, const CanopyFrame& frame, const Image* present, uint32_t slot) {
  if (slot >= Host::kFramesInFlight) return Status::error("demo: frame slot " + std::to_string(slot) + " out of range");
  CANOPY_TRY(beginCanopyFrame(h.canopy, frame));
  if (h.graphGeneration != canopyResourceGeneration(h.canopy)) CANOPY_TRY(buildGraph(h));
  if (h.presentTarget != rg::kInvalidResource) {
    if (!present) return Status::error("demo: no swapchain image for this frame");
    CANOPY_TRY(h.graph.bindImage(h.presentTarget, *present));
  }
  if (h.readbackId != rg::kInvalidResource) CANOPY_TRY(h.graph.bindBuffer(h.readbackId, h.readback[slot].buffer));
  h.timer[slot].reset(cmd);
  h.shadow.viewProj = toGlm(frame.camera.proj) * toGlm(frame.camera.view);
  CANOPY_TRY(h.graph.record(cmd, &h.timer[slot]));
  if (!h.shadow.on) return Status();
  // The vegetation's shadow of this frame (the ground of the next frame reads it), then its read-back.
  Host::Shadow& sh = h.shadow;
  const rg::State sampled = rg::stateOf(rg::Use::FragmentSampled);
  CanopyShadowInputs in;
  in.depth = canopyImage(sh.map.image, sh.map.view,
                         VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT | VK_IMAGE_USAGE_SAMPLED_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT |
                             VK_IMAGE_USAGE_TRANSFER_DST_BIT,
                         VK_FORMAT_D32_SFLOAT, sampled, sampled);
  in.width = in.height = Host::Shadow::kSize;
  in.lightViewProj = toFloat4x4(sh.light);
  h.timer[slot].begin(cmd, "canopy: shadow map");
  const Status st = recordCanopyShadow(h.canopy, cmd, in);
  h.timer[slot].end(cmd);
  CANOPY_TRY(st);
  if (!sh.readback) return Status();
  CANOPY_TRY(sh.copy.bindBuffer(sh.copyTarget, sh.mapReadback[slot].buffer));
  return sh.copy.record(cmd);
}

void readShadowMap(const Host& h, uint32_t slot, std::vector<float>* depth) {
  depth->resize(size_t(Host::Shadow::kSize) * Host::Shadow::kSize);
  std::memcpy(depth->data(), h.shadow.mapReadback[slot].allocation.mapped, depth->size() * sizeof(float));
}

Status createFrameRing(Device& d, FrameRing* r) {
  VkCommandPoolCreateInfo pci{VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO};
  pci.flags = VK_COMMAND_POOL_CREATE_RESET_COMMAND_BUFFER_BIT;
  pci.queueFamilyIndex = d.queueFamily;
  CANOPY_VK(vkCreateCommandPool(d.device, &pci, nullptr, &r->pool));
  VkCommandBufferAllocateInfo ai{VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
  ai.commandPool = r->pool;
  ai.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
  ai.commandBufferCount = Host::kFramesInFlight;
  CANOPY_VK(vkAllocateCommandBuffers(d.device, &ai, r->cmds));
  for (uint32_t i = 0; i < Host::kFramesInFlight; ++i) {
    VkFenceCreateInfo fi{VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
    VkSemaphoreCreateInfo si{VK_STRUCTURE_TYPE_SEMAPHORE_CREATE_INFO};
    CANOPY_VK(vkCreateFence(d.device, &fi, nullptr, &r->fences[i]));
    CANOPY_VK(vkCreateSemaphore(d.device, &si, nullptr, &r->acquired[i]));
  }
  return Status();
}

Status waitFrameSlot(Device& d, FrameRing& r, uint32_t slot, bool* waited) {
  if (waited) *waited = r.pending[slot];
  if (!r.pending[slot]) return Status();
  CANOPY_VK(vkWaitForFences(d.device, 1, &r.fences[slot], VK_TRUE, UINT64_MAX));
  CANOPY_VK(vkResetFences(d.device, 1, &r.fences[slot]));
  r.pending[slot] = false;
  return Status();
}

Status recordFrameSlot(Host& h, FrameRing& r, uint32_t slot, const CanopyFrame& frame, const Image* present) {
  VkCommandBuffer cmd = r.cmds[slot];
  CANOPY_VK(vkResetCommandBuffer(cmd, 0));
  VkCommandBufferBeginInfo bi{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
  bi.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
  CANOPY_VK(vkBeginCommandBuffer(cmd, &bi));
  const Status rs = recordHostFrame(h, cmd, frame, present, slot);
  CANOPY_VK(vkEndCommandBuffer(cmd));
  return rs;
}

void destroyFrameRing(Device& d, FrameRing& r) {
  if (!d.device) return;
  for (uint32_t i = 0; i < Host::kFramesInFlight; ++i) {
    if (r.fences[i]) vkDestroyFence(d.device, r.fences[i], nullptr);  // the caller waited for its frames
    if (r.acquired[i]) vkDestroySemaphore(d.device, r.acquired[i], nullptr);
  }
  if (r.pool) vkDestroyCommandPool(d.device, r.pool, nullptr);
  r = FrameRing{};
}

void readPixels(const Host& h, uint32_t slot, std::vector<uint8_t>* rgba) {
  rgba->resize(size_t(h.width) * h.height * 4);
  std::memcpy(rgba->data(), h.readback[slot].allocation.mapped, rgba->size());
  const bool bgra = h.presentFormat == VK_FORMAT_B8G8R8A8_UNORM || h.presentFormat == VK_FORMAT_B8G8R8A8_SRGB;
  for (size_t i = 0; i < rgba->size(); i += 4) {
    if (bgra) std::swap((*rgba)[i], (*rgba)[i + 2]);
    (*rgba)[i + 3] = 255;
  }
}

// ---- timing -------------------------------------------------------------------------------------

void TimingLog::add(const std::vector<PassTiming>& passes, double wall) {
  for (const PassTiming& p : passes) {
    if (!passMs.count(p.name)) order.push_back(p.name);
    passMs[p.name].push_back(p.milliseconds);
  }
  wallMs.push_back(wall);
}

std::string TimingLog::summary(const std::string& title) const {
  std::string s = title + "\n";
  char line[256];
  std::snprintf(line, sizeof line, "  %-40s %10s %10s\n", "pass (GPU timestamps)", "median ms", "max ms");
  s += line;
  for (const std::string& name : order) {
    const std::vector<double>& v = passMs.at(name);
    std::snprintf(line, sizeof line, "  %-40s %10.3f %10.3f\n", name.c_str(), median(v), *std::max_element(v.begin(), v.end()));
    s += line;
  }
  if (!wallMs.empty()) {
    std::snprintf(line, sizeof line, "  %-40s %10.3f %10.3f   (%.1f FPS)\n", "whole frame, wall clock (completion to completion)",
                  median(wallMs), *std::max_element(wallMs.begin(), wallMs.end()), 1000.0 / std::max(median(wallMs), 1e-6));
    s += line;
  }
  return s;
}

}  // namespace canopy::demo
