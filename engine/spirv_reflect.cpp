#include "engine/spirv_reflect.h"

#include <algorithm>
#include <unordered_map>

namespace canopy {
namespace {
// SPIR-V 1.x opcodes, decorations and storage classes (the SPIR-V specification, section 3).
enum : uint32_t {
  OpTypeImage = 25, OpTypeSampler = 26, OpTypeSampledImage = 27, OpTypeArray = 28, OpTypeRuntimeArray = 29,
  OpTypeStruct = 30, OpTypePointer = 32, OpVariable = 59, OpDecorate = 71,
};
enum : uint32_t { DecorationBlock = 2, DecorationBufferBlock = 3, DecorationBinding = 33, DecorationDescriptorSet = 34 };
enum : uint32_t { StorageUniformConstant = 0, StorageUniform = 2, StorageStorageBuffer = 12 };

struct Ids {
  std::unordered_map<uint32_t, uint32_t> binding, set, pointee, pointerClass;
  std::unordered_map<uint32_t, uint32_t> imageSampled;  // OpTypeImage: 1 sampled, 2 storage
  std::unordered_map<uint32_t, uint32_t> opcode;        // type id -> its opcode
  std::unordered_map<uint32_t, bool> block, bufferBlock;
  struct Var { uint32_t id, type, storage; };
  std::vector<Var> vars;
};
}  // namespace

const char* descriptorTypeName(VkDescriptorType t) {
  switch (t) {
    case VK_DESCRIPTOR_TYPE_STORAGE_BUFFER: return "storage buffer";
    case VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER: return "uniform buffer";
    case VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER: return "combined image sampler";
    case VK_DESCRIPTOR_TYPE_SAMPLED_IMAGE: return "sampled image";
    case VK_DESCRIPTOR_TYPE_STORAGE_IMAGE: return "storage image";
    case VK_DESCRIPTOR_TYPE_SAMPLER: return "sampler";
    case VK_DESCRIPTOR_TYPE_MAX_ENUM: return "nothing";
    default: return "another descriptor type";
  }
}

Status reflectDescriptors(const uint32_t* code, size_t words, DescriptorTypes* out) {
  out->clear();
  if (!code || words < 5 || code[0] != 0x07230203u) return Status::error("not a SPIR-V module (magic number)");
  Ids ids;
  for (size_t i = 5; i < words;) {
    const uint32_t op = code[i] & 0xffffu, len = code[i] >> 16;
    if (len == 0 || i + len > words) return Status::error("malformed SPIR-V: instruction at word " + std::to_string(i));
    const uint32_t* w = code + i;
    switch (op) {
      case OpDecorate:
        if (len >= 3 && w[2] == DecorationBlock) ids.block[w[1]] = true;
        if (len >= 3 && w[2] == DecorationBufferBlock) ids.bufferBlock[w[1]] = true;
        if (len >= 4 && w[2] == DecorationBinding) ids.binding[w[1]] = w[3];
        if (len >= 4 && w[2] == DecorationDescriptorSet) ids.set[w[1]] = w[3];
        break;
      case OpTypeImage:
        if (len >= 9) ids.imageSampled[w[1]] = w[7];
        ids.opcode[w[1]] = op;
        break;
      case OpTypeSampler: case OpTypeSampledImage: case OpTypeArray: case OpTypeRuntimeArray: case OpTypeStruct:
        if (len >= 2) ids.opcode[w[1]] = op;
        break;
      case OpTypePointer:
        if (len >= 4) {
          ids.pointerClass[w[1]] = w[2];
          ids.pointee[w[1]] = w[3];
        }
        break;
      case OpVariable:
        if (len >= 4) ids.vars.push_back({w[2], w[1], w[3]});
        break;
      default: break;
    }
    i += len;
  }
  for (const Ids::Var& v : ids.vars) {
    if (v.storage != StorageUniformConstant && v.storage != StorageUniform && v.storage != StorageStorageBuffer) continue;
    auto b = ids.binding.find(v.id);
    if (b == ids.binding.end()) continue;  // not a descriptor (e.g. a push-constant block)
    const std::string where = "binding " + std::to_string(b->second);
    auto s = ids.set.find(v.id);
    if (s != ids.set.end() && s->second != 0)
      return Status::error(where + " is in descriptor set " + std::to_string(s->second) + "; Canopy's pipelines use set 0 only");
    auto p = ids.pointee.find(v.type);
    if (p == ids.pointee.end()) return Status::error(where + ": its variable's type is not a pointer");
    const uint32_t type = p->second;
    const uint32_t kind = ids.opcode.count(type) ? ids.opcode[type] : 0;
    VkDescriptorType t = VK_DESCRIPTOR_TYPE_MAX_ENUM;
    if (kind == OpTypeArray || kind == OpTypeRuntimeArray)
      return Status::error(where + " is an array of descriptors (Canopy binds one descriptor per binding)");
    if (v.storage == StorageStorageBuffer) t = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER;
    else if (v.storage == StorageUniform)
      t = ids.bufferBlock.count(type) ? VK_DESCRIPTOR_TYPE_STORAGE_BUFFER : VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER;
    else if (kind == OpTypeSampledImage) t = VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER;
    else if (kind == OpTypeSampler) t = VK_DESCRIPTOR_TYPE_SAMPLER;
    else if (kind == OpTypeImage)
      t = ids.imageSampled[type] == 2 ? VK_DESCRIPTOR_TYPE_STORAGE_IMAGE : VK_DESCRIPTOR_TYPE_SAMPLED_IMAGE;
    else return Status::error(where + ": a resource type Canopy does not bind");
    if (b->second > 255) return Status::error(where + " is beyond 255");
    if (out->size() <= b->second) out->resize(b->second + 1, VK_DESCRIPTOR_TYPE_MAX_ENUM);
    VkDescriptorType& slot = (*out)[b->second];
    if (slot != VK_DESCRIPTOR_TYPE_MAX_ENUM && slot != t)
      return Status::error(where + " is declared twice, as " + descriptorTypeName(slot) + " and " + descriptorTypeName(t));
    slot = t;
  }
  return Status();
}

Status mergeDescriptors(const DescriptorTypes& a, const DescriptorTypes& b, const std::string& what, DescriptorTypes* out) {
  DescriptorTypes m(std::max(a.size(), b.size()), VK_DESCRIPTOR_TYPE_MAX_ENUM);
  for (size_t i = 0; i < m.size(); ++i) {
    const VkDescriptorType x = i < a.size() ? a[i] : VK_DESCRIPTOR_TYPE_MAX_ENUM;
    const VkDescriptorType y = i < b.size() ? b[i] : VK_DESCRIPTOR_TYPE_MAX_ENUM;
    if (x != VK_DESCRIPTOR_TYPE_MAX_ENUM && y != VK_DESCRIPTOR_TYPE_MAX_ENUM && x != y)
      return Status::error(what + ": binding " + std::to_string(i) + " is a " + descriptorTypeName(x) +
                           " in one stage and a " + descriptorTypeName(y) + " in the other");
    m[i] = x != VK_DESCRIPTOR_TYPE_MAX_ENUM ? x : y;
  }
  *out = std::move(m);
  return Status();
}

Status requireContiguous(const DescriptorTypes& types, const std::string& what) {
  for (size_t i = 0; i < types.size(); ++i)
    if (types[i] == VK_DESCRIPTOR_TYPE_MAX_ENUM)
      return Status::error(what + ": binding " + std::to_string(i) + " is declared by no stage, binding " +
                           std::to_string(types.size() - 1) + " is (bindings are pushed as one list from 0)");
  return Status();
}

}  // namespace canopy
