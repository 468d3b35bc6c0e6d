// Steps 3 and 4 of upsample.hpp: each new direction's image from the blurred shadow maps,
// the barycentric blend or the SH fit of the inputs' highlight-free images, the image priors,
// and its highlight layer.
#include "relight/upsample_synthesis.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <optional>
#include <utility>

#include <Eigen/Dense>

#include "core/parallel.hpp"
#include "core/progress.hpp"
#include "core/sphere.hpp"
#include "relight/image_priors.hpp"

namespace rfd::relight::upsampling {
namespace {

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
        FitSums sums;
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
                    fell_back = !fit(p, fit_set, basis, closeness, true, blend, sums, lit) || fell_back;
                }
            }
            if (sk < 1.0f) {
                if (all_shadowed) shadowed = blend;
                else {
                    extrapolated = true;
                    fell_back = !fit(p, fit_set, basis, closeness, false, blend, sums, shadowed) || fell_back;
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
    // The per-channel sums of one fit, kept across pixels so that a fit allocates nothing.
    struct FitSums {
        std::vector<Eigen::Vector4d> rhs;
        std::vector<double> high;
    };

    // Least-squares fit of (1, x, y, z) to the fit set's samples labelled lit (or shadowed)
    // at pixel p, weighted by closeness and by how reliable the label is (S-bar), evaluated
    // at the target. Fewer than 4 samples: their weighted mean; none: the barycentric blend
    // (returns false). The result is kept in [0, twice the largest sample] so that a poorly
    // conditioned fit cannot run off, while extrapolation past the samples stays possible.
    bool fit(std::size_t p, const std::vector<std::size_t>& fit_set, const std::vector<Eigen::Vector4d>& basis,
             const std::vector<double>& closeness, bool want_lit, const std::vector<double>& blend, FitSums& sums,
             std::vector<double>& out) const {
        const int channels = field_.channels();
        const std::uint8_t wanted = want_lit ? 1 : 0;
        Eigen::Matrix4d normal = Eigen::Matrix4d::Zero();
        std::vector<Eigen::Vector4d>& rhs = sums.rhs;
        std::vector<double>& high = sums.high;
        rhs.assign(static_cast<std::size_t>(channels), Eigen::Vector4d::Zero());
        high.assign(rhs.size(), 0.0);
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

Synthesized synthesize_new_images(const ReflectanceField& field, const SphericalInterpolator& interpolator,
                                  const std::vector<Node>& nodes, const std::vector<Image>& diffuse,
                                  const UpsampleOptions& options) {
    const std::size_t n = field.size();
    const int width = field.width(), height = field.height();
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

    Synthesized out;
    out.images = std::move(synthesized);
    for (std::size_t a = 0; a < added; ++a) {
        out.extrapolated += counts[a].extrapolated;
        out.fallback += counts[a].fallback;
    }
    return out;
}

}  // namespace rfd::relight::upsampling
