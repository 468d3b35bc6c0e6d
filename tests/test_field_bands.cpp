// Fields read and relit a band of rows at a time (relight/field.hpp FieldReader,
// relight/render.hpp relight_to_files, core/resample.hpp): the same samples as whole images
// whatever the bands, the scale resampled as OpenCV resamples it, and the sRGB decoding
// table the same as the formula.

#include <algorithm>
#include <cmath>
#include <fstream>
#include <random>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "core/error.hpp"
#include "core/image_file.hpp"
#include "core/image_io.hpp"
#include "core/resample.hpp"
#include "core/sphere.hpp"
#include "relight/evaluate.hpp"
#include "relight/field.hpp"
#include "relight/interpolation.hpp"
#include "relight/render.hpp"
#include "relight/vision.hpp"
#include "tests/support/error_of.hpp"
#include "tests/support/temp_dir.hpp"

namespace rfd::relight {
namespace {

using ::testing::HasSubstr;
using rfd::testing::error_of;
using rfd::testing::TempDir;

Image noise_image(int w, int h, int c, unsigned seed) {
    std::mt19937 random(seed);
    std::uniform_real_distribution<float> value(0.0f, 1.0f);
    Image image(w, h, c);
    for (float& v : image.samples()) v = value(random);
    return image;
}

// A field of `count` images of w x h on disk, in `extension`'s encoding, lit from a ring of
// directions around the zenith.
std::filesystem::path write_noise_field(const TempDir& dir, const std::string& name, int count, int w, int h,
                                        const std::string& extension) {
    FieldWriter out(dir / name, "field", extension);
    for (int i = 0; i < count; ++i) {
        const double theta = i == 0 ? 0.0 : 0.7, phi = 2.0 * M_PI * i / std::max(1, count - 1);
        out.add(noise_image(w, h, 3, static_cast<unsigned>(10 + i)), direction_from_angles(theta, phi));
    }
    out.finish();
    return dir / name;
}

TEST(ImageBands, SrgbTableIsTheFormulaAtEveryCode) {
    // 8- and 16-bit files decode through a table; every code's entry is the formula's value.
    TempDir dir;
    Image ramp(256, 1, 1);
    for (int x = 0; x < 256; ++x) ramp.at(x, 0, 0) = srgb_to_linear(static_cast<float>(x) / 255.0f);
    write_image(dir / "ramp.png", ramp);
    const Image read = read_image(dir / "ramp.png");
    int checked = 0;
    for (int x = 0; x < 256; ++x, ++checked)
        EXPECT_EQ(read.at(x, 0, 0), srgb_to_linear(static_cast<float>(x) / 255.0f)) << "code " << x;
    EXPECT_EQ(checked, 256);
    // 16 bits: a TIFF ramp of every 257th code and its neighbours.
    Image wide(3 * 256, 1, 1);
    for (int x = 0; x < 256; ++x)
        for (int d = 0; d < 3; ++d) {
            const int code = std::clamp(257 * x + d - 1, 0, 65535);
            wide.at(3 * x + d, 0, 0) = srgb_to_linear(static_cast<float>(code) / 65535.0f);
        }
    write_image(dir / "ramp.tif", wide);
    const Image wide_read = read_image(dir / "ramp.tif");
    for (int x = 0; x < wide.width(); ++x) EXPECT_NEAR(wide_read.at(x, 0, 0), wide.at(x, 0, 0), 1e-6f) << x;
}

TEST(ImageBands, EightBitCodesFromTheTableAreTheEncodersCodes) {
    // The codes OpenImageIO makes of encoded floats (how 8-bit files were written before the
    // table) against the table's, at 2^20 linear values over [0, 1], out of range, and one
    // float either side of each code's threshold.
    std::vector<float> linear{-1.0f, -0.0f, 1.0f, 1.5f, 1e30f};
    for (int i = 0; i <= (1 << 20); ++i) linear.push_back(static_cast<float>(i) / (1 << 20));
    for (int code = 1; code < 256; ++code) {
        float low = 0.0f, high = 1.0f;  // the threshold, by bisection on the table's encoder
        for (int step = 0; step < 60; ++step) {
            const float middle = 0.5f * (low + high);
            (encode_srgb8(middle) >= code ? high : low) = middle;
        }
        linear.insert(linear.end(), {std::nextafter(high, 0.0f), high, std::nextafter(high, 2.0f)});
    }
    TempDir dir;
    const int width = 1024, height = static_cast<int>(linear.size() / width + 1);
    std::vector<float> encoded(static_cast<std::size_t>(width * height), 0.0f);
    for (std::size_t i = 0; i < linear.size(); ++i) encoded[i] = linear_to_srgb(std::clamp(linear[i], 0.0f, 1.0f));
    ImageFileWriter old_way(dir / "old.png", {.width = width, .height = height, .channels = 1, .type = SampleType::UInt8});
    old_way.write_rows(0, height, encoded);
    old_way.finish();
    std::vector<std::uint8_t> codes(encoded.size());
    ImageFileReader(dir / "old.png").read_rows(0, height, codes);
    std::size_t checked = 0;
    for (std::size_t i = 0; i < linear.size(); ++i, ++checked)
        ASSERT_EQ(encode_srgb8(linear[i]), codes[i]) << "linear " << linear[i];
    EXPECT_EQ(checked, (std::size_t{1} << 20) + 6 + 3 * 255);
}

TEST(ImageBands, BandsReadAndWrittenAreTheWholeImage) {
    TempDir dir;
    const Image image = noise_image(53, 41, 3, 7);
    for (const char* name : {"a.exr", "a.png", "a.tif"}) {
        write_image(dir / name, image);
        const Image whole = read_image(dir / name);
        ImageBandReader reader(dir / name);
        ImageBandWriter writer(dir / (std::string("b_") + name), 53, 41, 3);
        int rows_checked = 0;
        for (int y0 = 0; y0 < 41; y0 += 9) {
            const int y1 = std::min(41, y0 + 9);
            const Image band = reader.read(y0, y1, 5, 50);
            ASSERT_EQ(band.width(), 45);
            for (int c = 0; c < 3; ++c)
                for (int y = y0; y < y1; ++y, rows_checked += c == 0)
                    for (int x = 5; x < 50; ++x) ASSERT_EQ(band.at(x - 5, y - y0, c), whole.at(x, y, c)) << name;
            writer.write(ImageBandReader(dir / name).read(y0, y1));
        }
        EXPECT_EQ(rows_checked, 41);
        writer.finish();
        std::ifstream a(dir / name, std::ios::binary), b(dir / (std::string("b_") + name), std::ios::binary);
        const std::string bytes_a((std::istreambuf_iterator<char>(a)), {}), bytes_b((std::istreambuf_iterator<char>(b)), {});
        EXPECT_EQ(bytes_a, bytes_b) << name << ": written in bands, the file is not the one written whole";
    }
}

TEST(Resample, WeightsAreOpenCvsAreaResampling) {
    // Shrinking by whole and fractional factors, and enlarging: the band resampler's output
    // against OpenCV's INTER_AREA resize of the whole image.
    const Image image = noise_image(97, 61, 1, 3);
    int sizes_checked = 0;
    for (const auto& [w, h] : std::vector<std::pair<int, int>>{{48, 30}, {33, 21}, {97, 61}, {20, 7}, {150, 90}}) {
        const AxisResampling columns(97, w), rows(61, h);
        for (int o = 0; o < w; ++o) {
            double sum = 0.0;
            for (int t = 0; t < columns.end(o) - columns.first(o); ++t) sum += columns.weights(o)[t];
            ASSERT_NEAR(sum, 1.0, 1e-6) << w << " " << o;
        }
        Image expected(w, h, 1);
        vision().resize({97, 61}, image.plane(0), {w, h}, expected.plane(0));
        const Image got = resample_band(image, 0, columns, rows, 0, h);
        float worst = 0.0f;
        for (std::size_t k = 0; k < expected.samples().size(); ++k)
            worst = std::max(worst, std::abs(got.samples()[k] - expected.samples()[k]));
        EXPECT_LT(worst, 2e-5f) << "97 x 61 to " << w << " x " << h;
        ++sizes_checked;
    }
    EXPECT_EQ(sizes_checked, 5);
}

TEST(FieldReader, AnyBandsGiveTheWholeFieldThroughAWindow) {
    TempDir dir;
    const auto field_path = write_noise_field(dir, "f", 5, 61, 47, ".png");
    for (const double scale : {1.0, 0.37, 0.5, 1.6}) {
        ImageWindow window = parse_region("3,2,55,43", "--region");
        window.scale = scale;
        const ReflectanceField whole = read_field(field_path, window);
        // The window applied to whole images, as before bands existed.
        for (std::size_t i = 0; i < whole.size(); ++i) {
            const Image direct = apply_window(read_image(dir / "f" / ("field_000" + std::to_string(i) + ".png")), window, "x");
            ASSERT_EQ(direct, whole.images[i]) << "scale " << scale << " image " << i;
        }
        for (const int rows : {1, 4, 7, 1000}) {
            FieldReader reader(field_path, window);
            ASSERT_EQ(reader.width(), whole.width());
            ASSERT_EQ(reader.height(), whole.height());
            // Every other band leaves image 2 out: its carried rows must still be right after.
            int band_index = 0;
            for (int y0 = 0; y0 < reader.height(); y0 += rows, ++band_index) {
                const int y1 = std::min(reader.height(), y0 + rows);
                std::vector<bool> wanted(5, true);
                wanted[2] = band_index % 2 == 0;
                const std::vector<Image> band = reader.read_band(y0, y1, wanted);
                for (std::size_t i = 0; i < 5; ++i) {
                    if (!wanted[i]) {
                        EXPECT_TRUE(band[i].empty());
                        continue;
                    }
                    for (int c = 0; c < 3; ++c)
                        for (int y = y0; y < y1; ++y)
                            for (int x = 0; x < reader.width(); ++x)
                                ASSERT_EQ(band[i].at(x, y - y0, c), whole.images[i].at(x, y, c))
                                    << "scale " << scale << ", bands of " << rows << " rows, image " << i << " (" << x
                                    << ", " << y << ")";
                }
            }
            // Reading from the top again starts the files again.
            EXPECT_EQ(reader.read_band(0, 1)[3].at(0, 0, 1), whole.images[3].at(0, 0, 1));
        }
    }
}

TEST(FieldReader, ABadImageIsNamedAtItsLineWhicheverThreadReadsIt) {
    TempDir dir;
    const auto field_path = write_noise_field(dir, "f", 4, 16, 12, ".exr");
    Image bad = noise_image(16, 12, 3, 1);
    bad.at(3, 9, 1) = std::nanf("");
    // Written raw: write_image refuses NaN.
    ImageFileWriter raw(dir / "f" / "field_0002.exr", {.width = 16, .height = 12, .channels = 3});
    std::vector<float> interleaved;
    for (int y = 0; y < 12; ++y)
        for (int x = 0; x < 16; ++x)
            for (int c = 0; c < 3; ++c) interleaved.push_back(bad.at(x, y, c));
    raw.write_rows(0, 12, interleaved);
    raw.finish();
    FieldReader reader(field_path);
    EXPECT_NO_THROW(reader.read_band(0, 5));
    EXPECT_THAT(error_of([&] { reader.read_band(5, 12); }),
                HasSubstr("field.lp:4: image 'field_0002.exr': " + (dir / "f" / "field_0002.exr").string() +
                          ": pixel (3, 9) channel 1 is not a finite number"));
}

TEST(RelightToFiles, SeveralLightsInOnePassAreWholeFieldRelightsBitForBit) {
    TempDir dir;
    const auto field_path = write_noise_field(dir, "f", 9, 40, 33, ".jpg");
    const ReflectanceField field = read_field(field_path);
    const SphericalInterpolator interpolator(field.directions);
    const std::vector<std::vector<Light>> lights{
        {DirectionalLight{direction_from_angles(0.3, 1.0)}},
        {DirectionalLight{direction_from_angles(0.6, 4.0), Eigen::Vector3d(1.0, 0.5, 0.25)}},
        {DiskLight{direction_from_angles(0.2, 2.0), 0.3}},
        {DirectionalLight{direction_from_angles(0.3, 1.0)}, DirectionalLight{direction_from_angles(0.5, 3.0)}}};
    std::vector<LightCoefficients> k;
    std::vector<std::filesystem::path> outs;
    for (std::size_t j = 0; j < lights.size(); ++j) {
        k.push_back(light_coefficients(interpolator, lights[j]));
        outs.push_back(dir / ("out_" + std::to_string(j) + ".exr"));
    }
    // A band budget of a few rows: many bands.
    FieldReader reader(field_path);
    relight_to_files(reader, k, outs, 9 * 40 * 3 * 4 * 5);
    for (std::size_t j = 0; j < lights.size(); ++j)
        EXPECT_EQ(read_image(outs[j]), relight(field, k[j])) << "light set " << j;
}

TEST(LeaveOneOut, EachImageScoredAsTheFieldWithoutItPredictsIt) {
    // Against evaluate() of the field without image j on image j alone, and the 8-bit PSNR
    // against the relit image written as a PNG and its codes read back; in bands of 4 rows.
    TempDir dir;
    const auto field_path = write_noise_field(dir, "f", 7, 24, 18, ".png");
    const ReflectanceField field = read_field(field_path);
    FieldReader reader(field_path);
    ASSERT_EQ(reader.sample_type(), SampleType::UInt8);
    const LeaveOneOut loo = leave_one_out(reader, Interpolation::Delaunay, 7 * 24 * 3 * 4 * 4);
    ASSERT_TRUE(loo.eight_bit());
    float peak = 0.0f;
    for (const Image& image : field.images) peak = std::max(peak, *std::max_element(image.samples().begin(), image.samples().end()));
    EXPECT_EQ(loo.peak, peak);
    std::size_t checked = 0;
    for (std::size_t j = 0; j < field.size(); ++j) {
        ReflectanceField others, held_out;
        for (std::size_t i = 0; i < field.size(); ++i) {
            ReflectanceField& into = i == j ? held_out : others;
            into.directions.push_back(field.directions[i]);
            into.images.push_back(field.images[i]);
        }
        const Evaluation e = evaluate(others, held_out);
        // evaluate() rounds each difference to float, leave_one_out() keeps it in double.
        EXPECT_NEAR(loo.squared_error[j], e.total_squared_error, 1e-7 * e.total_squared_error) << j;
        const Image relit = render(others, {DirectionalLight{field.directions[j]}});
        write_image(dir / "relit.png", relit);
        std::vector<std::uint8_t> predicted(relit.samples().size()), truth(relit.samples().size());
        ImageFileReader(dir / "relit.png").read_rows(0, relit.height(), predicted);
        ImageFileReader(dir / "f" / ("field_000" + std::to_string(j) + ".png")).read_rows(0, relit.height(), truth);
        double codes = 0.0;
        for (std::size_t k = 0; k < truth.size(); ++k) codes += std::pow(static_cast<double>(predicted[k]) - truth[k], 2.0);
        EXPECT_NEAR(loo.psnr_srgb8(j), psnr_from_mse(codes / static_cast<double>(truth.size()), 255.0), 1e-9) << j;
        ++checked;
    }
    EXPECT_EQ(checked, 7u);
    // A float field has no 8-bit PSNR; too few images is refused.
    const auto exr = write_noise_field(dir, "g", 4, 8, 6, ".exr");
    FieldReader floats(exr);
    EXPECT_FALSE(leave_one_out(floats).eight_bit());
    const auto three = write_noise_field(dir, "h", 3, 8, 6, ".exr");
    FieldReader few(three);
    EXPECT_THAT(error_of([&] { leave_one_out(few); }), HasSubstr("leave-one-out needs at least 4 images"));
}

}  // namespace
}  // namespace rfd::relight
