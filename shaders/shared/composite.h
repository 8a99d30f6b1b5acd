// Inverse warp + alpha compositing (paper 3.2 and 3.6, docs/design.md "Conventions where the paper is silent", compositing): every output
// pixel p samples layer i at p - d_i(p), d_i bilinear between the warp-grid corners written by the
// dynamics pass, and composites the layers with the rigid background and the host's scene by
// depth. The grid lookup and the "over" step are shared inline functions, compiled into the
// fragment shader and into the C++ reference, so the two cannot drift.
#ifndef CANOPY_SHARED_COMPOSITE_H
#define CANOPY_SHARED_COMPOSITE_H
#include "interop.h"
#include "layers.h"

#define COMPOSITE_TILE 8u                // occupancy tile, pixels per side
#define COMPOSITE_OCCUPANCY_GROUP 64u    // occupancy kernel workgroup (one tile per invocation)
#define COMPOSITE_SCENE_GROUP 64u        // scene-depth copy workgroup (one pixel per invocation)
#define COMPOSITE_CLASSIFY_GROUP 64u     // classification workgroup (one screen tile per invocation)
#define COMPOSITE_DISP_GROUP 64u         // displacement-image workgroup (one warp-grid corner per invocation)
#define COMPOSITE_SUMS_GROUP 64u         // occupancy sums: a workgroup per slot, a row then a column per invocation
// Compute path, a tile-list entry: (position, layer mask). The mask has bit i for layer i (all 32
// layers fit); the position word holds the tile's x in bits 0-14, its y in bits 15-29 and this bit
// when the rigid background (trunks) reaches the tile.
#define COMPOSITE_TILE_BACKGROUND 0x80000000u
// Classification reads the warp grid's corners under at most this many occupancy tiles per axis of
// a screen tile's source rectangle (a plane mapping it wider than ~COMPOSITE_TILE * this pixels:
// a steep plane); a wider one counts as reached. Its occupancy is read from the summed-area table
// (composite_occupancy_sums.comp), four reads however wide the rectangle.
#define COMPOSITE_CLASSIFY_MAX_SPAN 16u

// CompositePush.flags
#define COMPOSITE_EARLY_EXIT 1u     // front to back, stop once the pixel is opaque
#define COMPOSITE_SKIP_EMPTY 2u     // skip a layer where the occupancy tile under p - d_i is empty
#define COMPOSITE_BILINEAR 4u       // bilinear colour + footprint-min depth (else nearest texel)
#define COMPOSITE_MOTION 8u         // write motion vectors (attachment 1)
#define COMPOSITE_MOTION_VALID 16u  // the previous displacement is last frame's (else motion 0)
#define COMPOSITE_BACKGROUND 32u    // a rigid background was drawn
#define COMPOSITE_SCENE_DEPTH 64u   // the host's depth was copied (else everything is in front)
#define COMPOSITE_REVERSE_Z 128u    // the host's depth is reverse-Z (1 = near); layers are standard
#define COMPOSITE_OCCUPANCY_UNION 256u  // occupancy: OR the next layer set's tiles into the current
                                        // occupancy (a spread re-slice, before its cross-fade)
#define COMPOSITE_REPROJECT 512u  // the current camera differs from the slice camera: read the
                                  // layers through CompositeView (else pixel p is layer pixel p)

// The tile kernel's specialization (composite_tiles.comp kVariant): one pipeline per combination of
// these, picked per frame from the flags (compositeTileVariant).
#define COMPOSITE_VARIANT_REPROJECT 1u
#define COMPOSITE_VARIANT_BILINEAR 2u
#define COMPOSITE_TILE_VARIANTS 4u

// CompositePush.debugView: what the demo's and a host's debug overlays show.
#define COMPOSITE_DEBUG_NONE 0u
#define COMPOSITE_DEBUG_LAYERS 1u        // every layer in its own false colour (paper Figure 3c)
#define COMPOSITE_DEBUG_VELOCITY 2u      // the tiled simulation field on the simulation plane
#define COMPOSITE_DEBUG_GRID 3u          // the nearest layer's warp grid, displaced

// A layer pixel with alpha below this is treated as empty (RGBA16F keeps far smaller values; this
// only avoids blending exact zeros).
#define COMPOSITE_MIN_ALPHA (1.0f / 4096.0f)
// Accumulated alpha at which front-to-back compositing stops: what is behind adds < 1/1024.
#define COMPOSITE_OPAQUE (1.0f - 1.0f / 1024.0f)
// A footprint texel's alpha this close to 0 or 1 counts as empty or opaque (compositeSharpenEdge).
#define COMPOSITE_EDGE_TOLERANCE (1.0f / 512.0f)

CANOPY_NAMESPACE_BEGIN

struct CompositePush {
  uint layerCount;     // 1..CANOPY_MAX_LAYERS
  uint gridX;          // warp-grid corners per row (gridCorners(width, cellSize))
  uint gridY;
  uint flags;          // COMPOSITE_*
  float cellSize;      // warp-grid cell, layer pixels
  float width;         // output size, pixels
  float height;
  float depthAlpha;    // a layer writes the depth output where its alpha >= this (0.5)
  uint tilesX;         // occupancy tiles per row: ceil(width / COMPOSITE_TILE)
  uint tilesY;
  uint debugView;      // COMPOSITE_DEBUG_*
  float debugScale;    // velocity view: speed shown at full brightness, domain units/s
  float exposure;      // the vegetation's linear colour is scaled by this (HDR hosts), >= 0
  uint dispWidth;      // compute path: texels per row / column of the displacement image (>= gridX, gridY)
  uint dispHeight;
  uint tilesPerGroup;  // compute path: listed tiles per workgroup of the tile kernel (>= 1; CompositorDesc)
  // Occupancy pass: the tiles [occupancyX0, occupancyX1) x [occupancyY0, occupancyY1) can hold
  // foliage (the layers' projected bounds); the others are empty without reading a texel.
  uint occupancyX0;
  uint occupancyY0;
  uint occupancyX1;
  uint occupancyY1;
  // The layer images (docs/design.md "Layers: guard band"): the output plus a guard band on each
  // side, so layer pixel = output pixel + origin for the slice camera itself; the warp grid and the
  // occupancy tiles are over the layer images.
  float layerWidth;
  float layerHeight;
  float originX;       // guard band width, pixels (a multiple of COMPOSITE_TILE)
  float originY;
  uint layerTilesX;    // occupancy tiles per row: ceil(layerWidth / COMPOSITE_TILE)
  uint layerTilesY;
  uint halfResolution; // LayerFrame.halfResolution: layer i read at texel s x layerTexelScale(halfResolution, i)
  float sharpness;     // the bilinear ramp's steepness between texel centres (compositeSharpPoint), 1..8
};
CANOPY_SIZE_CHECK(CompositePush, 112)

// Reprojection between re-slices (docs/design.md "Layers: reprojection"): the layers and the rigid
// background were drawn from the slice camera; the composite shows them from the current camera.
// Pixel p (current camera, centres at +0.5, y down) reads layer i at s = H_i p, H_i the homography of
// the slab's plane (render/reprojection.h); the inverse warp then reads q = s - d_i(s) (paper 3.2,
// d_i on the slice camera's warp grid). A texel's depth and its previous-frame position come from
// its slice-camera clip coordinates (s, z) through the two matrices.
#define COMPOSITE_VIEW_BACKGROUND CANOPY_MAX_LAYERS  // the background's homography follows the layers'
struct CompositeView {
  mat4 sliceToCurrent;   // slice camera clip -> current camera clip
  mat4 sliceToPrevious;  // slice camera clip -> the previous frame's camera clip (motion vectors)
  mat4 currentToSlice;   // current camera clip -> slice camera clip (the depth search's ray)
  // Row r of plane i's homography (current pixel -> layer pixel) is homography[3 i + r].xyz; the
  // background's plane is i = COMPOSITE_VIEW_BACKGROUND.
  vec4 homography[3u * (CANOPY_MAX_LAYERS + 1u)];
  // Layer i's depth search (compositeRaySearch; the background's at i = COMPOSITE_VIEW_BACKGROUND):
  // x, y the slice camera's NDC depths of the two ends of the range its texels lie in, z the most
  // samples along a pixel's ray (each pixel takes what its own ray needs; 0: the plane alone), w how far (layer pixels) a sample may land from the
  // plane's point (the classification widens its boxes by it where a ray end is behind a camera).
  vec4 search[CANOPY_MAX_LAYERS + 1u];
};
CANOPY_SIZE_CHECK(CompositeView, 192 + 64 * (CANOPY_MAX_LAYERS + 1))

// H p in homogeneous layer pixels: (x, y, w), the point in front of both cameras where w > 0.
CANOPY_INLINE vec3 compositeHomogeneous(vec4 r0, vec4 r1, vec4 r2, vec2 p) {
  vec3 ph = vec3(p.x, p.y, 1.0f);
  return vec3(dot(vec3(r0), ph), dot(vec3(r1), ph), dot(vec3(r2), ph));
}
// The point shown at layer pixel s (of `size`, the layer images) with slice-camera depth z, in
// camera `toClip`'s clip space.
CANOPY_INLINE vec4 compositeClipOf(mat4 toClip, vec2 s, float z, vec2 size) {
  return toClip * vec4(s.x / size.x * 2.0f - 1.0f, s.y / size.y * 2.0f - 1.0f, z, 1.0f);
}
CANOPY_INLINE float compositeClipDepth(vec4 c) { return c.z / c.w; }
CANOPY_INLINE vec2 compositeClipPixel(vec4 c, vec2 size) {
  return vec2((c.x / c.w + 1.0f) * 0.5f * size.x, (c.y / c.w + 1.0f) * 0.5f * size.y);
}

// The depth search (docs/design.md "Layers: reprojection", per-texel depth): the plane's homography
// puts a texel off its plane where the camera has moved sideways (parallax). Each layer texel holds
// the slice camera's depth of what it shows, so the layer is a height field seen from the slice
// camera; pixel p's ray of the current camera, carried into the slice camera's clip space, is the
// homogeneous line A + t B (t: the current camera's NDC depth). Samples along it between the
// layer's depths, front to back, find where the ray first passes behind the height field (relief
// mapping, Policarpo et al. 2005; the iterative inverse warp of Bowles et al. 2012 from the
// texel's own depth); the ray's point at that texel's depth is the layer pixel shown at p.
struct CompositeRay {
  vec4 a;        // slice clip of the ray's point at the current camera's NDC depth 0
  vec4 b;        // slice clip per unit of the current camera's NDC depth
  float t0;      // first sample (nearest the current camera)
  float dt;      // between samples
  uint steps;    // samples; 0: no search (the plane's point alone)
  uint pad0;
};
// The ray of current pixel p in the slice camera's clip space: (a, b) as in CompositeRay; b is the
// same for every pixel. Once per pixel, for all layers.
CANOPY_INLINE vec4 compositeRayOrigin(mat4 currentToSlice, vec2 p, vec2 outSize) {
  vec2 ndc = p / outSize * 2.0f - 1.0f;
  return currentToSlice * vec4(ndc.x, ndc.y, 0.0f, 1.0f);
}
// The ray parameter t at which its slice NDC depth is z (homogeneous: X = a + t b has depth
// X.z / X.w whatever its scale): (t, 1), or (0, 0) where no such point exists.
CANOPY_INLINE vec2 compositeRayT(vec4 a, vec4 b, float z) {
  float den = b.z - z * b.w;
  if (abs(den) < 1e-20f) return vec2(0.0f);
  return vec2((z * a.w - a.z) / den, 1.0f);
}
// The search's samples are this many layer pixels apart along a pixel's ray (a surface narrower
// than that along the ray's direction can be stepped over); a ray whose range lands within
// COMPOSITE_SHORT_PATH_PX of the plane's point takes the plane alone (docs/design.md "Layers:
// reprojection", the short path). render/reprojection.cpp picks each layer's most samples with the same two.
#define COMPOSITE_SEARCH_SPACING_PX 2.0f
#define COMPOSITE_SHORT_PATH_PX 0.25f
// Layer `search` (CompositeView.search) along the ray (a, b) of the pixel whose plane point is
// `plane` (layer pixels of `size`): search.z samples at most, fewer where this pixel's ray spans
// less — the range's two ends seen from this pixel, the parallax being smooth but not uniform over
// the image (a dolly's is zero at its centre): none where both ends land within
// COMPOSITE_SHORT_PATH_PX of the plane's point, one where they lie within one spacing, else one a
// spacing apart, the ends included.
CANOPY_INLINE CompositeRay compositeRaySearch(vec4 a, vec4 b, vec4 search, vec2 plane, vec2 size) {
  CompositeRay r;
  r.a = a;
  r.b = b;
  r.steps = uint(search.z);
  r.pad0 = 0u;
  vec2 tNear = compositeRayT(a, b, search.x), tFar = compositeRayT(a, b, search.y);
  if (tNear.y == 0.0f || tFar.y == 0.0f) r.steps = 0u;
  vec4 xn = a + tNear.x * b, xf = a + tFar.x * b;
  if (r.steps > 0u && xn.w > 0.0f && xf.w > 0.0f) {
    vec2 pn = vec2((xn.x / xn.w + 1.0f) * 0.5f * size.x, (xn.y / xn.w + 1.0f) * 0.5f * size.y);
    vec2 pf = vec2((xf.x / xf.w + 1.0f) * 0.5f * size.x, (xf.y / xf.w + 1.0f) * 0.5f * size.y);
    float stretch = length(pn - pf), reach = max(length(pn - plane), length(pf - plane));
    uint need = reach < COMPOSITE_SHORT_PATH_PX ? 0u
                : stretch <= COMPOSITE_SEARCH_SPACING_PX ? 1u
                                                        : uint(ceil(stretch / COMPOSITE_SEARCH_SPACING_PX)) + 1u;
    r.steps = min(r.steps, need);
  }
  // One sample: the range's middle (a thin range's secant step from about the plane's point).
  r.t0 = r.steps == 1u ? 0.5f * (tNear.x + tFar.x) : min(tNear.x, tFar.x);
  r.dt = r.steps > 1u ? (max(tNear.x, tFar.x) - r.t0) / float(r.steps - 1u) : 0.0f;
  return r;
}
// Sample k: the layer pixel (x, y) and the ray's slice NDC depth (z); w <= 0: behind a camera.
CANOPY_INLINE vec4 compositeRaySample(CompositeRay r, uint k, vec2 size) {
  vec4 x = r.a + (r.t0 + float(k) * r.dt) * r.b;
  return vec4((x.x / x.w + 1.0f) * 0.5f * size.x, (x.y / x.w + 1.0f) * 0.5f * size.y, x.z / x.w, x.w);
}
// Where the ray meets the depth z of the texel found at sample k: (x, y) that layer pixel, z = 1
// where it does so before sample k + 1 (the last sample: anywhere), in front of the cameras — the
// ray then meets that texel's surface before it could reach the next sample (a texel's surface
// is taken flat in depth over the ray's few pixels); else 0.
CANOPY_INLINE vec3 compositeRayCrossing(CompositeRay r, uint k, float z, vec2 size) {
  vec2 t = compositeRayT(r.a, r.b, z);
  vec4 x = r.a + t.x * r.b;
  bool before = k + 1u >= r.steps || t.x < r.t0 + float(k + 1u) * r.dt;
  if (t.y == 0.0f || x.w <= 0.0f || !before) return vec3(0.0f);
  return vec3((x.x / x.w + 1.0f) * 0.5f * size.x, (x.y / x.w + 1.0f) * 0.5f * size.y, 1.0f);
}

// The wind's inverse warp and reprojection resample the layers at fractional texel positions,
// where bilinear filtering turns an alpha-tested leaf edge (texels of alpha 0 and 1) into a faint
// ramp about a pixel wide that the layers drawn still have not, and a one-pixel grass blade into
// two half-alpha pixels that no longer read as foliage. Where the four footprint texels (alphas
// `a`) are each empty or opaque, the sample is cut at alpha 1/2 — the edge at the sub-texel
// position the bilinear ramp puts it — and shown opaque in the footprint's mean colour; footprints
// with partial alpha (blended materials, parts fading to impostors, a cross-fade) keep the bilinear
// sample (docs/design.md "Layers: reprojection", edges).
CANOPY_INLINE vec4 compositeSharpenEdge(vec4 c, vec4 a) {
  float partial = max(max(min(a.x, 1.0f - a.x), min(a.y, 1.0f - a.y)), max(min(a.z, 1.0f - a.z), min(a.w, 1.0f - a.w)));
  if (partial > COMPOSITE_EDGE_TOLERANCE) return c;
  return c.a >= 0.5f ? c / c.a : vec4(0.0f);
}

// The warp's reconstruction filter (docs/design.md "Layers: reprojection", sharp resampling): the
// inverse warp reads every layer at a fractional position that changes each frame, and the
// bilinear tent averages neighbouring texels there — a leaf's veins and its neighbours' shading fade
// by up to half as the position sweeps through a pixel (issue 67: 0.72 of a still frame's luminance
// gradient on the shrub). The fraction f between two layer-pixel centres is steepened about 1/2 to
// clamp((f - 1/2) k + 1/2, 0, 1): k = 1 is the bilinear tent, k -> infinity the nearest pixel; k
// between keeps a pixel whole for most of the sweep and blends only over 1/k of it, so sub-pixel
// motion still moves continuously (unlike the nearest pixel's whole-pixel jumps). In layer pixels,
// not texels: a pixel centre (a still frame) stays where it is, so a half-resolution layer keeps
// its bilinear upsampling. The same point feeds the colour, the edge cut's footprint and the depth.
CANOPY_INLINE vec2 compositeSharpPoint(vec2 q, float k) {
  vec2 t = q - vec2(0.5f);
  vec2 base = floor(t);
  vec2 f = clamp((t - base - vec2(0.5f)) * k + vec2(0.5f), vec2(0.0f), vec2(1.0f));
  return base + f + vec2(0.5f);
}

// Compute path: the tile list the classification appends to. The header doubles as the indirect
// dispatch of the warp + composite kernel (one workgroup per tilesPerGroup listed tiles) and the
// indirect draw of the resolve pass (one six-vertex quad per tile); the host resets it every frame.
struct CompositeTileHeader {
  uint groupsX;        // = ceil(listed tiles / tilesPerGroup)
  uint groupsY;        // 1
  uint groupsZ;        // 1
  uint pad0;
  uint vertexCount;    // 6
  uint instanceCount;  // = listed tiles
  uint firstVertex;    // 0
  uint firstInstance;  // 0
};
CANOPY_SIZE_CHECK(CompositeTileHeader, 32)

// The host's depth in Canopy's standard convention (0 = near), and back (design: one convention
// inside, the host's at the edges; the scene's own value is written back untouched).
CANOPY_INLINE float compositeStandardDepth(uint flags, float hostZ) {
  return (flags & COMPOSITE_REVERSE_Z) != 0u ? 1.0f - hostZ : hostZ;
}

// Bilinear position of layer pixel point p (pixel centres at +0.5, y down) in the warp grid: the
// four corner indices (row-major, gridX per row) and the weights. Corner (gx, gy) sits at layer
// pixel (min(gx cell, layerWidth), min(gy cell, layerHeight)), as the dynamics pass places it.
struct GridSample {
  uint i00;
  uint i10;
  uint i01;
  uint i11;
  vec2 t;
  vec2 cell;  // (gx, gy) of corner i00, so no caller divides i00 by gridX (CPU drivers run integer division lane by lane)
};

CANOPY_INLINE GridSample gridSample(CompositePush c, vec2 p) {
  GridSample s;
  float cx = clamp(floor(p.x / c.cellSize), 0.0f, float(c.gridX - 2u));
  float cy = clamp(floor(p.y / c.cellSize), 0.0f, float(c.gridY - 2u));
  float x0 = cx * c.cellSize, y0 = cy * c.cellSize;
  float x1 = min(x0 + c.cellSize, c.layerWidth), y1 = min(y0 + c.cellSize, c.layerHeight);
  s.t = vec2(clamp((p.x - x0) / max(x1 - x0, 1e-6f), 0.0f, 1.0f), clamp((p.y - y0) / max(y1 - y0, 1e-6f), 0.0f, 1.0f));
  uint gx = uint(cx), gy = uint(cy);
  s.cell = vec2(cx, cy);
  s.i00 = gy * c.gridX + gx;
  s.i10 = s.i00 + 1u;
  s.i01 = s.i00 + c.gridX;
  s.i11 = s.i01 + 1u;
  return s;
}

// Compute path: where pixel point p reads the displacement image (texel (gx, gy) = corner (gx, gy))
// with hardware bilinear filtering: the same corners and weights as gridSample, in normalized
// coordinates.
CANOPY_INLINE vec2 gridTexcoord(CompositePush c, GridSample s) {
  return vec2((s.cell.x + s.t.x + 0.5f) / float(c.dispWidth), (s.cell.y + s.t.y + 0.5f) / float(c.dispHeight));
}

// An occupancy entry (composite_occupancy.comp) holds a bit per cell of its tile, the tile split
// COMPOSITE_OCCUPANCY_SPLIT times a side: bit cy * SPLIT + cx for the cell (cx, cy) of
// COMPOSITE_OCCUPANCY_CELL layer pixels a side, each counting the texels one pixel around it;
// nonzero: the tile holds foliage. The classification asks the cells (a moving camera's boxes do
// not align with the tiles: a whole tile's flag would list a layer up to a tile away).
#define COMPOSITE_OCCUPANCY_SPLIT 4u
#define COMPOSITE_OCCUPANCY_CELL (COMPOSITE_TILE / COMPOSITE_OCCUPANCY_SPLIT)
#define COMPOSITE_OCCUPANCY_FULL ((1u << (COMPOSITE_OCCUPANCY_SPLIT * COMPOSITE_OCCUPANCY_SPLIT)) - 1u)
// The occupancy's summed-area table (composite_occupancy_sums.comp), over the cells: slot k's
// (SPLIT layerTilesX + 1) x (SPLIT layerTilesY + 1) entries start here; entries for `slots` slots of
// a tilesX x tilesY layer grid.
CANOPY_INLINE uint compositeSumsStride(CompositePush c) { return COMPOSITE_OCCUPANCY_SPLIT * c.layerTilesX + 1u; }
CANOPY_INLINE uint compositeSumsEntries(uint tilesX, uint tilesY, uint slots) {
  return (COMPOSITE_OCCUPANCY_SPLIT * tilesX + 1u) * (COMPOSITE_OCCUPANCY_SPLIT * tilesY + 1u) * slots;
}
CANOPY_INLINE uint compositeSumsBase(CompositePush c, uint slot) { return compositeSumsEntries(c.layerTilesX, c.layerTilesY, slot); }

// The tile kernel's variant for a frame's flags (COMPOSITE_VARIANT_*).
CANOPY_INLINE uint compositeTileVariant(uint flags) {
  return ((flags & COMPOSITE_REPROJECT) != 0u ? COMPOSITE_VARIANT_REPROJECT : 0u) |
         ((flags & COMPOSITE_BILINEAR) != 0u ? COMPOSITE_VARIANT_BILINEAR : 0u);
}

// Bits 0 .. count-1 set (count up to 32; a shift by 32 is undefined).
CANOPY_INLINE uint compositeLayerBits(uint count) { return count >= 32u ? 0xffffffffu : (1u << count) - 1u; }
CANOPY_INLINE uint compositeTilePosition(uint x, uint y) { return x | (y << 15u); }
CANOPY_INLINE uint compositeTileX(uint position) { return position & 0x7fffu; }
CANOPY_INLINE uint compositeTileY(uint position) { return (position >> 15u) & 0x7fffu; }

CANOPY_INLINE vec2 blendCorners(GridSample s, vec2 d00, vec2 d10, vec2 d01, vec2 d11) {
  return mix(mix(d00, d10, s.t.x), mix(d01, d11, s.t.x), s.t.y);
}

// Front-to-back "over" of premultiplied colour c under the accumulated colour acc (the same sum as
// far-to-near compositing, since "over" is associative).
CANOPY_INLINE vec4 underPremultiplied(vec4 acc, vec4 c) { return acc + (1.0f - acc.w) * c; }

// The compute path's composed pixel, composite_tiles.comp -> composite_resolve.frag: one RGBA32UI
// texel, so the tile kernel stores once and the resolve fetches once (three images cost ~7 ms more per
// frame on lavapipe: docs/performance.md). x, y: premultiplied colour as two half2 (an RGBA16F
// image's precision); z: the depth to write (float bits); w: motion as half2, or COMPOSITE_NO_MOTION
// where the vegetation is not frontmost (the resolve then leaves the host's motion alone).
#define COMPOSITE_NO_MOTION 0xffffffffu
#ifndef __cplusplus
uvec4 compositePackPixel(vec4 color, float depth, bool frontmost, vec2 motion) {
  return uvec4(packHalf2x16(color.rg), packHalf2x16(color.ba), floatBitsToUint(depth),
               frontmost ? packHalf2x16(motion) : COMPOSITE_NO_MOTION);
}
vec4 compositeUnpackColor(uvec4 p) { return vec4(unpackHalf2x16(p.x), unpackHalf2x16(p.y)); }
float compositeUnpackDepth(uvec4 p) { return uintBitsToFloat(p.z); }
vec4 compositeUnpackMotion(uvec4 p) { return p.w == COMPOSITE_NO_MOTION ? vec4(0.0) : vec4(unpackHalf2x16(p.w), 0.0, 1.0); }
#endif

// Debug colours: a hue in [0, 1) at full saturation and value.
CANOPY_INLINE vec3 debugHue(float h) {
  return clamp(abs(fract(vec3(h) + vec3(1.0f, 2.0f / 3.0f, 1.0f / 3.0f)) * 6.0f - vec3(3.0f)) - vec3(1.0f), vec3(0.0f), vec3(1.0f));
}
// Layer i's false colour: hues spread by the golden ratio, so neighbouring layers differ most.
CANOPY_INLINE vec3 debugLayerColor(uint layer) { return debugHue(fract(float(layer) * 0.618034f)); }

CANOPY_NAMESPACE_END
#endif
