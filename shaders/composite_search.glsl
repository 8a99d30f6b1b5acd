// The depth search of the composite's reprojection (docs/design.md "Layers: reprojection",
// per-texel depth), shared by composite_tiles.comp and composite.frag; the CPU reference
// (render/composite_reference.cpp) runs the same steps with the same shared/composite.h functions.
// The including shader declares `layerDepth` (sampler2DArray, nearest, border = 1),
// `backgroundDepth` (sampler2D), the push constant `pc` (CompositePush) and `view` (CompositeView).

// Layer i's slice depth at layer pixel q for the search: the nearest of the bilinear footprint's
// four texels (the colour read there can show a leaf when any of them holds one), the nearest
// texel without bilinear; 1 = empty, also beyond the image. i = COMPOSITE_VIEW_BACKGROUND: the
// rigid background's depth at its nearest texel (it is read at the nearest texel).
float layerDepthAt(uint i, vec2 q) {
  vec2 size = vec2(pc.layerWidth, pc.layerHeight);
  if (i == COMPOSITE_VIEW_BACKGROUND) {
    if (any(lessThan(q, vec2(0.0))) || any(greaterThanEqual(q, size))) return 1.0;
    return texelFetch(backgroundDepth, ivec2(floor(q)), 0).r;
  }
  vec3 uvw = vec3(q * layerTexelScale(pc.halfResolution, i) / size, float(i));
  if ((pc.flags & COMPOSITE_BILINEAR) == 0u) return textureLod(layerDepth, uvw, 0.0).r;
  vec4 z4 = textureGather(layerDepth, uvw, 0);
  return min(min(z4.x, z4.y), min(z4.z, z4.w));
}

// The texels layerDepthAt reads at q, named by their first (two positions with the same name read
// the same depth).
vec2 searchTexels(uint i, vec2 q) {
  if (i == COMPOSITE_VIEW_BACKGROUND) return floor(q);
  return floor(q * layerTexelScale(pc.halfResolution, i) - ((pc.flags & COMPOSITE_BILINEAR) != 0u ? 0.5 : 0.0));
}

// Layer i (or the background, i = COMPOSITE_VIEW_BACKGROUND, d = 0) along the ray (rayA, rayB) of
// the current pixel (shared/composite.h compositeRaySearch),
// the displacement d read at the plane's point (it varies over warp cells, not pixels): the first
// sample whose texels hold a surface the ray meets before the next sample, and that meeting point
// where its texels hold one too. Returns false where nothing is found (the layer shows nothing at
// this pixel); s is the plane's point on entry, the layer pixel shown on return. No search set for
// the layer (view.search[i].z = 0): s unchanged, true.
bool compositeDepthSearch(uint i, vec4 rayA, vec4 rayB, vec2 d, vec2 size, inout vec2 s) {
  CompositeRay ray = compositeRaySearch(rayA, rayB, view.search[i]);
  if (ray.steps == 0u) return true;
  for (uint k = 0u; k < ray.steps; ++k) {
    vec4 x = compositeRaySample(ray, k, size);
    if (x.w <= 0.0) continue;
    float zt = layerDepthAt(i, x.xy - d);
    if (zt >= 1.0) continue;
    vec3 c = compositeRayCrossing(ray, k, zt, size);
    // The crossing's texels hold a surface (the sample's own: known to).
    if (c.z > 0.0 && (all(equal(searchTexels(i, c.xy - d), searchTexels(i, x.xy - d))) || layerDepthAt(i, c.xy - d) < 1.0)) {
      s = c.xy;
      return true;
    }
  }
  return false;
}
