#version 460
#extension GL_GOOGLE_include_directive : require
// rigid_follow.vert with motion vectors (CanopyDesc.motionFormat set).
#define RIGID_MOTION
#include "rigid_follow_draw.glsl"
