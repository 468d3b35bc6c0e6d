#pragma once
// Feature-guided upsampling of a reflectance field (thesis chapter 6): new images for light
// directions between the measured ones, with highlights that move and shadow edges that
// travel instead of the cross-fades and banding of linear blending.
//
// Pipeline (figure 6.3), for a field R_i of n images:
// 1. Semantics (6.2). P: per pixel, the quantile `percentile` (230/256) of the luminances
//    of all R_i, a level that is neither highlight nor shadow.
//    Highlights: M_i = L_i >= f_highlight * P, dilated by a box of `highlight_dilation`;
//    D_i: R_i with M_i filled in from around it (OpenCV's Navier-Stokes inpainting), kept
//    <= R_i; H_i = R_i - D_i >= 0.
//    Shadows, per pixel over directions: S_i = 1 (lit) where the 3x3-prefiltered luminance
//    is >= P, then region growing over the Delaunay neighbours of the directions: a shadowed
//    i next to a lit j becomes lit when L_i > f_lit * L_j, until nothing changes. The
//    default 0.7 sits low in the thesis's 0.66 to 0.9: with lights 9 degrees apart, the
//    smooth fall-off of a lit surface toward grazing loses more than a fifth between
//    neighbours, which 0.8 calls shadow. Just below a feature's own contrast it fails: 0.66
//    mislabels a caustic 1.5 times as bright as its surround.
// 2. Feature upsampling (6.3), `levels` times: every edge of the Delaunay triangulation of
//    the directions so far gets its midpoint k. H_k: compact highlights matched between
//    the two layers (mutual nearest energy centroids within `blob_reach` pixels, and the one
//    moved onto the other covering at least half of it) move rigidly half-way: a reflected
//    small light is a blob of a few pixels that the flow cannot track, yet its centroid is
//    exact. A glossy streak that changes shape goes to the flow. A highlight with no
//    highlight near it in the other layer is seen from one end of the edge only, a glint
//    narrower in light directions than the sampling (the bottle's glass edges): it stays in
//    place, scaled by the overlap of the two light kernels (one_sided_highlight_weight), so
//    it vanishes at a midpoint more than two kernel radii away instead of being smeared
//    half-bright over the edge as blending does. The rest: optical flow (OpenCV's
//    Farneback) both ways on clamped, blurred highlight luminance, both layers warped
//    half-way with their full range (each keeping its total energy) and averaged. Where
//    the two lights' discs overlap (an edge shorter than two kernel radii: a wide,
//    frost-like light, or the close directions of an adaptive capture), a mirror pixel lit
//    at both ends is lit at the midpoint too, since the lens the discs share lies in the
//    midpoint's disc, and much of a highlight may not move at all; what the flow, carried
//    all the way, lays onto the other layer no closer than it already lies stays in place,
//    pixel by pixel (the mean where both are lit). A highlight lit at one end only keeps
//    midpoint_highlight_weight, the share of that end's own light the midpoint sees
//    (one_sided_highlight_weight where the discs are apart). Glints that are thin segments,
//    shrinking in place as the light leaves their track, are still partly moved rigidly by
//    the matching: such a field is better blended.
//    S_k: level-set blending: the two maps' signed distance functions, each carried
//    half-way along the flow between them, averaged, and re-quantised to 0/1 at the zero
//    level set. (The plain mean of two distance functions, without the flow, shrinks a
//    sliding shadow to the overlap.)
//    Glossy lobes (not in the thesis): a pixel whose highlight shows in `lobe_samples` (8)
//    or more inputs, all within `lobe_spread_deg` (30) of one axis, has its highlight
//    sampled as a function of the light direction, and the samples say more than the two
//    layers of an edge: a von Mises-Fisher lobe fitted to them (fit_highlight_lobe) gives
//    H_k there at every new direction next to an input that shows the highlight at that
//    pixel. The lacquer of the figure scene (GGX, roughness 0.12) makes streaks that
//    split and bend between neighbouring lights, which neither the matching nor the flow
//    follows. The spread test keeps out pixels with two highlights and the glass's
//    caustics. A lobe at least as wide as the edge (angular_width() >= the angle between
//    its ends) is sampled finely enough that the two ends' mean beats the fit, whose
//    log-linear model is only right near the peak: there H_k is that mean. A lobe broader
//    than the spread allows is mostly turned away by the spread test; a wider spread
//    catches it but costs the spheres under an area light, so 30 stays the default.
// 3. Synthesis (6.4.1), per new direction k in input triangle (a, b, c) with barycentric
//    weights: blurred shadow maps S-bar = the mean S over the `blur_neighbours` nearest
//    directions (inputs and new ones). The thesis averages 10; the default here is 1 (S-bar =
//    S): with 10 after one level the average spans a whole input spacing and blurs moving
//    shadows (after two levels the two tie). Uncertain pixels, 0 < S-bar < 1, then come
//    from the fit alone. Where S-bar_a = S-bar_b = S-bar_c = 1 the lit value is
//    the barycentric blend of D; where all are 0 the shadowed value is; otherwise the value
//    is extrapolated by a least-squares fit of two spherical-harmonic bands (1, x, y, z) to
//    the `fit_neighbours` nearest inputs labelled lit (or shadowed) at the pixel, weighted by
//    closeness and by the label's reliability (S-bar). R_reco = S-bar_k * lit +
//    (1 - S-bar_k) * shadowed.
// 4. Image-based priors (6.4.2, relight/image_priors.hpp): the extrapolated pixels of R_reco
//    and those at an edge of S_k are regularised, `priors.iterations` times (3), against
//    the 5 x 5 windows of the highlight-free inputs D of the triangle around k, matched up
//    to an intensity scale. R_k = R_reco + H_k. They help on the diffuse part of the image
//    and cost most of the time per new image.
//
// Where it fails stays no worse than linear blending: a pixel with no reliable samples of
// the needed state falls back to the barycentric blend, pixels that are black in every
// image are never highlights, a highlight-free pair of images skips the flow, and shadow
// maps that do not overlap blend to whatever their mean distance says (the thesis's
// grazing-angle limitation, 6.5.1).
//
// What each rule gains, with the commands that reproduce it: docs/results.md, "Feature-guided
// upsampling" (the rules one by one, overlapping lights, time).
//
// The stages have their own headers, which include none above them: upsample_types.hpp
// (the options and what the stages pass on), upsample_features.hpp (P, the shadow maps and
// what carries a direction's features), upsample_highlights.hpp (masks, removal, half-way
// layers, one-sided weights, glossy lobes), upsample_synthesis.hpp (the new images).
//
// Example: UpsampledField up = upsample_field(read_field("in"), 1, UpsampleOptions{});

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <vector>

#include <Eigen/Core>

#include "core/image.hpp"
#include "relight/field.hpp"
#include "relight/upsample_types.hpp"

namespace rfd::relight {

struct UpsampleStatistics {
    std::size_t inputs = 0;
    std::size_t synthesized = 0;
    double highlight_fraction = 0.0;       ///< of input pixels marked as highlight
    double lit_fraction = 0.0;             ///< of input pixels labelled lit
    double extrapolated_fraction = 0.0;    ///< of synthesized pixels that needed the SH fit
    double fallback_fraction = 0.0;        ///< of synthesized pixels without reliable samples
    std::size_t guard_probes = 0;          ///< inputs held out to judge the tiles (0: no guard)
    std::size_t guarded_tiles = 0;         ///< tiles judged
    std::size_t upsampled_tiles = 0;       ///< of them, those keeping the upsampled images
};

/// The guard's factor: a tile keeps the upsampled images when their leave-one-out error there
/// is below this share of blending's.
inline constexpr double kGuardMargin = 0.9;

/// Where upsampling is trusted: per tile, 1 where the upsampled images predicted the held-out
/// inputs better than blending did (by kGuardMargin in sum, and for at least three quarters
/// of them), else 0.
/// The probes are inputs inside the others' triangulation: new images on the edges of the
/// inputs' outer ring (both ends on it, and the new images between such) are never judged
/// and are blended everywhere.
struct UpsampleGuard {
    int tile = 0, columns = 0, rows = 0;
    std::vector<double> upsampled;       ///< per tile, row-major
    std::vector<std::size_t> probes;     ///< the inputs held out
    /// Per pixel, the tiles' values interpolated bilinearly between their centres.
    Image pixel_weights(int width, int height) const;
};

struct UpsampledField {
    ReflectanceField field;            ///< the inputs first, in their order, then the new images
    UpsampleStatistics statistics;
    /// Per new image, the two images (indices into field) whose edge it halves.
    std::vector<std::array<std::size_t, 2>> parents;
};

/// Upsamples `field` by `levels` rounds of edge subdivision (0 returns it unchanged).
/// InputError for fewer than 4 images, levels outside [0, 4] or options out of range
/// (f_highlight <= 1, f_lit outside (0, 1], an even dilation, neighbour counts < 1, lobe
/// samples 1 to 3 or a lobe spread outside (0, 180]);
/// what SphericalInterpolator throws for its directions. Deterministic.
UpsampledField upsample_field(const ReflectanceField& field, int levels, const UpsampleOptions& options);

/// The guard of upsample_field (options.guard_tile > 0): up to options.guard_probes inputs,
/// interior to the others' triangulation and spread over them, each held out in turn; the
/// others upsampled around it (the three new directions on the edges of the triangle that
/// holds it) and it relit with and without them. The errors are of display values
/// (sRGB-encoded), as 8-bit captures are judged. No probes (no interior input): every tile 1.
UpsampleGuard judge_tiles(const ReflectanceField& field, const UpsampleOptions& options);

}  // namespace rfd::relight
