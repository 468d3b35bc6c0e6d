#pragma once
// Predicted display output against the software relighting of the same field (issue 5):
// how faithfully a Design I or II display, its pattern as printed, shows the field it was
// encoded from.
//
// For a light from field direction v (unit, toward the light, core/sphere.hpp's frame) the
// display is lit from display direction d = mapping.display_direction(v) (unit, direction
// of travel, optics/analysis.hpp's frame), kappa the angle of d to the array's normal.
//
//   prediction  P_l = DisplaySimulator::simulate, then the mean irradiance over lenslet l's
//               cell on the diffuser (per_lenslet), relative to the light's irradiance on a
//               plane facing it;
//   reference   Q_l = W_l(d) T( R_l(v) / cos(kappa) ),
//               R_l(v) = sum_i w_i(v) R_i,l: the field's images box-filtered over lenslet
//               l's footprint (Encoder::lenslet_sample, the encoder's image fit) and blended
//               with the encoder's interpolation weights w_i (its SphericalInterpolator and
//               method). R_l(v) / cos(kappa) is exactly the value the encoder writes in the
//               dots of lenslet l that the chief ray of d reaches; T is the print's tone
//               mapping (print::ToneMap::stack_transmittance: brightness / white, clamped,
//               the stack's black level),
//               so T(...) is the transmittance a perfect display shows there (transmittance()).
//               W_l(d) is the scale: the same simulation with a clear print (transmittance 1
//               everywhere), sampled as P is: the display's flat field, a property of the
//               design and the direction (the light falling into the lenslet, cos(kappa);
//               Fresnel losses; vignetting; the macro-pixel's spread), not fitted to the
//               pattern. Its mean over the array is about eta(d) cos(kappa), eta the optical
//               efficiency the simulator reports (DirectionComparison::efficiency). A single
//               least-squares gain is also fitted and reported beside it.
//   macro-pixel cores: a Design II whose corrective pair images each lenslet onto the
//               diffuser at |m| > 1 (the preset: 1.157x with real 2 mm lenslets) spreads a
//               macro-pixel over m^2 times its cell, overlapping its neighbours by
//               (|m| - 1)/2 of a pitch on each side. The mean over the whole cell
//               (per_lenslet) then mixes about 1 - 1/m^2 of the neighbours' light in: the
//               overlap is real crosstalk, reported as the "cell" figures. The headline P_l
//               and W_l are means over the cell's core, the cell shrunk about its centre by
//               c = 2 - |m| (macro_pixel_core: what no neighbour reaches; less the one pixel
//               the simulator's bilinear splat reaches further). Design I (no corrective
//               pair) and |m| <= 1 use the whole cell.
//   error       P - Q per lenslet and channel; PSNR = 10 log10(peak^2 / MSE) with peak
//               the largest reference value over lenslets and channels, MSE over them all.
//   field of view: the directions whose chief ray through the centre lenslet lands inside
//               its cell on the pattern plane (no wrap-over; `rfd design show`'s field of
//               view). Inside it, a narrower cone is crosstalk-free: the lenslet's full
//               bundle lands inside its cell (`rfd design show`'s "crosstalk begins").
//               Between the two, part of each spot lands under the neighbouring lenslet.
//
// Images at the display's resolution: count_x by count_y, row 0 at the top (lattice row
// count_y - 1), as DisplaySimulator::per_lenslet lays them out.
//
// Example: DisplayComparison cmp(simulator, transparency, encoder, tone);
//          DirectionComparison r = cmp.compare(direction_from_angles(0.1, 0.0), {});

#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/options.hpp"
#include "core/image.hpp"
#include "optics/display.hpp"
#include "patterns/encode.hpp"
#include "print/printer.hpp"

namespace rfd::predict {

/// How many light directions `simulate compare` (and a project's compare step) sweeps.
inline constexpr IntegerOption kSweepOption{"--sweep", "compare_sweep", "", 0, 1000, 9,
                                            "Light directions spread over the display's range, the first on its "
                                            "axis (0: only --light)"};

/// The macro-pixel core of the header for a design: c = clamp(2 - |m|, 0.25, 1) and m (the
/// corrective pair's magnification of A onto the diffuser) for Design II with |m| > 1;
/// c = 1, m = 1 otherwise.
struct MacroPixelCore {
    double fraction = 1.0;       ///< c, linear, of the cell about its centre
    double magnification = 1.0;  ///< |m|
};
MacroPixelCore macro_pixel_core(const optics::DesignOptics& optics);

/// The mean of `image` over the core of each lenslet's cell (the cell shrunk by `fraction`
/// about its centre), laid out as DisplaySimulator::per_lenslet; fraction 1 is per_lenslet.
/// Lenslets whose core holds no pixel centre read 0: use a few pixels per pitch or more.
Image per_lenslet_core(const optics::Lattice& lattice, const optics::DiffuserImage& image, double fraction);

/// Prediction against reference, both count_x x count_y x channels, same units.
struct ImageComparison {
    Image error;                 ///< prediction - reference (signed)
    double peak = 0.0;           ///< largest reference value (the PSNR's peak)
    double mse = 0.0;            ///< over lenslets and channels
    double psnr_db = 0.0;        ///< 10 log10(peak^2 / mse); +inf when equal
    double fitted_gain = 1.0;    ///< g minimising |g P - Q|^2 (1 when P is all zero)
    double fitted_mse = 0.0;     ///< the MSE of g P against Q
    double psnr_fitted_db = 0.0; ///< the PSNR of g P against Q
};
/// Compares two images of one shape (RFD_CHECK'ed). A zero peak gives psnr 0 unless equal.
ImageComparison compare_images(const Image& prediction, const Image& reference);

/// One light direction compared.
struct DirectionComparison {
    Eigen::Vector3d field_direction = Eigen::Vector3d::UnitZ();    ///< toward the light, field frame
    Eigen::Vector3d display_direction = Eigen::Vector3d::UnitZ();  ///< travel, optics frame
    double display_angle_deg = 0.0;  ///< kappa, the angle of d to the array's normal
    bool inside_field_of_view = false;  ///< chief ray inside the cell (no wrap-over)
    bool crosstalk_free = false;        ///< full bundle inside the cell
    double efficiency = 0.0;         ///< eta(d): the simulator's optical efficiency
    MacroPixelCore core;             ///< where P and Q of the header are taken
    Image prediction, reference;     ///< per lenslet (cores), row 0 at the top
    ImageComparison comparison;
    /// The same over whole cells (per_lenslet): with the macro-pixels' overlap.
    Image cell_prediction, cell_reference;
    ImageComparison cell_comparison;
    std::size_t rays = 0;            ///< rays the simulation traced
    double seconds = 0.0;            ///< wall time of the simulation and the reference
};

/// The field a pattern was encoded from, read as its encoder read it (the options the
/// pattern records), and that encoder: the reference side of a comparison. InputError,
/// naming the field, when it is not the pattern's field (other channels or another white).
/// Not movable: the encoder keeps the field by reference.
class EncodedField {
public:
    EncodedField(const optics::Design& design, const std::string& pattern_file, const patterns::PatternGeometry& geometry,
                 double pattern_white, const std::string& field_path);
    EncodedField(const EncodedField&) = delete;
    EncodedField& operator=(const EncodedField&) = delete;
    const patterns::Encoder& encoder() const { return *encoder_; }
    const relight::ReflectanceField& field() const { return field_; }

private:
    relight::ReflectanceField field_;
    std::unique_ptr<patterns::Encoder> encoder_;
};

class DisplayComparison {
public:
    /// `encoder` must be built from the pattern's field with the options the pattern was
    /// encoded with (patterns::encode_options_of) on the design of `simulator`; the three
    /// are kept by reference. `tone` is the print's (print::PrintedTransparency::tone()).
    DisplayComparison(const optics::DisplaySimulator& simulator, const optics::Transparency& pattern,
                      const patterns::Encoder& encoder, const print::ToneMap& tone);

    /// T(R_l(v) / cos(kappa)) of the header for field direction v, per lenslet (3
    /// channels): what a perfect display shows relative to its clear-print response.
    Image transmittance(const Eigen::Vector3d& field_direction) const;
    /// True when the exact chief ray of display direction d through the centre lenslet
    /// lands inside that lenslet's cell on the pattern plane (no wrap-over).
    bool inside_field_of_view(const Eigen::Vector3d& display_direction) const;
    /// True when its full bundle (16 x 16 rays, exact) does: no crosstalk.
    bool crosstalk_free(const Eigen::Vector3d& display_direction) const;
    /// Prediction, reference and their comparison under a light of unit irradiance (white)
    /// from field direction v. InputError when v maps to no display direction (d.z <= 0).
    DirectionComparison compare(const Eigen::Vector3d& field_direction, const optics::SimulationOptions& options) const;

    /// `count` field directions spread over the display's range (kSweepOption): display directions on a
    /// golden-angle spiral over the disc of angles up to the encoder's DisplayRange
    /// max_angle_rad (the cell's corners), the first on the axis; deterministic. Directions
    /// past the flat sides of the cell fall outside the field of view and are kept, so a
    /// sweep also shows where the display stops.
    std::vector<Eigen::Vector3d> sweep(int count) const;

    const patterns::Encoder& encoder() const { return encoder_; }
    const MacroPixelCore& core() const { return core_; }

private:
    const optics::DisplaySimulator& simulator_;
    const optics::Transparency& pattern_;
    const patterns::Encoder& encoder_;
    print::ToneMap tone_;
    MacroPixelCore core_;
};

/// The three panels of a comparison side by side for viewing: prediction | reference |
/// |error| x `error_gain`, each divided by the reference's peak, a lenslet drawn as
/// `pixels_per_lenslet` square pixels, panels parted by a grey gap of one lenslet.
Image side_by_side(const DirectionComparison& result, int pixels_per_lenslet, double error_gain);

/// The simulator's speed against its accuracy: per-lenslet predictions of each model and
/// ray count against a converged one (exact model, `reference_rays` rays per side), over
/// the given display directions; times measured in the same run (wall clock, all cores).
struct AccuracyModel {
    std::string label;  ///< "paraxial", "exact", "auto (exact)"
    optics::Model model = optics::Model::Paraxial;
};
struct AccuracyPoint {
    std::string label;
    int rays_per_side = 0;
    std::size_t rays = 0;       ///< traced over all directions
    double seconds = 0.0;       ///< simulation time over all directions
    double mse = 0.0;           ///< mean over directions of the per-lenslet MSE
    double psnr_db = 0.0;       ///< peak: the converged prediction's maximum over directions
    double worst_psnr_db = 0.0; ///< the lowest per-direction PSNR
    std::vector<double> psnr_per_direction_db;  ///< peak: that direction's converged maximum
    /// The same after one least-squares gain per direction: the error of the picture's
    /// shape, without the overall scale (the paraxial model has no Fresnel losses, about
    /// 21 % of the light through Design II's four uncoated surfaces).
    double fitted_mse = 0.0;
    double fitted_psnr_db = 0.0;
    std::vector<double> fitted_psnr_per_direction_db;
};
std::vector<AccuracyPoint> accuracy_sweep(const optics::DisplaySimulator& simulator,
                                          const optics::Transparency& pattern,
                                          const std::vector<Eigen::Vector3d>& display_directions,
                                          const std::vector<AccuracyModel>& models,
                                          const std::vector<int>& rays_per_side, int reference_rays,
                                          const optics::SimulationOptions& base);

}  // namespace rfd::predict
