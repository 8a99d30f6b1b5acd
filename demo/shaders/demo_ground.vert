#version 460
#extension GL_EXT_scalar_block_layout : require
// canopy-demo --shadows: the ground, one quad (two triangles from gl_VertexIndex) under the
// vegetation, in the host's colour and depth before Canopy's passes (docs/design.md "Shadows").
layout(binding = 0, scalar) readonly buffer GroundBuf {
  mat4 light;       // world -> the light's Vulkan clip space (the shadow map's)
  vec4 origin;      // xyz: the quad's centre
  vec4 u;           // xyz: half its side along x
  vec4 v;           // xyz: half its side along z
  vec4 albedo;      // rgb: linear albedo; a: ambient share
  vec4 lightTexel;  // xyz: towards the light; w: one shadow-map texel in uv
} ground;
layout(push_constant, scalar) uniform Push { mat4 viewProj; } pc;
layout(location = 0) out vec3 vWorld;

void main() {
  const vec2 corners[6] = vec2[6](vec2(-1, -1), vec2(1, -1), vec2(1, 1), vec2(-1, -1), vec2(1, 1), vec2(-1, 1));
  vec2 c = corners[gl_VertexIndex % 6];
  vWorld = ground.origin.xyz + c.x * ground.u.xyz + c.y * ground.v.xyz;
  gl_Position = pc.viewProj * vec4(vWorld, 1.0);
}
