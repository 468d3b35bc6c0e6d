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

#include <string>
#include <utility>
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

/// How the photographs were taken. A pinhole of known focal length sees each sphere from
/// its own direction (a sphere 7 degrees off the axis shifts its lights by as much, and its
/// outline is an ellipse 0.75 % longer radially); without one the camera is taken as distant
/// (orthographic), the model of RTIBuilder and CNR relight.
struct CalibrationCamera {
    double focal_length_px = 0.0;  ///< pixels; 0 (or less): orthographic
    Eigen::Vector2d principal_point = Eigen::Vector2d::Zero();  ///< pixels: the image centre

    bool orthographic() const { return !(focal_length_px > 0.0); }
    /// Unit direction from the camera through an image point (field frame): -z when
    /// orthographic.
    Eigen::Vector3d ray(const Eigen::Vector2d& point) const;
    /// The image point a direction from the camera passes through (perspective only).
    Eigen::Vector2d project(const Eigen::Vector3d& direction) const;
    /// The same camera for a crop of the image whose top-left corner is `origin`.
    CalibrationCamera cropped(const Eigen::Vector2d& origin) const;
};

/// A pinhole camera whose principal point is the centre of a `width` x `height` image.
CalibrationCamera pinhole_camera(double focal_length_px, int width, int height);

/// A sphere as `camera` sees it. Under a pinhole, `sphere` reads as the cone of rays
/// tangent to the sphere: its centre is the image of the ray through the sphere's centre,
/// its radius f tan(alpha) for the cone's half-angle alpha (the outline's radius when the
/// sphere sits on the axis); the sphere's own radius is the unit of length. Orthographic,
/// it is the outline circle (the maps of mirror_normal and reflect_view above).
class SphereView {
public:
    SphereView(const MirrorSphere& sphere, const CalibrationCamera& camera);

    const MirrorSphere& sphere() const { return sphere_; }
    const CalibrationCamera& camera() const { return camera_; }
    /// The ray through `point` meets the sphere (pixel-centre test).
    bool sees(const Eigen::Vector2d& point) const;
    /// Unit normal where the ray through `point` meets the sphere (on the silhouette for
    /// rays that miss it) and the unit view vector there (toward the camera).
    std::pair<Eigen::Vector3d, Eigen::Vector3d> normal_and_view(const Eigen::Vector2d& point) const;
    /// Direction toward the light a mirror at `point` shows the camera.
    Eigen::Vector3d reflected(const Eigen::Vector2d& point) const;
    /// The image point where the light from unit `direction` appears (the inverse of
    /// reflected(); under a pinhole solved by fixed-point iteration, Alhazen's problem).
    Eigen::Vector2d highlight_point(const Eigen::Vector3d& direction) const;
    /// The sphere's centre relative to the camera, field frame, in sphere radii (pinhole);
    /// orthographic: (x, -y, 0) of the outline's centre in radii.
    Eigen::Vector3d centre() const;

private:
    MirrorSphere sphere_;
    CalibrationCamera camera_;
    Eigen::Vector3d axis_ = -Eigen::Vector3d::UnitZ();  // unit, camera to the centre
    double sin_half_angle_ = 0.0, distance_ = 0.0;       // of the tangent cone; centre distance in radii
};

/// Sphere normal (unit, field frame) under an image point inside the outline; points on or
/// beyond the outline get the normal on the outline (n.z = 0). Orthographic camera.
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
    Multiple,     ///< a second blob nearly as bright as the first (several lights)
    Overexposed,  ///< the blob covers more than a quarter of the sphere
    Faint,        ///< far fainter than the sphere's other highlights: the lamp is hidden from it
    Inconsistent, ///< its direction is far from the primary sphere's: a reflection, not the lamp
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
    double second_blob = 0.0;  ///< the next brightest blob's contrast over the chosen one's (0: none)
    /// Multiple: each blob as bright, measured (status found), for another sphere's
    /// direction to choose from (relight/sphere_detection.hpp).
    std::vector<Highlight> alternatives;
    bool chosen_by_agreement = false;  ///< found: picked among several blobs by other spheres
    double off_primary_deg = 0.0;      ///< inconsistent: its angle to the primary sphere's direction
};

/// Finds the highlight in `image` (any channel count; the channel mean is used). Only pixels
/// whose centres lie inside both the outline and the image are searched. Of several blobs
/// the brightest is measured; it is Multiple only when another one comes within
/// kSecondHighlight of its contrast (two lights, not a reflection of the room). Never throws.
Highlight find_highlight(const Image& image, const MirrorSphere& sphere, const CalibrationCamera& camera = {});

/// A second blob this close to the brightest one's contrast makes a photograph ambiguous.
inline constexpr double kSecondHighlight = 0.8;

/// Why a photograph's highlight cannot be used, for messages ("" when it was found).
std::string highlight_problem(const Highlight& highlight);

}  // namespace rfd::relight
