#include "project/index.hpp"

#include <algorithm>
#include <fstream>
#include <optional>
#include <string>
#include <system_error>


#include <nlohmann/json.hpp>

#include "core/error.hpp"
#include "core/files.hpp"
#include "core/text.hpp"
#include "optics/design.hpp"
#include "predict/summaries.hpp"
#include "predict/verdict.hpp"
#include "print/moire.hpp"
#include "print/printer.hpp"
#include "holders/profile.hpp"
#include "project/preview.hpp"

namespace rfd::project {
namespace {

namespace fs = std::filesystem;

// One instruction: what to do, and the files it is about (relative to the output folder).
struct Item {
    std::string text;
    std::vector<std::string> files;
};
struct Section {
    std::string title;
    std::vector<Item> items;
};

bool made(const fs::path& out, const std::string& file) {
    std::error_code ec;
    return fs::exists(out / file, ec);
}

std::vector<std::string> files_with_extension(const fs::path& folder, const fs::path& out, const std::string& ext) {
    std::vector<std::string> files;
    std::error_code ec;
    for (const auto& entry : fs::directory_iterator(folder, ec))
        if (entry.path().extension() == ext) files.push_back(fs::relative(entry.path(), out).generic_string());
    std::sort(files.begin(), files.end());
    return files;
}

// The registration step's result as one instruction; nullopt when it was not made (or its
// file is not what it wrote: the step re-makes it next time).
std::optional<std::string> registration_text(const fs::path& out) {
    std::error_code ec;
    if (!fs::exists(out / "calibration/registration.json", ec)) return std::nullopt;
    predict::RegistrationSummary r;
    try {
        r = predict::read_summary<predict::RegistrationSummary>(out / "calibration/registration.json");
    } catch (const Error&) {
        return std::nullopt;
    }
    std::string text = "Measured from " + std::to_string(r.photographs) + " photograph(s) of the display (light " +
                       r.light + "): the pattern lies " + format_fixed(r.shift_mm[0], 3) + ", " +
                       format_fixed(r.shift_mm[1], 3) + " mm right and up of where it belongs (+-" +
                       format_fixed(std::max(r.sigma_shift_mm[0], r.sigma_shift_mm[1]), 3) + "), turned " +
                       format_fixed(r.rotation_deg, 3) + " deg counter-clockwise, seen from the front. ";
    if (r.inside && *r.inside)
        text += "That is inside the assembly tolerances: fix the pattern where it is.";
    else
        text += std::string(r.inside ? "That is OUTSIDE the assembly tolerances: " : "") + "move the pattern by " +
                format_fixed(-r.shift_mm[0], 3) + ", " + format_fixed(-r.shift_mm[1], 3) + " mm and turn it by " +
                format_fixed(-r.rotation_deg, 3) + " deg" +
                (r.inside ? "." : " (no tolerances were predicted to judge against).");
    return text + " The whole report: logs/calibrate_registration.txt.";
}

std::vector<Section> instructions(const Project& project, const fs::path& out) {
    const optics::Design design = optics::load_design(project.design);
    const print::PrinterProfile printer = print::load_printer(project.printer);
    const std::string film_printer = printer.name + " (" + format_number(printer.dpi_x.value) + " x " +
                                     format_number(printer.dpi_y.value) + " dpi)";
    std::vector<Section> sections;

    Section holder{"1. Print the holder", {}};
    if (made(out, "holder")) {
        const holders::HolderProfile profile = holders::load_profile(project.printer_3d);
        holder.items.push_back({"3D-print these parts with " + profile.name +
                                    ". holder.txt in logs/ lists the seats and the checks they passed; holder.scad "
                                    "is the OpenSCAD source.",
                                files_with_extension(out / "holder", out, ".stl")});
    }
    holder.items.push_back(
        {"If you do not know your 3D printer's clearance, print the fit-test coupon first: "
         "rfd holder coupon --out coupon.scad --stl coupon.stl",
         {}});
    sections.push_back(holder);

    // The order that makes the rest right: the test sheets are printed and photographed
    // before the pattern, which is then encoded for the measured pitch and tone.
    Section print_first{"2. Calibrate (before printing the pattern)", {}};
    if (made(out, "calibration/design.toml"))
        print_first.items.push_back(
            {"The lens array's pitch, measured from " + std::to_string(project.calibration.moire_photos.size()) +
                 " photograph(s) of the moire sheet: the pattern, the sheets, the holder and the predictions here "
                 "are for it (calibration/design.toml, its pitch line says how far it is from the design's; every "
                 "lenslet's reading in calibration/pitch).",
             {"calibration/pitch/profile_x.png", "calibration/design.toml"}});
    else if (made(out, "print/moire.pdf") && !project.pitch_refusal.empty())
        print_first.items.push_back(
            {"Print moire.pdf on transparency film with " + film_printer +
                 ", at 100 % (no scaling, no colour adjustment). Lay the lens array on it: the band whose fringes "
                 "vanish or are widest has the array's true pitch (this array is too small for rfd calibrate pitch). "
                 "If it is not the design's, put it into the design's lattice and run rfd make again.",
             {"print/moire.pdf", "print/moire.png"}});
    else if (made(out, "print/moire.pdf") && print::lays_array_whole(design, printer.paper))
        print_first.items.push_back(
            {"Print moire.pdf on transparency film with " + film_printer +
                 ", at 100 % (no scaling, no colour adjustment). Lay it in the holder's pattern pocket with the whole "
                 "lens array on its \"measure x\" band, light it from behind and photograph it from 20 to 40 degrees "
                 "off the vertical with its four corner discs in view; then the same with the array on the "
                 "\"measure rows\" band. Two or three such pairs, the array laid down again each time, read finer "
                 "than one (docs/usage.md, \"Calibrating from photographs\"). Name the photographs in the project's "
                 "[calibration] moire_photos: rfd make then measures the array's true pitch and builds everything "
                 "for it.",
             {"print/moire.pdf", "print/moire.png"}});
    else if (made(out, "print/moire.pdf"))
        print_first.items.push_back(
            {"Print moire.pdf on transparency film with " + film_printer +
                 ", at 100 % (no scaling, no colour adjustment). Lay it in the holder's pattern pocket under the lens "
                 "array, light it from behind and photograph it from the front with its four corner discs in view "
                 "(docs/usage.md, \"Calibrating from photographs\"); name the photographs in the project's "
                 "[calibration] moire_photos: rfd make then measures the array's true pitch and builds everything "
                 "for it.",
             {"print/moire.pdf", "print/moire.png"}});
    if (made(out, "calibration/printer.toml"))
        print_first.items.push_back(
            {"The printer's tone curve, measured from " + std::to_string(project.calibration.wedge_photos.size()) +
                 " photograph(s) of the printed wedge: the pattern, the sheets and the predictions here use it "
                 "(calibration/printer.toml; the patches and curves in calibration/tone).",
             {"calibration/tone/tone_chart.png", "calibration/printer.toml"}});
    else if (made(out, "print/wedge.pdf"))
        print_first.items.push_back(
            {"Print wedge.pdf the same way, photograph or scan it lit from behind with its four corner discs in view "
             "(docs/usage.md, \"Calibrating from photographs\"), and name the photographs in the project's "
             "[calibration] wedge_photos: rfd make then measures the printer's tone curve and prints and predicts "
             "everything with it.",
             {"print/wedge.pdf", "print/wedge.png"}});
    sections.push_back(print_first);


    Section film{"3. Print the pattern", {}};
    std::vector<std::string> fronts, backs;
    for (const char* format : {"png", "pdf", "tif"}) {
        if (made(out, std::string("print/front.") + format)) fronts.push_back(std::string("print/front.") + format);
        if (made(out, std::string("print/back.") + format)) backs.push_back(std::string("print/back.") + format);
    }
    film.items.push_back({"Print the front sheet on transparency film with " + film_printer +
                              ", at 100 %, no colour adjustment (the PDF and the TIFF are the same page; use "
                              "the one your printer driver takes at its true resolution; the PNG is a picture of "
                              "the page to check it). A small pattern is printed as many times as the page holds: "
                              "spares, cut along the crop marks.",
                          fronts});
    if (!backs.empty())
        film.items.push_back({"Print the mirrored back sheet the same way. Lay it behind the front sheet, ink "
                              "to ink, registration markers on markers: two sheets double the density.",
                              backs});
    sections.push_back(film);

    Section assemble{"4. Assemble", {}};
    assemble.items.push_back(
        {"Lay the pattern (" + std::to_string(printer.sheets) + " sheet(s)) into the holder's pattern pocket and "
         "each lens part into the base, pressed against its seat (the seats are listed in logs/holder.txt), then "
         "close the lid. " +
             std::string(design.kind == optics::DesignKind::I
                             ? "Look through the corner sight windows: the registration markers must sit "
                               "centred under their lenslets."
                             : "The registration markers lie under the corner lenslets: centre them."),
         {}});
    assemble.items.push_back(
        {"Light it from behind with a small lamp; the picture changes as the lamp moves.", {}});
    sections.push_back(assemble);

    Section check{"5. Check where the pattern sits", {}};
    if (const std::optional<std::string> measured = registration_text(out))
        check.items.push_back({*measured, {"calibration/registration.json"}});
    else if (!project.registration_refusal.empty())
        check.items.push_back({"This array is too small for rfd calibrate registration: look at the display lit "
                               "from behind and move the pattern until the picture is sharp and the markers sit "
                               "centred under the corner lenslets.",
                               {}});
    else
        check.items.push_back(
            {std::string("Light the display from behind with one small lamp far away (or the sun)") +
                 (design.kind == optics::DesignKind::II
                      ? " on its axis, within a third of a degree: each corner macro-pixel then shows the dark "
                        "cross of its marker magnified (tilt the display until all four do), which reads whatever "
                        "the picture (a picture with detail inside its macro-pixels also reads with the lamp 2 to 9 "
                        "degrees off the axis, not along the rows or columns)"
                      : "") +
                 ", photograph it from the "
             "front with the whole display in the frame, then turn the display by half a turn in its plane, the "
             "lamp and camera where they were, and photograph it again; name them in the project's [calibration] "
             "display_photos and turned_photos: rfd make then says how far the pattern is from where it belongs "
             "and whether that is inside the tolerances (docs/usage.md, \"Calibrating from photographs\").",
             {}});
    sections.push_back(check);

    Section predicted{"What it will show", {}};
    if (made(out, "predict/compare/psnr.png"))
        predicted.items.push_back({"The predicted display against the field relit in software, PSNR against the "
                                   "light's angle (pictures per light in the folder; summary in logs/compare.txt).",
                                   {"predict/compare/psnr.png"}});
    if (made(out, "predict/compare/contact_sheet.png"))
        predicted.items.push_back({"Each compared light: predicted | relit | difference x 4 (in the order of "
                                   "predict/compare/directions.csv).",
                                   {"predict/compare/contact_sheet.png"}});
    if (made(out, "predict/optimize/compare.png"))
        predicted.items.push_back({"The optimised pattern against the direct encoding it started from, as the "
                                   "simulator judges them per light (directions.csv), and the optimiser's progress "
                                   "(iterations.csv).",
                                   {"predict/optimize/compare.png", "predict/optimize/convergence.png"}});
    if (made(out, "predict/tolerance"))
        predicted.items.push_back({"How precisely to assemble it (summary.txt and a chart per error).",
                                   {"predict/tolerance/summary.txt"}});
    predicted.items.push_back({made(out, "pattern_optimized.exr")
                                   ? "The direct encoding the optimised pattern started from, scaled down for the screen."
                                   : "The pattern, scaled down for the screen.",
                               {"pattern.png"}});
    sections.push_back(predicted);
    return sections;
}

std::string html_escaped(const std::string& text) {
    std::string out;
    for (char c : text) {
        switch (c) {
        case '&': out += "&amp;"; break;
        case '<': out += "&lt;"; break;
        case '>': out += "&gt;"; break;
        case '"': out += "&quot;"; break;
        default: out += c;
        }
    }
    return out;
}

bool is_picture(const std::string& file) { return file.ends_with(".png"); }

// The verdict step's result: its one line and the figures under it, empty when the step
// was not made (or its file is not what it wrote).
struct VerdictText {
    std::string call, line;
    std::vector<std::string> figures;
};
VerdictText read_verdict(const fs::path& out, const Eigen::Vector2d& extent_mm) {
    std::error_code ec;
    if (!fs::exists(out / "verdict.json", ec)) return {};
    predict::VerdictReport v;
    try {
        v = predict::read_summary<predict::VerdictReport>(out / "verdict.json");
    } catch (const Error&) {
        return {};  // not what the verdict step wrote: the step re-makes it next time
    }
    VerdictText text{v.call, v.line, {}};
    text.figures.push_back("on this field: " + v.field_line);
    text.figures.push_back("on the design: " + v.design_line);
    const auto number = [](const std::optional<double>& value, const std::string& unit) {
        return value ? format_fixed(*value, 2) + unit : std::string("-");
    };
    text.figures.push_back("predicted PSNR over the field of view: mean " + number(v.psnr_mean_in_fov_db, " dB") +
                           ", min " + number(v.psnr_min_in_fov_db, " dB") + " (against the field's brightest)");
    text.figures.push_back("crosstalk-free cone " + number(v.crosstalk_free_cone_deg, " deg") + " (PSNR " +
                           number(v.psnr_mean_crosstalk_free_db, " dB") + "), field of view " +
                           number(v.field_of_view_deg, " deg"));
    if (const auto& t = v.tolerances)
        text.figures.push_back(
            "assemble within: " +
            predict::maker_tolerance_text({t->shift_mm, t->rotation_deg, t->pitch_error_ppm, t->spacer_mm}, t->at_least,
                                          extent_mm));
    for (const std::string& warning : v.warnings) text.figures.push_back("design warning: " + warning);
    return text;
}

}  // namespace

std::vector<std::string> advice_lines(const fs::path& out) {
    std::error_code ec;
    if (!fs::exists(out / "advice.json", ec)) return {};
    try {
        const nlohmann::json advice = nlohmann::json::parse(read_text_file(out / "advice.json"));
        return advice.at("lines").get<std::vector<std::string>>();
    } catch (const std::exception&) {
        return {};  // not what the advice step wrote: the step re-makes it next time
    }
}

void write_index(const Project& project, const fs::path& out, const std::vector<Step>& steps) {
    const std::vector<Section> sections = instructions(project, out);
    const std::string title = project.name + ": a passive reflectance-field display";

    const VerdictText verdict = read_verdict(out, predict::printed_extent_mm(optics::load_design(project.design)));
    const std::vector<std::string> advice = advice_lines(out);
    std::string text = title + "\nMade by rfd make from " + fs::absolute(project.file).lexically_normal().string() +
                       ". Paths are relative to this folder; run the commands below from it.\n";
    if (!advice.empty()) {
        text += "\nAdvice on this field (advice.json)\n";
        for (const std::string& line : advice) text += "  " + line + "\n";
    }
    if (!verdict.line.empty()) {
        text += "\nVerdict: " + verdict.line + "\n";
        for (const std::string& figure : verdict.figures) text += "  " + figure + "\n";
    }
    for (const Section& section : sections) {
        if (section.items.empty()) continue;
        text += "\n" + section.title + "\n";
        for (const Item& item : section.items) {
            text += "- " + item.text + "\n";
            for (const std::string& file : item.files) text += "    " + file + "\n";
        }
    }
    text += "\nHow each file was made, each command run from this folder (run `rfd make` again to re-make only what "
            "changed; any line alone to vary it)\n";
    for (const Step& step : steps) text += "- " + step.title + "\n    " + command_line(step) + "\n";
    write_text_file(out / "README.txt", text);

    std::string html = "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n<title>" +
                       html_escaped(title) +
                       "</title>\n<style>\nbody{font-family:sans-serif;max-width:60em;margin:2em auto;padding:0 1em;"
                       "line-height:1.4}\nimg{max-width:100%;border:1px solid #ccc}\ncode{font-size:90%}\n.verdict{padding:0.5em 1em;border-left:6px solid #c90}\n.verdict.go{border-color:#393}\n.verdict.no-go{border-color:#c33}\n.advice{padding:0.5em 1em;border-left:6px solid #36c;margin-bottom:1em}\n.viewer{display:flex;flex-wrap:wrap;gap:1em;align-items:flex-start}\n"
                       "figure{margin:0}\ncanvas.picture{width:220px;image-rendering:pixelated;background:#000}\n"
                       "#light-disc{cursor:crosshair;touch-action:none}\n#light-readout{width:220px;font-size:90%}\n#holder-view{min-height:2em}\n</style>\n"
                       "</head>\n<body>\n<h1>" +
                       html_escaped(title) + "</h1>\n<p>Made by <code>rfd make</code> from <code>" +
                       html_escaped(fs::absolute(project.file).lexically_normal().string()) + "</code>.</p>\n";
    if (!advice.empty()) {
        html += "<div class=\"advice\"><strong>Advice on this field</strong><ul>\n";
        for (const std::string& line : advice) html += "<li>" + html_escaped(line) + "</li>\n";
        html += "</ul></div>\n";
    }
    if (!verdict.line.empty()) {
        html += "<div class=\"verdict " + html_escaped(verdict.call) + "\"><strong>" + html_escaped(verdict.line) +
                "</strong><ul>\n";
        for (const std::string& figure : verdict.figures) html += "<li>" + html_escaped(figure) + "</li>\n";
        html += "</ul></div>\n";
    }
    if (made(out, "preview/data.js")) {
        const std::vector<fs::path> stls = [&] {
            std::vector<fs::path> files;
            for (const std::string& file : files_with_extension(out / "holder", out, ".stl")) files.push_back(out / file);
            return files;
        }();
        const bool three = write_preview_assets(out / "preview", stls);
        html += R"(<h2>Move the light</h2>
<p>Drag the point on the disc (or focus it and use the arrow keys): the centre is a lamp straight behind the
display, the rim the edge of the range. Inside the yellow line no light crosses into a neighbouring lenslet;
the red dashed line is the edge of the field of view.</p>
<div class="viewer">
<div><canvas id="light-disc" width="220" height="220" tabindex="0" aria-label="light direction"></canvas>
<div id="light-readout"></div></div>
<figure><canvas id="relit" class="picture"></canvas><figcaption>the field relit in software</figcaption></figure>
<figure><canvas id="predicted" class="picture"></canvas><figcaption>the predicted display</figcaption></figure>
<figure><canvas id="difference" class="picture"></canvas><figcaption>|difference| &times; 4</figcaption></figure>
</div>
<h2>The holder</h2>
<div id="holder-view"></div>
)";
        if (three)
            html += "<script src=\"preview/vendor/three.min.js\"></script>\n<script src=\"preview/vendor/STLLoader.js\">"
                    "</script>\n<script src=\"preview/vendor/OrbitControls.js\"></script>\n";
        if (!stls.empty()) html += "<script src=\"preview/holder.js\"></script>\n";
        html += "<script src=\"preview/data.js\"></script>\n<script src=\"preview/preview.js\"></script>\n";
    }
    for (const Section& section : sections) {
        if (section.items.empty()) continue;
        html += "<h2>" + html_escaped(section.title) + "</h2>\n<ul>\n";
        for (const Item& item : section.items) {
            html += "<li>" + html_escaped(item.text);
            for (const std::string& file : item.files)
                html += is_picture(file) ? "<br><img src=\"" + html_escaped(file) + "\" alt=\"" + html_escaped(file) + "\">"
                                         : " <a href=\"" + html_escaped(file) + "\">" + html_escaped(file) + "</a>";
            html += "</li>\n";
        }
        html += "</ul>\n";
    }
    html += "<h2>How each file was made</h2>\n<ul>\n";
    for (const Step& step : steps)
        html += "<li>" + html_escaped(step.title) + " (<a href=\"logs/" + html_escaped(step.name) +
                ".txt\">report</a>)<br><code>" + html_escaped(command_line(step)) + "</code></li>\n";
    html += "</ul>\n</body>\n</html>\n";
    write_text_file(out / "index.html", html);
}

}  // namespace rfd::project
