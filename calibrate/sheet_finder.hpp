#pragma once
// Finding a printed calibration sheet in a photograph or scan by its registration marks
// (print/marks.hpp): four black discs in the corners and a small one below the top-left disc.
// Any side up, any perspective short of grazing, and the film seen from its back (the map is
// then mirrored).
//
// Dark blobs are found against the local brightness (each pixel against the mean around it),
// kept when they are filled ellipses (the Mahalanobis radius of their boundary varies little: a
// square's varies by 35 %), and the four corner discs chosen as the set whose homography puts a
// blob of the small disc's size where the small disc must be. The homography maps the disc
// centres; each blob's centroid is corrected for perspective (a disc's image centroid is not
// the image of its centre) and the map solved again.
//
// Example: SheetLocation where = find_sheet(photo, print::sheet_marks(paper), "scan.jpg");

#include <span>
#include <string>
#include <utility>

#include <Eigen/Core>

#include "core/image.hpp"
#include "print/marks.hpp"

namespace rfd::calibrate {

struct SheetLocation {
    Eigen::Matrix3d page_to_photo;   ///< homography from page mm to the photo's pixels
    bool mirrored = false;           ///< the sheet is seen from its back
    double mm_per_pixel = 0.0;       ///< page mm per photo pixel at the sheet's centre (geometric mean)
    double orientation_error = 0.0;  ///< pixels between the small disc and where the corners put it
};

/// Locates the sheet. `photo` is linear (any channels: their mean is used); `name` names it in
/// messages. InputError when the marks are not all in view (saying how many round marks were
/// seen).
SheetLocation find_sheet(const Image& photo, const print::SheetMarks& marks, const std::string& name);

/// The homography taking four points exactly to four others.
Eigen::Matrix3d homography_from_points(const std::array<Eigen::Vector2d, 4>& from,
                                       const std::array<Eigen::Vector2d, 4>& to);

/// Channel `channel` of `plane` at pixel (u, v) (pixel centres at integers), bilinear; NaN
/// outside the outermost pixel centres.
double sample_bilinear(const Image& plane, double u, double v, int channel = 0);

/// The mean of one photo plane over a page rectangle [x0, x1] x [y0, y1] mm, sampled bilinearly
/// about once per photo pixel; NaN when the rectangle leaves the photo.
double mean_over_page_rect(const Image& plane, const Eigen::Matrix3d& page_to_photo, double x0, double y0, double x1,
                           double y1);

/// The luminance of a linear photo: the mean of its channels, one channel.
Image photo_luminance(const Image& photo);

/// The photo at a point of a plane (page mm, or any plane's mm) through `plane_to_photo`,
/// bilinear; NaN outside the photo.
double photo_at_page(const Image& luminance, const Eigen::Matrix3d& plane_to_photo, const Eigen::Vector2d& point);

/// Mean and variance of the photo over a disc about a plane point (radius in the plane's mm),
/// sampled every `step` mm; NaN mean when any sample leaves the photo.
std::pair<double, double> disc_statistics(const Image& luminance, const Eigen::Matrix3d& plane_to_photo,
                                          const Eigen::Vector2d& centre, double radius, double step);

/// Otsu's threshold of the finite values (the one best splitting them into two classes).
double otsu_threshold(std::span<const float> values);

}  // namespace rfd::calibrate
