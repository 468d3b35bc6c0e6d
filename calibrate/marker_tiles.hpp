#pragma once
// Design II's corner macro-pixels read as pictures of their registration markers (thesis
// 8.4.1 aligned such markers under a microscope; here the display's own optics are the
// microscope). The corrective pair images each primary lenslet's aperture onto the diffuser,
// and the aperture's zones focus the light on slightly different points about its spot
// (spherical aberration, the sun's disc): a macro-pixel shows the pattern within about
// 0.15 mm of the spot, magnified more than ten times. With the light within about half a
// degree of the display's axis the spot lies on the crosshair of the corner lenslets'
// markers, and the four corner macro-pixels show it: where its lines cross each tile says
// where the spot lies on the marker, whatever the picture around them (a pattern plain within
// its cells, which the macro-pixels' brightness cannot place).
//
// The model: the rays of one lenslet under a light on the axis (exact optics, the sun's
// disc), binned by where they land on the diffuser (squares of kMarkerBinMm over the cell's
// core, where no neighbour's light reaches); bin j of the corner lenslet at c_k reads
//     g_k mean_{r in j} T(p(c_k + q_r)) + o_k,
// q_r the ray's point on the pattern, T the printed pattern with its markers (PatternMap) and
// p the mounting (registration.hpp: b, turn, scale). A light tilted by a little moves every
// q_r by its spot offset, which b takes, as it does for the other lenslets' readings. The fit:
// b searched over kMarkerSearchMm by correlation, then Gauss-Newton on (b, turn, scale) with
// each tile's gain and offset solved linearly at every step; the uncertainty the fit's, or
// the delete-a-tile jackknife's when larger.
//
// Example: MarkerTiles tiles(design);
//          if (auto fit = tiles.read(luminance, array_to_photo, map)) use(fit->parameters);

#include <optional>
#include <vector>

#include <Eigen/Core>

#include "calibrate/registration.hpp"
#include "core/image.hpp"
#include "optics/design.hpp"

namespace rfd::calibrate {

inline constexpr double kMarkerBinMm = 0.2;     // diffuser bins of a corner tile
inline constexpr double kMarkerSearchMm = 0.3;  // the spot's reach from the crosshair searched
/// The tiles show their markers when they vary within themselves by this much (their bins'
/// standard deviation over their mean, averaged): the light's spot near the crosshair (0.5-1.0).
/// An even tile (the spot on clear film: 0.14-0.19 with vignetting, noise and the neighbours'
/// edges) says nothing.
inline constexpr double kMinMarkerContrast = 0.3;
/// A fit of the tiles is taken when it explains them this well, its shift this certain: a
/// homography off by a fraction of a pitch (a picture dark along the display's edge hides its
/// outline) fits at 0.80-0.89 and 0.013-0.024 mm; good fits reach 0.93-0.97 and 0.003-0.007 mm.
inline constexpr double kMinMarkerCorrelation = 0.92;
inline constexpr double kMaxMarkerSigmaMm = 0.01;
/// ... and the light's spot this near the crosshair's centre (|b|): farther, the marker's ring
/// darkens the tiles' outer sides and a fit can drift along a line of the cross while still
/// fitting well (the demo's letters 0.12 mm off centre: within 0.002 mm; 0.14: 0.033 off).
inline constexpr double kMaxMarkerSpotMm = 0.12;

/// A fit of the four corner tiles.
struct MarkerTileFit {
    Eigen::Vector4d parameters = Eigen::Vector4d::Zero();  ///< b_x, b_y (mm), turn (rad), scale error
    Eigen::Matrix4d covariance = Eigen::Matrix4d::Zero();
    double contrast = 0.0;     ///< the tiles' own variation (see kMinMarkerContrast)
    double correlation = 0.0;  ///< of the bins with the model, within each tile
    double rms = 0.0;          ///< residual over the mean bin
    std::size_t bins = 0;      ///< read, over the four tiles
};

class MarkerTiles {
public:
    /// Traces one lenslet of `design` (Design II) under the sun on the axis.
    explicit MarkerTiles(const optics::Design& design);

    /// Fits the corner tiles of the photograph (`luminance`, one channel; the array's frame to
    /// the photo through `array_to_photo`) against `map`; nullopt when they do not show their
    /// markers (contrast under kMinMarkerContrast, or a tile off the photo).
    std::optional<MarkerTileFit> read(const Image& luminance, const Eigen::Matrix3d& array_to_photo,
                                      const PatternMap& map) const;

private:
    // A bin of a corner tile where no neighbour's direct light lands.
    struct TileBin {
        int grid = 0;                         // in the grid of columns_ x rows_ over the lenslet's light
        Eigen::Vector2d centre;               // on the diffuser, from the lenslet's centre
        std::vector<Eigen::Vector2d> points;  // where the rays landing in it crossed the pattern, likewise
        std::vector<double> weights;          // the light each carries to the diffuser
    };
    std::vector<Eigen::Vector2d> corners_;       // the corner lenslets' centres
    std::vector<std::vector<TileBin>> tiles_;    // per corner
    int columns_ = 0, rows_ = 0;
};

}  // namespace rfd::calibrate
