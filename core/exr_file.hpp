#pragma once
// rfd's own OpenEXR files, read and written with OpenEXR's library instead of OpenImageIO.
//
// Why: the OpenImageIO module links about 260 libraries (codecs, video, DICOM, OpenVDB) and
// takes 0.45 s to load, more than most commands spend on their images; nearly every rfd
// command and many tests touch only EXR files (fields, patterns, renders). OpenEXR loads in
// a millisecond.
//
// Covered, the files rfd writes and what capture tools commonly write: one part of scan
// lines, channels R, G, B (and A) or Y (and A), all half or all float, the data window at
// the origin. Written: .exr of 1, 3 or 4 channels, half or float, with a compression
// OpenEXR names ("none", "rle", "zips", "zip", "piz", ...), no description. The files
// written are byte for byte those OpenImageIO writes, and a file read gives the spec and
// samples OpenImageIO gives (tests/test_exr_file.cpp compares the two). Everything else
// (tiled, multi-part, layered or deep files, other channels) is left to OpenImageIO.
//
// Example: if (auto reader = open_exr_file(path)) ...; else ... the module's reader ...

#include <memory>
#include <string>

#include "core/image_backend.hpp"

namespace rfd {

/// A reader of `path` when it is an OpenEXR file of the kind covered above; null otherwise,
/// also when OpenEXR cannot read its header, so that OpenImageIO reports the problem.
std::unique_ptr<ImageFileReader::Backend> open_exr_file(const std::string& path);

/// True when create_exr_file() writes a file of `spec`.
bool exr_file_covers(const ImageFileSpec& spec);

/// A writer of a new OpenEXR file at `path` (any extension). Precondition:
/// exr_file_covers(spec). Null with `error` set when the file cannot be created.
std::unique_ptr<ImageFileWriter::Backend> create_exr_file(const std::string& path, const ImageFileSpec& spec,
                                                          std::string& error);

}  // namespace rfd
