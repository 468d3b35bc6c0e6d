#include "relight/upsample.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numeric>
#include <optional>
#include <string>
#include <utility>

#include <Eigen/Dense>

#include "core/error.hpp"
#include "core/parallel.hpp"
#include "core/progress.hpp"
#include "core/sphere.hpp"
#include "core/units.hpp"
#include "relight/image_priors.hpp"
#include "relight/interpolation.hpp"
#include "relight/vision.hpp"

namespace rfd::relight {
namespace {

PlaneSize size_of(const Image& image) { return {image.width(), image.height()}; }

bool all_zero(const Image& image) {
    const auto samples = image.samples();
    return std::all_of(samples.begin(), samples.end(), [](float v) { return v == 0.0f; });
}

// The `count` directions of `candidates` closest to `d`, nearest first (ties: lower index).
std::vector<std::size_t> nearest_directions(const Eigen::Vector3d& d, const std::vector<Eigen::Vector3d>& candidates,
                                            std::size_t count) {
    std::vector<std::pair<double, std::size_t>> order(candidates.size());
    for (std::size_t i = 0; i < candidates.size(); ++i) order[i] = {-d.dot(candidates[i]), i};
    count = std::min(count, order.size());
    std::partial_sort(order.begin(), order.begin() + static_cast<std::ptrdiff_t>(count), order.end());
    std::vector<std::size_t> nearest(count);
    for (std::size_t i = 0; i < count; ++i) nearest[i] = order[i].second;
    return nearest;
}

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

// Dense flow from `from` to `to` (8-bit, one channel): from(x) ~ to(x + flow(x)). A wide
// window and smoothing, so that the field carries a match into the mostly flat surroundings
// (the smooth fields of Brox et al. in the thesis).
std::vector<float> dense_flow(PlaneSize size, std::span<const std::uint8_t> from, std::span<const std::uint8_t> to) {
    FlowOptions options{.pyramid_scale = 0.5, .levels = 1, .window = 21, .iterations = 3, .polynomial_size = 7,
                        .polynomial_sigma = 1.5};
    // Pyramid levels down to about 16 pixels: coarser ones only add noise to the flow.
    for (int side = std::min(size.width, size.height); side >= 32 && options.levels < 5; side /= 2) ++options.levels;
    std::vector<float> flow(2 * size.area());
    vision().optical_flow(size, from, to, options, flow);
    return flow;
}

// The sampling maps x - fraction * flow(x) of a remap: what lies at x that far along the
// flow (0.5: half-way).
std::pair<std::vector<float>, std::vector<float>> flow_sampling_maps(PlaneSize size, std::span<const float> flow,
                                                                     float fraction = 0.5f) {
    std::vector<float> map_x(size.area()), map_y(size.area());
    for (int y = 0; y < size.height; ++y)
        for (int x = 0; x < size.width; ++x) {
            const std::size_t p = static_cast<std::size_t>(y) * static_cast<std::size_t>(size.width) +
                                  static_cast<std::size_t>(x);
            map_x[p] = static_cast<float>(x) - fraction * flow[2 * p];
            map_y[p] = static_cast<float>(y) - fraction * flow[2 * p + 1];
        }
    return {std::move(map_x), std::move(map_y)};
}

// `image` carried `fraction` of the way along the flow (0.5: half-way).
Image warp_along(const Image& image, std::span<const float> flow, float fraction = 0.5f) {
    const auto [map_x, map_y] = flow_sampling_maps(size_of(image), flow, fraction);
    Image out(image.width(), image.height(), image.channels());
    for (int c = 0; c < image.channels(); ++c)
        vision().remap(size_of(image), image.plane(c), map_x, map_y, out.plane(c), Border::Zero);
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

// Signed distance to the lit/shadow boundary: > 0 inside lit regions, < 0 in shadow. A
// uniform map has no boundary; its distance is the image diagonal, farther than any edge.
std::vector<float> signed_distance(const ShadowMap& map, PlaneSize size) {
    const auto diagonal = static_cast<float>(std::hypot(size.width, size.height));
    const auto lit = static_cast<std::size_t>(std::count(map.begin(), map.end(), std::uint8_t{1}));
    if (lit == map.size() || lit == 0) return std::vector<float>(size.area(), lit == 0 ? -diagonal : diagonal);
    ShadowMap shadow(map.size());
    for (std::size_t p = 0; p < map.size(); ++p) shadow[p] = map[p] == 0 ? 1 : 0;
    std::vector<float> inside(size.area()), outside(size.area());
    vision().distance_transform(size, map, inside);
    vision().distance_transform(size, shadow, outside);
    for (std::size_t p = 0; p < inside.size(); ++p) inside[p] -= outside[p];
    return inside;
}

void check_options(const ReflectanceField& field, int levels, const UpsampleOptions& options) {
    if (field.size() < 4)
        throw InputError("upsampling needs at least 4 images, the field has " + std::to_string(field.size()));
    if (levels < 0 || levels > 4)
        throw InputError("upsampling levels must be 0 to 4 (each multiplies the directions by about 4), got " +
                         std::to_string(levels));
    if (!(options.f_highlight > 1.0) || !std::isfinite(options.f_highlight))
        throw InputError("f_highlight must be > 1 (the thesis uses 2 or 4), got " + std::to_string(options.f_highlight));
    if (!(options.f_lit > 0.0 && options.f_lit <= 1.0))
        throw InputError("f_lit must be in (0, 1] (the thesis uses 0.66 to 0.9), got " + std::to_string(options.f_lit));
    if (!(options.percentile >= 0.0 && options.percentile <= 1.0))
        throw InputError("the percentile must be in [0, 1], got " + std::to_string(options.percentile));
    if (options.priors.iterations > 20)
        throw InputError("prior iterations must be 0 (off) to 20 (the thesis uses 3), got " +
                         std::to_string(options.priors.iterations));
    check_prior_options(options.priors);
    if (!(options.blob_reach >= 0.0) || !std::isfinite(options.blob_reach))
        throw InputError("the blob reach must be a distance in pixels >= 0, got " + std::to_string(options.blob_reach));
    if (options.highlight_dilation < 1 || options.highlight_dilation % 2 == 0)
        throw InputError("the highlight dilation must be an odd box size >= 1, got " +
                         std::to_string(options.highlight_dilation));
    if (options.blur_neighbours < 1 || options.fit_neighbours < 1)
        throw InputError("neighbour counts for blurring and fitting must be >= 1");
    if (options.lobe_samples < 0 || (options.lobe_samples > 0 && options.lobe_samples < 4))
        throw InputError("lobe samples must be 0 (off) or >= 4 (a lobe has 4 parameters), got " +
                         std::to_string(options.lobe_samples));
    if (!(options.lobe_spread_deg > 0.0 && options.lobe_spread_deg <= 180.0))
        throw InputError("the lobe spread must be an angle in (0, 180] degrees, got " +
                         std::to_string(options.lobe_spread_deg));
}

// One direction of the upsampled set with the features carried from level to level.
struct Node {
    Eigen::Vector3d direction;
    Image highlights;  // H, empty when there are none
    ShadowMap shadow;  // S
    double kernel_radius = 0.0;
    std::array<std::size_t, 2> parents{0, 0};  // the ends of the edge it halves (new nodes)
};

// The edges of the Delaunay triangulation of `directions`, each once, (low, high), sorted.
std::vector<std::array<std::size_t, 2>> delaunay_edges(const std::vector<Eigen::Vector3d>& directions) {
    std::vector<std::array<std::size_t, 2>> edges;
    for (const Triangle& t : delaunay_triangles(directions))
        for (std::size_t j = 0; j < 3; ++j) {
            const std::size_t a = t[j], b = t[(j + 1) % 3];
            edges.push_back({std::min(a, b), std::max(a, b)});
        }
    std::sort(edges.begin(), edges.end());
    edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
    return edges;
}

// S-bar: the mean of the shadow maps of `neighbours`.
std::vector<float> blurred_shadow(const std::vector<Node>& nodes, const std::vector<std::size_t>& neighbours) {
    std::vector<float> sum(nodes.front().shadow.size(), 0.0f);
    for (std::size_t m : neighbours) {
        const ShadowMap& s = nodes[m].shadow;
        for (std::size_t p = 0; p < sum.size(); ++p) sum[p] += static_cast<float>(s[p]);
    }
    // Divided, not scaled by a reciprocal: all lit must give exactly 1 (the cases of 6.4.1).
    const auto count = static_cast<float>(neighbours.size());
    for (float& v : sum) v /= count;
    return sum;
}

// The image priors' windows (5 x 5, as in the thesis's figures) and the principal
// components the k-d tree searches; the basis is fitted to every 8th window of the inputs.
constexpr int kPriorWindowRadius = 2;
constexpr int kPriorComponents = 8;
constexpr int kPriorBasisStride = 8;

// Adds to `mask` the pixels on either side of a lit/shadow boundary of `shadow`.
void mark_shadow_edges(const ShadowMap& shadow, int width, int height, std::vector<std::uint8_t>& mask) {
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x) {
            const auto p = static_cast<std::size_t>(y * width + x);
            const bool right = x + 1 < width && shadow[p + 1] != shadow[p];
            const bool below = y + 1 < height && shadow[p + static_cast<std::size_t>(width)] != shadow[p];
            if (right) mask[p] = mask[p + 1] = 1;
            if (below) mask[p] = mask[p + static_cast<std::size_t>(width)] = 1;
        }
}

// True where the highlight layer of `node` shows something at pixel p.
bool shows_highlight(const Node& node, std::size_t p) {
    if (node.highlights.empty()) return false;
    for (int c = 0; c < node.highlights.channels(); ++c)
        if (node.highlights.plane(c)[p] > 0.0f) return true;
    return false;
}

// The glossy lobes of upsample.hpp: per pixel, the inputs' highlight luminances are fitted
// as a lobe over the light directions; each new node next to an input (or an earlier new
// node) that shows the highlight at the pixel takes the lobe's value there, in the
// highlight's own colour (its channels' share of the samples' total), or, where the lobe is
// at least as wide as the node's edge, the mean of the edge's two ends.
void refit_glossy_highlights(std::vector<Node>& nodes, std::size_t inputs, const UpsampleOptions& options) {
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

// The synthesis of 6.4.1 for one new direction.
class Synthesis {
public:
    Synthesis(const ReflectanceField& field, const std::vector<Image>& diffuse,
              const std::vector<std::vector<float>>& input_blurred, const std::vector<const ShadowMap*>& input_shadow,
              double spacing)
        : field_(field), diffuse_(diffuse), input_blurred_(input_blurred), input_shadow_(input_shadow),
          spacing_(spacing) {}

    struct Counts {
        std::size_t extrapolated = 0;
        std::size_t fallback = 0;
    };

    // The diffuse reconstruction R_reco at `direction` (without highlights); `extrapolated`
    // gets 1 where the value came from the fit rather than the barycentric blend.
    Image reconstruct(const Eigen::Vector3d& direction, const InterpolationWeights& weights,
                      const std::vector<std::size_t>& fit_set, const std::vector<float>& blurred_k,
                      Counts& counts, std::vector<std::uint8_t>& extrapolated_mask) const {
        const int channels = field_.channels();
        const std::size_t pixels = field_.images.front().pixel_count();
        Image out(field_.width(), field_.height(), channels);
        extrapolated_mask.assign(pixels, 0);

        // Fit samples: offsets from the target (the fit's constant term is the value there)
        // and closeness weights.
        std::vector<Eigen::Vector4d> basis(fit_set.size());
        std::vector<double> closeness(fit_set.size());
        for (std::size_t s = 0; s < fit_set.size(); ++s) {
            const Eigen::Vector3d offset = field_.directions[fit_set[s]] - direction;
            basis[s] = Eigen::Vector4d(1.0, offset.x(), offset.y(), offset.z());
            closeness[s] = 1.0 / (angle_between(field_.directions[fit_set[s]], direction) + spacing_);
        }

        std::vector<double> lit(static_cast<std::size_t>(channels)), shadowed(lit.size()), blend(lit.size());
        for (std::size_t p = 0; p < pixels; ++p) {
            const float sk = blurred_k[p];
            bool all_lit = true, all_shadowed = true;
            for (std::size_t j = 0; j < weights.count; ++j) {
                if (weights.weight[j] == 0.0) continue;
                const float s = input_blurred_[weights.index[j]][p];
                all_lit = all_lit && s == 1.0f;
                all_shadowed = all_shadowed && s == 0.0f;
            }
            for (int c = 0; c < channels; ++c) {
                double v = 0.0;
                for (std::size_t j = 0; j < weights.count; ++j)
                    v += weights.weight[j] * diffuse_[weights.index[j]].plane(c)[p];
                blend[static_cast<std::size_t>(c)] = v;
            }
            bool extrapolated = false, fell_back = false;
            if (sk > 0.0f) {
                if (all_lit) lit = blend;
                else {
                    extrapolated = true;
                    fell_back = !fit(p, fit_set, basis, closeness, true, blend, lit) || fell_back;
                }
            }
            if (sk < 1.0f) {
                if (all_shadowed) shadowed = blend;
                else {
                    extrapolated = true;
                    fell_back = !fit(p, fit_set, basis, closeness, false, blend, shadowed) || fell_back;
                }
            }
            for (int c = 0; c < channels; ++c) {
                const auto ci = static_cast<std::size_t>(c);
                const double v = (sk > 0.0f ? sk * lit[ci] : 0.0) + (sk < 1.0f ? (1.0f - sk) * shadowed[ci] : 0.0);
                out.plane(c)[p] = static_cast<float>(v);
            }
            counts.extrapolated += extrapolated ? 1 : 0;
            extrapolated_mask[p] = extrapolated ? 1 : 0;
            counts.fallback += fell_back ? 1 : 0;
        }
        return out;
    }

private:
    // Least-squares fit of (1, x, y, z) to the fit set's samples labelled lit (or shadowed)
    // at pixel p, weighted by closeness and by how reliable the label is (S-bar), evaluated
    // at the target. Fewer than 4 samples: their weighted mean; none: the barycentric blend
    // (returns false). The result is kept in [0, twice the largest sample] so that a poorly
    // conditioned fit cannot run off, while extrapolation past the samples stays possible.
    bool fit(std::size_t p, const std::vector<std::size_t>& fit_set, const std::vector<Eigen::Vector4d>& basis,
             const std::vector<double>& closeness, bool want_lit, const std::vector<double>& blend,
             std::vector<double>& out) const {
        const int channels = field_.channels();
        const std::uint8_t wanted = want_lit ? 1 : 0;
        Eigen::Matrix4d normal = Eigen::Matrix4d::Zero();
        std::vector<Eigen::Vector4d> rhs(static_cast<std::size_t>(channels), Eigen::Vector4d::Zero());
        std::vector<double> high(rhs.size(), 0.0);
        double weight_sum = 0.0;
        std::size_t used = 0;
        for (std::size_t s = 0; s < fit_set.size(); ++s) {
            const std::size_t m = fit_set[s];
            if ((*input_shadow_[m])[p] != wanted) continue;
            const double lit = input_blurred_[m][p];
            const double w = closeness[s] * std::max(want_lit ? lit : 1.0 - lit, 0.1);
            normal += w * basis[s] * basis[s].transpose();
            for (int c = 0; c < channels; ++c) {
                const auto ci = static_cast<std::size_t>(c);
                const double v = diffuse_[m].plane(c)[p];
                rhs[ci] += w * v * basis[s];
                high[ci] = std::max(high[ci], v);
            }
            weight_sum += w;
            ++used;
        }
        if (used == 0) {
            out = blend;
            return false;
        }
        if (used < 4) {
            for (std::size_t ci = 0; ci < out.size(); ++ci) out[ci] = rhs[ci][0] / weight_sum;
            return true;
        }
        // A light ridge on the slopes keeps samples bunched on one side from tilting the plane.
        const double ridge = 1e-3 * normal(0, 0) * spacing_ * spacing_;
        for (int i = 1; i < 4; ++i) normal(i, i) += ridge;
        const Eigen::LDLT<Eigen::Matrix4d> solver(normal);
        for (std::size_t ci = 0; ci < out.size(); ++ci) {
            const double value = solver.solve(rhs[ci])[0];
            out[ci] = std::isfinite(value) ? std::clamp(value, 0.0, 2.0 * high[ci]) : rhs[ci][0] / weight_sum;
        }
        return true;
    }

    const ReflectanceField& field_;
    const std::vector<Image>& diffuse_;
    const std::vector<std::vector<float>>& input_blurred_;
    const std::vector<const ShadowMap*>& input_shadow_;
    double spacing_;
};

}  // namespace

Image percentile_image(const std::vector<Image>& luminances, double quantile) {
    if (luminances.empty()) throw InputError("the percentile image needs at least one image");
    if (!(quantile >= 0.0 && quantile <= 1.0)) throw InputError("the percentile must be in [0, 1]");
    const std::size_t n = luminances.size();
    const std::size_t rank = std::min(n - 1, static_cast<std::size_t>(std::floor(quantile * static_cast<double>(n))));
    Image out(luminances.front().width(), luminances.front().height(), 1);
    const std::size_t pixels = out.pixel_count();
    parallel_for_chunks(pixels, 4096, [&](std::size_t begin, std::size_t end) {
        std::vector<float> values(n);
        for (std::size_t p = begin; p < end; ++p) {
            for (std::size_t i = 0; i < n; ++i) values[i] = luminances[i].plane(0)[p];
            std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(rank), values.end());
            out.plane(0)[p] = values[rank];
        }
    });
    return out;
}

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

std::vector<ShadowMap> shadow_maps(const std::vector<Image>& prefiltered_luminances, const Image& percentile,
                                   const std::vector<std::vector<std::size_t>>& neighbours, double f_lit) {
    const std::size_t n = prefiltered_luminances.size();
    const std::size_t pixels = percentile.pixel_count();
    std::vector<ShadowMap> maps(n, ShadowMap(pixels, 0));
    parallel_for_chunks(pixels, 1024, [&](std::size_t begin, std::size_t end) {
        std::vector<float> l(n);
        std::vector<std::size_t> queue;
        for (std::size_t p = begin; p < end; ++p) {
            queue.clear();
            for (std::size_t i = 0; i < n; ++i) {
                l[i] = prefiltered_luminances[i].plane(0)[p];
                if (l[i] >= percentile.plane(0)[p]) {
                    maps[i][p] = 1;
                    queue.push_back(i);
                }
            }
            // Region growing (6.2.2): the lit set spreads to a neighbour as long as the
            // neighbour keeps f_lit of the light; a sharper drop is a shadow boundary.
            for (std::size_t head = 0; head < queue.size(); ++head) {
                const std::size_t j = queue[head];
                for (std::size_t i : neighbours[j]) {
                    if (maps[i][p] != 0 || !(static_cast<double>(l[i]) > f_lit * static_cast<double>(l[j]))) continue;
                    maps[i][p] = 1;
                    queue.push_back(i);
                }
            }
        }
    });
    return maps;
}

namespace {

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

}  // namespace

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

ShadowMap halfway_shadow_map(const ShadowMap& first, const ShadowMap& second, int width, int height) {
    const PlaneSize size{width, height};
    const std::vector<float> phi_a = signed_distance(first, size), phi_b = signed_distance(second, size);
    // The two level-set functions are carried half-way along the flow between them before
    // they are averaged: a shadow that slides keeps its shape instead of shrinking to the
    // overlap, as the plain mean of two distance functions would. The flow matches the
    // distances near the boundary only (clamped to +-kBand pixels, 8 grey levels per pixel).
    constexpr double kBand = 15.0;
    const auto flow_input_of = [&](const std::vector<float>& phi) {
        std::vector<float> clamped(phi.size());
        for (std::size_t p = 0; p < phi.size(); ++p)
            clamped[p] = std::clamp(phi[p], static_cast<float>(-kBand), static_cast<float>(kBand));
        std::vector<std::uint8_t> grey(phi.size());
        vision().scale_to_bytes(clamped, 127.0 / kBand, 127.5, grey);
        return grey;
    };
    const std::vector<std::uint8_t> ga = flow_input_of(phi_a), gb = flow_input_of(phi_b);
    const auto warp = [&](const std::vector<float>& phi, const std::vector<float>& flow) {
        const auto [map_x, map_y] = flow_sampling_maps(size, flow);
        std::vector<float> out(phi.size());
        vision().remap(size, phi, map_x, map_y, out, Border::Replicate);
        return out;
    };
    const std::vector<float> a = warp(phi_a, dense_flow(size, ga, gb)), b = warp(phi_b, dense_flow(size, gb, ga));
    ShadowMap out(first.size());
    for (std::size_t p = 0; p < out.size(); ++p) out[p] = a[p] + b[p] > 0.0f ? 1 : 0;
    return out;
}

UpsampledField upsample_field(const ReflectanceField& field, int levels, const UpsampleOptions& options) {
    check_options(field, levels, options);
    UpsampledField result;
    result.statistics.inputs = field.size();
    if (levels == 0) {
        result.field = field;
        return result;
    }
    const SphericalInterpolator interpolator(field.directions);
    const std::size_t n = field.size();
    const int width = field.width(), height = field.height();
    const std::size_t pixels = field.images.front().pixel_count();

    // 1. Semantics.
    std::vector<Image> luminances(n), prefiltered(n);
    parallel_for_chunks(n, 1, [&](std::size_t begin, std::size_t end) {
        for (std::size_t i = begin; i < end; ++i) {
            luminances[i] = luminance(field.images[i]);
            prefiltered[i] = luminances[i];
            vision().gaussian_blur(size_of(luminances[i]), luminances[i].plane(0), prefiltered[i].plane(0), 3, 0.0, 0.0,
                                   Border::Replicate);
        }
    });
    const Image percentile = percentile_image(prefiltered, options.percentile);
    float brightest = 0.0f;
    for (const Image& l : luminances) brightest = std::max(brightest, *std::max_element(l.plane(0).begin(), l.plane(0).end()));
    // Pixels darker than this in the image itself are never highlights: it keeps pixels that
    // are black in most images (P = 0) from turning every speck into a highlight.
    const float floor = 1e-3f * brightest;

    std::vector<Image> diffuse(n);
    std::vector<Node> nodes(n);
    std::vector<std::size_t> highlight_pixels(n, 0);
    {
        Progress progress("highlight separation", n);
        parallel_for_chunks(n, 1, [&](std::size_t begin, std::size_t end) {
            for (std::size_t i = begin; i < end; ++i) {
                const auto mask = highlight_mask(luminances[i], percentile, options.f_highlight,
                                                 options.highlight_dilation, floor);
                highlight_pixels[i] = static_cast<std::size_t>(std::count(mask.begin(), mask.end(), std::uint8_t{1}));
                diffuse[i] = remove_highlights(field.images[i], mask);
                Image h = field.images[i];
                for (std::size_t s = 0; s < h.samples().size(); ++s) h.samples()[s] -= diffuse[i].samples()[s];
                nodes[i].direction = field.directions[i];
                nodes[i].kernel_radius = field.kernel_radius(i);
                if (!all_zero(h)) nodes[i].highlights = std::move(h);
                progress.advance();
            }
        });
    }
    {
        auto maps = shadow_maps(prefiltered, percentile, interpolator.one_rings(), options.f_lit);
        std::size_t lit = 0;
        for (std::size_t i = 0; i < n; ++i) {
            lit += static_cast<std::size_t>(std::count(maps[i].begin(), maps[i].end(), std::uint8_t{1}));
            nodes[i].shadow = std::move(maps[i]);
        }
        const double total = static_cast<double>(n * pixels);
        result.statistics.lit_fraction = static_cast<double>(lit) / total;
        std::size_t high = 0;
        for (std::size_t c : highlight_pixels) high += c;
        result.statistics.highlight_fraction = static_cast<double>(high) / total;
    }
    luminances.clear();
    prefiltered.clear();

    // 2. Feature upsampling, level by level.
    for (int level = 0; level < levels; ++level) {
        std::vector<Eigen::Vector3d> directions(nodes.size());
        for (std::size_t i = 0; i < nodes.size(); ++i) directions[i] = nodes[i].direction;
        const auto edges = delaunay_edges(directions);
        std::vector<Node> added(edges.size());
        Progress progress("subdivision level " + std::to_string(level + 1), edges.size());
        parallel_for_chunks(edges.size(), 1, [&](std::size_t begin, std::size_t end) {
            for (std::size_t e = begin; e < end; ++e) {
                const Node& a = nodes[edges[e][0]];
                const Node& b = nodes[edges[e][1]];
                added[e].direction = (a.direction + b.direction).normalized();
                added[e].kernel_radius = 0.5 * (a.kernel_radius + b.kernel_radius);
                added[e].parents = edges[e];
                const double edge = angle_between(a.direction, b.direction);
                const double radius = added[e].kernel_radius;
                added[e].highlights = halfway_highlights(a.highlights, b.highlights, options.blob_reach,
                                                         midpoint_highlight_weight(edge, radius), edge < 2.0 * radius);
                if (!added[e].highlights.empty() && all_zero(added[e].highlights)) added[e].highlights = Image();
                added[e].shadow = halfway_shadow_map(a.shadow, b.shadow, width, height);
                progress.advance();
            }
        });
        for (Node& node : added) nodes.push_back(std::move(node));
    }

    if (options.lobe_samples > 0) refit_glossy_highlights(nodes, n, options);

    // 3. Synthesis.
    std::vector<Eigen::Vector3d> all_directions(nodes.size());
    for (std::size_t i = 0; i < nodes.size(); ++i) all_directions[i] = nodes[i].direction;
    const auto blur = static_cast<std::size_t>(options.blur_neighbours);
    std::vector<std::vector<float>> input_blurred(n);
    parallel_for_chunks(n, 1, [&](std::size_t begin, std::size_t end) {
        for (std::size_t i = begin; i < end; ++i)
            input_blurred[i] = blurred_shadow(nodes, nearest_directions(all_directions[i], all_directions, blur));
    });
    // Closeness weights level off within about half the input spacing.
    std::vector<double> gaps(n);
    for (std::size_t i = 0; i < n; ++i) {
        const auto nearest = nearest_directions(field.directions[i], field.directions, 2);
        gaps[i] = angle_between(field.directions[i], field.directions[nearest.back()]);
    }
    std::nth_element(gaps.begin(), gaps.begin() + static_cast<std::ptrdiff_t>(n / 2), gaps.end());
    const double spacing = std::max(0.5 * gaps[n / 2], 1e-6);

    std::vector<const ShadowMap*> input_shadow(n);
    for (std::size_t i = 0; i < n; ++i) input_shadow[i] = &nodes[i].shadow;
    const Synthesis synthesis(field, diffuse, input_blurred, input_shadow, spacing);
    std::optional<PatchBasis> patch_basis;
    if (options.priors.iterations > 0) {
        std::vector<const Image*> all_diffuse;
        for (const Image& d : diffuse) all_diffuse.push_back(&d);
        patch_basis = PatchBasis::fit(all_diffuse, kPriorWindowRadius, kPriorComponents, kPriorBasisStride);
    }
    const std::size_t added = nodes.size() - n;
    std::vector<Image> synthesized(added);
    std::vector<Synthesis::Counts> counts(added);
    {
        Progress progress("synthesis", added);
        parallel_for_chunks(added, 1, [&](std::size_t begin, std::size_t end) {
            for (std::size_t a = begin; a < end; ++a) {
                const Node& node = nodes[n + a];
                const auto blurred = blurred_shadow(nodes, nearest_directions(node.direction, all_directions, blur));
                const auto fit_set = nearest_directions(node.direction, field.directions,
                                                        static_cast<std::size_t>(options.fit_neighbours));
                const InterpolationWeights weights = interpolator.weights(node.direction);
                std::vector<std::uint8_t> uncertain;
                Image image = synthesis.reconstruct(node.direction, weights, fit_set, blurred, counts[a], uncertain);
                if (options.priors.iterations > 0) {
                    // 6.4.2: extrapolated pixels and those at a shadow edge are checked
                    // against the windows of the inputs around this direction.
                    mark_shadow_edges(node.shadow, width, height, uncertain);
                    std::vector<const Image*> sources;
                    for (std::size_t j = 0; j < weights.count; ++j)
                        if (weights.weight[j] > 0.0) sources.push_back(&diffuse[weights.index[j]]);
                    image = regularise_with_priors(image, uncertain, sources, *patch_basis, options.priors);
                }
                if (!node.highlights.empty())
                    for (std::size_t s = 0; s < image.samples().size(); ++s)
                        image.samples()[s] += node.highlights.samples()[s];
                synthesized[a] = std::move(image);
                progress.advance();
            }
        });
    }

    result.field = field;
    const bool radii = !field.kernel_radii.empty();
    std::size_t extrapolated = 0, fallback = 0;
    for (std::size_t a = 0; a < added; ++a) {
        result.field.directions.push_back(nodes[n + a].direction);
        result.field.images.push_back(std::move(synthesized[a]));
        if (radii) result.field.kernel_radii.push_back(nodes[n + a].kernel_radius);
        extrapolated += counts[a].extrapolated;
        fallback += counts[a].fallback;
    }
    result.statistics.synthesized = added;
    const double synthesized_pixels = static_cast<double>(std::max<std::size_t>(added, 1) * pixels);
    result.statistics.extrapolated_fraction = static_cast<double>(extrapolated) / synthesized_pixels;
    result.statistics.fallback_fraction = static_cast<double>(fallback) / synthesized_pixels;
    return result;
}

}  // namespace rfd::relight
