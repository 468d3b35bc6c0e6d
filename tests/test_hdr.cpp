// HDR assembly: synthetic brackets of a known radiance image through a known camera
// (gamma 2.2, per-channel gain, clipping at 1, 8-bit rounding) must merge back to that
// radiance; the calibrated response must follow the true curve; files round-trip; bad
// brackets and bad response files are input errors that say where.

#include <algorithm>
#include <cmath>
#include <fstream>
#include <functional>
#include <string>
#include <vector>

#include "core/image_file.hpp"
#include <gtest/gtest.h>

#include "core/error.hpp"
#include "core/image_io.hpp"
#include "relight/hdr.hpp"
#include "tests/support/temp_dir.hpp"

namespace rfd::relight {
namespace {

constexpr double kGamma = 2.2;
// Different gains per channel: a red/blue swap anywhere (OpenCV works in BGR) shows up.
constexpr double kGain[3] = {1.0, 0.6, 0.3};

// Radiance spanning three decades, a different ramp per channel so channels never coincide.
Image radiance_ramp(int width, int height, int channels) {
    Image e(width, height, channels);
    const double n = static_cast<double>(width * height - 1);
    for (int c = 0; c < channels; ++c)
        for (int y = 0; y < height; ++y)
            for (int x = 0; x < width; ++x) {
                const int k = (x + width * y + c * 397) % (width * height);
                e.at(x, y, c) = static_cast<float>(0.01 * std::pow(1000.0, k / n));
            }
    return e;
}

// The synthetic camera: z = round(255 * clamp(gain * E * t, 0, 1)^(1 / gamma)).
CodeImage expose(const Image& e, double seconds) {
    CodeImage image{e.width(), e.height(), e.channels(), {}};
    for (int c = 0; c < e.channels(); ++c)
        for (int y = 0; y < e.height(); ++y)
            for (int x = 0; x < e.width(); ++x) {
                const double exposure = std::clamp(kGain[c] * e.at(x, y, c) * seconds, 0.0, 1.0);
                image.codes.push_back(static_cast<std::uint8_t>(std::lround(255.0 * std::pow(exposure, 1.0 / kGamma))));
            }
    return image;
}

Bracket bracket_of(const Image& e, const std::vector<double>& times) {
    Bracket bracket;
    for (std::size_t i = 0; i < times.size(); ++i) {
        bracket.images.push_back(expose(e, times[i]));
        bracket.exposure_seconds.push_back(times[i]);
        bracket.names.push_back("exposure_" + std::to_string(i) + ".png");
    }
    return bracket;
}

// The camera's exact inverse response, g(z) = (z / 255)^gamma / gain.
CameraResponse true_response() {
    CameraResponse g;
    for (int c = 0; c < 3; ++c)
        for (int z = 0; z < kCodeCount; ++z)
            g.channels[c][z] = static_cast<float>(std::pow(z / 255.0, kGamma) / kGain[c]);
    return g;
}

// A sample is measurable when some exposure records it unclipped in the middle of the range.
bool well_exposed(const Bracket& bracket, int x, int y, int c) {
    for (const CodeImage& image : bracket.images)
        if (image.at(x, y, c) >= 32 && image.at(x, y, c) <= 240) return true;
    return false;
}

// A regular bracket (steps of 4x) and an uneven one over the same range.
const std::vector<double> kTimes = {1.0 / 16, 1.0 / 4, 1.0, 4.0};
const std::vector<double> kUneven = {1.0 / 16, 1.0 / 5, 1.0, 3.3};

// Worst relative error of a calibrated g against the truth, both normalised at code 128,
// over codes 16..250 (below 16 a code step is over 7% of the value).
double worst_response_error(const CameraResponse& g) {
    const CameraResponse truth = true_response();
    double worst = 0.0;
    for (int c = 0; c < 3; ++c)
        for (int z = 16; z <= 250; ++z) {
            const double expected = truth.channels[c][z] / truth.channels[c][128];
            worst = std::max(worst, std::abs(g.channels[c][z] / expected - 1.0));
        }
    return worst;
}

TEST(Hdr, MergeWithTrueResponseRecoversRadianceWithoutScale) {
    const Image e = radiance_ramp(48, 32, 3);
    const Bracket bracket = bracket_of(e, kTimes);
    const MergedImage merged = merge_bracket(bracket, true_response());
    ASSERT_TRUE(merged.radiance.same_shape(e));
    double worst = 0.0, worst_mid = 0.0;
    for (int c = 0; c < 3; ++c)
        for (int y = 0; y < e.height(); ++y)
            for (int x = 0; x < e.width(); ++x) {
                ASSERT_TRUE(well_exposed(bracket, x, y, c));
                int best = 0;  // the highest unclipped code of this sample over the bracket
                for (const CodeImage& image : bracket.images)
                    if (image.at(x, y, c) < 255) best = std::max<int>(best, image.at(x, y, c));
                const double error = std::abs(merged.radiance.at(x, y, c) / e.at(x, y, c) - 1.0);
                worst = std::max(worst, error);
                if (best >= 64) worst_mid = std::max(worst_mid, error);
            }
    // Only 8-bit rounding remains: half a code at code z is a relative error of about
    // gamma * 0.5 / z: 1.7% at z = 64, 3.4% at z = 32 (the darkest blue samples reach 34).
    EXPECT_LT(worst_mid, 0.017) << "worst relative error where some code >= 64: " << worst_mid;
    EXPECT_LT(worst, 0.034) << "worst relative error: " << worst;
    EXPECT_EQ(merged.saturated_samples, 0u);
    EXPECT_EQ(merged.black_samples, 0u);
}

TEST(Hdr, CalibratedResponseFollowsTheTrueCurve) {
    ASSERT_FALSE(regular_exposure_ratios(kUneven));
    const CameraResponse g = calibrate_response(bracket_of(radiance_ramp(64, 48, 3), kUneven));
    for (int c = 0; c < 3; ++c) {
        EXPECT_NEAR(g.channels[c][128], 1.0, 1e-6);  // OpenCV's normalisation point
        for (int z = 1; z < kCodeCount; ++z) EXPECT_GT(g.channels[c][z], 0.0f) << "code " << z;
    }
    const double worst = worst_response_error(g);
    EXPECT_LT(worst, 0.02) << "worst relative error of g over codes 16..250: " << worst;
}

TEST(Hdr, RegularBracketsLeaveTheResponseAmbiguous) {
    // Where Robertson self-calibration fails: with every time a power of 4 times the shortest,
    // g times any function of period log 4 in log exposure fits the bracket exactly, and the
    // iteration keeps the ripple its linear start leaves (about 20% for gamma 2.2).
    EXPECT_TRUE(regular_exposure_ratios(kTimes));
    EXPECT_TRUE(regular_exposure_ratios({1.0 / 60, 1.0 / 30, 1.0 / 8}));  // 1, 2 and 3 steps of 2x
    EXPECT_FALSE(regular_exposure_ratios({1.0, 2.0, 3.0}));
    const double worst = worst_response_error(calibrate_response(bracket_of(radiance_ramp(64, 48, 3), kTimes)));
    EXPECT_GT(worst, 0.1) << "the regular bracket calibrated well (" << worst << "): update the docs";
}

TEST(Hdr, CalibratedMergeIsProportionalToTheTruth) {
    const Image e = radiance_ramp(64, 48, 3);
    const Bracket bracket = bracket_of(e, kUneven);
    const MergedImage merged = merge_bracket(bracket, calibrate_response(bracket));
    for (int c = 0; c < 3; ++c) {
        // Least-squares scale per channel (each channel's g is normalised on its own).
        double num = 0.0, den = 0.0;
        for (int y = 0; y < e.height(); ++y)
            for (int x = 0; x < e.width(); ++x) {
                const double m = merged.radiance.at(x, y, c), t = e.at(x, y, c);
                num += m / t;
                den += (m / t) * (m / t);
            }
        const double scale = num / den;  // minimises sum (scale * m / t - 1)^2
        double worst = 0.0;
        for (int y = 0; y < e.height(); ++y)
            for (int x = 0; x < e.width(); ++x)
                if (well_exposed(bracket, x, y, c))
                    worst = std::max(worst, std::abs(scale * merged.radiance.at(x, y, c) / e.at(x, y, c) - 1.0));
        // Measured 2.2% (red), 2.4% (green), 3.7% (blue, the darkest): g's 1-2% error plus rounding.
        EXPECT_LT(worst, 0.04) << "channel " << c << " worst relative error " << worst;
        // Calibration normalises g(128) = 1, so the scale is g_true(128) = (128/255)^gamma / gain,
        // different per channel: the channel order survived OpenCV's BGR.
        const double expected_scale = std::pow(128.0 / 255.0, kGamma) / kGain[c];
        EXPECT_NEAR(scale / expected_scale, 1.0, 0.01) << "channel " << c;
    }
}

TEST(Hdr, GreyBracketMergesToOneChannel) {
    const Image e = radiance_ramp(32, 32, 1);
    const Bracket bracket = bracket_of(e, kTimes);
    CameraResponse g = true_response();
    g.channels[1] = g.channels[0];  // a grey bracket uses the green column
    const MergedImage merged = merge_bracket(bracket, g);
    ASSERT_EQ(merged.radiance.channels(), 1);
    for (int y = 0; y < e.height(); ++y)
        for (int x = 0; x < e.width(); ++x)
            ASSERT_NEAR(merged.radiance.at(x, y, 0) / e.at(x, y, 0), 1.0, 0.02);
    const CameraResponse calibrated = calibrate_response(bracket);
    EXPECT_EQ(calibrated.channels[0], calibrated.channels[1]);
    EXPECT_EQ(calibrated.channels[1], calibrated.channels[2]);
}

TEST(Hdr, SamplesClippedEverywhereGetBoundsAndAreCounted) {
    Image e = radiance_ramp(16, 16, 3);
    e.at(3, 4, 0) = 1.0e6f;  // saturated even in the shortest exposure
    e.at(5, 6, 2) = 1.0e-9f;  // black even in the longest
    const Bracket bracket = bracket_of(e, kTimes);
    const CameraResponse g = true_response();
    const MergedImage merged = merge_bracket(bracket, g);
    EXPECT_EQ(merged.saturated_samples, 1u);
    EXPECT_EQ(merged.black_samples, 1u);
    EXPECT_FLOAT_EQ(merged.radiance.at(3, 4, 0), static_cast<float>(g.channels[0][254] / kTimes.front()));
    EXPECT_EQ(merged.radiance.at(5, 6, 2), 0.0f);
}

TEST(Hdr, MergeIsDeterministic) {
    const Bracket bracket = bracket_of(radiance_ramp(32, 16, 3), kTimes);
    const CameraResponse a = calibrate_response(bracket);
    const CameraResponse b = calibrate_response(bracket);
    EXPECT_EQ(a.channels, b.channels);
    EXPECT_EQ(merge_bracket(bracket, a).radiance, merge_bracket(bracket, b).radiance);
}

TEST(Hdr, ResponseCsvRoundTripsBitForBit) {
    rfd::testing::TempDir dir;
    const CameraResponse g = calibrate_response(bracket_of(radiance_ramp(32, 32, 3), kTimes));
    write_response(dir / "response.csv", g);
    const CameraResponse back = read_response(dir / "response.csv");
    EXPECT_EQ(back.channels, g.channels);
    write_response(dir / "again.csv", back);
    std::ifstream a(dir / "response.csv"), b(dir / "again.csv");
    const std::string text_a((std::istreambuf_iterator<char>(a)), {}), text_b((std::istreambuf_iterator<char>(b)), {});
    EXPECT_EQ(text_a, text_b);
}

// A valid response file with one line replaced (or removed when `replacement` is empty).
std::filesystem::path response_with(const rfd::testing::TempDir& dir, int code, const std::string& replacement) {
    const std::filesystem::path path = dir / ("response_" + std::to_string(code) + ".csv");
    write_response(path, true_response());
    std::ifstream in(path);
    std::string text, line;
    while (std::getline(in, line)) {
        if (line.rfind(std::to_string(code) + ",", 0) == 0 || (code < 0 && line.rfind("code,", 0) == 0)) {
            if (!replacement.empty()) text += replacement + "\n";
            continue;
        }
        text += line + "\n";
    }
    in.close();
    std::ofstream(path) << text;
    return path;
}

void expect_input_error(const std::function<void()>& call, const std::string& fragment) {
    try {
        call();
        ADD_FAILURE() << "no error; expected one mentioning '" << fragment << "'";
    } catch (const InputError& error) {
        EXPECT_NE(std::string(error.what()).find(fragment), std::string::npos) << error.what();
    }
}

TEST(Hdr, MalformedResponseFilesNameFileLineAndProblem) {
    rfd::testing::TempDir dir;
    // Line numbers: two comment lines, the header on line 3, code z on line z + 4.
    expect_input_error([&] { read_response(response_with(dir, -1, "code,r,g,b")); }, ":3: expected the header");
    expect_input_error([&] { read_response(response_with(dir, 17, "")); }, ":21: expected code 17");
    expect_input_error([&] { read_response(response_with(dir, 40, "40,0.1,-0.5,0.2")); }, ":44: green: expected a finite, non-negative");
    expect_input_error([&] { read_response(response_with(dir, 41, "41,nan,0.5,0.2")); }, ":45: red: expected a finite");
    expect_input_error([&] { read_response(response_with(dir, 42, "42,0.1,0.5")); }, ":46: expected 'code,red,green,blue'");
    expect_input_error([&] { read_response(response_with(dir, 43, "43,0.1,0.5,0.2,9")); }, ":47: expected 'code,red,green,blue'");
    expect_input_error([&] { read_response(response_with(dir, 44, "44,0.1,0.5x,0.2")); }, ":48: expected 'code,red,green,blue'");
    expect_input_error([&] { read_response(response_with(dir, 255, "")); }, "the file ends after 255");
    expect_input_error([&] { read_response(response_with(dir, 255, "255,1,1,1\n256,1,1,1")); }, "more than 256 codes");
    CameraResponse zero = true_response();
    zero.channels[2].fill(0.0f);
    write_response(dir / "zero.csv", zero);
    expect_input_error([&] { read_response(dir / "zero.csv"); }, "blue: the response is zero for every code");
    EXPECT_THROW(read_response(dir / "missing.csv"), IoError);
}

TEST(Hdr, BadBracketsAreInputErrorsNamingTheImage) {
    const Image e = radiance_ramp(16, 8, 3);
    const CameraResponse g = true_response();
    expect_input_error([&] { merge_bracket(bracket_of(e, {1.0}), g); }, "at least 2 exposures, got 1");
    expect_input_error([&] { merge_bracket(bracket_of(e, {1.0, 0.0}), g); }, "exposure_1.png: exposure time must be a positive");
    expect_input_error([&] { merge_bracket(bracket_of(e, {1.0, -2.0}), g); }, "must be a positive");
    expect_input_error([&] { merge_bracket(bracket_of(e, {1.0, NAN}), g); }, "must be a positive");
    expect_input_error([&] { calibrate_response(bracket_of(e, {0.5, 1.0, 0.5})); }, "exposure_2.png: exposure time 0.5");
    Bracket mixed = bracket_of(e, {0.5, 1.0});
    mixed.images[1] = expose(radiance_ramp(16, 9, 3), 1.0);
    expect_input_error([&] { merge_bracket(mixed, g); }, "exposure_1.png: image is 16x9 with 3 channel(s), but exposure_0.png is 16x8");
    mixed.images[1] = expose(radiance_ramp(16, 8, 1), 1.0);
    expect_input_error([&] { merge_bracket(mixed, g); }, "with 1 channel(s)");
    // Everything saturated: nothing to measure, in calibration and merging alike.
    const Image bright(16, 8, 3, 1.0e3f);
    expect_input_error([&] { merge_bracket(bracket_of(bright, {0.5, 1.0}), g); }, "is 0 or 255 in every exposure");
    expect_input_error([&] { calibrate_response(bracket_of(bright, {0.5, 1.0})); }, "is 0 or 255 in every exposure");
}

TEST(Hdr, CalibrationFailsWithoutMidGrey) {
    // A bracket that never reaches code 128 cannot be normalised: a clear error, not NaN.
    const Image dim(16, 16, 3, 1.0e-3f);
    expect_input_error([&] { calibrate_response(bracket_of(dim, {1.0, 2.0})); },
                       "code 128 (the normalisation point) never occurs in the red channel");
}

void write_codes(const std::filesystem::path& path, const CodeImage& image, double exposure_seconds) {
    ImageFileSpec spec{.width = image.width, .height = image.height, .channels = image.channels,
                       .type = SampleType::UInt8};
    if (exposure_seconds > 0.0) spec.exposure_seconds = exposure_seconds;
    std::vector<std::uint8_t> interleaved;
    for (int y = 0; y < image.height; ++y)
        for (int x = 0; x < image.width; ++x)
            for (int c = 0; c < image.channels; ++c) interleaved.push_back(image.at(x, y, c));
    ImageFileWriter out(path, spec);
    out.write_rows(0, image.height, SampleType::UInt8, interleaved.data());
    out.finish();
}

TEST(Hdr, FilesGiveCodesAndExifTimes) {
    rfd::testing::TempDir dir;
    const Image e = radiance_ramp(24, 16, 3);
    const std::vector<double> times = {1.0 / 8, 1.0 / 2, 2.0};
    std::vector<std::filesystem::path> files;
    for (std::size_t i = 0; i < times.size(); ++i) {
        files.push_back(dir / ("exposure_" + std::to_string(i) + ".tif"));
        write_codes(files.back(), expose(e, times[i]), times[i]);
    }
    ASSERT_TRUE(read_exposure_time(files[1]).has_value());
    EXPECT_NEAR(*read_exposure_time(files[1]), 0.5, 1e-7);
    const Bracket from_exif = read_bracket(files);
    for (std::size_t i = 0; i < times.size(); ++i) {
        EXPECT_NEAR(from_exif.exposure_seconds[i], times[i], 1e-7 * times[i]);
        EXPECT_EQ(from_exif.images[i].codes, expose(e, times[i]).codes) << "codes of " << files[i];
    }
    // Times on the command line win over EXIF; the count must match.
    EXPECT_EQ(read_bracket(files, {1.0, 2.0, 3.0}).exposure_seconds, (std::vector<double>{1.0, 2.0, 3.0}));
    expect_input_error([&] { read_bracket(files, {1.0, 2.0}); }, "3 images but 2 exposure times");

    // No EXIF time: named.
    write_codes(dir / "plain.png", expose(e, 1.0), 0.0);
    EXPECT_FALSE(read_exposure_time(dir / "plain.png").has_value());
    expect_input_error([&] { read_bracket({files[0], dir / "plain.png"}); }, "plain.png: no EXIF ExposureTime");
    // Not 8-bit: HDR assembly from float data makes no sense.
    write_image(dir / "float.exr", e);
    expect_input_error([&] { read_code_image(dir / "float.exr"); }, "float.exr: expected an 8-bit camera image");
    EXPECT_THROW(read_code_image(dir / "missing.png"), IoError);
}

}  // namespace
}  // namespace rfd::relight
