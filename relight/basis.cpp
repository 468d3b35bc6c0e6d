#include "relight/basis.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include <Eigen/QR>

#include "core/error.hpp"
#include "core/units.hpp"

namespace rfd::relight {
namespace {

// OpenLIME's lowest elevation for hemispherical harmonics: lights nearer the horizon are
// evaluated as if at it.
constexpr double kMinElevation = 0.15;

// The associated Legendre function P_l^m(t), m >= 0, without the Condon-Shortley phase.
double legendre(int l, int m, double t) {
    const double s = std::sqrt(std::max(0.0, 1.0 - t * t));
    double pmm = 1.0;
    for (int i = 1; i <= m; ++i) pmm *= (2.0 * i - 1.0) * s;
    if (l == m) return pmm;
    double pmm1 = t * (2.0 * m + 1.0) * pmm;
    for (int ll = m + 2; ll <= l; ++ll) {
        const double pll = ((2.0 * ll - 1.0) * t * pmm1 - (ll + m - 1.0) * pmm) / (ll - m);
        pmm = pmm1;
        pmm1 = pll;
    }
    return pmm1;
}

double factorial(int n) {
    double f = 1.0;
    for (int i = 2; i <= n; ++i) f *= i;
    return f;
}

}  // namespace

int basis_size(Basis basis) {
    switch (basis) {
    case Basis::Ptm: return 6;
    case Basis::Hsh2: return 4;
    case Basis::Hsh3: return 9;
    case Basis::Hsh4: return 16;
    }
    return 0;
}

Eigen::VectorXd basis_values(Basis basis, const Eigen::Vector3d& d) {
    Eigen::VectorXd b(basis_size(basis));
    if (basis == Basis::Ptm) {
        b << 1.0, d.x(), d.y(), d.x() * d.x(), d.x() * d.y(), d.y() * d.y();
        return b;
    }
    const int degrees = basis == Basis::Hsh2 ? 2 : basis == Basis::Hsh3 ? 3 : 4;
    const double theta = std::min(std::acos(std::clamp(d.z(), -1.0, 1.0)), kPi / 2.0 - kMinElevation);
    const double phi = std::atan2(d.y(), d.x());
    const double t = 2.0 * std::cos(theta) - 1.0;  // the hemisphere's shift of the argument
    Eigen::Index k = 0;
    for (int l = 0; l < degrees; ++l)
        for (int m = l; m >= -l; --m) {
            const int a = std::abs(m);
            const double norm = std::sqrt((2.0 * l + 1.0) / (2.0 * kPi) * factorial(l - a) / factorial(l + a));
            const double azimuth = m > 0 ? std::sqrt(2.0) * std::cos(m * phi)
                                   : m < 0 ? std::sqrt(2.0) * std::sin(a * phi)
                                           : 1.0;
            const double sign = a == 2 ? -1.0 : 1.0;  // as OpenLIME writes its m = +-2 functions
            b[k++] = sign * norm * legendre(l, a, t) * azimuth;
        }
    return b;
}

BasisFit::BasisFit(Basis basis, const std::vector<Eigen::Vector3d>& directions) : basis_(basis) {
    const auto n = static_cast<Eigen::Index>(directions.size());
    const int m = basis_size(basis);
    const std::string name(name_of(kBasisNames, basis));
    if (n < m)
        throw InputError("basis " + name + " has " + std::to_string(m) + " functions; the field has " +
                         std::to_string(n) + " lights, fewer than it needs");
    design_.resize(n, m);
    for (Eigen::Index i = 0; i < n; ++i) design_.row(i) = basis_values(basis, directions[static_cast<std::size_t>(i)]);
    Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(design_);
    qr.setThreshold(1e-10);
    if (qr.rank() < m)
        throw InputError("the field's " + std::to_string(n) + " lights leave " + std::to_string(m - qr.rank()) +
                         " combination(s) of basis " + name +
                         "'s functions unseen (lights on one circle, or all at one elevation): choose a smaller basis");
    solve_ = qr.solve(Eigen::MatrixXd::Identity(n, n));
    leverage_ = (design_ * solve_).diagonal();
}

}  // namespace rfd::relight
