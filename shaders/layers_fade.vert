#version 460
// Cross-fade of a spread re-slice: one full-screen triangle per visible layer (render/layers.cpp).
void main() {
  const vec2 p = vec2((gl_VertexIndex << 1) & 2, gl_VertexIndex & 2);
  gl_Position = vec4(p * 2.0 - 1.0, 0.0, 1.0);
}
