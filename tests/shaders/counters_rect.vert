#version 460
// tests/counters_test.cpp: triangles tiling a rectangle whose edges lie on pixel edges (two a cell
// of `cells` cells across it), so the pixels they cover are known exactly.
layout(push_constant) uniform Push {
  vec4 rect;    // x0, y0, x1, y1 in NDC
  uint cells;   // cells across the rectangle (two triangles each)
} pc;

const vec2 kCorner[6] = vec2[](vec2(0, 0), vec2(1, 0), vec2(1, 1), vec2(0, 0), vec2(1, 1), vec2(0, 1));

void main() {
  uint cell = uint(gl_VertexIndex) / 6u;
  vec2 c = kCorner[gl_VertexIndex % 6];
  float x = mix(pc.rect.x, pc.rect.z, (float(cell) + c.x) / float(pc.cells));
  float y = mix(pc.rect.y, pc.rect.w, c.y);
  gl_Position = vec4(x, y, 0.5, 1.0);
}
