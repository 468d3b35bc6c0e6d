#include "print/printer.hpp"

#include <algorithm>
#include <cmath>

#include "core/config.hpp"
#include "core/error.hpp"
#include "core/text.hpp"

namespace rfd::print {
namespace {

// The [tone] table of a measured curve: checked to be a curve the tone mapping can invert.
void read_tone_table(ConfigTable& t, PrinterProfile& p) {
    constexpr std::size_t kMaxSteps = 257;  // a wedge has at most 256 codes
    p.tone_ink = t.number_list("ink", 2, kMaxSteps, 0.0, 1.0);
    p.tone_transmittance = t.number_list("transmittance", 2, kMaxSteps, 1e-6, 1.0);
    if (p.tone_transmittance.size() != p.tone_ink.size())
        t.fail("transmittance", "expected one transmittance per ink value (" + std::to_string(p.tone_ink.size()) +
                                    "), got " + std::to_string(p.tone_transmittance.size()));
    if (p.tone_ink.front() != 0.0 || p.tone_ink.back() != 1.0)
        t.fail("ink", "expected ink values from 0 (bare film) to 1 (full ink)");
    for (std::size_t k = 1; k < p.tone_ink.size(); ++k) {
        if (!(p.tone_ink[k] > p.tone_ink[k - 1])) t.fail("ink", "expected increasing ink values");
        if (!(p.tone_transmittance[k] < p.tone_transmittance[k - 1]))
            t.fail("transmittance", "expected transmittances that fall as ink grows");
    }
    if (p.tone_transmittance.front() != 1.0) t.fail("transmittance", "expected 1 (bare film) at ink 0");
    // max_density names full ink's transmittance; the table's last value must agree.
    const double ink = std::pow(10.0, -p.max_density);
    if (std::abs(p.tone_transmittance.back() / ink - 1.0) > 1e-3)
        t.fail("transmittance", "full ink transmits " + format_number(p.tone_transmittance.back()) +
                                    " here, but [printer] max_density " + format_number(p.max_density) +
                                    " says " + format_number(ink));
    t.finish();
}

PrinterProfile read_profile(ConfigTable& root) {
    PrinterProfile p;
    p.file = root.file();
    {
        ConfigTable t = root.table("printer");
        p.name = t.string("name");
        p.dpi_x = Dpi(t.number("dpi_x", 1.0, 100000.0));
        p.dpi_y = Dpi(t.number("dpi_y", 1.0, 100000.0));
        p.gamma = t.number("gamma", 0.1, 10.0);
        p.max_density = t.number("max_density", 0.01, 6.0);
        p.black_level = t.number("black_level", 0.0, 0.99);
        p.sheets = static_cast<int>(t.optional_integer("sheets", 1, 2).value_or(1));
        p.film = t.optional_number("film_mm", 0.01, 2.0).value_or(p.film);
        if (p.black_level < p.ink_transmittance())
            t.fail("black_level", "black level " + std::to_string(p.black_level) +
                                      " is darker than full ink can print (max_density " +
                                      std::to_string(p.max_density) + " gives transmittance " +
                                      std::to_string(p.ink_transmittance()) + ")");
        t.finish();
    }
    if (auto t = root.optional_table("tone")) read_tone_table(*t, p);
    if (auto t = root.optional_table("paper")) {
        p.paper.name = t->string("name");
        p.paper.width = t->number("width_mm", 10.0, 5000.0);
        p.paper.height = t->number("height_mm", 10.0, 50000.0);
        p.paper.margin = t->number("margin_mm", 0.0, 100.0);
        if (2 * p.paper.margin >= std::min(p.paper.width, p.paper.height))
            t->fail("margin_mm", "margins leave no printable area on " + p.paper.name);
        t->finish();
    }
    root.finish();
    return p;
}

}  // namespace

double PrinterProfile::ink_transmittance() const { return std::pow(10.0, -max_density); }

double PrinterProfile::transmittance(double v) const {
    v = std::clamp(v, 0.0, 1.0);
    if (!tone_ink.empty()) {
        const auto above = std::upper_bound(tone_ink.begin() + 1, tone_ink.end() - 1, v);
        const std::size_t k = static_cast<std::size_t>(above - tone_ink.begin());
        const double f = (v - tone_ink[k - 1]) / (tone_ink[k] - tone_ink[k - 1]);
        return std::exp((1.0 - f) * std::log(tone_transmittance[k - 1]) + f * std::log(tone_transmittance[k]));
    }
    const double ink = ink_transmittance();
    return ink + (1.0 - ink) * std::pow(1.0 - v, gamma);
}

double PrinterProfile::printer_value(double t) const {
    if (!tone_ink.empty()) {
        t = std::clamp(t, tone_transmittance.back(), 1.0);
        // Transmittances fall along the table: the first at or below t closes t's interval.
        const auto below = std::lower_bound(tone_transmittance.begin() + 1, tone_transmittance.end() - 1, t,
                                            [](double entry, double value) { return entry > value; });
        const std::size_t k = static_cast<std::size_t>(below - tone_transmittance.begin());
        const double f = std::log(t / tone_transmittance[k - 1]) /
                         std::log(tone_transmittance[k] / tone_transmittance[k - 1]);
        return std::clamp(tone_ink[k - 1] + f * (tone_ink[k] - tone_ink[k - 1]), 0.0, 1.0);
    }
    const double ink = ink_transmittance();
    t = std::clamp(t, ink, 1.0);
    return std::clamp(1.0 - std::pow((t - ink) / (1.0 - ink), 1.0 / gamma), 0.0, 1.0);
}

std::filesystem::path bundled_printer_folder() { return RFD_PRINTERS_DIR; }

namespace {

std::string tone_toml(const PrinterProfile& p) {
    if (p.tone_ink.empty()) return "";
    const auto list = [](const std::vector<double>& values) {
        std::string out = "[";
        for (std::size_t k = 0; k < values.size(); ++k) out += (k ? ", " : "") + format_number(values[k], 17);
        return out + "]";
    };
    return "\n[tone]\nink = " + list(p.tone_ink) + "\ntransmittance = " + list(p.tone_transmittance) + "\n";
}

}  // namespace

std::string printer_toml(const PrinterProfile& p) {
    // 17 significant digits: every double reads back to itself.
    const auto number = [](double value) { return format_number(value, 17); };
    const auto text = [](const std::string& value) { return toml_string(value); };
    return "[printer]\nname = " + text(p.name) + "\ndpi_x = " + number(p.dpi_x.value) + "\ndpi_y = " +
           number(p.dpi_y.value) + "\ngamma = " + number(p.gamma) + "\nmax_density = " + number(p.max_density) +
           "\nblack_level = " + number(p.black_level) + "\nsheets = " + std::to_string(p.sheets) +
           "\nfilm_mm = " + number(p.film) + "\n\n[paper]\nname = " + text(p.paper.name) +
           "\nwidth_mm = " + number(p.paper.width) + "\nheight_mm = " + number(p.paper.height) +
           "\nmargin_mm = " + number(p.paper.margin) + "\n" + tone_toml(p);
}

PrinterProfile default_printer(Dpi dpi_x, Dpi dpi_y) {
    PrinterProfile printer = load_printer("epson_stylus_pro_4800");
    printer.dpi_x = dpi_x;
    printer.dpi_y = dpi_y;
    if (dpi_x.value != 2880.0 || dpi_y.value != 1440.0)
        printer.name += " (default profile at " + format_number(dpi_x.value) + " x " + format_number(dpi_y.value) + " dpi)";
    return printer;
}

std::filesystem::path printer_file(const std::string& name_or_path) {
    std::filesystem::path path(name_or_path);
    std::error_code ec;
    // A bare name without a folder or extension is a bundled profile.
    if (!std::filesystem::exists(path, ec) && !path.has_parent_path() && !path.has_extension())
        path = bundled_printer_folder() / (name_or_path + ".toml");
    if (!std::filesystem::is_regular_file(path, ec)) {
        std::string known;
        for (const auto& entry : std::filesystem::directory_iterator(bundled_printer_folder(), ec))
            if (entry.path().extension() == ".toml")
                known += (known.empty() ? "" : ", ") + entry.path().stem().string();
        throw IoError(SourceLocation{name_or_path},
                      "cannot open printer profile: no such file or bundled profile (bundled: " +
                          known + ")");
    }
    return path;
}

PrinterProfile load_printer(const std::string& name_or_path) {
    const std::filesystem::path path = printer_file(name_or_path);
    ConfigTable root = ConfigTable::parse_file(path);
    return read_profile(root);
}

PrinterProfile parse_printer(const std::string& toml_text, const std::string& name) {
    ConfigTable root = ConfigTable::parse_string(toml_text, name);
    return read_profile(root);
}

double ToneMap::stack_transmittance(double pattern_value) const {
    RFD_CHECK(sheets == 1 || sheets == 2);
    RFD_CHECK(brightness > 0.0 && white > 0.0);
    const double t = std::clamp(brightness * pattern_value / white, 0.0, 1.0);
    const double black = std::pow(printer.black_level, sheets);
    return black + (1.0 - black) * t;
}

double ToneMap::sheet_transmittance(double pattern_value) const {
    const double stack = stack_transmittance(pattern_value);
    return sheets == 1 ? stack : std::sqrt(stack);
}

double ToneMap::printer_value(double pattern_value) const {
    return printer.printer_value(sheet_transmittance(pattern_value));
}

}  // namespace rfd::print
