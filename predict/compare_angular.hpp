#pragma once
// Designs III and IV judged as a viewer sees them: the display, its pattern as printed, lit
// by one distant light and seen from one distant viewpoint, against the 6D field it was
// encoded from, relit and viewed the same way.
//
// For a light whose travel direction is d (display frame; the field sees it as a light at
// field_light_of(d), patterns/angular.hpp) and a viewpoint toward o (unit, from the display
// to the observer, which is also the field's view direction):
//
//   prediction  P_m = AngularDisplaySimulator::simulate from o under d, then the mean over
//               macro-pixel m's meso-pixels (per_macro_pixel: an observer too far away to
//               resolve them, as the thesis's camera);
//   reference   Q_m = W_m T(R_m): R_m the field at the light itself (not the mean over its
//               incident bin: a bin's quantisation of the light is the display's error),
//               toward o, at macro-pixel m; T the print's tone map (value / white, clamped,
//               the stack's black level: print::ToneMap::stack_transmittance), so T(R_m) is
//               the transmittance a perfect pattern shows; W_m the same simulation with a
//               clear print: the display's flat field for this light and viewpoint (the
//               light the meso lenslet receives, vignetting, the cos terms, crosstalk's
//               loss), a property of the optics, not fitted to the pattern.
//   error       P - Q per macro-pixel and channel; PSNR against the brightest reference of
//               every pair compared (as the verdict's), and each pair's own.
//   ceiling     C_m = W_m T(R_m(bin)): the bins' bound on any pattern. Every light of an
//               incident bin lights the same dots the same way (the main lens's image fills
//               the pattern whatever the light's place in the bin: thesis 8.3.1), so no
//               pattern shows more than one value per bin, view and macro-pixel, and the one
//               nearest R over the bin's lights is their mean (the encoder's bin samples;
//               the light's bin is the meso cell its chief ray lands in). C against Q is an
//               upper bound on what any pattern reaches: it leaves out the crosstalk (light
//               of a bin's dots leaving through a neighbouring projection lenslet in a wrong
//               direction, which a pattern can only trade against the right direction) and
//               the borders between bins (where a light's spot straddles two cells and the
//               display mixes their values).
//
// The pairs: lights on an n x n grid over the meso array (incident slopes offset / B, B the
// main lens's map, inside 0.9 of the array's half-extent: every bin and the borders between
// them) and viewpoints on an m x m grid over the output cone (slopes gain * offset, inside
// 0.7 of half a meso cell: where every dot of the cell is lit). A grid offset by half a
// step is a held-out set of the same size.
//
// Example: AngularComparison cmp(simulator, printed, *lookup, lights, tone, options);
//          const PairComparison r = cmp.compare(0, view);

#include <memory>
#include <vector>

#include <Eigen/Core>

#include "core/image.hpp"
#include "optics/display_angular.hpp"
#include "patterns/angular_fields.hpp"
#include "predict/compare.hpp"
#include "print/printer.hpp"

namespace rfd::predict {

/// Light travel directions (display frame) on a side x side grid over the meso array, and
/// viewpoint directions on a side x side grid over the output cone (see the header), side
/// >= 2; `midpoints`: the (side - 1)^2 points halfway between those (the held-out set).
std::vector<Eigen::Vector3d> angular_light_grid(const optics::AngularDisplaySimulator& simulator, int side,
                                                bool midpoints = false);
std::vector<Eigen::Vector3d> angular_view_grid(const optics::AngularDisplaySimulator& simulator, int side,
                                               bool midpoints = false);

/// One light and viewpoint compared.
struct PairComparison {
    Eigen::Vector3d light = Eigen::Vector3d::UnitZ();  ///< travel, display frame
    Eigen::Vector3d view = Eigen::Vector3d::UnitZ();   ///< toward the observer
    double light_angle_deg = 0.0, view_angle_deg = 0.0;
    Image prediction, reference, flat;  ///< per macro-pixel (macro_x x macro_y), row 0 at the top
    ImageComparison comparison;          ///< against the pair's own brightest reference
    Image ceiling;                       ///< what the best pattern shows (C of the header)
    ImageComparison ceiling_comparison;  ///< ceiling against reference
    double crossed_fraction = 0.0;       ///< of the light entering, leaving through a neighbour
};

class AngularComparison {
public:
    /// `lights` are the light travel directions that will be compared (the field is bound
    /// to each as a bin of its own); `field` must be the pattern's. Keeps references.
    AngularComparison(const optics::AngularDisplaySimulator& simulator, const optics::Transparency& printed,
                      const patterns::AngularField& field, std::vector<Eigen::Vector3d> lights,
                      const print::ToneMap& tone, const optics::AngularSimulationOptions& options);
    AngularComparison(const AngularComparison&) = delete;
    AngularComparison& operator=(const AngularComparison&) = delete;
    ~AngularComparison();

    const std::vector<Eigen::Vector3d>& lights() const { return lights_; }
    /// Light `light` (an index into lights()) seen from `views`: one comparison per view.
    std::vector<PairComparison> compare(std::size_t light, const std::vector<Eigen::Vector3d>& views) const;

private:
    const optics::AngularDisplaySimulator& simulator_;
    const optics::Transparency& printed_;
    std::vector<Eigen::Vector3d> lights_;
    std::unique_ptr<patterns::AngularLookup> lookup_;       // one bin per compared light
    std::unique_ptr<patterns::AngularLookup> bin_lookup_;   // the display's bins (meso cells)
    std::vector<std::size_t> bin_of_;                       // per compared light; lattice_cells_: none
    std::size_t lattice_cells_ = 0;
    const print::ToneMap& tone_;
    optics::AngularSimulationOptions options_;
    int channels_ = 1;
};

}  // namespace rfd::predict
