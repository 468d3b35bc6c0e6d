#pragma once
// How well a sparse field predicts a denser reference (thesis 5.2, figure 5.4): every
// reference image R_ref,j is compared with the sparse field relit by a directional light of
// unit irradiance from the reference's direction d_j, sum_i l_i(d_j) R_i (eq. 4.1).
//
// total_squared_error = sum over j, pixels and channels of (relit - R_ref,j)^2;
// psnr = 10 log10(peak^2 / mse), mse = total / (samples of all reference images), peak = the
// largest sample of all reference images (linear units); +inf when the error is 0, -inf for
// an all-black reference with a non-zero error.
// The weights are computed once per reference direction; directions are processed in
// parallel, each summed in a fixed order, so the result does not depend on the threads.
//
// Example: Evaluation e = evaluate(read_field("sparse"), read_field("dense"));

#include <array>
#include <vector>

#include <Eigen/Core>

#include "relight/basis.hpp"
#include "relight/field.hpp"
#include "relight/interpolation.hpp"
#include "relight/light_model.hpp"
#include "relight/render.hpp"

namespace rfd::relight {

struct Evaluation {
    double total_squared_error = 0.0;   ///< sum over reference directions, pixels, channels
    double psnr = 0.0;                  ///< dB, peak = max reference sample
    double peak = 0.0;                  ///< that largest reference sample (linear)
    double samples_per_entry = 0.0;     ///< samples behind each per_direction entry (one image)
    std::vector<double> per_direction;  ///< squared error per reference direction, reference order

    /// PSNR of per_direction[j] alone, against the same peak.
    double entry_psnr(std::size_t j) const;
};

/// Throws InputError when the fields' images differ in shape or a field is empty, and what
/// SphericalInterpolator throws for the sparse field's directions.
Evaluation evaluate(const ReflectanceField& sparse, const ReflectanceField& reference,
                    Interpolation method = Interpolation::Delaunay);

/// The same score under each of `lights` instead of every reference direction: both fields
/// relit (render()) and compared, one entry of per_direction per light; peak = the largest
/// sample of the reference's relit images. For area lights and environment maps, where
/// interpolation errors average out or not.
struct LightEvaluation {
    Evaluation score;
    std::vector<Image> relit;            ///< the sparse field under each light
    std::vector<Image> reference_relit;  ///< the reference under each light
};

/// InputError as evaluate(), and for no lights or a light check_light() rejects.
LightEvaluation evaluate_under_lights(const ReflectanceField& sparse, const ReflectanceField& reference,
                                      const std::vector<Light>& lights, Interpolation method = Interpolation::Delaunay);

/// Leave-one-out on a field alone, as RTI fits are judged: every image predicted from the
/// others (interpolated with that image left out of the triangulation) and compared with it,
/// the field read a band of rows at a time. Two PSNRs, labelled wherever they are printed:
///  - in 8-bit sRGB codes, peak 255, the prediction encoded as an 8-bit file would store it:
///    what RTI papers and tools quote, given for fields of 8-bit images;
///  - linear, peak the field's brightest sample (relight eval's other scores);
/// and SSIM of the 8-bit sRGB pictures.
struct LeaveOneOut {
    std::vector<Eigen::Vector3d> directions;   ///< of the held-out images, field order
    std::vector<double> squared_error;         ///< linear, summed over each image's samples
    std::vector<double> code_squared_error;    ///< in 8-bit codes; empty unless the images are 8-bit
    /// SSIM of the 8-bit sRGB pictures (the prediction and the image as 8-bit files store
    /// them), the mean over blocks of kSsimBlock x kSsimBlock pixels of each channel.
    std::vector<double> ssim;
    double peak = 0.0;                         ///< the field's brightest sample (linear)
    double samples_per_image = 0.0;

    bool eight_bit() const { return !code_squared_error.empty(); }
    double psnr_linear(std::size_t j) const;
    double psnr_srgb8(std::size_t j) const;
    /// Means over the held-out images of their PSNRs, as RTI evaluations average them
    /// (images with NaN errors left out).
    double mean_psnr_linear() const;
    double mean_psnr_srgb8() const;
    double mean_ssim() const;
};

/// The SSIM blocks of LeaveOneOut: 8 x 8 pixels, as Wang et al. (2004) first windowed it, side
/// by side so that a field read in bands of whole blocks is scored on the same blocks in any band size.
inline constexpr int kSsimBlock = 8;

/// InputError for a field of fewer than 4 images, or one whose directions left one out do
/// not triangulate (SphericalInterpolator).
/// `band_bytes` bounds a band (FieldReader::band_rows).
LeaveOneOut leave_one_out(FieldReader& field, Interpolation method = Interpolation::Delaunay,
                          std::size_t band_bytes = FieldReader::kBandBytes);
/// The same for a fitted basis (relight/basis.hpp), each light's prediction that of the fit
/// without it (in closed form). A light the others cannot determine the fit without (leverage
/// 1) has NaN errors and is left out of the means.
LeaveOneOut leave_one_out(FieldReader& field, const BasisFit& fit, std::size_t band_bytes = FieldReader::kBandBytes);

/// The same for several models at once (relight/light_model.hpp), the field read once: each
/// light predicted by the row of its model's leave-one-out matrix. Lights a model cannot
/// predict have NaN errors.
std::vector<LeaveOneOut> leave_one_out(FieldReader& field, const std::vector<const LightWeights*>& models,
                                       std::size_t band_bytes = FieldReader::kBandBytes);

/// Sum of (w0 a + w1 b + w2 c - reference)^2 over every sample (weights of images a, b, c;
/// pass the same image with weight 0 for unused slots). Fixed order, vectorisable.
double relit_squared_error(const Image& reference, const std::array<const Image*, 3>& images,
                           const std::array<float, 3>& weights);

}  // namespace rfd::relight
