#pragma once
// Patterns optimised through the display's own forward model (Designs I and II).
//
// The direct encoder (patterns/encode.hpp) writes every dot as if the light through a
// lenslet reached only that lenslet's cell on the diffuser. It does not: a Design I's
// spot slides over the neighbours' cells as the light moves, a Design II's macro-pixel is
// imaged at |m| > 1 and overlaps them. Here the pattern is chosen so that what the
// simulator predicts comes closest to the field relit in software.
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
// Operator. For a display direction d, the simulator's rays of one lenslet
// (DisplaySimulator::trace_lenslet), repeated at every lenslet k: a ray reads the pattern
// where it meets it (the nodes' interpolation there) and lands in the diffuser cell l
// holding its end point, adding its power over the cell's area. (The printed dot holds the
// interpolation at its centre, at most half a dot from the ray: nodes a dozen dots apart
// change by a few per cent of their difference over that; reading at the ray lets every
// lenslet share one table of weights per ray, which makes the operator fast.) So
//     (A_d u)_l = the mean irradiance over cell l, relative to the light's
// (DiffuserImage units, as per_lenslet measures the simulator's image, without its pixel
// grid). The print's black level adds b W_d, W_d the flat field (every dot clear), so the
// printed display shows b W_d + (1 - b) A_d u and the reference of predict/compare.hpp,
// W_d (b + (1 - b) u*_d), is matched when A_d u = W_d u*_d, u*_d the field's desired
// transmittance at d. The adjoint splats per-cell values back along the same rays.
//
// Problem. minimise f(u) = 1/2 sum_d w_d |A_d u - W_d u*_d|^2 over 0 <= u <= 1, w_d the
// solid angle a direction stands for (normalised to mean 1). Solved by projected gradient
// with Barzilai-Borwein steps and an exact line search along the projected direction (the
// objective is quadratic, so the step is closed-form and f never increases; Dai and
// Fletcher 2005), or without the bounds by CGLS (Hestenes-Stiefel conjugate gradients on
// the normal equations) for the unconstrained optimum, the ceiling.
//
// Determinism: each direction's forward sums its lenslets in order; the adjoint sums
// bands of lenslet rows far enough apart to write disjoint nodes in parallel, then the
// bands between them: byte-identical results whatever the thread count.
//
// Example:
//   NodeGrid nodes(lattice, geometry, 0.1);
//   DisplayOperator A(simulator, nodes, directions, options);
//   OptimizationProblem problem(A, targets, weights);
//   OptimizationResult r = solve(problem, direct_nodes(nodes, encoder, tone), {});

#include <algorithm>
#include <array>
#include <cstdint>
#include <functional>
#include <optional>
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

/// The linear map of the header from node values to the mean over each diffuser cell, one
/// block of lenslets x 3 values (linear_index order, channel fastest) per direction; for a
/// Design II whose macro-pixels overlap (predict/compare.hpp) and when asked, the block goes
/// on with the mean over each cell's core. Whole cells are the picture at the display's
/// resolution; fitting them sharpens each macro-pixel against the light its neighbours
/// spill in, which changes the core, where no neighbour reaches: weighing the cores in too
/// keeps a picture's shape there (SIG08's letters) at some cost to the cells.
class DisplayOperator {
public:
    /// Traces `display_directions` (travel, z > 0) through `simulator` (options.model,
    /// options.rays_per_side; a full grid per direction). Only the rays of lenslets in
    /// `sources` are followed (a crop: the window of cells to fit, grown by the reach of
    /// the light); the default is every lenslet.
    /// With `cores`, a design whose macro-pixels overlap also has its cores' means.
    DisplayOperator(const optics::DisplaySimulator& simulator, const NodeGrid& nodes,
                    std::vector<Eigen::Vector3d> display_directions, const optics::SimulationOptions& options,
                    std::optional<LensletWindow> sources = std::nullopt, bool cores = false);

    std::size_t directions() const { return directions_.size(); }
    const Eigen::Vector3d& direction(std::size_t d) const { return directions_[d].display; }
    /// Outputs per direction: the cells' means, then (Design II) their cores' means.
    std::size_t block_size() const { return nodes_.lenslets() * 3 * regions(); }
    /// 2 when asked for cores and the design's macro-pixels overlap their neighbours
    /// (predict/compare.hpp's macro_pixel_core: fraction < 1); else 1.
    std::size_t regions() const { return core_fraction_ < 1.0 ? 2 : 1; }
    double core_fraction() const { return core_fraction_; }
    std::size_t output_size() const { return directions_.size() * block_size(); }
    std::size_t input_size() const { return nodes_.size(); }
    const NodeGrid& nodes() const { return nodes_; }
    /// Lenslet rows a cell's light reaches beyond its own, on the pattern or the diffuser.
    int reach_rows() const { return reach_rows_; }

    /// y = A u; `outside` is the transmittance of dots in no lenslet (0: opaque, 1: the flat field).
    void forward(std::span<const double> u, std::span<double> y, double outside = 0.0) const;
    /// The same for one direction: `y` holds one block.
    void forward_direction(std::size_t d, std::span<const double> u, std::span<double> y, double outside = 0.0) const;
    /// g = A^T y.
    void adjoint(std::span<const double> y, std::span<double> g) const;
    /// W: every direction's response to a clear print (dots in no lenslet clear too).
    std::vector<double> flat_field() const;

    // Offsets between lattice indices depend on the parity of a hexagonal lattice's row.
    struct CellStep {
        std::array<std::int16_t, 2> di{}, dj{};  // per parity of the source's row
    };
    // A ray as every lenslet repeats it: the lenslet whose nodes it reads (the cell holding
    // the point where it meets the pattern) and their weights there, the cell it lands in
    // on the diffuser, its power over that cell's area, and the lenslets it crosses.
    struct Ray {
        CellStep read, landing;
        std::array<std::uint32_t, 4> node{};  // index of channel 0 within the read lenslet's nodes
        std::array<double, 4> weight{};
        double power = 0.0;
        double core_power = 0.0;  // over the core's area when it lands in the core, else 0
        std::uint32_t first_crossed = 0, crossed = 0;
    };
    struct Direction {
        Eigen::Vector3d display;
        std::vector<Ray> rays;
        std::vector<CellStep> crossed;
    };
    template <typename Visit>
    void for_each_ray(const Direction& direction, optics::CellIndex source, Visit&& visit) const;

    NodeGrid nodes_;
    std::vector<Direction> directions_;
    LensletWindow sources_;
    int reach_rows_ = 0;
    double core_fraction_ = 1.0;
};

/// f(u) of the header: the operator, the targets W_d u*_d (output_size()) and per-direction
/// weights; cells outside `fitted` (default: all) do not count.
class OptimizationProblem {
public:
    /// `core_weight`: the cores' share beside the whole cells' (when op has cores).
    OptimizationProblem(const DisplayOperator& op, std::vector<double> target, std::vector<double> weights,
                        std::optional<LensletWindow> fitted = std::nullopt, double core_weight = 1.0);
    const DisplayOperator& op() const { return op_; }
    const std::vector<double>& target() const { return target_; }
    /// r = w (A u - target) per output value (w: the direction's weight, 0 outside the
    /// fitted cells), so that A^T r is the gradient; returns f.
    double residual(std::span<const double> au, std::span<double> r) const;
    /// The weight of output value k (0 outside the fitted window).
    double weight_of(std::size_t k) const;

private:
    const DisplayOperator& op_;
    std::vector<double> target_, weights_;
    std::vector<std::uint8_t> fitted_;  // per lenslet
    double core_weight_ = 0.0;
};

struct SolverOptions {
    int iterations = 50;
    /// Stop when an iteration lowers f by less than this fraction of f.
    double tolerance = 1e-6;
    bool bounded = true;  ///< 0 <= u <= 1; false: CGLS, unconstrained
    /// Called after every iteration with its number, f, and the iterate (for charts).
    std::function<void(int, double, std::span<const double>)> on_iteration;
};

struct OptimizationResult {
    std::vector<double> u;
    std::vector<double> objective;  ///< f at the start and after each iteration
    int iterations = 0;
    bool converged = false;         ///< the tolerance was met (or the projected gradient vanished)
};

/// Minimises the problem's f from `start` (clamped to the bounds when bounded).
OptimizationResult solve(const OptimizationProblem& problem, std::vector<double> start, const SolverOptions& options);

// --- From an encoded field to a problem, and back to a pattern ---------------------------

/// Pattern-plane offsets from a lenslet's centre (mm) inside its cell: the nodes', or with
/// `between` the points midway between four nodes. Their chief rays (the encoder's inverse
/// map) are the directions optimised, and those in between to judge by.
std::vector<Eigen::Vector2d> cell_offsets(const NodeGrid& nodes, bool between);

/// The display directions (travel) of those offsets in the encoder's model, and the solid
/// angle each stands for (its node's square mapped to directions), normalised to mean 1.
struct SweepDirections {
    std::vector<Eigen::Vector3d> display;
    std::vector<double> weights;
};
SweepDirections sweep_directions(const patterns::Encoder& encoder, const NodeGrid& nodes, bool between);

/// u* of the header for display direction d: clamp(brightness R_l(v) / (cos(kappa) white),
/// 0, 1) per lenslet (linear_index order) and channel (3; a grey field repeats its one).
std::vector<double> desired_transmittance(const patterns::Encoder& encoder, const print::ToneMap& tone,
                                          const Eigen::Vector3d& display_direction);

/// The targets W_d u*_d of every direction of `op`, given its flat field.
std::vector<double> optimization_targets(const DisplayOperator& op, const std::vector<double>& flat_field,
                                         const patterns::Encoder& encoder, const print::ToneMap& tone);

/// The direct encoding at the nodes: u* at each node's own direction, per lenslet.
std::vector<double> direct_nodes(const NodeGrid& nodes, const patterns::Encoder& encoder, const print::ToneMap& tone);

/// A pattern at the nodes: u at each node read from `pattern` (stack transmittance t' of
/// the dot under the node, black level removed).
std::vector<double> nodes_from_pattern(const NodeGrid& nodes, const optics::Transparency& pattern,
                                       const print::ToneMap& tone);

/// Per direction of `op`, the PSNR of A_d u against the targets over the fitted whole cells (peak:
/// the direction's largest target), as predict/compare.hpp measures (without the black
/// level's b W_d on both sides, so these read a little lower). NaN for a direction whose
/// targets are all 0 (nothing to show), +inf for an exact match.
std::vector<double> direction_psnr(const DisplayOperator& op, const std::vector<double>& target,
                                   std::span<const double> u, std::optional<LensletWindow> fitted = std::nullopt);

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
