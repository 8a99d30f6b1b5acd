#version 460
#extension GL_GOOGLE_include_directive : require
// Rigid parts in wind, drawn every frame (rigid_follow_draw.glsl).
#include "rigid_follow_draw.glsl"
