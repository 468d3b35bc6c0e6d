#include "calibrate/sheet_finder.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <optional>
#include <vector>

#include <Eigen/Dense>

#include "calibrate/camera.hpp"
#include "core/error.hpp"
#include "core/text.hpp"
#include "relight/vision.hpp"

namespace rfd::calibrate {
namespace {

constexpr double kDarkFraction = 0.5;  // a mark pixel is darker than this part of its surroundings
// The relative spread of a blob's boundary pixels' Mahalanobis radius: a filled ellipse's comes
// from its pixels alone (less than 0.8 / sqrt(its pixels)), a square's is 0.1.
constexpr double kRadiusSpread = 0.04, kPixelSpread = 0.8;
constexpr int kMinMarkPixels = 12;       // smaller blobs are text and dust
constexpr std::size_t kCandidates = 14;  // largest round blobs tried as corner discs

struct Blob {
    Eigen::Vector2d centre;
    double area = 0.0;  ///< pixels
};

// Round dark blobs of the luminance plane.
std::vector<Blob> round_dark_blobs(const Image& luminance) {
    const int w = luminance.width(), h = luminance.height();
    const relight::PlaneSize size{w, h};
    const relight::Vision& vision = relight::vision();
    // The white around each pixel: the mean, over a window larger than a mark, of the pixels
    // brighter than the mean there. A blurred edge between a mark and that white crosses half
    // of it where the mark's edge is.
    const int kernel = std::max(15, (std::min(w, h) / 6) | 1);
    const auto local_mean = [&](const Image& values, const Image& weights) {
        Image sum = values, weight = weights;
        vision.box_blur(size, sum.plane(0), kernel);
        vision.box_blur(size, weight.plane(0), kernel);
        for (std::size_t k = 0; k < sum.pixel_count(); ++k)
            sum.plane(0)[k] = weight.plane(0)[k] > 0.0f ? sum.plane(0)[k] / weight.plane(0)[k] : 0.0f;
        return sum;
    };
    const Image average = local_mean(luminance, Image(w, h, 1, 1.0f));
    Image bright(w, h, 1), brighter(w, h, 1);
    for (std::size_t k = 0; k < luminance.pixel_count(); ++k) {
        const bool above = luminance.plane(0)[k] > average.plane(0)[k];
        bright.plane(0)[k] = above ? 1.0f : 0.0f;
        brighter.plane(0)[k] = above ? luminance.plane(0)[k] : 0.0f;
    }
    const Image white = local_mean(brighter, bright);
    std::vector<std::uint8_t> mask(luminance.pixel_count());
    for (std::size_t k = 0; k < mask.size(); ++k)
        mask[k] = luminance.plane(0)[k] < kDarkFraction * white.plane(0)[k] ? 1 : 0;
    std::vector<int> labels(mask.size());
    const int count = vision.connected_components(size, mask, labels);

    struct Moments {
        double n = 0, sx = 0, sy = 0, sxx = 0, sxy = 0, syy = 0;
        bool touches_edge = false;
    };
    std::vector<Moments> moments(static_cast<std::size_t>(count));
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const int label = labels[static_cast<std::size_t>(y) * w + x];
            if (label == 0) continue;
            Moments& m = moments[static_cast<std::size_t>(label)];
            m.n += 1;
            m.sx += x;
            m.sy += y;
            m.sxx += double(x) * x;
            m.sxy += double(x) * y;
            m.syy += double(y) * y;
            if (x == 0 || y == 0 || x == w - 1 || y == h - 1) m.touches_edge = true;
        }
    // Mean and spread of each blob's boundary pixels' Mahalanobis radius.
    std::vector<Eigen::Matrix2d> inverse(moments.size(), Eigen::Matrix2d::Zero());
    std::vector<Eigen::Vector2d> centre(moments.size());
    std::vector<double> r_sum(moments.size(), 0.0), r2_sum(moments.size(), 0.0), r_n(moments.size(), 0.0);
    for (std::size_t k = 1; k < moments.size(); ++k) {
        const Moments& m = moments[k];
        if (m.n < kMinMarkPixels || m.touches_edge) continue;
        centre[k] = Eigen::Vector2d(m.sx / m.n, m.sy / m.n);
        Eigen::Matrix2d cov;
        cov << m.sxx / m.n - centre[k].x() * centre[k].x(), m.sxy / m.n - centre[k].x() * centre[k].y(),
            m.sxy / m.n - centre[k].x() * centre[k].y(), m.syy / m.n - centre[k].y() * centre[k].y();
        inverse[k] = cov.determinant() > 0.0 ? Eigen::Matrix2d(cov.inverse()) : Eigen::Matrix2d::Zero();
    }
    const auto label_at = [&](int x, int y) { return labels[static_cast<std::size_t>(y) * w + x]; };
    for (int y = 1; y < h - 1; ++y)
        for (int x = 1; x < w - 1; ++x) {
            const int label = label_at(x, y);
            if (label == 0 || r_n.size() <= static_cast<std::size_t>(label)) continue;
            const auto k = static_cast<std::size_t>(label);
            if (inverse[k].isZero()) continue;
            if (label_at(x - 1, y) == label && label_at(x + 1, y) == label && label_at(x, y - 1) == label &&
                label_at(x, y + 1) == label)
                continue;
            // The pixel's outer edge lies half a pixel beyond its centre.
            const Eigen::Vector2d d = Eigen::Vector2d(x, y) - centre[k];
            const double r = std::sqrt(std::max(0.0, d.dot(inverse[k] * d)));
            r_sum[k] += r;
            r2_sum[k] += r * r;
            r_n[k] += 1;
        }
    std::vector<Blob> blobs;
    for (std::size_t k = 1; k < moments.size(); ++k) {
        if (r_n[k] < 8 || inverse[k].isZero()) continue;
        const double mean = r_sum[k] / r_n[k];
        const double spread = std::sqrt(std::max(0.0, r2_sum[k] / r_n[k] - mean * mean)) / mean;
        if (spread > kRadiusSpread + kPixelSpread / std::sqrt(moments[k].n)) continue;
        blobs.push_back({centre[k], moments[k].n});
    }
    std::sort(blobs.begin(), blobs.end(), [](const Blob& a, const Blob& b) { return a.area > b.area; });
    return blobs;
}

// Twice the signed area of a quadrilateral.
double signed_area(const std::array<Eigen::Vector2d, 4>& q) {
    double sum = 0.0;
    for (std::size_t k = 0; k < 4; ++k) {
        const Eigen::Vector2d& a = q[k];
        const Eigen::Vector2d& b = q[(k + 1) % 4];
        sum += a.x() * b.y() - b.x() * a.y();
    }
    return sum;
}

// The area of the image of a disc, pixels, and how far its centroid lies from the image of its
// centre (perspective moves it toward the nearer side).
struct DiscImage {
    double area = 0.0;
    Eigen::Vector2d centroid_offset = Eigen::Vector2d::Zero();
};

DiscImage disc_image(const Eigen::Matrix3d& h, const Eigen::Vector2d& centre, double diameter) {
    constexpr int kSides = 96;
    std::vector<Eigen::Vector2d> polygon;
    for (int k = 0; k < kSides; ++k) {
        const double a = 2.0 * std::numbers::pi * k / kSides;
        polygon.push_back(apply(h, centre + 0.5 * diameter * Eigen::Vector2d(std::cos(a), std::sin(a))));
    }
    double area2 = 0.0;
    Eigen::Vector2d weighted = Eigen::Vector2d::Zero();
    for (int k = 0; k < kSides; ++k) {
        const Eigen::Vector2d& a = polygon[static_cast<std::size_t>(k)];
        const Eigen::Vector2d& b = polygon[static_cast<std::size_t>((k + 1) % kSides)];
        const double cross = a.x() * b.y() - b.x() * a.y();
        area2 += cross;
        weighted += cross * (a + b);
    }
    return {std::abs(0.5 * area2), weighted / (3.0 * area2) - apply(h, centre)};
}

// The area of a small disc's image, from the map's local stretch: pi r^2 |det J|, with J
// the homography's Jacobian at the centre. Within a few per cent of disc_image's for the
// marks, at a hundredth of its cost: what the search over candidate corners uses.
double disc_image_area(const Eigen::Matrix3d& h, const Eigen::Vector2d& centre, double diameter) {
    const double w = h(2, 0) * centre.x() + h(2, 1) * centre.y() + h(2, 2);
    const Eigen::Vector2d image = apply(h, centre);
    Eigen::Matrix2d jacobian = h.topLeftCorner<2, 2>() - image * h.block<1, 2>(2, 0);
    jacobian /= w;
    return std::numbers::pi * 0.25 * diameter * diameter * std::abs(jacobian.determinant());
}

}  // namespace

Eigen::Matrix3d homography_from_points(const std::array<Eigen::Vector2d, 4>& from,
                                       const std::array<Eigen::Vector2d, 4>& to) {
    Eigen::Matrix<double, 8, 8> a;
    Eigen::Matrix<double, 8, 1> b;
    for (int k = 0; k < 4; ++k) {
        const double x = from[static_cast<std::size_t>(k)].x(), y = from[static_cast<std::size_t>(k)].y();
        const double u = to[static_cast<std::size_t>(k)].x(), v = to[static_cast<std::size_t>(k)].y();
        a.row(2 * k) << x, y, 1, 0, 0, 0, -u * x, -u * y;
        a.row(2 * k + 1) << 0, 0, 0, x, y, 1, -v * x, -v * y;
        b(2 * k) = u;
        b(2 * k + 1) = v;
    }
    const Eigen::Matrix<double, 8, 1> h = a.fullPivLu().solve(b);
    Eigen::Matrix3d out;
    out << h(0), h(1), h(2), h(3), h(4), h(5), h(6), h(7), 1.0;
    return out;
}

Image photo_luminance(const Image& photo) {
    Image out(photo.width(), photo.height(), 1);
    for (int c = 0; c < photo.channels(); ++c) {
        const auto plane = photo.plane(c);
        for (std::size_t k = 0; k < plane.size(); ++k)
            out.plane(0)[k] += plane[k] / static_cast<float>(photo.channels());
    }
    return out;
}

double sample_bilinear(const Image& plane, double u, double v, int channel) {
    if (!(u >= 0.0 && v >= 0.0 && u <= plane.width() - 1.0 && v <= plane.height() - 1.0))
        return std::numeric_limits<double>::quiet_NaN();
    const int x0 = std::min(static_cast<int>(u), plane.width() - 2), y0 = std::min(static_cast<int>(v), plane.height() - 2);
    const double fx = u - x0, fy = v - y0;
    const int c = channel;
    return (1 - fy) * ((1 - fx) * plane.at(x0, y0, c) + fx * plane.at(x0 + 1, y0, c)) +
           fy * ((1 - fx) * plane.at(x0, y0 + 1, c) + fx * plane.at(x0 + 1, y0 + 1, c));
}

double mean_over_page_rect(const Image& plane, const Eigen::Matrix3d& page_to_photo, double x0, double y0, double x1,
                           double y1) {
    // Page mm per photo pixel here, from the map's local stretch.
    const Eigen::Vector2d mid(0.5 * (x0 + x1), 0.5 * (y0 + y1));
    const double stretch =
        (apply(page_to_photo, mid + Eigen::Vector2d(0.5, 0.0)) - apply(page_to_photo, mid - Eigen::Vector2d(0.5, 0.0)))
            .norm();
    const int nx = std::max(1, static_cast<int>(std::ceil((x1 - x0) * stretch)));
    const int ny = std::max(1, static_cast<int>(std::ceil((y1 - y0) * stretch)));
    double sum = 0.0;
    for (int j = 0; j < ny; ++j)
        for (int i = 0; i < nx; ++i) {
            const Eigen::Vector2d p =
                apply(page_to_photo, {x0 + (x1 - x0) * (i + 0.5) / nx, y0 + (y1 - y0) * (j + 0.5) / ny});
            const double value = sample_bilinear(plane, p.x(), p.y());
            if (std::isnan(value)) return value;
            sum += value;
        }
    return sum / (nx * ny);
}

SheetLocation find_sheet(const Image& photo, const print::SheetMarks& marks, const std::string& name) {
    // A one-channel photo is its own luminance (measure_wedge passes the one it made).
    const Image mixed = photo.channels() == 1 ? Image() : photo_luminance(photo);
    std::vector<Blob> blobs = round_dark_blobs(photo.channels() == 1 ? photo : mixed);
    const std::size_t tried = std::min(blobs.size(), kCandidates);
    const std::array<Eigen::Vector2d, 4>& page = marks.corners;
    const double page_area = signed_area(page);

    struct Choice {
        double score = std::numeric_limits<double>::infinity();
        std::array<Eigen::Vector2d, 4> corners;
        Eigen::Vector2d orientation;
        bool mirrored = false;
    } best;
    std::array<std::size_t, 4> pick{};
    // Every 4 of the largest round blobs, in every assignment to the page's corners that keeps
    // them a convex quadrilateral in order.
    for (pick[0] = 0; pick[0] < tried; ++pick[0])
        for (pick[1] = pick[0] + 1; pick[1] < tried; ++pick[1])
            for (pick[2] = pick[1] + 1; pick[2] < tried; ++pick[2])
                for (pick[3] = pick[2] + 1; pick[3] < tried; ++pick[3]) {
                    std::array<Eigen::Vector2d, 4> quad;
                    Eigen::Vector2d mean = Eigen::Vector2d::Zero();
                    for (std::size_t k = 0; k < 4; ++k) mean += 0.25 * blobs[pick[k]].centre;
                    std::array<std::size_t, 4> order = pick;
                    std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
                        const Eigen::Vector2d da = blobs[a].centre - mean, db = blobs[b].centre - mean;
                        return std::atan2(da.y(), da.x()) < std::atan2(db.y(), db.x());
                    });
                    for (std::size_t k = 0; k < 4; ++k) quad[k] = blobs[order[k]].centre;
                    for (int reflect = 0; reflect < 2; ++reflect)
                        for (std::size_t shift = 0; shift < 4; ++shift) {
                            std::array<Eigen::Vector2d, 4> to;
                            std::array<double, 4> areas{};
                            for (std::size_t k = 0; k < 4; ++k) {
                                const std::size_t index = reflect ? (shift + 4 - k) % 4 : (shift + k) % 4;
                                to[k] = quad[index];
                                areas[k] = blobs[order[index]].area;
                            }
                            const Eigen::Matrix3d h = homography_from_points(page, to);
                            if (!h.allFinite()) continue;
                            // Each corner blob the size its disc's image would be.
                            bool sizes_agree = true;
                            for (std::size_t k = 0; k < 4 && sizes_agree; ++k) {
                                const double expected = disc_image_area(h, page[k], marks.corner_diameter);
                                sizes_agree = areas[k] > 0.5 * expected && areas[k] < 2.0 * expected;
                            }
                            if (!sizes_agree) continue;
                            const Eigen::Vector2d where = apply(h, marks.orientation);
                            const double small = disc_image_area(h, marks.orientation, marks.orientation_diameter);
                            const double radius = std::sqrt(small / std::numbers::pi);
                            for (const Blob& blob : blobs) {
                                const double distance = (blob.centre - where).norm() / radius;
                                if (distance > 0.5 || blob.area < 0.25 * small || blob.area > 2.5 * small)
                                    continue;
                                if (distance < best.score)
                                    best = {distance, to, blob.centre, (signed_area(to) > 0) != (page_area > 0)};
                            }
                        }
                }
    if (!std::isfinite(best.score))
        throw InputError(SourceLocation{name},
                         "cannot find the sheet: it needs its four corner discs "
                         "and the small disc below the "
                         "top-left one in view (" +
                             std::to_string(blobs.size()) +
                             " round dark marks seen); "
                             "photograph the whole sheet filling most of the frame, evenly lit, in focus");

    // Perspective moves a disc's image centroid off the image of its centre: correct the
    // measured centroids by the offset the current map predicts, and solve again.
    Eigen::Matrix3d h = homography_from_points(page, best.corners);
    for (int pass = 0; pass < 3; ++pass) {
        std::array<Eigen::Vector2d, 4> corrected;
        for (std::size_t k = 0; k < 4; ++k)
            corrected[k] = best.corners[k] - disc_image(h, page[k], marks.corner_diameter).centroid_offset;
        h = homography_from_points(page, corrected);
    }
    SheetLocation location;
    location.page_to_photo = h;
    location.mirrored = best.mirrored;
    const Eigen::Vector2d centre = 0.25 * (page[0] + page[1] + page[2] + page[3]);
    const double along_x =
        (apply(h, centre + Eigen::Vector2d(0.5, 0)) - apply(h, centre - Eigen::Vector2d(0.5, 0))).norm();
    const double along_y =
        (apply(h, centre + Eigen::Vector2d(0, 0.5)) - apply(h, centre - Eigen::Vector2d(0, 0.5))).norm();
    location.mm_per_pixel = 1.0 / std::sqrt(along_x * along_y);
    location.orientation_error =
        (best.orientation - disc_image(h, marks.orientation, marks.orientation_diameter).centroid_offset -
         apply(h, marks.orientation))
            .norm();
    return location;
}

double photo_at_page(const Image& luminance, const Eigen::Matrix3d& page_to_photo, const Eigen::Vector2d& page) {
    const Eigen::Vector2d pixel = apply(page_to_photo, page);
    return sample_bilinear(luminance, pixel.x(), pixel.y());
}

double otsu_threshold(std::span<const float> values) {
    constexpr int kBins = 256;
    float lo = HUGE_VALF, hi = -HUGE_VALF;
    for (const float v : values)
        if (std::isfinite(v)) lo = std::min(lo, v), hi = std::max(hi, v);
    if (!(hi > lo)) return lo;
    std::vector<double> histogram(kBins, 0.0);
    double count = 0.0, sum = 0.0;
    for (const float v : values)
        if (std::isfinite(v)) {
            const int bin = std::min(kBins - 1, static_cast<int>((v - lo) / (hi - lo) * kBins));
            histogram[static_cast<std::size_t>(bin)] += 1.0;
            count += 1.0;
            sum += bin;
        }
    double below = 0.0, below_sum = 0.0, best = -1.0;
    int best_bin = 0;
    for (int bin = 0; bin < kBins - 1; ++bin) {
        below += histogram[static_cast<std::size_t>(bin)];
        below_sum += bin * histogram[static_cast<std::size_t>(bin)];
        if (below == 0.0 || below == count) continue;
        const double mean_below = below_sum / below, mean_above = (sum - below_sum) / (count - below);
        const double between = below * (count - below) * (mean_below - mean_above) * (mean_below - mean_above);
        if (between > best) best = between, best_bin = bin;
    }
    return lo + (best_bin + 1.0) / kBins * (hi - lo);
}

std::pair<double, double> disc_statistics(const Image& luminance, const Eigen::Matrix3d& page_to_photo,
                                          const Eigen::Vector2d& centre, double radius, double step) {
    double sum = 0.0, sum2 = 0.0;
    int n = 0;
    const int steps = std::max(1, static_cast<int>(std::ceil(radius / step)));
    for (int j = -steps; j <= steps; ++j)
        for (int i = -steps; i <= steps; ++i) {
            const Eigen::Vector2d d(i * radius / steps, j * radius / steps);
            if (d.squaredNorm() > radius * radius) continue;
            const double v = photo_at_page(luminance, page_to_photo, centre + d);
            if (!std::isfinite(v)) return {NAN, NAN};
            sum += v;
            sum2 += v * v;
            ++n;
        }
    const double mean = sum / n;
    return {mean, std::max(0.0, sum2 / n - mean * mean)};
}

}  // namespace rfd::calibrate
