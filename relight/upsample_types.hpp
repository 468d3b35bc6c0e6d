#pragma once
// What the stages of feature-guided upsampling (relight/upsample.hpp, whose header describes
// the pipeline and the options' values) share: the options, a shadow map, a glossy lobe.
// Every stage header includes this one, not upsample.hpp, so no stage sees the pipeline
// that calls it.

#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "relight/image_priors.hpp"

namespace rfd::relight {

struct UpsampleOptions {
    double f_highlight = 2.0;            ///< highlight where L >= f_highlight * P (thesis: 2 or 4)
    double f_lit = 0.7;                  ///< region growing factor (thesis: 0.66..0.9; see above)
    double percentile = 230.0 / 256.0;   ///< P's quantile (thesis: P_230 of 256)
    int highlight_dilation = 5;          ///< box size growing M_i (1: none; odd)
    int blur_neighbours = 1;             ///< directions averaged into S-bar (thesis: 10; see above)
    int fit_neighbours = 16;             ///< inputs offered to the SH extrapolation
    double blob_reach = 12.0;            ///< pixels a compact highlight may move and be matched (0: flow only)
    int lobe_samples = 8;                ///< inputs a pixel's highlight must show in to be fitted as a lobe (0: off)
    double lobe_spread_deg = 30.0;       ///< ... all of them within this angle of the lobe's axis
    PriorOptions priors;                 ///< regularisation of uncertain pixels (iterations 0: off)
};

/// A binary map per pixel, row-major, 1 = lit.
using ShadowMap = std::vector<std::uint8_t>;

/// One pixel's highlight as a function of the light direction l: a von Mises-Fisher lobe
/// h(l) = exp(log_scale + sharpness_axis . l), with axis sharpness_axis / |sharpness_axis|.
struct HighlightLobe {
    double log_scale = 0.0;
    Eigen::Vector3d sharpness_axis = Eigen::Vector3d::Zero();
    double brightest = 0.0;  ///< the largest sample fitted; the lobe is capped at twice this

    double operator()(const Eigen::Vector3d& light) const;
    /// sigma of the lobe near its axis (radians): exp(k (cos t - 1)) ~ exp(-t^2 / (2 sigma^2))
    /// with sigma = 1 / sqrt(k), k = |sharpness_axis|.
    double angular_width() const;
};

}  // namespace rfd::relight
