#include "core/exr_header.hpp"

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <map>
#include <system_error>
#include <utility>

namespace rfd {
namespace {

// The value sizes of OpenEXR 3.1's fixed-size attribute types (ImfHeader.cpp registers them).
const std::map<std::string, std::int64_t>& fixed_sizes() {
    static const std::map<std::string, std::int64_t> sizes = {
        {"box2i", 16}, {"box2f", 16}, {"compression", 1}, {"lineOrder", 1}, {"envmap", 1},
        {"deepImageState", 1}, {"float", 4}, {"double", 8}, {"int", 4}, {"rational", 8},
        {"v2i", 8}, {"v2f", 8}, {"v2d", 16}, {"v3i", 12}, {"v3f", 12}, {"v3d", 24},
        {"m33f", 36}, {"m33d", 72}, {"m44f", 64}, {"m44d", 128}, {"chromaticities", 32},
        {"keycode", 28}, {"timecode", 8}, {"tiledesc", 9},
    };
    return sizes;
}

class Walk {
public:
    explicit Walk(const std::filesystem::path& path) : in_(path, std::ios::binary) {
        std::error_code ec;
        size_ = static_cast<std::int64_t>(std::filesystem::file_size(path, ec));
        if (ec) size_ = -1;
    }

    std::optional<std::string> problem() {
        unsigned char start[8] = {};
        if (size_ < 0 || !in_.read(reinterpret_cast<char*>(start), sizeof start)) return std::nullopt;
        if (start[0] != 0x76 || start[1] != 0x2f || start[2] != 0x31 || start[3] != 0x01) return std::nullopt;
        const bool multi_part = (start[5] & 0x10) != 0;  // version field bit 12
        while (true) {
            std::string name;
            if (!read_name(name)) return problem_;
            if (name.empty()) break;  // an empty header: the end of a multi-part list
            window_ = tile_ = {};
            lines_per_chunk_ = 1;
            while (!name.empty())
                if (!read_attribute(name) || !read_name(name)) return problem_;
            if (!check_tiles()) return problem_;
            chunks_ += chunks();
            if (!multi_part) break;
        }
        if (!check_offset_tables()) return problem_;
        return std::nullopt;
    }

private:
    std::int64_t left() { return size_ - static_cast<std::int64_t>(in_.tellg()); }

    bool fail(const std::string& message) {
        problem_ = "its EXR header " + message;
        return false;
    }

    // A null-terminated name of at most 255 characters, as OpenEXR reads names and types.
    bool read_name(std::string& name) {
        name.clear();
        for (int c = in_.get(); c != 0; c = in_.get()) {
            if (c == std::char_traits<char>::eof()) return fail("ends early");
            if (name.size() >= 255) return fail("holds a name of more than 255 characters");
            name += static_cast<char>(c);
        }
        return true;
    }

    bool read_int32(std::int32_t& value) {
        unsigned char b[4];
        if (!in_.read(reinterpret_cast<char*>(b), 4)) return fail("ends early");
        value = static_cast<std::int32_t>(static_cast<std::uint32_t>(b[0]) | static_cast<std::uint32_t>(b[1]) << 8 |
                                          static_cast<std::uint32_t>(b[2]) << 16 |
                                          static_cast<std::uint32_t>(b[3]) << 24);
        return true;
    }

    // The attribute whose name has been read: its type, size and value.
    bool read_attribute(const std::string& name) {
        std::string type;
        std::int32_t size = 0;
        if (!read_name(type) || !read_int32(size)) return false;
        const std::string what = "'s attribute '" + name + "' (" + type + ")";
        const std::int64_t available = left();
        if (size < 0 || size > available)
            return fail_attribute(what, "declares " + std::to_string(size) + " bytes, but " +
                                            std::to_string(available) + " are left in the file");
        const auto fixed = fixed_sizes().find(type);
        if (fixed != fixed_sizes().end() && size != fixed->second)
            return fail_attribute(what, "declares " + std::to_string(size) + " bytes, but a " + type + " holds " +
                                            std::to_string(fixed->second));
        if (type == "chlist") return check_channels(what, size);
        const std::int64_t end = static_cast<std::int64_t>(in_.tellg()) + size;
        if (name == "dataWindow" && type == "box2i") {
            std::int32_t box[4];
            for (std::int32_t& v : box)
                if (!read_int32(v)) return false;
            window_ = {static_cast<std::int64_t>(box[2]) - box[0] + 1, static_cast<std::int64_t>(box[3]) - box[1] + 1};
        } else if (name == "compression" && type == "compression") {
            lines_per_chunk_ = lines_per_chunk(in_.get());
        } else if (name == "tiles" && type == "tiledesc") {
            std::int32_t x = 0, y = 0;
            if (!read_int32(x) || !read_int32(y)) return false;
            tile_ = {static_cast<std::uint32_t>(x), static_cast<std::uint32_t>(y)};
        }
        in_.seekg(end);
        return true;
    }

    // OpenEXR allocates a whole tile's pixels for reading, and fills it: a 2 KB file of
    // 19 x 19 pixels in tiles of 16000 x 16000 took 1.6 GB and 1.8 s to read. A tile larger
    // than its image serves nothing, so beyond OpenEXR's default of 64 pixels a tile may
    // not be larger than the data window: its buffer is then no larger than the image,
    // which rfd's readers bound before they read.
    bool check_tiles() {
        const auto [width, height] = window_;
        const auto [tile_x, tile_y] = tile_;
        if (tile_x > std::max<std::int64_t>(width, 64) || tile_y > std::max<std::int64_t>(height, 64))
            return fail("declares tiles of " + std::to_string(tile_x) + " x " + std::to_string(tile_y) +
                        " pixels, larger than its data window of " + std::to_string(width) + " x " +
                        std::to_string(height));
        return true;
    }

    // How many chunks of pixels the current header's image has, at least: scanline blocks, or
    // tiles of the full-resolution level (mipmap and ripmap levels add more). OpenEXR 3.1's
    // scanline reader sizes its offset table as (height + lines - 1) / lines.
    // In double: tile counts of damaged headers overflow 64 bits, and beyond 2^53 only the
    // size matters.
    double chunks() const {
        const auto [width, height] = window_;
        if (width <= 0 || height <= 0) return 0;  // OpenEXR refuses these itself
        const auto [tile_x, tile_y] = tile_;
        const auto blocks = [](std::int64_t length, std::int64_t block) {
            return static_cast<double>((length + block - 1) / block);
        };
        if (tile_x == 0 && tile_y == 0) return blocks(height, lines_per_chunk_);
        if (tile_x == 0 || tile_y == 0) return 0;
        return blocks(width, tile_x) * blocks(height, tile_y);
    }

    // OpenEXR allocates and reads a table of one 64-bit file offset per chunk before any
    // pixel: a 2 KB file declaring 400 million rows made it reserve 3 GB (3-8 s under ASan).
    // A whole file holds its tables after the headers, so the chunks must fit in what is left.
    bool check_offset_tables() {
        const std::int64_t available = left();
        if (8.0 * chunks_ <= static_cast<double>(available)) return true;
        const auto whole = [](double value) {
            char text[32];
            std::snprintf(text, sizeof text, "%.0f", value);
            return std::string(text);
        };
        return fail("declares " + whole(chunks_) + " chunks of pixels, whose offset table alone takes " +
                    whole(8.0 * chunks_) + " bytes, but " + std::to_string(available) + " are left in the file");
    }

    // The scanlines in one chunk, by OpenEXR's compression code (ImfCompression.h); unknown
    // codes, which OpenEXR refuses, count as the largest.
    static std::int64_t lines_per_chunk(int compression) {
        switch (compression) {
            case 0: case 1: case 2: return 1;     // none, RLE, ZIPS
            case 3: case 5: return 16;            // ZIP, PXR24
            case 4: case 6: case 7: case 8: return 32;  // PIZ, B44, B44A, DWAA
            default: return 256;                  // DWAB
        }
    }

    bool fail_attribute(const std::string& what, const std::string& message) {
        problem_ = "its EXR header" + what + " " + message;
        return false;
    }

    // OpenEXR reads a channel list to its empty name, whatever the size says: name, 16 bytes
    // (type, pLinear, reserved, x and y sampling), ..., an empty name.
    bool check_channels(const std::string& what, std::int64_t size) {
        const std::int64_t begin = in_.tellg();
        std::string channel;
        while (true) {
            if (!read_name(channel)) return false;
            if (channel.empty()) break;
            in_.seekg(16, std::ios::cur);
            if (static_cast<std::int64_t>(in_.tellg()) - begin > size) break;
        }
        if (static_cast<std::int64_t>(in_.tellg()) - begin != size)
            return fail_attribute(what, "declares " + std::to_string(size) + " bytes, but its channel list does not end there");
        return true;
    }

    std::ifstream in_;
    std::int64_t size_ = -1;
    std::string problem_;
    std::pair<std::int64_t, std::int64_t> window_;  // the current header's data window, 0 x 0 if none
    std::pair<std::int64_t, std::int64_t> tile_;    // its tile size, 0 x 0 if none
    std::int64_t lines_per_chunk_ = 1;              // its scanlines per chunk, by its compression
    double chunks_ = 0;                             // the chunks of every header read so far
};

}  // namespace

std::optional<std::string> exr_header_problem(const std::filesystem::path& path) {
    Walk walk(path);
    return walk.problem();
}

}  // namespace rfd
