#version 460
#extension GL_GOOGLE_include_directive : require
// Single-pass layered rasterization: the whole foliage drawn once, each triangle routed to the
// layer of its leaf root with gl_Layer from the vertex shader (shaderOutputLayer, Vulkan 1.2).
#extension GL_ARB_shader_viewport_layer_array : require
#define CANOPY_VERTEX
#include "layers_common.glsl"

void main() {
  emitVertex();
  gl_Layer = int(triangleLayer());
}
