#pragma once
// The unknowns of an optimised pattern (predict/optimize.hpp), and back to a pattern.
//
// Unknowns. Per lenslet, a square grid of nodes over its cell's bounding box, `spacing`
// apart, centred on its axis with an even count per side (the axis lies between four
// nodes). A printed dot takes the bilinear interpolation of its own lenslet's nodes at the
// dot's centre (constant beyond the outer nodes); dots in no lenslet of the array are
// opaque. A node holds u in [0, 1] per channel, the desired stack transmittance before
// the black level (print/printer.hpp: t = clamp(brightness p / white), t' = b + (1 - b) t).
// Interpolation is a convex combination, so nodes within [0, 1] keep every dot printable.
// The nodes are coarser than the dots on purpose: a light direction's spot covers a few
// nodes, directions in between the optimised ones read interpolated nodes, and the problem
// stays small (about 10 million unknowns for the 144-million-dot Design I preset).
//
// Example:
//   NodeGrid nodes(lattice, geometry, 0.1);
//   std::vector<double> u = direct_nodes(nodes, encoder, tone);
//   write_pattern("optimized.exr", NodePattern(nodes, u, 3, tone.white, tone.brightness), attributes);

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include <Eigen/Core>

#include "optics/display.hpp"
#include "optics/lattice.hpp"
#include "patterns/encode.hpp"
#include "patterns/raster.hpp"
#include "print/printer.hpp"

namespace rfd::predict {

/// Lenslets [i0, i1) x [j0, j1) of a lattice (lattice indices, j up).
struct LensletWindow {
    int i0 = 0, j0 = 0, i1 = 0, j1 = 0;
    bool contains(optics::CellIndex cell) const { return cell.i >= i0 && cell.i < i1 && cell.j >= j0 && cell.j < j1; }
    LensletWindow grown(int by) const { return {i0 - by, j0 - by, i1 + by, j1 + by}; }
    /// The part inside the lattice's array.
    LensletWindow clipped(const optics::Lattice& lattice) const {
        return {std::max(i0, 0), std::max(j0, 0), std::min(i1, lattice.count_x()), std::min(j1, lattice.count_y())};
    }
    static LensletWindow whole(const optics::Lattice& lattice) { return {0, 0, lattice.count_x(), lattice.count_y()}; }
};

/// The unknowns of the header: per lenslet, nodes_x x nodes_y nodes of 3 channels.
class NodeGrid {
public:
    /// InputError when `spacing_mm` is not positive or gives more than 256 nodes per side.
    NodeGrid(const optics::Lattice& lattice, const patterns::PatternGeometry& geometry, double spacing_mm);

    int nodes_x() const { return nodes_x_; }
    int nodes_y() const { return nodes_y_; }
    double spacing() const { return spacing_; }
    const optics::Lattice& lattice() const { return lattice_; }
    const patterns::PatternGeometry& geometry() const { return geometry_; }
    std::size_t per_lenslet() const { return static_cast<std::size_t>(nodes_x_) * static_cast<std::size_t>(nodes_y_); }
    /// Values of a whole pattern: lenslets x per_lenslet() x 3, channel fastest, lenslets in
    /// Lattice::linear_index order, nodes row by row from the bottom (y up).
    std::size_t lenslets() const {
        return static_cast<std::size_t>(lattice_.count_x()) * static_cast<std::size_t>(lattice_.count_y());
    }
    std::size_t size() const { return lenslets() * per_lenslet() * 3; }
    /// Where node (a, b) lies from its lenslet's centre, mm.
    Eigen::Vector2d node_offset(int a, int b) const {
        return {(a - 0.5 * (nodes_x_ - 1)) * spacing_, (b - 0.5 * (nodes_y_ - 1)) * spacing_};
    }
    /// Index into the values of channel 0 of node (a, b) of `cell`.
    std::size_t index(optics::CellIndex cell, int a, int b) const {
        return (lattice_.linear_index(cell) * per_lenslet() + static_cast<std::size_t>(b) * nodes_x_ + a) * 3;
    }

    /// The printed dot under `point` (lattice frame, mm): its lenslet and the bilinear
    /// weights of that lenslet's nodes at the dot's centre (indices of channel 0). False
    /// when the dot lies off the raster or in no lenslet of the array (opaque).
    struct Stencil {
        optics::CellIndex cell;
        std::array<std::size_t, 4> index{};
        std::array<double, 4> weight{};
    };
    bool stencil(const Eigen::Vector2d& point, Stencil& out) const;
    /// The bilinear weights at `offset` from a lenslet's centre, by the indices of channel 0
    /// within one lenslet's nodes.
    void local_stencil(const Eigen::Vector2d& offset, std::array<std::uint32_t, 4>& index,
                       std::array<double, 4>& weight) const;
    /// The same for dot (px, py) of the raster.
    bool dot_stencil(int px, int py, Stencil& out) const;

private:
    optics::Lattice lattice_;
    patterns::PatternGeometry geometry_;
    double spacing_ = 0.0;
    int nodes_x_ = 0, nodes_y_ = 0;
};

/// Pattern-plane offsets from a lenslet's centre (mm) inside its cell: the nodes', or with
/// `between` the points midway between four nodes. Their chief rays (the encoder's inverse
/// map) are the directions optimised, and those in between to judge by.
std::vector<Eigen::Vector2d> cell_offsets(const NodeGrid& nodes, bool between);

/// u* of predict/display_operator.hpp for display direction d: clamp(brightness R_l(v) / (cos(kappa) white),
/// 0, 1) per lenslet (linear_index order) and channel (3; a grey field repeats its one).
std::vector<double> desired_transmittance(const patterns::Encoder& encoder, const print::ToneMap& tone,
                                          const Eigen::Vector3d& display_direction);

/// The direct encoding at the nodes: u* at each node's own direction, per lenslet.
std::vector<double> direct_nodes(const NodeGrid& nodes, const patterns::Encoder& encoder, const print::ToneMap& tone);

/// A pattern at the nodes: u at each node read from `pattern` (stack transmittance t' of
/// the dot under the node, black level removed).
std::vector<double> nodes_from_pattern(const NodeGrid& nodes, const optics::Transparency& pattern,
                                       const print::ToneMap& tone);

/// Node values as the simulator sees them printed: the dot under each point holds the
/// interpolation of its lenslet's nodes at its centre, through the print's black level
/// (t' = black + (1 - black) u); dots in no lenslet black, points off the sheet 0. Holds no
/// raster: a preset's 144 million dots cost nothing.
class NodeTransparency final : public optics::Transparency {
public:
    NodeTransparency(const NodeGrid& nodes, std::vector<double> u, double black);
    int channels() const override { return 3; }
    void sample(std::span<const Eigen::Vector2d> points, std::span<float> out) const override;

private:
    const NodeGrid& nodes_;
    std::vector<double> u_;
    double black_;
};

/// The printed pattern of node values: every dot the interpolation of its lenslet's nodes,
/// as a pattern value (u white / brightness, so that the print's tone map gives back u);
/// dots in no lenslet 0.
class NodePattern final : public patterns::PatternSource {
public:
    NodePattern(const NodeGrid& nodes, std::vector<double> u, int channels, double white, double brightness);
    const patterns::PatternGeometry& geometry() const override { return nodes_.geometry(); }
    int channels() const override { return channels_; }
    void render_row(int py, std::span<float> out) const override;

private:
    const NodeGrid& nodes_;
    std::vector<double> u_;
    int channels_;
    double scale_;
};

}  // namespace rfd::predict
