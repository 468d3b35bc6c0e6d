#include "patterns/raster.hpp"

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <cstdlib>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <future>
#include <limits>
#include <span>
#include <utility>
#include <vector>

#include "core/error.hpp"
#include "core/number.hpp"
#include "core/files.hpp"
#include "core/half.hpp"
#include "core/image.hpp"
#include "core/image_file.hpp"
#include "core/image_io.hpp"
#include "core/parallel.hpp"
#include "core/progress.hpp"

namespace rfd::patterns {
namespace {

constexpr const char* kAttributePrefix = "rfd:";

// Half-extent of what the pattern must cover, mm.
Eigen::Vector2d covered_half_extent(const optics::Design& design) {
    if (design.macro)
        return {0.5 * design.macro->count_x * design.macro->pitch_x,
                0.5 * design.macro->count_y * design.macro->pitch_y};
    const optics::Plane& plane = design.pattern_plane();
    if (plane.part) {
        if (const auto* array = std::get_if<optics::LensletArrayPart>(&*plane.part))
            return array->lattice.half_extent();
    }
    // The pattern lies on a sheet: the extent of the first lenslet array of the design.
    for (const optics::Plane& p : design.planes)
        if (p.part)
            if (const auto* array = std::get_if<optics::LensletArrayPart>(&*p.part))
                return array->lattice.half_extent();
    throw InputError(SourceLocation{design.file}, "design has no lenslet array to print a pattern for");
}

// The first dot of `row` with a NaN or infinite value, or -1. The common all-finite case
// is a branch-free pass the compiler vectorises; only a bad row is searched.
int first_non_finite(std::span<const float> row, int channels) {
    bool all_finite = true;
    for (const float v : row) all_finite &= std::abs(v) <= std::numeric_limits<float>::max();
    if (all_finite) return -1;
    for (std::size_t i = 0; i < row.size(); ++i)
        if (!std::isfinite(row[i])) return static_cast<int>(i / static_cast<std::size_t>(channels));
    return -1;
}

// The first sample of `bits` that is an infinite (or NaN) half float, or -1: a finite value
// too large for a half (65520 and up) becomes infinite in conversion.
long first_infinite_half(std::span<const std::uint16_t> bits) {
    constexpr std::uint16_t exponent = 0x7C00;
    bool all_finite = true;
    for (const std::uint16_t b : bits) all_finite &= (b & exponent) != exponent;
    if (all_finite) return -1;
    for (std::size_t i = 0; i < bits.size(); ++i)
        if ((bits[i] & exponent) == exponent) return static_cast<long>(i);
    return -1;
}

}  // namespace

PatternGeometry pattern_geometry(const optics::Design& design, Dpi dpi_x, Dpi dpi_y,
                                 double margin_mm) {
    const SourceLocation where{design.file, 0, 0, "printer"};
    if (!(dpi_x.value > 0.0) || !(dpi_y.value > 0.0) || !std::isfinite(dpi_x.value) ||
        !std::isfinite(dpi_y.value))
        throw InputError(where, "print resolution must be positive, got " +
                                    std::to_string(dpi_x.value) + " x " + std::to_string(dpi_y.value) +
                                    " dpi");
    if (!(margin_mm >= 0.0)) throw InputError(where, "pattern margin must not be negative");
    const Eigen::Vector2d half = covered_half_extent(design);
    PatternGeometry g;
    g.dpi_x = dpi_x.value;
    g.dpi_y = dpi_y.value;
    g.dot_x = dpi_x.dot_mm();
    g.dot_y = dpi_y.dot_mm();
    g.margin_mm = margin_mm;
    // Whole dots; a hair of tolerance so an extent that is a whole number of dots in exact
    // arithmetic does not gain one from rounding.
    const double w = std::ceil(2.0 * (half.x() + margin_mm) / g.dot_x - 1e-9);
    const double h = std::ceil(2.0 * (half.y() + margin_mm) / g.dot_y - 1e-9);
    constexpr double kMaxSide = std::numeric_limits<int>::max();
    if (w > kMaxSide || h > kMaxSide)
        throw InputError(where, "a pattern of " + std::to_string(w) + " x " + std::to_string(h) +
                                    " dots is too large");
    g.width = static_cast<int>(w);
    g.height = static_cast<int>(h);
    return g;
}

void require_printable_channels(int channels, const SourceLocation& where) {
    if (channels != 1 && channels != 3)
        throw InputError(where, "the field's images have " + std::to_string(channels) +
                                    " channels; a pattern is grey (1 channel) or colour (3: R, G, B)");
}

void write_pattern(const std::filesystem::path& path, const PatternSource& source,
                   const PatternAttributes& attributes, const WriteOptions& options) {
    const PatternGeometry& g = source.geometry();
    const int channels = source.channels();
    RFD_CHECK(g.width > 0 && g.height > 0 && options.rows_per_strip > 0);
    require_printable_channels(channels, SourceLocation{path.string()});
    const std::string ext = lower_extension(path);
    ImageFileSpec spec{.width = g.width, .height = g.height, .channels = channels, .dpi_x = g.dpi_x, .dpi_y = g.dpi_y};
    bool srgb = false;
    if (ext == ".exr") {
        spec.type = options.half_float ? SampleType::Half : SampleType::Float32;
        spec.compression = options.exr_compression;
        for (const auto& [key, value] : attributes) spec.attributes[key] = value;
    } else if (ext == ".tif" || ext == ".tiff" || ext == ".png") {
        spec.type = ext == ".png" ? SampleType::UInt8 : SampleType::UInt16;
        if (ext != ".png") spec.compression = "zip";
        srgb = true;
        // TIFF and PNG keep no custom attributes: one "rfd:key=value" line each in the
        // image description instead.
        for (const auto& [key, value] : attributes) {
            RFD_CHECK(key.find('=') == std::string::npos && value.find('\n') == std::string::npos);
            spec.description += kAttributePrefix + key + "=" + value + "\n";
        }
    } else {
        throw InputError(SourceLocation{path.string()},
                         "unknown pattern extension '" + ext + "' (expected .exr, .tif or .png)");
    }
    ImageFileWriter output(path, spec, "pattern");

    const std::size_t row_floats = static_cast<std::size_t>(g.width) * static_cast<std::size_t>(channels);
    const int strip_rows = std::min(options.rows_per_strip, g.height);
    // Half-float EXR rows are converted by the rendering threads (F16C, in parallel), so the
    // writer thread is left with compression and disk; other formats go as float to
    // OpenImageIO, which converts them.
    const bool half = spec.type == SampleType::Half;
    const SampleType strip_type = half ? SampleType::Half : SampleType::Float32;
    const std::size_t row_bytes = row_floats * sample_size(strip_type);
    // Two strips: one is written (on its own thread: compression and disk) while the next
    // is rendered in parallel.
    std::array<std::vector<std::byte>, 2> strips;
    for (auto& strip : strips) strip.resize(row_bytes * static_cast<std::size_t>(strip_rows));
    std::vector<int> first_bad(static_cast<std::size_t>(strip_rows));
    // Per row of a strip: the first sample too large for a half float, and its value.
    std::vector<std::pair<long, float>> too_large(static_cast<std::size_t>(strip_rows));
    std::future<void> writing;
    Progress progress(options.progress_label, static_cast<std::size_t>(g.height));
    auto finish_writing = [&] {
        if (writing.valid()) writing.get();  // rethrows the writer's IoError
    };
    try {
        for (int y0 = 0, k = 0; y0 < g.height; y0 += strip_rows, ++k) {
            const int y1 = std::min(g.height, y0 + strip_rows);
            std::vector<std::byte>& strip = strips[static_cast<std::size_t>(k % 2)];
            parallel_for_chunks(static_cast<std::size_t>(y1 - y0), 1, [&](std::size_t begin, std::size_t end) {
                std::vector<float> rendered(half ? row_floats : 0);
                for (std::size_t r = begin; r < end; ++r) {
                    std::byte* destination = strip.data() + r * row_bytes;
                    std::span<float> row = half ? std::span<float>(rendered)
                                                : std::span<float>(reinterpret_cast<float*>(destination), row_floats);
                    source.render_row(y0 + static_cast<int>(r), row);
                    first_bad[r] = first_non_finite(row, channels);
                    if (first_bad[r] >= 0) continue;
                    if (half) {
                        const std::span<std::uint16_t> bits(reinterpret_cast<std::uint16_t*>(destination), row_floats);
                        floats_to_half(row, bits);
                        const long sample = first_infinite_half(bits);
                        too_large[r] = {sample, sample >= 0 ? row[static_cast<std::size_t>(sample)] : 0.0f};
                    } else if (srgb) {
                        for (float& v : row) v = linear_to_srgb(std::clamp(v, 0.0f, 1.0f));
                    }
                }
            });
            for (int r = 0; r < y1 - y0; ++r) {
                const std::size_t row = static_cast<std::size_t>(r);
                if (first_bad[row] >= 0)
                    throw InputError(SourceLocation{path.string()},
                                     "refusing to write dot (" + std::to_string(first_bad[row]) + ", " +
                                         std::to_string(y0 + r) + "): the pattern value is not a finite number");
                if (half && too_large[row].first >= 0) {
                    char value[32];
                    std::snprintf(value, sizeof value, "%g", static_cast<double>(too_large[row].second));
                    throw InputError(SourceLocation{path.string()},
                                     "refusing to write dot (" + std::to_string(too_large[row].first / channels) + ", " +
                                         std::to_string(y0 + r) + "): the pattern value " +
                                         value +
                                         " is beyond the largest half float, 65504 (a field in camera units?): "
                                         "scale the field down, or write 32-bit floats (--single-float)");
                }
            }
            finish_writing();  // the other strip's write, before this one starts
            writing = std::async(std::launch::async, [&output, &strip, strip_type, y0, y1] {
                output.write_rows(y0, y1, strip_type, strip.data());
            });
            progress.advance(static_cast<std::size_t>(y1 - y0));
        }
        finish_writing();
    } catch (...) {
        if (writing.valid()) writing.wait();  // never leave the writer running on freed strips
        throw;
    }
    output.finish();
    progress.finish();
}

namespace {

PatternFileInfo info_of(const ImageFileSpec& spec) {
    PatternFileInfo info{.width = spec.width, .height = spec.height, .channels = spec.channels,
                         .dpi_x = spec.dpi_x, .dpi_y = spec.dpi_y, .attributes = spec.attributes};
    const std::string prefix = kAttributePrefix;
    const std::string& description = spec.description;
    std::size_t start = 0;
    while (start < description.size()) {
        std::size_t end = description.find('\n', start);
        if (end == std::string::npos) end = description.size();
        const std::string line = description.substr(start, end - start);
        const std::size_t equals = line.find('=');
        if (line.rfind(prefix, 0) == 0 && equals != std::string::npos)
            info.attributes[line.substr(prefix.size(), equals - prefix.size())] = line.substr(equals + 1);
        start = end + 1;
    }
    return info;
}

}  // namespace

PatternReader::PatternReader(const std::filesystem::path& path)
    : file_(std::make_unique<ImageFileReader>(path, "pattern")), info_(info_of(file_->spec())) {
    if (info_.width <= 0 || info_.height <= 0 || info_.channels <= 0)
        throw InputError(SourceLocation{path.string()}, "pattern has no pixels");
}

PatternReader::~PatternReader() = default;
PatternReader::PatternReader(PatternReader&&) noexcept = default;
PatternReader& PatternReader::operator=(PatternReader&&) noexcept = default;

void PatternReader::read_rows(int y0, int y1, std::span<float> out) {
    RFD_CHECK(0 <= y0 && y0 <= y1 && y1 <= info_.height);
    const std::size_t row_floats = static_cast<std::size_t>(info_.width) * static_cast<std::size_t>(info_.channels);
    RFD_CHECK(out.size() >= row_floats * static_cast<std::size_t>(y1 - y0));
    if (y0 == y1) return;
    file_->read_rows(y0, y1, out);
    const bool srgb = file_->spec().type == SampleType::UInt8 || file_->spec().type == SampleType::UInt16;
    const std::size_t count = row_floats * static_cast<std::size_t>(y1 - y0);
    for (std::size_t k = 0; k < count; ++k) {
        float& v = out[k];
        if (!std::isfinite(v)) {
            const std::size_t row = k / row_floats;
            const std::size_t column = (k % row_floats) / static_cast<std::size_t>(info_.channels);
            throw InputError(SourceLocation{file_->path().string()},
                             "dot (" + std::to_string(column) + ", " + std::to_string(y0 + static_cast<int>(row)) +
                                 ") is not a finite number");
        }
        if (srgb) v = srgb_to_linear(v);
    }
}

PatternFileInfo read_pattern_info(const std::filesystem::path& path) {
    return PatternReader(path).info();
}

Image box_averaged(const std::filesystem::path& pattern, int width, int height) {
    RFD_CHECK(width > 0 && height > 0);
    PatternReader reader(pattern);
    const PatternFileInfo& info = reader.info();
    const int w = width, h = height, channels = info.channels;
    std::vector<double> sum(static_cast<std::size_t>(w) * static_cast<std::size_t>(h) * static_cast<std::size_t>(channels), 0.0);
    std::vector<double> count(static_cast<std::size_t>(w) * static_cast<std::size_t>(h), 0.0);
    const std::size_t row_floats = static_cast<std::size_t>(info.width) * static_cast<std::size_t>(channels);
    constexpr int kStrip = 64;
    std::vector<float> strip(row_floats * kStrip);
    for (int y0 = 0; y0 < info.height; y0 += kStrip) {
        const int y1 = std::min(info.height, y0 + kStrip);
        reader.read_rows(y0, y1, strip);
        for (int y = y0; y < y1; ++y) {
            const int py = std::min(h - 1, static_cast<int>(static_cast<long long>(y) * h / info.height));
            const float* row = strip.data() + static_cast<std::size_t>(y - y0) * row_floats;
            for (int x = 0; x < info.width; ++x) {
                const int px = std::min(w - 1, static_cast<int>(static_cast<long long>(x) * w / info.width));
                const std::size_t p = static_cast<std::size_t>(py) * static_cast<std::size_t>(w) + static_cast<std::size_t>(px);
                count[p] += 1.0;
                for (int c = 0; c < channels; ++c)
                    sum[p * static_cast<std::size_t>(channels) + static_cast<std::size_t>(c)] += row[static_cast<std::size_t>(x * channels + c)];
            }
        }
    }
    Image image(w, h, channels);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const std::size_t p = static_cast<std::size_t>(y) * static_cast<std::size_t>(w) + static_cast<std::size_t>(x);
            for (int c = 0; c < channels; ++c)
                image.at(x, y, c) = static_cast<float>(sum[p * static_cast<std::size_t>(channels) + static_cast<std::size_t>(c)] /
                                                       std::max(count[p], 1.0));
        }
    return image;
}

void write_preview(const std::filesystem::path& pattern, const std::filesystem::path& preview, int max_side,
                   double white) {
    RFD_CHECK(max_side > 0);
    const PatternFileInfo info = read_pattern_info(pattern);
    if (!(white > 0.0)) {
        const auto it = info.attributes.find("white");
        white = it != info.attributes.end() ? std::atof(it->second.c_str()) : 1.0;
        if (!(white > 0.0)) white = 1.0;
    }
    // Physical aspect: dots are 1/dpi_x by 1/dpi_y inches.
    const double width_in = info.dpi_x > 0 ? info.width / info.dpi_x : info.width;
    const double height_in = info.dpi_y > 0 ? info.height / info.dpi_y : info.height;
    // No preview pixel smaller than a dot, so that every one averages at least one.
    const double scale = std::min({max_side / std::max(width_in, height_in), info.width / width_in, info.height / height_in});
    const int w = std::max(1, static_cast<int>(std::lround(width_in * scale)));
    const int h = std::max(1, static_cast<int>(std::lround(height_in * scale)));
    Image image = box_averaged(pattern, w, h);
    for (float& v : image.samples()) v = static_cast<float>(v / white);
    write_image(preview, image);
}

double number_attribute(const PatternFileInfo& info, const std::string& key, const std::filesystem::path& file,
                        double fallback, NumberRange range) {
    const auto it = info.attributes.find(key);
    if (it == info.attributes.end()) return fallback;
    const std::optional<double> value = finite_number(it->second);
    const bool in_range = value && (range == NumberRange::Any || (range == NumberRange::NonNegative && *value >= 0.0) ||
                                    (range == NumberRange::Positive && *value > 0.0));
    if (!in_range) {
        const char* expected = range == NumberRange::Positive      ? "a positive number"
                               : range == NumberRange::NonNegative ? "a non-negative number"
                                                                   : "a number";
        throw InputError(SourceLocation{file.string(), 0, 0, "rfd:" + key},
                         std::string("expected ") + expected + ", got '" + it->second + "'");
    }
    return *value;
}

}  // namespace rfd::patterns
