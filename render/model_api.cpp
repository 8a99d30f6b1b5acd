// The model entry points of <canopy/canopy.h> (loadModel, createModel, destroyModel and the
// queries): a Model is a VegetationModel in host memory; no device is involved, so a host may call
// them on any thread (docs/embedding.md "Threads").
#include <algorithm>
#include <cmath>
#include <new>
#include <string>

#include "render/canopy.h"
#include "render/gltf_loader.h"

namespace canopy {

Status loadModel(const std::string& path, const GltfLoadOptions& options, Model** out) {
  return guardApi("loadModel", [&]() -> Status {
    if (!out) return Status::error("loadModel: out is null");
    *out = nullptr;
    auto* m = new (std::nothrow) Model();
    if (!m) return Status::error(Result::OutOfHostMemory, "loadModel: out of host memory");
    Status s = loadGltf(path, options, &m->data);
    if (!s.ok()) {
      delete m;
      return s.code() == Result::InvalidArgument ? Status::error(Result::InvalidModel, s.message()) : s;
    }
    *out = m;
    return Status();
  });
}

Status createModel(const MeshDesc& desc, Model** out) {
  return guardApi("createModel", [&]() -> Status {
    if (!out) return Status::error("createModel: out is null");
    *out = nullptr;
    const std::string what = "MeshDesc '" + desc.name + "'";
    if (!desc.positions || desc.vertexCount == 0) return Status::error(Result::InvalidModel, what + ": no positions");
    if (!desc.indices || desc.indexCount == 0 || desc.indexCount % 3 != 0)
      return Status::error(Result::InvalidModel, what + ": indexCount = " + std::to_string(desc.indexCount) +
                                                     " is not a positive multiple of 3 (or indices is null)");
    const uint64_t triangles = desc.indexCount / 3;
    if (desc.triangleMaterials && (desc.materialCount == 0 || !desc.materials))
      return Status::error(Result::InvalidModel, what + ": triangleMaterials needs materials (materialCount >= 1)");
    if (desc.imageCount && !desc.images) return Status::error(Result::InvalidModel, what + ": imageCount without images");
    if ((desc.vertexBranches != nullptr) != (desc.vertexW != nullptr) || (desc.vertexBranches && !desc.branches) ||
        (desc.branchCount && !desc.branches))
      return Status::error(Result::InvalidModel,
                           what + ": a branch hierarchy needs vertexBranches, vertexW and branches (branchCount >= 1) together");
    auto m = std::unique_ptr<Model>(new (std::nothrow) Model());
    if (!m) return Status::error(Result::OutOfHostMemory, "createModel: out of host memory");
    VegetationModel& v = m->data;
    try {
      v.positions.resize(desc.vertexCount);
      for (uint32_t i = 0; i < desc.vertexCount; ++i) {
        const glm::vec3 p(desc.positions[3 * i], desc.positions[3 * i + 1], desc.positions[3 * i + 2]);
        if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
          return Status::error(Result::InvalidModel, what + ": position " + std::to_string(i) + " is not finite");
        v.positions[i] = p;
      }
      v.indices.assign(desc.indices, desc.indices + desc.indexCount);
      for (uint64_t i = 0; i < desc.indexCount; ++i)
        if (v.indices[i] >= desc.vertexCount)
          return Status::error(Result::InvalidModel, what + ": indices[" + std::to_string(i) + "] = " +
                                                         std::to_string(v.indices[i]) + " is not below vertexCount " +
                                                         std::to_string(desc.vertexCount));
      v.uvs.assign(desc.vertexCount, glm::vec2(0.0f));
      if (desc.uvs)
        for (uint32_t i = 0; i < desc.vertexCount; ++i) v.uvs[i] = {desc.uvs[2 * i], desc.uvs[2 * i + 1]};
      v.normals.assign(desc.vertexCount, glm::vec3(0.0f));
      if (desc.normals) {
        for (uint32_t i = 0; i < desc.vertexCount; ++i) {
          const glm::vec3 n(desc.normals[3 * i], desc.normals[3 * i + 1], desc.normals[3 * i + 2]);
          const float len = glm::length(n);
          v.normals[i] = std::isfinite(len) && len > 0 ? n / len : glm::vec3(0, 1, 0);
        }
      } else {
        // Area-weighted face normals, as the glTF loader computes them for files without normals.
        for (uint64_t t = 0; t < triangles; ++t) {
          const uint32_t a = v.indices[3 * t], b = v.indices[3 * t + 1], cc = v.indices[3 * t + 2];
          const glm::vec3 n = glm::cross(v.positions[b] - v.positions[a], v.positions[cc] - v.positions[a]);
          v.normals[a] += n;
          v.normals[b] += n;
          v.normals[cc] += n;
        }
        for (glm::vec3& n : v.normals) n = glm::length(n) > 0 ? glm::normalize(n) : glm::vec3(0, 1, 0);
      }
      for (uint32_t i = 0; i < desc.imageCount; ++i) {
        const MeshImage& im = desc.images[i];
        if (im.width < 1 || im.height < 1 || im.width > 16384 || im.height > 16384 || !im.rgba)
          return Status::error(Result::InvalidModel, what + ": images[" + std::to_string(i) + "] is " +
                                                         std::to_string(im.width) + "x" + std::to_string(im.height) +
                                                         " (1..16384 per side, with texels)");
        ModelImage mi;
        mi.name = "image " + std::to_string(i);
        mi.width = im.width;
        mi.height = im.height;
        mi.rgba.assign(im.rgba, im.rgba + size_t(im.width) * im.height * 4);
        v.images.push_back(std::move(mi));
      }
      const uint32_t materialCount = std::max(desc.materialCount, 1u);
      for (uint32_t i = 0; i < desc.materialCount; ++i) {
        const MeshMaterial& mm = desc.materials[i];
        if (mm.image < -1 || mm.image >= int32_t(desc.imageCount))
          return Status::error(Result::InvalidModel, what + ": materials[" + std::to_string(i) + "].image = " +
                                                         std::to_string(mm.image) + " is outside -1.." +
                                                         std::to_string(int32_t(desc.imageCount) - 1));
        if (!(mm.alphaCutoff >= 0.0f && mm.alphaCutoff <= 1.0f) || uint32_t(mm.alphaMode) > 2)
          return Status::error(Result::InvalidModel, what + ": materials[" + std::to_string(i) +
                                                         "]: alphaCutoff outside [0, 1] or an unknown alphaMode");
        if (!((mm.roughness >= 0.0f && mm.roughness <= 1.0f) || mm.roughness == -1.0f) || !(mm.specular >= 0.0f && mm.specular <= 1.0f))
          return Status::error(Result::InvalidModel, what + ": materials[" + std::to_string(i) +
                                                         "]: roughness outside [0, 1] (or -1: none) or specular outside [0, 1]");
        ModelMaterial mat;
        mat.name = mm.name;
        mat.baseColorFactor = {mm.baseColor[0], mm.baseColor[1], mm.baseColor[2], mm.baseColor[3]};
        mat.baseColorImage = mm.image;
        mat.alphaMode = mm.alphaMode;
        mat.alphaCutoff = mm.alphaCutoff;
        mat.doubleSided = mm.doubleSided;
        mat.roughness = mm.roughness;
        mat.specularFactor = mm.specular;
        v.materials.push_back(mat);
      }
      // The loader's convention: the file's materials, then one default material last.
      ModelMaterial fallback;
      fallback.name = "default";
      v.materials.push_back(fallback);
      v.triangleMaterial.assign(triangles, desc.triangleMaterials ? 0u : uint32_t(v.materials.size() - 1));
      if (desc.triangleMaterials) {
        for (uint64_t t = 0; t < triangles; ++t) {
          if (desc.triangleMaterials[t] >= materialCount)
            return Status::error(Result::InvalidModel, what + ": triangleMaterials[" + std::to_string(t) + "] = " +
                                                           std::to_string(desc.triangleMaterials[t]) +
                                                           " is not below materialCount " + std::to_string(desc.materialCount));
          v.triangleMaterial[t] = desc.triangleMaterials[t];
        }
      }
      if (desc.vertexBranches) {
        // Checked for consistency (parents, levels, axes, indices) by createCanopy's
        // validateBendHierarchy; here only what the packing needs.
        for (uint32_t i = 0; i < desc.branchCount; ++i) {
          const MeshBranch& b = desc.branches[i];
          v.branches.push_back(gpu::BendBranch{toGlm(b.origin), b.parent, toGlm(b.axis), b.level});
        }
        v.bend.resize(desc.vertexCount);
        for (uint32_t i = 0; i < desc.vertexCount; ++i) {
          uint32_t w = 0;
          for (uint32_t k = 0; k < 4; ++k) {
            const float x = desc.vertexW[4 * i + k];
            if (!(x >= 0.0f && x <= 1.0f))
              return Status::error(Result::InvalidModel, what + ": vertexW[" + std::to_string(4 * i + k) + "] = " +
                                                             std::to_string(x) + " is outside [0, 1]");
            w |= uint32_t(std::lround(x * 255.0f)) << (8 * k);
          }
          v.bend[i] = gpu::BendVertex{desc.vertexBranches[i] == kNoBranch ? BEND_LEAF_ONLY : desc.vertexBranches[i], w};
        }
      }
    } catch (const std::bad_alloc&) {
      return Status::error(Result::OutOfHostMemory, what + ": out of host memory");
    }
    v.boundsMin = v.boundsMax = v.positions[0];
    for (const glm::vec3& p : v.positions) {
      v.boundsMin = glm::min(v.boundsMin, p);
      v.boundsMax = glm::max(v.boundsMax, p);
    }
    *out = m.release();
    return Status();
  });
}

void destroyModel(Model* model) { delete model; }

uint64_t modelTriangleCount(const Model* model) { return model ? model->data.triangleCount() : 0; }

void modelBounds(const Model* model, Float3* min, Float3* max) {
  if (!model) return;
  if (min) *min = toFloat3(model->data.boundsMin);
  if (max) *max = toFloat3(model->data.boundsMax);
}

Status canopySceneInstances(const CanopyScene& scene, const std::vector<const Model*>& models, std::vector<CanopyInstance>* out) {
  return guardApi("canopySceneInstances", [&]() -> Status {
    if (!out) return Status::error(Result::InvalidArgument, "canopySceneInstances: out is null");
    std::vector<Float3> lo(models.size()), hi(models.size());
    for (size_t i = 0; i < models.size(); ++i) {
      if (!models[i]) return Status::error(Result::InvalidArgument, "canopySceneInstances: model #" + std::to_string(i) + " is null");
      modelBounds(models[i], &lo[i], &hi[i]);
    }
    return sceneCopies(scene, lo, hi, out);
  });
}

}  // namespace canopy
