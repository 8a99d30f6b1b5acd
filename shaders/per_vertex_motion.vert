#version 460
#extension GL_GOOGLE_include_directive : require
// per_vertex.vert with motion vectors (CanopyDesc.motionFormat set).
#define PER_VERTEX_MOTION
#include "per_vertex_draw.glsl"
