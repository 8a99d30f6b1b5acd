#include "render/gltf_accessors.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <string>

#include "render/gltf_json_checks.h"

namespace canopy {

uint32_t componentSize(int type) {
  switch (type) {
    case TINYGLTF_COMPONENT_TYPE_BYTE:
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: return 1;
    case TINYGLTF_COMPONENT_TYPE_SHORT:
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: return 2;
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT:
    case TINYGLTF_COMPONENT_TYPE_FLOAT: return 4;
    default: return 0;
  }
}
uint32_t componentCount(int type) {
  switch (type) {
    case TINYGLTF_TYPE_SCALAR: return 1;
    case TINYGLTF_TYPE_VEC2: return 2;
    case TINYGLTF_TYPE_VEC3: return 3;
    case TINYGLTF_TYPE_VEC4: return 4;
    case TINYGLTF_TYPE_MAT2: return 4;
    case TINYGLTF_TYPE_MAT3: return 9;
    case TINYGLTF_TYPE_MAT4: return 16;
    default: return 0;
  }
}

double readComponent(const unsigned char* p, int type, bool normalized) {
  switch (type) {
    case TINYGLTF_COMPONENT_TYPE_FLOAT: { float v; std::memcpy(&v, p, 4); return v; }
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: return normalized ? p[0] / 255.0 : p[0];
    case TINYGLTF_COMPONENT_TYPE_BYTE: { int8_t v; std::memcpy(&v, p, 1); return normalized ? std::max(v / 127.0, -1.0) : v; }
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: { uint16_t v; std::memcpy(&v, p, 2); return normalized ? v / 65535.0 : v; }
    case TINYGLTF_COMPONENT_TYPE_SHORT: { int16_t v; std::memcpy(&v, p, 2); return normalized ? std::max(v / 32767.0, -1.0) : v; }
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT: { uint32_t v; std::memcpy(&v, p, 4); return v; }
  }
  return 0;
}


Status GltfReader::view(int index, const unsigned char** data, uint64_t* size, uint32_t* stride) const {
  const std::string what = "bufferViews[" + std::to_string(index) + "]";
  if (index < 0 || size_t(index) >= m_.bufferViews.size()) return Status::error(what + " does not exist");
  const tinygltf::BufferView& v = m_.bufferViews[size_t(index)];
  if (v.buffer < 0 || size_t(v.buffer) >= m_.buffers.size())
    return Status::error(what + ": buffer " + std::to_string(v.buffer) + " does not exist");
  const tinygltf::Buffer& b = m_.buffers[size_t(v.buffer)];
  const uint64_t off = v.byteOffset, len = v.byteLength;
  if (len == 0 || !rangeFits(off, len, b.data.size()))
    return Status::error(what + ": byteLength " + std::to_string(len) + " at byteOffset " + std::to_string(off) + " does not fit buffers[" +
                         std::to_string(v.buffer) + "] (" + std::to_string(b.data.size()) + " bytes loaded)");
  if (v.byteStride != 0 && (v.byteStride < 4 || v.byteStride > 252 || v.byteStride % 4 != 0))
    return Status::error(what + ": byteStride " + std::to_string(v.byteStride) + " is not a multiple of 4 in [4, 252]");
  *data = b.data.data() + off;
  *size = len;
  *stride = uint32_t(v.byteStride);
  return Status();
}

Status GltfReader::read(int index, const std::vector<int>& types, std::vector<uint32_t> componentTypes, uint64_t maxCount,
                        std::vector<double>* out, uint32_t* outComponents, uint64_t* outCount) const {
  const std::string what = "accessors[" + std::to_string(index) + "]";
  if (index < 0 || size_t(index) >= m_.accessors.size()) return Status::error(what + " does not exist");
  const tinygltf::Accessor& a = m_.accessors[size_t(index)];
  if (std::find(types.begin(), types.end(), a.type) == types.end())
    return Status::error(what + ": type " + std::to_string(a.type) + " is not allowed here");
  if (std::find(componentTypes.begin(), componentTypes.end(), uint32_t(a.componentType)) == componentTypes.end())
    return Status::error(what + ": componentType " + std::to_string(a.componentType) + " is not allowed here");
  const uint32_t cs = componentSize(a.componentType), nc = componentCount(a.type), elem = cs * nc;
  const uint64_t count = a.count;
  if (count == 0) return Status::error(what + ": count 0 (glTF requires at least 1)");
  const unsigned char* data = nullptr;
  uint32_t stride = elem;
  const uint64_t offset = a.byteOffset;
  if (a.bufferView >= 0) {
    uint64_t size;
    CANOPY_TRY(view(a.bufferView, &data, &size, &stride).context(what));
    if (stride == 0) stride = elem;
    if (stride < elem) return Status::error(what + ": byteStride " + std::to_string(stride) + " is smaller than an element (" + std::to_string(elem) + ")");
    if (offset % cs != 0) return Status::error(what + ": byteOffset " + std::to_string(offset) + " is not a multiple of the component size");
    uint64_t need = count - 1;  // offset + stride * (count - 1) + elem, checked
    const bool fits = mulTo(&need, stride) && addTo(&need, offset) && addTo(&need, elem) && need <= size;
    if (!fits)
      return Status::error(what + ": byteOffset " + std::to_string(offset) + " + " + std::to_string(count) + " elements of stride " +
                           std::to_string(stride) + " do not fit bufferViews[" + std::to_string(a.bufferView) + "] (" +
                           std::to_string(size) + " bytes)");
  } else {
    if (offset != 0) return Status::error(what + ": byteOffset without a bufferView");
    if (count > maxCount)
      return Status::error(what + ": count " + std::to_string(count) + " without a bufferView exceeds the model's limit of " +
                           std::to_string(maxCount) + " (GltfLoadOptions.maxVertices / maxTriangles)");
  }
  // The sparse part, checked before any allocation too.
  const unsigned char *idata = nullptr, *vdata = nullptr;
  uint64_t n = 0;
  uint32_t ics = 0;
  uint64_t ioff = 0, voff = 0;
  if (a.sparse.isSparse) {
    if (a.sparse.count <= 0 || uint64_t(a.sparse.count) > count)
      return Status::error(what + ": sparse count " + std::to_string(a.sparse.count) + " is outside [1, count = " + std::to_string(count) + "]");
    n = uint64_t(a.sparse.count);
    ics = componentSize(a.sparse.indices.componentType);
    if (ics == 0 || a.sparse.indices.componentType == TINYGLTF_COMPONENT_TYPE_BYTE ||
        a.sparse.indices.componentType == TINYGLTF_COMPONENT_TYPE_SHORT || a.sparse.indices.componentType == TINYGLTF_COMPONENT_TYPE_FLOAT)
      return Status::error(what + ": sparse indices componentType " + std::to_string(a.sparse.indices.componentType) + " is invalid");
    if (a.sparse.indices.byteOffset < 0)
      return Status::error(what + ".sparse.indices: byteOffset " + std::to_string(a.sparse.indices.byteOffset) + " is negative");
    if (a.sparse.values.byteOffset < 0)
      return Status::error(what + ".sparse.values: byteOffset " + std::to_string(a.sparse.values.byteOffset) + " is negative");
    ioff = uint64_t(a.sparse.indices.byteOffset);
    voff = uint64_t(a.sparse.values.byteOffset);
    uint64_t isize, vsize;
    uint32_t istride, vstride;
    CANOPY_TRY(view(a.sparse.indices.bufferView, &idata, &isize, &istride).context(what + ".sparse.indices"));
    CANOPY_TRY(view(a.sparse.values.bufferView, &vdata, &vsize, &vstride).context(what + ".sparse.values"));
    uint64_t ibytes = n, vbytes = n;
    if (!mulTo(&ibytes, ics) || !rangeFits(ioff, ibytes, isize))
      return Status::error(what + ".sparse.indices: " + std::to_string(n) + " indices at byteOffset " + std::to_string(ioff) +
                           " do not fit their bufferView (" + std::to_string(isize) + " bytes)");
    if (!mulTo(&vbytes, elem) || !rangeFits(voff, vbytes, vsize))
      return Status::error(what + ".sparse.values: " + std::to_string(n) + " values at byteOffset " + std::to_string(voff) +
                           " do not fit their bufferView (" + std::to_string(vsize) + " bytes)");
  }
  out->assign(size_t(count) * nc, 0.0);
  if (data)
    for (uint64_t i = 0; i < count; ++i)
      for (uint32_t c = 0; c < nc; ++c)
        (*out)[i * nc + c] = readComponent(data + offset + stride * i + cs * c, a.componentType, a.normalized);
  for (uint64_t k = 0; k < n; ++k) {
    const uint64_t target = uint64_t(readComponent(idata + ioff + k * ics, a.sparse.indices.componentType, false));
    if (target >= count) return Status::error(what + ".sparse.indices[" + std::to_string(k) + "] = " + std::to_string(target) + " is past count " + std::to_string(count));
    for (uint32_t c = 0; c < nc; ++c)
      (*out)[target * nc + c] = readComponent(vdata + voff + k * elem + cs * c, a.componentType, a.normalized);
  }
  for (double v : *out)
    if (!std::isfinite(v)) return Status::error(what + ": contains NaN or infinity");
  *outComponents = nc;
  *outCount = count;
  return Status();
}

}  // namespace canopy
