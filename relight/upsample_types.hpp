#pragma once
// What the stages of feature-guided upsampling (relight/upsample.hpp, whose header describes
// the pipeline and the options' values) share: the options, a shadow map, a glossy lobe.
// Every stage header includes this one, not upsample.hpp, so no stage sees the pipeline
// that calls it.

#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "core/options.hpp"
#include "relight/image_priors.hpp"

namespace rfd::relight {

// The options as `rfd relight upsample` offers them (core/options.hpp). Their ranges are
// what the command line accepts; inside them, check_options (upsample.cpp) still refuses
// what the method cannot use: f_highlight = 1, f_lit = 0, an even dilation, 1 to 3 lobe
// samples, a spread of 0.
inline constexpr NumberOption kHighlightFactorOption{
    "--f-highlight", "", "", 1.0, 100.0, 2.0,
    "A pixel is a highlight where it is this many times its percentile level (thesis: 2 or 4)"};
inline constexpr NumberOption kLitFractionOption{
    "--f-lit", "", "", 0.0, 1.0, 0.7,
    "Shadow region growing: a neighbouring direction stays lit while it keeps this fraction of the light "
    "(thesis: 0.66 to 0.9)"};
inline constexpr NumberOption kPercentileOption{
    "--percentile", "", "", 0.0, 1.0, 230.0 / 256.0,
    "Quantile of a pixel over all directions that is neither highlight nor shadow (thesis: 230/256)"};
inline constexpr IntegerOption kDilationOption{"--dilation", "", "pixels", 1, 63, 5,
                                               "Box size growing the highlight masks (odd)"};
inline constexpr IntegerOption kBlurNeighboursOption{
    "--blur-neighbours", "", "", 1, 1000, 1,
    "Directions averaged into the blurred shadow maps (the thesis: 10; 1 measured better here)"};
inline constexpr IntegerOption kFitNeighboursOption{"--fit-neighbours", "", "", 1, 1000, 16,
                                                    "Nearest inputs offered to the spherical-harmonic extrapolation"};
inline constexpr NumberOption kBlobReachOption{
    "--blob-reach", "", "pixels", 0.0, 10000.0, 12.0,
    "How far a compact highlight may move between neighbouring inputs and still be matched as one (0: optical "
    "flow only)"};
inline constexpr IntegerOption kLobeSamplesOption{
    "--lobe-samples", "", "", 0, 1000, 8,
    "Inputs a pixel's highlight must show in to be fitted as a glossy lobe over the light directions (0: off; "
    "else >= 4)"};
inline constexpr NumberOption kLobeSpreadOption{
    "--lobe-spread", "", "deg", 0.0, 180.0, 30.0,
    "Angle from the lobe's axis within which all of a pixel's highlight samples must lie"};

inline constexpr IntegerOption kGuardTileOption{
    "--guard-tile", "", "pixels", 0, 4096, 32,
    "Side of the tiles in which the upsampled images must beat blending in leave-one-out on the capture itself, "
    "or are blended instead (0: no guard)"};
inline constexpr IntegerOption kGuardProbesOption{
    "--guard-probes", "", "", 1, 64, 8,
    "Inputs held out, one at a time, to judge the tiles (spread over the capture's lights)"};

struct UpsampleOptions {
    double f_highlight = kHighlightFactorOption.fallback;  ///< highlight where L >= f_highlight * P
    double f_lit = kLitFractionOption.fallback;             ///< region growing factor (see above)
    double percentile = kPercentileOption.fallback;         ///< P's quantile (thesis: P_230 of 256)
    int highlight_dilation = static_cast<int>(kDilationOption.fallback);  ///< box size growing M_i (1: none)
    int blur_neighbours = static_cast<int>(kBlurNeighboursOption.fallback);  ///< directions averaged into S-bar
    int fit_neighbours = static_cast<int>(kFitNeighboursOption.fallback);    ///< inputs offered to the SH fit
    double blob_reach = kBlobReachOption.fallback;           ///< pixels a compact highlight may move and match
    int lobe_samples = static_cast<int>(kLobeSamplesOption.fallback);  ///< samples of a fitted lobe (0: off)
    double lobe_spread_deg = kLobeSpreadOption.fallback;     ///< ... all within this angle of the lobe's axis
    PriorOptions priors;                                     ///< regularisation of uncertain pixels
    int guard_tile = static_cast<int>(kGuardTileOption.fallback);      ///< tile side; 0: no guard
    int guard_probes = static_cast<int>(kGuardProbesOption.fallback);  ///< inputs held out to judge tiles
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
