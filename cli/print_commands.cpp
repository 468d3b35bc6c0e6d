// rfd print sheet and rfd print moire: printable sheets of a pattern (tone-mapped, with
// registration markers, crop marks, ruler and label) and pitch-calibration sheets.

#include <cstdio>
#include <memory>
#include <string>

#include <nlohmann/json.hpp>

#include "cli/arguments.hpp"
#include "cli/commands.hpp"
#include "optics/design.hpp"
#include "patterns/raster.hpp"
#include "print/moire.hpp"
#include "print/printed.hpp"
#include "print/printer.hpp"
#include "print/sheet.hpp"
#include "print/wedge.hpp"

namespace rfd::cli {
namespace {

void add_sheet_command(CLI::App& print_cmd) {
    auto* cmd = print_cmd.add_subcommand(
        "sheet", "A printable sheet of a pattern: tone-mapped for the printer, with registration markers under the "
                 "corner lenslets, crop marks, ruler and label (TIFF or PDF)");
    struct Options {
        std::string design, pattern, printer, out;
        print::SheetOptions sheet;
        bool json = false;
    };
    auto opt = std::make_shared<Options>();
    cmd->add_option("DESIGN", opt->design, "Design TOML file")->required();
    cmd->add_option("PATTERN", opt->pattern, "Pattern file (EXR/TIFF/PNG) at the printer's resolution")->required();
    cmd->add_option("--printer", opt->printer,
                    "Printer profile: a TOML file or a bundled name (epson_stylus_pro_4800, laser_1200, "
                    "inkjet_720). Default: the one the pattern was encoded for, else the Epson's tone values at "
                    "the pattern's dpi");
    cmd->add_option("--out", opt->out, "Output sheet, .tif/.tiff or .pdf")->required();
    cmd->add_flag("--mirror", opt->sheet.mirror, "The back sheet: the whole page mirrored left-right");
    add_option(*cmd, print::kBrightnessOption, opt->sheet.brightness);
    add_option(*cmd, print::kSheetsOption, opt->sheet.sheets);
    cmd->add_option("--bits", opt->sheet.bits, "TIFF bits per channel, 8 or 16");
    cmd->add_option("--copies", opt->sheet.copies,
                    "Copies of the pattern on the page, each with its marks (0: as many as fit)")
        ->check(CLI::Range(0, 10000));
    cmd->add_option("--preview", opt->sheet.preview, "Also a small PNG of the page (800 pixels along its longer side)");
    cmd->add_flag("--json", opt->json, "Machine-readable summary");
    cmd->callback([opt] {
        const optics::Design design = optics::load_design(opt->design);
        const print::PrinterProfile printer = print::printer_for_pattern(design, opt->pattern, opt->printer);
        const print::SheetReport r = print::write_sheet(opt->out, design, printer, opt->pattern, opt->sheet);
        const print::SheetLayout& l = r.layout;
        nlohmann::json markers = nlohmann::json::array();
        for (const auto& m : l.markers)
            markers.push_back({{"lenslet", {m.lenslet.i, m.lenslet.j}},
                               {"page_mm", {m.centre.x(), m.centre.y()}},
                               {"page_dots", {m.centre.x() / l.dot_x - 0.5, m.centre.y() / l.dot_y - 0.5}}});
        const nlohmann::json summary = {
            {"out", opt->out},
            {"printer", printer.name},
            {"dpi", {l.dpi_x, l.dpi_y}},
            {"paper", {{"name", l.paper.name}, {"mm", {l.paper.width, l.paper.height}}}},
            {"page_dots", {l.page_width, l.page_height}},
            {"pattern_dots", {l.pattern.width, l.pattern.height}},
            {"pattern_offset_dots", {l.offset_x, l.offset_y}},
            {"pattern_mm", {l.pattern.size_mm().x(), l.pattern.size_mm().y()}},
            {"brightness", r.tone.brightness},
            {"white", r.tone.white},
            {"sheets", r.tone.sheets},
            {"mirror", l.mirror},
            {"copies", l.copies.size()},
            {"markers", markers}};
        if (opt->json) {
            std::printf("%s\n", summary.dump(2).c_str());
            return;
        }
        std::printf("%s: %s sheet, %d x %d dots at %g x %g dpi (%s, %.0f x %.0f mm)\n", opt->out.c_str(),
                    l.mirror ? "back (mirrored)" : "front", l.page_width, l.page_height, l.dpi_x, l.dpi_y,
                    l.paper.name.c_str(), l.paper.width, l.paper.height);
        std::printf("  pattern   %d x %d dots (%.2f x %.2f mm) at dot (%d, %d)", l.pattern.width, l.pattern.height,
                    l.pattern.size_mm().x(), l.pattern.size_mm().y(), l.offset_x, l.offset_y);
        if (l.copies.size() > 1) std::printf(", %zu copies", l.copies.size());
        std::printf("\n");
        std::printf("  tone      brightness %g, white %g, %d sheet(s), black %.4f of the stack\n", r.tone.brightness,
                    r.tone.white, r.tone.sheets, r.tone.stack_transmittance(0.0));
        for (const auto& m : l.markers)
            std::printf("  marker    lenslet (%d, %d) at %.3f, %.3f mm on the front page\n", m.lenslet.i, m.lenslet.j,
                        m.centre.x(), m.centre.y());
        if (l.markers.empty()) std::printf("  markers   none (Design IV arrays are aligned by hand)\n");
    });
}

void add_moire_command(CLI::App& print_cmd) {
    auto* cmd = print_cmd.add_subcommand(
        "moire", "Pitch-calibration sheet (thesis 8.4.1): line bands for a range of pitch hypotheses (PDF)");
    struct Options {
        std::string design, printer, out, pitch, pitch_y, preview;
        bool json = false;
    };
    auto opt = std::make_shared<Options>();
    cmd->add_option("DESIGN", opt->design, "Design TOML file")->required();
    cmd->add_option("--pitch", opt->pitch,
                    "Pitch hypotheses along a row, FROM:TO:STEPS in mm (default: the design's pitch +-0.4 %, 9 steps)");
    cmd->add_option("--pitch-y", opt->pitch_y,
                    "Rectangular arrays: row-spacing hypotheses FROM:TO:STEPS (default: --pitch scaled by the "
                    "design's pitch_y / pitch_x)");
    cmd->add_option("--printer", opt->printer,
                    "Printer profile (paper size) (default: the thesis's Epson at the design's [printer] resolution)");
    cmd->add_option("--out", opt->out, "Output PDF")->required();
    cmd->add_option("--preview", opt->preview, "Also a PNG of the first page (800 pixels along its longer side)");
    cmd->add_flag("--json", opt->json, "Machine-readable list of bands");
    cmd->callback([opt] {
        const std::filesystem::path out(opt->out);
        if (out.extension() != ".pdf")
            throw InputError(SourceLocation{opt->out, 0, 0, "--out"}, "expected a .pdf file");
        if (!opt->preview.empty() && std::filesystem::path(opt->preview).extension() != ".png")
            throw InputError(SourceLocation{opt->preview, 0, 0, "--preview"}, "expected a .png file");
        const optics::Design design = optics::load_design(opt->design);
        print::MoireOptions options = moire_options(design, opt->pitch, opt->pitch_y);
        options.preview = opt->preview;
        const print::PrinterProfile printer = printer_for(design, opt->printer);
        const auto bands = print::write_moire_pdf(out, design, printer, options);
        if (opt->json) {
            nlohmann::json list = nlohmann::json::array();
            for (const auto& b : bands)
                list.push_back({{"direction", b.along_x ? "x" : "rows"},
                                {"pitch_mm", b.pitch},
                                {"period_mm", b.period},
                                {"page", b.page + 1}});
            std::printf("%s\n", nlohmann::json{{"out", opt->out}, {"bands", list}}.dump(2).c_str());
            return;
        }
        std::printf("%s: %zu bands on %d page(s)\n", opt->out.c_str(), bands.size(), bands.back().page + 1);
        for (const auto& b : bands)
            std::printf("  %-4s pitch %.4f mm, line period %.4f mm (page %d)\n", b.along_x ? "x" : "rows", b.pitch,
                        b.period, b.page + 1);
    });
}

void add_wedge_command(CLI::App& print_cmd) {
    auto* cmd = print_cmd.add_subcommand(
        "wedge", "Step-wedge sheet (PDF): patches from bare film to full ink, to measure the printer's tone curve "
                 "for its profile");
    struct Options {
        std::string printer = "epson_stylus_pro_4800", out, preview;
        int steps = static_cast<int>(print::kWedgeStepsOption.fallback);
        bool json = false;
    };
    auto opt = std::make_shared<Options>();
    cmd->add_option("--printer", opt->printer, "Printer profile: a TOML file or a bundled name");
    add_option(*cmd, print::kWedgeStepsOption, opt->steps);
    cmd->add_option("--out", opt->out, "Output PDF")->required();
    cmd->add_option("--preview", opt->preview, "Also a PNG of the first page (800 pixels along its longer side)");
    cmd->add_flag("--json", opt->json, "Machine-readable list of patches");
    cmd->callback([opt] {
        if (std::filesystem::path(opt->out).extension() != ".pdf")
            throw InputError(SourceLocation{opt->out, 0, 0, "--out"}, "expected a .pdf file");
        const print::PrinterProfile printer = print::load_printer(opt->printer);
        if (!opt->preview.empty() && std::filesystem::path(opt->preview).extension() != ".png")
            throw InputError(SourceLocation{opt->preview, 0, 0, "--preview"}, "expected a .png file");
        const auto patches = print::write_wedge_pdf(opt->out, printer, opt->steps, opt->preview);
        if (opt->json) {
            nlohmann::json list = nlohmann::json::array();
            for (const auto& p : patches)
                list.push_back({{"code", p.code}, {"ink", p.ink}, {"transmittance", p.transmittance}, {"page", p.page + 1}});
            std::printf("%s\n", nlohmann::json{{"out", opt->out}, {"printer", printer.name}, {"patches", list}}.dump(2).c_str());
            return;
        }
        std::printf("%s: %zu patches for %s on %d page(s)\n", opt->out.c_str(), patches.size(), printer.name.c_str(),
                    patches.back().page + 1);
        for (const auto& p : patches)
            std::printf("  code %3d  ink %.3f  predicted transmittance %.4f\n", p.code, p.ink, p.transmittance);
    });
}

}  // namespace

void add_print_commands(CLI::App& app) {
    auto* print_cmd = app.add_subcommand("print", "Printable sheets: patterns for a printer, pitch calibration, the step wedge");
    print_cmd->require_subcommand(1);
    add_sheet_command(*print_cmd);
    add_moire_command(*print_cmd);
    add_wedge_command(*print_cmd);
}

}  // namespace rfd::cli
