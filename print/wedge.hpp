#pragma once
// The step wedge: patches of evenly spaced printer codes, from bare film (code 255, no
// ink) to full ink (code 0), to measure a printer's tone curve on its film (docs/formats.md,
// "Printer profiles"): measure each patch's transmittance against bare film, read
// max_density from the full-ink patch and fit gamma to the rest. Each patch is printed as
// an image, as patterns are, so the driver treats it alike; its label gives the code, the
// ink value v = 1 - code/255 and the transmittance the profile predicts for it.
//
// Example: write_wedge_pdf("wedge.pdf", load_printer("inkjet_720"), 21);

#include <filesystem>
#include <vector>


#include "core/image.hpp"
#include "core/options.hpp"
#include "print/marks.hpp"
#include "print/printer.hpp"

namespace rfd::print {

/// Patches of a wedge, the same for printing it and for reading it back.
inline constexpr IntegerOption kWedgeStepsOption{"--steps", "", "", 2, 256, 21,
                                                 "Patches of the step wedge, from code 255 (no ink) to 0 (full ink)"};

struct WedgePatch {
    int code = 255;               ///< what the sheet file holds, 0..255 (255: no ink)
    double ink = 0.0;             ///< the printer value v = 1 - code / 255
    double transmittance = 1.0;   ///< the profile's T(v)
    int page = 0;                 ///< 0-based
    double left = 0.0, top = 0.0; ///< page frame, mm
};

/// The `steps` codes (2..256) from 255 down to 0, rounded to whole codes, with what the
/// profile predicts for each.
std::vector<WedgePatch> wedge_patches(const PrinterProfile& printer, int steps);

/// The wedge laid out on the profile's paper: its patches placed page by page, the
/// registration marks every page carries (print/marks.hpp), the patches' side.
struct WedgeSheet {
    std::vector<WedgePatch> patches;
    SheetMarks marks;
    int pages = 1;
    double patch_size = 16.0;  ///< mm
};

/// wedge_patches placed on the paper. InputError when the paper cannot hold one patch.
WedgeSheet wedge_sheet(const PrinterProfile& printer, int steps);

/// Paints page `page` of the wedge (user units: page-frame mm) over white.
void draw_wedge_page(cairo_t* cr, const WedgeSheet& sheet, const PrinterProfile& printer, int page);

/// Page `page` of the wedge as the printer receives it (print/pdf_file.hpp page_codes), at
/// `px_per_mm`: what a simulated print of the sheet starts from.
Image wedge_page_codes(const WedgeSheet& sheet, const PrinterProfile& printer, int page, double px_per_mm);

/// Writes the wedge as a PDF on the profile's paper (temporary file + rename), and its first
/// page as a PNG at `preview` when given, and returns its patches. InputError when the
/// paper cannot hold one patch; IoError when it cannot write.
std::vector<WedgePatch> write_wedge_pdf(const std::filesystem::path& out, const PrinterProfile& printer, int steps,
                                        const std::filesystem::path& preview = {});

}  // namespace rfd::print
