// Bindings and the shared vertex stage of the impostor draws (render/impostor_gpu.cpp declares the
// same six push-descriptor bindings; shared/impostor.h the structs and view frames): one polygon
// per box facing the viewer and covering its outline, in the layer of the box's root. A box is of
// its species' model; an impostor instance names the copy it stands for (the copies' table, as the
// leaves read it), and both stages work in that model's space, where the views were baked: the
// viewer is brought into it, the polygon and the leaf depth taken out by the copy's transform
// (docs/design.md "Impostors: copies and species"). Its fragments
// show either the paper's crossed polygons (every stored view on its plane, met by the viewer's ray)
// or the two views nearest the viewer's direction (Lluch et al.: alpha-blended against popping).
#include "shared/layers.h"
#include "shared/impostor.h"

layout(binding = 0, scalar) readonly buffer FrameBuf { LayerFrame f; };
layout(binding = 1, scalar) readonly buffer BoxBuf { ImpostorBox boxes[]; };
layout(binding = 2, scalar) readonly buffer InstanceBuf { ImpostorInstance instances[]; };
layout(binding = 3) uniform sampler2DArray atlasColor;  // premultiplied linear RGBA per view tile
layout(binding = 4) uniform sampler2DArray atlasDepth;  // 0 at the side the view looks from, 1 at the far side
layout(binding = 5, scalar) readonly buffer CopyBuf { LayerInstance copies[]; };  // the placed copies (CanopyInstance)
layout(push_constant, scalar) uniform Push { ImpostorPush pc; };

// The viewer in the copy's model space: the camera position (w = 1), or an orthographic camera's
// direction towards the viewer (w = 0). Set by each stage's main before towardsViewer is used.
vec4 modelEye;

// Towards the viewer from p (model space).
vec3 towardsViewer(vec3 p) { return modelEye.w > 0.0 ? normalize(modelEye.xyz - p) : modelEye.xyz; }

#ifdef CANOPY_VERTEX
layout(location = 0) out vec3 vModel;          // on the polygon, in the copy's model space
layout(location = 1) flat out uvec4 vBoxViews;  // box, first view, second view, level
layout(location = 2) flat out vec2 vWeights;    // the first view's share, the instance's weight
layout(location = 3) flat out vec4 vEye;        // modelEye
layout(location = 4) flat out uint vCopy;       // the copy (index into copies[])

// Half the box's extent along unit axis a.
float support(vec3 h, vec3 a) { return abs(h.x * a.x) + abs(h.y * a.y) + abs(h.z * a.z); }

uint impostorVertex() {
  ImpostorInstance inst = instances[gl_InstanceIndex];
  ImpostorBox b = boxes[inst.box];
  mat4 model = copies[inst.copy].model;
  mat4 toModel = inverse(model);
  modelEye = f.eye.w > 0.0 ? vec4((toModel * vec4(f.eye.xyz, 1.0)).xyz, 1.0) : vec4(normalize(mat3(toModel) * f.eye.xyz), 0.0);
  vec3 c = b.center.xyz, h = b.halfExtent.xyz;
  vec3 w = towardsViewer(c);
  // The two views that face the viewer best; the first's share falls to 1/2 as the second catches up.
  uint k1 = pc.firstView, k2 = pc.firstView + 1u;
  float s1 = -2.0, s2 = -2.0;
  for (uint k = pc.firstView; k < IMPOSTOR_VIEWS; ++k) {
    float s = impostorViewScore(k, w);
    if (s > s1) { s2 = s1; k2 = k1; s1 = s; k1 = k; }
    else if (s > s2) { s2 = s; k2 = k; }
  }
  float w1 = 0.5 + 0.5 * clamp((s1 - s2) / 0.15, 0.0, 1.0);
  // The polygon: through the centre, facing the viewer, covering the box's outline (enlarged for a
  // near perspective camera, whose outline of the box's front is wider than at its centre).
  vec3 up = abs(w.y) > 0.99 ? vec3(0.0, 0.0, -1.0) : vec3(0.0, 1.0, 0.0);
  vec3 r = normalize(impostorCross(up, w));
  vec3 u = impostorCross(w, r);
  float grow = 1.0;
  if (modelEye.w > 0.0) {
    float dist = length(modelEye.xyz - c), radius = length(h);
    grow = dist / max(dist - radius, 0.5 * dist);
  }
  const vec2 corners[6] = vec2[6](vec2(-1, -1), vec2(1, -1), vec2(1, 1), vec2(-1, -1), vec2(1, 1), vec2(-1, 1));
  vec2 q = corners[gl_VertexIndex % 6];
  vModel = c + grow * (r * support(h, r) * q.x + u * support(h, u) * q.y);
  gl_Position = f.viewProj * (model * vec4(vModel, 1.0));
  vBoxViews = uvec4(inst.box, k1, k2, inst.level);
  vWeights = vec2(w1, inst.weight);
  vEye = modelEye;
  vCopy = inst.copy;
  return layerOfDepth(f, dot(f.depthRow, model * vec4(b.root.xyz, 1.0)));
}
#endif
