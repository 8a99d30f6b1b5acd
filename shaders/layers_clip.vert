#version 460
#extension GL_GOOGLE_include_directive : require
// The fallback for devices without shaderOutputLayer (one draw per layer) and the background.
// Near/far planes as clip distances: on the leaf root (a whole leaf is kept or dropped, decided by
// the same layerOfDepth() as the single-pass path, so both give identical pixels), or on the
// vertex itself for the paper's simple segmentation, which cuts leaves crossing a boundary.
#define CANOPY_VERTEX
#define CANOPY_CLIP_DISTANCES
#include "layers_common.glsl"

void main() {
  emitVertex();
  float keepNear = 1.0, keepFar = 1.0;
  if (pc.passKind == LAYER_PASS_ONE_LAYER) {
    if (f.sliceMode == LAYER_SLICE_GEOMETRY) {
      float d = viewDepth(worldPosition());
      if (pc.targetLayer > 0u) keepNear = d - f.boundaries[pc.targetLayer];
      if (pc.targetLayer + 1u < f.layerCount) keepFar = f.boundaries[pc.targetLayer + 1u] - d;
    } else {
      keepNear = keepFar = triangleLayer() == pc.targetLayer ? 1.0 : -1.0;
    }
  }
  gl_ClipDistance[0] = keepNear;
  gl_ClipDistance[1] = keepFar;
  // One layer's pass draws into that layer's quarter when it is at half resolution; the background
  // (and the impostor bake) never are.
  layerHalfResolution(pc.passKind == LAYER_PASS_ONE_LAYER && layerTexelScale(f.halfResolution, pc.targetLayer) < 1.0);
}
