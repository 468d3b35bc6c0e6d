#pragma once
// The two models of light every analysis, encoder and simulator takes, and the user's
// choice between them: one of the two, or `auto`, the cheapest one that places every dot
// within a tolerance of where the exact optics put it.
//
// Example: ResolvedModel m = resolve(ModelChoice::Auto, DesignOptics(design), optics.dot_mm());
//          // m.model == Model::Paraxial for Design I at the Epson's 2880 x 1440 dpi

#include <array>
#include <optional>
#include <string>
#include <string_view>

#include <Eigen/Core>

#include "core/options.hpp"
#include "core/names.hpp"

namespace rfd::optics {

class DesignOptics;

enum class Model { Paraxial, Exact };
/// As the command line, JSON reports and a pattern's rfd:model attribute spell them.
inline constexpr std::array kModelNames{Named{Model::Paraxial, "paraxial"}, Named{Model::Exact, "exact"}};
std::string_view to_string(Model model);

/// What a user asks for (`--model`). Diffraction: exact rays, and the simulators see the
/// pattern through the lenslets' point-spread function (optics/diffraction.hpp).
enum class ModelChoice { Auto, Paraxial, Exact, Diffraction };
inline constexpr std::array kModelChoiceNames{Named{ModelChoice::Auto, "auto"}, Named{ModelChoice::Paraxial, "paraxial"},
                                              Named{ModelChoice::Exact, "exact"},
                                              Named{ModelChoice::Diffraction, "diffraction"}};

/// The model a choice comes to for one design at one print resolution.
struct ResolvedModel {
    Model model = Model::Paraxial;
    ModelChoice choice = ModelChoice::Auto;
    /// Designs I/II: the paraxial map's largest landing error over one cell against the
    /// exact trace, in dots (along x or y). Designs III/IV: none (not estimated).
    std::optional<double> paraxial_error_dots;
    /// The central lobe of the lenslets' PSF on the pattern at 650 nm, in dots (the larger
    /// of x and y); computed for Auto and Diffraction.
    std::optional<double> diffraction_lobe_dots;
    /// The simulators see the pattern through the PSF (DiffractedTransparency).
    bool diffraction = false;
    std::string reason;  ///< one line: why this model ("as asked", "auto: ...")
};

/// Paraxial or Exact as asked; Diffraction: exact with the blur; Auto: for Designs I/II
/// paraxial when paraxial_error_dots <= tolerance_dots, exact otherwise, and the blur where
/// the PSF's central lobe at 650 nm exceeds tolerance_dots; for Designs III/IV exact (their meso-pixel maps
/// have no paraxial error estimate, and the angular simulator traces its rays once for all
/// macro-pixels, so the exact model costs little there). `dot_mm` is the print dot on
/// the pattern plane (x, y); the error is measured at the cell's centre, on rings toward
/// its boundary, on the boundary and at its corners (probe_offsets).
/// --tolerance of --model auto, every command's.
inline constexpr NumberOption kModelToleranceOption{
    "--tolerance", "", "print dots", 0.0, 1000.0, 0.25,
    "--model auto: the largest error of the paraxial model on the pattern plane before the exact one is used"};
ResolvedModel resolve(ModelChoice choice, const DesignOptics& optics, const Eigen::Vector2d& dot_mm,
                      double tolerance_dots = kModelToleranceOption.fallback);

}  // namespace rfd::optics
