#pragma once
// Internal to relight/upsample*.cpp, not part of rfd_relight's interface (that is
// relight/upsample.hpp): steps 3 and 4 of the pipeline described there, the images at the
// new directions from the inputs' highlight-free images, the shadow maps of every node
// and the highlight layers carried to the new ones.

#include <cstddef>
#include <vector>

#include "core/image.hpp"
#include "relight/field.hpp"
#include "relight/interpolation.hpp"
#include "relight/upsample_types.hpp"
#include "relight/upsample_features.hpp"

namespace rfd::relight::upsampling {

struct Synthesized {
    std::vector<Image> images;     // for nodes[inputs...], in their order
    std::size_t extrapolated = 0;  // pixels that needed the SH fit
    std::size_t fallback = 0;      // pixels without reliable samples (the barycentric blend)
};

// The image at each new node's direction: R_reco from the inputs' highlight-free images
// `diffuse` (one per input, nodes[0 .. field.size()) being the inputs), regularised by the
// image priors where `options.priors` asks, plus the node's highlight layer H.
Synthesized synthesize_new_images(const ReflectanceField& field, const SphericalInterpolator& interpolator,
                                  const std::vector<Node>& nodes, const std::vector<Image>& diffuse,
                                  const UpsampleOptions& options);

}  // namespace rfd::relight::upsampling
