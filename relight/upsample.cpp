// The pipeline of upsample.hpp: the options checked, the inputs' features separated (1),
// subdivided level by level (2), the glossy lobes refitted and the new images synthesised
// (3, 4; relight/upsample_synthesis.cpp), and the field assembled.
#include "relight/upsample.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
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
void subdivide(std::vector<Node>& nodes, int levels, int width, int height, const UpsampleOptions& options) {
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
}

}  // namespace

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
    const std::size_t pixels = field.images.front().pixel_count();

    Separated separated = separate_features(field, interpolator, options, result.statistics);
    std::vector<Node>& nodes = separated.nodes;
    subdivide(nodes, levels, field.width(), field.height(), options);
    if (options.lobe_samples > 0) upsampling::refit_glossy_highlights(nodes, n, options);
    // 3. and 4.: synthesis, with the image priors.
    upsampling::Synthesized synthesized =
        upsampling::synthesize_new_images(field, interpolator, nodes, separated.diffuse, options);

    const std::size_t added = nodes.size() - n;
    result.field = field;
    const bool radii = !field.kernel_radii.empty();
    for (std::size_t a = 0; a < added; ++a) {
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

}  // namespace rfd::relight
