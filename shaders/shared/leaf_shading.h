// Leaf shading (seed 004, Habel: section III; docs/design.md "Layers: leaf shading"), evaluated
// once per layer rebuild in the layer fragment shaders and by the CPU (tests) from this one
// definition. A leaf seen from the side the light falls on reflects: Lambert diffuse plus, on its
// front (adaxial) side, a Cook-Torrance specular lobe (Beckmann distribution of slope roughness
// sigma, unpolarised Fresnel of the effective refractive index n, Cook-Torrance masking); its back
// side is diffuse only. A leaf seen from the unlit side glows by diffuse transmission: the light
// that passes through, tinted by the transmission colour and scaled by the transmission factor
// (glTF KHR_materials_diffuse_transmission), which then dominates.
#ifndef CANOPY_SHARED_LEAF_SHADING_H
#define CANOPY_SHARED_LEAF_SHADING_H
#include "interop.h"

// The measured ranges of Bousquet et al. that Habel uses (section III.B); parameters outside them
// are refused by the API.
#define LEAF_IOR_MIN 1.2f
#define LEAF_IOR_MAX 1.7f
#define LEAF_ROUGHNESS_MIN 0.078f
#define LEAF_ROUGHNESS_MAX 0.5f

CANOPY_NAMESPACE_BEGIN

// Unpolarised Fresnel reflectance of a dielectric of relative index n at cos(angle) c (Cook and
// Torrance 1982, eq. for F with g^2 = n^2 + c^2 - 1).
CANOPY_INLINE float leafFresnel(float c, float n) {
  float g = sqrt(max(n * n + c * c - 1.0f, 0.0f));
  float a = (g - c) / (g + c);
  float b = (c * (g + c) - 1.0f) / (c * (g - c) + 1.0f);
  return 0.5f * a * a * (1.0f + b * b);
}

// Beckmann microfacet distribution of slope roughness m at cos(half-angle) nh.
CANOPY_INLINE float leafBeckmann(float nh, float m) {
  float c2 = nh * nh;
  float t2 = (1.0f - c2) / c2;
  return exp(-t2 / (m * m)) / (3.14159265f * m * m * c2 * c2);
}

// Cook-Torrance specular BRDF D F G / (4 (n.l)(n.v)) for unit n, v (towards the viewer) and l
// (towards the light), both on n's side; 0 where either is not.
CANOPY_INLINE float leafCookTorrance(vec3 n, vec3 v, vec3 l, float ior, float roughness) {
  float nl = dot(n, l);
  float nv = dot(n, v);
  if (nl <= 0.0f || nv <= 0.0f) return 0.0f;
  vec3 h = normalize(v + l);
  float nh = max(dot(n, h), 1e-4f);
  float vh = max(dot(v, h), 1e-4f);
  float g = min(1.0f, min(2.0f * nh * nv / vh, 2.0f * nh * nl / vh));
  return leafBeckmann(nh, roughness) * leafFresnel(vh, ior) * g / (4.0f * nl * nv);
}

// The transmission colour of a leaf whose material gives none: its base colour's hue at full value
// (a leaf's transmitted light is about as saturated as its reflection but, seen against the sun,
// far brighter; the base colour itself would make the glow as dark as the shade).
CANOPY_INLINE vec3 leafTransmissionTint(vec3 base) {
  return base / max(max(base.x, max(base.y, base.z)), 1e-3f);
}

// Outgoing radiance of a leaf fragment for a directional light of colour `light` (irradiance
// scale) towards `l` and an ambient term `ambient` (0..1 of the light's colour), seen along `v`.
// `n`: unit shading normal of the side facing the viewer; `front`: that side is the leaf's front
// (glTF front face), which alone has the specular lobe. `specular`: 0 turns the lobe off (bark).
// `transmission` 0..1 and `transmissionColor`: the diffuse transmission (0: opaque leaf), mixed as
// glTF's KHR_materials_diffuse_transmission mixes it: (1 - t) of the reflection, t of the
// transmission, whose colour is the material's (not multiplied by the base colour).
// Lambert is base * (n.l) (the convention of the layers before: base colour under a unit light),
// so the lobe enters as pi * f_s * (n.l) (the BRDF times pi, against Lambert's base / pi).
CANOPY_INLINE vec3 leafShade(vec3 base, vec3 n, bool front, vec3 v, vec3 l, vec3 light, float ambient,
                             float ior, float roughness, float specular, float transmission,
                             vec3 transmissionColor) {
  float nl = dot(n, l);
  vec3 lit = base * ambient;
  if (nl > 0.0f) {
    // The light's side: what is not transmitted is reflected.
    float lobe = front ? specular * 3.14159265f * leafCookTorrance(n, v, l, ior, roughness) : 0.0f;
    lit += (1.0f - ambient) * nl * (base * (1.0f - transmission) + vec3(lobe, lobe, lobe));
  } else {
    // The unlit side: light through the leaf from behind.
    lit += (1.0f - ambient) * (-nl) * transmission * transmissionColor;
  }
  return lit * light;
}

// Habel's translucency (seed 004, section III.C; docs/design.md "Layers: leaf shading"): the light
// seen on the unlit side enters through the light-facing side's relief — its normal-mapped normal,
// the viewer-facing `n` negated (the same relief seen from the other side), not the geometric one —
// less what that surface reflects (Fresnel, normalised to 1 at normal incidence), shadowed by its own
// relief at grazing light (a facet tilted by alpha from the leaf's plane is fully lit only above an
// elevation alpha: lit by elevation / alpha below it), attenuated through the leaf (Beer-Lambert,
// optical depth `tau` per channel along the refracted path) and leaves diffusely. `nGeom`: the
// viewer-facing geometric normal. Returns the irradiance factor that replaces the diffuse BTDF's -n.l.
CANOPY_INLINE vec3 leafTransmittedHabel(vec3 n, vec3 nGeom, vec3 l, float ior, vec3 tau) {
  float cosIn = -dot(n, l);
  float cosGeom = -dot(nGeom, l);
  if (cosIn <= 0.0f || cosGeom <= 0.0f) return vec3(0.0f, 0.0f, 0.0f);
  float tilt = acos(clamp(dot(n, nGeom), -1.0f, 1.0f));
  float elevation = asin(clamp(cosGeom, 0.0f, 1.0f));
  float shadow = tilt > 1e-4f ? clamp(elevation / tilt, 0.0f, 1.0f) : 1.0f;
  float enter = (1.0f - leafFresnel(cosIn, ior)) / (1.0f - leafFresnel(1.0f, ior));
  float sinT = sqrt(max(1.0f - cosIn * cosIn, 0.0f)) / ior;
  float cosT = max(sqrt(max(1.0f - sinT * sinT, 0.0f)), 1e-3f);
  vec3 through = vec3(exp(-tau.x / cosT), exp(-tau.y / cosT), exp(-tau.z / cosT));
  return through * (cosIn * shadow * enter);
}

// leafShade with Habel's translucency on the unlit side (the lit side is leafShade's).
CANOPY_INLINE vec3 leafShadeHabel(vec3 base, vec3 n, vec3 nGeom, bool front, vec3 v, vec3 l, vec3 light, float ambient,
                                  float ior, float roughness, float specular, float transmission, vec3 transmissionColor,
                                  vec3 tau) {
  if (dot(n, l) > 0.0f)
    return leafShade(base, n, front, v, l, light, ambient, ior, roughness, specular, transmission, transmissionColor);
  vec3 lit = base * ambient + transmissionColor * leafTransmittedHabel(n, nGeom, l, ior, tau) * ((1.0f - ambient) * transmission);
  return lit * light;
}

CANOPY_NAMESPACE_END
#endif
