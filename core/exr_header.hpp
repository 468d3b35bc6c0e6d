#pragma once
// A check of an OpenEXR file's header against the file's size, before OpenEXR reads it.
//
// OpenEXR 3.1 allocates a string attribute's declared size, and an unknown type's, before it
// reads the bytes: a damaged size in a pattern of 2 KB made a reader allocate and fill
// 1.7 GB and take 17 s before it reported the file's end (fuzz/fuzz_pattern.cpp found it).
// In a whole file every attribute lies inside the file, so one that declares more than is
// left is refused here. The walk keeps in step with OpenEXR's own reading: name, type,
// 32-bit size, value; fixed-size types must declare their size, and a channel list must
// end where its size says (OpenEXR reads both by their content, whatever the size says);
// one header, or for a multi-part file a list of them ending in an empty one. A tile may
// not be larger than its data window (beyond 64 pixels): OpenEXR fills a whole tile's
// buffer to read one. The headers' chunks of pixels must leave room in the file for their
// offset tables (8 bytes a chunk), which OpenEXR allocates before it reads a pixel.
//
// Example: if (auto problem = exr_header_problem("a.exr")) throw InputError(..., *problem);

#include <filesystem>
#include <optional>
#include <string>

namespace rfd {

/// Nothing when `path` is not an OpenEXR file (by its first four bytes) or when everything
/// its header declares fits in the file; otherwise what does not, as a phrase such as
/// "its EXR header's attribute 'capDate' (string) declares 1664102458 bytes, but 1954 are
/// left in the file". Throws nothing: a file it cannot read is left to the reader.
std::optional<std::string> exr_header_problem(const std::filesystem::path& path);

}  // namespace rfd
