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

#include "relight/field.hpp"
#include "relight/interpolation.hpp"
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

/// Sum of (w0 a + w1 b + w2 c - reference)^2 over every sample (weights of images a, b, c;
/// pass the same image with weight 0 for unused slots). Fixed order, vectorisable.
double relit_squared_error(const Image& reference, const std::array<const Image*, 3>& images,
                           const std::array<float, 3>& weights);

}  // namespace rfd::relight
