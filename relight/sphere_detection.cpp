#include "relight/sphere_detection.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <exception>
#include <numbers>
#include <random>
#include <string>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <tbb/task_arena.h>

#include "core/error.hpp"
#include "core/image_io.hpp"
#include "core/parallel.hpp"
#include "core/progress.hpp"
#include "core/sphere.hpp"
#include "core/text.hpp"
#include "core/units.hpp"

namespace rfd::relight {
namespace {

namespace fs = std::filesystem;

// A calibration sphere's highlights are far brighter than its body: in the maximum over
// the capture, the inner disc's brightest percent stands this far above the mean's median
// there. A diffuse ball reaches about 3, a glossy lacquer about 15, a black ball or a chrome
// one hundreds (and, clipped to 8 bits, still about a hundred).
constexpr double kSpecularContrast = 40.0;
// An outline's step is at least this fraction of the steepest along its ray.
constexpr double kOutlineStep = 0.2;
// The outline is the outermost circle of steps crossed by this share of the rays that cross
// the best supported one.
constexpr double kOuterSupport = 0.7;
// Highlights this close (rms, pixels) to where the primary sphere's directions put them say
// the lamps are distant, and a sphere's outline may be aligned to them.
constexpr double kAlignedRmsPx = 0.35;
// Of several blobs on a sphere, one this close to the other spheres' direction is the lamp.
constexpr double kConfirmDeg = 5.0;
// A highlight is at least this fraction as bright (above the sphere's median) as the
// sphere's typical one.
constexpr float kFaintHighlight = 0.1f;
// Rays from a candidate's centre that must find its edge: a chrome ball's outline, a step of its
// reflectance only, is found on 40-60 % of them in noisy JPEGs of 4 Mpx.
constexpr double kEdgeFraction = 0.35;
// Two detected spheres belong to one calibration when their directions agree this well
// (median over the photographs), and a sphere's reading this far from the primary's is not
// the lamp. Generous: lamps at a dome's radius differ by 20 degrees and more between
// spheres a third of it apart.
constexpr double kAgreementDeg = 45.0;

float quantile(std::vector<float> values, double q) {
    if (values.empty()) return 0.0f;
    const auto k = static_cast<std::ptrdiff_t>(q * static_cast<double>(values.size() - 1));
    std::nth_element(values.begin(), values.begin() + k, values.end());
    return values[static_cast<std::size_t>(k)];
}

// Tukey's biweight of a residual over its cutoff.
double tukey(double u) { return std::abs(u) < 1.0 ? (1.0 - u * u) * (1.0 - u * u) : 0.0; }

// One weighted Gauss-Newton step for three parameters: the Jacobian of `residuals` by
// central differences (1e-4, pixels), `r` the residuals at `x`, `w` their weights.
template <typename Residuals>
Eigen::Vector3d gauss_newton_step(const Residuals& residuals, const Eigen::Vector3d& x, const Eigen::VectorXd& r,
                                  const Eigen::VectorXd& w) {
    constexpr double kStep = 1e-4;
    Eigen::MatrixXd jacobian(r.size(), 3);
    Eigen::VectorXd plus(r.size()), minus(r.size());
    for (int k = 0; k < 3; ++k) {
        Eigen::Vector3d a = x, b = x;
        a(k) += kStep;
        b(k) -= kStep;
        residuals(a, plus);
        residuals(b, minus);
        jacobian.col(k) = (plus - minus) / (2.0 * kStep);
    }
    return (jacobian.transpose() * w.asDiagonal() * jacobian).ldlt().solve(-(jacobian.transpose() * w.asDiagonal() * r));
}

// InputError unless the photograph `in` reads is `size`, the first one's.
void check_size(const ImageBandReader& in, PlaneSize size) {
    if (in.width() != size.width || in.height() != size.height)
        throw InputError(SourceLocation{in.path().string()},
                         "is " + std::to_string(in.width()) + "x" + std::to_string(in.height()) +
                             "; the first photograph is " + std::to_string(size.width) + "x" +
                             std::to_string(size.height) + " (expected one size)");
}

// One photograph's channel-mean brightness, read a band of rows at a time.
std::vector<float> brightness_plane(const fs::path& path, PlaneSize size) {
    ImageBandReader in(path);
    check_size(in, size);
    std::vector<float> plane(size.area());
    constexpr int kBandRows = 256;
    for (int y0 = 0; y0 < size.height; y0 += kBandRows) {
        const int y1 = std::min(size.height, y0 + kBandRows);
        const Image band = in.read(y0, y1);
        const float scale = 1.0f / static_cast<float>(band.channels());
        float* out = plane.data() + static_cast<std::size_t>(y0) * static_cast<std::size_t>(size.width);
        for (int c = 0; c < band.channels(); ++c) {
            const std::span<const float> samples = band.plane(c);
            for (std::size_t p = 0; p < samples.size(); ++p) out[p] += samples[p] * scale;
        }
    }
    return plane;
}

// Bilinear sample of a plane at a continuous image point (pixel centres at .5); NaN
// outside the pixel centres' hull.
float sample(const CaptureBrightness& b, const std::vector<float>& plane, double x, double y) {
    const double fx = x - 0.5, fy = y - 0.5;
    if (!(fx >= 0.0 && fy >= 0.0 && fx <= b.size.width - 1 && fy <= b.size.height - 1))
        return std::numeric_limits<float>::quiet_NaN();
    const int x0 = std::min(static_cast<int>(fx), b.size.width - 2 < 0 ? 0 : b.size.width - 2);
    const int y0 = std::min(static_cast<int>(fy), b.size.height - 2 < 0 ? 0 : b.size.height - 2);
    const int x1 = std::min(x0 + 1, b.size.width - 1), y1 = std::min(y0 + 1, b.size.height - 1);
    const double tx = fx - x0, ty = fy - y0;
    const auto at = [&](int px, int py) {
        return static_cast<double>(plane[static_cast<std::size_t>(py) * static_cast<std::size_t>(b.size.width) +
                                         static_cast<std::size_t>(px)]);
    };
    return static_cast<float>((1 - ty) * ((1 - tx) * at(x0, y0) + tx * at(x1, y0)) +
                              ty * ((1 - tx) * at(x0, y1) + tx * at(x1, y1)));
}

// How far in front of the outline an image point lies, in pixels near the axis: the angle
// between its ray and the cone's axis less the cone's half-angle, times f (orthographic:
// the distance to the circle).
double outline_residual(const MirrorSphere& sphere, const CalibrationCamera& camera, const Eigen::Vector2d& point) {
    const Eigen::Vector2d centre(sphere.centre_x, sphere.centre_y);
    if (camera.orthographic()) return (point - centre).norm() - sphere.radius;
    const Eigen::Vector3d axis = camera.ray(centre), ray = camera.ray(point);
    const double angle = std::atan2(ray.cross(axis).norm(), ray.dot(axis));
    return camera.focal_length_px * (angle - std::atan(sphere.radius / camera.focal_length_px));
}

// The outline through `edges`, from `start`, by Gauss-Newton with Tukey's biweight; the
// scale is the residuals' median absolute deviation (at least 0.05 px).
OutlineFit robust_outline(const std::vector<Eigen::Vector2d>& edges, const MirrorSphere& start,
                          const CalibrationCamera& camera, int rays) {
    Eigen::Vector3d x(start.centre_x, start.centre_y, start.radius);
    const auto sphere_of = [](const Eigen::Vector3d& v) { return MirrorSphere{v.x(), v.y(), v.z()}; };
    const std::size_t n = edges.size();
    Eigen::VectorXd r(n), w(n);
    double sigma = 1.0;
    const auto residuals = [&](const Eigen::Vector3d& v, Eigen::VectorXd& out) {
        for (std::size_t i = 0; i < n; ++i) out(static_cast<Eigen::Index>(i)) = outline_residual(sphere_of(v), camera, edges[i]);
    };
    for (int iteration = 0; iteration < 60; ++iteration) {
        residuals(x, r);
        std::vector<float> magnitudes(n);
        for (std::size_t i = 0; i < n; ++i) magnitudes[i] = static_cast<float>(std::abs(r(static_cast<Eigen::Index>(i))));
        sigma = std::max(0.05, 1.4826 * static_cast<double>(quantile(magnitudes, 0.5)));
        const double cutoff = 4.685 * sigma;
        for (std::size_t i = 0; i < n; ++i)
            w(static_cast<Eigen::Index>(i)) = tukey(r(static_cast<Eigen::Index>(i)) / cutoff);
        const Eigen::Vector3d step = gauss_newton_step(residuals, x, r, w);
        if (!step.allFinite()) break;
        x += step;
        if (step.norm() < 1e-7) break;
    }
    residuals(x, r);
    OutlineFit fit{sphere_of(x), rays, 0, 0.0};
    const double inlier = std::max(1.0, 3.0 * sigma);
    double sum2 = 0.0;
    for (std::size_t i = 0; i < n; ++i) {
        const double v = r(static_cast<Eigen::Index>(i));
        if (std::abs(v) > inlier) continue;
        ++fit.edges;
        sum2 += v * v;
    }
    fit.rms_px = fit.edges > 0 ? std::sqrt(sum2 / fit.edges) : 0.0;
    return fit;
}

// Each photograph's highlight on each sphere: the sphere's box read from the file (a band
// of rows, a span of columns) and searched.
std::vector<std::vector<Highlight>> read_highlights(const std::vector<fs::path>& images,
                                                    const std::vector<MirrorSphere>& spheres,
                                                    const CalibrationCamera& camera, PlaneSize size) {
    std::vector<std::vector<Highlight>> found(images.size(), std::vector<Highlight>(spheres.size()));
    // Boxes in the order of their first rows: a file decodes once, top to bottom.
    std::vector<std::size_t> order(spheres.size());
    for (std::size_t s = 0; s < order.size(); ++s) order[s] = s;
    std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
        return spheres[a].centre_y - spheres[a].radius < spheres[b].centre_y - spheres[b].radius;
    });
    std::vector<std::exception_ptr> failures(images.size());
    Progress progress("finding the highlights", images.size());
    parallel_for_chunks(images.size(), 1, [&](std::size_t begin, std::size_t end) {
        for (std::size_t i = begin; i < end; ++i) {
            try {
                ImageBandReader in(images[i]);
                check_size(in, size);
                for (const std::size_t s : order) {
                    const MirrorSphere& sphere = spheres[s];
                    const auto clamp_to = [](double v, int limit) {
                        return static_cast<int>(std::clamp(v, 0.0, static_cast<double>(limit)));
                    };
                    const int x0 = clamp_to(std::floor(sphere.centre_x - sphere.radius) - 3.0, size.width);
                    const int x1 = clamp_to(std::ceil(sphere.centre_x + sphere.radius) + 4.0, size.width);
                    const int y0 = clamp_to(std::floor(sphere.centre_y - sphere.radius) - 3.0, size.height);
                    const int y1 = clamp_to(std::ceil(sphere.centre_y + sphere.radius) + 4.0, size.height);
                    if (x0 >= x1 || y0 >= y1) continue;
                    const Image crop = in.read(y0, y1, x0, x1);
                    const Eigen::Vector2d origin(x0, y0);
                    const MirrorSphere local{sphere.centre_x - x0, sphere.centre_y - y0, sphere.radius};
                    Highlight h = find_highlight(crop, local, camera.cropped(origin));
                    h.centroid += origin;
                    for (Highlight& alternative : h.alternatives) alternative.centroid += origin;
                    found[i][s] = h;
                }
            } catch (...) {
                failures[i] = std::current_exception();
            }
            progress.advance();
        }
    });
    progress.finish();
    for (const auto& failure : failures)
        if (failure) std::rethrow_exception(failure);
    return found;
}

// The steps of the mean brightness along rays from `centre`, radii [from, to]: each a local
// maximum of the difference across one pixel that reaches kOutlineStep of the ray's
// steepest, located to a fraction of a pixel (radius, step).
struct RayEdges {
    Eigen::Vector2d direction;
    std::vector<std::pair<double, double>> edges;
};

std::vector<RayEdges> edges_along_rays(const CaptureBrightness& b, const Eigen::Vector2d& centre, double from, double to,
                                       int rays) {
    constexpr double kStep = 0.25;  // pixels along a ray
    std::vector<RayEdges> found;
    if (!(from > 0.0) || !(to > from)) return found;
    const int steps = static_cast<int>(std::ceil((to - from) / kStep)) + 1;
    std::vector<double> profile(static_cast<std::size_t>(steps)), slope(static_cast<std::size_t>(steps));
    for (int k = 0; k < rays; ++k) {
        const double angle = 2.0 * std::numbers::pi * (k + 0.5) / rays;
        RayEdges ray{Eigen::Vector2d(std::cos(angle), std::sin(angle)), {}};
        bool inside = true;
        for (int j = 0; j < steps && inside; ++j) {
            const Eigen::Vector2d p = centre + (from + j * kStep) * ray.direction;
            profile[static_cast<std::size_t>(j)] = static_cast<double>(sample(b, b.mean, p.x(), p.y()));
            inside = std::isfinite(profile[static_cast<std::size_t>(j)]);
        }
        if (!inside) continue;  // the ray leaves the image: not counted
        double steepest = 0.0;
        for (int j = 0; j < steps; ++j) {
            const auto u = static_cast<std::size_t>(j);
            slope[u] = j >= 2 && j + 2 < steps ? std::abs(profile[u + 2] - profile[u - 2]) : 0.0;
            steepest = std::max(steepest, slope[u]);
        }
        for (int j = 3; j + 3 < steps && steepest > 0.0; ++j) {
            const auto u = static_cast<std::size_t>(j);
            if (slope[u] < kOutlineStep * steepest || slope[u] < slope[u - 1] || slope[u] <= slope[u + 1]) continue;
            const double curvature = slope[u - 1] - 2.0 * slope[u] + slope[u + 1];
            const double offset = curvature < 0.0 ? std::clamp(0.5 * (slope[u - 1] - slope[u + 1]) / curvature, -0.5, 0.5) : 0.0;
            ray.edges.emplace_back(from + (j + offset) * kStep, slope[u]);
        }
        found.push_back(std::move(ray));
    }
    return found;
}

// The circle through steps of the most rays (within a pixel), by RANSAC: circles through
// three steps on rays at least 40 degrees apart, about `centre` within a quarter of `radius`
// and of a radius within a third of it. Deterministic (a fixed sequence of triples).
std::optional<MirrorSphere> most_crossed_circle(const std::vector<RayEdges>& rays, const Eigen::Vector2d& centre,
                                                double radius) {
    struct Step {
        std::size_t ray;
        Eigen::Vector2d point;
    };
    std::vector<Step> steps;
    for (std::size_t k = 0; k < rays.size(); ++k)
        for (const auto& e : rays[k].edges) steps.push_back({k, centre + e.first * rays[k].direction});
    if (steps.size() < 3) return std::nullopt;
    std::mt19937_64 random(0x5EED);
    std::vector<std::pair<std::size_t, MirrorSphere>> circles;
    std::size_t best_support = 0;
    for (int trial = 0; trial < 2000; ++trial) {
        const Step& a = steps[random() % steps.size()];
        const Step& b = steps[random() % steps.size()];
        const Step& c = steps[random() % steps.size()];
        const auto apart = [&](const Step& u, const Step& v) {
            return rays[u.ray].direction.dot(rays[v.ray].direction) < std::cos(degrees_to_radians(40.0));
        };
        if (!apart(a, b) || !apart(b, c) || !apart(a, c)) continue;
        // The circumcircle: equidistant from the three points.
        Eigen::Matrix2d m;
        m << (b.point - a.point).transpose(), (c.point - a.point).transpose();
        const Eigen::Vector2d rhs(0.5 * (b.point.squaredNorm() - a.point.squaredNorm()),
                                  0.5 * (c.point.squaredNorm() - a.point.squaredNorm()));
        if (std::abs(m.determinant()) < 1e-9) continue;
        const Eigen::Vector2d o = m.inverse() * rhs;
        const double r = (a.point - o).norm();
        if ((o - centre).norm() > 0.25 * radius || std::abs(r - radius) > radius / 3.0) continue;
        std::size_t support = 0;
        for (const RayEdges& ray : rays)
            support += std::any_of(ray.edges.begin(), ray.edges.end(), [&](const auto& e) {
                return std::abs((centre + e.first * ray.direction - o).norm() - r) <= 1.0;
            });
        circles.push_back({support, MirrorSphere{o.x(), o.y(), r}});
        best_support = std::max(best_support, support);
    }
    // The outline is the outermost circle nearly as well supported as the best: a chrome
    // ball's rim mirrors the table right up to the outline (a step of the mirror's
    // reflectance only), inside which the mirrored edge of the table against the dark room
    // is the steeper step.
    std::optional<MirrorSphere> best;
    for (const auto& [support, circle] : circles)
        if (static_cast<double>(support) >= kOuterSupport * static_cast<double>(best_support) &&
            (!best || circle.radius > best->radius))
            best = circle;
    return best;
}

// A sphere's outline that puts its highlights where the reference sphere's directions say
// distant lamps put them: Gauss-Newton on the centre and radius with Tukey's weights. Taken
// only when the lamps are distant enough for one outline to explain every highlight (rms
// within kAlignedRmsPx, nine in ten within three times that) and it moves the outline by
// less than a quarter of its radius.
struct AlignedOutline {
    MirrorSphere sphere;
    double rms_px = 0.0;
};

std::optional<AlignedOutline> align_outline(const MirrorSphere& start, const CalibrationCamera& camera,
                                            const std::vector<std::vector<Highlight>>& highlights, std::size_t own,
                                            std::size_t reference) {
    std::vector<Eigen::Vector2d> seen;
    std::vector<Eigen::Vector3d> directions;
    for (const auto& image : highlights) {
        const Highlight& mine = image[own];
        const Highlight& theirs = image[reference];
        if (mine.status != HighlightStatus::Found || theirs.status != HighlightStatus::Found || mine.touches_rim ||
            theirs.direction.z() < -0.5)
            continue;
        seen.push_back(mine.centroid);
        directions.push_back(theirs.direction);
    }
    constexpr std::size_t kFewest = 8;
    if (seen.size() < kFewest) return std::nullopt;
    const auto residuals = [&](const Eigen::Vector3d& v, Eigen::VectorXd& out) {
        const SphereView view({v.x(), v.y(), v.z()}, camera);
        for (std::size_t i = 0; i < seen.size(); ++i)
            out.segment<2>(static_cast<Eigen::Index>(2 * i)) = view.highlight_point(directions[i]) - seen[i];
    };
    const auto n = static_cast<Eigen::Index>(2 * seen.size());
    Eigen::Vector3d x(start.centre_x, start.centre_y, start.radius);
    Eigen::VectorXd r(n), w(n);
    double sigma = 1.0;
    for (int iteration = 0; iteration < 30; ++iteration) {
        residuals(x, r);
        std::vector<float> distances(seen.size());
        for (std::size_t i = 0; i < seen.size(); ++i)
            distances[i] = static_cast<float>(r.segment<2>(static_cast<Eigen::Index>(2 * i)).norm());
        sigma = std::max(0.02, 1.4826 * static_cast<double>(quantile(distances, 0.5)));
        for (std::size_t i = 0; i < seen.size(); ++i)
            w.segment<2>(static_cast<Eigen::Index>(2 * i))
                .setConstant(tukey(static_cast<double>(distances[i]) / (4.685 * sigma)));
        const Eigen::Vector3d step = gauss_newton_step(residuals, x, r, w);
        if (!step.allFinite() || !(x.z() + step.z() > 0.0)) return std::nullopt;
        x += step;
        if (step.norm() < 1e-7) break;
    }
    residuals(x, r);
    double sum2 = 0.0;
    std::size_t close = 0;
    for (std::size_t i = 0; i < seen.size(); ++i) {
        const double d = r.segment<2>(static_cast<Eigen::Index>(2 * i)).norm();
        sum2 += d * d;
        close += d <= 3.0 * kAlignedRmsPx;
    }
    const double rms = std::sqrt(sum2 / static_cast<double>(seen.size()));
    const double moved = (x - Eigen::Vector3d(start.centre_x, start.centre_y, start.radius)).norm();
    if (rms > kAlignedRmsPx || 10 * close < 9 * seen.size() || moved > 0.25 * start.radius) return std::nullopt;
    return AlignedOutline{{x.x(), x.y(), x.z()}, rms};
}

// A spot far fainter than a sphere's highlights in the other photographs is not one: the
// lamp is hidden from the sphere and the spot is a reflection, JPEG ringing or noise.
void reject_faint(std::vector<std::vector<Highlight>>& highlights) {
    if (highlights.empty()) return;
    for (std::size_t s = 0; s < highlights.front().size(); ++s) {
        std::vector<float> contrasts;
        for (const auto& image : highlights)
            if (image[s].status == HighlightStatus::Found) contrasts.push_back(image[s].peak - image[s].background);
        if (contrasts.size() < 3) continue;
        const float typical = quantile(contrasts, 0.5);
        for (auto& image : highlights)
            if (image[s].status == HighlightStatus::Found &&
                image[s].peak - image[s].background < kFaintHighlight * typical)
                image[s].status = HighlightStatus::Faint;
    }
}

// A photograph with several bright blobs on one sphere (a glossy object's highlight mirrored
// beside the lamp's, both clipped) takes the blob the other spheres' direction confirms:
// the only one within kConfirmDeg of their mean.
void resolve_by_agreement(std::vector<Highlight>& image) {
    for (std::size_t s = 0; s < image.size(); ++s) {
        if (image[s].status != HighlightStatus::Multiple) continue;
        Eigen::Vector3d others = Eigen::Vector3d::Zero();
        for (std::size_t t = 0; t < image.size(); ++t)
            if (t != s && image[t].status == HighlightStatus::Found) others += image[t].direction;
        if (others.norm() < 1e-12) continue;
        const Highlight* confirmed = nullptr;
        int near = 0;
        for (const Highlight& candidate : image[s].alternatives)
            if (radians_to_degrees(angle_between(candidate.direction, others.normalized())) <= kConfirmDeg) {
                confirmed = &candidate;
                ++near;
            }
        if (near != 1) continue;
        Highlight chosen = *confirmed;
        chosen.alternatives.clear();
        chosen.blobs = image[s].blobs;
        chosen.chosen_by_agreement = true;
        image[s] = chosen;
    }
}

// The other spheres' readings of a photograph checked against the primary's: an ambiguous
// one resolved by agreement, then one pointing far from the primary's direction (a
// reflection taken for the lamp) set aside.
void check_against_primary(std::vector<Highlight>& image, std::size_t primary) {
    resolve_by_agreement(image);
    if (image[primary].status != HighlightStatus::Found) return;
    for (std::size_t s = 0; s < image.size(); ++s) {
        if (s == primary || image[s].status != HighlightStatus::Found) continue;
        const double off = radians_to_degrees(angle_between(image[s].direction, image[primary].direction));
        if (off > kAgreementDeg) {
            image[s].status = HighlightStatus::Inconsistent;
            image[s].off_primary_deg = off;
        }
    }
}

double median_angle_deg(const std::vector<std::vector<Highlight>>& highlights, std::size_t a, std::size_t b) {
    std::vector<float> angles;
    for (const auto& image : highlights)
        if (image[a].status == HighlightStatus::Found && image[b].status == HighlightStatus::Found)
            angles.push_back(static_cast<float>(radians_to_degrees(angle_between(image[a].direction, image[b].direction))));
    return angles.empty() ? 180.0 : static_cast<double>(quantile(angles, 0.5));
}

}  // namespace

CaptureBrightness capture_brightness(const std::vector<fs::path>& images) {
    RFD_CHECK(!images.empty());
    CaptureBrightness out;
    {
        const ImageBandReader first(images.front());
        out.size = {first.width(), first.height()};
    }
    const std::size_t area = out.size.area();
    std::vector<float> sum(area, 0.0f);
    out.max.assign(area, 0.0f);
    // A few photographs decode at once, then add in order: the sums do not depend on the
    // thread count, and memory holds a few planes, not the capture.
    const auto group = static_cast<std::size_t>(std::clamp(tbb::this_task_arena::max_concurrency(), 1, 4));
    Progress progress("reading the photographs", images.size());
    for (std::size_t start = 0; start < images.size(); start += group) {
        const std::size_t count = std::min(group, images.size() - start);
        std::vector<std::vector<float>> planes(count);
        std::vector<std::exception_ptr> failures(count);
        parallel_for_chunks(count, 1, [&](std::size_t begin, std::size_t end) {
            for (std::size_t i = begin; i < end; ++i) {
                try {
                    planes[i] = brightness_plane(images[start + i], out.size);
                } catch (...) {
                    failures[i] = std::current_exception();
                }
                progress.advance();
            }
        });
        for (const auto& failure : failures)
            if (failure) std::rethrow_exception(failure);
        for (const auto& plane : planes)
            for (std::size_t p = 0; p < area; ++p) {
                sum[p] += plane[p];
                out.max[p] = std::max(out.max[p], plane[p]);
            }
    }
    progress.finish();
    const float scale = 1.0f / static_cast<float>(images.size());
    out.mean.resize(area);
    for (std::size_t p = 0; p < area; ++p) out.mean[p] = sum[p] * scale;
    return out;
}

std::vector<MirrorSphere> find_sphere_candidates(const CaptureBrightness& b) {
    const int longest = std::max(b.size.width, b.size.height);
    const int factor = std::max(1, (longest + kDetectionWidth - 1) / kDetectionWidth);
    const PlaneSize small{std::max(1, b.size.width / factor), std::max(1, b.size.height / factor)};
    std::vector<float> mean = b.mean;
    if (factor > 1) {
        mean.assign(small.area(), 0.0f);
        vision().resize(b.size, b.mean, small, mean);
    }
    const float top = quantile(mean, 0.995);
    if (!(top > 0.0f)) return {};
    for (float& v : mean) v = std::min(v / top, 1.0f);
    std::vector<std::uint8_t> codes(mean.size());
    encode_srgb8(mean, codes);
    const int shortest = std::min(small.width, small.height);
    const int min_radius = std::max(5, shortest / 100), max_radius = std::max(min_radius + 1, shortest / 4);
    const auto circles = vision().hough_circles(small, codes, min_radius, 150.0, 0.7, min_radius, max_radius);

    std::vector<MirrorSphere> candidates;
    for (const auto& c : circles) {
        const MirrorSphere circle{static_cast<double>(c[0]) * factor, static_cast<double>(c[1]) * factor,
                                  static_cast<double>(c[2]) * factor};
        // Specular: the maximum's brightest percent over the inner disc against the mean's median.
        std::vector<float> max_inside, mean_inside;
        const double inner = 0.7 * circle.radius;
        const int x0 = std::max(0, static_cast<int>(circle.centre_x - inner));
        const int x1 = std::min(b.size.width, static_cast<int>(circle.centre_x + inner) + 1);
        const int y0 = std::max(0, static_cast<int>(circle.centre_y - inner));
        const int y1 = std::min(b.size.height, static_cast<int>(circle.centre_y + inner) + 1);
        for (int y = y0; y < y1; ++y)
            for (int x = x0; x < x1; ++x) {
                const double dx = x + 0.5 - circle.centre_x, dy = y + 0.5 - circle.centre_y;
                if (dx * dx + dy * dy > inner * inner) continue;
                const std::size_t p = static_cast<std::size_t>(y) * static_cast<std::size_t>(b.size.width) +
                                      static_cast<std::size_t>(x);
                max_inside.push_back(b.max[p]);
                mean_inside.push_back(b.mean[p]);
            }
        if (max_inside.size() < 20) continue;
        const double body = std::max(static_cast<double>(quantile(mean_inside, 0.5)), 1e-4 * static_cast<double>(top));
        const double spots = quantile(max_inside, 0.99);
        if (spots / body >= kSpecularContrast) candidates.push_back(circle);
    }
    return candidates;
}

std::optional<OutlineFit> fit_sphere_outline(const CaptureBrightness& b, const MirrorSphere& rough,
                                             const CalibrationCamera& camera) {
    MirrorSphere current = rough;
    OutlineFit fit;
    for (int pass = 0; pass < 3; ++pass) {
        // The rough circle may be off by a tenth of its radius or more (a chrome ball's faint
        // outline); the ones fitted since are good to a pixel.
        const double half_window = std::max(3.0, current.radius / (pass == 0 ? 4.0 : 6.0));
        const Eigen::Vector2d centre(current.centre_x, current.centre_y);
        const int rays = std::clamp(static_cast<int>(std::lround(2.0 * std::numbers::pi * current.radius)), 64, 1440);
        const std::vector<RayEdges> found = edges_along_rays(b, centre, current.radius - half_window,
                                                             current.radius + half_window, rays);
        std::vector<Eigen::Vector2d> edges;
        if (pass == 0) {
            // From the rough circle, the circle of steps that the most rays cross (RANSAC over
            // triples of steps on rays far apart): its centre is the sphere's even when it
            // is an inner ring of a chrome ball's reflections. Its own steps seed the fit.
            const std::optional<MirrorSphere> circle = most_crossed_circle(found, centre, current.radius);
            if (!circle) return std::nullopt;
            const Eigen::Vector2d c(circle->centre_x, circle->centre_y);
            for (const RayEdges& ray : found)
                for (const auto& e : ray.edges) {
                    const Eigen::Vector2d p = centre + e.first * ray.direction;
                    if (std::abs((p - c).norm() - circle->radius) <= 1.0) edges.push_back(p);
                }
        } else {
            // About the outline fitted, each ray's outermost step within a pixel and a half.
            for (const RayEdges& ray : found)
                for (auto e = ray.edges.rbegin(); e != ray.edges.rend(); ++e)
                    if (std::abs(e->first - current.radius) <= 1.5) {
                        edges.push_back(centre + e->first * ray.direction);
                        break;
                    }
        }
        if (edges.size() < 16) return std::nullopt;
        fit = robust_outline(edges, current, camera, static_cast<int>(found.size()));
        if (!(fit.sphere.radius > 0.0) || !std::isfinite(fit.sphere.centre_x) || !std::isfinite(fit.sphere.centre_y))
            return std::nullopt;
        current = fit.sphere;
    }
    return fit;
}

CaptureCalibration calibrate_capture(const std::vector<fs::path>& images, const SphereCalibrationOptions& options) {
    RFD_CHECK(!images.empty());
    CaptureCalibration result;
    PlaneSize size;
    {
        const ImageBandReader first(images.front());
        size = {first.width(), first.height()};
    }
    std::vector<CalibrationSphere> spheres;
    if (options.spheres.empty()) {
        const CaptureBrightness brightness = capture_brightness(images);
        const std::vector<MirrorSphere> candidates = find_sphere_candidates(brightness);
        result.candidates = static_cast<int>(candidates.size());
        std::vector<OutlineFit> fits;
        for (const MirrorSphere& candidate : candidates) {
            const std::optional<OutlineFit> fit = fit_sphere_outline(brightness, candidate, options.camera);
            if (fit && fit->edges >= kEdgeFraction * fit->rays) fits.push_back(*fit);
        }
        // One sphere, one outline: of circles centred inside one another, the one whose
        // edges fit best (the largest share of rays, then the smallest scatter).
        std::stable_sort(fits.begin(), fits.end(), [](const OutlineFit& a, const OutlineFit& b) {
            const double share_a = static_cast<double>(a.edges) / a.rays, share_b = static_cast<double>(b.edges) / b.rays;
            if (std::abs(share_a - share_b) > 0.02) return share_a > share_b;
            return a.rms_px < b.rms_px;
        });
        for (const OutlineFit& fit : fits) {
            const bool seen = std::any_of(spheres.begin(), spheres.end(), [&](const CalibrationSphere& s) {
                return std::hypot(s.outline.centre_x - fit.sphere.centre_x, s.outline.centre_y - fit.sphere.centre_y) <
                       std::max(s.outline.radius, fit.sphere.radius);
            });
            if (!seen) spheres.push_back({fit.sphere, fit, 0});
        }
    } else {
        for (const MirrorSphere& sphere : options.spheres) {
            if (!(std::isfinite(sphere.centre_x) && std::isfinite(sphere.centre_y) && std::isfinite(sphere.radius) &&
                  sphere.radius > 0.0))
                throw InputError("mirror sphere: expected a finite centre and a positive radius in pixels, got (" +
                                 format_number(sphere.centre_x) + ", " + format_number(sphere.centre_y) +
                                 ") radius " + format_number(sphere.radius));
            if (sphere.centre_x - sphere.radius < 0.0 || sphere.centre_y - sphere.radius < 0.0 ||
                sphere.centre_x + sphere.radius > size.width || sphere.centre_y + sphere.radius > size.height)
                throw InputError(SourceLocation{images.front().string()},
                                 "the mirror sphere (centre " + format_number(sphere.centre_x) + ", " +
                                     format_number(sphere.centre_y) + ", radius " + format_number(sphere.radius) +
                                     " px) does not fit inside this " + std::to_string(size.width) + "x" +
                                     std::to_string(size.height) + " image");
            spheres.push_back({sphere, std::nullopt, 0});
        }
    }
    if (spheres.empty())
        throw InputError("no calibration sphere found in the " + std::to_string(images.size()) + " photographs (" +
                         std::to_string(result.candidates) +
                         " circles looked specular; none had a clean outline): give its outline with --sphere CX,CY,R");

    std::vector<MirrorSphere> outlines;
    for (const auto& s : spheres) outlines.push_back(s.outline);
    std::vector<std::vector<Highlight>> highlights = read_highlights(images, outlines, options.camera, size);
    reject_faint(highlights);
    for (std::size_t s = 0; s < spheres.size(); ++s)
        for (const auto& image : highlights)
            if (image[s].status == HighlightStatus::Found) ++spheres[s].highlights;

    std::vector<std::size_t> kept;
    if (options.spheres.empty()) {
        // A detected sphere shows a highlight in most photographs; of several, the ones whose
        // lights agree with the most others' are the calibration.
        std::vector<std::size_t> lit;
        for (std::size_t s = 0; s < spheres.size(); ++s)
            if (2 * spheres[s].highlights >= static_cast<int>(images.size())) lit.push_back(s);
        std::size_t anchor = lit.empty() ? 0 : lit.front();
        int most = -1;
        for (const std::size_t a : lit) {
            int agreeing = 0;
            for (const std::size_t b : lit)
                if (b != a && median_angle_deg(highlights, a, b) <= kAgreementDeg) ++agreeing;
            if (agreeing > most || (agreeing == most && spheres[a].highlights > spheres[anchor].highlights)) {
                most = agreeing;
                anchor = a;
            }
        }
        for (const std::size_t s : lit)
            if (s == anchor || median_angle_deg(highlights, anchor, s) <= kAgreementDeg) kept.push_back(s);
        if (kept.empty())
            throw InputError("no calibration sphere found: of " + std::to_string(spheres.size()) +
                             " round outlines, none shows a highlight in half the photographs or more; give the "
                             "sphere's outline with --sphere CX,CY,R");
    } else {
        for (std::size_t s = 0; s < spheres.size(); ++s) kept.push_back(s);
    }

    for (const std::size_t s : kept) result.spheres.push_back(spheres[s]);
    result.primary = 0;  // given spheres: the first
    if (options.spheres.empty()) {
        // The crispest outline gives the directions: a chrome ball's outline against a table
        // it mirrors is found to about a pixel, a black ball's to a fifth of one.
        for (std::size_t s = 1; s < result.spheres.size(); ++s)
            if (result.spheres[s].fit->rms_px < result.spheres[static_cast<std::size_t>(result.primary)].fit->rms_px)
                result.primary = static_cast<int>(s);
    }
    const auto primary = static_cast<std::size_t>(result.primary);
    std::vector<std::vector<Highlight>> used(images.size());
    for (std::size_t i = 0; i < images.size(); ++i) {
        for (const std::size_t s : kept) used[i].push_back(highlights[i][s]);
        check_against_primary(used[i], primary);
    }
    if (options.spheres.empty()) {
        // The others' outlines, aligned to its lights where distant lamps explain their
        // highlights to a fraction of a pixel; then their highlights are read again.
        bool aligned = false;
        for (std::size_t s = 0; s < result.spheres.size(); ++s) {
            if (static_cast<int>(s) == result.primary) continue;
            const auto fit = align_outline(result.spheres[s].outline, options.camera, used, s, primary);
            if (!fit) continue;
            result.spheres[s].outline = fit->sphere;
            result.spheres[s].aligned_rms_px = fit->rms_px;
            aligned = true;
        }
        if (aligned) {
            std::vector<MirrorSphere> kept_outlines;
            for (const auto& sphere : result.spheres) kept_outlines.push_back(sphere.outline);
            used = read_highlights(images, kept_outlines, options.camera, size);
            reject_faint(used);
            for (auto& image : used) check_against_primary(image, primary);
        }
    }
    for (std::size_t s = 0; s < result.spheres.size(); ++s) {
        result.spheres[s].highlights = 0;
        for (const auto& image : used)
            if (image[s].status == HighlightStatus::Found) ++result.spheres[s].highlights;
    }
    std::vector<SphereView> views;
    for (const auto& sphere : result.spheres) views.emplace_back(sphere.outline, options.camera);
    const Eigen::Vector3d object = object_point(views);
    for (const auto& image : used) {
        CalibratedImageLight light;
        light.highlights = image;
        Eigen::Vector3d sum = Eigen::Vector3d::Zero();
        for (std::size_t a = 0; a < light.highlights.size(); ++a) {
            const Highlight& h = light.highlights[a];
            if (h.status != HighlightStatus::Found) continue;
            sum += h.direction;
            ++light.spheres_used;
            for (std::size_t b = 0; b < a; ++b)
                if (light.highlights[b].status == HighlightStatus::Found)
                    light.disagreement_deg = std::max(
                        light.disagreement_deg, radians_to_degrees(angle_between(light.highlights[b].direction, h.direction)));
        }
        if (result.primary >= 0 && light.highlights[static_cast<std::size_t>(result.primary)].status == HighlightStatus::Found)
            light.direction = light.highlights[static_cast<std::size_t>(result.primary)].direction;
        else if (light.spheres_used > 0 && sum.norm() > 1e-12)
            light.direction = sum.normalized();
        if (views.size() > 1) light.lamp = near_light(views, light.highlights);
        if (options.near_lamps && light.lamp && !light.lamp->distant)
            light.direction = (light.lamp->position - object).normalized();
        result.lights.push_back(std::move(light));
    }
    return result;
}

Eigen::Vector3d object_point(const std::vector<SphereView>& spheres) {
    RFD_CHECK(!spheres.empty());
    if (spheres.front().camera().orthographic()) {
        // Depth unknown: the spheres' mean position, one radius below their centres.
        Eigen::Vector3d mean = Eigen::Vector3d::Zero();
        for (const SphereView& view : spheres) mean += view.centre();
        return mean / static_cast<double>(spheres.size()) - Eigen::Vector3d::UnitZ();
    }
    double depth = 0.0;
    for (const SphereView& view : spheres) depth += -view.centre().z();
    depth = depth / static_cast<double>(spheres.size()) + 1.0;
    // Where the camera's axis meets the plane of the spheres' lowest points.
    const Eigen::Vector3d axis = spheres.front().camera().ray(spheres.front().camera().principal_point);
    return axis * (depth / -axis.z());
}

std::vector<CalibratedLight> calibrate_lights(const std::vector<fs::path>& mirror_images, const MirrorSphere& sphere,
                                              const CalibrationCamera& camera) {
    const CaptureCalibration calibration = calibrate_capture(mirror_images, {camera, {sphere}});
    std::vector<CalibratedLight> lights;
    for (std::size_t i = 0; i < mirror_images.size(); ++i) {
        const Highlight& h = calibration.lights[i].highlights.front();
        if (h.status != HighlightStatus::Found)
            throw InputError(SourceLocation{mirror_images[i].string()}, highlight_problem(h));
        lights.push_back({mirror_images[i], h});
    }
    return lights;
}

std::optional<NearLight> near_light(const std::vector<SphereView>& spheres, const std::vector<Highlight>& highlights) {
    RFD_CHECK(spheres.size() == highlights.size());
    Eigen::Matrix3d a = Eigen::Matrix3d::Zero();
    Eigen::Vector3d rhs = Eigen::Vector3d::Zero(), mean_centre = Eigen::Vector3d::Zero();
    int used = 0;
    for (std::size_t s = 0; s < spheres.size(); ++s) {
        if (highlights[s].status != HighlightStatus::Found) continue;
        const Eigen::Vector3d d = highlights[s].direction;
        const Eigen::Matrix3d across = Eigen::Matrix3d::Identity() - d * d.transpose();
        a += across;
        rhs += across * spheres[s].centre();
        mean_centre += spheres[s].centre();
        ++used;
    }
    if (used < 2) return std::nullopt;
    mean_centre /= used;
    NearLight light;
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(a);
    // Parallel rays leave the normal matrix singular along them: the lamp is at infinity.
    if (eigen.eigenvalues()(0) < 1e-9 * eigen.eigenvalues()(2)) {
        light.distant = true;
        return light;
    }
    light.position = a.ldlt().solve(rhs);
    double sum2 = 0.0;
    for (std::size_t s = 0; s < spheres.size(); ++s) {
        if (highlights[s].status != HighlightStatus::Found) continue;
        const Eigen::Vector3d d = highlights[s].direction;
        const Eigen::Vector3d offset = light.position - spheres[s].centre();
        sum2 += (offset - offset.dot(d) * d).squaredNorm();
        if (offset.dot(d) <= 0.0) light.distant = true;  // behind a sphere: the rays diverge
    }
    light.residual_rms = std::sqrt(sum2 / used);
    light.distance = (light.position - mean_centre).norm();
    return light;
}

}  // namespace rfd::relight
