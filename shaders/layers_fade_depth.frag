#version 460
#extension GL_GOOGLE_include_directive : require
// Cross-fade of a spread re-slice, the depth of one visible layer at its first blend: the nearer of
// the old and the new set's depth (the pipeline's LESS test against the visible depth). The new
// set's leaves then pass the composite's depth tests while they fade in, where the old depth was
// empty (a leaf that moves to another layer under new settings); docs/design.md "Layers: spread
// re-slicing", the cross-fade.
#include "shared/layers.h"

layout(binding = 0) uniform sampler2DArray newDepth;
layout(push_constant, scalar) uniform Push { LayerFadePush pc; };

void main() { gl_FragDepth = texelFetch(newDepth, ivec3(ivec2(gl_FragCoord.xy), int(pc.layer)), 0).r; }
