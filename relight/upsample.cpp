// The pipeline of upsample.hpp: the options checked, the inputs' features separated (1),
// subdivided level by level (2), the glossy lobes refitted and the new images synthesised
// (3, 4; relight/upsample_synthesis.cpp), and the field assembled.
#include "relight/upsample.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <span>
#include <string>
#include <utility>

#include "core/error.hpp"
#include "core/parallel.hpp"
#include "core/progress.hpp"
#include "core/sphere.hpp"
#include "relight/image_priors.hpp"
#include "relight/interpolation.hpp"
#include "relight/upsample_features.hpp"
#include "relight/upsample_highlights.hpp"
#include "relight/upsample_synthesis.hpp"
#include "relight/vision.hpp"

namespace rfd::relight {
namespace {

using upsampling::all_zero;
using upsampling::Node;
using upsampling::size_of;

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

// The inputs as nodes, with their highlight-free images D.
struct Separated {
    std::vector<Node> nodes;
    std::vector<Image> diffuse;
};

// 1. Semantics: P, then per input its highlight layer H, D and its shadow map S; the
// fractions of highlight and lit pixels go to `statistics`.
Separated separate_features(const ReflectanceField& field, const SphericalInterpolator& interpolator,
                            const UpsampleOptions& options, UpsampleStatistics& statistics) {
    const std::size_t n = field.size();
    const std::size_t pixels = field.images.front().pixel_count();
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
    for (const Image& l : luminances)
        brightest = std::max(brightest, *std::max_element(l.plane(0).begin(), l.plane(0).end()));
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
        statistics.lit_fraction = static_cast<double>(lit) / total;
        std::size_t high = 0;
        for (std::size_t c : highlight_pixels) high += c;
        statistics.highlight_fraction = static_cast<double>(high) / total;
    }
    return {std::move(nodes), std::move(diffuse)};
}

// 2. Feature upsampling, `levels` times: a new node at the midpoint of every Delaunay edge
// of the nodes so far, its highlights and shadow map carried half-way from the edge's ends.
// `only` (when not empty) replaces the first level's edges: a probe subdivides the edges
// around one direction alone.
void subdivide(std::vector<Node>& nodes, int levels, int width, int height, const UpsampleOptions& options,
               const std::vector<std::array<std::size_t, 2>>& only = {}) {
    for (int level = 0; level < levels; ++level) {
        std::vector<Eigen::Vector3d> directions(nodes.size());
        for (std::size_t i = 0; i < nodes.size(); ++i) directions[i] = nodes[i].direction;
        const auto edges = level == 0 && !only.empty() ? only : delaunay_edges(directions);
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
}

// The pipeline without the guard; `only` as subdivide() takes it.
UpsampledField upsample_unguarded(const ReflectanceField& field, int levels, const UpsampleOptions& options,
                                  const std::vector<std::array<std::size_t, 2>>& only = {}) {
    UpsampledField result;
    result.statistics.inputs = field.size();
    if (levels == 0) {
        result.field = field;
        return result;
    }
    const SphericalInterpolator interpolator(field.directions);
    const std::size_t n = field.size();
    const std::size_t pixels = field.images.front().pixel_count();

    Separated separated = separate_features(field, interpolator, options, result.statistics);
    std::vector<Node>& nodes = separated.nodes;
    subdivide(nodes, levels, field.width(), field.height(), options, only);
    if (options.lobe_samples > 0) upsampling::refit_glossy_highlights(nodes, n, options);
    // 3. and 4.: synthesis, with the image priors.
    upsampling::Synthesized synthesized =
        upsampling::synthesize_new_images(field, interpolator, nodes, separated.diffuse, options);

    const std::size_t added = nodes.size() - n;
    result.field = field;
    const bool radii = !field.kernel_radii.empty();
    for (std::size_t a = 0; a < added; ++a) {
        result.parents.push_back(nodes[n + a].parents);
        result.field.directions.push_back(nodes[n + a].direction);
        result.field.images.push_back(std::move(synthesized.images[a]));
        if (radii) result.field.kernel_radii.push_back(nodes[n + a].kernel_radius);
    }
    result.statistics.synthesized = added;
    const double synthesized_pixels = static_cast<double>(std::max<std::size_t>(added, 1) * pixels);
    result.statistics.extrapolated_fraction = static_cast<double>(synthesized.extrapolated) / synthesized_pixels;
    result.statistics.fallback_fraction = static_cast<double>(synthesized.fallback) / synthesized_pixels;
    return result;
}

// Sum of relight(images, weights) over directions: the interpolated image.
Image blend(const std::vector<Image>& images, const InterpolationWeights& w) {
    Image out(images.front().width(), images.front().height(), images.front().channels());
    for (std::size_t k = 0; k < w.count; ++k) {
        const std::span<const float> from = images[w.index[k]].samples();
        const auto weight = static_cast<float>(w.weight[k]);
        for (std::size_t s = 0; s < from.size(); ++s) out.samples()[s] += weight * from[s];
    }
    return out;
}

// Squared differences of display values (sRGB-encoded, as 8-bit captures are judged), per
// tile of `tile` pixels, all channels.
std::vector<double> tile_errors(const Image& a, const Image& b, int tile, int columns, int rows) {
    std::vector<double> out(static_cast<std::size_t>(columns * rows), 0.0);
    for (int c = 0; c < a.channels(); ++c)
        for (int y = 0; y < a.height(); ++y)
            for (int x = 0; x < a.width(); ++x) {
                const double e = linear_to_srgb(std::clamp(a.at(x, y, c), 0.0f, 1.0f)) -
                                 linear_to_srgb(std::clamp(b.at(x, y, c), 0.0f, 1.0f));
                out[static_cast<std::size_t>((y / tile) * columns + x / tile)] += e * e;
            }
    return out;
}

// Inputs to hold out: interior ones (the others' triangulation holds them), spread by
// farthest-point sampling from the one nearest the zenith.
std::vector<std::size_t> probe_lights(const ReflectanceField& field, std::size_t wanted) {
    const std::size_t n = field.size();
    std::vector<std::size_t> interior;
    for (std::size_t j = 0; j < n; ++j) {
        std::vector<Eigen::Vector3d> others;
        for (std::size_t i = 0; i < n; ++i)
            if (i != j) others.push_back(field.directions[i]);
        if (SphericalInterpolator(others).covers(field.directions[j])) interior.push_back(j);
    }
    std::vector<std::size_t> chosen;
    if (interior.empty()) return chosen;
    std::size_t first = interior.front();
    for (const std::size_t j : interior)
        if (field.directions[j].z() > field.directions[first].z()) first = j;
    chosen.push_back(first);
    while (chosen.size() < std::min(wanted, interior.size())) {
        std::size_t best = interior.front();
        double farthest = -1.0;
        for (const std::size_t j : interior) {
            double nearest = 10.0;
            for (const std::size_t c : chosen) nearest = std::min(nearest, angle_between(field.directions[j], field.directions[c]));
            if (nearest > farthest) {
                farthest = nearest;
                best = j;
            }
        }
        chosen.push_back(best);
    }
    return chosen;
}

}  // namespace

UpsampleGuard judge_tiles(const ReflectanceField& field, const UpsampleOptions& options) {
    UpsampleGuard guard;
    const int tile = options.guard_tile;
    if (tile <= 0) return guard;
    guard.tile = tile;
    guard.columns = (field.width() + tile - 1) / tile;
    guard.rows = (field.height() + tile - 1) / tile;
    const auto tiles = static_cast<std::size_t>(guard.columns * guard.rows);
    guard.upsampled.assign(tiles, 1.0);
    guard.probes = probe_lights(field, static_cast<std::size_t>(options.guard_probes));
    if (guard.probes.empty()) return guard;
    std::vector<double> up(tiles, 0.0), blended(tiles, 0.0);
    std::vector<int> losses(tiles, 0);
    UpsampleOptions inner = options;
    inner.guard_tile = 0;
    Progress progress("upsampling guard", guard.probes.size());
    for (const std::size_t j : guard.probes) {
        ReflectanceField others;
        for (std::size_t i = 0; i < field.size(); ++i) {
            if (i == j) continue;
            others.directions.push_back(field.directions[i]);
            others.images.push_back(field.images[i]);
            if (!field.kernel_radii.empty()) others.kernel_radii.push_back(field.kernel_radii[i]);
        }
        const Eigen::Vector3d& d = field.directions[j];
        const InterpolationWeights around = SphericalInterpolator(others.directions).weights(d);
        // The three edges of the triangle holding the held-out light: their midpoints are the
        // new directions the held-out light is relit from.
        std::vector<std::array<std::size_t, 2>> edges;
        for (std::size_t a = 0; a < 3; ++a) {
            const std::size_t p = around.index[a], q = around.index[(a + 1) % 3];
            edges.push_back({std::min(p, q), std::max(p, q)});
        }
        std::sort(edges.begin(), edges.end());
        const UpsampledField local = upsample_unguarded(others, 1, inner, edges);
        const Image with_upsampling =
            blend(local.field.images, SphericalInterpolator(local.field.directions).weights(d));
        const Image with_blending = blend(others.images, around);
        const std::vector<double> e_up = tile_errors(with_upsampling, field.images[j], tile, guard.columns, guard.rows);
        const std::vector<double> e_blend = tile_errors(with_blending, field.images[j], tile, guard.columns, guard.rows);
        for (std::size_t t = 0; t < tiles; ++t) {
            up[t] += e_up[t];
            blended[t] += e_blend[t];
            losses[t] += e_up[t] > e_blend[t] ? 1 : 0;
        }
        progress.advance();
    }
    progress.finish();
    // A tile keeps the upsampled images where they win clearly in sum and lose to blending for
    // at most a quarter of the probes (half let a held-out light of the figure scene lose
    // 0.16 dB in scripts/upsample_study.sh).
    for (std::size_t t = 0; t < tiles; ++t) {
        const bool wins = up[t] < kGuardMargin * blended[t] && 4 * losses[t] <= static_cast<int>(guard.probes.size());
        guard.upsampled[t] = wins ? 1.0 : 0.0;
    }
    return guard;
}

UpsampledField upsample_field(const ReflectanceField& field, int levels, const UpsampleOptions& options) {
    check_options(field, levels, options);
    if (options.guard_tile < 0 || options.guard_probes < 1)
        throw InputError("the guard's tile must be >= 0 pixels (0: off) and its probes >= 1");
    UpsampledField result = upsample_unguarded(field, levels, options);
    if (levels == 0 || options.guard_tile == 0) return result;
    const UpsampleGuard guard = judge_tiles(field, options);
    result.statistics.guard_probes = guard.probes.size();
    result.statistics.guarded_tiles = guard.upsampled.size();
    std::size_t kept = 0;
    for (const double u : guard.upsampled) kept += u > 0.5 ? 1 : 0;
    result.statistics.upsampled_tiles = kept;
    if (guard.probes.empty()) return result;
    // Elsewhere, each new image is the inputs blended at its direction, the weights of the
    // tiles' centres interpolated bilinearly across tile borders so no seam shows.
    const Image weight = guard.pixel_weights(field.width(), field.height());
    const SphericalInterpolator inputs(field.directions);
    const std::size_t n = field.size();
    // The outer ring's edges and what lies between them: no probe judged them.
    std::vector<bool> unjudged(result.field.size(), false);
    for (const std::size_t b : inputs.boundary_vertices()) unjudged[b] = true;
    for (std::size_t k = n; k < result.field.size(); ++k) {
        const auto& [a, b] = result.parents[k - n];
        unjudged[k] = unjudged[a] && unjudged[b];
    }
    parallel_for_chunks(result.field.size() - n, 1, [&](std::size_t begin, std::size_t end) {
        for (std::size_t k = n + begin; k < n + end; ++k) {
            const Image blended = blend(field.images, inputs.weights(result.field.directions[k]));
            Image& image = result.field.images[k];
            for (int c = 0; c < image.channels(); ++c)
                for (int y = 0; y < image.height(); ++y)
                    for (int x = 0; x < image.width(); ++x) {
                        const float w = unjudged[k] ? 0.0f : weight.at(x, y, 0);
                        image.at(x, y, c) = w * image.at(x, y, c) + (1.0f - w) * blended.at(x, y, c);
                    }
        }
    });
    return result;
}

Image UpsampleGuard::pixel_weights(int width, int height) const {
    Image out(width, height, 1, 1.0f);
    if (tile <= 0) return out;
    const auto at = [&](int column, int row) {
        column = std::clamp(column, 0, columns - 1);
        row = std::clamp(row, 0, rows - 1);
        return upsampled[static_cast<std::size_t>(row * columns + column)];
    };
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x) {
            // Tile centres at (i + 0.5) tile.
            const double u = (x + 0.5) / tile - 0.5, v = (y + 0.5) / tile - 0.5;
            const int i = static_cast<int>(std::floor(u)), k = static_cast<int>(std::floor(v));
            const double fu = u - i, fv = v - k;
            out.at(x, y, 0) = static_cast<float>((1 - fu) * (1 - fv) * at(i, k) + fu * (1 - fv) * at(i + 1, k) +
                                                 (1 - fu) * fv * at(i, k + 1) + fu * fv * at(i + 1, k + 1));
        }
    return out;
}

}  // namespace rfd::relight
