// Canopy's wind for a host's shaders (docs/embedding.md "The wind and pushers"): include it (glslc -I of the
// installed include folder, or GL_GOOGLE_include_directive) in any stage, bind the image that
// canopyWind() names as a sampled image (any sampler: texels are fetched, not filtered), and pass
// the CanopyWindInfo it gives (a uniform block, a storage buffer or push constants: 64 bytes,
// std140 and std430 alike).
//
// canopyWindAt(wind, info, p) is the wind at world point p, a world vector in world units per second:
// the simulation's tiled V_wind (paper 3.3) at p's orthogonal projection onto the simulation plane,
// bilinear between cells and periodic over the plane's tile, as the plants read it. It has no
// component along the plane's normal and is the same on every plane parallel to it
// (docs/design.md "The wind a host reads"). The image is what the last recordCanopy that stepped
// the simulation wrote; read it after that recordCanopy in the same queue.
#ifndef CANOPY_WIND_GLSL
#define CANOPY_WIND_GLSL

struct CanopyWindInfo {
  vec4 origin;  // xyz: world point at plane coordinate (0, 0); w: the tile's size, world units
  vec4 right;   // xyz: the plane's unit x axis; w: the image's size n, texels a side
  vec4 up;      // xyz: its unit y axis
  vec4 normal;  // xyz: right x up (no wind along it)
};

// The wind image's texel (i, j) wrapped into the tile (row 0 at the plane's bottom).
vec2 canopyWindTexel(sampler2D wind, int n, int i, int j) {
  return texelFetch(wind, ivec2(((i % n) + n) % n, ((j % n) + n) % n), 0).xy;
}

// Plane coordinates (tile units) of world point p.
vec2 canopyWindPlane(CanopyWindInfo info, vec3 p) {
  vec3 rel = p - info.origin.xyz;
  return vec2(dot(rel, info.right.xyz), dot(rel, info.up.xyz)) / info.origin.w;
}

// The wind at world point p: world units per second.
vec3 canopyWindAt(sampler2D wind, CanopyWindInfo info, vec3 p) {
  int n = int(info.right.w);
  vec2 x = fract(canopyWindPlane(info, p)) * float(n) - 0.5;
  vec2 fl = floor(x);
  vec2 t = x - fl;
  int i = int(fl.x), j = int(fl.y);
  vec2 v = mix(mix(canopyWindTexel(wind, n, i, j), canopyWindTexel(wind, n, i + 1, j), t.x),
               mix(canopyWindTexel(wind, n, i, j + 1), canopyWindTexel(wind, n, i + 1, j + 1), t.x), t.y);
  v *= info.origin.w;  // domain units/s -> world units/s
  return v.x * info.right.xyz + v.y * info.up.xyz;
}

#endif
