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

#include <array>
#include <cstddef>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json_fwd.hpp>

#include "predict/preview.hpp"

namespace rfd::project {

/// window.RFD_PREVIEW of data.js: what the page (project/assets/preview.js) reads. The
/// atlases are PNG data: URIs, `columns` tiles of `tile` pixels to a row.
struct PreviewData {
    struct Rim {
        double phi_deg = 0.0;
        std::optional<double> wrap_over_deg, crosstalk_deg;
    };
    std::string design;
    std::string frame = "display: z the display's axis, toward the light";
    double max_angle_deg = 0.0;
    double scale = 1.0;
    std::array<int, 2> tile{0, 0};
    int columns = 0;
    std::vector<std::array<double, 3>> directions;
    std::vector<std::array<std::size_t, 3>> triangles;
    std::vector<std::array<std::array<double, 3>, 3>> edge_planes;
    std::vector<Rim> rims;
    std::string predicted, relit;
    std::optional<std::string> predicted_direct;
};
void to_json(nlohmann::json& json, const PreviewData& data);
void from_json(const nlohmann::json& json, PreviewData& data);

/// Writes the atlases of `set` and data.js into `folder` (created), for `design_name`;
/// returns what data.js holds.
PreviewData write_preview_data(const predict::PreviewSet& set, const std::string& design_name,
                               const std::filesystem::path& folder);
/// data.js read back; InputError naming the file when it is not one rfd wrote.
PreviewData read_preview_data(const std::filesystem::path& file);

/// Copies the page's script, the vendored three.js files (when installed; false when not)
/// and `stls` as holder.js into `folder`.
bool write_preview_assets(const std::filesystem::path& folder, const std::vector<std::filesystem::path>& stls);

/// `bytes` in base64 (RFC 4648, with padding).
std::string base64(const std::string& bytes);

}  // namespace rfd::project
