#pragma once
// Internal to relight/upsample*.cpp, not part of rfd_relight's interface (that is
// relight/upsample.hpp, which declares the highlight stages themselves: masks, removal,
// half-way layers, the one-sided weights and the glossy lobes). Here: the glossy lobes
// applied to the new directions, a pass over all nodes once the levels are built.

#include <cstddef>
#include <vector>

#include "relight/upsample.hpp"
#include "relight/upsample_features.hpp"

namespace rfd::relight::upsampling {

// The glossy lobes of upsample.hpp: per pixel, the inputs' highlight luminances are fitted
// as a lobe over the light directions; each new node next to an input (or an earlier new
// node) that shows the highlight at the pixel takes the lobe's value there, in the
// highlight's own colour (its channels' share of the samples' total), or, where the lobe is
// at least as wide as the node's edge, the mean of the edge's two ends.
void refit_glossy_highlights(std::vector<Node>& nodes, std::size_t inputs, const UpsampleOptions& options);

}  // namespace rfd::relight::upsampling
