#pragma once
// A view set: the same scene captured from several viewpoints, one reflectance field per view,
// as the source of observer-variant displays (Designs III and IV, thesis 8.3).
//
// Display frame: the field frame of the first camera (core/sphere.hpp: x right, y up in its
// image, z toward it). The display stands where the scene is and faces that camera, so a
// view's direction (the unit vector from what the camera looks at toward the camera, in
// this frame) is the output direction of travel in which the display must show that view;
// the first camera's is (0, 0, 1). Each view's light file records directions in its own
// camera's field frame (relight/stage.hpp); the view file carries the rotation back.
//
// On disk, `views.txt` in the capture folder (`rfd capture render` writes it for scenes with
// several cameras):
//     # rfd view set: folder, direction toward the camera (display frame), and optionally
//     # the 3 x 3 rotation (row-major) from the view's light frame to the display frame
//     2
//     view_00 0 0 1 1 0 0 0 1 0 0 0 1
//     view_01 0.1736 0 0.9848 0.9848 0 -0.1736 0 1 0 0.1736 0 0.9848
// First line the view count, then one line per view: the folder of its field (relative to
// the view file's folder), three numbers for its direction (normalised on reading), and
// either nothing (the light file is already in the display frame) or nine numbers.
// Lines starting with '#' are comments.
//
// Example: ViewSet set = read_view_set("out/capture/views.txt"); set.fields[1].size();

#include <filesystem>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "relight/field.hpp"

namespace rfd::relight {

struct ViewEntry {
    std::string folder;                                      ///< as written in the file
    Eigen::Vector3d direction = Eigen::Vector3d::UnitZ();    ///< unit, toward the camera
    Eigen::Matrix3d to_display = Eigen::Matrix3d::Identity();///< view light frame -> display
    int line = 0;                                            ///< 1-based line in the file
};

struct ViewSet {
    std::filesystem::path file;       ///< the view file read
    std::vector<ViewEntry> views;
    /// One field per view, light directions already turned into the display frame.
    std::vector<ReflectanceField> fields;
};

/// Parses a view file. Throws InputError naming file and line for a bad count, a count that
/// does not match the lines, a missing or unparsable number, a zero-length direction, a
/// rotation that is not orthonormal, or a direction behind the display (z <= 0); IoError
/// if it cannot be read.
std::vector<ViewEntry> read_view_file(const std::filesystem::path& path);

/// Writes a view file (rotations always written).
void write_view_file(const std::filesystem::path& path, const std::vector<ViewEntry>& views);

/// The view file of a view set given as a folder (holding views.txt) or as the file.
std::filesystem::path view_file_of(const std::filesystem::path& set);

/// Reads the view file and every view's field, each image through `window`. Throws
/// InputError (naming the view file and line) for a missing view folder, views whose images
/// differ in size or channel count, and anything read_field rejects.
ViewSet read_view_set(const std::filesystem::path& set, const ImageWindow& window = {});

}  // namespace rfd::relight
