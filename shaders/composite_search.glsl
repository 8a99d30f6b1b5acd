// The depth search of the composite's reprojection (docs/design.md "Layers: reprojection",
// per-texel depth), shared by composite_tiles.comp and composite.frag; the CPU reference
// (render/composite_reference.cpp) runs the same steps with the same shared/composite.h functions.
// The including shader declares `layerDepth` (sampler2DArray, nearest, border = 1),
// `backgroundDepth` (sampler2D), the push constant `pc` (CompositePush), `view` (CompositeView)
// and COMPOSITE_SEARCH_BILINEAR (a bool: the footprint's nearest depth, else the nearest texel's;
// the tile kernel's is a specialization constant, so only one of the two reads is compiled in).

// Layer i's slice depth at layer pixel q: the nearest of the bilinear footprint's four texels (the
// colour read there can show a leaf when any of them holds one), the nearest texel without
// bilinear; 1 = empty, also beyond the image. The same read as the composite's own depth at q.
float layerDepthAt(uint i, vec2 q) {
  vec3 uvw = vec3(q * layerTexelScale(pc.halfResolution, i) / vec2(pc.layerWidth, pc.layerHeight), float(i));
  if (!(COMPOSITE_SEARCH_BILINEAR)) return textureLod(layerDepth, uvw, 0.0).r;
  vec4 z4 = textureGather(layerDepth, uvw, 0);
  return min(min(z4.x, z4.y), min(z4.z, z4.w));
}
// The rigid background's depth at its nearest texel (it is read at the nearest texel); 1 beyond the image.
float backgroundDepthAt(vec2 q) {
  if (any(lessThan(q, vec2(0.0))) || any(greaterThanEqual(q, vec2(pc.layerWidth, pc.layerHeight)))) return 1.0;
  return texelFetch(backgroundDepth, ivec2(floor(q)), 0).r;
}
// `background` is a constant at every call: each call compiles one of the two reads (CPU drivers
// run both sides of a branch, masked).
float searchDepthAt(bool background, uint i, vec2 q) { return background ? backgroundDepthAt(q) : layerDepthAt(i, q); }

// Layer i (or the rigid background: `background`, d = 0) along the ray (rayA, rayB) of the current
// pixel (shared/composite.h compositeRaySearch), the displacement d read at the plane's point (it
// varies over warp cells, not pixels): the first sample whose texels hold a surface the ray meets
// before the next sample, and that meeting point. Returns false where nothing is found (this layer
// shows nothing at this pixel); s is the plane's point on entry, the layer pixel shown on return,
// z the slice depth shown there: the sample's, the surface taken flat in depth between the sample
// and the meeting point, as the meeting point's own solve takes it (the colour read at the meeting
// point tells whether it holds the surface). No search set for the layer (view.search.z = 0, the
// short path: the plane's homography alone): the depth at the plane's point. One depth read per
// sample, the composite's depth read included.
bool compositeDepthSearch(bool background, uint i, vec4 rayA, vec4 rayB, vec2 d, vec2 size, inout vec2 s, out float z) {
  CompositeRay ray = compositeRaySearch(rayA, rayB, view.search[background ? COMPOSITE_VIEW_BACKGROUND : i], s, size);
  bool plane = ray.steps == 0u, found = false;
  z = 1.0;
  for (uint k = 0u; k < max(ray.steps, 1u) && !found; ++k) {
    vec4 x = plane ? vec4(s, 0.0, 1.0) : compositeRaySample(ray, k, size);
    float zt = x.w > 0.0 ? searchDepthAt(background, i, x.xy - d) : 1.0;
    vec3 c = plane ? vec3(s, 1.0) : compositeRayCrossing(ray, k, zt, size);
    if (zt < 1.0 && c.z > 0.0) {
      s = c.xy;
      z = zt;
      found = true;
    }
  }
  return found;
}
