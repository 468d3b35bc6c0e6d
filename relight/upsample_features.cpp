// The feature maps of upsample.hpp other than the highlights: the percentile image P, the
// shadow maps S and their level-set half-way; and the image and flow helpers shared with
// the highlights (upsample_features.hpp).
#include "relight/upsample_features.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <utility>

#include "core/error.hpp"
#include "core/parallel.hpp"
#include "relight/vision.hpp"

namespace rfd::relight {
namespace {

using upsampling::dense_flow;
using upsampling::size_of;

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

}  // namespace

bool upsampling::all_zero(const Image& image) {
    const auto samples = image.samples();
    return std::all_of(samples.begin(), samples.end(), [](float v) { return v == 0.0f; });
}

std::vector<float> upsampling::dense_flow(PlaneSize size, std::span<const std::uint8_t> from,
                                          std::span<const std::uint8_t> to) {
    FlowOptions options{.pyramid_scale = 0.5, .levels = 1, .window = 21, .iterations = 3, .polynomial_size = 7,
                        .polynomial_sigma = 1.5};
    // Pyramid levels down to about 16 pixels: coarser ones only add noise to the flow.
    for (int side = std::min(size.width, size.height); side >= 32 && options.levels < 5; side /= 2) ++options.levels;
    std::vector<float> flow(2 * size.area());
    vision().optical_flow(size, from, to, options, flow);
    return flow;
}

Image upsampling::warp_along(const Image& image, std::span<const float> flow, float fraction) {
    const auto [map_x, map_y] = flow_sampling_maps(size_of(image), flow, fraction);
    Image out(image.width(), image.height(), image.channels());
    for (int c = 0; c < image.channels(); ++c)
        vision().remap(size_of(image), image.plane(c), map_x, map_y, out.plane(c), Border::Zero);
    return out;
}

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

}  // namespace rfd::relight
