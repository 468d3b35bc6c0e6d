#pragma once
// Reflection models of the virtual light stage's opaque materials.
//
// Every function takes unit vectors in one frame: n the shading normal, v toward the viewer,
// l toward the light, with n.v > 0; it returns f_r (per steradian) for n.l > 0 and 0 below
// the surface. Reflected radiance under a directional light of unit irradiance is
// f_r(v, l) * (n.l): a white Lambertian surface facing the light reflects 1/pi.
//
// glossy: Ashikhmin and Shirley's (2000) coupled diffuse term plus a GGX microfacet lobe
//     f = 28 Rd / (23 pi) (1 - Rs) (1 - (1 - n.l/2)^5) (1 - (1 - n.v/2)^5)
//       + D(h) G2(v, l) F(v.h) / (4 (n.l)(n.v)),
//     D the GGX distribution of width alpha (Walter et al. 2007), G2 Smith's
//     height-correlated masking-shadowing (Heitz 2014), F Schlick's Fresnel with normal
//     reflectance Rs. The diffuse term gives up exactly the energy the Fresnel term takes,
//     and the microfacet lobe never adds energy (masking only removes it), so the
//     directional albedo stays below 1 for Rd, Rs <= 1 (tests/test_stage.cpp integrates it).
//
// phong: the thesis's synthetic snooker ball (7.5): a Lambertian term plus the normalised
//     modified Phong lobe weighted by the Fresnel reflectance of a dielectric of index ior,
//     f = albedo / pi + F(v.h) (e + 2) / (2 pi) max(0, r.v)^e,   r = l mirrored about n.
//     Both terms are reciprocal (r.v is symmetric in v and l, and so is v.h); at ior 1.5 the
//     lobe reflects 4 % facing the camera and everything at grazing angles, as a black
//     snooker ball does. A low exponent e spreads the lobe, a high one sharpens it toward a
//     mirror.
//
// Example: Rgb f = glossy_brdf(n, v, l, {0.5, 0.1, 0.1}, {0.04, 0.04, 0.04}, 0.2);

#include <Eigen/Core>

namespace rfd::relight {

using Rgb = Eigen::Array3d;

/// Lambertian: albedo / pi above the surface.
Rgb lambert_brdf(const Eigen::Vector3d& n, const Eigen::Vector3d& l, const Rgb& albedo);

/// The glossy model above; `alpha` is the GGX roughness (0 < alpha <= 1, the slope spread).
Rgb glossy_brdf(const Eigen::Vector3d& n, const Eigen::Vector3d& v, const Eigen::Vector3d& l,
                const Rgb& diffuse, const Rgb& specular, double alpha);

/// The Phong plus Fresnel model above: `exponent` e > 0, `ior` the dielectric's index (> 1).
Rgb phong_fresnel_brdf(const Eigen::Vector3d& n, const Eigen::Vector3d& v, const Eigen::Vector3d& l,
                       const Rgb& albedo, double exponent, double ior);

/// Fresnel reflectance of unpolarised light at a dielectric interface, from the medium of
/// index n1 into n2, for the cosine of the incidence angle (> 0). 1 under total internal
/// reflection.
double fresnel_dielectric(double cos_incidence, double n1, double n2);

}  // namespace rfd::relight
