#include "calibrate/mounting_fit.hpp"

#include <algorithm>
#include <cmath>

#include <Eigen/Dense>

namespace rfd::calibrate {

Eigen::Vector2d pattern_point(const Eigen::Vector4d& p, const Eigen::Vector2d& c) {
    const double cs = std::cos(p(2)), sn = std::sin(p(2));
    const Eigen::Vector2d d = c - p.head<2>();
    return Eigen::Vector2d(cs * d.x() + sn * d.y(), -sn * d.x() + cs * d.y()) / (1.0 + p(3));
}

MountingFit fit_mounting(const std::function<Eigen::VectorXd(const Eigen::Vector4d&)>& residuals, Eigen::Vector4d p,
                         double linear) {
    const Eigen::Vector4d step(1e-3, 1e-3, 1e-5, 1e-5);
    Eigen::VectorXd r = residuals(p);
    Eigen::MatrixXd jacobian(r.size(), 4);
    for (int iteration = 0; iteration < 30; ++iteration) {
        for (int i = 0; i < 4; ++i) {
            Eigen::Vector4d plus = p, minus = p;
            plus(i) += step(i);
            minus(i) -= step(i);
            jacobian.col(i) = (residuals(plus) - residuals(minus)) / (2.0 * step(i));
        }
        const Eigen::Vector4d delta = -(jacobian.transpose() * jacobian).ldlt().solve(jacobian.transpose() * r);
        // Halve the step until the residual falls.
        double scale = 1.0;
        Eigen::VectorXd trial;
        for (; scale > 1e-3; scale *= 0.5) {
            trial = residuals(p + scale * delta);
            if (trial.squaredNorm() <= r.squaredNorm()) break;
        }
        if (scale <= 1e-3) break;
        p += scale * delta;
        r = trial;
        if ((scale * delta).cwiseQuotient(step).cwiseAbs().maxCoeff() < 1e-3) break;
    }
    MountingFit fit;
    fit.parameters = p;
    const double dof = std::max(1.0, static_cast<double>(r.size()) - 4 - linear);
    fit.covariance = (jacobian.transpose() * jacobian).inverse() * (r.squaredNorm() / dof);
    return fit;
}

void widen_by_jackknife(Eigen::Matrix4d& covariance, std::span<const Eigen::Vector4d> estimates) {
    const auto groups = static_cast<double>(estimates.size());
    Eigen::Vector4d mean = Eigen::Vector4d::Zero();
    for (const Eigen::Vector4d& e : estimates) mean += e / groups;
    Eigen::Matrix4d jackknife = Eigen::Matrix4d::Zero();
    for (const Eigen::Vector4d& e : estimates) jackknife += (e - mean) * (e - mean).transpose();
    jackknife *= (groups - 1.0) / groups;
    for (int i = 0; i < 4; ++i)
        if (jackknife(i, i) > covariance(i, i)) {
            const double ratio = std::sqrt(jackknife(i, i) / covariance(i, i));
            covariance.row(i) *= ratio;
            covariance.col(i) *= ratio;
        }
}

}  // namespace rfd::calibrate
