#pragma once
// Light-direction calibration from the highlight on a mirror sphere (thesis 4.1: the light
// stage's directions are measured with a mirror ball photographed under each light).
//
// Frames and units. Image pixel coordinates are continuous: pixel (i, j) covers
// [i, i+1) x [j, j+1), x to the right, y down the rows, so pixel centres sit at half-integers.
// Directions are in the field frame of core/sphere.hpp (x right, y up in the image, z toward
// the camera). The camera is distant (orthographic) and looks along -z, so the view vector
// (surface toward camera) is v = +z everywhere.
//
// Maths. A point p inside the sphere's outline (centre c, radius R, pixels) sees the normal
//     n = ((p.x - c.x) / R, -(p.y - c.y) / R, sqrt(1 - n.x^2 - n.y^2)),
// and a mirror there reflects the light arriving from
//     l = 2 (n . v) n - v = (2 n.z n.x, 2 n.z n.y, 2 n.z^2 - 1),
// i.e. theta_l = 2 theta_n, phi_l = phi_n. This map is equal-area: a pixel of area dA covers
// the solid angle dOmega_l = 4 dA / R^2 of light directions wherever it lies (it is Lambert's
// azimuthal projection). So the brightness-weighted mean of the pixels' reflected directions
// is the centroid of the light on the sphere of directions, free of the image-space
// distortion that makes a plain centroid-then-reflect estimate drift near the rim.
//
// The highlight is the connected blob (8-neighbours) of sphere pixels brighter than half way
// from the sphere's median (its background) to its peak; each pixel weighs its brightness
// above that threshold, so the estimate varies continuously with the image.
// Accuracy degrades toward the rim: at light polar angle theta the image moves
// R/2 cos(theta/2) pixels per radian, so a fixed pixel error costs 1/cos(theta/2) more angle
// (about 11x at theta = 170 degrees); lights behind the sphere (theta near 180) are lost.
//
// Example:
//     MirrorSphere sphere{320.5, 240.5, 200.0};
//     Highlight h = find_highlight(read_image("ball_000.png"), sphere);
//     if (h.status == HighlightStatus::Found) use(h.direction);

#include <filesystem>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/image.hpp"

namespace rfd::relight {

/// The outline of a mirror sphere in its image, in continuous pixel coordinates.
struct MirrorSphere {
    double centre_x = 0.0;  ///< pixels from the left edge
    double centre_y = 0.0;  ///< pixels from the top edge
    double radius = 0.0;    ///< pixels, > 0
};

/// Sphere normal (unit, field frame) under an image point inside the outline; points on or
/// beyond the outline get the normal on the outline (n.z = 0).
Eigen::Vector3d mirror_normal(const MirrorSphere& sphere, const Eigen::Vector2d& point);

/// Direction toward the light whose reflection a mirror with this normal shows to the camera:
/// the view vector +z reflected about `normal`.
Eigen::Vector3d reflect_view(const Eigen::Vector3d& normal);

/// The image point where the light from unit `direction` appears (inverse of the two maps
/// above). `direction` must not be -z, whose reflection is the whole outline.
Eigen::Vector2d highlight_point(const MirrorSphere& sphere, const Eigen::Vector3d& direction);

/// What the search for a highlight found: outcomes of the photograph, not errors.
enum class HighlightStatus {
    Found,        ///< one blob; the fields below describe it
    None,         ///< the sphere shows no contrast (black, uniform, or saturated everywhere)
    Multiple,     ///< more than one blob above the threshold (several lights, reflections)
    Overexposed,  ///< the blob covers more than a quarter of the sphere
};

struct Highlight {
    HighlightStatus status = HighlightStatus::None;
    Eigen::Vector3d direction = Eigen::Vector3d::UnitZ();  ///< unit, toward the light, field frame
    Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();     ///< unit sphere normal halfway to it
    Eigen::Vector2d centroid = Eigen::Vector2d::Zero();    ///< weighted image centroid, pixels
    int pixels = 0;          ///< pixels in the chosen blob
    int blobs = 0;           ///< blobs above the threshold
    double coverage = 0.0;   ///< fraction of the sphere's pixels above the threshold
    float peak = 0.0f;       ///< brightest sphere pixel (channel mean)
    float background = 0.0f; ///< median sphere pixel (channel mean)
    bool touches_rim = false;  ///< the blob reaches the outermost pixel ring: may be cut off
};

/// Finds the highlight in `image` (any channel count; the channel mean is used). Only pixels
/// whose centres lie inside both the outline and the image are searched. Never throws.
Highlight find_highlight(const Image& image, const MirrorSphere& sphere);

/// A calibrated light: the mirror-sphere image it came from and what was found there.
struct CalibratedLight {
    std::filesystem::path mirror_image;
    Highlight highlight;  ///< status is always found
};

/// Reads each mirror-sphere image and finds its highlight. Throws InputError naming the image
/// when the outline does not fit inside it or its highlight is missing, multiple or
/// overexposed; InputError for a non-positive or non-finite radius; IoError when unreadable.
std::vector<CalibratedLight> calibrate_lights(const std::vector<std::filesystem::path>& mirror_images,
                                              const MirrorSphere& sphere);

}  // namespace rfd::relight
