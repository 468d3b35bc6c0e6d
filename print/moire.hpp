#pragma once
// The pitch-calibration sheet of thesis 8.4.1: "we have printed patterns for a set of
// hypotheses and then chosen the distance which minimized the Moire effects that occur
// when rotating the lens array on top of the pattern."
//
// For every pitch hypothesis p the sheet has a band of lines with that period, labelled
// with p: x bands carry vertical lines every p (they measure the lenslet spacing along a
// row), y bands horizontal lines every row spacing (they measure the spacing of the rows).
// A lens array of true pitch P laid on a band of period p, focused on it, shows each
// lenslet's view of the line at an offset growing by p - P per lenslet: fringes of period
// P p / |p - P| (the moire magnifier). The band where the fringes are widest, or vanish so
// the band looks even, has p = P. Lines are a quarter of the period wide.
//
// Hexagonal arrays: rows lie pitch sqrt(3)/2 apart, so the y band of pitch hypothesis p has
// lines every p sqrt(3)/2 and is labelled with both numbers. Rectangular arrays have their
// own y range (default: the x range scaled by pitch_y / pitch_x).
//
// Page frame as layout.hpp (mm, y down). Bands run across the array's width (or the
// printable width, if narrower); as many pages as the bands need.
//
// Example: write_moire_pdf("calib.pdf", design, printer, {parse_pitch_range("2.34:2.38:9", "--pitch")});

#include <array>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/image.hpp"
#include "optics/design.hpp"
#include "print/marks.hpp"
#include "print/printer.hpp"

namespace rfd::print {

/// `steps` pitches from `from` to `to`, both included, evenly spaced (mm).
struct PitchRange {
    double from = 0.0, to = 0.0;
    int steps = 0;
    std::vector<double> values() const;
};

/// Parses "FROM:TO:STEPS" (0 < FROM < TO, 2 <= STEPS <= 200). Throws InputError naming
/// `option` and saying what was expected.
PitchRange parse_pitch_range(const std::string& text, const std::string& option);

/// The hypotheses to print when none are given: the design's pitch along a row +-0.4 % in
/// 9 steps (moulded arrays are made to a few tenths of a percent). InputError when the
/// design has no lenslet array.
PitchRange default_pitch_range(const optics::Design& design);

/// A line's width, of its period (hypothesis bands).
inline constexpr double kMoireLineFraction = 0.25;

/// The lens array the sheet calibrates: the pattern plane's, else the first. InputError when
/// the design has none.
const optics::Lattice& moire_lattice(const optics::Design& design);

struct MoireOptions {
    PitchRange x;                  ///< pitch along a row, mm
    std::optional<PitchRange> y;   ///< rectangular arrays: row spacing; default x scaled
    double band_height = 10.0;     ///< mm
    /// Standard deviation of a lenslet's spot on the sheet along x and y, mm, for the measuring
    /// bands' period; default: lenslet_spot(design).
    std::optional<Eigen::Vector2d> spot_mm;
    std::filesystem::path preview; ///< also a PNG of the first page here, when not empty
};

/// One band of the sheet.
struct MoireBand {
    bool along_x = true;   ///< vertical lines (x pitch) or horizontal lines (row spacing)
    double pitch = 0.0;    ///< the hypothesis, mm
    double period = 0.0;   ///< line period printed, mm (row spacing for y bands)
    int page = 0;          ///< 0-based
    double top = 0.0;      ///< band's top edge, page frame mm
    double left = 0.0, width = 0.0, height = 0.0;  ///< the rest of its rectangle, mm
    double line_fraction = kMoireLineFraction;     ///< a line's width, of the period
    bool measuring = false;                        ///< a measuring band (see MoireSheet)
    /// The lines' turn from square to the band, counter-clockwise on the page (y down),
    /// radians: 0 but for measuring bands.
    double slant_rad = 0.0;
    /// A rectangle (left, top, width, height) inside it left bare: where the measuring
    /// bands cross. Width 0: none.
    std::array<double, 4> hole{};
    /// Lines of graded density: across them the transmittance runs as a cosine from bare film
    /// (between lines) to full ink (on a line's centre), instead of sharp lines line_fraction
    /// of the period wide. Any lens blur leaves a cosine a cosine (only its depth falls), so
    /// every lenslet reads its phase whatever its spot (print/moire.cpp says where it is used).
    bool graded = false;

    /// Whether page point (x, y) lies in the band and not in its hole.
    bool inside(double x, double y) const;
    /// The unit normal to the lines, page frame: (1, 0) or (0, 1) turned by the slant.
    Eigen::Vector2d normal() const;
    /// Whether page point (x, y) mm lies on one of the band's lines (line_fraction of the
    /// period wide, one centred in the band across the lines).
    bool inked(double x, double y) const;
    /// How much ink page point (x, y) mm gets, as the part of the way from bare film's
    /// transmittance to full ink's: 0 or 1 on sharp lines (inked), (1 + cos(2 pi phase)) / 2
    /// on graded ones, phase 0 on the centred line; 0 outside the band.
    double ink(double x, double y) const;
};

/// The sheet laid out: its bands page by page and the registration marks every page carries.
/// Above the hypotheses, two measuring bands (x, then rows) for `rfd calibrate pitch`: lines
/// half a period wide (graded, for an array laid whole on them) whose period is not the pitch, so that across the array the lenslets
/// read every phase of them (measuring_period), slanted a few degrees so that the lenslets of
/// one column (x) or one row (rows) read different phases too.
struct MoireSheet {
    std::vector<MoireBand> bands;      ///< the hypotheses, for the eye
    std::vector<MoireBand> measuring;  ///< x, rows
    SheetMarks marks;
    int pages = 1;
    /// The measuring bands do not cross: the array (too small for a cross) is laid whole on
    /// each in turn and photographed there.
    bool whole_array = false;
};

/// The calibration's light: the sun, a disc of this angular radius, rad.
inline constexpr double kSunRadius = 0.00465;

/// The standard deviation of a lenslet's spot on the pattern plane along x and y, mm, under
/// the sun (a disc 0.53 deg across) on the axis, traced exactly (Designs I and II; 0.02 mm
/// for others).
Eigen::Vector2d lenslet_spot(const optics::Design& design);

/// A measuring band's line period for lenslets `spacing` mm apart, `count` of them across the
/// band, a spot of `spot` mm and printer dots of `dot` mm: spacing / (n + drift), n lines per
/// lenslet (about 5 spots or 12 dots a line, 1 to 40), drift 0.2 + 2 / count (at most 0.45):
/// from one lenslet to the next the phase steps by a fifth of a period, and over the array it
/// drifts by two more periods, so the lenslets read every phase. An array laid whole on the
/// band (`whole_array`) drifts by a quarter period per lenslet and gets graded lines about
/// 5.3 spots apart (print/moire.cpp says why).
double measuring_period(double spacing, int count, double spot, double dot, bool whole_array = false);

/// Whether the sheet for `design` on `paper` lays the array whole on each measuring band in
/// turn (MoireSheet::whole_array: the array too small for the bands to cross under it).
bool lays_array_whole(const optics::Design& design, const Paper& paper);

/// The bands for `options` on the printer's paper. InputError when the design has no lenslet
/// array or a band does not fit the printable area.
MoireSheet moire_sheet(const optics::Design& design, const PrinterProfile& printer, const MoireOptions& options);

/// Draws page `page` of the sheet (user units: page-frame mm): header, marks, labels, lines.
void draw_moire_page(cairo_t* cr, const MoireSheet& sheet, const optics::Design& design,
                     const PrinterProfile& printer, int page);

/// Page `page` as the printer receives it, at `px_per_mm` (see page_codes: 1 is no ink).
Image moire_page_codes(const MoireSheet& sheet, const optics::Design& design, const PrinterProfile& printer, int page,
                       double px_per_mm);

/// Writes the calibration PDF (temporary file + rename) and returns its bands.
/// Throws InputError when the design has no lenslet array, IoError when it cannot write.
std::vector<MoireBand> write_moire_pdf(const std::filesystem::path& out, const optics::Design& design,
                                       const PrinterProfile& printer, const MoireOptions& options);

}  // namespace rfd::print
