// Cross-fade step of a spread re-slice (shared/layers.h LayerFadePush; docs/design.md "Layers:
// spread re-slicing"). The colour written is the new layer's premultiplied colour already
// weighted; the pipeline lays it over the visible one (an image's first half of blends) or adds it
// to destination * (1 - weight) (the second half). Depth is not blended: layers_fade_depth.frag
// takes the nearer of the two sets' at a layer's first blend, and the last step copies the new set
// whole (render/layer_passes.cpp recordFadeCopy).
#include "shared/layers.h"

#ifdef CANOPY_FADE_BACKGROUND
layout(binding = 0) uniform sampler2D newColor;
#define FETCH(t) texelFetch(t, ivec2(gl_FragCoord.xy), 0)
#else
layout(binding = 0) uniform sampler2DArray newColor;
#define FETCH(t) texelFetch(t, ivec3(ivec2(gl_FragCoord.xy), int(pc.layer)), 0)
#endif
layout(push_constant, scalar) uniform Push { LayerFadePush pc; };
layout(location = 0) out vec4 outColor;

void main() { outColor = FETCH(newColor) * pc.weight; }
