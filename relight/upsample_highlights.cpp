// The highlights of upsample.hpp: detection (the masks M_i) and removal (D_i, H_i), the
// layers carried half-way (compact highlights matched and moved rigidly, one-sided glints kept
// in place, the rest by optical flow), the light kernels' overlap weights, and the glossy lobes.
#include "relight/upsample_highlights.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numeric>
#include <optional>
#include <span>
#include <utility>

#include <Eigen/Dense>

#include "core/error.hpp"
#include "core/parallel.hpp"
#include "core/sphere.hpp"
#include "core/units.hpp"
#include "relight/upsample_features.hpp"
#include "relight/vision.hpp"

namespace rfd::relight {
namespace {

using upsampling::all_zero;
using upsampling::dense_flow;
using upsampling::Node;
using upsampling::size_of;
using upsampling::warp_along;

// The clamped highlight luminance the flow matches on: HDR highlights span decades, so
// everything above the median highlight level `clamp` is one plateau (6.3.1).
std::vector<std::uint8_t> flow_input(const Image& luminance, float clamp) {
    const auto values = luminance.plane(0);
    std::vector<std::uint8_t> out(values.size());
    for (std::size_t p = 0; p < values.size(); ++p) {
        const float v = std::clamp(values[p] / clamp, 0.0f, 1.0f);
        out[p] = static_cast<std::uint8_t>(std::lround(255.0f * v));
    }
    return out;
}

// Scales `warped` to the total of `original`, channel by channel.
void conserve_energy(Image& warped, const Image& original) {
    for (int c = 0; c < warped.channels(); ++c) {
        double before = 0.0, after = 0.0;
        for (float v : original.plane(c)) before += v;
        for (float v : warped.plane(c)) after += v;
        if (after > 0.0 && before > 0.0)
            for (float& v : warped.plane(c)) v = static_cast<float>(v * (before / after));
    }
}

// A connected highlight of one layer: its component label, energy-weighted centroid, total
// luminance and bounding box (inclusive).
struct Blob {
    int label = 0;
    double x = 0.0, y = 0.0, energy = 0.0;
    int x0 = 0, y0 = 0, x1 = -1, y1 = -1;
};

// The component label of every pixel of a layer, 0 where it is dark.
struct Labels {
    int width = 0;
    std::vector<int> ids;
    int at(int x, int y) const {
        return ids[static_cast<std::size_t>(y) * static_cast<std::size_t>(width) + static_cast<std::size_t>(x)];
    }
};

std::vector<Blob> blobs_of(const Image& luminance, Labels& labels) {
    const auto l = luminance.plane(0);
    std::vector<std::uint8_t> lit(l.size());
    for (std::size_t p = 0; p < l.size(); ++p) lit[p] = l[p] > 0.0f ? 255 : 0;
    labels.width = luminance.width();
    labels.ids.assign(l.size(), 0);
    const int count = vision().connected_components(size_of(luminance), lit, labels.ids);
    std::vector<Blob> blobs(static_cast<std::size_t>(count));
    for (Blob& b : blobs) {
        b.x0 = luminance.width();
        b.y0 = luminance.height();
    }
    for (int y = 0; y < luminance.height(); ++y)
        for (int x = 0; x < luminance.width(); ++x) {
            const int k = labels.at(x, y);
            if (k == 0) continue;
            const double v = luminance.at(x, y, 0);
            Blob& b = blobs[static_cast<std::size_t>(k)];
            b.label = k;
            b.energy += v;
            b.x += v * x;
            b.y += v * y;
            b.x0 = std::min(b.x0, x);
            b.y0 = std::min(b.y0, y);
            b.x1 = std::max(b.x1, x);
            b.y1 = std::max(b.y1, y);
        }
    std::vector<Blob> kept;
    for (Blob& b : blobs)
        if (b.energy > 0.0) {
            b.x /= b.energy;
            b.y /= b.energy;
            kept.push_back(b);
        }
    return kept;
}

std::size_t nearest_blob(const Blob& from, const std::vector<Blob>& to) {
    std::size_t best = to.size();
    double best_distance = std::numeric_limits<double>::infinity();
    for (std::size_t j = 0; j < to.size(); ++j) {
        const double d = std::hypot(to[j].x - from.x, to[j].y - from.y);
        if (d < best_distance) {
            best_distance = d;
            best = j;
        }
    }
    return best;
}

// Adds weight x the pixels of `blob` in `image`, moved by (dx, dy) and spread bilinearly
// over the four pixels around where each lands, so that the energy is kept exactly. `out`
// covers the image from (origin_x, origin_y) on; what lands outside it is dropped.
void splat(const Image& image, const Labels& labels, const Blob& blob, double dx, double dy, float weight,
           Image& out, int origin_x = 0, int origin_y = 0) {
    const int shift_x = static_cast<int>(std::floor(dx)), shift_y = static_cast<int>(std::floor(dy));
    const auto fx = static_cast<float>(dx - shift_x), fy = static_cast<float>(dy - shift_y);
    const std::array<float, 4> share = {(1 - fx) * (1 - fy), fx * (1 - fy), (1 - fx) * fy, fx * fy};
    for (int y = blob.y0; y <= blob.y1; ++y)
        for (int x = blob.x0; x <= blob.x1; ++x) {
            if (labels.at(x, y) != blob.label) continue;
            for (int q = 0; q < 4; ++q) {
                const int tx = x + shift_x + q % 2 - origin_x, ty = y + shift_y + q / 2 - origin_y;
                if (share[static_cast<std::size_t>(q)] == 0.0f || tx < 0 || ty < 0 || tx >= out.width() ||
                    ty >= out.height())
                    continue;
                const float w = weight * share[static_cast<std::size_t>(q)];
                for (int c = 0; c < image.channels(); ++c) out.at(tx, ty, c) += w * image.at(x, y, c);
            }
        }
}

// How well blob p of luminance la, moved by the offset between the two centroids, lands on
// blob q of lb: the sum of min(p', q') over pixels, p' and q' the two blurred by a 3 x 3
// box (a glint of a pixel or two is sampled differently at two light directions) and
// scaled to unit energy. 1 for the same shape, 0 for disjoint ones.
double moved_shape_agreement(const Image& la, const Labels& labels_a, const Blob& p, const Image& lb,
                             const Labels& labels_b, const Blob& q) {
    // Both, over a box holding every pixel p lands on and a margin for the blur.
    const double dx = q.x - p.x, dy = q.y - p.y;
    const int ix = static_cast<int>(std::floor(dx)), iy = static_cast<int>(std::floor(dy));
    const int x0 = std::min(q.x0, p.x0 + ix) - 2, y0 = std::min(q.y0, p.y0 + iy) - 2;
    const int x1 = std::max(q.x1, p.x1 + ix + 1) + 2, y1 = std::max(q.y1, p.y1 + iy + 1) + 2;
    Image moved_image(x1 - x0 + 1, y1 - y0 + 1, 1), target_image(x1 - x0 + 1, y1 - y0 + 1, 1);
    splat(la, labels_a, p, dx, dy, 1.0f, moved_image, x0, y0);
    splat(lb, labels_b, q, 0.0, 0.0, 1.0f, target_image, x0, y0);
    const auto moved = moved_image.plane(0), target = target_image.plane(0);
    vision().box_blur(size_of(moved_image), moved, 3);
    vision().box_blur(size_of(target_image), target, 3);
    const double sum_moved = std::accumulate(moved.begin(), moved.end(), 0.0);
    const double sum_target = std::accumulate(target.begin(), target.end(), 0.0);
    if (!(sum_moved > 0.0) || !(sum_target > 0.0)) return 0.0;
    double shared = 0.0;
    for (std::size_t k = 0; k < moved.size(); ++k) shared += std::min(moved[k] / sum_moved, target[k] / sum_target);
    return shared;
}

// Where the lights of an edge overlap, a highlight may not move at all: a mirror pixel lit
// at both ends is lit half-way too (the lens two overlapping discs share lies inside the
// midpoint's disc), and one lit at one end only is lit there with one_sided_weight.
Image in_place_highlights(const Image& a, const Image& b, float one_sided_weight) {
    Image out(a.width(), a.height(), a.channels());
    for (std::size_t p = 0; p < a.pixel_count(); ++p) {
        bool lit_a = false, lit_b = false;
        for (int c = 0; c < a.channels(); ++c) {
            lit_a = lit_a || a.plane(c)[p] > 0.0f;
            lit_b = lit_b || b.plane(c)[p] > 0.0f;
        }
        const float weight = lit_a && lit_b ? 0.5f : one_sided_weight;
        for (int c = 0; c < a.channels(); ++c) out.plane(c)[p] = weight * (a.plane(c)[p] + b.plane(c)[p]);
    }
    return out;
}

// How far each luminance layer, carried all the way along its flow, lands from the other,
// against how far the two differ unmoved; both as sums of absolute differences. A flow that
// does not beat standing still explains nothing.
std::pair<double, double> flow_and_still_misfit(const Image& la, const Image& lb, std::span<const float> flow_ab,
                                                 std::span<const float> flow_ba) {
    const Image a_at_b = warp_along(la, flow_ab, 1.0f), b_at_a = warp_along(lb, flow_ba, 1.0f);
    double flow = 0.0, still = 0.0;
    for (std::size_t p = 0; p < la.pixel_count(); ++p) {
        const double va = la.plane(0)[p], vb = lb.plane(0)[p];
        flow += std::abs(a_at_b.plane(0)[p] - vb) + std::abs(b_at_a.plane(0)[p] - va);
        still += 2.0 * std::abs(va - vb);
    }
    return {flow, still};
}

// Half-way by dense optical flow both ways; either layer may be all zero (the other is then
// scaled by one_sided_weight). With `lights_overlap`, layers that the flow carries onto each
// other no better than they already lie stay in place (in_place_highlights).
Image halfway_by_flow(const Image& a, const Image& b, float one_sided_weight, bool lights_overlap) {
    const bool a_empty = all_zero(a), b_empty = all_zero(b);
    Image out(a.width(), a.height(), a.channels());
    if (a_empty && b_empty) return out;
    // A highlight that appears or vanishes has nothing to match: it stays, weighted.
    if (a_empty || b_empty) {
        const Image& only = a_empty ? b : a;
        for (std::size_t s = 0; s < out.samples().size(); ++s) out.samples()[s] = one_sided_weight * only.samples()[s];
        return out;
    }
    const Image la = luminance(a), lb = luminance(b);
    std::vector<float> levels;
    for (const Image* l : {&la, &lb})
        for (float v : l->plane(0))
            if (v > 0.0f) levels.push_back(v);
    std::nth_element(levels.begin(), levels.begin() + static_cast<std::ptrdiff_t>(levels.size() / 2), levels.end());
    const float clamp = levels[levels.size() / 2];

    // Blurred, so that highlights of a few pixels give the flow's polynomials a slope to fit.
    const PlaneSize size = size_of(la);
    std::vector<std::uint8_t> ga = flow_input(la, clamp), gb = flow_input(lb, clamp);
    vision().gaussian_blur(size, ga, ga, 3.0);
    vision().gaussian_blur(size, gb, gb, 3.0);
    const std::vector<float> flow_ab = dense_flow(size, ga, gb), flow_ba = dense_flow(size, gb, ga);
    if (lights_overlap) {
        const auto [flow_misfit, still_misfit] = flow_and_still_misfit(la, lb, flow_ab, flow_ba);
        if (!(flow_misfit < still_misfit)) return in_place_highlights(a, b, one_sided_weight);
    }
    Image wa = warp_along(a, flow_ab), wb = warp_along(b, flow_ba);
    // A backward warp stretches where the flow diverges; a highlight carries its energy.
    conserve_energy(wa, a);
    conserve_energy(wb, b);
    for (std::size_t s = 0; s < out.samples().size(); ++s)
        out.samples()[s] = 0.5f * (wa.samples()[s] + wb.samples()[s]);
    return out;
}

// True where the highlight layer of `node` shows something at pixel p.
bool shows_highlight(const Node& node, std::size_t p) {
    if (node.highlights.empty()) return false;
    for (int c = 0; c < node.highlights.channels(); ++c)
        if (node.highlights.plane(c)[p] > 0.0f) return true;
    return false;
}

}  // namespace

std::vector<std::uint8_t> highlight_mask(const Image& luminance, const Image& percentile, double f_highlight,
                                         int dilation, float floor) {
    const auto l = luminance.plane(0);
    const auto level = percentile.plane(0);
    std::vector<std::uint8_t> mask(l.size());
    for (std::size_t p = 0; p < l.size(); ++p)
        mask[p] = l[p] > floor && static_cast<double>(l[p]) >= f_highlight * static_cast<double>(level[p]) ? 1 : 0;
    if (dilation > 1) vision().dilate(size_of(luminance), mask, dilation);
    return mask;
}

Image remove_highlights(const Image& image, const std::vector<std::uint8_t>& mask) {
    Image out = image;
    if (std::none_of(mask.begin(), mask.end(), [](std::uint8_t v) { return v != 0; })) return out;
    std::vector<float> filled(image.pixel_count());
    for (int c = 0; c < image.channels(); ++c) {
        // Navier-Stokes inpainting (Bertalmio et al. 2001): OpenCV 4.6's Telea method returns
        // values far off the surroundings for float images (see tests/test_upsample.cpp).
        vision().inpaint(size_of(image), image.plane(c), mask, 3.0, filled);
        // D <= R: inpainting that overshoots the image would give negative highlights.
        auto dst = out.plane(c);
        for (std::size_t p = 0; p < dst.size(); ++p) dst[p] = std::min(dst[p], filled[p]);
    }
    return out;
}

Image halfway_highlights(const Image& first, const Image& second, double blob_reach, double one_sided_weight,
                         bool lights_overlap) {
    if (first.empty() && second.empty()) return {};
    const Image& shape = first.empty() ? second : first;
    const Image zero(shape.width(), shape.height(), shape.channels());
    const Image& a = first.empty() ? zero : first;
    const Image& b = second.empty() ? zero : second;
    if (!a.same_shape(b)) throw InputError("highlight layers of different shapes");

    // Compact highlights that are each other's nearest within blob_reach pixels, of similar
    // energy, are one highlight that moved: each is carried rigidly half-way to the other.
    // A highlight of a few pixels gives the flow almost nothing to fit (its images barely
    // overlap), yet its centroid is exact.
    Labels labels_a, labels_b;
    const Image luminance_a = luminance(a), luminance_b = luminance(b);
    const std::vector<Blob> blobs_a = blobs_of(luminance_a, labels_a), blobs_b = blobs_of(luminance_b, labels_b);
    Image out(a.width(), a.height(), a.channels());
    std::vector<bool> handled_a(blobs_a.size(), false), handled_b(blobs_b.size(), false);
    for (std::size_t i = 0; i < blobs_a.size() && blob_reach > 0.0; ++i) {
        const Blob& p = blobs_a[i];
        const std::size_t j = nearest_blob(p, blobs_b);
        if (j == blobs_b.size() || nearest_blob(blobs_b[j], blobs_a) != i) continue;
        const Blob& q = blobs_b[j];
        const double ratio = p.energy / q.energy;
        if (std::hypot(q.x - p.x, q.y - p.y) > blob_reach || ratio < 0.25 || ratio > 4.0) continue;
        // Moved rigidly, the one must land on the other; a highlight that changes shape
        // (a glossy streak that splits, grows or bends) goes to the flow instead.
        if (moved_shape_agreement(luminance_a, labels_a, p, luminance_b, labels_b, q) < 0.5) continue;
        handled_a[i] = handled_b[j] = true;
        splat(a, labels_a, p, 0.5 * (q.x - p.x), 0.5 * (q.y - p.y), 0.5f, out);
        splat(b, labels_b, q, 0.5 * (p.x - q.x), 0.5 * (p.y - q.y), 0.5f, out);
    }
    // A highlight with nothing of the other layer within blob_reach of it is seen from one
    // side only: it stays where it is, weighted by the chance that the new direction still
    // lights it (one_sided_highlight_weight). Blending would smear it over the whole edge.
    const auto isolate = [&](const Image& layer, const Labels& labels, const std::vector<Blob>& blobs,
                             std::vector<bool>& handled, const Image& other) {
        if (blob_reach <= 0.0) return;
        const int r = static_cast<int>(std::ceil(blob_reach));
        for (std::size_t k = 0; k < blobs.size(); ++k) {
            if (handled[k]) continue;
            const Blob& blob = blobs[k];
            bool near = false;
            for (int y = std::max(0, blob.y0 - r); y <= std::min(other.height() - 1, blob.y1 + r) && !near; ++y)
                for (int x = std::max(0, blob.x0 - r); x <= std::min(other.width() - 1, blob.x1 + r) && !near; ++x)
                    near = other.at(x, y, 0) > 0.0f;
            if (near) continue;
            handled[k] = true;
            splat(layer, labels, blob, 0.0, 0.0, static_cast<float>(one_sided_weight), out);
        }
    };
    isolate(a, labels_a, blobs_a, handled_a, luminance_b);
    isolate(b, labels_b, blobs_b, handled_b, luminance_a);
    // Everything else (large, merging or splitting highlights, caustics) goes to the flow.
    const auto unhandled = [](const Image& layer, const Labels& labels, const std::vector<Blob>& blobs,
                              const std::vector<bool>& handled) {
        Image rest = layer;
        for (std::size_t k = 0; k < blobs.size(); ++k)
            if (handled[k])
                for (int y = blobs[k].y0; y <= blobs[k].y1; ++y)
                    for (int x = blobs[k].x0; x <= blobs[k].x1; ++x)
                        if (labels.at(x, y) == blobs[k].label)
                            for (int c = 0; c < rest.channels(); ++c) rest.at(x, y, c) = 0.0f;
        return rest;
    };
    const Image flowed = halfway_by_flow(unhandled(a, labels_a, blobs_a, handled_a),
                                         unhandled(b, labels_b, blobs_b, handled_b),
                                         static_cast<float>(one_sided_weight), lights_overlap);
    for (std::size_t s = 0; s < out.samples().size(); ++s) out.samples()[s] += flowed.samples()[s];
    return out;
}

double one_sided_highlight_weight(double distance, double kernel_radius) {
    if (!(distance > 0.0)) return 1.0;
    const double x = distance / (2.0 * kernel_radius);
    if (!(x < 1.0)) return 0.0;
    return 2.0 / kPi * (std::acos(x) - x * std::sqrt(1.0 - x * x));
}

double midpoint_highlight_weight(double edge, double kernel_radius) {
    const double whole = one_sided_highlight_weight(edge, kernel_radius);
    // The lens both discs share lies inside the midpoint's disc, so what the midpoint sees of
    // one end's disc outside the other is the overlap at half the edge less the lens.
    if (!(whole < 1.0)) return 0.5;  // the two lights coincide: the limit of the ratio
    return std::clamp((one_sided_highlight_weight(0.5 * edge, kernel_radius) - whole) / (1.0 - whole), 0.0, 1.0);
}

double HighlightLobe::operator()(const Eigen::Vector3d& light) const {
    return std::min(std::exp(log_scale + sharpness_axis.dot(light)), 2.0 * brightest);
}

double HighlightLobe::angular_width() const { return 1.0 / std::sqrt(sharpness_axis.norm()); }

std::optional<HighlightLobe> fit_highlight_lobe(const std::vector<Eigen::Vector3d>& directions,
                                                const std::vector<double>& values, std::size_t min_samples,
                                                double max_spread) {
    if (directions.size() != values.size()) throw InputError("a lobe needs one value per direction");
    // log h = log_scale + v . l is linear in (log_scale, v): one weighted least-squares solve.
    Eigen::Matrix4d normal = Eigen::Matrix4d::Zero();
    Eigen::Vector4d rhs = Eigen::Vector4d::Zero();
    double brightest = 0.0;
    std::size_t used = 0;
    const auto usable = [](double h) { return h > 0.0 && std::isfinite(h); };
    for (std::size_t s = 0; s < values.size(); ++s) {
        const double h = values[s];
        if (!usable(h)) continue;
        const Eigen::Vector4d basis(1.0, directions[s].x(), directions[s].y(), directions[s].z());
        normal += h * basis * basis.transpose();
        rhs += h * std::log(h) * basis;
        brightest = std::max(brightest, h);
        ++used;
    }
    if (used < std::max<std::size_t>(min_samples, 4)) return std::nullopt;
    const Eigen::Vector4d solution = normal.ldlt().solve(rhs);
    HighlightLobe lobe;
    lobe.log_scale = solution[0];
    lobe.sharpness_axis = solution.tail<3>();
    lobe.brightest = brightest;
    const double sharpness = lobe.sharpness_axis.norm();
    if (!solution.allFinite() || !(sharpness >= 1.0)) return std::nullopt;
    const Eigen::Vector3d axis = lobe.sharpness_axis / sharpness;
    for (std::size_t s = 0; s < values.size(); ++s)
        if (usable(values[s]) && angle_between(axis, directions[s]) > max_spread) return std::nullopt;
    return lobe;
}

void upsampling::refit_glossy_highlights(std::vector<Node>& nodes, std::size_t inputs,
                                         const UpsampleOptions& options) {
    const Node* shaped = nullptr;
    for (std::size_t i = 0; i < inputs && shaped == nullptr; ++i)
        if (!nodes[i].highlights.empty()) shaped = &nodes[i];
    if (shaped == nullptr) return;
    const int width = shaped->highlights.width(), height = shaped->highlights.height();
    const int channels = shaped->highlights.channels();
    const std::size_t pixels = shaped->highlights.pixel_count();
    std::vector<Image> luminances(inputs);
    for (std::size_t i = 0; i < inputs; ++i)
        if (!nodes[i].highlights.empty()) luminances[i] = luminance(nodes[i].highlights);

    const auto min_samples = static_cast<std::size_t>(options.lobe_samples);
    const double max_spread = degrees_to_radians(options.lobe_spread_deg);
    std::vector<std::optional<HighlightLobe>> lobes(pixels);
    std::vector<float> colour(pixels * static_cast<std::size_t>(channels), 0.0f);
    parallel_for_chunks(pixels, 1024, [&](std::size_t begin, std::size_t end) {
        std::vector<Eigen::Vector3d> directions;
        std::vector<double> values;
        std::vector<std::size_t> showing;
        for (std::size_t p = begin; p < end; ++p) {
            directions.clear();
            values.clear();
            showing.clear();
            for (std::size_t i = 0; i < inputs; ++i) {
                if (luminances[i].empty() || !(luminances[i].plane(0)[p] > 0.0f)) continue;
                directions.push_back(nodes[i].direction);
                values.push_back(luminances[i].plane(0)[p]);
                showing.push_back(i);
            }
            lobes[p] = fit_highlight_lobe(directions, values, min_samples, max_spread);
            if (!lobes[p]) continue;
            const double total = std::accumulate(values.begin(), values.end(), 0.0);
            for (int c = 0; c < channels; ++c) {
                double sum = 0.0;
                for (std::size_t i : showing) sum += nodes[i].highlights.plane(c)[p];
                colour[p * static_cast<std::size_t>(channels) + static_cast<std::size_t>(c)] =
                    static_cast<float>(sum / total);
            }
        }
    });
    std::vector<std::size_t> fitted;
    for (std::size_t p = 0; p < pixels; ++p)
        if (lobes[p]) fitted.push_back(p);
    // In order: a node's parents come before it, so a second level sees the first's lobes.
    for (std::size_t k = inputs; k < nodes.size(); ++k) {
        Node& node = nodes[k];
        const Node& first = nodes[node.parents[0]];
        const Node& second = nodes[node.parents[1]];
        const double edge = angle_between(first.direction, second.direction);
        for (std::size_t p : fitted) {
            if (!shows_highlight(first, p) && !shows_highlight(second, p)) continue;
            if (node.highlights.empty()) node.highlights = Image(width, height, channels);
            if (lobes[p]->angular_width() >= edge) {
                for (int c = 0; c < channels; ++c) {
                    const float h_first = first.highlights.empty() ? 0.0f : first.highlights.plane(c)[p];
                    const float h_second = second.highlights.empty() ? 0.0f : second.highlights.plane(c)[p];
                    node.highlights.plane(c)[p] = 0.5f * (h_first + h_second);
                }
                continue;
            }
            const double value = (*lobes[p])(node.direction);
            for (int c = 0; c < channels; ++c)
                node.highlights.plane(c)[p] = static_cast<float>(
                    value * colour[p * static_cast<std::size_t>(channels) + static_cast<std::size_t>(c)]);
        }
    }
}

}  // namespace rfd::relight
