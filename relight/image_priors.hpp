#pragma once
// Regularisation with image-based priors (thesis 6.4.2, after Wexler et al. 2004): every
// small window of a synthesised image should look like some window of the measured images,
// up to an intensity scale. Pixels flagged uncertain (extrapolated, near a shadow edge) are
// replaced, a few times over, by the similarity-weighted mean of what the best-matching
// source windows say they should be.
//
// One iteration, windows of (2 radius + 1)^2 pixels:
// - For every window W_E(q) of the estimate E that covers an uncertain pixel, the best
//   match W_I(s, t) among the sources, up to a scale: d = min over lambda of
//   |W_E - lambda W_I|^2 over all channels (eq. 6.1). The lookup is a k-d tree (nanoflann)
//   of the sources' windows, each normalised to unit luminance norm (so lambda drops out)
//   and reduced to `components` principal components, plus the window's position times
//   `proximity` (the thesis's term favouring close-by regions, which also keeps the tree
//   shallow); the `candidates` nearest are re-scored with the exact d.
// - Similarity s = exp(-d' / (2 sigma^2)) (eq. 6.2) with d' = d / |W_E|^2 (scale free) and
//   sigma^2 the 75th percentile of d' over the iteration's matches (Wexler et al.).
// - Each uncertain pixel p becomes sum_j s_j c_j / sum_j s_j over the windows j covering it,
//   c_j = lambda_j I_j(p shifted into the match) (eq. 6.3). Other pixels never change.
//
// Where it stops being valid: a window unlike anything in the sources (a shadow edge of a
// shape no input shows) gets a poor match with a small weight, and the estimate is kept
// where every match is poor; only pixels in `uncertain` are ever touched.
//
// Example:
//   const PatchBasis basis = PatchBasis::fit({&a, &b}, 2, 8);
//   Image e = regularise_with_priors(estimate, uncertain, {&a, &b}, basis, PriorOptions{});

#include <cstdint>
#include <vector>

#include <Eigen/Dense>

#include "core/image.hpp"
#include "core/options.hpp"

namespace rfd::relight {

// As `rfd relight upsample` offers them (core/options.hpp).
inline constexpr IntegerOption kPriorIterationsOption{
    "--prior-iterations", "", "", 0, 20, 3,
    "Image-based prior iterations on extrapolated and shadow-edge pixels (thesis 6.4.2: 3; 0: off)"};
inline constexpr NumberOption kPriorProximityOption{
    "--prior-proximity", "", "", 0.0, 1e6, 0.05,
    "How strongly the prior prefers windows close by (patch-distance units per pixel)"};

struct PriorOptions {
    int iterations = static_cast<int>(kPriorIterationsOption.fallback);  ///< thesis: three are usually enough
    double proximity = kPriorProximityOption.fallback;  ///< feature units per pixel of window displacement
    int candidates = 4;        ///< nearest windows re-scored with the exact distance
};

/// InputError for iterations < 0, a proximity that is not > 0 and finite, candidates < 1.
void check_prior_options(const PriorOptions& options);

/// Principal components of unit-normalised luminance windows: the space the k-d tree
/// searches in.
class PatchBasis {
public:
    static constexpr int kMaxRadius = 7;  ///< windows of at most 15 x 15 pixels
    static constexpr int kMaxWindowSize = (2 * kMaxRadius + 1) * (2 * kMaxRadius + 1);

    /// From the windows of `images` (every `stride`-th window centre in x and y, so that
    /// the fit stays cheap on large fields). A radius outside [1, kMaxRadius], components
    /// outside [1, window size] or images of different shapes are the caller's bug.
    static PatchBasis fit(const std::vector<const Image*>& images, int radius, int components, int stride = 4);

    int radius() const { return radius_; }
    int components() const { return static_cast<int>(axes_.cols()); }
    /// Coordinates of a luminance window (row-major, (2 radius + 1)^2 values) after
    /// normalising it to unit norm; zeros for a black window.
    void project(const float* window, float* out) const;

private:
    int radius_ = 0;
    Eigen::MatrixXf axes_;  // window size x components, orthonormal columns
};

/// `estimate` with its `uncertain` pixels (row-major, 1 = uncertain) regularised against
/// `sources` (same shape as the estimate). Returns the estimate unchanged when nothing is
/// uncertain or options.iterations == 0. InputError for options out of range; shapes that
/// differ or an empty source list are the caller's bug. Deterministic.
Image regularise_with_priors(const Image& estimate, const std::vector<std::uint8_t>& uncertain,
                             const std::vector<const Image*>& sources, const PatchBasis& basis,
                             const PriorOptions& options);

}  // namespace rfd::relight
