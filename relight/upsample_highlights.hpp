#pragma once
// The highlight stages of feature-guided upsampling (relight/upsample.hpp): masks, removal,
// half-way layers, the one-sided weights and the glossy lobes, public for their tests; and,
// internal to relight/upsample*.cpp, the glossy lobes applied to the new directions, a pass
// over all nodes once the levels are built.

#include <cstddef>
#include <cstdint>
#include <optional>
#include <vector>

#include <Eigen/Core>

#include "core/image.hpp"

#include "relight/upsample_types.hpp"
#include "relight/upsample_features.hpp"

namespace rfd::relight {

/// M_i before dilation is L >= f_highlight * P and L > floor (floor keeps pixels that are
/// black everywhere out); then dilated by a box of `dilation` pixels. Row-major 0/1.
std::vector<std::uint8_t> highlight_mask(const Image& luminance, const Image& percentile,
                                         double f_highlight, int dilation, float floor);

/// D_i: `image` with `mask` filled in by inpainting from its surroundings (radius 3).
Image remove_highlights(const Image& image, const std::vector<std::uint8_t>& mask);

/// H_k half-way between two highlight layers of the same shape. Connected highlights that
/// are each other's nearest (by energy centroid) within `blob_reach` pixels, within a
/// factor 4 in energy and of the same shape (moved by the offset of their centroids, the one
/// shares at least half its energy with the other, both blurred by a 3 x 3 box) are moved
/// rigidly half-way, each with half its energy; a highlight that splits, merges or bends
/// (a glossy streak over a curved surface) goes to the flow instead. A highlight
/// with nothing of the other layer within `blob_reach` pixels of its bounding box is seen
/// from one side only and stays in place, times `one_sided_weight`. The rest goes by
/// optical flow both ways; a flow layer without a partner layer is also scaled by
/// `one_sided_weight`. With `lights_overlap` (the two lights' discs overlap), a rest that
/// the flow, carried all the way, lays onto the other layer no closer than it lies unmoved
/// stays in place instead, pixel by pixel: the mean where both layers are lit, times
/// `one_sided_weight` where one is. An empty image stands for a layer without highlights;
/// returns empty when both are.
Image halfway_highlights(const Image& first, const Image& second, double blob_reach = 12.0,
                         double one_sided_weight = 0.5, bool lights_overlap = false);

/// The share of a highlight seen at one light direction that a direction `distance` radians
/// away still shows, when both are lights of angular radius `kernel_radius` and the
/// highlight is a mirror reflection (a point in light space somewhere inside the first
/// disc): the overlap of the two discs over the area of one (small-angle, planar), 1 at 0
/// and 0 from 2 * kernel_radius on. A point light (radius 0) shares nothing.
double one_sided_highlight_weight(double distance, double kernel_radius);

/// The share of a mirror highlight lit at one end of an edge `edge` radians long and not at
/// the other that the edge's midpoint still shows, for lights of angular radius
/// `kernel_radius`: of the part of the one end's disc outside the other's, what the
/// midpoint's disc covers, (f(edge / 2) - f(edge)) / (1 - f(edge)) with f =
/// one_sided_highlight_weight (the lens of the two discs lies inside the midpoint's). It is
/// f(edge / 2) where the discs do not overlap (edge >= 2 kernel_radius), tends to 1/2,
/// blending's weight, as the edge shrinks, and is 0 for point lights.
double midpoint_highlight_weight(double edge, double kernel_radius);

/// Fits a lobe to one pixel's highlight samples (unit light directions, values > 0; others
/// are skipped): least squares on log h, weighted by h so that the peak counts most.
/// nullopt for fewer than `min_samples` samples (at least 4, the lobe's parameters), a lobe
/// flatter than sharpness 1, or a sample farther than `max_spread` radians from the fitted
/// axis (two highlights, or a caustic, at one pixel).
std::optional<HighlightLobe> fit_highlight_lobe(const std::vector<Eigen::Vector3d>& directions,
                                                const std::vector<double>& values, std::size_t min_samples,
                                                double max_spread);

}  // namespace rfd::relight

namespace rfd::relight::upsampling {

// The glossy lobes of upsample.hpp: per pixel, the inputs' highlight luminances are fitted
// as a lobe over the light directions; each new node next to an input (or an earlier new
// node) that shows the highlight at the pixel takes the lobe's value there, in the
// highlight's own colour (its channels' share of the samples' total), or, where the lobe is
// at least as wide as the node's edge, the mean of the edge's two ends.
void refit_glossy_highlights(std::vector<Node>& nodes, std::size_t inputs, const UpsampleOptions& options);

}  // namespace rfd::relight::upsampling
