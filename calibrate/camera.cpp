#include "calibrate/camera.hpp"

#include <algorithm>
#include <cmath>
#include <random>

#include <Eigen/Geometry>

#include "core/error.hpp"
#include "core/image_io.hpp"
#include "core/parallel.hpp"
#include "core/units.hpp"
#include "relight/vision.hpp"

namespace rfd::calibrate {
namespace {

constexpr int kSupersampling = 2;  // samples per pixel along each axis

// Bilinear sample of a one-channel raster at page point (x, y) mm; `outside` beyond it.
float sample_page(const Image& page, double px_per_mm, double x, double y, float outside) {
    const double u = x * px_per_mm - 0.5, v = y * px_per_mm - 0.5;
    if (!(u >= -0.5 && v >= -0.5 && u <= page.width() - 0.5 && v <= page.height() - 0.5)) return outside;
    const int x0 = std::clamp(static_cast<int>(std::floor(u)), 0, page.width() - 1);
    const int y0 = std::clamp(static_cast<int>(std::floor(v)), 0, page.height() - 1);
    const int x1 = std::min(x0 + 1, page.width() - 1), y1 = std::min(y0 + 1, page.height() - 1);
    const double fx = std::clamp(u - x0, 0.0, 1.0), fy = std::clamp(v - y0, 0.0, 1.0);
    const double top = (1 - fx) * page.at(x0, y0, 0) + fx * page.at(x1, y0, 0);
    const double bottom = (1 - fx) * page.at(x0, y1, 0) + fx * page.at(x1, y1, 0);
    return static_cast<float>((1 - fy) * top + fy * bottom);
}

}  // namespace

Camera framing_camera(const print::Paper& paper, double distance, double fill, int long_side) {
    RFD_CHECK(long_side >= 4);
    Camera camera;
    const bool portrait = paper.height >= paper.width;
    const int short_side = long_side * 3 / 4;
    camera.width = portrait ? short_side : long_side;
    camera.height = portrait ? long_side : short_side;
    camera.pose.aim = {0.5 * paper.width, 0.5 * paper.height};
    camera.pose.distance = distance;
    camera.focal = fill * std::min(camera.height / paper.height, camera.width / paper.width) * distance;
    return camera;
}

namespace {

// From the aim point back to the camera: the page's normal toward the viewer (-z), leaned by
// the tilt toward the turn azimuth.
Eigen::Vector3d toward_camera(const CameraPose& pose) {
    const double tilt = degrees_to_radians(pose.tilt_deg), turn = degrees_to_radians(pose.turn_deg);
    return {std::sin(tilt) * std::cos(turn), std::sin(tilt) * std::sin(turn), -std::cos(tilt)};
}

}  // namespace

Eigen::Vector3d camera_centre(const CameraPose& pose) {
    return Eigen::Vector3d(pose.aim.x(), pose.aim.y(), 0.0) + pose.distance * toward_camera(pose);
}

Eigen::Matrix3d page_to_pixels(const Camera& camera) {
    const CameraPose& pose = camera.pose;
    const Eigen::Vector3d centre = camera_centre(pose);
    const Eigen::Vector3d forward = -toward_camera(pose);
    // The image's right: the page's x made perpendicular to the line of sight, then rolled.
    Eigen::Vector3d right = Eigen::Vector3d::UnitX() - Eigen::Vector3d::UnitX().dot(forward) * forward;
    if (right.norm() < 1e-9) right = Eigen::Vector3d::UnitY().cross(forward);
    right = Eigen::AngleAxisd(degrees_to_radians(pose.roll_deg), forward) * right.normalized();
    const Eigen::Vector3d down = forward.cross(right);
    Eigen::Matrix3d rotation;
    rotation.row(0) = right;
    rotation.row(1) = down;
    rotation.row(2) = forward;
    Eigen::Matrix3d intrinsics;
    intrinsics << camera.focal, 0, 0.5 * (camera.width - 1), 0, camera.focal, 0.5 * (camera.height - 1), 0, 0, 1;
    Eigen::Matrix3d extrinsics;
    extrinsics.col(0) = rotation.col(0);
    extrinsics.col(1) = rotation.col(1);
    extrinsics.col(2) = -rotation * centre;
    return intrinsics * extrinsics;
}

Eigen::Vector2d apply(const Eigen::Matrix3d& homography, const Eigen::Vector2d& page) {
    const Eigen::Vector3d p = homography * page.homogeneous();
    return p.hnormalized();
}

std::optional<EstimatedPose> estimate_pose(const Eigen::Matrix3d& page_to_pixels, int width, int height,
                                           double min_tilt_deg) {
    Eigen::Matrix3d to_centre;
    to_centre << 1, 0, -0.5 * (width - 1), 0, 1, -0.5 * (height - 1), 0, 0, 1;
    const Eigen::Matrix3d h = to_centre * page_to_pixels;
    // With K = diag(f, f, 1), K^-1 h's first two columns are orthogonal and of equal length:
    // a u + b = 0 twice for u = 1 / f^2, solved together by least squares.
    const double a1 = h(0, 0) * h(0, 1) + h(1, 0) * h(1, 1), b1 = h(2, 0) * h(2, 1);
    const double a2 = h(0, 0) * h(0, 0) + h(1, 0) * h(1, 0) - h(0, 1) * h(0, 1) - h(1, 1) * h(1, 1);
    const double b2 = h(2, 0) * h(2, 0) - h(2, 1) * h(2, 1);
    const double u = -(a1 * b1 + a2 * b2) / (a1 * a1 + a2 * a2);
    if (!(u > 0.0) || !std::isfinite(u)) return std::nullopt;
    EstimatedPose pose;
    pose.focal = 1.0 / std::sqrt(u);
    const Eigen::Matrix3d m = Eigen::Vector3d(1.0 / pose.focal, 1.0 / pose.focal, 1.0).asDiagonal() * h;
    // The scale, its sign putting the page in front of the camera where the picture's middle sees it.
    double lambda = 2.0 / (m.col(0).norm() + m.col(1).norm());
    const Eigen::Vector3d middle = (page_to_pixels.inverse() * Eigen::Vector3d(0.5 * (width - 1), 0.5 * (height - 1), 1.0));
    if ((m * (middle / middle.z())).z() < 0.0) lambda = -lambda;
    Eigen::Matrix3d rotation;  // columns: the page's x, y and normal in the camera's frame
    rotation.col(0) = (lambda * m.col(0)).normalized();
    rotation.col(1) = (lambda * m.col(1)).normalized();
    rotation.col(2) = rotation.col(0).cross(rotation.col(1));
    const Eigen::Vector3d centre = -rotation.transpose() * (lambda * m.col(2));
    pose.centre = Eigen::Vector3d(centre.x(), centre.y(), -std::abs(centre.z()));
    pose.tilt_deg = radians_to_degrees(std::acos(std::min(1.0, std::abs(rotation(2, 2)))));
    if (!(pose.tilt_deg >= min_tilt_deg)) return std::nullopt;
    return pose;
}

Image photograph(const Image& transmittance, double px_per_mm, const Camera& camera) {
    RFD_CHECK(transmittance.channels() == 1 && px_per_mm > 0.0);
    RFD_CHECK(camera.width > 0 && camera.height > 0 && camera.focal > 0.0);
    const Eigen::Matrix3d to_page = page_to_pixels(camera).inverse();
    const double page_width = transmittance.width() / px_per_mm;
    const double cx = 0.5 * (camera.width - 1), cy = 0.5 * (camera.height - 1);
    const double corner2 = cx * cx + cy * cy;
    Image photo(camera.width, camera.height, 1);
    // Rows are independent: each is traced alone, so the picture is the same on any number
    // of threads.
    parallel_for_chunks(static_cast<std::size_t>(camera.height), 16, [&](std::size_t begin, std::size_t end) {
        for (auto y = static_cast<int>(begin); y < static_cast<int>(end); ++y)
            for (int x = 0; x < camera.width; ++x) {
                double sum = 0.0;
                for (int sy = 0; sy < kSupersampling; ++sy)
                    for (int sx = 0; sx < kSupersampling; ++sx) {
                        // to_page applied by hand: Eigen's small products are slow unoptimised.
                        const double u = x + (sx + 0.5) / kSupersampling - 0.5;
                        const double v = y + (sy + 0.5) / kSupersampling - 0.5;
                        const double w = to_page(2, 0) * u + to_page(2, 1) * v + to_page(2, 2);
                        double page_x = (to_page(0, 0) * u + to_page(0, 1) * v + to_page(0, 2)) / w;
                        const double page_y = (to_page(1, 0) * u + to_page(1, 1) * v + to_page(1, 2)) / w;
                        if (camera.pose.from_back) page_x = page_width - page_x;
                        const float t = sample_page(transmittance, px_per_mm, page_x, page_y, -1.0f);
                        const double light = 1.0 - camera.light_gradient * std::clamp(page_x / page_width, 0.0, 1.0);
                        sum += t < 0.0f ? camera.background : camera.exposure * light * t;
                    }
                const double r2 = (x - cx) * (x - cx) + (y - cy) * (y - cy);
                photo.at(x, y, 0) = static_cast<float>(sum / (kSupersampling * kSupersampling) *
                                                       (1.0 - camera.vignetting * r2 / corner2));
            }
    });
    const relight::PlaneSize size{camera.width, camera.height};
    if (camera.blur > 0.0)
        relight::vision().gaussian_blur(size, photo.plane(0), photo.plane(0), 0, camera.blur, camera.blur,
                                        relight::Border::Replicate);
    if (camera.photons > 0.0 || camera.read_noise > 0.0) {
        std::mt19937_64 generator(camera.seed);
        std::normal_distribution<double> normal;
        for (float& value : photo.plane(0)) {
            const double variance = (camera.photons > 0.0 ? std::max(0.0f, value) / camera.photons : 0.0) +
                                    camera.read_noise * camera.read_noise;
            value = static_cast<float>(value + std::sqrt(variance) * normal(generator));
        }
    }
    return photo;
}

void write_photograph(const std::filesystem::path& path, const Image& photo, int jpeg_quality) {
    RFD_CHECK(jpeg_quality >= 1 && jpeg_quality <= 100);
    const std::string ext = lower_extension(path);
    write_image(path, photo, ext == ".jpg" || ext == ".jpeg" ? "jpeg:" + std::to_string(jpeg_quality) : "");
}

}  // namespace rfd::calibrate
