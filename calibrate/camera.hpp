#pragma once
// The camera that makes rfd's own test photographs of printed sheets: a pinhole camera looking
// at the page from a pose (distance, tilt, turn, roll), with the faults a phone or a scanner
// adds: lens blur, vignetting, uneven light, photon and read noise, 8-bit sRGB and JPEG
// compression. Page frame as print/layout.hpp (mm, x right, y down); the world has z = x cross
// y, into the page, so the camera sits at negative z and looks down +z.
//
// Projection: a page point P = (x, y, 0) goes to the camera frame as R (P - C) (rows of R: the
// image's right, down and forward directions) and to pixel (cx + f X/Z, cy + f Y/Z) with (cx,
// cy) the image centre; the page-to-pixel homography is K [r1 r2 -R C].
//
// Example: Camera camera; camera.pose.tilt_deg = 30;
//          Image photo = photograph(transmittance, 8.0, camera);

#include <cstdint>
#include <filesystem>
#include <optional>

#include <Eigen/Core>

#include "core/image.hpp"
#include "core/options.hpp"
#include "print/printer.hpp"

namespace rfd::calibrate {

/// The camera's settings as options of `rfd calibrate simulate-photo`.
inline constexpr NumberOption kCameraTiltOption{"--camera-tilt", "", "deg", 0, 80, 0,
                                                "Angle between the line of sight and the sheet's normal"};
inline constexpr NumberOption kCameraTurnOption{"--camera-turn", "", "deg", -360, 360, 0,
                                                "Azimuth the camera leans toward, from the sheet's +x"};
inline constexpr NumberOption kCameraRollOption{"--camera-roll", "", "deg", -360, 360, 0,
                                                "Rotation of the picture about the line of sight"};
inline constexpr NumberOption kCameraDistanceOption{"--camera-distance", "", "mm", 50, 5000, 450,
                                                    "From the camera to the sheet's centre"};
inline constexpr NumberOption kFrameFillOption{"--frame-fill", "", "", 0.02, 1, 0.9,
                                               "Part of the picture's height (or width) the sheet fills"};
inline constexpr NumberOption kBlurOption{"--blur", "", "pixels", 0, 20, 0, "Standard deviation of the lens blur"};
inline constexpr NumberOption kVignettingOption{"--vignetting", "", "", 0, 0.9, 0,
                                                "Part of the light lost in the picture's corners"};
inline constexpr NumberOption kPhotonsOption{"--photons", "", "", 0, 1e7, 0,
                                             "Photons of a pixel at full scale, for shot noise (0: none)"};
inline constexpr IntegerOption kJpegQualityOption{"--jpeg-quality", "", "", 1, 100, 80,
                                                  "Quality of a JPEG output"};

struct CameraPose {
    Eigen::Vector2d aim{105.0, 148.5};  ///< page point at the image centre, mm
    double distance = 450.0;            ///< from the camera to `aim`, mm
    double tilt_deg = 0.0;              ///< angle between the line of sight and the page's normal
    double turn_deg = 0.0;              ///< azimuth the camera leans toward, from the page's +x
    double roll_deg = 0.0;              ///< rotation of the image about the line of sight
    bool from_back = false;             ///< photographed through the film from its back (mirrored)
};

struct Camera {
    int width = 1600, height = 1200;  ///< pixels
    double focal = 1500.0;            ///< focal length, pixels
    CameraPose pose;
    double exposure = 0.8;        ///< pixel value of bare film in the image centre (linear)
    double background = 0.0;      ///< pixel value outside the sheet (0: dark table; a
                                  ///< light box: above exposure)
    double blur = 0.0;            ///< standard deviation of the lens blur, pixels
    double vignetting = 0.0;      ///< light lost in the image corners, fraction (falls off as r^2)
    double light_gradient = 0.0;  ///< light lost across the page from left to right, fraction
    double photons = 0.0;         ///< photons of a pixel at value 1 (shot noise); 0: none
    double read_noise = 0.0;      ///< standard deviation added to every pixel
    std::uint64_t seed = 1;       ///< of the noise
};

/// A camera of `long_side` x 3/4 `long_side` pixels that frames `paper` whole, upright, from
/// `distance` mm, the sheet filling `fill` of the frame's height (or width): the start of a
/// simulated photograph.
Camera framing_camera(const print::Paper& paper, double distance = kCameraDistanceOption.fallback,
                      double fill = kFrameFillOption.fallback, int long_side = 1600);

/// Where the camera's centre of projection is, in the page's frame (z < 0: in front).
Eigen::Vector3d camera_centre(const CameraPose& pose);

/// The 3 x 3 homography from page mm to the camera's pixels (pixel centres at integers).
Eigen::Matrix3d page_to_pixels(const Camera& camera);
/// `page` point through homography H.
Eigen::Vector2d apply(const Eigen::Matrix3d& homography, const Eigen::Vector2d& page);

/// Where a photograph was taken from, told by its page-to-pixel homography alone.
struct EstimatedPose {
    Eigen::Vector3d centre;  ///< the centre of projection, page frame (z < 0)
    double focal = 0.0;      ///< pixels
    double tilt_deg = 0.0;   ///< between the line of sight and the page's normal
};

/// The inverse of page_to_pixels for a camera of unknown focal length: square pixels, the
/// principal point at the middle of a `width` x `height` picture. The focal length follows
/// from the homography's first two columns imaging orthogonal vectors of equal length (Zhang,
/// "A flexible new technique for camera calibration", 2000, with one unknown), then the pose.
/// nullopt for a photograph within `min_tilt_deg` of frontal: there the focal length and the
/// distance trade against each other and the homography cannot tell them apart.
std::optional<EstimatedPose> estimate_pose(const Eigen::Matrix3d& page_to_pixels, int width, int height,
                                           double min_tilt_deg);

/// A photograph of a sheet whose transmittance (one channel, 1: bare film) is sampled at
/// `px_per_mm`, lit evenly from behind: linear pixel values, one channel, noise added, not yet
/// quantised. Pixels are averaged over 2 x 2 samples before the blur.
Image photograph(const Image& transmittance, double px_per_mm, const Camera& camera);

/// Writes a photograph as a camera would store it: 8-bit sRGB, as a JPEG of `jpeg_quality`
/// (1..100) for .jpg files, losslessly for .png. IoError when it cannot be written.
void write_photograph(const std::filesystem::path& path, const Image& photo,
                      int jpeg_quality = static_cast<int>(kJpegQualityOption.fallback));

}  // namespace rfd::calibrate
