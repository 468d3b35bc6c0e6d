#pragma once
// The semantics stage of feature-guided upsampling (relight/upsample.hpp): P and the shadow
// maps, public for their tests. Then, internal to relight/upsample*.cpp: the node that
// carries a direction's features from level to level, and the image and optical-flow
// helpers both features (highlights and shadows) are moved with.

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include <Eigen/Core>

#include "core/image.hpp"
#include "relight/upsample_types.hpp"
#include "relight/vision.hpp"

namespace rfd::relight {

/// P: per pixel, the sample at index floor(quantile * n) (clamped to n - 1) of the n
/// luminances sorted ascending. InputError for an empty list or quantile outside [0, 1].
Image percentile_image(const std::vector<Image>& luminances, double quantile);

/// S_i for every direction: lit where the prefiltered luminance >= P, then region growing
/// over `neighbours` (one-ring lists per direction) with factor f_lit.
std::vector<ShadowMap> shadow_maps(const std::vector<Image>& prefiltered_luminances,
                                   const Image& percentile,
                                   const std::vector<std::vector<std::size_t>>& neighbours,
                                   double f_lit);

/// S_k half-way between two shadow maps of width x height, by level-set blending.
ShadowMap halfway_shadow_map(const ShadowMap& first, const ShadowMap& second, int width, int height);

}  // namespace rfd::relight

namespace rfd::relight::upsampling {

// One direction of the upsampled set with the features carried from level to level.
struct Node {
    Eigen::Vector3d direction;
    Image highlights;  // H, empty when there are none
    ShadowMap shadow;  // S
    double kernel_radius = 0.0;
    std::array<std::size_t, 2> parents{0, 0};  // the ends of the edge it halves (new nodes)
};

inline PlaneSize size_of(const Image& image) { return {image.width(), image.height()}; }

bool all_zero(const Image& image);

// Dense flow from `from` to `to` (8-bit, one channel): from(x) ~ to(x + flow(x)). A wide
// window and smoothing, so that the field carries a match into the mostly flat surroundings
// (the smooth fields of Brox et al. in the thesis).
std::vector<float> dense_flow(PlaneSize size, std::span<const std::uint8_t> from, std::span<const std::uint8_t> to);

// `image` carried `fraction` of the way along the flow (0.5: half-way).
Image warp_along(const Image& image, std::span<const float> flow, float fraction = 0.5f);

}  // namespace rfd::relight::upsampling
