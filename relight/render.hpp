#pragma once
// Relighting a reflectance field (thesis 4.2, eq. 4.2): I = sum_i k_i R_i, with
// k_i = integral over the sphere of L(omega) l_i(omega) d omega, the l_i the interpolation
// weights of relight/interpolation.hpp. Radiometry as everywhere in relight/: R_i is the
// image under a distant light delivering unit irradiance on a surface facing it, so a
// directional light of irradiance E from d gives k_i = E l_i(d).
//
// Light from below the horizon (z < 0) is outside what a field of the upper hemisphere
// measured and is dropped: a directional light below the horizon contributes nothing, disks
// and environment maps only through their part with z >= 0.
//
// Colour: every light has an irradiance or radiance per channel (R, G, B; a grey light has
// three equal values). The k_i are kept per channel; the image has the field's channels,
// or three when a grey (1-channel) field is lit by coloured light.
//
// Example: Image out = render(field, {DirectionalLight{direction_from_angles(0.5, 0.0)}});

#include <cstddef>
#include <filesystem>
#include <variant>
#include <vector>

#include <Eigen/Core>

#include "core/image.hpp"
#include "relight/field.hpp"
#include "relight/interpolation.hpp"
#include "relight/light_model.hpp"

namespace rfd::relight {

/// A distant point light. Frame: core/sphere.hpp.
struct DirectionalLight {
    Eigen::Vector3d direction = Eigen::Vector3d::UnitZ();       ///< unit, toward the light
    Eigen::Vector3d irradiance = Eigen::Vector3d::Ones();       ///< per channel, on a facing surface
};

/// A distant light of uniform radiance over a cap of angular radius `radius` around
/// `direction`, normalised: it delivers `irradiance` on a surface facing it, like the
/// directional light it tends to as the radius goes to 0. k_i = E / Omega_cap * integral
/// over the cap of l_i, by a deterministic equal-solid-angle spiral quadrature with points
/// spaced a quarter of the field's mean direction spacing (at least 16, at most 4096).
struct DiskLight {
    Eigen::Vector3d direction = Eigen::Vector3d::UnitZ();  ///< unit, centre of the cap
    double radius = 0.0;                                   ///< radians, in (0, pi/2]
    Eigen::Vector3d irradiance = Eigen::Vector3d::Ones();  ///< per channel
};

/// `count` directions covering the cap of angular radius `radius` around unit `centre`, one
/// per equal share of its solid angle (a golden-angle spiral): the quadrature of DiskLight.
std::vector<Eigen::Vector3d> cap_points(const Eigen::Vector3d& centre, double radius, std::size_t count);

/// A latitude-longitude environment map of radiance (per steradian, linear; 1 or 3
/// channels). Pixel (u, v) of a W x H map covers theta in [v, v + 1] * pi / H (row 0 at the
/// zenith, the horizon in the middle) and phi in [-pi + u * 2pi / W, -pi + (u + 1) * 2pi / W]
/// (column W / 2 faces +x, phi growing toward +y), solid angle (2pi / W)(cos theta_0 -
/// cos theta_1). Each pixel is integrated with sub-pixels spaced at most a quarter of the
/// field's mean direction spacing; only its part above the horizon counts.
struct EnvironmentMap {
    Image radiance;
};

/// Throws InputError unless `radiance` has 1 or 3 channels of finite, non-negative samples.
void check_environment_map(const Image& radiance);

using Light = std::variant<DirectionalLight, DiskLight, EnvironmentMap>;

/// Throws InputError for a light nothing can be lit with: a colour that is negative or not
/// finite, a zero or non-finite direction, a disk radius outside (0, 90] degrees, an
/// environment map check_environment_map() rejects.
void check_light(const Light& light);

/// k_i per direction and channel (n x 3), and what was computed.
struct LightCoefficients {
    Eigen::MatrixX3d k;                ///< row i: coefficient of image i for R, G, B
    std::size_t nonzero = 0;           ///< images with a non-zero coefficient
    std::size_t weight_evaluations = 0;  ///< directions at which the weights were computed
    bool grey = true;                  ///< all three channels equal for every image
};

/// Coefficients `k` with their counts filled in (nonzero, grey; no weight evaluations).
LightCoefficients coefficients_from(Eigen::MatrixX3d k);

/// Sum of the lights' k_i. Throws InputError for an environment map without 1 or 3
/// channels or with a negative sample, a disk radius outside (0, pi/2], non-finite values.
LightCoefficients light_coefficients(const SphericalInterpolator& interpolator, const std::vector<Light>& lights,
                                     Interpolation method = Interpolation::Delaunay);

/// The same for any model's weights (relight/light_model.hpp): a fitted basis or radial
/// basis functions relight a field as interpolation does, each light a weighted sum of the
/// images.
LightCoefficients light_coefficients(const LightWeights& weights, const std::vector<Light>& lights);

/// out = sum_i k_i R_i in one pass over the images, skipping zero k_i; parallel over pixel
/// blocks, each pixel summed in image order (deterministic). `field` must have as many
/// images as `coefficients` rows.
Image relight(const ReflectanceField& field, const LightCoefficients& coefficients);

/// The same for bare images (all of one shape), as implicit relighting combines them.
Image relight(const std::vector<Image>& images, const LightCoefficients& coefficients);

/// relight() of the field `reader` reads, once per entry of `coefficients`, writing image j
/// to `outs[j]` (its encoding by extension, as write_image()) a band of rows at a time. Only
/// the images some light needs are decoded, each once, and memory holds one band of them
/// (FieldReader::kBandBytes), whatever the field's size. The same samples as relight() of
/// the whole field. Nothing is at an output's path until every band is written.
/// `band_bytes` bounds a band (FieldReader::band_rows). Returns how many images were decoded.
std::size_t relight_to_files(FieldReader& reader, const std::vector<LightCoefficients>& coefficients,
                      const std::vector<std::filesystem::path>& outs,
                      std::size_t band_bytes = FieldReader::kBandBytes);

/// light_coefficients() of the field's own interpolator, then relight().
Image render(const ReflectanceField& field, const std::vector<Light>& lights,
             Interpolation method = Interpolation::Delaunay);

}  // namespace rfd::relight
