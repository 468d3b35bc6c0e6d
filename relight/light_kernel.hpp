#pragma once
// The angular profile of a light-stage light (thesis 4.2, 5.4): a distant light whose
// radiance spreads over a cap of directions around its centre d.
//
// Radiance toward the scene from direction w (unit, toward the light) at angle a = angle(w, d):
//     K(w) = c * f(a)   for a <= radius, 0 beyond,
// with the profile f
//     constant:  f = 1                          (a spotlight with a hard iris, narrow setting)
//     smooth:    f = cos^2(pi a / (2 radius))   (frost filter: C1 fall-off, half maximum at
//                                                a = radius / 2)
//     gaussian:  f = exp(-a^2 / (2 sigma^2))    (truncated at radius = 3 sigma)
// and c chosen so that the integral of K over the sphere is 1: the kernel is a blend of
// directional lights whose irradiances (each measured on a surface facing it) add up to 1,
// the radiometric convention of relight/ (a surface facing the centre then receives
// integral K(w) (w.d) dw, slightly below 1: (1 + cos radius) / 2 for the constant profile).
// radius = 0 is an ideal directional light of unit irradiance (a Dirac K).
// Angles in radians; directions in any frame, as long as d and w share it.
//
// Example: KernelSampler sampler(LightKernel::narrow());
//          Eigen::Vector3d w = sampler.sample(d, 0.3, 0.7);   // distributed like K

#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace rfd::relight {

enum class KernelProfile { Constant, Smooth, Gaussian };

std::string to_string(KernelProfile profile);

struct LightKernel {
    KernelProfile profile = KernelProfile::Constant;
    double radius = 0.0;  ///< angular radius of the support, radians; 0 = directional light
    double sigma = 0.0;   ///< width of the gaussian profile, radians (gaussian only)

    bool is_directional() const { return radius <= 0.0; }

    /// An ideal directional light.
    static LightKernel directional() { return {}; }
    /// The thesis's narrow setting (iris 30 %, no frost: 3.1-4.3 degrees across): constant,
    /// 2 degrees radius.
    static LightKernel narrow();
    /// The thesis's wide setting (iris open, frost filter): smooth, 15 degrees radius, so
    /// 15 degrees across at half maximum.
    static LightKernel wide();
    /// A smooth kernel of the given radius; a gaussian kernel of width sigma (radius 3 sigma).
    static LightKernel smooth(double radius);
    static LightKernel gaussian(double sigma);
};

/// Evaluates and samples one kernel; construction tabulates the radial distribution once
/// (cheap: a few thousand operations), after which every call is constant time and
/// thread-safe.
class KernelSampler {
public:
    explicit KernelSampler(const LightKernel& kernel);

    const LightKernel& kernel() const { return kernel_; }

    /// K at angle `a` (radians) from the centre, per steradian. Zero for a directional light.
    double radiance(double a) const;
    /// K(w) for unit vectors w and centre d (uses an accurate angle).
    double radiance(const Eigen::Vector3d& w, const Eigen::Vector3d& d) const;

    /// A direction distributed with density K around the unit centre d, from two uniform
    /// numbers in [0, 1): u1 picks the angle from d (inverse radial distribution), u2 the
    /// azimuth. Stratified (u1, u2) give stratified directions. Returns d when directional.
    Eigen::Vector3d sample(const Eigen::Vector3d& d, double u1, double u2) const;

    /// Angle from the centre below which a fraction u of the kernel's power lies.
    double quantile_angle(double u) const;

private:
    LightKernel kernel_;
    double normaliser_ = 0.0;            // c in the header comment
    std::vector<double> cdf_;            // radial distribution at angles_ (smooth, gaussian)
    std::vector<double> angles_;
};

/// Two unit vectors completing the unit vector n to a right-handed orthonormal frame
/// (Duff et al. 2017, branchless and continuous except at n.z = -1).
void orthonormal_basis(const Eigen::Vector3d& n, Eigen::Vector3d& b1, Eigen::Vector3d& b2);

}  // namespace rfd::relight
