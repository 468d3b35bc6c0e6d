#pragma once
// Lenslet lattices: the arrangement of lenslet centres in a lens array.
//
// Frame: the array's own plane, x to the right and y up as seen by the observer, origin at
// the centre of the array (the mean of all lenslet centres), millimetres.
//
// Rectangular: count_x by count_y cells of pitch_x by pitch_y; every cell a rectangle.
// Hexagonal: rows along x with centre spacing `pitch`, rows spaced pitch*sqrt(3)/2 apart and
// odd rows shifted by pitch/2. Every cell is a regular hexagon with two flat sides facing
// +-x (inradius pitch/2 along x, the "flat" direction) and corners at +-y (circumradius
// pitch/sqrt(3), the "corner" direction). Cell area pitch^2*sqrt(3)/2.
//
// Which cell a point belongs to is decided by the nearest centre (the Voronoi cell). A point
// on a shared edge goes to one of its cells deterministically: within a row to the higher
// column (x/pitch rounds half up), between the rows of a hexagonal lattice to the lower
// row, between the rows of a rectangular lattice to the higher row.
// Centres are always computed from the floating-point lattice, never by accumulation.
//
// Example: Lattice::hexagonal(2.358, 40, 40).cell_at({0.3, -1.2})

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <vector>

#include <Eigen/Core>

namespace rfd::optics {

enum class LatticeKind : std::uint8_t { Hexagonal, Rectangular };

/// Index of a lattice cell; cells of the array have 0 <= i < count_x and 0 <= j < count_y,
/// cells outside the array have indices outside that range.
struct CellIndex {
    int i = 0;  ///< column
    int j = 0;  ///< row
    friend bool operator==(CellIndex, CellIndex) = default;
};

class Lattice {
public:
    static Lattice hexagonal(double pitch, int count_x, int count_y);
    static Lattice rectangular(double pitch_x, double pitch_y, int count_x, int count_y);

    LatticeKind kind() const { return kind_; }
    int count_x() const { return count_x_; }
    int count_y() const { return count_y_; }
    /// Centre-to-centre distance along x.
    double pitch_x() const { return pitch_x_; }
    /// Row spacing along y (pitch*sqrt(3)/2 for hexagonal lattices).
    double pitch_y() const { return pitch_y_; }
    /// Lenslets per square millimetre.
    double density_per_mm2() const;
    /// Area of one cell in square millimetres.
    double cell_area() const;

    /// Centre of cell (i, j); defined for cells outside the array too.
    Eigen::Vector2d center(CellIndex cell) const {
        return kind_ == LatticeKind::Hexagonal ? center_of<LatticeKind::Hexagonal>(cell)
                                               : center_of<LatticeKind::Rectangular>(cell);
    }
    /// The cell whose Voronoi region contains `point` (may lie outside the array).
    CellIndex cell_at(const Eigen::Vector2d& point) const {
        return kind_ == LatticeKind::Hexagonal ? cell_at_of<LatticeKind::Hexagonal>(point)
                                               : cell_at_of<LatticeKind::Rectangular>(point);
    }
    bool contains(CellIndex cell) const {
        return (cell.i >= 0) & (cell.j >= 0) & (cell.i < count_x_) & (cell.j < count_y_);
    }
    /// True when `point` lies in the (closed) region of `cell`; cheaper than cell_at().
    bool cell_contains(CellIndex cell, const Eigen::Vector2d& point) const {
        return kind_ == LatticeKind::Hexagonal
                   ? cell_contains_of<LatticeKind::Hexagonal>(cell, point)
                   : cell_contains_of<LatticeKind::Rectangular>(cell, point);
    }

    // The same three for a kind known at compile time, for loops over many rays: inline
    // and free of branches, so batch tracers vectorise them. Precondition: K == kind().
    template <LatticeKind K>
    Eigen::Vector2d center_of(CellIndex cell) const {
        return {origin_.x() + cell.i * pitch_x_ + row_shift_of<K>(cell.j),
                origin_.y() + cell.j * pitch_y_};
    }
    template <LatticeKind K>
    CellIndex cell_at_of(const Eigen::Vector2d& point) const {
        // Plain scalars: Eigen's 2-vector packets cost more here than they save.
        const double x = point.x() - origin_.x();
        const double y = point.y() - origin_.y();
        if constexpr (K == LatticeKind::Rectangular) {
            return {floor_to_int(x * inverse_pitch_x_ + 0.5), floor_to_int(y * inverse_pitch_y_ + 0.5)};
        } else {
            // The nearest centre lies in the nearest row or in the neighbouring row on the
            // point's side of it (rows are pitch*sqrt(3)/2 apart, cells reach
            // pitch/sqrt(3)). Arithmetic on 0/1 values: the row side is random from ray to
            // ray, and branches on it would mispredict half the time.
            const double row_position = y * inverse_pitch_y_;
            const int j0 = floor_to_int(row_position + 0.5);
            const int j1 = j0 + 2 * static_cast<int>(row_position >= j0) - 1;
            const double shift0 = row_shift_of<K>(j0);
            const double shift1 = row_shift_of<K>(j1);
            const int i0 = floor_to_int((x - shift0) * inverse_pitch_x_ + 0.5);
            const int i1 = floor_to_int((x - shift1) * inverse_pitch_x_ + 0.5);
            const double dx0 = x - (i0 * pitch_x_ + shift0), dy0 = y - j0 * pitch_y_;
            const double dx1 = x - (i1 * pitch_x_ + shift1), dy1 = y - j1 * pitch_y_;
            const double d0 = dx0 * dx0 + dy0 * dy0;
            const double d1 = dx1 * dx1 + dy1 * dy1;
            // On a tie (a point on the shared edge) the lower row wins, deterministically.
            const int second = static_cast<int>(d1 < d0) |
                               (static_cast<int>(d1 == d0) & static_cast<int>(j1 < j0));
            return {i0 + second * (i1 - i0), j0 + second * (j1 - j0)};
        }
    }
    template <LatticeKind K>
    bool cell_contains_of(CellIndex cell, const Eigen::Vector2d& point) const {
        const double x = point.x() - (origin_.x() + cell.i * pitch_x_ + row_shift_of<K>(cell.j));
        const double y = point.y() - (origin_.y() + cell.j * pitch_y_);
        const double half = 0.5 * pitch_x_;
        const double ax = x < 0 ? -x : x;
        if constexpr (K == LatticeKind::Rectangular) {
            return (ax <= half) & ((y < 0 ? -y : y) <= 0.5 * pitch_y_);
        } else {
            // Face normals of the hexagon at 0, 60 and 120 degrees (0.866... = sqrt(3)/2).
            const double a = 0.5 * x + 0.8660254037844386 * y;
            const double b = -0.5 * x + 0.8660254037844386 * y;
            return (ax <= half) & ((a < 0 ? -a : a) <= half) & ((b < 0 ? -b : b) <= half);
        }
    }

    /// Where the horizontal line at height `y` leaves the region of `cell` toward +x (the
    /// right end of the cell's chord on that line), for scan-line loops over many points.
    /// Edge rounding aside, points of the line left of it and right of the region's left end
    /// belong to `cell`. Precondition: K == kind().
    template <LatticeKind K>
    double cell_exit_x_of(CellIndex cell, double y) const {
        const double half = 0.5 * pitch_x_;
        const double centre_x = origin_.x() + cell.i * pitch_x_ + row_shift_of<K>(cell.j);
        if constexpr (K == LatticeKind::Rectangular) {
            (void)y;
            return centre_x + half;
        } else {
            // The flat side at +pitch/2, or a slanted side (x = pitch - sqrt(3)|dy|) nearer the corners.
            const double dy = std::abs(y - (origin_.y() + cell.j * pitch_y_));
            return centre_x + std::min(half, pitch_x_ - 1.7320508075688772 * dy);
        }
    }

    /// Corners of a cell relative to its centre, counter-clockwise (4 or 6 of them).
    std::vector<Eigen::Vector2d> cell_corners() const;
    /// Largest distance from a cell's centre to its boundary (the corner distance).
    double circumradius() const;
    /// Distance from the centre to the cell boundary along the unit direction `dir`.
    double boundary_distance(const Eigen::Vector2d& dir) const;
    /// Half-extent of the whole array (outer cell boundaries) along x and y: the wider
    /// side, as a hexagonal array with an odd number of rows reaches further to +x.
    Eigen::Vector2d half_extent() const;
    /// Linear index (j * count_x + i) of a cell inside the array.
    std::size_t linear_index(CellIndex cell) const {
        return static_cast<std::size_t>(cell.j) * static_cast<std::size_t>(count_x_) +
               static_cast<std::size_t>(cell.i);
    }

private:
    // floor() to int without the libm call the default x86-64 target makes of std::floor.
    // Beyond 2^30 cells (and for NaN) v is clamped: such a point is far outside any array,
    // and converting it unclamped would overflow the int. Branch-free (min/max), so it
    // vectorises in batch loops.
    static int floor_to_int(double v) {
        v = v > -0x1p30 ? v : -0x1p30;  // NaN compares false: clamped low
        v = v < 0x1p30 ? v : 0x1p30;
        const int truncated = static_cast<int>(v);
        return truncated - static_cast<int>(v < static_cast<double>(truncated));
    }

    Lattice(LatticeKind kind, double pitch_x, double pitch_y, int count_x, int count_y);
    // x shift of row j: pitch/2 on odd rows of a hexagonal lattice (j & 1 is the floor
    // modulo 2 for negative rows too, in two's complement).
    double row_shift(int j) const {
        return kind_ == LatticeKind::Hexagonal ? row_shift_of<LatticeKind::Hexagonal>(j) : 0.0;
    }
    template <LatticeKind K>
    double row_shift_of(int j) const {
        if constexpr (K == LatticeKind::Hexagonal) return (j & 1) * (0.5 * pitch_x_);
        return 0.0;
    }

    LatticeKind kind_;
    double pitch_x_;
    double pitch_y_;
    int count_x_;
    int count_y_;
    double inverse_pitch_x_;  // multiplications instead of divisions in cell_at()
    double inverse_pitch_y_;
    Eigen::Vector2d origin_;  // centre of cell (0, 0)
};

/// Offsets (mm from a cell's centre) that sample one cell for a worst case: the centre,
/// rings at 0.35, 0.7, 0.9 of the way to the boundary and the boundary itself along 96
/// azimuths, and the corners.
std::vector<Eigen::Vector2d> probe_offsets(const Lattice& lattice);

}  // namespace rfd::optics
