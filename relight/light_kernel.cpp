#include "relight/light_kernel.hpp"

#include <algorithm>
#include <cmath>

#include "core/error.hpp"
#include "core/sphere.hpp"
#include "core/units.hpp"

namespace rfd::relight {
namespace {

// Radial table resolution for the tabulated profiles: with the midpoint rule its relative
// error in the normalisation is about (1/kTableSize)^2, far below image noise.
constexpr int kTableSize = 4096;

double profile_value(const LightKernel& kernel, double a) {
    if (a > kernel.radius) return 0.0;
    switch (kernel.profile) {
        case KernelProfile::Constant: return 1.0;
        case KernelProfile::Smooth: {
            const double c = std::cos(0.5 * kPi * a / kernel.radius);
            return c * c;
        }
        case KernelProfile::Gaussian: return std::exp(-0.5 * a * a / (kernel.sigma * kernel.sigma));
    }
    return 0.0;
}

}  // namespace

std::string to_string(KernelProfile profile) {
    switch (profile) {
        case KernelProfile::Constant: return "constant";
        case KernelProfile::Smooth: return "smooth";
        case KernelProfile::Gaussian: return "gaussian";
    }
    return "?";
}

LightKernel LightKernel::narrow() { return {KernelProfile::Constant, degrees_to_radians(2.0), 0.0}; }

LightKernel LightKernel::wide() { return smooth(degrees_to_radians(15.0)); }

LightKernel LightKernel::smooth(double radius) { return {KernelProfile::Smooth, radius, 0.0}; }

LightKernel LightKernel::gaussian(double sigma) {
    return {KernelProfile::Gaussian, 3.0 * sigma, sigma};
}

void orthonormal_basis(const Eigen::Vector3d& n, Eigen::Vector3d& b1, Eigen::Vector3d& b2) {
    const double sign = std::copysign(1.0, n.z());
    const double a = -1.0 / (sign + n.z());
    const double b = n.x() * n.y() * a;
    b1 = Eigen::Vector3d(1.0 + sign * n.x() * n.x() * a, sign * b, -sign * n.x());
    b2 = Eigen::Vector3d(b, sign + n.y() * n.y() * a, -n.y());
}

KernelSampler::KernelSampler(const LightKernel& kernel) : kernel_(kernel) {
    if (kernel_.is_directional()) return;
    RFD_CHECK(kernel_.radius < kPi);
    RFD_CHECK(kernel_.profile != KernelProfile::Gaussian || kernel_.sigma > 0.0);
    if (kernel_.profile == KernelProfile::Constant) {
        // Solid angle of a cap: 2 pi (1 - cos r) = 4 pi sin^2(r / 2), accurate for tiny r.
        const double s = std::sin(0.5 * kernel_.radius);
        normaliser_ = 1.0 / (4.0 * kPi * s * s);
        return;
    }
    // Cumulative power integral f(a) sin(a) da, midpoint rule per cell.
    angles_.resize(kTableSize + 1);
    cdf_.resize(kTableSize + 1);
    const double step = kernel_.radius / kTableSize;
    double sum = 0.0;
    angles_[0] = 0.0;
    cdf_[0] = 0.0;
    for (int i = 0; i < kTableSize; ++i) {
        const double mid = (i + 0.5) * step;
        sum += profile_value(kernel_, mid) * std::sin(mid) * step;
        angles_[i + 1] = (i + 1) * step;
        cdf_[i + 1] = sum;
    }
    for (double& value : cdf_) value /= sum;
    normaliser_ = 1.0 / (2.0 * kPi * sum);
}

double KernelSampler::radiance(double a) const {
    if (kernel_.is_directional()) return 0.0;
    return normaliser_ * profile_value(kernel_, a);
}

double KernelSampler::radiance(const Eigen::Vector3d& w, const Eigen::Vector3d& d) const {
    if (kernel_.is_directional()) return 0.0;
    // Cheap rejection before the accurate angle: cos(radius) with a little slack.
    if (w.dot(d) < std::cos(std::min(kPi, kernel_.radius * 1.001 + 1e-9))) return 0.0;
    return radiance(angle_between(w, d));
}

double KernelSampler::quantile_angle(double u) const {
    if (kernel_.is_directional()) return 0.0;
    u = std::clamp(u, 0.0, 1.0);
    if (kernel_.profile == KernelProfile::Constant)
        return 2.0 * std::asin(std::min(1.0, std::sqrt(u) * std::sin(0.5 * kernel_.radius)));
    const auto it = std::upper_bound(cdf_.begin(), cdf_.end(), u);
    if (it == cdf_.end()) return kernel_.radius;
    const auto i = static_cast<std::size_t>(it - cdf_.begin());  // cdf_[i-1] <= u < cdf_[i]
    const double span = cdf_[i] - cdf_[i - 1];
    const double t = span > 0.0 ? (u - cdf_[i - 1]) / span : 0.0;
    return angles_[i - 1] + t * (angles_[i] - angles_[i - 1]);
}

Eigen::Vector3d KernelSampler::sample(const Eigen::Vector3d& d, double u1, double u2) const {
    if (kernel_.is_directional()) return d;
    const double a = quantile_angle(u1);
    const double phi = 2.0 * kPi * u2;
    Eigen::Vector3d b1, b2;
    orthonormal_basis(d, b1, b2);
    const double s = std::sin(a);
    return (std::cos(a) * d + s * (std::cos(phi) * b1 + std::sin(phi) * b2)).normalized();
}

}  // namespace rfd::relight
