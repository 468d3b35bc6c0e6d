#pragma once
// Implicit relighting with a Bayesian approach (thesis chapter 7).
//
// A scene is photographed n times beside a probe object (a black snooker ball) under lights
// nobody calibrated. A new photograph of the probe alone then says how to light the scene:
// the combination l of the training probes S_i that best explains it also combines the
// training images I_i into the scene under that light, I = sum_i l_i I_i (eq. 7.13).
//
// Training (7.3, 7.4): the probe is cut out of every training image by its bounding box,
// scaled to size x size pixels (orthographic view of a sphere: scale and translation only)
// and masked to its disc. Per colour channel, the PCA of the masked probes by SVD,
// A = [S_i - mean] = U W V^T, gives the prior: coefficients c along the principal
// components u_i are normal with variances sigma_i^2 = w_i^2 / n.
//
// Prediction: for a probe image S, the maximum-a-posteriori coefficients minimise
//     E(c) = |U c + mean - S|^2 + eta sum_i c_i^2 / sigma_i^2            (eq. 7.7)
// at c_i = sigma_i^2 / (sigma_i^2 + eta) u_i^T (S - mean)                   (eq. 7.9),
// which in the training images' own basis is ridge regression with penalty n eta:
//     l~ = V diag(w_i / (w_i^2 + n eta)) U^T (S - mean),
//     l_i = l~_i + (1 - sum_k l~_k) / n                                      (eq. 7.11, 7.12).
// eta = sigma_N^2, the variance of the pixel noise (in squared linear pixel units): 0 is
// the pseudo-inverse, which reproduces the probe's noise with extreme coefficients; larger
// values give a smoother, more conservative light (figure 7.3).
// Second pass (7.4): where the fitted probe goes negative, the negated negative part is
// fitted again with a smaller eta and the coefficients added. It is fitted as a change of
// light: the centred ridge solve plus as much of the mean light as the centred span cannot
// give, so the coefficients sum to 1 plus that (small) amount, not to 2.
//
// Colour: the PCA and the coefficients are per channel, so a coloured light on the probe
// colours the scene.
//
// Example: ImplicitModel model = train_implicit(probes);
//          ImplicitFit fit = implicit_fit(model, crop_probe(photo, box), {.eta = 1e-6});
//          Image scene = relight(training_images, fit.coefficients());

#include <cstddef>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/image.hpp"
#include "relight/render.hpp"
#include "relight/scene.hpp"

namespace rfd::relight {

/// Where the probe sphere lies in an image: its bounding box in continuous image
/// coordinates (x right, y down, (0, 0) the top-left corner of the image).
struct ProbeBox {
    double x = 0.0, y = 0.0, width = 0.0, height = 0.0;
};

/// The default probe resolution (the thesis's 64 x 64, 7.4).
inline constexpr int kProbeSize = 64;

/// Pixel indices (y * size + x) of a size x size probe inside its disc, shrunk by one pixel
/// so that no sample mixes the sphere's rim with the background.
std::vector<int> probe_mask(int size);

/// The probe cut out of `image`: the box mapped onto size x size pixels, low-pass filtered
/// first when that shrinks it, 0 outside the mask. Throws InputError when the box is empty
/// or reaches outside the image.
Image crop_probe(const Image& image, const ProbeBox& box, int size = kProbeSize);

/// The PCA of the training probes, per channel.
struct ImplicitModel {
    int size = kProbeSize;      ///< probe side, pixels
    int channels = 0;
    std::vector<int> mask;      ///< probe_mask(size)
    struct Channel {
        Eigen::VectorXd mean;   ///< masked pixels
        Eigen::MatrixXd u;      ///< masked pixels x rank, orthonormal columns
        Eigen::VectorXd w;      ///< singular values, descending, all > 0
        Eigen::MatrixXd v;      ///< n x rank, orthonormal columns
    };
    std::vector<Channel> pca;   ///< one per channel
    std::size_t count = 0;      ///< training images n
    /// sigma_N^2 estimated from the tail of the spectrum, where the light's smooth
    /// variation has died out and what is left is pixel noise: the median of w_i^2 / M
    /// over the lower half (M masked pixels), averaged over the channels. A starting value
    /// for eta.
    double noise_variance = 0.0;
};

/// The model of `probes` (crop_probe() images of the training photographs, all of one size
/// and channel count, at least 2). Throws InputError for fewer than 2 probes, mixed shapes
/// or non-finite samples.
ImplicitModel train_implicit(const std::vector<Image>& probes);

struct ImplicitOptions {
    double eta = 0.0;                  ///< regularisation, sigma_N^2 (>= 0)
    bool second_pass = true;           ///< refit the negative part of the fitted probe
    double second_pass_eta_scale = 0.25;  ///< the second pass's eta, relative to eta
};

/// The MAP light for one probe image.
struct ImplicitFit {
    Eigen::MatrixXd l;                 ///< n x channels: coefficient of training image i (eq. 7.12)
    Image probe;                       ///< the fitted probe, sum_i l_i S_i (0 outside the mask)
    std::size_t negative_first = 0;    ///< negative masked samples of the first pass's fit
    std::size_t negative_final = 0;    ///< ... and of the final one
    double residual_rms = 0.0;         ///< rms of fit - probe over the masked samples
    /// The coefficients as render.hpp's light coefficients (a grey model repeats its column).
    LightCoefficients coefficients() const;
};

/// Fits `probe` (model.size square, model.channels channels, as crop_probe() makes it).
/// Throws InputError for a probe of another shape, non-finite samples or a negative eta.
ImplicitFit implicit_fit(const ImplicitModel& model, const Image& probe, const ImplicitOptions& options);

/// A probe sphere rendered for designed lighting (thesis 7.5): orthographic view of a
/// sphere filling a size x size image, lit by `lights` without shadows, reflecting with
/// `material` (diffuse, glossy or Phong, constant albedo). Directions in the field frame of
/// core/sphere.hpp (z toward the camera); unlike a field, the probe sees light from the
/// whole sphere. Disks are integrated with 1024 equal-solid-angle points, environment maps
/// averaged to at most 64 x 32 blocks, one direction each (within 2.5 % for a Lambertian
/// probe in a uniform map: the terminator cuts through blocks). 3 channels, 0 outside the disc. Throws InputError for a mirror or glass
/// material or a textured albedo.
Image render_probe(const std::vector<Light>& lights, const Material& material, int size = kProbeSize);

/// Where a set of photographs shows the probe, and the probe's material when it is known
/// (a virtual light stage set; constant albedo). On disk: probe.json beside the training
/// images, {"format": "rfd implicit relighting probe", "probe_box": [x, y, width, height],
/// "probe_material": {"type": "phong", "albedo": [r, g, b], "exponent": e, "ior": n}}.
struct ProbeDescription {
    ProbeBox box;
    std::optional<PhongMaterial> material;
};
void write_probe_description(const std::filesystem::path& file, const ProbeDescription& probe);
/// Throws InputError naming the file and field for anything malformed, IoError when unreadable.
ProbeDescription read_probe_description(const std::filesystem::path& file);

/// A model on disk: a folder with implicit.json (the probe box and size, the training
/// images, the singular values, the noise estimate) and the matrices as float EXR images:
/// probe_mean.exr (size x size), probe_u.exr (rank x masked pixels), probe_v.exr (rank x n),
/// one channel per colour channel.
struct ImplicitModelFiles {
    ImplicitModel model;
    ProbeBox box;                                   ///< where the training images show the probe
    std::vector<std::filesystem::path> images;      ///< the training images (absolute or relative to the cwd)
    /// The probe's material when known (a virtual light stage set): predict renders synthetic
    /// probes for designed lighting with it. Constant albedo.
    std::optional<PhongMaterial> probe_material;
};

/// Writes `files` to `folder` (created if needed); implicit.json goes last, so an interrupted
/// write leaves no readable model. Image paths are stored relative to the folder.
void write_implicit_model(const std::filesystem::path& folder, const ImplicitModelFiles& files);
/// Reads a model. Throws InputError naming the file and field for anything malformed.
ImplicitModelFiles read_implicit_model(const std::filesystem::path& folder);

/// The images of a field (a folder holding one .lp, or the .lp) in light-file order.
std::vector<std::filesystem::path> field_image_files(const std::filesystem::path& field);
/// Training images: a field (its directions are ignored) or a folder of images (.exr, .hdr,
/// .png, .jpg, .tif) in name order. InputError when fewer than 2.
std::vector<std::filesystem::path> training_image_files(const std::filesystem::path& training);
/// The scene's probe: the object called `name`, or without a name its only sphere of a
/// Phong material. InputError naming `scene_file` otherwise.
const SceneObject& probe_object(const Scene& scene, const std::string& name, const std::string& scene_file);

}  // namespace rfd::relight
