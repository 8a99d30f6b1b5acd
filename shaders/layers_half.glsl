// A layer drawn at half resolution (LayerFrame.halfResolution; docs/design.md "Layers: half
// resolution") goes into the top-left quarter of its image, so layer pixel s lands on texel s / 2:
// clip (x, y) -> ((x - w) / 2, (y - w) / 2), i.e. NDC n -> (n - 1) / 2, w and depth unchanged (the
// interpolation stays perspective-correct, the texture LOD follows the coarser pixels). Two clip
// distances keep what lay right of or below the image out of the rest of it (the clip volume's own
// planes keep the left and top edges). The including shader declares gl_ClipDistance with the two
// entries from LAYER_HALF_CLIP_FIRST.
void layerHalfResolution(bool halved) {
  vec4 p = gl_Position;
  gl_ClipDistance[LAYER_HALF_CLIP_FIRST] = halved ? p.w - p.x : 1.0;
  gl_ClipDistance[LAYER_HALF_CLIP_FIRST + 1] = halved ? p.w - p.y : 1.0;
  if (halved) gl_Position = vec4(0.5 * (p.xy - p.w), p.z, p.w);
}
