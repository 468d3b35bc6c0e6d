#include "relight/interpolation.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <numeric>
#include <string>
#include <utility>

#include <CGAL/Delaunay_triangulation_3.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Triangulation_vertex_base_with_info_3.h>

#include "core/error.hpp"
#include "core/parallel.hpp"
#include "core/sphere.hpp"
#include "core/units.hpp"
#include "core/text.hpp"

namespace rfd::relight {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using VertexBase = CGAL::Triangulation_vertex_base_with_info_3<std::size_t, Kernel>;
using DataStructure = CGAL::Triangulation_data_structure_3<VertexBase>;
using Delaunay = CGAL::Delaunay_triangulation_3<Kernel, DataStructure>;

constexpr double kBelowHorizonTolerance = degrees_to_radians(5.0);
constexpr double kDuplicateAngle = 1e-6;  // radians
// A query on an edge gives a determinant of rounding size on that edge's side.

double det(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
    return a.dot(b.cross(c));
}

std::vector<Eigen::Vector3d> checked_directions(std::vector<Eigen::Vector3d> directions) {
    if (directions.size() < 3)
        throw InputError("spherical interpolation needs at least 3 light directions, got " +
                         std::to_string(directions.size()));
    const double lowest_z = -std::sin(kBelowHorizonTolerance);
    for (std::size_t i = 0; i < directions.size(); ++i) {
        Eigen::Vector3d& d = directions[i];
        const double norm = d.norm();
        if (!std::isfinite(norm) || norm == 0.0)
            throw InputError("light direction " + std::to_string(i) + " is zero or not finite");
        d /= norm;
        if (d.z() < lowest_z)
            throw InputError("light direction " + std::to_string(i) + " (" + format_direction(d) +
                             ") lies more than 5 degrees below the horizon; fields cover the "
                             "upper hemisphere z > 0");
    }
    // Duplicates would be merged by the triangulation and leave an image without weight.
    std::vector<std::size_t> order(directions.size());
    std::iota(order.begin(), order.end(), std::size_t{0});
    std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
        return directions[a].z() < directions[b].z() || (directions[a].z() == directions[b].z() && a < b);
    });
    for (std::size_t p = 0; p < order.size(); ++p)
        for (std::size_t q = p + 1; q < order.size(); ++q) {
            const Eigen::Vector3d& a = directions[order[p]];
            const Eigen::Vector3d& b = directions[order[q]];
            if (b.z() - a.z() > kDuplicateAngle) break;  // sorted by z: no closer pair ahead
            if (angle_between(a, b) < kDuplicateAngle) {
                const std::size_t i = std::min(order[p], order[q]), j = std::max(order[p], order[q]);
                throw InputError("light directions " + std::to_string(i) + " and " +
                                 std::to_string(j) + " are the same direction (" +
                                 format_direction(directions[i]) + "); each image needs its own");
            }
        }
    return directions;
}

}  // namespace

double spherical_triangle_solid_angle(const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                                      const Eigen::Vector3d& c) {
    const double numerator = std::abs(det(a, b, c));
    const double denominator = 1.0 + a.dot(b) + b.dot(c) + c.dot(a);
    return 2.0 * std::atan2(numerator, denominator);
}

// Lat-long cells over the whole sphere; per cell the triangles whose bounding cap meets the
// cell's bounding cap, and the directions that can be nearest to a point in the cell.
struct SphericalInterpolator::Grid {
    int rows = 0, cols = 0;
    std::vector<std::uint32_t> triangle_offsets, triangle_list;
    std::vector<std::uint32_t> nearest_offsets, nearest_list;

    std::size_t cell_of(const Eigen::Vector3d& d) const {
        const double theta = std::acos(std::clamp(d.z(), -1.0, 1.0));
        const double phi = std::atan2(d.y(), d.x());
        const int row = std::clamp(static_cast<int>(theta / kPi * rows), 0, rows - 1);
        const int col = std::clamp(static_cast<int>((phi + kPi) / (2.0 * kPi) * cols), 0, cols - 1);
        return static_cast<std::size_t>(row) * static_cast<std::size_t>(cols) + static_cast<std::size_t>(col);
    }
};

SphericalInterpolator::SphericalInterpolator(std::vector<Eigen::Vector3d> directions)
    : directions_(checked_directions(std::move(directions))) {
    const std::size_t n = directions_.size();
    std::vector<std::pair<Delaunay::Point, std::size_t>> points;
    points.reserve(n + 1);
    for (std::size_t i = 0; i < n; ++i)
        points.emplace_back(Delaunay::Point(directions_[i].x(), directions_[i].y(), directions_[i].z()), i);
    points.emplace_back(Delaunay::Point(0.0, 0.0, -1.0), n);  // the guardian g
    Delaunay delaunay(points.begin(), points.end());
    if (delaunay.dimension() < 3)
        throw InputError("the " + std::to_string(n) +
                         " light directions lie on one plane with the point below the hemisphere "
                         "(e.g. all on one great circle through the zenith); they span no "
                         "triangle to interpolate in");

    // Hull facets are the finite faces of the infinite cells. The guardian also has edges
    // inside the hull (all points are cospherical), so the boundary vertices are taken from
    // its hull facets, not from its adjacency.
    std::vector<char> on_boundary(n, 0);
    for (auto cell = delaunay.all_cells_begin(); cell != delaunay.all_cells_end(); ++cell) {
        if (!delaunay.is_infinite(cell)) continue;
        const int infinite = cell->index(delaunay.infinite_vertex());
        Triangle t{};
        bool touches_guardian = false;
        for (int k = 0; k < 3; ++k) {
            const std::size_t index = cell->vertex((infinite + 1 + k) % 4)->info();
            touches_guardian = touches_guardian || index == n;
            t[static_cast<std::size_t>(k)] = index;
        }
        if (touches_guardian) {
            for (const std::size_t index : t)
                if (index != n) on_boundary[index] = 1;
            continue;
        }
        if (det(directions_[t[0]], directions_[t[1]], directions_[t[2]]) < 0.0) std::swap(t[1], t[2]);
        triangles_.push_back(t);
    }
    triangles_ = canonical_order(std::move(triangles_));
    for (std::size_t i = 0; i < n; ++i)
        if (on_boundary[i]) boundary_.push_back(i);
    auto phi_of = [&](std::size_t i) { return std::atan2(directions_[i].y(), directions_[i].x()); };
    std::sort(boundary_.begin(), boundary_.end(), [&](std::size_t a, std::size_t b) {
        const double pa = phi_of(a), pb = phi_of(b);
        return pa < pb || (pa == pb && a < b);
    });
    for (const std::size_t b : boundary_) boundary_phi_.push_back(phi_of(b));

    // Point-location grid: about eight cells per direction.
    grid_ = std::make_unique<Grid>();
    Grid& grid = *grid_;
    grid.rows = std::clamp(static_cast<int>(std::ceil(2.0 * std::sqrt(static_cast<double>(n)))), 8, 512);
    grid.cols = 2 * grid.rows;
    const std::size_t triangle_count = triangles_.size();
    // Neighbours across each edge (opposite vertex j), for walking from a hinted triangle.
    neighbours_.assign(triangle_count, {kNoTriangle, kNoTriangle, kNoTriangle});
    {
        std::map<std::pair<std::size_t, std::size_t>, std::pair<std::size_t, std::size_t>> edges;
        for (std::size_t t = 0; t < triangle_count; ++t)
            for (std::size_t j = 0; j < 3; ++j) {
                std::size_t a = triangles_[t][(j + 1) % 3], b = triangles_[t][(j + 2) % 3];
                if (a > b) std::swap(a, b);
                auto [it, inserted] = edges.try_emplace({a, b}, t, j);
                if (!inserted) {
                    neighbours_[t][j] = it->second.first;
                    neighbours_[it->second.first][it->second.second] = t;
                }
            }
    }
    std::vector<Eigen::Vector3d> cap_centre(triangle_count);
    std::vector<double> cap_radius(triangle_count), theta_low(triangle_count), theta_high(triangle_count);
    std::vector<bool> locatable(triangle_count);
    planes_.resize(triangle_count);
    for (std::size_t t = 0; t < triangle_count; ++t) {
        const Eigen::Vector3d& a = directions_[triangles_[t][0]];
        const Eigen::Vector3d& b = directions_[triangles_[t][1]];
        const Eigen::Vector3d& c = directions_[triangles_[t][2]];
        planes_[t] = {b.cross(c), c.cross(a), a.cross(b)};
        // A triangle through the origin covers no direction (a flat fan of three points on
        // one great circle); it stays in T for the mesh but is never located.
        locatable[t] = det(a, b, c) > 0.0 && (a + b + c).norm() > 0.0;
        cap_centre[t] = (a + b + c).normalized();
        cap_radius[t] = std::max({angle_between(cap_centre[t], a), angle_between(cap_centre[t], b),
                                  angle_between(cap_centre[t], c)});
        const double theta = angles_of(cap_centre[t]).theta;
        // A cap over half a hemisphere wide is not spherically convex: list it everywhere.
        const bool huge = cap_radius[t] >= 0.5 * kPi - 1e-6;
        theta_low[t] = huge ? 0.0 : theta - cap_radius[t];
        theta_high[t] = huge ? kPi : theta + cap_radius[t];
        if (huge) cap_radius[t] = kPi;
    }

    const std::size_t cells = static_cast<std::size_t>(grid.rows) * static_cast<std::size_t>(grid.cols);
    std::vector<std::vector<std::uint32_t>> cell_triangles(cells), cell_nearest(cells);
    const double row_height = kPi / grid.rows, col_width = 2.0 * kPi / grid.cols;
    parallel_for_chunks(static_cast<std::size_t>(grid.rows), 1, [&](std::size_t begin, std::size_t end) {
        std::vector<double> cosines(n);
        for (std::size_t row = begin; row < end; ++row) {
            const double t0 = row_height * static_cast<double>(row), t1 = t0 + row_height;
            std::vector<std::size_t> in_row;
            for (std::size_t t = 0; t < triangle_count; ++t)
                if (locatable[t] && theta_high[t] >= t0 - 1e-9 && theta_low[t] <= t1 + 1e-9) in_row.push_back(t);
            for (int col = 0; col < grid.cols; ++col) {
                const double p0 = -kPi + col_width * col, p1 = p0 + col_width;
                const Eigen::Vector3d centre = direction_from_angles(0.5 * (t0 + t1), 0.5 * (p0 + p1));
                // Distances from the centre to points of a lat-long cell peak at its corners.
                double reach = 0.0;
                for (const double t : {t0, t1})
                    for (const double p : {p0, p1})
                        reach = std::max(reach, angle_between(centre, direction_from_angles(t, p)));
                reach += 1e-9;
                const std::size_t cell = row * static_cast<std::size_t>(grid.cols) + static_cast<std::size_t>(col);
                for (const std::size_t t : in_row)
                    if (cap_radius[t] + reach >= kPi || angle_between(centre, cap_centre[t]) <= cap_radius[t] + reach)
                        cell_triangles[cell].push_back(static_cast<std::uint32_t>(t));
                // The nearest direction to any point of the cell is within `closest + 2 reach`
                // of the centre (triangle inequality).
                double best = -2.0;
                for (std::size_t i = 0; i < n; ++i) {
                    cosines[i] = centre.dot(directions_[i]);
                    best = std::max(best, cosines[i]);
                }
                const double limit = std::acos(std::clamp(best, -1.0, 1.0)) + 2.0 * reach;
                const double min_cosine = limit >= kPi ? -2.0 : std::cos(limit) - 1e-12;
                for (std::size_t i = 0; i < n; ++i)
                    if (cosines[i] >= min_cosine) cell_nearest[cell].push_back(static_cast<std::uint32_t>(i));
            }
        }
    });
    auto flatten = [](const std::vector<std::vector<std::uint32_t>>& lists, std::vector<std::uint32_t>& offsets,
                      std::vector<std::uint32_t>& flat) {
        offsets.assign(1, 0);
        for (const auto& list : lists) {
            flat.insert(flat.end(), list.begin(), list.end());
            offsets.push_back(static_cast<std::uint32_t>(flat.size()));
        }
    };
    flatten(cell_triangles, grid.triangle_offsets, grid.triangle_list);
    flatten(cell_nearest, grid.nearest_offsets, grid.nearest_list);
}

SphericalInterpolator::~SphericalInterpolator() = default;
SphericalInterpolator::SphericalInterpolator(SphericalInterpolator&&) noexcept = default;
SphericalInterpolator& SphericalInterpolator::operator=(SphericalInterpolator&&) noexcept = default;

std::vector<std::vector<std::size_t>> SphericalInterpolator::one_rings() const {
    return relight::one_rings(directions_.size(), triangles_);
}

bool SphericalInterpolator::locate(const Eigen::Vector3d& d, std::size_t cell, InterpolationWeights& out,
                                   std::size_t* found) const {
    const Grid& grid = *grid_;
    for (std::uint32_t k = grid.triangle_offsets[cell]; k < grid.triangle_offsets[cell + 1]; ++k) {
        const std::uint32_t t = grid.triangle_list[k];
        if (!in_triangle(d, t, out)) continue;
        if (found) *found = t;
        return true;
    }
    return false;
}

InterpolationWeights SphericalInterpolator::arc_weights(const Eigen::Vector3d& d) const {
    const std::size_t m = boundary_.size();
    const double phi = std::atan2(d.y(), d.x());
    // j: the last boundary vertex with phi_j <= phi, wrapping to the last one below phi_0.
    const auto above = std::upper_bound(boundary_phi_.begin(), boundary_phi_.end(), phi);
    const std::size_t j = above == boundary_phi_.begin() ? m - 1 : static_cast<std::size_t>(above - boundary_phi_.begin()) - 1;
    const std::size_t k = (j + 1) % m;
    double phi_j = boundary_phi_[j], phi_k = boundary_phi_[k], query = phi;
    if (k <= j) phi_k += 2.0 * kPi;  // the wrap-around duplicate of eq. 4.7
    if (query < phi_j) query += 2.0 * kPi;
    const double gap = phi_k - phi_j;

    InterpolationWeights out;
    out.count = 2;
    out.index = {boundary_[j], boundary_[k], 0};
    const Eigen::Vector3d& bj = directions_[boundary_[j]];
    const Eigen::Vector3d& bk = directions_[boundary_[k]];
    if (gap < kPi - 1e-9) {
        // The boundary edge's own weights at d's azimuth: continuous with T.
        const double wj = std::max(0.0, d.x() * bk.y() - d.y() * bk.x());
        const double wk = std::max(0.0, bj.x() * d.y() - bj.y() * d.x());
        if (wj + wk > 0.0) {
            out.weight = {wj / (wj + wk), wk / (wj + wk), 0.0};
            return out;
        }
    }
    const double t = gap > 0.0 ? std::clamp((query - phi_j) / gap, 0.0, 1.0) : 0.0;  // eq. 4.8
    out.weight = {1.0 - t, t, 0.0};
    return out;
}

InterpolationWeights SphericalInterpolator::nearest_weights(const Eigen::Vector3d& d, std::size_t cell) const {
    const Grid& grid = *grid_;
    std::size_t best = grid.nearest_list[grid.nearest_offsets[cell]];
    double best_cosine = -2.0;
    for (std::uint32_t k = grid.nearest_offsets[cell]; k < grid.nearest_offsets[cell + 1]; ++k) {
        const std::size_t i = grid.nearest_list[k];  // ascending: ties keep the lowest index
        const double cosine = d.dot(directions_[i]);
        if (cosine > best_cosine) {
            best_cosine = cosine;
            best = i;
        }
    }
    InterpolationWeights out;
    out.count = 1;
    out.index[0] = best;
    out.weight[0] = 1.0;
    return out;
}

InterpolationWeights SphericalInterpolator::weights(const Eigen::Vector3d& direction, Interpolation method) const {
    std::size_t hint = kNoTriangle;
    return weights(direction, method, hint);
}

InterpolationWeights SphericalInterpolator::weights(const Eigen::Vector3d& direction, Interpolation method,
                                                    std::size_t& hint) const {
    InterpolationWeights out;
    // The hinted triangle first: its three plane tests spare the grid cell's angles (and,
    // being tests of sign and ratio, do not need a unit vector).
    bool hinted = false;
    if (method != Interpolation::Nearest && hint < triangles_.size()) {
        // Walk from the hinted triangle toward the direction, across the edge it lies
        // beyond, for a few steps: coherent queries land in the same or an adjacent one.
        std::size_t t = hint;
        for (int step = 0; step < 4 && t != kNoTriangle; ++step) {
            if (in_triangle(direction, t, out)) {
                hint = t;
                hinted = true;
                break;
            }
            const auto& planes = planes_[t];
            std::size_t worst = 0;
            double lowest = direction.dot(planes[0]);
            for (std::size_t j = 1; j < 3; ++j) {
                const double w = direction.dot(planes[j]);
                if (w < lowest) {
                    lowest = w;
                    worst = j;
                }
            }
            t = neighbours_[t][worst];
        }
    }
    if (!hinted) {
        const Eigen::Vector3d unit = direction.normalized();
        const std::size_t cell = grid_->cell_of(unit);
        if (method == Interpolation::Nearest) return nearest_weights(unit, cell);
        if (!locate(unit, cell, out, &hint)) {
            hint = kNoTriangle;
            return arc_weights(unit);
        }
    }
    // At a measured direction the coordinates are exactly (1, 0, 0); the solid angles of its
    // degenerate sub-triangles are zero only up to rounding, so keep them.
    const bool at_vertex = out.weight[0] == 1.0 || out.weight[1] == 1.0 || out.weight[2] == 1.0;
    if (method == Interpolation::SolidAngle && out.count == 3 && !at_vertex) {
        const Eigen::Vector3d direction_unit = direction.normalized();
        const Eigen::Vector3d& a = directions_[out.index[0]];
        const Eigen::Vector3d& b = directions_[out.index[1]];
        const Eigen::Vector3d& c = directions_[out.index[2]];
        const std::array<double, 3> omega = {spherical_triangle_solid_angle(direction_unit, b, c),
                                             spherical_triangle_solid_angle(a, direction_unit, c),
                                             spherical_triangle_solid_angle(a, b, direction_unit)};
        const double total = omega[0] + omega[1] + omega[2];
        if (total > 0.0) out.weight = {omega[0] / total, omega[1] / total, omega[2] / total};
    }
    return out;
}

std::vector<Triangle> delaunay_triangles(const std::vector<Eigen::Vector3d>& directions) {
    return SphericalInterpolator(directions).triangles();
}

}  // namespace rfd::relight
