#include "print/printed.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "core/parallel.hpp"
#include "core/text.hpp"

namespace rfd::print {

patterns::PatternGeometry check_pattern(const optics::Design& design, const PrinterProfile& printer,
                                        const std::filesystem::path& pattern_file,
                                        const patterns::PatternFileInfo& info) {
    const double margin = patterns::number_attribute(info, "margin_mm", pattern_file, 0.0, patterns::NumberRange::NonNegative);
    const patterns::PatternGeometry expected =
        patterns::pattern_geometry(design, printer.dpi_x, printer.dpi_y, margin);
    const auto dpi_differs = [](double file_dpi, Dpi dpi) {
        return file_dpi > 0.0 && std::abs(file_dpi - dpi.value) > 1e-3 * dpi.value;
    };
    if (info.width != expected.width || info.height != expected.height ||
        dpi_differs(info.dpi_x, printer.dpi_x) || dpi_differs(info.dpi_y, printer.dpi_y)) {
        std::string file_size = std::to_string(info.width) + " x " + std::to_string(info.height) + " dots";
        if (info.dpi_x > 0.0)
            file_size += " at " + format_number(info.dpi_x) + " x " + format_number(info.dpi_y) + " dpi";
        throw InputError(SourceLocation{pattern_file.string()},
                         "the pattern is " + file_size + ", but '" + design.name + "' at " +
                             format_number(printer.dpi_x.value) + " x " + format_number(printer.dpi_y.value) +
                             " dpi (printer '" + printer.name + "') needs " + std::to_string(expected.width) +
                             " x " + std::to_string(expected.height) +
                             " dots: encode the pattern at the printer's resolution");
    }
    return expected;
}

patterns::PatternAttributes printer_attributes(const PrinterProfile& printer) {
    return {{"printer", printer.name}, {"printer_profile", printer_toml(printer)}};
}

std::optional<PrinterProfile> recorded_printer(const patterns::PatternFileInfo& info,
                                               const std::filesystem::path& pattern_file) {
    const auto record = info.attributes.find("printer_profile");
    if (record == info.attributes.end()) return std::nullopt;
    return parse_printer(record->second, pattern_file.string() + " (rfd:printer_profile)");
}

namespace {

// What two profiles disagree on, for a message: "dpi, tone, sheets".
std::string differences(const PrinterProfile& a, const PrinterProfile& b) {
    std::vector<std::string> parts;
    if (a.dpi_x.value != b.dpi_x.value || a.dpi_y.value != b.dpi_y.value)
        parts.push_back("dpi " + format_number(a.dpi_x.value) + " x " + format_number(a.dpi_y.value) + " against " +
                        format_number(b.dpi_x.value) + " x " + format_number(b.dpi_y.value));
    if (a.gamma != b.gamma || a.max_density != b.max_density || a.black_level != b.black_level)
        parts.push_back("tone values");
    if (a.sheets != b.sheets)
        parts.push_back(std::to_string(a.sheets) + " sheet(s) against " + std::to_string(b.sheets));
    if (a.film != b.film) parts.push_back("film thickness");
    if (a.paper.name != b.paper.name || a.paper.width != b.paper.width || a.paper.height != b.paper.height ||
        a.paper.margin != b.paper.margin)
        parts.push_back("paper");
    if (parts.empty()) parts.push_back("name");
    std::string text;
    for (const std::string& part : parts) text += (text.empty() ? "" : ", ") + part;
    return text;
}

}  // namespace

PrinterProfile printer_for_pattern(const optics::Design& design, const std::filesystem::path& pattern_file,
                                   const std::string& requested) {
    const std::optional<PrinterProfile> chosen_first =
        requested.empty() ? std::nullopt : std::optional<PrinterProfile>(load_printer(requested));
    const patterns::PatternFileInfo info = patterns::read_pattern_info(pattern_file);
    const std::optional<PrinterProfile> recorded = recorded_printer(info, pattern_file);
    if (!chosen_first) {
        if (recorded) return *recorded;
        if (info.dpi_x > 0.0 && info.dpi_y > 0.0) return default_printer(Dpi{info.dpi_x}, Dpi{info.dpi_y});
        return default_printer(design.printer.dpi_x, design.printer.dpi_y);
    }
    const PrinterProfile& chosen = *chosen_first;
    if (recorded && printer_toml(*recorded) != printer_toml(chosen))
        throw InputError(SourceLocation{pattern_file.string(), 0, 0, "rfd:printer"},
                         "the pattern was encoded for printer '" + recorded->name + "', but --printer " + requested +
                             " is '" + chosen.name + "' (" + differences(*recorded, chosen) +
                             "): leave --printer out to use the pattern's, or encode the pattern again with --printer " +
                             requested);
    return chosen;
}

void check_tone_options(double brightness, int sheets) {
    if (!(brightness > 0.0) || !std::isfinite(brightness))
        throw InputError(SourceLocation{"", 0, 0, "--brightness"}, "expected a positive number, got " + format_number(brightness));
    if (sheets != 0 && sheets != 1 && sheets != 2)
        throw InputError(SourceLocation{"", 0, 0, "--sheets"}, "expected 1 or 2, got " + std::to_string(sheets));
}

PrintSetup check_print(const optics::Design& design, const PrinterProfile& printer,
                       const std::filesystem::path& pattern_file, const patterns::PatternFileInfo& info,
                       double brightness, int sheets) {
    check_tone_options(brightness, sheets);
    if (info.channels != 1 && info.channels != 3)
        throw InputError(SourceLocation{pattern_file.string()},
                         "expected a pattern with 1 (grey) or 3 (RGB) channels, got " + std::to_string(info.channels));
    PrintSetup setup;
    setup.geometry = check_pattern(design, printer, pattern_file, info);
    setup.channels = info.channels;
    setup.tone.printer = printer;
    setup.tone.brightness = brightness;
    setup.tone.white = patterns::number_attribute(info, "white", pattern_file, 1.0, patterns::NumberRange::Positive);
    setup.tone.sheets = sheets == 0 ? printer.sheets : sheets;
    return setup;
}

PrintedTransparency::PrintedTransparency(const optics::Design& design, const PrinterProfile& printer,
                                         std::filesystem::path pattern_file, double brightness, int sheets)
    : file_(std::move(pattern_file)) {
    const PrintSetup setup = check_print(design, printer, file_, patterns::read_pattern_info(file_), brightness, sheets);
    geometry_ = setup.geometry;
    tone_ = setup.tone;
    channels_ = setup.channels;
}

void PrintedTransparency::sample(std::span<const Eigen::Vector2d> points, std::span<float> out) const {
    const std::size_t c = static_cast<std::size_t>(channels_);
    RFD_CHECK(out.size() == points.size() * c);
    std::fill(out.begin(), out.end(), 0.0f);
    // The dot under each point (off the sheet: none), then the points in row order.
    const patterns::PatternGeometry& g = geometry_;
    std::vector<int> row(points.size(), -1), column(points.size(), -1);
    parallel_for_chunks(points.size(), 1 << 14, [&](std::size_t begin, std::size_t end) {
        for (std::size_t k = begin; k < end; ++k) {
            const Eigen::Vector2d r = g.raster_position(points[k]);
            const double x = std::floor(r.x() + 0.5), y = std::floor(r.y() + 0.5);
            if (!(x >= 0.0 && y >= 0.0 && x < g.width && y < g.height)) continue;
            row[k] = static_cast<int>(y);
            column[k] = static_cast<int>(x);
        }
    });
    // Counting sort by row (stable): millions of points per call, so no comparison sort.
    int first_row = g.height, last_row = -1;
    for (int y : row)
        if (y >= 0) {
            first_row = std::min(first_row, y);
            last_row = std::max(last_row, y);
        }
    if (last_row < 0) return;
    std::vector<std::size_t> starts(static_cast<std::size_t>(last_row - first_row + 2), 0);
    for (int y : row)
        if (y >= 0) ++starts[static_cast<std::size_t>(y - first_row) + 1];
    for (std::size_t i = 1; i < starts.size(); ++i) starts[i] += starts[i - 1];
    std::vector<std::size_t> order(starts.back());
    for (std::size_t k = 0; k < points.size(); ++k)
        if (row[k] >= 0) order[starts[static_cast<std::size_t>(row[k] - first_row)]++] = k;

    constexpr int kStripRows = 64;
    patterns::PatternReader reader(file_);
    const std::size_t row_floats = static_cast<std::size_t>(g.width) * c;
    std::vector<float> strip;
    for (std::size_t next = 0; next < order.size();) {
        // A strip of consecutive rows that points land in: rows no point needs are not read.
        const int y0 = row[order[next]];
        int y1 = y0 + 1;
        for (std::size_t k = next; k < order.size() && row[order[k]] <= y1 && y1 - y0 < kStripRows; ++k)
            y1 = std::max(y1, row[order[k]] + 1);
        strip.resize(row_floats * static_cast<std::size_t>(y1 - y0));
        reader.read_rows(y0, y1, strip);
        for (; next < order.size() && row[order[next]] < y1; ++next) {
            const std::size_t k = order[next];
            const float* dot = strip.data() + static_cast<std::size_t>(row[k] - y0) * row_floats +
                               static_cast<std::size_t>(column[k]) * c;
            for (std::size_t ch = 0; ch < c; ++ch)
                out[k * c + ch] = static_cast<float>(tone_.stack_transmittance(dot[ch]));
        }
    }
}

MarkedTransparency::MarkedTransparency(const optics::Transparency& pattern, const optics::Design& design,
                                       const ToneMap& tone)
    : pattern_(pattern),
      markers_(marker_shapes(design, tone.printer.dpi_x.dot_mm(), tone.printer.dpi_y.dot_mm())),
      ink_(static_cast<float>(std::pow(tone.printer.ink_transmittance(), tone.sheets))) {
    for (const MarkerShape& marker : markers_) {
        double reach2 = 0.0;
        for (const Eigen::Vector2d& corner : marker.cell) reach2 = std::max(reach2, (corner - marker.centre).squaredNorm());
        reach2_.push_back(reach2);
    }
}

void MarkedTransparency::sample(std::span<const Eigen::Vector2d> points, std::span<float> out) const {
    pattern_.sample(points, out);
    const auto channels = static_cast<std::size_t>(pattern_.channels());
    for (std::size_t k = 0; k < points.size(); ++k)
        for (std::size_t m = 0; m < markers_.size(); ++m) {
            const MarkerShape& marker = markers_[m];
            // Most points lie far from the four corner cells: a distance first.
            if ((points[k] - marker.centre).squaredNorm() > reach2_[m] || !marker.in_cell(points[k])) continue;
            const float value = marker.inked(points[k]) ? ink_ : 1.0f;
            std::fill_n(out.begin() + static_cast<std::ptrdiff_t>(k * channels), channels, value);
            break;
        }
}

}  // namespace rfd::print
