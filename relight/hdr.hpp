#pragma once
// HDR assembly from exposure brackets (thesis 4.1: every light-stage image is an HDR image
// assembled from several exposures), after Robertson, Borman and Stevenson (2003), through
// OpenCV's photo module.
//
// Model: an 8-bit camera records code z = f(E * t) for irradiance E and exposure time t;
// the inverse response g = f^-1 maps each code 0..255 to a linear exposure E * t. Given g,
// the merged irradiance of a pixel is the weighted least-squares estimate over the bracket
//     E = sum_i w(z_i) t_i g(z_i) / sum_i w(z_i) t_i^2,
// with OpenCV's Robertson weights w (a Gaussian bump over the codes, exactly zero at 0 and
// 255, so clipped codes carry no information). Calibration estimates g from the bracket
// itself (alternating E and g). g, hence E, is known only up to one scale per channel:
// OpenCV scales each channel so that g(128) = 1. Results are linear, in units of g per
// second; fit one scale against a reference when absolute radiance matters.
//
// A whole light-stage capture should share one response: calibrate it once on a
// well-exposed bracket, save it (write_response, a CSV documented in docs/formats.md), and
// merge every other bracket with it.
//
// Images are 8-bit code values exactly as the camera wrote them (no sRGB decoding: the
// response curve replaces it), grey or RGB; an alpha channel is dropped.
//
// Example:
//     Bracket bracket = read_bracket({"a.jpg", "b.jpg"}, {1.0 / 60, 1.0 / 15});
//     CameraResponse g = calibrate_response(bracket);
//     Image radiance = merge_bracket(bracket, g).radiance;

#include <array>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "core/image.hpp"

namespace rfd::relight {

/// Number of code values of an 8-bit camera.
inline constexpr int kCodeCount = 256;

/// An 8-bit photograph as the camera encoded it, planar like rfd::Image:
/// code (x, y, c) lives at codes[(c * height + y) * width + x]; channels are R, G, B (or grey).
struct CodeImage {
    int width = 0;
    int height = 0;
    int channels = 0;                  ///< 1 (grey) or 3 (RGB)
    std::vector<std::uint8_t> codes;   ///< width * height * channels values, 0..255

    std::uint8_t at(int x, int y, int c) const {
        return codes[(static_cast<std::size_t>(c) * static_cast<std::size_t>(height) +
                      static_cast<std::size_t>(y)) * static_cast<std::size_t>(width) +
                     static_cast<std::size_t>(x)];
    }
};

/// Exposures of one scene from one viewpoint, differing only in exposure time.
struct Bracket {
    std::vector<CodeImage> images;        ///< all the same size and channel count
    std::vector<double> exposure_seconds; ///< one per image, > 0, all distinct
    std::vector<std::string> names;       ///< per image, for messages (file names)
};

/// Inverse camera response g per channel: linear exposure (arbitrary units, g(128) = 1 after
/// calibration) for each code 0..255. Channel order R, G, B; a grey camera's response has
/// three equal columns.
struct CameraResponse {
    std::array<std::array<float, kCodeCount>, 3> channels{};  ///< [channel][code]
};

/// Reads an 8-bit image file's code values through OpenImageIO. Throws IoError if it cannot
/// be read, InputError if it is not 8 bits per sample or has other than 1 or 3 colour channels.
CodeImage read_code_image(const std::filesystem::path& path);

/// The EXIF ExposureTime of an image file in seconds, or nullopt when the file has none.
/// Throws IoError if the file cannot be opened.
std::optional<double> read_exposure_time(const std::filesystem::path& path);

/// Reads every file and pairs it with its exposure time; `exposure_seconds` empty means "use
/// each file's EXIF ExposureTime". Throws InputError naming the file for a missing EXIF
/// time, and everything validate_bracket() throws.
Bracket read_bracket(const std::vector<std::filesystem::path>& files,
                     const std::vector<double>& exposure_seconds = {});

/// Throws InputError (naming the image) unless the bracket holds at least two images of the
/// same size and channel count, with one positive, finite, distinct exposure time each.
void validate_bracket(const Bracket& bracket);

/// Robertson calibration of the inverse response from the bracket itself. Codes the bracket
/// never shows are filled by linear interpolation between their observed neighbours, so the
/// response can merge other brackets. Throws InputError when the bracket cannot determine a
/// response: a channel never shows code 128 (the normalisation point), or no sample is
/// unclipped (every code 0 or 255).
CameraResponse calibrate_response(const Bracket& bracket);

/// True when every exposure time is the shortest times an integer power of one ratio (within
/// a tenth of a step), as in the usual +-1 EV brackets. Self-calibration is then ambiguous: any
/// g times a factor periodic in log exposure with that period explains the bracket equally
/// well, and Robertson's iteration keeps whatever its linear start leaves there (errors of
/// 20% in g for a gamma-2.2 camera and 4x steps). Calibrate from a bracket with uneven steps.
bool regular_exposure_ratios(const std::vector<double>& exposure_seconds);

/// Result of merging a bracket.
struct MergedImage {
    Image radiance;                   ///< linear, one channel per bracket channel, finite, >= 0
    std::size_t saturated_samples = 0;  ///< samples at 255 in every exposure: set to the
                                        ///< lower bound g(255) / t_min
    std::size_t black_samples = 0;      ///< samples at 0 in every exposure: set to 0
};

/// Merges the bracket into one linear image with `response` (Robertson's estimator above).
/// Throws InputError when every sample of the bracket is clipped (0 or 255 in every
/// exposure): there is nothing to measure.
MergedImage merge_bracket(const Bracket& bracket, const CameraResponse& response);

/// Writes a response as CSV (docs/formats.md, "Camera response files"), atomically.
void write_response(const std::filesystem::path& path, const CameraResponse& response);

/// Reads a response CSV. Throws IoError if unreadable, InputError naming file and line for a
/// wrong header, a missing or out-of-order code, an unparsable, negative or non-finite value,
/// or a channel that is zero everywhere.
CameraResponse read_response(const std::filesystem::path& path);

}  // namespace rfd::relight
