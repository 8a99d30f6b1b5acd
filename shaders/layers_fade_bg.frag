#version 460
#extension GL_GOOGLE_include_directive : require
#define CANOPY_FADE_BACKGROUND
#include "layers_fade.glsl"
