// rfd's own EXR reader and writer (core/exr_file.hpp) against OpenImageIO's, which they
// stand in for: the same bytes written for every spec they cover, the same spec and samples
// read from every file they cover, and every other file left to OpenImageIO.

#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfFloatAttribute.h>
#include <OpenEXR/ImfFrameBuffer.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfIntAttribute.h>
#include <OpenEXR/ImfOutputFile.h>
#include <OpenEXR/ImfStringAttribute.h>
#include <OpenEXR/ImfTiledOutputFile.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <iterator>
#include <optional>
#include <string>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "core/exr_file.hpp"
#include "core/half.hpp"
#include "core/image_backend.hpp"
#include "core/image_file.hpp"
#include "core/image_io.hpp"
#include "tests/support/temp_dir.hpp"

namespace rfd {
namespace {

using rfd::testing::TempDir;

std::string bytes_of(const std::filesystem::path& path) {
    std::ifstream in(path, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// Samples that exercise a format: negative, tiny, large, repeated runs (for rle), as floats.
std::vector<float> test_samples(const ImageFileSpec& spec) {
    std::vector<float> samples(static_cast<std::size_t>(spec.width) * spec.height * spec.channels);
    for (std::size_t i = 0; i < samples.size(); ++i)
        samples[i] = (i / 7) % 3 == 0 ? 0.25f : static_cast<float>(std::sin(0.37 * static_cast<double>(i)) * 40.0 - 3.0);
    return samples;
}

// The samples in the spec's type, as a writer is handed them.
std::vector<std::uint8_t> in_type(const std::vector<float>& samples, SampleType type) {
    std::vector<std::uint8_t> bytes(samples.size() * sample_size(type));
    if (type == SampleType::Float32) {
        std::memcpy(bytes.data(), samples.data(), bytes.size());
    } else {
        std::vector<std::uint16_t> halves(samples.size());
        floats_to_half(samples, halves);
        std::memcpy(bytes.data(), halves.data(), bytes.size());
    }
    return bytes;
}

// Writes the rows `bytes` (of `rows` samples; the file's type unless given) with rfd's writer
// or OpenImageIO's.
void write_with(bool own, const std::filesystem::path& path, const ImageFileSpec& spec,
                const std::vector<std::uint8_t>& bytes, std::optional<SampleType> rows = std::nullopt) {
    const SampleType type = rows.value_or(spec.type);
    std::string error;
    std::unique_ptr<ImageFileWriter::Backend> writer =
        own ? create_exr_file(path.string(), spec, error) : imageio_backend().create(path.string(), spec, error);
    ASSERT_NE(writer, nullptr) << error;
    const std::size_t row = static_cast<std::size_t>(spec.width) * spec.channels * sample_size(type);
    // In two strips, as the pattern writer hands them over.
    const int half = spec.height / 2;
    ASSERT_TRUE(writer->write_rows(0, half, type, bytes.data())) << writer->error();
    ASSERT_TRUE(writer->write_rows(half, spec.height, type, bytes.data() + row * half)) << writer->error();
    ASSERT_TRUE(writer->close()) << writer->error();
}

TEST(ExrFile, WritesTheBytesOpenImageIoWrites) {
    const TempDir dir;
    int checked = 0;
    for (const int channels : {1, 3, 4})
        for (const SampleType type : {SampleType::Half, SampleType::Float32})
            for (const SampleType rows : {SampleType::Half, SampleType::Float32})
                for (const std::string compression : {"", "none", "rle", "zips", "zip", "piz"})
                    for (const bool attributes : {false, true}) {
                        ImageFileSpec spec{.width = 37, .height = 41, .channels = channels, .type = type,
                                           .compression = compression};
                        if (attributes) {
                            spec.dpi_x = 2880.0;
                            spec.dpi_y = 1440.0;
                            spec.attributes = {{"design", "Design II: 6x5 lenslets"}, {"white", "0.993056595"}, {"kind", "II"}};
                        }
                        ASSERT_TRUE(exr_file_covers(spec));
                        const std::vector<std::uint8_t> bytes = in_type(test_samples(spec), rows);
                        write_with(true, dir / "own.exr", spec, bytes, rows);
                        write_with(false, dir / "oiio.exr", spec, bytes, rows);
                        const std::string own = bytes_of(dir / "own.exr"), oiio = bytes_of(dir / "oiio.exr");
                        EXPECT_GT(own.size(), 300u);
                        EXPECT_TRUE(own == oiio) << channels << " channels, " << sample_type_name(type) << " from "
                                                 << sample_type_name(rows) << ", '"
                                                 << compression << "', attributes " << attributes << ": "
                                                 << own.size() << " bytes against " << oiio.size();
                        ++checked;
                    }
    EXPECT_EQ(checked, 3 * 2 * 2 * 6 * 2);
}

TEST(ExrFile, LeavesOtherSpecsToOpenImageIo) {
    EXPECT_FALSE(exr_file_covers({.width = 2, .height = 2, .channels = 2}));
    EXPECT_FALSE(exr_file_covers({.width = 2, .height = 2, .channels = 5}));
    EXPECT_FALSE(exr_file_covers({.width = 2, .height = 2, .channels = 3, .type = SampleType::UInt16}));
    EXPECT_FALSE(exr_file_covers({.width = 2, .height = 2, .channels = 3, .compression = "dwaa"}));
    EXPECT_FALSE(exr_file_covers({.width = 2, .height = 2, .channels = 3, .compression = "zip:9"}));
    EXPECT_FALSE(exr_file_covers({.width = 2, .height = 2, .channels = 3, .description = "a"}));
    EXPECT_FALSE(exr_file_covers({.width = 2, .height = 2, .channels = 3, .exposure_seconds = 0.5}));
}

// A file as other tools write it: the given channels (all of `type`), header attributes.
struct ForeignFile {
    std::vector<std::string> channels{"R", "G", "B"};
    Imf::PixelType type = Imf::HALF;
    Imf::Compression compression = Imf::ZIP_COMPRESSION;
    float aspect = 1.0f;
    Imath::V2i origin{0, 0};
    bool tiled = false;
    std::vector<std::pair<std::string, std::string>> strings;
    std::vector<std::pair<std::string, float>> floats;
    bool integer_attribute = false;  ///< an "rfd:" attribute that is not a string
};

void write_foreign(const std::filesystem::path& path, const ForeignFile& f) {
    const int width = 19, height = 23;
    const Imath::Box2i window(f.origin, f.origin + Imath::V2i(width - 1, height - 1));
    Imf::Header header(window, window, f.aspect, Imath::V2f(0, 0), 1.0f, Imf::INCREASING_Y, f.compression);
    for (const std::string& name : f.channels) header.channels().insert(name, Imf::Channel(f.type));
    for (const auto& [name, value] : f.strings) header.insert(name, Imf::StringAttribute(value));
    for (const auto& [name, value] : f.floats) header.insert(name, Imf::FloatAttribute(value));
    if (f.integer_attribute) header.insert("rfd:count", Imf::IntAttribute(3));
    const std::size_t n = f.channels.size();
    std::vector<float> samples(static_cast<std::size_t>(width) * height * n);
    for (std::size_t i = 0; i < samples.size(); ++i) samples[i] = static_cast<float>(std::cos(0.23 * static_cast<double>(i)) * 2.0 + 0.5);
    std::vector<std::uint16_t> halves(samples.size());
    floats_to_half(samples, halves);
    const std::size_t sample = f.type == Imf::HALF ? 2 : 4;
    const char* base = f.type == Imf::HALF ? reinterpret_cast<const char*>(halves.data())
                                           : reinterpret_cast<const char*>(samples.data());
    Imf::FrameBuffer frame;
    for (std::size_t c = 0; c < n; ++c)
        frame.insert(f.channels[c], Imf::Slice::Make(f.type, base + c * sample, window, n * sample, n * sample * width));
    if (f.tiled) {
        header.setTileDescription(Imf::TileDescription(8, 8));
        Imf::TiledOutputFile out(path.c_str(), header);
        out.setFrameBuffer(frame);
        out.writeTiles(0, out.numXTiles() - 1, 0, out.numYTiles() - 1);
    } else {
        Imf::OutputFile out(path.c_str(), header);
        out.setFrameBuffer(frame);
        out.writePixels(height);
    }
}

// Reads `path` with both readers and compares what they give. False when rfd's own reader
// leaves the file to OpenImageIO.
bool reads_as_openimageio_does(const std::filesystem::path& path) {
    std::unique_ptr<ImageFileReader::Backend> own = open_exr_file(path.string());
    if (!own) return false;
    std::string error;
    std::unique_ptr<ImageFileReader::Backend> oiio = imageio_backend().open(path.string(), error);
    EXPECT_NE(oiio, nullptr) << error;
    if (!oiio) return true;
    const ImageFileSpec& a = own->spec();
    const ImageFileSpec& b = oiio->spec();
    EXPECT_EQ(a.width, b.width);
    EXPECT_EQ(a.height, b.height);
    EXPECT_EQ(a.channels, b.channels);
    EXPECT_EQ(a.type, b.type);
    EXPECT_EQ(a.dpi_x, b.dpi_x);
    EXPECT_EQ(a.dpi_y, b.dpi_y);
    EXPECT_EQ(a.description, b.description);
    EXPECT_EQ(a.compression, b.compression);
    EXPECT_EQ(a.exposure_seconds, b.exposure_seconds);
    EXPECT_EQ(a.attributes, b.attributes);
    for (const SampleType type : {SampleType::Float32, SampleType::Half, SampleType::UInt16, SampleType::UInt8}) {
        const std::size_t row = static_cast<std::size_t>(a.width) * a.channels * sample_size(type);
        // Rows 3 to 17: a strip that starts and ends inside the file's blocks of rows.
        std::vector<std::uint8_t> mine(row * 14), theirs(row * 14);
        EXPECT_TRUE(own->read_rows(3, 17, type, mine.data())) << own->error();
        EXPECT_TRUE(oiio->read_rows(3, 17, type, theirs.data())) << oiio->error();
        EXPECT_TRUE(mine == theirs) << path << " read as " << sample_type_name(type);
    }
    return true;
}

TEST(ExrFile, ReadsWhatOpenImageIoReads) {
    const TempDir dir;
    int covered = 0;
    // What rfd writes.
    for (const int channels : {1, 3, 4})
        for (const SampleType type : {SampleType::Half, SampleType::Float32}) {
            ImageFileSpec spec{.width = 37, .height = 41, .channels = channels, .type = type, .dpi_x = 720.0,
                               .dpi_y = 360.0, .compression = "rle", .attributes = {{"field", "f"}}};
            write_with(true, dir / "rfd.exr", spec, in_type(test_samples(spec), type));
            EXPECT_TRUE(reads_as_openimageio_does(dir / "rfd.exr")) << channels << " channels";
            ++covered;
        }
    // What other tools write.
    const std::vector<ForeignFile> files = {
        {},
        {.channels = {"R", "G", "B", "A"}},
        {.channels = {"Y"}, .type = Imf::FLOAT},
        {.channels = {"Y", "A"}},
        {.compression = Imf::NO_COMPRESSION, .strings = {{"comments", "a camera's note"}}, .floats = {{"expTime", 0.125f}}},
        {.compression = Imf::PIZ_COMPRESSION, .aspect = 2.0f, .floats = {{"xDensity", 300.0f}}},
        {.compression = Imf::ZIPS_COMPRESSION, .strings = {{"owner", "someone"}, {"rfd:kind", "I"}}},
    };
    for (const ForeignFile& file : files) {
        write_foreign(dir / "foreign.exr", file);
        EXPECT_TRUE(reads_as_openimageio_does(dir / "foreign.exr")) << "file " << covered - 6;
        ++covered;
    }
    EXPECT_EQ(covered, 6 + 7);
}

TEST(ExrFile, LeavesOtherFilesToOpenImageIo) {
    const TempDir dir;
    const std::vector<ForeignFile> files = {
        {.tiled = true},
        {.origin = {4, -2}},
        {.channels = {"R", "G", "B", "Z"}},
        {.channels = {"diffuse.R", "diffuse.G", "diffuse.B"}},
        {.channels = {"R", "G"}},
        {.type = Imf::UINT},
        {.compression = Imf::DWAA_COMPRESSION},
        {.compression = Imf::B44_COMPRESSION},
        {.strings = {{"ResolutionUnit", "cm"}}, .floats = {{"xDensity", 100.0f}}},
        {.integer_attribute = true},
    };
    int left = 0;
    for (const ForeignFile& file : files) {
        write_foreign(dir / "other.exr", file);
        EXPECT_EQ(open_exr_file((dir / "other.exr").string()), nullptr) << "file " << left;
        // OpenImageIO reads them, and so ImageFileReader does.
        EXPECT_NO_THROW(ImageFileReader reader(dir / "other.exr")) << "file " << left;
        ++left;
    }
    EXPECT_EQ(left, 10);
    // Not EXR at all, and damaged: OpenImageIO's turn, and its message.
    write_image(dir / "a.png", Image(3, 2, 3));
    EXPECT_EQ(open_exr_file((dir / "a.png").string()), nullptr);
    std::ofstream(dir / "cut.exr", std::ios::binary) << std::string("\x76\x2f\x31\x01\x02\0\0\0chan", 12);
    EXPECT_EQ(open_exr_file((dir / "cut.exr").string()), nullptr);
}

}  // namespace
}  // namespace rfd
