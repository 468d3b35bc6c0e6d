// Pattern rasters: dot geometry against the lattice, and the streaming writer's round trip
// (values, resolution tags, attributes), including refusing non-finite values without
// leaving a file behind.

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "optics/design.hpp"
#include "patterns/raster.hpp"
#include "tests/support/error_of.hpp"
#include "tests/support/temp_dir.hpp"
#include "tests/support/bundled.hpp"

namespace rfd::patterns {
namespace {

using ::testing::HasSubstr;
using rfd::testing::bundled_design;
using rfd::testing::error_of;
using rfd::testing::TempDir;


// A value every dot can be checked against: distinct per dot and channel, exact in half floats.
float expected_value(int x, int y, int c) { return static_cast<float>((x * 7 + y * 3 + c) % 64) / 64.0f; }

class Ramp final : public PatternSource {
public:
    // Row `bad_row`'s dot 5 has `bad_value` in its first channel.
    Ramp(PatternGeometry g, int channels, int bad_row = -1, float bad_value = std::nanf(""))
        : g_(g), channels_(channels), bad_row_(bad_row), bad_value_(bad_value) {}
    const PatternGeometry& geometry() const override { return g_; }
    int channels() const override { return channels_; }
    void render_row(int py, std::span<float> out) const override {
        for (int x = 0; x < g_.width; ++x)
            for (int c = 0; c < channels_; ++c)
                out[static_cast<std::size_t>(x * channels_ + c)] = expected_value(x, py, c);
        if (py == bad_row_) out[5 * static_cast<std::size_t>(channels_)] = bad_value_;
    }

private:
    PatternGeometry g_;
    int channels_;
    int bad_row_;
    float bad_value_;
};

PatternGeometry small_geometry() {
    PatternGeometry g;
    g.width = 37;
    g.height = 23;
    g.dpi_x = 2880;
    g.dpi_y = 1440;
    g.dot_x = 25.4 / 2880;
    g.dot_y = 25.4 / 1440;
    return g;
}

TEST(PatternGeometry, CoversTheArrayCentredOnIt) {
    const optics::Design design = bundled_design(1);
    const PatternGeometry g = pattern_geometry(design, Dpi{2880}, Dpi{1440});
    const auto& array = std::get<optics::LensletArrayPart>(*design.plane("A").part);
    const Eigen::Vector2d half = array.lattice.half_extent();
    // Whole dots covering the array, less than one dot more.
    EXPECT_GE(g.width * g.dot_x, 2 * half.x());
    EXPECT_LT(g.width * g.dot_x, 2 * half.x() + g.dot_x + 1e-9);
    EXPECT_GE(g.height * g.dot_y, 2 * half.y());
    EXPECT_LT(g.height * g.dot_y, 2 * half.y() + g.dot_y + 1e-9);
    // The raster's centre is the array's centre, and dot positions invert.
    const Eigen::Vector2d centre = g.dot_centre(0.5 * g.width - 0.5, 0.5 * g.height - 0.5);
    EXPECT_NEAR(centre.norm(), 0.0, 1e-12);
    const Eigen::Vector2d p = g.raster_position(g.dot_centre(1234, 567));
    EXPECT_NEAR(p.x(), 1234, 1e-9);
    EXPECT_NEAR(p.y(), 567, 1e-9);
    // y runs down the raster and up the lattice.
    EXPECT_GT(g.dot_centre(0, 0).y(), g.dot_centre(0, 1).y());
    const PatternGeometry with_margin = pattern_geometry(design, Dpi{2880}, Dpi{1440}, 5.0);
    EXPECT_NEAR((with_margin.width - g.width) * g.dot_x, 10.0, 2 * g.dot_x);
}

TEST(PatternGeometry, RejectsNonPositiveResolution) {
    const optics::Design design = bundled_design(2);
    EXPECT_THAT(error_of([&] { pattern_geometry(design, Dpi{0}, Dpi{1440}); }),
                HasSubstr("print resolution must be positive"));
}

TEST(WritePattern, RoundTripKeepsValuesResolutionAndAttributes) {
    TempDir dir;
    const Ramp ramp(small_geometry(), 3);
    for (const char* name : {"p.exr", "p.tif"}) {
        const auto path = dir / name;
        WriteOptions options;
        options.rows_per_strip = 5;  // strips that do not divide the height
        write_pattern(path, ramp, {{"design", "test design"}, {"white", "0.75"}}, options);
        PatternReader reader(path);
        const PatternFileInfo& info = reader.info();
        EXPECT_EQ(info.width, 37);
        EXPECT_EQ(info.height, 23);
        EXPECT_EQ(info.channels, 3);
        EXPECT_DOUBLE_EQ(info.dpi_x, 2880.0) << name;
        EXPECT_DOUBLE_EQ(info.dpi_y, 1440.0) << name;
        EXPECT_EQ(info.attributes.at("design"), "test design") << name;
        EXPECT_EQ(info.attributes.at("white"), "0.75") << name;
        std::vector<float> rows(static_cast<std::size_t>(37 * 3 * 23));
        reader.read_rows(0, 23, rows);
        // EXR half floats hold these exactly; 16-bit sRGB to within its quantisation.
        const double tolerance = std::string(name) == "p.exr" ? 0.0 : 2e-4;
        double worst = 0;
        for (int y = 0; y < 23; ++y)
            for (int x = 0; x < 37; ++x)
                for (int c = 0; c < 3; ++c)
                    worst = std::max(worst, std::abs(rows[static_cast<std::size_t>((y * 37 + x) * 3 + c)] -
                                                     static_cast<double>(expected_value(x, y, c))));
        EXPECT_LE(worst, tolerance) << name;
    }
}

TEST(WritePattern, NonFiniteValueLeavesNoFile) {
    TempDir dir;
    const Ramp ramp(small_geometry(), 3, /*bad_row=*/17);
    const auto path = dir / "bad.exr";
    EXPECT_THAT(error_of([&] { write_pattern(path, ramp, {}); }),
                HasSubstr("dot (5, 17): the pattern value is not a finite number"));
    EXPECT_TRUE(std::filesystem::is_empty(dir.path()));
}

TEST(WritePattern, ValuesBeyondHalfFloatAreRefusedOrWrittenAsFloat) {
    // Half floats end at 65504; from 65520 on a value rounds to infinity. A field in camera
    // units reaches that, and an infinite dot must not be written as if it were a pattern.
    TempDir dir;
    EXPECT_THAT(error_of([&] { write_pattern(dir / "big.exr", Ramp(small_geometry(), 3, 17, 70000.0f), {}); }),
                HasSubstr("dot (5, 17): the pattern value 70000 is beyond the largest half float, 65504"));
    EXPECT_TRUE(std::filesystem::is_empty(dir.path()));
    EXPECT_THAT(error_of([&] { write_pattern(dir / "big.exr", Ramp(small_geometry(), 3, 17, 65520.0f), {}); }),
                HasSubstr("value 65520 is beyond"));
    // The largest values that stay finite are written; as 32-bit floats, any finite value.
    const auto value_at_bad_dot = [](const std::filesystem::path& path) {
        PatternReader reader(path);
        std::vector<float> row(static_cast<std::size_t>(37 * 3));
        reader.read_rows(17, 18, row);
        return row[5 * 3];
    };
    write_pattern(dir / "largest.exr", Ramp(small_geometry(), 3, 17, 65519.0f), {});
    EXPECT_EQ(value_at_bad_dot(dir / "largest.exr"), 65504.0f);
    WriteOptions single;
    single.half_float = false;
    write_pattern(dir / "single.exr", Ramp(small_geometry(), 3, 17, 70000.0f), {}, single);
    EXPECT_EQ(value_at_bad_dot(dir / "single.exr"), 70000.0f);
}

TEST(WritePattern, UnwritableDirectoryIsAnIoError) {
    const Ramp ramp(small_geometry(), 1);
    EXPECT_THAT(error_of([&] { write_pattern("/proc/rfd-no/p.exr", ramp, {}); }),
                HasSubstr("does not exist"));
}

// A pattern whose header's rfd:white attribute declares `size` bytes (little-endian int32).
std::filesystem::path pattern_with_attribute_size(const TempDir& dir, std::uint32_t size) {
    const auto path = dir / "p.exr";
    write_pattern(path, Ramp(small_geometry(), 3), {{"white", "0.75"}});
    std::string bytes;
    {
        std::ifstream in(path, std::ios::binary);
        bytes.assign(std::istreambuf_iterator<char>(in), {});
    }
    const std::string attribute("rfd:white\0string\0", 17);
    const std::size_t at = bytes.find(attribute);
    EXPECT_NE(at, std::string::npos);
    for (std::size_t b = 0; b < 4; ++b) bytes[at + attribute.size() + b] = static_cast<char>((size >> (8 * b)) & 0xff);
    std::ofstream(path, std::ios::binary) << bytes;
    return path;
}

TEST(ReadPattern, AttributeLargerThanTheFileIsAnInputError) {
    // Found by fuzz/fuzz_pattern.cpp: OpenEXR allocated the 1.6 GB a damaged attribute size
    // declared (1.6 s under ASan) before noticing the file's end.
    TempDir dir;
    const auto path = pattern_with_attribute_size(dir, 1664102458u);
    try {
        read_pattern_info(path);
        ADD_FAILURE() << "no error";
    } catch (const InputError& error) {
        EXPECT_THAT(error.what(), HasSubstr("p.exr: pattern file is damaged: its EXR header's attribute "
                                            "'rfd:white' (string) declares 1664102458 bytes, but "));
    }
    EXPECT_THAT(error_of([&] { read_pattern_info(pattern_with_attribute_size(dir, 0xffffffffu)); }),
                HasSubstr("'rfd:white' (string) declares -1 bytes"));
    // The true size reads as before.
    EXPECT_EQ(read_pattern_info(pattern_with_attribute_size(dir, 4)).attributes.at("white"), "0.75");
}

TEST(ReadPattern, TilesLargerThanTheImageAreAnInputError) {
    // Found by fuzz/fuzz_pattern.cpp: a 19 x 19 pattern in tiles of 16904 x 2048 pixels made
    // OpenEXR fill a 200 MB tile buffer (1.6 GB for tiles of 16000 x 16000) to read it.
    TempDir dir;
    std::string bytes;
    {
        std::ifstream in(std::filesystem::path(RFD_SOURCE_DIR) / "fuzz/corpus/pattern/tiled.exr", std::ios::binary);
        bytes.assign(std::istreambuf_iterator<char>(in), {});
    }
    const auto with_tiles = [&](std::uint32_t x, std::uint32_t y) {
        std::string file = bytes;
        const std::string attribute("tiles\0tiledesc\0\x09\0\0\0", 19);
        const std::size_t at = file.find(attribute);
        EXPECT_NE(at, std::string::npos);
        for (std::size_t b = 0; b < 4; ++b) {
            file[at + attribute.size() + b] = static_cast<char>((x >> (8 * b)) & 0xff);
            file[at + attribute.size() + 4 + b] = static_cast<char>((y >> (8 * b)) & 0xff);
        }
        const auto path = dir / "tiled.exr";
        std::ofstream(path, std::ios::binary) << file;
        return path;
    };
    EXPECT_THAT(error_of([&] { read_pattern_info(with_tiles(16904, 2048)); }),
                HasSubstr("tiled.exr: pattern file is damaged: its EXR header declares tiles of 16904 x 2048 "
                          "pixels, larger than its data window of 19 x 19"));
    // Tiles up to OpenEXR's default of 64 pixels, or up to the image, read as before.
    EXPECT_EQ(read_pattern_info(with_tiles(8, 8)).width, 19);
    EXPECT_EQ(read_pattern_info(with_tiles(64, 19)).width, 19);
}

TEST(ReadPattern, MoreRowsThanTheFileHasOffsetsForIsAnInputError) {
    // Found by fuzz/fuzz_pattern.cpp: a 2 KB pattern whose data window declared 400 million
    // rows made OpenEXR allocate an offset table of 3 GB (3-8 s under ASan) before reading.
    TempDir dir;
    const auto path = dir / "p.exr";
    write_pattern(path, Ramp(small_geometry(), 3), {});
    std::string bytes;
    {
        std::ifstream in(path, std::ios::binary);
        bytes.assign(std::istreambuf_iterator<char>(in), {});
    }
    const auto with_last_row = [&](std::int32_t y_max) {
        std::string file = bytes;
        const std::string attribute("dataWindow\0box2i\0\x10\0\0\0", 21);
        const std::size_t at = file.find(attribute);
        EXPECT_NE(at, std::string::npos);
        for (std::size_t b = 0; b < 4; ++b)
            file[at + attribute.size() + 12 + b] = static_cast<char>((static_cast<std::uint32_t>(y_max) >> (8 * b)) & 0xff);
        std::ofstream(path, std::ios::binary) << file;
        return path;
    };
    const std::string message = error_of([&] { read_pattern_info(with_last_row(400'000'000)); });
    EXPECT_THAT(message, HasSubstr("p.exr: pattern file is damaged: its EXR header declares "));
    EXPECT_THAT(message, HasSubstr("declares 400000001 chunks of pixels, whose offset table alone takes 3200000008 bytes"));
    // The true window reads as before.
    const PatternFileInfo info = read_pattern_info(with_last_row(small_geometry().height - 1));
    EXPECT_EQ(info.height, small_geometry().height);
}

}  // namespace
}  // namespace rfd::patterns
