// Pattern files (rfd pattern encode's EXR): the header and its rfd: attributes as the
// commands that take a pattern read them (read_pattern_info, the angular mapping, print
// sheet's checks against Design II at a 20 dpi printer), then the dots a strip at a time.
#include <algorithm>
#include <filesystem>
#include <vector>

#include "fuzz/fuzz.hpp"
#include "optics/design.hpp"
#include "patterns/encode.hpp"
#include "patterns/raster.hpp"
#include "print/printed.hpp"
#include "print/printer.hpp"

using namespace rfd;

namespace {

const optics::Design& design() {
    static const optics::Design loaded = optics::load_design(RFD_FUZZ_DESIGN);
    return loaded;
}

const print::PrinterProfile& printer() {
    static const print::PrinterProfile profile = print::parse_printer(
        "[printer]\nname = \"fuzz\"\ndpi_x = 20\ndpi_y = 20\ngamma = 1.0\nmax_density = 2.0\nblack_level = 0.02\n",
        "fuzz_printer.toml");
    return profile;
}

}  // namespace

RFD_FUZZ_TARGET(pattern) {
    const auto path = fuzz::scratch_folder() / "pattern.exr";
    fuzz::write_bytes(path, data, size);
    const patterns::PatternFileInfo header = patterns::read_pattern_info(path);
    patterns::encode_options_of(header, path.string());  // the mapping and every other attribute

    patterns::PatternReader reader(path);
    const patterns::PatternFileInfo& info = reader.info();
    patterns::require_printable_channels(info.channels, SourceLocation{path.string()});
    print::check_print(design(), printer(), path, info, /*brightness=*/1.0, /*sheets=*/0);
    constexpr int kStrip = 64;
    std::vector<float> strip(static_cast<std::size_t>(info.width) * static_cast<std::size_t>(info.channels) * kStrip);
    for (int y0 = 0; y0 < info.height; y0 += kStrip) reader.read_rows(y0, std::min(info.height, y0 + kStrip), strip);
}
