#include "optics/lattice.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "core/error.hpp"
#include "core/units.hpp"

namespace rfd::optics {
namespace {
constexpr double kSqrt3 = 1.7320508075688772;


}  // namespace

Lattice Lattice::hexagonal(double pitch, int count_x, int count_y) {
    return Lattice(LatticeKind::Hexagonal, pitch, pitch * kSqrt3 / 2.0, count_x, count_y);
}

Lattice Lattice::rectangular(double pitch_x, double pitch_y, int count_x, int count_y) {
    return Lattice(LatticeKind::Rectangular, pitch_x, pitch_y, count_x, count_y);
}

Lattice::Lattice(LatticeKind kind, double pitch_x, double pitch_y, int count_x, int count_y)
    : kind_(kind),
      pitch_x_(pitch_x),
      pitch_y_(pitch_y),
      count_x_(count_x),
      count_y_(count_y),
      inverse_pitch_x_(1.0 / pitch_x),
      inverse_pitch_y_(1.0 / pitch_y) {
    RFD_CHECK(pitch_x > 0.0 && pitch_y > 0.0 && count_x > 0 && count_y > 0);
    // Put the mean of all centres at the origin. In a hexagonal lattice with more than one
    // row, half the rows are shifted by pitch/2, so the mean shift is about pitch/4.
    double mean_shift = 0.0;
    if (kind_ == LatticeKind::Hexagonal) {
        const int odd_rows = count_y_ / 2;
        mean_shift = 0.5 * pitch_x_ * odd_rows / count_y_;
    }
    origin_ = Eigen::Vector2d(-0.5 * (count_x_ - 1) * pitch_x_ - mean_shift,
                              -0.5 * (count_y_ - 1) * pitch_y_);
}


double Lattice::cell_area() const { return pitch_x_ * pitch_y_; }

double Lattice::density_per_mm2() const { return 1.0 / cell_area(); }


std::vector<Eigen::Vector2d> Lattice::cell_corners() const {
    if (kind_ == LatticeKind::Rectangular) {
        const double hx = pitch_x_ / 2, hy = pitch_y_ / 2;
        return {{hx, -hy}, {hx, hy}, {-hx, hy}, {-hx, -hy}};
    }
    const double r = circumradius();
    std::vector<Eigen::Vector2d> corners;
    for (int k = 0; k < 6; ++k) {
        const double angle = (30.0 + 60.0 * k) * 3.14159265358979323846 / 180.0;
        corners.emplace_back(r * std::cos(angle), r * std::sin(angle));
    }
    return corners;
}

double Lattice::circumradius() const {
    if (kind_ == LatticeKind::Rectangular) return 0.5 * std::hypot(pitch_x_, pitch_y_);
    return pitch_x_ / kSqrt3;
}

double Lattice::boundary_distance(const Eigen::Vector2d& dir) const {
    const Eigen::Vector2d d = dir.normalized();
    if (kind_ == LatticeKind::Rectangular) {
        const double tx = std::abs(d.x()) > 0 ? 0.5 * pitch_x_ / std::abs(d.x()) : HUGE_VAL;
        const double ty = std::abs(d.y()) > 0 ? 0.5 * pitch_y_ / std::abs(d.y()) : HUGE_VAL;
        return std::min(tx, ty);
    }
    // Hexagon with inradius pitch/2 and face normals at 0, 60 and 120 degrees.
    double best = HUGE_VAL;
    for (int k = 0; k < 3; ++k) {
        const double angle = 60.0 * k * 3.14159265358979323846 / 180.0;
        const double c = std::abs(d.x() * std::cos(angle) + d.y() * std::sin(angle));
        if (c > 0) best = std::min(best, 0.5 * pitch_x_ / c);
    }
    return best;
}

Eigen::Vector2d Lattice::half_extent() const {
    if (kind_ == LatticeKind::Rectangular)
        return {0.5 * count_x_ * pitch_x_, 0.5 * count_y_ * pitch_y_};
    // Odd rows reach pitch/2 further right; centring the mean shifts the array left by
    // pitch/4 only for an even number of rows, so with an odd number (> 1) the right
    // side is the wider one.
    const double left = -origin_.x() + 0.5 * pitch_x_;
    const double right = origin_.x() + (count_x_ - 1) * pitch_x_ + row_shift(count_y_ > 1 ? 1 : 0) +
                         0.5 * pitch_x_;
    return {std::max(left, right), 0.5 * (count_y_ - 1) * pitch_y_ + circumradius()};
}

std::vector<Eigen::Vector2d> probe_offsets(const Lattice& lattice) {
    constexpr int kProbeAzimuths = 96;
    constexpr std::array<double, 5> kProbeRadii = {0.0, 0.35, 0.7, 0.9, 1.0};
    std::vector<Eigen::Vector2d> offsets;
    offsets.emplace_back(0.0, 0.0);
    for (int a = 0; a < kProbeAzimuths; ++a) {
        const double phi = 2.0 * kPi * (a + 0.5) / kProbeAzimuths;
        const Eigen::Vector2d dir(std::cos(phi), std::sin(phi));
        const double reach = lattice.boundary_distance(dir);
        for (double r : kProbeRadii)
            if (r > 0.0) offsets.push_back(r * reach * dir);
    }
    for (const Eigen::Vector2d& corner : lattice.cell_corners()) offsets.push_back(corner);
    return offsets;
}

}  // namespace rfd::optics
