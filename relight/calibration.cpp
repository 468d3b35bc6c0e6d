#include "relight/calibration.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>


#include "core/error.hpp"
#include "core/image_io.hpp"
#include "relight/vision.hpp"
#include "core/text.hpp"

namespace rfd::relight {
namespace {

// A highlight is a small spot; a blob over a quarter of the sphere is the sphere lit (or
// clipped) all over, where a centroid means nothing.
constexpr double kMaxCoverage = 0.25;

}  // namespace

Eigen::Vector3d mirror_normal(const MirrorSphere& sphere, const Eigen::Vector2d& point) {
    const double nx = (point.x() - sphere.centre_x) / sphere.radius;
    const double ny = -(point.y() - sphere.centre_y) / sphere.radius;
    const double r2 = nx * nx + ny * ny;
    if (r2 >= 1.0) {
        const double r = std::sqrt(r2);
        return {nx / r, ny / r, 0.0};
    }
    return {nx, ny, std::sqrt(1.0 - r2)};
}

Eigen::Vector3d reflect_view(const Eigen::Vector3d& normal) {
    const Eigen::Vector3d view = Eigen::Vector3d::UnitZ();
    return 2.0 * normal.dot(view) * normal - view;
}

Eigen::Vector2d highlight_point(const MirrorSphere& sphere, const Eigen::Vector3d& direction) {
    const Eigen::Vector3d half = direction + Eigen::Vector3d::UnitZ();
    RFD_CHECK_MSG(half.norm() > 1e-12, "the light straight behind the sphere has no single image point");
    const Eigen::Vector3d n = half.normalized();
    return {sphere.centre_x + sphere.radius * n.x(), sphere.centre_y - sphere.radius * n.y()};
}

Eigen::Vector3d CalibrationCamera::ray(const Eigen::Vector2d& point) const {
    if (orthographic()) return -Eigen::Vector3d::UnitZ();
    return Eigen::Vector3d((point.x() - principal_point.x()) / focal_length_px,
                           -(point.y() - principal_point.y()) / focal_length_px, -1.0)
        .normalized();
}

Eigen::Vector2d CalibrationCamera::project(const Eigen::Vector3d& direction) const {
    RFD_CHECK_MSG(!orthographic() && direction.z() < 0.0, "only a pinhole projects directions in front of it");
    return {principal_point.x() + focal_length_px * direction.x() / -direction.z(),
            principal_point.y() - focal_length_px * direction.y() / -direction.z()};
}

CalibrationCamera CalibrationCamera::cropped(const Eigen::Vector2d& origin) const {
    return {focal_length_px, principal_point - origin};
}

CalibrationCamera pinhole_camera(double focal_length_px, int width, int height) {
    return {focal_length_px, Eigen::Vector2d(0.5 * width, 0.5 * height)};
}

SphereView::SphereView(const MirrorSphere& sphere, const CalibrationCamera& camera) : sphere_(sphere), camera_(camera) {
    if (camera_.orthographic()) return;
    axis_ = camera_.ray({sphere.centre_x, sphere.centre_y});
    const double half_angle = std::atan(sphere.radius / camera_.focal_length_px);
    sin_half_angle_ = std::sin(half_angle);
    distance_ = 1.0 / sin_half_angle_;
}

bool SphereView::sees(const Eigen::Vector2d& point) const {
    if (camera_.orthographic()) {
        const double dx = point.x() - sphere_.centre_x, dy = point.y() - sphere_.centre_y;
        return dx * dx + dy * dy < sphere_.radius * sphere_.radius;
    }
    return camera_.ray(point).cross(axis_).norm() < sin_half_angle_ && camera_.ray(point).dot(axis_) > 0.0;
}

std::pair<Eigen::Vector3d, Eigen::Vector3d> SphereView::normal_and_view(const Eigen::Vector2d& point) const {
    if (camera_.orthographic()) return {mirror_normal(sphere_, point), Eigen::Vector3d::UnitZ()};
    // The ray t e from the camera meets the unit sphere about C = distance * axis where
    // t^2 - 2 t (e.C) + |C|^2 - 1 = 0; a ray that misses takes the silhouette's point.
    const Eigen::Vector3d e = camera_.ray(point);
    const Eigen::Vector3d c = distance_ * axis_;
    const double along = e.dot(c);
    const double across2 = std::max(0.0, c.squaredNorm() - along * along);
    Eigen::Vector3d normal;
    if (across2 < 1.0) {
        normal = (along - std::sqrt(1.0 - across2)) * e - c;
    } else {
        // The silhouette point nearest the ray: on the tangent cone, in the plane of e and C.
        const Eigen::Vector3d side = (e - e.dot(axis_) * axis_).normalized();
        const double cos_half = std::sqrt(1.0 - sin_half_angle_ * sin_half_angle_);
        const Eigen::Vector3d tangent = cos_half * axis_ + sin_half_angle_ * side;
        normal = (distance_ * cos_half) * tangent - c;
    }
    return {normal.normalized(), -e};
}

Eigen::Vector3d SphereView::reflected(const Eigen::Vector2d& point) const {
    const auto [normal, view] = normal_and_view(point);
    return 2.0 * normal.dot(view) * normal - view;
}

Eigen::Vector2d SphereView::highlight_point(const Eigen::Vector3d& direction) const {
    if (camera_.orthographic()) return rfd::relight::highlight_point(sphere_, direction);
    // The normal halves the light and the view, and the view depends on where on the sphere
    // the normal points: iterate from the view of the centre. Each step shrinks the error by
    // about 1/distance (the sphere's angular size), so a few steps reach double precision.
    const Eigen::Vector3d c = distance_ * axis_;
    Eigen::Vector3d view = -axis_;
    for (int step = 0; step < 60; ++step) {
        const Eigen::Vector3d half = direction + view;
        RFD_CHECK_MSG(half.norm() > 1e-12, "the light straight behind the sphere has no single image point");
        const Eigen::Vector3d next = -(c + half.normalized()).normalized();
        const bool converged = (next - view).norm() < 1e-15;
        view = next;
        if (converged) break;
    }
    return camera_.project(-view);
}

Eigen::Vector3d SphereView::centre() const {
    if (camera_.orthographic()) return {sphere_.centre_x / sphere_.radius, -sphere_.centre_y / sphere_.radius, 0.0};
    return distance_ * axis_;
}

Highlight find_highlight(const Image& image, const MirrorSphere& sphere, const CalibrationCamera& camera) {
    Highlight result;
    if (image.empty() || !(sphere.radius > 0.0) || !std::isfinite(sphere.radius) ||
        !std::isfinite(sphere.centre_x) || !std::isfinite(sphere.centre_y))
        return result;
    const SphereView view(sphere, camera);
    // Clamped in floating point first: a far-off outline must not overflow the int casts.
    // The box has a pixel of margin: a pinhole's outline is an ellipse a little longer than
    // the circle.
    const auto clamp_to = [](double v, int size) { return static_cast<int>(std::clamp(v, 0.0, static_cast<double>(size))); };
    const int x0 = clamp_to(std::floor(sphere.centre_x - sphere.radius) - 1.0, image.width());
    const int x1 = clamp_to(std::ceil(sphere.centre_x + sphere.radius) + 2.0, image.width());
    const int y0 = clamp_to(std::floor(sphere.centre_y - sphere.radius) - 1.0, image.height());
    const int y1 = clamp_to(std::ceil(sphere.centre_y + sphere.radius) + 2.0, image.height());
    if (x0 >= x1 || y0 >= y1) return result;

    // Channel-mean brightness of the pixels whose centres see the sphere.
    const int w = x1 - x0, h_rows = y1 - y0;
    const PlaneSize size{w, h_rows};
    const auto at = [w](int x, int y) { return static_cast<std::size_t>(y) * static_cast<std::size_t>(w) + static_cast<std::size_t>(x); };
    std::vector<std::uint8_t> inside(size.area(), 0);
    std::vector<float> brightness(size.area(), 0.0f);
    std::vector<float> values;
    for (int y = y0; y < y1; ++y)
        for (int x = x0; x < x1; ++x) {
            if (!view.sees({x + 0.5, y + 0.5})) continue;
            float sum = 0.0f;
            for (int c = 0; c < image.channels(); ++c) sum += image.at(x, y, c);
            const float v = sum / static_cast<float>(image.channels());
            inside[at(x - x0, y - y0)] = 255;
            brightness[at(x - x0, y - y0)] = v;
            values.push_back(v);
        }
    if (values.empty()) return result;
    result.peak = *std::max_element(values.begin(), values.end());
    auto middle = values.begin() + static_cast<std::ptrdiff_t>(values.size() / 2);
    std::nth_element(values.begin(), middle, values.end());
    result.background = *middle;
    // Relative contrast below float resolution: nothing stands out (black, flat or clipped).
    if (!(result.peak - result.background > 1e-6f * std::max(std::abs(result.peak), 1e-30f))) return result;

    // Blobs: pixels above half the contrast, with one-pixel gaps bridged (a small light near
    // the rim images to an arc thinner than a pixel, whose pixels dip below the threshold).
    const float threshold = result.background + 0.5f * (result.peak - result.background);
    std::vector<std::uint8_t> above(size.area());
    for (std::size_t p = 0; p < above.size(); ++p) above[p] = brightness[p] > threshold ? inside[p] : 0;
    std::vector<std::uint8_t> bridged = above;
    vision().dilate(size, bridged, 3);
    for (std::size_t p = 0; p < bridged.size(); ++p) bridged[p] &= inside[p];
    std::vector<int> labels(size.area());
    result.blobs = vision().connected_components(size, bridged, labels) - 1;  // label 0: the rest
    RFD_CHECK(result.blobs >= 1);  // the peak pixel itself lies above the threshold

    // The blob holding the peak is the highlight; the next brightest says whether the
    // photograph shows a second light.
    std::vector<float> blob_peak(static_cast<std::size_t>(result.blobs) + 1, result.background);
    for (std::size_t p = 0; p < labels.size(); ++p)
        if (above[p] != 0) {
            const auto label = static_cast<std::size_t>(labels[p]);
            blob_peak[label] = std::max(blob_peak[label], brightness[p]);
        }
    const auto brightest = static_cast<int>(std::max_element(blob_peak.begin() + 1, blob_peak.end()) - blob_peak.begin());
    float second = result.background;
    for (std::size_t label = 1; label < blob_peak.size(); ++label)
        if (static_cast<int>(label) != brightest) second = std::max(second, blob_peak[label]);
    result.second_blob = (second - result.background) / (result.peak - result.background);
    const auto lit_pixels = std::count_if(above.begin(), above.end(), [](std::uint8_t v) { return v != 0; });
    result.coverage = static_cast<double>(lit_pixels) / static_cast<double>(values.size());
    if (result.coverage > kMaxCoverage) {
        result.status = HighlightStatus::Overexposed;
        return result;
    }

    // Measure a blob over itself grown by two pixels, so the partly lit pixels on its edge
    // count in full, each weighing its brightness above the background: brightness-weighted
    // means of the reflected directions (the estimate; the map is equal-area, see the header)
    // and of the image positions (for reporting).
    const double rim2 = std::pow(std::max(0.0, sphere.radius - std::sqrt(2.0)), 2.0);  // the outermost pixel ring
    const auto measure = [&](int label, Highlight& h) {
        std::vector<std::uint8_t> blob(size.area());
        for (std::size_t p = 0; p < blob.size(); ++p) blob[p] = labels[p] == label ? 255 : 0;
        h.pixels = 0;
        for (std::size_t p = 0; p < blob.size(); ++p)
            if (blob[p] != 0 && above[p] != 0) ++h.pixels;
        std::vector<std::uint8_t> region = blob;
        vision().dilate(size, region, 5);
        for (std::size_t p = 0; p < region.size(); ++p) region[p] &= inside[p];
        Eigen::Vector3d direction_sum = Eigen::Vector3d::Zero();
        Eigen::Vector2d point_sum = Eigen::Vector2d::Zero();
        double weight_sum = 0.0;
        for (int y = 0; y < h_rows; ++y)
            for (int x = 0; x < w; ++x) {
                if (region[at(x, y)] == 0) continue;
                const double weight = std::max(0.0f, brightness[at(x, y)] - result.background);
                const Eigen::Vector2d point(x0 + x + 0.5, y0 + y + 0.5);
                direction_sum += weight * view.reflected(point);
                point_sum += weight * point;
                weight_sum += weight;
                const double dx = point.x() - sphere.centre_x, dy = point.y() - sphere.centre_y;
                if (above[at(x, y)] != 0 && blob[at(x, y)] != 0 && dx * dx + dy * dy >= rim2) h.touches_rim = true;
            }
        RFD_CHECK(weight_sum > 0.0);
        if (direction_sum.norm() < 1e-12 * weight_sum) {
            // Reflections cancel: a ring around the outline (light straight behind the sphere).
            h.status = HighlightStatus::Overexposed;
            return;
        }
        h.status = HighlightStatus::Found;
        h.direction = direction_sum.normalized();
        h.centroid = point_sum / weight_sum;
        const Eigen::Vector3d half = h.direction + view.normal_and_view(h.centroid).second;
        h.normal = half.norm() > 1e-12 ? Eigen::Vector3d(half.normalized()) : Eigen::Vector3d::UnitX();
    };
    if (result.second_blob >= kSecondHighlight) {
        // Ambiguous alone; each bright blob measured, for another sphere to choose from.
        result.status = HighlightStatus::Multiple;
        for (std::size_t label = 1; label < blob_peak.size(); ++label) {
            if ((blob_peak[label] - result.background) < kSecondHighlight * (result.peak - result.background)) continue;
            Highlight candidate = result;
            candidate.touches_rim = false;
            measure(static_cast<int>(label), candidate);
            if (candidate.status == HighlightStatus::Found) result.alternatives.push_back(candidate);
        }
        return result;
    }
    measure(brightest, result);
    return result;
}

std::string highlight_problem(const Highlight& h) {
    switch (h.status) {
        case HighlightStatus::Found: return "";
        case HighlightStatus::None:
            return "no highlight on the mirror sphere: it shows no contrast (brightest " + format_number(h.peak) +
                   ", median " + format_number(h.background) + "): black, uniform or saturated everywhere";
        case HighlightStatus::Multiple:
            return std::to_string(h.blobs) +
                   " separate highlights of like brightness on the mirror sphere; expected one light per image";
        case HighlightStatus::Overexposed:
            return "the highlight covers " + std::to_string(static_cast<int>(h.coverage * 100.0 + 0.5)) +
                   "% of the mirror sphere: overexposed or not a mirror sphere (expected a small spot)";
        case HighlightStatus::Inconsistent:
            return "its direction is " + format_number(h.off_primary_deg, 3) +
                   " degrees from the primary sphere's: a reflection, not the lamp";
        case HighlightStatus::Faint:
            return "the brightest spot on the sphere is far fainter than its highlights in the other photographs "
                   "(a reflection or noise): the lamp is hidden from it";
    }
    return "";
}

}  // namespace rfd::relight
