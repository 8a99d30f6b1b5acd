#version 460
#extension GL_GOOGLE_include_directive : require
// The single pass (layers.vert) with some layers at half resolution: each triangle routed to its
// leaf root's layer with gl_Layer and drawn into that layer's quarter when the layer's bit is set.
// A separate shader because the quarter needs clip distances, which layers.vert does not ask for.
#extension GL_ARB_shader_viewport_layer_array : require
#define CANOPY_VERTEX
#define CANOPY_HALF_RESOLUTION
#include "layers_common.glsl"

void main() {
  emitVertex();
  uint layer = triangleLayer();
  gl_Layer = int(layer);
  layerHalfResolution(layerTexelScale(f.halfResolution, layer) < 1.0);
}
