#include "relight/hdr.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <memory>
#include <set>
#include <span>
#include <vector>


#include "core/error.hpp"
#include "core/files.hpp"
#include "core/image_file.hpp"
#include "relight/vision.hpp"

namespace rfd::relight {
namespace {

constexpr int kMidCode = kCodeCount / 2;  // OpenCV normalises g(128) = 1
// OpenCV's default of 30 iterations stops Robertson's slow fixed-point iteration (started
// from a linear response) while g is still 4% off for a gamma-2.2 camera; 100 brings it
// to about 1% (tests/test_hdr.cpp). Codes a bracket never shows make OpenCV's convergence
// measure NaN, so it usually runs all of them.
constexpr int kRobertsonIterations = 100;
constexpr float kRobertsonTolerance = 1e-4f;
constexpr double kCalibrationPixels = 250000.0;
constexpr const char* kChannelNames[3] = {"red", "green", "blue"};
constexpr const char* kResponseHeader = "code,red,green,blue";

// OpenCV's Robertson code handles three channels only, interleaved in B, G, R order: a grey
// image is given to it as three equal channels. The images of a bracket, all of one size.
struct BgrImages {
    PlaneSize size;
    std::vector<std::vector<std::uint8_t>> images;
    std::vector<std::span<const std::uint8_t>> views() const { return {images.begin(), images.end()}; }
};

// `stride` > 1 keeps every stride-th pixel of every stride-th row.
BgrImages to_bgr(const Bracket& bracket, int stride = 1) {
    const CodeImage& first = bracket.images.front();
    BgrImages bgr{{(first.width + stride - 1) / stride, (first.height + stride - 1) / stride}, {}};
    for (const CodeImage& image : bracket.images) {
        std::vector<std::uint8_t>& codes = bgr.images.emplace_back(3 * bgr.size.area());
        std::size_t k = 0;
        for (int y = 0; y < bgr.size.height; ++y)
            for (int x = 0; x < bgr.size.width; ++x, k += 3)
                for (int c = 0; c < 3; ++c)
                    codes[k + static_cast<std::size_t>(2 - c)] =
                        image.at(x * stride, y * stride, image.channels == 1 ? 0 : c);
    }
    return bgr;
}

// A grey bracket is merged with the green column: green carries most of a grey camera's
// luminance-like sensitivity, and a grey calibration makes all three columns equal anyway.
BgrResponse to_bgr_response(const CameraResponse& response, int channels) {
    BgrResponse bgr{};
    for (int z = 0; z < kCodeCount; ++z)
        for (int c = 0; c < 3; ++c)
            bgr[static_cast<std::size_t>(z)][static_cast<std::size_t>(2 - c)] = response.channels[channels == 1 ? 1 : c][z];
    return bgr;
}

std::vector<float> exposure_times(const Bracket& bracket) {
    std::vector<float> times;
    for (const double t : bracket.exposure_seconds) times.push_back(static_cast<float>(t));
    return times;
}

// Fills codes the calibration never saw (OpenCV leaves them 0) by linear interpolation
// between the nearest observed codes, and proportionally (a line through the origin) beyond
// the first and last observed ones, so that another bracket merged with this response never
// meets a code with g = 0.
void fill_unobserved(std::array<float, kCodeCount>& g, const std::array<std::size_t, kCodeCount>& count) {
    std::vector<int> seen;
    for (int z = 0; z < kCodeCount; ++z)
        if (count[z] > 0) seen.push_back(z);
    RFD_CHECK(!seen.empty());
    for (int z = 0; z < kCodeCount; ++z) {
        if (count[z] > 0) continue;
        const auto upper = std::upper_bound(seen.begin(), seen.end(), z);
        if (upper == seen.begin()) {  // below the first observed code
            g[z] = *upper == 0 ? 0.0f : g[*upper] * static_cast<float>(z) / static_cast<float>(*upper);
        } else if (upper == seen.end()) {  // above the last observed code
            const int last = seen.back();
            g[z] = last == 0 ? g[last] : g[last] * static_cast<float>(z) / static_cast<float>(last);
        } else {
            const int hi = *upper;
            const int lo = *(upper - 1);
            const float s = static_cast<float>(z - lo) / static_cast<float>(hi - lo);
            g[z] = (1.0f - s) * g[lo] + s * g[hi];
        }
    }
}

bool any_unclipped(const Bracket& bracket) {
    for (const CodeImage& image : bracket.images)
        for (const std::uint8_t z : image.codes)
            if (z != 0 && z != kCodeCount - 1) return true;
    return false;
}

[[noreturn]] void all_clipped(const Bracket& bracket) {
    throw InputError("every sample of the bracket (" + bracket.names.front() + ", ...) is 0 or 255 "
                     "in every exposure: nothing left to measure (add shorter or longer exposures)");
}

}  // namespace

CodeImage read_code_image(const std::filesystem::path& path) {
    ImageFileReader file(path);
    const ImageFileSpec& spec = file.spec();
    if (spec.type != SampleType::UInt8)
        throw InputError(SourceLocation{path.string()},
                         "expected an 8-bit camera image (code values 0..255), got " +
                             std::string(sample_type_name(spec.type)) + " samples");
    const int channels = spec.channels;
    if (channels != 1 && channels != 3)
        throw InputError(SourceLocation{path.string()},
                         "expected a grey or RGB image, got " + std::to_string(channels) + " colour channels");
    if (spec.width <= 0 || spec.height <= 0)
        throw InputError(SourceLocation{path.string()}, "image has no pixels");
    std::vector<std::uint8_t> interleaved(static_cast<std::size_t>(spec.width) * spec.height * channels);
    file.read_rows(0, spec.height, interleaved);
    CodeImage image{spec.width, spec.height, channels, std::vector<std::uint8_t>(interleaved.size())};
    const std::size_t plane = static_cast<std::size_t>(spec.width) * spec.height;
    for (std::size_t p = 0; p < plane; ++p)
        for (int c = 0; c < channels; ++c)
            image.codes[static_cast<std::size_t>(c) * plane + p] = interleaved[p * channels + c];
    return image;
}

std::optional<double> read_exposure_time(const std::filesystem::path& path) {
    return ImageFileReader(path).spec().exposure_seconds;
}

Bracket read_bracket(const std::vector<std::filesystem::path>& files,
                     const std::vector<double>& exposure_seconds) {
    if (!exposure_seconds.empty() && exposure_seconds.size() != files.size())
        throw InputError("got " + std::to_string(files.size()) + " images but " +
                         std::to_string(exposure_seconds.size()) + " exposure times");
    Bracket bracket;
    for (std::size_t i = 0; i < files.size(); ++i) {
        bracket.names.push_back(files[i].string());
        bracket.images.push_back(read_code_image(files[i]));
        if (!exposure_seconds.empty()) {
            bracket.exposure_seconds.push_back(exposure_seconds[i]);
            continue;
        }
        const std::optional<double> t = read_exposure_time(files[i]);
        if (!t)
            throw InputError(SourceLocation{files[i].string()},
                             "no EXIF ExposureTime in this image: give the times with --exposures");
        bracket.exposure_seconds.push_back(*t);
    }
    validate_bracket(bracket);
    return bracket;
}

void validate_bracket(const Bracket& bracket) {
    RFD_CHECK(bracket.images.size() == bracket.exposure_seconds.size());
    RFD_CHECK(bracket.images.size() == bracket.names.size());
    if (bracket.images.size() < 2)
        throw InputError("HDR assembly needs at least 2 exposures, got " +
                         std::to_string(bracket.images.size()));
    const CodeImage& first = bracket.images.front();
    std::set<double> times;
    for (std::size_t i = 0; i < bracket.images.size(); ++i) {
        const CodeImage& image = bracket.images[i];
        const SourceLocation where{bracket.names[i]};
        if (image.width != first.width || image.height != first.height || image.channels != first.channels)
            throw InputError(where, "image is " + std::to_string(image.width) + "x" +
                                        std::to_string(image.height) + " with " +
                                        std::to_string(image.channels) + " channel(s), but " +
                                        bracket.names.front() + " is " + std::to_string(first.width) +
                                        "x" + std::to_string(first.height) + " with " +
                                        std::to_string(first.channels));
        const double t = bracket.exposure_seconds[i];
        if (!(std::isfinite(t) && t > 0.0))
            throw InputError(where, "exposure time must be a positive number of seconds, got " +
                                        std::to_string(t));
        if (!times.insert(t).second)
            throw InputError(where, "exposure time " + std::to_string(t) +
                                        " s appears twice: each exposure of a bracket needs its own time");
    }
}

CameraResponse calibrate_response(const Bracket& bracket) {
    validate_bracket(bracket);
    if (!any_unclipped(bracket)) all_clipped(bracket);
    const int channels = bracket.images.front().channels;
    // Every iteration merges the whole bracket: a regular subset of at most ~250k pixels
    // determines 256 values per channel just as well and keeps big photographs fast.
    const double pixels = static_cast<double>(bracket.images.front().width) * bracket.images.front().height;
    const int stride = std::max(1, static_cast<int>(std::ceil(std::sqrt(pixels / kCalibrationPixels))));
    const BgrImages bgr = to_bgr(bracket, stride);

    // How often each code occurs in what the calibration sees, per channel R, G, B.
    std::array<std::array<std::size_t, kCodeCount>, 3> count{};
    for (const std::vector<std::uint8_t>& codes : bgr.images)
        for (std::size_t k = 0; k < codes.size(); k += 3)
            for (int c = 0; c < channels; ++c) ++count[c][codes[k + static_cast<std::size_t>(2 - c)]];
    for (int c = 0; c < channels; ++c)
        if (count[c][kMidCode] == 0)
            throw InputError("cannot calibrate the camera response from " + bracket.names.front() +
                             ", ...: code 128 (the normalisation point) never occurs in the " +
                             (channels == 1 ? std::string("grey") : std::string(kChannelNames[c])) +
                             " channel; use a bracket whose exposures cover mid-grey, or --response");
    const BgrResponse bgr_response = vision().robertson_calibrate(bgr.size, bgr.views(), exposure_times(bracket),
                                                                  kRobertsonIterations, kRobertsonTolerance);

    CameraResponse response;
    for (int c = 0; c < 3; ++c) {
        const int source = channels == 1 ? 0 : c;
        for (int z = 0; z < kCodeCount; ++z) {
            const float g = bgr_response[static_cast<std::size_t>(z)][static_cast<std::size_t>(2 - (channels == 1 ? 1 : c))];
            // g(128) > 0 occurs (checked above), so the normalisation is finite.
            // Codes the bracket never shows come out as 0 * inf = NaN (OpenCV divides by
            // their zero count); fill_unobserved() replaces them below.
            RFD_CHECK_MSG(std::isfinite(g) || count[source][z] == 0, "non-finite response from OpenCV's calibration");
            response.channels[c][z] = std::isfinite(g) ? std::max(g, 0.0f) : 0.0f;
        }
        fill_unobserved(response.channels[c], count[source]);
    }
    return response;
}

bool regular_exposure_ratios(const std::vector<double>& exposure_seconds) {
    std::vector<double> logs;
    for (const double t : exposure_seconds) logs.push_back(std::log(t));
    std::sort(logs.begin(), logs.end());
    if (logs.size() < 2) return true;
    double base = 0.0;  // the smallest step between exposures, in log time
    for (std::size_t i = 1; i < logs.size(); ++i)
        if (logs[i] - logs[i - 1] > 0.0 && (base == 0.0 || logs[i] - logs[i - 1] < base)) base = logs[i] - logs[i - 1];
    if (base == 0.0) return true;
    for (std::size_t i = 1; i < logs.size(); ++i) {
        const double steps = (logs[i] - logs[0]) / base;
        if (std::abs(steps - std::round(steps)) > 0.1) return false;
    }
    return true;
}

MergedImage merge_bracket(const Bracket& bracket, const CameraResponse& response) {
    validate_bracket(bracket);
    if (!any_unclipped(bracket)) all_clipped(bracket);
    const CodeImage& first = bracket.images.front();
    const int channels = first.channels;

    const BgrImages images = to_bgr(bracket);
    std::vector<float> bgr(3 * images.size.area());
    vision().robertson_merge(images.size, images.views(), exposure_times(bracket), to_bgr_response(response, channels),
                             bgr);

    // Samples clipped in every exposure have zero total weight and come out of OpenCV as 0.
    // A sample at 255 somewhere is at least g(254) / t: the brightest exposure the camera
    // still resolves, over the shortest time at which it clipped.
    MergedImage merged;
    merged.radiance = Image(first.width, first.height, channels);
    for (int c = 0; c < channels; ++c) {
        const auto& g = response.channels[channels == 1 ? 1 : c];
        for (int y = 0; y < first.height; ++y) {
            const float* row = bgr.data() + 3 * static_cast<std::size_t>(y) * static_cast<std::size_t>(first.width);
            for (int x = 0; x < first.width; ++x) {
                bool clipped = true;
                double saturated_time = 0.0;
                for (std::size_t i = 0; i < bracket.images.size(); ++i) {
                    const std::uint8_t z = bracket.images[i].at(x, y, c);
                    if (z != 0 && z != kCodeCount - 1) {
                        clipped = false;
                        break;
                    }
                    if (z == kCodeCount - 1 &&
                        (saturated_time == 0.0 || bracket.exposure_seconds[i] < saturated_time))
                        saturated_time = bracket.exposure_seconds[i];
                }
                float value = row[3 * x + (channels == 1 ? 1 : 2 - c)];
                if (clipped && saturated_time > 0.0) {
                    value = static_cast<float>(g[kCodeCount - 2] / saturated_time);
                    ++merged.saturated_samples;
                } else if (clipped) {
                    value = 0.0f;
                    ++merged.black_samples;
                }
                // A response with g = 0 over the codes seen can give 0/eps, never NaN; keep
                // the promise of a finite, non-negative result regardless.
                merged.radiance.at(x, y, c) = std::isfinite(value) ? std::max(value, 0.0f) : 0.0f;
            }
        }
    }
    return merged;
}

void write_response(const std::filesystem::path& path, const CameraResponse& response) {
    std::string text =
        "# rfd camera response: inverse response g of an 8-bit camera, linear exposure per code\n"
        "# (Robertson et al. 2003; arbitrary scale per channel, g(128) = 1 after calibration)\n";
    text += kResponseHeader;
    text += "\n";
    char line[128];
    for (int z = 0; z < kCodeCount; ++z) {
        // 9 significant digits: floats survive the round trip bit for bit.
        std::snprintf(line, sizeof line, "%d,%.9g,%.9g,%.9g\n", z, static_cast<double>(response.channels[0][z]),
                      static_cast<double>(response.channels[1][z]), static_cast<double>(response.channels[2][z]));
        text += line;
    }
    write_text_file(path, text);
}

CameraResponse read_response(const std::filesystem::path& path) {
    std::ifstream in(path);
    if (!in) throw IoError(SourceLocation{path.string()}, "cannot open camera response file");
    CameraResponse response;
    std::string line;
    int line_number = 0;
    bool header = false;
    int code = 0;
    while (std::getline(in, line)) {
        ++line_number;
        if (!line.empty() && line.back() == '\r') line.pop_back();
        if (line.empty() || line.front() == '#') continue;
        if (!header) {
            if (line != kResponseHeader)
                throw InputError(line_in(path, line_number), "expected the header '" + std::string(kResponseHeader) +
                                                            "', got '" + line + "'");
            header = true;
            continue;
        }
        if (code == kCodeCount)
            throw InputError(line_in(path, line_number), "more than 256 codes: unexpected '" + line + "'");
        // Four comma-separated numbers: the code, then g for red, green, blue.
        std::array<double, 4> values{};
        const char* p = line.data();
        const char* end = line.data() + line.size();
        for (std::size_t k = 0; k < values.size(); ++k) {
            const auto [next, ec] = std::from_chars(p, end, values[k]);
            const bool separator_ok = k + 1 < values.size() ? (next != end && *next == ',') : next == end;
            if (ec != std::errc() || !separator_ok)
                throw InputError(line_in(path, line_number),
                                 "expected 'code,red,green,blue' (four numbers), got '" + line + "'");
            p = next + 1;
        }
        if (values[0] != code)
            throw InputError(line_in(path, line_number), "expected code " + std::to_string(code) + ", got '" + line + "'");
        for (int c = 0; c < 3; ++c) {
            const double g = values[static_cast<std::size_t>(c) + 1];
            if (!(std::isfinite(g) && g >= 0.0 && g <= 3.0e38))
                throw InputError(line_in(path, line_number), std::string(kChannelNames[c]) +
                                                            ": expected a finite, non-negative exposure, got '" +
                                                            line + "'");
            response.channels[c][code] = static_cast<float>(g);
        }
        ++code;
    }
    if (!header) throw InputError(line_in(path, line_number), "no header line '" + std::string(kResponseHeader) + "'");
    if (code != kCodeCount)
        throw InputError(line_in(path, line_number),
                         "expected 256 codes (0..255), the file ends after " + std::to_string(code));
    for (int c = 0; c < 3; ++c)
        if (std::all_of(response.channels[c].begin(), response.channels[c].end(), [](float g) { return g == 0.0f; }))
            throw InputError(SourceLocation{path.string()},
                             std::string(kChannelNames[c]) + ": the response is zero for every code");
    return response;
}

}  // namespace rfd::relight
