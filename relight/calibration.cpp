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

Highlight find_highlight(const Image& image, const MirrorSphere& sphere) {
    Highlight result;
    if (image.empty() || !(sphere.radius > 0.0) || !std::isfinite(sphere.radius) ||
        !std::isfinite(sphere.centre_x) || !std::isfinite(sphere.centre_y))
        return result;
    // Clamped in floating point first: a far-off outline must not overflow the int casts.
    const auto clamp_to = [](double v, int size) { return static_cast<int>(std::clamp(v, 0.0, static_cast<double>(size))); };
    const int x0 = clamp_to(std::floor(sphere.centre_x - sphere.radius), image.width());
    const int x1 = clamp_to(std::ceil(sphere.centre_x + sphere.radius) + 1.0, image.width());
    const int y0 = clamp_to(std::floor(sphere.centre_y - sphere.radius), image.height());
    const int y1 = clamp_to(std::ceil(sphere.centre_y + sphere.radius) + 1.0, image.height());
    if (x0 >= x1 || y0 >= y1) return result;

    // Channel-mean brightness of the pixels whose centres lie inside the outline.
    const int w = x1 - x0, h = y1 - y0;
    const PlaneSize size{w, h};
    const auto at = [w](int x, int y) { return static_cast<std::size_t>(y) * static_cast<std::size_t>(w) + static_cast<std::size_t>(x); };
    std::vector<std::uint8_t> inside(size.area(), 0);
    std::vector<float> brightness(size.area(), 0.0f);
    std::vector<float> values;
    const double r2 = sphere.radius * sphere.radius;
    // The outermost ring of pixels (within one pixel diagonal of the outline).
    const double rim2 = std::pow(std::max(0.0, sphere.radius - std::sqrt(2.0)), 2.0);
    for (int y = y0; y < y1; ++y)
        for (int x = x0; x < x1; ++x) {
            const double dx = x + 0.5 - sphere.centre_x, dy = y + 0.5 - sphere.centre_y;
            if (dx * dx + dy * dy >= r2) continue;
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
    const auto lit_pixels = std::count_if(above.begin(), above.end(), [](std::uint8_t v) { return v != 0; });
    result.coverage = static_cast<double>(lit_pixels) / static_cast<double>(values.size());
    if (result.blobs > 1) {
        result.status = HighlightStatus::Multiple;
        return result;
    }
    RFD_CHECK(result.blobs == 1);  // the peak pixel itself lies above the threshold
    if (result.coverage > kMaxCoverage) {
        result.status = HighlightStatus::Overexposed;
        return result;
    }
    result.pixels = static_cast<int>(lit_pixels);

    // Measure over the blob grown by two pixels, so the partly lit pixels on its edge count
    // in full, each weighing its brightness above the background: brightness-weighted means
    // of the reflected directions (the estimate; the map is equal-area, see the header) and
    // of the image positions (for reporting).
    std::vector<std::uint8_t> region = bridged;
    vision().dilate(size, region, 5);
    for (std::size_t p = 0; p < region.size(); ++p) region[p] &= inside[p];
    Eigen::Vector3d direction_sum = Eigen::Vector3d::Zero();
    Eigen::Vector2d point_sum = Eigen::Vector2d::Zero();
    double weight_sum = 0.0;
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            if (region[at(x, y)] == 0) continue;
            const double weight = std::max(0.0f, brightness[at(x, y)] - result.background);
            const Eigen::Vector2d point(x0 + x + 0.5, y0 + y + 0.5);
            direction_sum += weight * reflect_view(mirror_normal(sphere, point));
            point_sum += weight * point;
            weight_sum += weight;
            const double dx = point.x() - sphere.centre_x, dy = point.y() - sphere.centre_y;
            if (above[at(x, y)] != 0 && dx * dx + dy * dy >= rim2) result.touches_rim = true;
        }
    RFD_CHECK(weight_sum > 0.0);
    if (direction_sum.norm() < 1e-12 * weight_sum) {
        // Reflections cancel: a ring around the outline (light straight behind the sphere).
        result.status = HighlightStatus::Overexposed;
        return result;
    }
    result.status = HighlightStatus::Found;
    result.direction = direction_sum.normalized();
    const Eigen::Vector3d half = result.direction + Eigen::Vector3d::UnitZ();
    result.normal = half.norm() > 1e-12 ? Eigen::Vector3d(half.normalized()) : Eigen::Vector3d::UnitX();
    result.centroid = point_sum / weight_sum;
    return result;
}

std::vector<CalibratedLight> calibrate_lights(const std::vector<std::filesystem::path>& mirror_images,
                                              const MirrorSphere& sphere) {
    if (!(std::isfinite(sphere.centre_x) && std::isfinite(sphere.centre_y) && std::isfinite(sphere.radius) &&
          sphere.radius > 0.0))
        throw InputError("mirror sphere: expected a finite centre and a positive radius in pixels, got (" +
                         format_number(sphere.centre_x) + ", " + format_number(sphere.centre_y) +
                         ") radius " + format_number(sphere.radius));
    std::vector<CalibratedLight> lights;
    for (const auto& path : mirror_images) {
        const Image image = read_image(path);
        const SourceLocation where{path.string()};
        if (sphere.centre_x - sphere.radius < 0.0 || sphere.centre_y - sphere.radius < 0.0 ||
            sphere.centre_x + sphere.radius > image.width() || sphere.centre_y + sphere.radius > image.height())
            throw InputError(where, "the mirror sphere (centre " + format_number(sphere.centre_x) + ", " +
                                        format_number(sphere.centre_y) + ", radius " +
                                        format_number(sphere.radius) + " px) does not fit inside this " +
                                        std::to_string(image.width()) + "x" + std::to_string(image.height()) +
                                        " image");
        const Highlight h = find_highlight(image, sphere);
        switch (h.status) {
            case HighlightStatus::Found: break;
            case HighlightStatus::None:
                throw InputError(where, "no highlight on the mirror sphere: it shows no contrast (brightest " +
                                            format_number(h.peak) + ", median " + format_number(h.background) +
                                            "): black, uniform or saturated everywhere");
            case HighlightStatus::Multiple:
                throw InputError(where, std::to_string(h.blobs) +
                                            " separate highlights on the mirror sphere; expected one light per image");
            case HighlightStatus::Overexposed:
                throw InputError(where, "the highlight covers " + std::to_string(static_cast<int>(h.coverage * 100.0 + 0.5)) +
                                            "% of the mirror sphere: overexposed or not a mirror sphere "
                                            "(expected a small spot)");
        }
        lights.push_back({path, h});
    }
    return lights;
}

}  // namespace rfd::relight
