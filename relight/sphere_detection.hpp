#pragma once
// Calibration spheres found in a capture by themselves: the chrome and black glossy balls an
// RTI dome or a hand-held kit puts beside the object, one highlight per photograph on each,
// the light's direction read off every sphere (relight/calibration.hpp) and compared.
//
// How, in four steps:
//  1. capture_brightness(): the per-pixel mean and maximum, over every photograph, of the
//     channel-mean brightness (linear), decoded in parallel a band of rows at a time. In the
//     mean a calibration sphere is a dark disc (black, or a mirror of a dark room) on a lit
//     table; in the maximum it holds one small bright spot per light.
//  2. find_sphere_candidates(): circles in the mean (OpenCV's HoughCircles on an 8-bit copy
//     at most kDetectionWidth pixels wide), kept when the maximum shows bright spots where
//     the mean is dark: a specular ball, not a diffuse one or a round shadow.
//  3. fit_sphere_outline(): each circle refined at full resolution. Along rays from its
//     centre the mean's steepest step is located to a fraction of a pixel, and the camera's
//     model of a sphere's outline (SphereView's tangent cone; a circle when orthographic)
//     is fitted to those edges by Gauss-Newton with Tukey weights, so the stand, the
//     sphere's shadow and reflections of the room cost nothing.
//  4. calibrate_capture(): every photograph's highlight on every sphere. A detected sphere
//     is kept when most photographs show a highlight on it and, with several, when its
//     directions agree with the others'. A light's direction is the one read off the sphere
//     whose outline is crispest (a chrome ball mirrors the table right up to its outline,
//     which is then found to about a pixel, against a fifth of one for a black ball); the
//     others check it, and their largest disagreement is reported.
//
// With two spheres or more the lights' positions follow as well (near_light()): each
// sphere's direction is a ray from its centre, and the point nearest every ray is the lamp.
//
// Example:
//     CaptureCalibration c = calibrate_capture(images, {.camera = pinhole_camera(4800, 1224, 816)});
//     for (const CalibratedImageLight& light : c.lights) use(light.direction);

#include <cstddef>
#include <filesystem>
#include <optional>
#include <vector>

#include <Eigen/Core>

#include "relight/calibration.hpp"
#include "relight/vision.hpp"

namespace rfd::relight {

/// Per-pixel statistics of a capture's brightness (channel mean, linear), row-major.
struct CaptureBrightness {
    PlaneSize size;
    std::vector<float> mean;
    std::vector<float> max;
};

/// Reads every photograph (all of one size: InputError naming the first that differs).
CaptureBrightness capture_brightness(const std::vector<std::filesystem::path>& images);

/// Circles are sought on a copy at most this wide (and as many pixels high); outlines are
/// then refined at full resolution.
inline constexpr int kDetectionWidth = 1200;

/// Circles in the mean that may be calibration spheres, most likely first.
std::vector<MirrorSphere> find_sphere_candidates(const CaptureBrightness& brightness);

/// A sphere's outline fitted to the mean's edges.
struct OutlineFit {
    MirrorSphere sphere;
    int rays = 0;          ///< rays cast from the centre that stayed inside the image
    int edges = 0;         ///< of them, edges that fit the outline (within 3 sigma, at least 1 px)
    double rms_px = 0.0;   ///< of those edges' distances to the outline
};

/// Refines `rough` (within about a tenth of its radius) to the outline; nullopt when fewer
/// than 16 rays find an edge.
std::optional<OutlineFit> fit_sphere_outline(const CaptureBrightness& brightness, const MirrorSphere& rough,
                                             const CalibrationCamera& camera);

struct SphereCalibrationOptions {
    CalibrationCamera camera;          ///< its principal point in the photographs' pixels
    std::vector<MirrorSphere> spheres; ///< the user's outlines, the first giving the directions: nothing detected
    /// The lamps are near (a dome, a hand-held lamp): each light's direction is the one from
    /// the object (object_point()) to its lamp placed by near_light(), where two spheres or
    /// more see it.
    bool near_lamps = false;
};

/// A sphere the calibration used.
struct CalibrationSphere {
    MirrorSphere outline;
    std::optional<OutlineFit> fit;  ///< how it was detected (none when the user gave it)
    int highlights = 0;             ///< photographs with a highlight found on it
    /// Set when its outline was aligned to the primary sphere's lights (distant lamps):
    /// the rms distance of its highlights from where those lights put them, pixels.
    std::optional<double> aligned_rms_px;
};

/// A lamp placed from two spheres or more.
struct NearLight {
    Eigen::Vector3d position = Eigen::Vector3d::Zero();  ///< field frame, sphere radii from the camera
    double distance = 0.0;      ///< from the spheres' mean centre, sphere radii
    double residual_rms = 0.0;  ///< the rays' distances to the position, sphere radii
    bool distant = false;       ///< the rays are parallel to within their scatter: a distant light
};

/// One photograph's light.
struct CalibratedImageLight {
    std::vector<Highlight> highlights;  ///< one per sphere, in the order of CaptureCalibration::spheres
    int spheres_used = 0;               ///< highlights found (0: no direction)
    /// Unit: the primary sphere's direction; where it shows no highlight, or with no
    /// primary, the mean of the spheres' that do.
    Eigen::Vector3d direction = Eigen::Vector3d::UnitZ();
    double disagreement_deg = 0.0;      ///< largest angle between two spheres' directions
    std::optional<NearLight> lamp;       ///< placed from two spheres or more
};

struct CaptureCalibration {
    std::vector<CalibrationSphere> spheres;
    std::vector<CalibratedImageLight> lights;  ///< one per photograph, in order
    int candidates = 0;                        ///< circles examined (0 when the user gave the spheres)
    /// The sphere whose directions the lights take: of detected ones, the one whose outline
    /// fits best (the smallest edge rms); of given ones, the first.
    int primary = -1;
};

/// Finds the spheres (unless given) and every photograph's highlights on them. InputError
/// when no sphere shows a highlight in most photographs; a photograph whose light no
/// sphere shows is reported with spheres_used = 0, for the caller to drop or refuse.
CaptureCalibration calibrate_capture(const std::vector<std::filesystem::path>& images,
                                     const SphereCalibrationOptions& options);

/// A calibrated light: the mirror-sphere image it came from and what was found there.
struct CalibratedLight {
    std::filesystem::path mirror_image;
    Highlight highlight;  ///< status is always found
};

/// Each mirror-sphere image's highlight on the one sphere given. Throws InputError naming
/// the image when the outline does not fit inside it or its highlight is missing, multiple
/// or overexposed; InputError for a non-positive or non-finite radius; IoError when
/// unreadable.
std::vector<CalibratedLight> calibrate_lights(const std::vector<std::filesystem::path>& mirror_images,
                                              const MirrorSphere& sphere, const CalibrationCamera& camera = {});

/// The object's centre as the spheres place it: where the camera's axis meets the plane of
/// the spheres' lowest points (the table they sit on), field frame, sphere radii.
Eigen::Vector3d object_point(const std::vector<SphereView>& spheres);

/// The point nearest the rays from each sphere's centre along its direction (unit, toward the
/// light); spheres whose highlight was not found are left out. nullopt with fewer than two.
std::optional<NearLight> near_light(const std::vector<SphereView>& spheres, const std::vector<Highlight>& highlights);

}  // namespace rfd::relight
