#pragma once
// The mounting's fit that the macro-pixels' readings (registration.cpp) and the corner markers
// (marker_tiles.cpp) share: the encoded pattern's point under an array point, Gauss-Newton on
// p = (b_x, b_y, turn, scale error) by central differences, and the jackknife's widening of
// the fit's covariance.
//
// Example: MountingFit fit = fit_mounting([&](const Eigen::Vector4d& p) { return residuals(p); }, start, 3);

#include <functional>
#include <span>

#include <Eigen/Core>

namespace rfd::calibrate {

/// The encoded pattern's point read at array point `c` under mounting p (optics/misalignment.hpp):
/// R(-turn) (c - b) / (1 + scale error).
Eigen::Vector2d pattern_point(const Eigen::Vector4d& p, const Eigen::Vector2d& c);

struct MountingFit {
    Eigen::Vector4d parameters = Eigen::Vector4d::Zero();
    Eigen::Matrix4d covariance = Eigen::Matrix4d::Zero();  ///< from the residuals
};

/// Gauss-Newton from `start` on `residuals` (each step halved until their sum of squares falls;
/// at most 30), the covariance with `linear` more parameters solved inside `residuals` counted
/// out of the degrees of freedom.
MountingFit fit_mounting(const std::function<Eigen::VectorXd(const Eigen::Vector4d&)>& residuals, Eigen::Vector4d start,
                         double linear);

/// Widens `covariance` along each parameter whose delete-a-group jackknife variance over
/// `estimates` (one per group left out) is larger.
void widen_by_jackknife(Eigen::Matrix4d& covariance, std::span<const Eigen::Vector4d> estimates);

}  // namespace rfd::calibrate
