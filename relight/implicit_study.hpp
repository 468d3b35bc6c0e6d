#pragma once
// Implicit relighting on the virtual light stage (thesis 7.4, figure 7.3): the lights of a
// training set and of held-out test lights, camera noise, and the study of the
// regularisation eta against ground truth.
//
// Training lights stand in for the thesis's hand-held lamp pointed at white walls: extended,
// overlapping, nobody measures them. Held-out lights are smooth too (natural light is), but
// narrower on average and placed at random, so they ask for detail the training set can only
// approximate, as a real new light does.
//
// Noise regimes. eta = sigma_N^2 buys nothing when the new probe is as clean as the training
// probes: the noise then floors the training spectrum at about sigma^2 M (M masked pixels),
// and the MAP shrink factor at eta = sigma^2 is M / (M + n), close to 1. It pays when the new
// probe is noisier than the training set, as with an LDR snapshot of the probe against an
// HDR training capture (7.4, figure 7.5): the pseudo-inverse then fits the probe's noise with
// extreme coefficients. The study reports whichever regime it is given.
//
// Example: auto lights = implicit_training_lights(272, 1);
//          EtaStudy study = study_eta(model, training_images, test_probes, references, etas);

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <nlohmann/json.hpp>

#include "core/csv.hpp"
#include "core/image.hpp"
#include "relight/implicit.hpp"
#include "relight/light_kernel.hpp"

namespace rfd::relight {

/// One light of the virtual stage: direction (unit, toward the light, field frame) and kernel.
struct StageLight {
    Eigen::Vector3d direction;
    LightKernel kernel;
};

/// `count` training lights: near-uniform directions over the upper hemisphere
/// (repulsion_pattern(count, seed)) with smooth kernels whose radii cycle through 15, 25 and
/// 40 degrees, so each light overlaps many neighbours (272 lights are about 9 degrees apart).
std::vector<StageLight> implicit_training_lights(std::size_t count, std::uint64_t seed);

/// `count` held-out lights: directions uniform over the hemisphere above `min_elevation`,
/// smooth kernels with radii uniform in [min_radius, max_radius] (radians; defaults 15, 10
/// and 25 degrees), deterministic for the seed.
std::vector<StageLight> held_out_lights(std::size_t count, std::uint64_t seed,
                                        double min_elevation = 0.2617993877991494,
                                        double min_radius = 0.17453292519943295,
                                        double max_radius = 0.4363323129985824);

/// Adds zero-mean gaussian noise of standard deviation `sigma` to every sample, a camera's
/// read and shot noise at one exposure. Deterministic for the seed (a standard-specified
/// engine and Box-Muller, so the same on every platform). Throws InputError for a negative
/// or non-finite sigma.
void add_camera_noise(Image& image, double sigma, std::uint64_t seed);

/// One eta of the study.
struct EtaStudyPoint {
    double eta = 0.0;
    double psnr = 0.0;                 ///< dB over all test lights: peak = the largest reference
                                       ///< sample, mse over every sample (evaluate.hpp's convention)
    std::vector<double> light_psnr;    ///< dB per test light, the same peak
    double probe_residual_rms = 0.0;   ///< of the probe fit, rms over the test lights
    double max_abs_coefficient = 0.0;  ///< largest |l_i| over the test lights: the pseudo-inverse's tell
};

struct EtaStudy {
    std::vector<EtaStudyPoint> points;  ///< in the order of the etas given
    std::size_t best = 0;               ///< index of the highest psnr
};

/// Relights the scene for every test probe with every eta and compares it with the
/// reference: `training_images` are the n images the model was trained on (in order),
/// `test_probes` the crop_probe() images of the test photographs, `references` the scene
/// under the same lights without noise. Throws InputError for mismatched counts or shapes,
/// no etas, a negative or non-finite eta, or an all-black reference set.
EtaStudy study_eta(const ImplicitModel& model, const std::vector<Image>& training_images,
                   const std::vector<Image>& test_probes, const std::vector<Image>& references,
                   const std::vector<double>& etas, bool second_pass = true);

/// The default etas of a study: 0 (the pseudo-inverse), then half decades from 1e-6 to 1e2
/// times the mean square of the model's mean probe (eta is in squared pixel units, so the
/// grid follows the probe's brightness).
std::vector<double> default_eta_grid(const ImplicitModel& model);

// ---- `rfd relight implicit sweep`: the study from files to a report ----------------------

/// Every training image of a model, checked to share the first one's size and channels
/// (InputError naming the file and both sizes otherwise).
std::vector<Image> read_training_images(const std::vector<std::filesystem::path>& files);

/// A held-out set as `rfd capture implicit` writes test/: photos/ (fields of photographs
/// showing the probe) and truth/ (the scene under the same lights, clean). Each image must
/// have the training images' shape; the probes are cropped with the model's box.
struct HeldOutSet {
    std::vector<Image> probes, truths;
    std::vector<Image> photos;  ///< the first `examples` photographs, for the comparison images
};
HeldOutSet read_held_out_set(const std::filesystem::path& folder, const ImplicitModelFiles& files,
                             const Image& training_shape, std::size_t examples);

/// FOLDER/eta_psnr.{csv,gp,svg,png} (a warning on stderr when gnuplot is missing),
/// eta_sweep.csv, and per example light_NN.png (truth | eta 0 | best eta | largest eta, one
/// exposure) and light_NN_probe.png. Returns whether the chart was drawn.
bool write_eta_sweep_report(const std::filesystem::path& folder, const EtaStudy& study, const ImplicitModel& model,
                            const std::vector<Image>& training, const HeldOutSet& held_out, bool second_pass);

/// The coefficients l_i of a fit, one row per training image (its file name), one column per
/// channel.
CsvTable coefficient_table(const ImplicitFit& fit, const std::vector<std::filesystem::path>& images);

/// The study for --json and as text; `model_name` is the model's folder as given.
nlohmann::json eta_sweep_json(const EtaStudy& study, const ImplicitModel& model, const std::string& model_name,
                              std::size_t test_lights, bool second_pass, bool charted);
std::string eta_sweep_text(const EtaStudy& study, const std::string& model_name, const std::string& folder,
                           std::size_t test_lights, std::size_t examples);

}  // namespace rfd::relight
