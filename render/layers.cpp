#include "render/layers.h"

#include "render/impostor_gpu.h"

#include "engine/hash.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <functional>
#include <glm/gtc/packing.hpp>

#include "engine/device.h"
#include "engine/timing.h"
#include "engine/transfer.h"
#include "render/layer_common.h"
#include "render/layer_placement.h"

namespace canopy {

uint32_t layerShadingFeatures(const LayeredVegetation& lv, const LayerSettings& s) {
  uint32_t f = s.translucencyModel == TranslucencyModel::Habel ? LAYER_FEATURE_HABEL : LAYER_FEATURE_DIFFUSE_BTDF;
  if (s.impostors.debugView) f |= LAYER_FEATURE_LEVEL_COLORS;
  for (const ModelMaterial& m : lv.mesh.materials) {
    if (m.normalImage >= 0) f |= LAYER_FEATURE_NORMAL_MAP;
    if (m.transmissionImage >= 0) f |= LAYER_FEATURE_TRANSMISSION_TEXTURE;
    if (m.transmissionColorImage >= 0) f |= LAYER_FEATURE_TRANSMISSION_COLOR_TEXTURE;
  }
  return f;
}

namespace {

Status checkImpostorSettings(const LayeredVegetation& lv, const LayerSettings& s) {
  if (s.impostors.mode == ImpostorMode::Off && !s.impostors.debugView) return Status();
  if (!lv.impostors.enabled)
    return Status::error("LayerSettings.impostors.mode: impostors need CanopyDesc.impostors.enable at creation (the box "
                         "hierarchy and its baked views)");
  if (lv.desc.writeIds) return Status::error("LayerSettings.impostors.mode: the id output draws every leaf; impostors are off with it");
  return Status();
}

// The cross-fade pipelines and their sampler (texel fetches only), for the next set.
Status createFadePipelines(LayeredVegetation& lv) {
  Device& d = *lv.device;
  if (!lv.pipelines.nearestSampler) {
    VkSamplerCreateInfo si{VK_STRUCTURE_TYPE_SAMPLER_CREATE_INFO};
    si.magFilter = si.minFilter = VK_FILTER_NEAREST;
    si.mipmapMode = VK_SAMPLER_MIPMAP_MODE_NEAREST;
    si.addressModeU = si.addressModeV = si.addressModeW = VK_SAMPLER_ADDRESS_MODE_CLAMP_TO_EDGE;
    CANOPY_VK(d.vk.CreateSampler(d.device, &si, d.allocationCallbacks, &lv.pipelines.nearestSampler));
  }
  if (lv.pipelines.fade.pipeline) return Status();
  GraphicsPipelineDesc p;
  p.pushConstantSize = sizeof(gpu::LayerFadePush);
  p.colorFormats = {lv.desc.colorFormat};
  p.blend = BlendMode::ConstantMix;
  p.depthTest = p.depthWrite = false;
  p.vertexShader = "layers_fade.vert";
  p.fragmentShader = "layers_fade.frag";
  CANOPY_TRY(createGraphicsPipeline(d, p, &lv.pipelines.fade));
  p.fragmentShader = "layers_fade_bg.frag";
  CANOPY_TRY(createGraphicsPipeline(d, p, &lv.pipelines.fadeBackground));
  p.blend = BlendMode::PremultipliedOver;  // the same shader output, new * w, laid over the visible
  CANOPY_TRY(createGraphicsPipeline(d, p, &lv.pipelines.fadeOverBackground));
  p.fragmentShader = "layers_fade.frag";
  CANOPY_TRY(createGraphicsPipeline(d, p, &lv.pipelines.fadeOver));
  GraphicsPipelineDesc z;
  z.pushConstantSize = sizeof(gpu::LayerFadePush);
  z.depthFormat = kLayerDepthFormat;
  z.depthTest = z.depthWrite = true;  // LESS: the nearer of the visible and the new depth
  z.vertexShader = "layers_fade.vert";
  z.fragmentShader = "layers_fade_depth.frag";
  return createGraphicsPipeline(d, z, &lv.pipelines.fadeDepth);
}



// The layer images for the settings in force, and the cross-fade's pipelines where re-slices go
// through the next set.
Status createTargets(LayeredVegetation& lv) {
  const bool nextSet = usesNextSet(lv);
  if (nextSet) CANOPY_TRY(createFadePipelines(lv));
  LayerTargetsDesc t;
  t.width = lv.desc.width;
  t.height = lv.desc.height;
  t.layers = lv.settings.layout.count();
  t.colorFormat = lv.desc.colorFormat;
  t.ids = lv.desc.writeIds;
  t.nextSet = nextSet;
  t.restUse = lv.desc.restUse;
  return createLayerTargets(*lv.device, t, lv.targets);
}

// The bytes of the second layer set still to be made: the visible set's twin (none when it exists).
uint64_t nextSetBytesToCome(const LayerTargets& t) {
  uint64_t bytes = 0;
  if (!t.next.color.image)
    for (const Image* img : {&t.color, &t.depth, &t.backgroundColor, &t.backgroundDepth}) bytes += img->allocation.size;
  return bytes;
}

// The scheduler's view of the vegetation (render/reslice_scheduler.h).
struct ReslicePartsOf {
  PlacementInputs placement;
  ResliceParts parts;
  explicit ReslicePartsOf(LayeredVegetation& lv)
      : placement(placementInputs(lv)),
        parts{placement, lv.settings, lv.mesh, lv.visible, lv.stats, lv.device, layerOutputSize(lv),
              spreadEnabled(lv.settings, lv.desc.writeIds), lv.desc.fixedSliceTriangles, pacedEnabled(lv.settings, lv.desc.writeIds)} {}
};

// Shading once's pair for a draw path (docs/design.md "Layers: shading once"); `p`: the path's
// plain pipeline. The same vertex shader in both, so the shading pass meets the pre-pass's depth
// exactly (EQUAL).
Status createShadeOnce(Device& d, GraphicsPipelineDesc p, LayerShadingPipelines::ShadeOnce* out) {
  p.fragmentShader = "layers_depth.frag";
  p.colorWrite = false;
  CANOPY_TRY(createGraphicsPipeline(d, p, &out->depth));
  p.fragmentShader = "layers_shade_once.frag";
  p.colorWrite = true;
  p.depthWrite = false;
  p.depthCompare = VK_COMPARE_OP_EQUAL;
  return createGraphicsPipeline(d, p, &out->shade);
}

void destroyShading(Device& d, LayerShadingPipelines& s) {
  for (GraphicsPipeline* p : {&s.layered, &s.layeredHalf, &s.perLayer, &s.background}) destroyGraphicsPipeline(d, *p);
  for (LayerShadingPipelines::ShadeOnce* o : {&s.layeredOnce, &s.perLayerOnce, &s.backgroundOnce, &s.layeredHalfOnce}) {
    destroyGraphicsPipeline(d, o->depth);
    destroyGraphicsPipeline(d, o->shade);
  }
  s = LayerShadingPipelines{};
}

Status createShading(LayeredVegetation& lv, uint32_t features, LayerShadingPipelines* out) {
  Device& d = *lv.device;
  out->features = features;
  GraphicsPipelineDesc p = layerMeshPipelineDesc(lv.desc.colorFormat, kLayerDepthFormat);
  p.fragmentSpecialization = {features};
  if (d.shaderClipDistance) {
    p.vertexShader = "layers_clip.vert";
    CANOPY_TRY(createGraphicsPipeline(d, p, &out->background));
    CANOPY_TRY(createShadeOnce(d, p, &out->backgroundOnce));
  }
  // The id output (a test and debug view) writes every triangle's ids: shaded the plain way.
  const bool once = !lv.desc.writeIds;
  if (lv.desc.writeIds) {
    p.colorFormats.push_back(kLayerIdsFormat);
    p.fragmentShader = "layers_ids.frag";
  }
  if (d.shaderClipDistance) {
    p.vertexShader = "layers_clip.vert";
    CANOPY_TRY(createGraphicsPipeline(d, p, &out->perLayer));
    if (once) CANOPY_TRY(createShadeOnce(d, p, &out->perLayerOnce));
  }
  if (d.shaderOutputLayer) {
    p.vertexShader = "layers.vert";
    CANOPY_TRY(createGraphicsPipeline(d, p, &out->layered));
    if (once) CANOPY_TRY(createShadeOnce(d, p, &out->layeredOnce));
  }
  if (d.shaderOutputLayer && d.shaderClipDistance) {
    p.vertexShader = "layers_half.vert";
    CANOPY_TRY(createGraphicsPipeline(d, p, &out->layeredHalf));
    if (once) CANOPY_TRY(createShadeOnce(d, p, &out->layeredHalfOnce));
  }
  return Status();
}

// The draws' pipelines for settings `s`: those in force when their features match, else ones made
// for them before, else new ones (the others kept: a frame in flight may use them).
Status useShadingFor(LayeredVegetation& lv, const LayerSettings& s) {
  LayerPipelines& p = lv.pipelines;
  const uint32_t features = layerShadingFeatures(lv, s);
  const bool made = p.shaded.features != 0;  // every set has one translucency model's bit
  if (made && p.shaded.features == features) return Status();
  for (LayerShadingPipelines& o : p.otherShading)
    if (o.features == features) {
      std::swap(p.shaded, o);
      return Status();
    }
  LayerShadingPipelines fresh;
  Status st = createShading(lv, features, &fresh);
  if (!st.ok()) {
    destroyShading(*lv.device, fresh);
    return st;
  }
  if (made) p.otherShading.push_back(std::move(p.shaded));
  p.shaded = std::move(fresh);
  return Status();
}

// Picks the draw path for the settings on this device.
Status chooseDrawPath(const LayeredVegetation& lv, const LayerSettings& s, bool* singlePass) {
  const Device& d = *lv.device;
  const bool canSingle = d.shaderOutputLayer && s.slice == SliceMode::LeafRoots;
  if (s.draw == LayerDrawMode::SinglePass && !canSingle)
    return Status::error(s.slice == SliceMode::Geometry
                             ? "layer draw mode SinglePass: geometric slicing cuts triangles and is drawn per layer"
                             : "layer draw mode SinglePass: the device lacks shaderOutputLayer (gl_Layer from the vertex shader)");
  *singlePass = s.draw == LayerDrawMode::PerLayer ? false : canSingle;
  if (!*singlePass && !d.shaderClipDistance)
    return Status::error("layers: the device has neither shaderOutputLayer nor shaderClipDistance; cannot slice");
  if (s.halfResolutionLayers > 0 && !d.shaderClipDistance)
    return Status::error(Result::UnsupportedDevice, "LayerSettings.halfResolutionLayers = " + std::to_string(s.halfResolutionLayers) +
                                                  ": drawing a layer into its image's quarter needs shaderClipDistance, which the device lacks");
  return Status();
}
}  // namespace

Status validateLayerSettings(const LayerSettings& s) {
  // Each region first: their sum could wrap around 2^32.
  for (int i = 0; i < 3; ++i)
    if (s.layout.region[i] > kMaxLayers)
      return Status::error("LayerSettings.layout.region[" + std::to_string(i) + "] = " + std::to_string(s.layout.region[i]) +
                           " is outside [0, " + std::to_string(kMaxLayers) + "]");
  if (s.layout.count() < 1 || s.layout.count() > kMaxLayers)
    return Status::error("LayerSettings.layout " + toString(s.layout) + " must hold 1.." + std::to_string(kMaxLayers) + " layers");
  // The schema's leaf ranges are Habel's measured ones (seed 004, III.B), as the shader clamps them.
  static_assert(LEAF_IOR_MIN == 1.2f && LEAF_IOR_MAX == 1.7f, "CANOPY_LAYER_SETTINGS's leafRefractiveIndex range");
  static_assert(LEAF_ROUGHNESS_MIN == 0.078f && LEAF_ROUGHNESS_MAX == 0.5f, "CANOPY_LAYER_SETTINGS's leafRoughness range");
  CANOPY_TRY(checkParams(s, "LayerSettings."));
  if (s.halfResolutionLayers > s.layout.count())
    return Status::error("LayerSettings.halfResolutionLayers = " + std::to_string(s.halfResolutionLayers) + " is outside [0, " +
                         std::to_string(s.layout.count()) + "] (the layers of layout " + toString(s.layout) + ")");
  return validateRegionSplit(s.regions);
}

Status createLayeredVegetation(Device& d, const VegetationModel& m, const LayeredVegetationDesc& desc,
                               LayeredVegetation* out) {
  return createLayeredVegetation(d, std::vector<SpeciesModel>{SpeciesModel{&m}}, desc, out);
}

Status createLayeredVegetation(Device& d, const std::vector<SpeciesModel>& species, const LayeredVegetationDesc& desc,
                               LayeredVegetation* out) {
  *out = LayeredVegetation{};
  LayeredVegetation& lv = *out;
  lv.device = &d;
  lv.desc = desc;
  lv.settings = desc.settings;
  if (desc.width < 1 || desc.width > 16384 || desc.height < 1 || desc.height > 16384)
    return Status::error("layers: size " + std::to_string(desc.width) + "x" + std::to_string(desc.height) +
                         " is outside 1..16384 per side");
  if (2ull * desc.guardX >= desc.width || 2ull * desc.guardY >= desc.height)
    return Status::error("layers: a guard band of " + std::to_string(desc.guardX) + "x" + std::to_string(desc.guardY) +
                         " px leaves no output in " + std::to_string(desc.width) + "x" + std::to_string(desc.height));
  if (desc.colorFormat != VK_FORMAT_R16G16B16A16_SFLOAT && desc.colorFormat != VK_FORMAT_R8G8B8A8_UNORM)
    return Status::error("layers: colour format must be R16G16B16A16_SFLOAT or R8G8B8A8_UNORM");
  if (desc.writeIds && (!d.fragmentPrimitiveId || !d.independentBlend))
    return Status::error("layers: the id output needs gl_PrimitiveID in fragment shaders (geometryShader) and independentBlend");
  CANOPY_TRY(validateLayerSettings(desc.settings));
  CANOPY_TRY(checkSpecies(species));
  for (const SpeciesModel& sm : species) {
    const VegetationModel& m = *sm.model;
    if (m.uvs.size() != m.positions.size() || m.indices.size() % 3 || m.triangleMaterial.size() != m.triangleCount())
      return Status::error("layers: inconsistent model arrays in " + m.path);
    for (size_t i = 0; i < m.materials.size(); ++i) {
      const ModelMaterial& mm = m.materials[i];
      for (int32_t image : {mm.baseColorImage, mm.normalImage, mm.transmissionImage, mm.transmissionColorImage})
        if (image < -1 || image >= int32_t(m.images.size()))
          return Status::error("layers: material " + std::to_string(i) + " ('" + mm.name + "') names image " +
                               std::to_string(image) + " of " + std::to_string(m.images.size()));
    }
  }
  const VegetationModel& m = *species[0].model;  // the impostor views' cache file (one species)
  if (desc.stagingRingBytes < 1 || desc.stagingRingBytes > (4ull << 30))
    return Status::error("layers: stagingRingBytes " + std::to_string(desc.stagingRingBytes) + " is outside [1, 4 GiB]");
  const uint64_t liveAtStart = d.allocator->liveBytes;
  Status s = [&]() -> Status {
    CompactMesh mesh;
    uint64_t key = 0;
    CANOPY_TRY(chooseDrawPath(lv, lv.settings, &lv.pipelines.singlePass));
    CANOPY_TRY(prepareLayerMesh(d, desc, species, lv.mesh, lv.impostors, lv.stats, &mesh, &key));
    CANOPY_TRY(createBuffer(d, sizeof(gpu::LayerFrame), VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT,
                            MemoryUsage::DeviceLocal, &lv.visible.frameBuffer, "layers: frame"));
    CANOPY_TRY(createTargets(lv));
    CANOPY_TRY(chooseLayerMeshResidency(d, desc, lv.mesh, liveAtStart, mesh.bytes(), nextSetBytesToCome(lv.targets)));
    if (lv.mesh.streamed && !lv.targets.next.color.image) {
      // Streamed re-slices draw into the second set. The images were never used by a frame (their
      // clear was submitted and waited for, or is dropped): freed now, so the allocator's count is
      // exact for the ring that follows.
      destroyLayerTargets(d, lv.targets, true);
      CANOPY_TRY(createTargets(lv));
    }
    CANOPY_TRY(placeLayerMesh(d, desc, lv.mesh, lv.stats, std::move(mesh), liveAtStart));
    InstanceInputs copies = desc.copies;
    if (copies.models.empty()) copies.models = {glm::mat4(1.0f)};
    CANOPY_TRY(setInstances(d, &lv.mesh.pendingUploads, copies, lv.mesh.species, &lv.instances));
    CANOPY_TRY(useShadingFor(lv, lv.settings));
    if (lv.impostors.enabled) {
      if (lv.mesh.streamed)
        return Status::error("impostors (CanopyDesc.impostors.enable) bake from the resident mesh and cut it into draw "
                             "ranges: the mesh (" + mib(lv.stats.meshBytes) + ") is streamed under deviceMemoryBudget " +
                             mib(desc.deviceMemoryBudget) + "; raise it (or 0: no limit)");
      if (species.size() > 1) lv.impostors.cacheNote = "cache off: the views are cached for one species";
      if (!desc.rootCacheDir.empty() && !m.path.empty() && species.size() == 1) {
        // The views' file cache sits beside the leaf roots' and is keyed by what they are drawn from.
        const CompactMesh& hm = lv.mesh.hostMesh;
        const std::vector<uint64_t> meshHashes = {
            hashBytes(key, hm.vertices.data(), hm.vertices.size() * sizeof(gpu::LayerVertex)),
            hashBytes(key, hm.indices.data(), hm.indices.size() * 2),
            hashBytes(key, hm.roots.data(), hm.roots.size() * sizeof(gpu::LayerLeafRoot))};
        lv.impostors.cachePath = impostorCachePath(m.path, desc.rootCacheDir);
        lv.impostors.cacheKey = impostorModelKey(lv.impostors, m, meshHashes);
        lv.impostors.cacheMaxBytes = desc.cacheMaxBytes;
      }
      ImpostorSources sources;
      sources.mesh = &lv.mesh;
      sources.instances = &lv.instances;
      sources.settings = &lv.settings;
      sources.colorFormat = desc.colorFormat;
      CANOPY_TRY(createImpostors(d, sources, lv.impostors));
      lv.stats.impostorBoxes = uint32_t(lv.impostors.nodes.size());
      lv.stats.impostorBakedBoxes = lv.impostors.baked;
      lv.stats.impostorTilePixels = lv.impostors.tileSize;
      lv.stats.impostorBytes = lv.impostors.bytes;
      lv.stats.impostorViewsPerBox = lv.impostors.viewCount();
      lv.stats.impostorBytesPerBox = uint64_t(lv.impostors.viewCount()) * lv.impostors.tileSize * lv.impostors.tileSize * 8;
      lv.stats.impostorBakeMs = lv.impostors.bakeMs;
      lv.stats.impostorCacheHit = lv.impostors.cacheHit;
      lv.stats.impostorCacheNote = lv.impostors.cacheNote;
    }
    CANOPY_TRY(checkImpostorSettings(lv, lv.settings));
    lv.stats.singlePass = lv.pipelines.singlePass;
    return Status();
  }();
  if (!s.ok()) {
    destroyLayeredVegetation(lv);
    return s.context("layers");
  }
  return Status();
}

void destroyLayeredVegetation(LayeredVegetation& lv) {
  if (!lv.device) return;
  Device& d = *lv.device;
  destroyLayerTargets(d, lv.targets);
  destroyImpostors(d, lv.impostors);
  destroyShading(d, lv.pipelines.shaded);
  for (LayerShadingPipelines& o : lv.pipelines.otherShading) destroyShading(d, o);
  for (GraphicsPipeline* p : {&lv.pipelines.fade, &lv.pipelines.fadeBackground, &lv.pipelines.fadeDepth, &lv.pipelines.fadeOver,
                             &lv.pipelines.fadeOverBackground})
    destroyGraphicsPipeline(d, *p);
  destroyLayerMesh(d, lv.mesh);
  destroyInstances(d, lv.instances);
  if (lv.pipelines.nearestSampler) d.vk.DestroySampler(d.device, lv.pipelines.nearestSampler, d.allocationCallbacks);
  destroyBuffer(d, lv.visible.frameBuffer);
  lv = LayeredVegetation{};
}

bool layerWorkPending(const LayeredVegetation& lv) {
  return !lv.mesh.pendingUploads.empty() || !lv.impostors.pendingUploads.empty() || !lv.targets.pendingClear.empty();
}

Status flushLayerWork(LayeredVegetation& lv, VkCommandBuffer cmd) {
  CANOPY_TRY(flushPreparedWork(*lv.device, lv.mesh.pendingUploads, cmd));
  CANOPY_TRY(flushPreparedWork(*lv.device, lv.impostors.pendingUploads, cmd));
  return flushPreparedWork(*lv.device, lv.targets.pendingClear, cmd);
}

Status setLayerSettings(LayeredVegetation& lv, const LayerSettings& s, bool* targetsRecreated) {
  if (targetsRecreated) *targetsRecreated = false;
  CANOPY_TRY(validateLayerSettings(s));
  CANOPY_TRY(checkImpostorSettings(lv, s));
  bool single = false;
  CANOPY_TRY(chooseDrawPath(lv, s, &single));
  CANOPY_TRY(useShadingFor(lv, s));
  const bool nextSetBefore = usesNextSet(lv);
  // A new layer count, or layers changing resolution: texels of the two sets no longer match, so
  // no cross-fade between them (a re-slice at once into new targets).
  const bool countChanged = s.layout.count() != lv.settings.layout.count() || halfResolutionMask(s) != halfResolutionMask(lv.settings);
  // How a re-slice is scheduled does not change what the layers hold: no re-slice for it.
  LayerSettings content = s;
  content.rebuildBudgetMs = lv.settings.rebuildBudgetMs;
  content.crossFadeFrames = lv.settings.crossFadeFrames;
  content.predictFrames = lv.settings.predictFrames;
  content.pacedReslices = lv.settings.pacedReslices;
  const bool contentChanged = !(content == lv.settings);
  const bool budgetChanged = s.rebuildBudgetMs != lv.settings.rebuildBudgetMs;
  lv.settings = s;
  lv.pipelines.singlePass = single;
  lv.stats.singlePass = single;
  const bool recreate = countChanged || usesNextSet(lv) != nextSetBefore;
  if (recreate) {
    destroyLayerTargets(*lv.device, lv.targets);
    CANOPY_TRY(createTargets(lv));
    if (targetsRecreated) *targetsRecreated = true;
  }
  rescheduleAfterChange(lv.reslice, contentChanged, recreate, budgetChanged);
  return Status();
}

Status setLayerTargetSize(LayeredVegetation& lv, uint32_t width, uint32_t height, uint32_t guardX, uint32_t guardY) {
  if (width < 1 || width > 16384 || height < 1 || height > 16384)
    return Status::error("layers: size " + std::to_string(width) + "x" + std::to_string(height) +
                         " is outside 1..16384 per side");
  if (2ull * guardX >= width || 2ull * guardY >= height)
    return Status::error("layers: a guard band of " + std::to_string(guardX) + "x" + std::to_string(guardY) +
                         " px leaves no output in " + std::to_string(width) + "x" + std::to_string(height));
  // The same size keeps the targets, unless a failed call left none (then they are made again).
  if (width == lv.desc.width && height == lv.desc.height && guardX == lv.desc.guardX && guardY == lv.desc.guardY &&
      lv.targets.color.image)
    return Status();
  destroyLayerTargets(*lv.device, lv.targets);
  lv.desc.width = width;
  lv.desc.height = height;
  lv.desc.guardX = guardX;
  lv.desc.guardY = guardY;
  rescheduleAfterChange(lv.reslice, true, true, false);  // the placement is in pixels of the old size
  const Status s = createTargets(lv);
  if (!s.ok()) destroyLayerTargets(*lv.device, lv.targets);  // none rather than some
  return s;
}

Status setLayerInstances(LayeredVegetation& lv, const InstanceInputs& copies) {
  LayerInstances next;
  CANOPY_TRY(setInstances(*lv.device, &lv.mesh.pendingUploads, copies, lv.mesh.species, &next));
  if (lv.impostors.enabled) {
    const Status s = reserveImpostorList(*lv.device, lv.impostors, next);
    if (!s.ok()) {
      destroyInstances(*lv.device, next);
      return s;
    }
  }
  destroyBufferLater(*lv.device, lv.instances.buffer);  // frames in flight read the old table
  lv.instances = std::move(next);
  requestReslice(lv.reslice, "instances changed", true);
  return Status();
}

LayerView sliceCameraFor(const LayeredVegetation& lv, const LayerView& view) {
  return guardedView(view, layerOutputSize(lv), layerGuard(lv));
}

Status updateLayerView(LayeredVegetation& lv, const LayerView& view, bool* changed) {
  const ReslicePartsOf of(lv);
  return advanceReslice(lv.reslice, of.parts, view, sliceCameraFor(lv, view), changed);
}

bool usesNextSet(const LayeredVegetation& lv) {
  return spreadEnabled(lv.settings, lv.desc.writeIds) || pacedEnabled(lv.settings, lv.desc.writeIds) || lv.mesh.streamed;
}

MeshDraw meshDraw(const LayeredVegetation& lv) {
  MeshDraw md;
  md.device = lv.device;
  md.mesh = &lv.mesh;
  md.instances = lv.instances.buffer.buffer;
  md.speciesCopies = &lv.instances.speciesCopies;
  md.frame = lv.visible.frameBuffer.buffer;
  md.width = lv.desc.width;
  md.height = lv.desc.height;
  md.leafTransmission = lv.settings.leafTransmission;
  md.leafOpticalDepth = lv.settings.leafOpticalDepth;
  md.overrideLeafRoughness = lv.settings.overrideLeafRoughness;
  return md;
}

PlacementInputs placementInputs(const LayeredVegetation& lv) {
  PlacementInputs in;
  in.mesh = &lv.mesh;
  in.instances = &lv.instances;
  in.impostors = &lv.impostors;
  in.settings = &lv.settings;
  in.width = lv.desc.width;
  in.height = lv.desc.height;
  return in;
}

VkRect2D layerFootprint(const LayeredVegetation& lv) {
  std::vector<glm::mat4> views{lv.visible.frame.viewProj};
  const SpreadPhase phase = lv.reslice.spread.phase;
  if (phase == SpreadPhase::Drawing || phase == SpreadPhase::CrossFading) views.push_back(lv.reslice.spread.job.frame.viewProj);
  // World bounds: every copy.
  return projectedFootprint(views, lv.instances.boundsMin, lv.instances.boundsMax, lv.desc.width, lv.desc.height);
}

}  // namespace canopy
