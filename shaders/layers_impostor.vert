#version 460
#extension GL_GOOGLE_include_directive : require
// Impostors, single pass: gl_Layer = the layer of the box's root depth (as leaves go by their root).
#extension GL_ARB_shader_viewport_layer_array : require
#define CANOPY_VERTEX
#include "layers_impostor_common.glsl"

void main() { gl_Layer = int(impostorVertex()); }
