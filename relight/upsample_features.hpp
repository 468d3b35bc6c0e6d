#pragma once
// Internal to relight/upsample*.cpp, not part of rfd_relight's interface (that is
// relight/upsample.hpp): what the stages of the upsampling pipeline share. The node that
// carries a direction's features from level to level, and the image and optical-flow
// helpers both features (highlights and shadows) are moved with.

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include <Eigen/Core>

#include "core/image.hpp"
#include "relight/upsample.hpp"
#include "relight/vision.hpp"

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
