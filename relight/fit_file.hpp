#pragma once
// Fitted fields on disk in CNR relight's layout: the folder relight-cli writes and OpenLIME
// (ShaderRTI, LayerRTI) opens, so that rfd's fits open in the RTI community's viewer and
// their fits relight in rfd.
//
//   info.json     {"width", "height", "format": "jpg", "type": "ptm" | "hsh" | "rbf" | "bilinear",
//                  "colorspace": "rgb" (ptm, hsh) | "mrgb" (rbf, bilinear), "nplanes", "quality",
//                  "lights": [x, y, z, ...], "sigma" (rbf), "resolution" (bilinear),
//                  "basis" (rbf, bilinear: bytes),
//                  "materials": [{"scale": [...], "bias": [...], "range": [...] (rbf, bilinear)}]}
//   plane_0.jpg, ..., plane_{J-1}.jpg   J = ceil(nplanes / 3), three planes each (R, G, B)
//
// The rules, as OpenLIME evaluates them (values in display units, 0..1, the JPEG codes' own
// encoding: a fit of the photographs as they are stored, sRGB):
//  - plane p of a pixel is v_p = (code / 255 - bias[p]) * scale[p];
//  - rgb (ptm, hsh): plane 3 j + c is coefficient j of colour channel c; the value under a
//    light toward d is sum_j b_j(d) v_(3j+c), b the basis of relight/basis.hpp (ptm: 6
//    functions, nplanes 18; hsh: 4 or 9, nplanes 12 or 27; OpenLIME renders no more);
//  - mrgb (rbf): the pixel's samples under the capture's n lights, light-major and channel-
//    minor (3 n values), are mean + sum_p v_p e_p, with mean and e_p (principal components)
//    from "basis": (nplanes + 1) blocks of 3 n bytes, the mean's block as byte / 255, each
//    e_p as (byte - 127) / range[p]; under a light toward d the lights are blended by the
//    radial basis weights of relight/light_model.hpp with "sigma";
//  - mrgb (bilinear, OpenLIME's 'bln'): the same with the samples at the R x R nodes of the
//    octahedral grid of relight/light_model.hpp ("resolution" R) instead of the lights, 3 R^2
//    values per block, blended bilinearly between the four nodes around the light. rfd fills
//    the nodes as its bilinear light model does (the capture resampled by a least-squares
//    grid pulled toward the rbf prior), then takes the principal components.
//
// rfd's exact variant keeps what quantisation would lose: "format": "exr", planes
// plane_N.exr of float coefficients of linear light (scale 1, bias 0), "basis" as floats,
// "linear": true. OpenLIME does not open it; rfd reads both.
//
// Example: FitSpec spec; spec.type = FitType::Hsh; spec.basis = Basis::Hsh3;
//          fit_field(field, spec, "out/coin_hsh");
//          render_fit_to_files("out/coin_hsh", {direction}, {"relit.png"});

#include <cstddef>
#include <filesystem>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/image.hpp"
#include "relight/basis.hpp"

namespace rfd::relight {

class FieldReader;

enum class FitType { Ptm, Hsh, Rbf, Bilinear };
/// "ptm", "hsh", "rbf", "bilinear": info.json's "type".
const char* fit_type_name(FitType type);

/// What to fit.
struct FitSpec {
    FitType type = FitType::Ptm;
    Basis basis = Basis::Ptm;  ///< ptm: Ptm; hsh: Hsh2 or Hsh3 (Hsh4 only with `exact`)
    int planes = 18;           ///< rbf, bilinear: principal components kept
    double sigma = 0.0;        ///< rbf (bilinear: its prior): the Gaussian's width; 0: least leave-one-out error
    int resolution = 8;        ///< bilinear: the grid's side (CNR relight's default)
    bool exact = false;        ///< rfd's variant: float planes of linear light
    int quality = 95;          ///< the planes' JPEG quality
};

/// info.json, decoded.
struct FitFile {
    FitType type = FitType::Ptm;
    Basis basis = Basis::Ptm;  ///< ptm / hsh: the functions (hsh: from nplanes)
    int width = 0, height = 0;
    int nplanes = 0;
    bool exact = false;
    int quality = 95;
    std::vector<Eigen::Vector3d> lights;
    double sigma = 0.0;
    int resolution = 0;                      ///< bilinear: the grid's side
    std::vector<double> scale, bias, range;  ///< per plane
    Eigen::MatrixXd mean;                    ///< rbf, bilinear: nodes x 3, decoded (nodes: lights, or R^2)
    std::vector<Eigen::MatrixXd> components; ///< rbf, bilinear: per plane nodes x 3, decoded

    /// Whether the planes are principal components (colorspace mrgb).
    bool principal() const { return type == FitType::Rbf || type == FitType::Bilinear; }
    int jpegs() const { return (nplanes + 2) / 3; }
    std::filesystem::path plane_file(const std::filesystem::path& folder, int j) const;
    /// The value of colour channel c under a light toward unit d is
    /// offset[c] + sum_p weights(c, p) v_p (display units, or linear for the exact variant).
    void light_weights(const Eigen::Vector3d& d, Eigen::Matrix3Xd& weights, Eigen::Vector3d& offset) const;
};

/// Reads `folder`/info.json (or the file itself). InputError naming the file and the field
/// for anything the rules above cannot use (an unknown type or colour space, arrays of the
/// wrong length, a basis byte count that does not match); IoError when it cannot be read.
FitFile read_fit(const std::filesystem::path& folder);

/// How a fit went.
struct FitReport {
    FitFile file;
    std::size_t sampled_pixels = 0;  ///< behind the ranges (and rbf's components, sigma)
    double kept_variance = 1.0;      ///< rbf, bilinear: share of the samples' variance the planes keep
    std::size_t clipped = 0;         ///< plane samples outside their range, clamped (jpg)
};

/// Fits `field` (1 or 3 channels; grey is fitted as three equal channels) and writes
/// `folder`: a sample of pixels first (for the planes' ranges, and rbf's principal
/// components and sigma), then every pixel, a band of rows at a time. info.json is written
/// last and any earlier one removed first, so the folder never pairs new planes with an old
/// info.json. InputError for a spec the format cannot hold or lights that cannot carry it.
FitReport fit_field(FieldReader& field, const FitSpec& spec, const std::filesystem::path& folder);

/// The fit relit under a distant light toward each of `directions` (unit, field frame),
/// image j written to `outs[j]` (encoding by extension, as write_image()), linear light,
/// a band of rows at a time.
void render_fit_to_files(const std::filesystem::path& folder, const std::vector<Eigen::Vector3d>& directions,
                         const std::vector<std::filesystem::path>& outs);
/// The same into memory.
std::vector<Image> render_fit(const std::filesystem::path& folder, const std::vector<Eigen::Vector3d>& directions);

}  // namespace rfd::relight
