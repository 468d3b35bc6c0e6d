#pragma once
// The lens array's true pitch and rotation from photographs of the moire sheet mounted in the
// display in its pattern's place, lit from behind by the sun (print/moire.hpp; how to take
// them: docs/usage.md), continuously, not by picking a band (thesis 8.4.1 picked the band with
// the least moire by eye).
//
// Each lenslet shows, on the diffuser, how much light the sheet lets through at its focus:
// lenslet k at array position a_k (design frame, calibrate/moire_photo.hpp) focuses on page
// point Y_k = c + M a_k, and a measuring band whose lines (period p, normal n, one through o)
// are half a period wide reads
//     b_k = E(k) G((n . Y_k - n . o) / p),
// G the lines seen through a Gaussian spot (B off the lines, D on them, the lines' width w and
// the spot's size s unknown: the printer's dot gain and the lens's blur) and E a smooth light
// falloff (a quadratic over the band). The band's period is not the pitch, so across the
// array the lenslets read every phase of the lines (a vernier): n^T M and n . c are fitted
// from where each lenslet falls against them. The x band gives sx and the row band sy, M
// being F R(theta) diag(sx, sy) (moire_photo.hpp); a band's slant of a few degrees mixes in
// the turn, which the other entry of n^T M gives.
//
// Steps: the sheet's marks give the page-to-photo homography (sheet_finder.hpp); the diffuser
// is the darker region over the measuring bands; its lattice of lenslet images (the diffuser
// lies nearer the camera than the sheet: the array magnified by parallax, not turned) is
// found from the peaks of its Fourier transform near the design's, on the image over its
// local mean (the moire's slow modulation would add peaks beside the lattice's); every lenslet
// image fully inside it and off the array's edge is read over its central part; each band is
// searched on a grid for the phase coherence of its lenslets within +-1 % of the design's
// pitch, then fitted by least squares (Eigen's Levenberg-Marquardt), outliers (over 5 robust
// standard deviations) dropped, and fitted again. Uncertainties: the fit's own, or the
// delete-a-group jackknife's over 8 groups of lenslets when larger (sharp lines inform only
// near their edges, which the fit's own understates).
//
// An array too small for the bands to cross under it (Design II's 6 x 5) is laid whole on each
// band in turn (print::MoireSheet::whole_array) and read whole, outer lenslets too. Its
// lenslet images lie on the diffuser above the sheet and look larger by kappa = Z / (Z - h),
// Z the camera's height over the sheet and h the diffuser's; its 30 images are too few for
// the spectrum to give that to the 0.5 % the reading needs, so the lattice is kappa times the
// design's cells, turned as the spectrum says, with Z from the photograph's pose
// (calibrate/camera.hpp: a tilted photograph). Its reading discs see the middle of each
// lenslet (the corrective pair images the lenslet on the diffuser), whose spot is traced
// through the exact optics; the 6 x 5 block is the one ringed by the darkest points (the
// holder); where each lenslet focuses is where its image is, the parallax undone; and the fit
// starts from the smoothest row too (phase dispersion), keeping the better fit: a few lenslets'
// coherence can peak beside the true row.
//
// Where it stops: marks not all in view, no darker diffuser region, fewer than 12 lenslets
// inside both bands, lenslets reading fewer than 16 of 20 phases of a band's lines (an array
// turned against the slant; fewer for a few lenslets, which fill fewer even at random), or
// lines no deeper than 4 times the noise (blurred, dark, the array not over the bands); a
// whole array photographed within 10 deg of frontal, or not all in view: InputError, saying
// which. Arrays of fewer than 24 lenslets are refused before any photograph is read
// (check_pitch_readable).
//
// Example: PitchReading reading = read_pitch_photo(photo, "photo.jpg", design, sheet);

#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/image.hpp"
#include "optics/design.hpp"
#include "print/moire.hpp"

namespace rfd::calibrate {

/// One lenslet's reading, for the picture of the fit.
struct LensletReading {
    Eigen::Vector2d page = Eigen::Vector2d::Zero();  ///< where its light is seen, page mm
    double value = 0.0;                              ///< mean over its central part, linear
    int band = -1;                                   ///< index into the sheet's bands
    bool along_x = true;                             ///< the band's lines are vertical
    double light = 1.0;                              ///< the fitted light falloff E there
    double phase = 0.0;                              ///< fitted, periods
    double fitted = 0.0;                             ///< the model's value
    bool outlier = false;
};

/// One axis: its row of the array-to-page map, fitted from that axis's measuring band
/// (lenslets 0: the band is not under the array in this photograph).
struct AxisFit {
    bool along_x = true;
    double normal_angle = 0.0;                      ///< of the band's lines' normal n, page frame, rad
    Eigen::Vector2d row = Eigen::Vector2d::Zero();  ///< n^T M: the map's row along n
    double offset = 0.0;                            ///< n . c, mm
    Eigen::Matrix2d row_covariance = Eigen::Matrix2d::Zero();
    double rms = 0.0;          ///< residual over the mean reading
    double contrast = 0.0;     ///< (max - min) / max of the fitted profile G
    int lenslets = 0, outliers = 0, bands = 0;
    std::vector<double> profile;  ///< G at 64 phases over one period
};

/// The most a large array's lenslet images' lattice departed from the lines' shape in good
/// simulated photographs (0.040 % at 60 deg of tilt; docs/results.md): beyond it the reading's
/// scale uncertainties grow by the excess.
inline constexpr double kLatticeMismatchNoise = 4e-4;

/// What one photograph says.
struct PitchReading {
    std::string name;
    bool mirrored = false;
    double mm_per_pixel = 0.0;
    AxisFit x, y;
    std::vector<LensletReading> lenslets;
    /// A large array read on both bands: how far the lattice of its lenslet images departs
    /// from the shape the lines measure (the larger over the smaller stretch, minus one). The
    /// two are one lattice (the images magnified about the camera's foot); a departure means
    /// the reading discs drift across the images (read_pitch_photo).
    double lattice_mismatch = 0.0;

    /// The reading discs drift across the images: the departure is beyond good photographs'.
    bool discs_drift() const { return lattice_mismatch > kLatticeMismatchNoise; }
};

/// InputError naming the design file when its array is too small for the measuring bands:
/// fewer than 24 lenslets (twice the fit's parameters; the hypothesis bands read by eye serve
/// it).
void check_pitch_readable(const optics::Design& design);

/// Reads one photograph (linear; any channels) of page `page` of `sheet`, printed for
/// `design`. InputError naming `name` where it cannot measure (see the header comment).
PitchReading read_pitch_photo(const Image& photo, const std::string& name, const optics::Design& design,
                              const print::MoireSheet& sheet, int page = 0);

/// The array's measured geometry, over all photographs.
struct PitchCalibration {
    double design_pitch_x = 0.0, design_pitch_y = 0.0;  ///< mm (pitch_y: row spacing)
    double scale_x = 1.0, scale_y = 1.0;                ///< true / design, along a row and across rows
    double sigma_scale_x = 0.0, sigma_scale_y = 0.0;    ///< standard uncertainties
    /// Per photograph: the rows' angle against the sheet's x (counter-clockwise as the camera
    /// sees it), its uncertainty, and the axes' departure from square (NaN when the
    /// photograph shows one measuring band).
    std::vector<double> rotation_deg, sigma_rotation_deg, shear_deg;
    /// Sheet scale (true page mm per nominal page mm, from a ruler): applied to the scales.
    double sheet_scale_x = 1.0, sheet_scale_y = 1.0;

    double pitch_x() const { return design_pitch_x * scale_x; }
    double pitch_y() const { return design_pitch_y * scale_y; }
};

/// Combines readings (inverse-variance weighted), the sheet printed at `sheet_scale` of its
/// nominal size along x and y.
PitchCalibration calibrate_pitch(const optics::Design& design, const std::vector<PitchReading>& readings,
                                 const Eigen::Vector2d& sheet_scale = Eigen::Vector2d::Ones());

}  // namespace rfd::calibrate
