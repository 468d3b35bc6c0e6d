#pragma once
// The preview page's files (docs/formats.md, "The preview page"): the precomputed pictures
// and what the page blends them with, as one script the page loads with a <script> tag, so
// that it opens from the file system with no server and works offline (browsers refuse to
// let a page read files beside it; scripts and data: URIs they load).
//
//   FOLDER/data.js         window.RFD_PREVIEW = {...}: directions, triangles, edge planes,
//                          rims, scale, and the two atlases as data: URIs
//   FOLDER/predicted.png   the predicted pictures, one tile per direction (sRGB)
//   FOLDER/relit.png       the field relit in software, the same tiles
//   FOLDER/direct.png      the direct encoding's predicted pictures, when the pattern was
//                          optimised from it (the page then switches between the two)
//   FOLDER/preview.js      the page's script (project/assets/preview.js)
//   FOLDER/holder.js       the holder's STLs (base64), when given
//   FOLDER/vendor/         three.js and its STL loader and orbit controls (Debian's
//                          libjs-three), when installed, for the holder's 3D view

#include <filesystem>
#include <string>
#include <vector>

#include "predict/preview.hpp"

namespace rfd::project {

/// Writes data.js and the atlases of `set` into `folder` (created), for `design_name`.
void write_preview_data(const predict::PreviewSet& set, const std::string& design_name,
                        const std::filesystem::path& folder);

/// Copies the page's script, the vendored three.js files (when installed; false when not)
/// and `stls` as holder.js into `folder`.
bool write_preview_assets(const std::filesystem::path& folder, const std::vector<std::filesystem::path>& stls);

/// `bytes` in base64 (RFC 4648, with padding).
std::string base64(const std::string& bytes);

}  // namespace rfd::project
