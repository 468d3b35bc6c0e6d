#include "optics/lattice.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/error.hpp"

namespace rfd::optics {
namespace {
constexpr double kSqrt3 = 1.7320508075688772;


// floor() to int without the libm call the default x86-64 target makes of std::floor;
// this runs once or more per ray. Beyond 2^30 cells (and for NaN) v is clamped: such a
// point is far outside any array, and converting it unclamped would overflow the int.
inline int floor_to_int(double v) {
    // A well-predicted branch: real rays never take it (NaN goes to -2^30).
    if (!(v > -0x1p30 && v < 0x1p30)) [[unlikely]] v = v > 0.0 ? 0x1p30 : -0x1p30;
    const int truncated = static_cast<int>(v);
    return truncated - (v < static_cast<double>(truncated) ? 1 : 0);
}
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


CellIndex Lattice::cell_at(const Eigen::Vector2d& point) const {
    // Plain scalars: this runs for every ray at every array, and Eigen's 2-vector packets
    // cost more here than they save.
    const double x = point.x() - origin_.x();
    const double y = point.y() - origin_.y();
    if (kind_ == LatticeKind::Rectangular)
        return {floor_to_int(x * inverse_pitch_x_ + 0.5), floor_to_int(y * inverse_pitch_y_ + 0.5)};
    // Hexagonal: the nearest centre lies in the nearest row or in the neighbouring row on
    // the point's side of it (rows are pitch*sqrt(3)/2 apart, cells reach pitch/sqrt(3)).
    // Written without data-dependent branches.
    const double row_position = y * inverse_pitch_y_;
    const int j0 = floor_to_int(row_position + 0.5);
    const int j1 = j0 + (row_position >= j0 ? 1 : -1);
    const double shift0 = (j0 & 1) ? 0.5 * pitch_x_ : 0.0;
    const double shift1 = (j1 & 1) ? 0.5 * pitch_x_ : 0.0;
    const int i0 = floor_to_int((x - shift0) * inverse_pitch_x_ + 0.5);
    const int i1 = floor_to_int((x - shift1) * inverse_pitch_x_ + 0.5);
    const double dx0 = x - (i0 * pitch_x_ + shift0), dy0 = y - j0 * pitch_y_;
    const double dx1 = x - (i1 * pitch_x_ + shift1), dy1 = y - j1 * pitch_y_;
    const double d0 = dx0 * dx0 + dy0 * dy0;
    const double d1 = dx1 * dx1 + dy1 * dy1;
    // On a tie (a point on the shared edge) the lower row wins, deterministically.
    const bool second = d1 < d0 || (d1 == d0 && j1 < j0);
    return {second ? i1 : i0, second ? j1 : j0};
}


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

}  // namespace rfd::optics
