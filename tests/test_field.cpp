// Images and reflectance fields on disk: round trips, colour decoding, and a distinct
// message for every way a light file can be malformed.

#include <algorithm>
#include <cmath>
#include <fstream>
#include <random>
#include <utility>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "core/error.hpp"
#include "core/image_io.hpp"
#include "core/sphere.hpp"
#include "core/units.hpp"
#include "relight/field.hpp"
#include "tests/support/error_of.hpp"
#include "tests/support/temp_dir.hpp"

#include "core/image_file.hpp"

namespace rfd::relight {
namespace {

using ::testing::HasSubstr;
using rfd::testing::TempDir;

Image random_image(int w, int h, int c, unsigned seed, float scale = 4.0f) {
    std::mt19937 random(seed);
    std::uniform_real_distribution<float> value(0.0f, scale);
    Image image(w, h, c);
    for (float& v : image.samples()) v = value(random);
    return image;
}

using rfd::testing::error_of;

void write(const std::filesystem::path& path, const std::string& text) {
    std::ofstream(path) << text;
}

TEST(ImageIo, ExrRoundTripIsBitExact) {
    TempDir dir;
    const Image image = random_image(37, 23, 3, 1);
    write_image(dir / "a.exr", image);
    EXPECT_EQ(read_image(dir / "a.exr"), image);
}

TEST(ImageIo, RowsReadAsStoredConvertExactlyAcrossTheReadersBands) {
    // Half-float rows read as floats go through the reader's own buffer, 8 MB of stored rows
    // at a time (932 rows of this width); float rows go straight into the caller's. Reads
    // within a band, across its edge and of the whole image give every value back. Whole
    // numbers below 2048 are exact in half floats.
    TempDir dir;
    const int width = 1500, height = 1000, channels = 3;
    const auto value = [](int x, int y, int c) { return static_cast<float>((7 * x + 13 * y + 5 * c) % 2048); };
    std::vector<float> written(static_cast<std::size_t>(width * height * channels));
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x)
            for (int c = 0; c < channels; ++c)
                written[static_cast<std::size_t>((y * width + x) * channels + c)] = value(x, y, c);
    for (const SampleType type : {SampleType::Half, SampleType::Float32}) {
        ImageFileSpec spec;
        spec.width = width;
        spec.height = height;
        spec.channels = channels;
        spec.type = type;
        const auto path = dir / (type == SampleType::Half ? "half.exr" : "float.exr");
        ImageFileWriter writer(path, spec);
        writer.write_rows(0, height, written);
        writer.finish();

        ImageFileReader reader(path);
        ASSERT_EQ(reader.spec().type, type);
        const std::size_t row = static_cast<std::size_t>(width * channels);
        for (const auto& [y0, y1] : {std::pair{0, 1}, std::pair{100, 164}, std::pair{930, 935}, std::pair{0, height}}) {
            std::vector<float> read(row * static_cast<std::size_t>(y1 - y0), -1.0f);
            reader.read_rows(y0, y1, read);
            EXPECT_TRUE(std::equal(read.begin(), read.end(), written.begin() + static_cast<std::ptrdiff_t>(row * y0)))
                << path.filename() << ", rows " << y0 << "-" << y1;
        }
    }
}

TEST(ImageIo, PngIsSrgbEncodedAndDecodedBack) {
    TempDir dir;
    Image image(4, 1, 1);
    image.at(0, 0, 0) = 0.0f;
    image.at(1, 0, 0) = 0.2140411f;  // sRGB 0.5 within a code value
    image.at(2, 0, 0) = 1.0f;
    image.at(3, 0, 0) = 7.0f;  // clamps
    write_image(dir / "a.png", image);
    const Image back = read_image(dir / "a.png");
    EXPECT_FLOAT_EQ(back.at(0, 0, 0), 0.0f);
    EXPECT_NEAR(back.at(1, 0, 0), 0.2140411f, 0.003f);  // 8-bit quantisation near mid-grey
    EXPECT_FLOAT_EQ(back.at(2, 0, 0), 1.0f);
    EXPECT_FLOAT_EQ(back.at(3, 0, 0), 1.0f);
}

TEST(ImageIo, SrgbCurveIsContinuousAndInvertible) {
    for (float v = 0.0f; v <= 1.0f; v += 0.001f) EXPECT_NEAR(srgb_to_linear(linear_to_srgb(v)), v, 1e-6f);
    // Where the linear segment meets the power curve (IEC 61966-2-1): both pieces agree.
    EXPECT_NEAR(srgb_to_linear(0.04045f), 0.04045 / 12.92, 1e-7);
    EXPECT_NEAR(srgb_to_linear(0.04045f), std::pow((0.04045 + 0.055) / 1.055, 2.4), 1e-6);
    EXPECT_NEAR(linear_to_srgb(0.0031308f), 0.04045, 1e-5);
}

TEST(ImageIo, RefusesToWriteNaN) {
    TempDir dir;
    Image image(2, 2, 1, 0.5f);
    image.at(1, 1, 0) = std::numeric_limits<float>::quiet_NaN();
    EXPECT_THAT(error_of([&] { write_image(dir / "a.exr", image); }),
                HasSubstr("pixel (1, 1) channel 0: not a finite number"));
    EXPECT_TRUE(std::filesystem::is_empty(dir.path()));
}

ReflectanceField small_field(bool kernels) {
    ReflectanceField field;
    for (int i = 0; i < 5; ++i) {
        field.directions.push_back(direction_from_angles(0.3 * i, 1.1 * i));
        field.images.push_back(random_image(9, 7, 3, 10 + i));
        if (kernels) field.kernel_radii.push_back(0.01 * i);
    }
    return field;
}

TEST(Field, WriteThenReadIsIdentical) {
    for (const bool kernels : {false, true}) {
        TempDir dir;
        const ReflectanceField field = small_field(kernels);
        write_field(dir.path(), field, "f");
        const ReflectanceField back = read_field(dir.path());
        ASSERT_EQ(back.size(), field.size());
        for (std::size_t i = 0; i < field.size(); ++i) {
            EXPECT_EQ(back.images[i], field.images[i]);
            EXPECT_EQ(back.directions[i], field.directions[i]);  // bit-exact with %.17g
        }
        if (kernels) {
            ASSERT_EQ(back.kernel_radii.size(), field.size());
            for (std::size_t i = 0; i < field.size(); ++i)
                EXPECT_NEAR(back.kernel_radii[i], field.kernel_radii[i], 1e-15);
        } else {
            EXPECT_TRUE(back.kernel_radii.empty());
        }
    }
}

TEST(Field, AnRtiBuilderCaptureReadsAsItIs) {
    // CRLF line ends, absolute Windows paths of the capturing machine, a name with spaces,
    // the JPEGs in jpeg-exports/ (tests/data/rtibuilder).
    const std::filesystem::path folder = std::filesystem::path(RFD_SOURCE_DIR) / "tests/data/rtibuilder";
    const std::vector<LightEntry> entries = read_light_file(folder / "Bottle.lp");
    ASSERT_EQ(entries.size(), 3u);
    EXPECT_EQ(entries[2].file, "C:\\Users\\Maker\\My Captures\\Bottle\\jpeg-exports\\Bottle 003.jpg");
    EXPECT_EQ(entries[0].path, folder / "jpeg-exports" / "Bottle_001.jpg");
    EXPECT_EQ(entries[2].path, folder / "jpeg-exports" / "Bottle 003.jpg");
    const ReflectanceField field = read_field(folder);
    ASSERT_EQ(field.size(), 3u);
    EXPECT_LT((field.directions[1] - Eigen::Vector3d(0.5, 0.0, 0.866025).normalized()).norm(), 1e-12);
    EXPECT_EQ(field.width(), 4);
    EXPECT_EQ(field.height(), 3);
    // Each image is the one its line names (they differ in red: 0.1, 0.2, 0.3, sRGB-coded).
    EXPECT_LT(field.images[0].at(0, 0, 0), field.images[1].at(0, 0, 0));
    EXPECT_LT(field.images[1].at(0, 0, 0), field.images[2].at(0, 0, 0));
    // A Windows name whose file is nowhere near: the reader names the place it looked.
    const TempDir dir;
    {
        std::ofstream lp(dir / "gone.lp");
        lp << "1\r\nC:\\capture\\jpeg-exports\\gone.jpg 0 0 1\r\n";
    }
    EXPECT_THAT(error_of([&] { read_field(dir / "gone.lp"); }), HasSubstr("gone.lp:2: image 'C:\\capture\\jpeg-exports\\gone.jpg'"));
    // Names with spaces do not swallow numbers: rfd's own five-value lines read as before.
    {
        std::ofstream lp(dir / "five.lp");
        lp << "1\nname with spaces.exr 0 0 1 4\n";
    }
    const std::vector<LightEntry> five = read_light_file(dir / "five.lp");
    EXPECT_EQ(five[0].file, "name with spaces.exr");
    EXPECT_NEAR(five[0].kernel_radius, degrees_to_radians(4.0), 1e-15);
}

// Tiles: image k at column k % columns, row k / columns, `gap` pixels of fill between and
// around; a last row may be short.
TEST(Image, TiledPlacesEachImageInItsCellWithGaps) {
    std::vector<Image> images;
    for (int k = 0; k < 5; ++k) images.emplace_back(2, 3, 1, static_cast<float>(k + 1));
    const Image sheet = tiled(images, 3, 1, -1.0f);
    ASSERT_EQ(sheet.width(), 1 + 3 * (2 + 1));
    ASSERT_EQ(sheet.height(), 1 + 2 * (3 + 1));
    for (int k = 0; k < 5; ++k) {
        const int x0 = 1 + k % 3 * 3, y0 = 1 + k / 3 * 4;
        EXPECT_EQ(sheet.at(x0, y0, 0), k + 1);
        EXPECT_EQ(sheet.at(x0 + 1, y0 + 2, 0), k + 1);
        EXPECT_EQ(sheet.at(x0 + 2, y0, 0), -1.0f);  // the gap after it
    }
    EXPECT_EQ(sheet.at(0, 0, 0), -1.0f);
    EXPECT_EQ(sheet.at(7, 5, 0), -1.0f);  // the sixth cell, empty
    EXPECT_EQ(tiled({images[0]}, 4).width(), 2);  // one image, no gap: itself
}

TEST(ImageWindow, CropsThenAveragesAndRefusesWhatLiesOutside) {
    Image image(6, 4, 2);
    for (int c = 0; c < 2; ++c)
        for (int y = 0; y < 4; ++y)
            for (int x = 0; x < 6; ++x) image.at(x, y, c) = static_cast<float>(10 * c + x + 6 * y);
    const ImageWindow region = parse_region("1,1,4,2", "--region");
    const Image cropped = apply_window(image, region, "a.exr");
    ASSERT_EQ(cropped.width(), 4);
    ASSERT_EQ(cropped.height(), 2);
    for (int c = 0; c < 2; ++c)
        for (int y = 0; y < 2; ++y)
            for (int x = 0; x < 4; ++x) EXPECT_EQ(cropped.at(x, y, c), image.at(x + 1, y + 1, c));
    // Halving averages each 2 x 2 block of the region.
    ImageWindow halved = region;
    halved.scale = 0.5;
    const Image small = apply_window(image, halved, "a.exr");
    ASSERT_EQ(small.width(), 2);
    ASSERT_EQ(small.height(), 1);
    for (int c = 0; c < 2; ++c)
        for (int x = 0; x < 2; ++x) {
            const float mean = 0.25f * (image.at(1 + 2 * x, 1, c) + image.at(2 + 2 * x, 1, c) + image.at(1 + 2 * x, 2, c) +
                                        image.at(2 + 2 * x, 2, c));
            EXPECT_NEAR(small.at(x, 0, c), mean, 1e-4) << x << " " << c;
        }
    EXPECT_EQ(apply_window(image, ImageWindow{}, "a.exr"), image);
    EXPECT_THAT(error_of([&] { apply_window(image, parse_region("3,0,4,4", "--region"), "a.exr"); }),
                HasSubstr("a.exr: --region 3,0,4,4 reaches outside the 6 x 4 image"));
    ImageWindow tiny;
    tiny.scale = 0.01;
    EXPECT_THAT(error_of([&] { apply_window(image, tiny, "a.exr"); }), HasSubstr("--scale 0.01 makes the 6 x 4 image 0 x 0"));
    for (const char* bad : {"1,1,4", "1,1,0,2", "-1,0,2,2", "1,1,4,2,5", "a,b,c,d"})
        EXPECT_THAT(error_of([&] { parse_region(bad, "--region"); }), HasSubstr("--region: expected X,Y,W,H")) << bad;
}

TEST(Field, WritingTwiceGivesIdenticalBytes) {
    TempDir dir;
    const ReflectanceField field = small_field(false);
    write_field(dir / "a", field);
    write_field(dir / "b", field);
    for (const auto& entry : std::filesystem::directory_iterator(dir / "a")) {
        std::ifstream a(entry.path(), std::ios::binary), b(dir / "b" / entry.path().filename(), std::ios::binary);
        const std::string bytes_a((std::istreambuf_iterator<char>(a)), {}), bytes_b((std::istreambuf_iterator<char>(b)), {});
        EXPECT_EQ(bytes_a, bytes_b) << entry.path();
    }
}

// A rewrite that stops half-way (here: the second image cannot be written) must not leave
// the earlier light file listing a mix of new and old images.
TEST(Field, AnInterruptedRewriteLeavesNoReadableField) {
    TempDir dir;
    write_field(dir.path(), small_field(false));
    ReflectanceField second = small_field(false);
    for (Image& image : second.images) image.at(0, 0, 0) += 1.0f;
    second.images[1].at(0, 0, 0) = std::nanf("");
    EXPECT_THROW(write_field(dir.path(), second), InputError);
    EXPECT_THAT(error_of([&] { read_field(dir.path()); }), HasSubstr("folder holds no .lp light file"));
}

TEST(Field, TheStreamingWriterWritesTheSameFilesAsWriteField) {
    TempDir dir;
    const ReflectanceField field = small_field(true);
    write_field(dir / "whole", field);
    FieldWriter writer(dir / "streamed");
    for (std::size_t i = 0; i < field.size(); ++i)
        EXPECT_EQ(writer.add(field.images[i], field.directions[i], field.kernel_radius(i)),
                  "field_000" + std::to_string(i) + ".exr");
    EXPECT_FALSE(std::filesystem::exists(dir / "streamed" / "field.lp"));  // not before finish()
    EXPECT_EQ(writer.finish(), dir / "streamed" / "field.lp");
    for (const auto& entry : std::filesystem::directory_iterator(dir / "whole")) {
        std::ifstream a(entry.path(), std::ios::binary), b(dir / "streamed" / entry.path().filename(), std::ios::binary);
        const std::string bytes_a((std::istreambuf_iterator<char>(a)), {}), bytes_b((std::istreambuf_iterator<char>(b)), {});
        EXPECT_EQ(bytes_a, bytes_b) << entry.path();
    }
}

// Each malformed light file gives its own message, naming the file and the line.
class MalformedLightFile : public ::testing::Test {
protected:
    void SetUp() override { write_image(dir / "a.exr", random_image(4, 3, 3, 1)); }
    std::string read_error(const std::string& lp_text) {
        write(dir / "f.lp", lp_text);
        return error_of([&] { read_field(dir / "f.lp"); });
    }
    TempDir dir;
};

TEST_F(MalformedLightFile, CountMismatch) {
    EXPECT_THAT(read_error("2\na.exr 0 0 1\n"), HasSubstr("f.lp:1: declares 2 images but lists 1"));
    // More lines than declared: the first ones are read, as RTIBuilder and relight read them,
    // whatever follows.
    write(dir / "f.lp", "2\na.exr 0 0 1\na.exr 0 1 1\nstray line\n");
    const std::vector<LightEntry> entries = read_light_file(dir / "f.lp");
    ASSERT_EQ(entries.size(), 2u);
    EXPECT_EQ(entries[1].line, 3);
    EXPECT_NEAR(entries[1].direction.y(), std::sqrt(0.5), 1e-15);
}
TEST_F(MalformedLightFile, BadCount) {
    EXPECT_THAT(read_error("two\na.exr 0 0 1\n"), HasSubstr("f.lp:1: expected the image count"));
}
TEST_F(MalformedLightFile, MissingImage) {
    EXPECT_THAT(read_error("1\nnope.exr 0 0 1\n"), HasSubstr("f.lp:2: image 'nope.exr'"));
    EXPECT_THAT(read_error("1\nnope.exr 0 0 1\n"), HasSubstr("no such image file"));
}
TEST_F(MalformedLightFile, ImageDeclaringATrillionPixels) {
    // A 69-byte PNG whose header declares 1 000 000 x 1 000 000 pixels: an input error naming
    // the .lp line and the size, not std::bad_alloc.
    std::filesystem::copy_file(std::filesystem::path(RFD_SOURCE_DIR) / "tests/data/huge_header.png", dir / "huge.png");
    const std::string message = read_error("1\nhuge.png 0 0 1\n");
    EXPECT_THAT(message, HasSubstr("f.lp:2: image 'huge.png'"));
    EXPECT_THAT(message, HasSubstr("declares 1000000 x 1000000 pixels of 3 channel(s)"));
}
TEST_F(MalformedLightFile, ZeroLengthDirection) {
    EXPECT_THAT(read_error("1\na.exr 0 0 0\n"), HasSubstr("f.lp:2: light direction (0.000000, 0.000000, 0.000000) has zero length"));
}
TEST_F(MalformedLightFile, MissingCoordinate) {
    EXPECT_THAT(read_error("1\na.exr 0 1\n"), HasSubstr("f.lp:2: expected 'filename x y z [kernel_degrees]'"));
}
TEST_F(MalformedLightFile, DifferentSizes) {
    write_image(dir / "b.exr", random_image(5, 3, 3, 2));
    EXPECT_THAT(read_error("2\na.exr 0 0 1\n# comment\nb.exr 1 0 1\n"),
                HasSubstr("f.lp:4: image 'b.exr' is 5 x 3 pixels, 3 channels, the field's first image 'a.exr' is 4 x 3 pixels, 3 channels"));
}
TEST_F(MalformedLightFile, NaNPixels) {
    // OpenImageIO writes NaN when asked to; rfd refuses to read it back.
    Image bad = random_image(4, 3, 3, 3);
    bad.at(2, 1, 1) = std::numeric_limits<float>::quiet_NaN();
    std::vector<float> interleaved;
    {
        ImageFileWriter out(dir / "nan.exr", {.width = 4, .height = 3, .channels = 3});
        for (int y = 0; y < 3; ++y)
            for (int x = 0; x < 4; ++x)
                for (int c = 0; c < 3; ++c) interleaved.push_back(bad.at(x, y, c));
        out.write_rows(0, 3, interleaved);
        out.finish();
    }
    EXPECT_THAT(read_error("1\nnan.exr 0 0 1\n"),
                HasSubstr("f.lp:2: image 'nan.exr': " + (dir / "nan.exr").string() +
                          ": pixel (2, 1) channel 1 is not a finite number"));
}
TEST_F(MalformedLightFile, ExtraValueAndBadKernel) {
    EXPECT_THAT(read_error("1\na.exr 0 0 1 2 3\n"), HasSubstr("f.lp:2: unexpected extra value '3'"));
    EXPECT_THAT(read_error("1\na.exr 0 0 1 200\n"), HasSubstr("f.lp:2: kernel radius must be in [0, 180)"));
    EXPECT_THAT(read_error("1\na.exr 0 0 1 wide\n"), HasSubstr("f.lp:2: the fifth value"));
}
TEST_F(MalformedLightFile, EmptyFile) {
    EXPECT_THAT(read_error("# nothing\n"), HasSubstr("light file is empty"));
}

TEST(Sphere, AnglesRoundTrip) {
    for (double theta = 0.05; theta < 3.1; theta += 0.3)
        for (double phi = -3.0; phi < 3.1; phi += 0.5) {
            const SphericalAngles a = angles_of(direction_from_angles(theta, phi));
            EXPECT_NEAR(a.theta, theta, 1e-12);
            EXPECT_NEAR(a.phi, phi, 1e-12);
        }
    EXPECT_NEAR(angle_between(Eigen::Vector3d::UnitX(), Eigen::Vector3d(1, 1e-9, 0).normalized()), 1e-9, 1e-20);
}

}  // namespace
}  // namespace rfd::relight
