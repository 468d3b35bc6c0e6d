#pragma once
// The display as a linear map from pattern nodes (predict/node_grid.hpp) to the picture,
// for the optimiser (predict/optimize.hpp).
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
// Determinism: each direction's forward sums its lenslets in order; the adjoint sums
// bands of lenslet rows far enough apart to write disjoint nodes in parallel, then the
// bands between them: byte-identical results whatever the thread count.
//
// Example:
//   DisplayOperator A(simulator, nodes, sweep_directions(encoder, nodes, false).display, options);
//   std::vector<double> targets = optimization_targets(A, A.flat_field(), encoder, tone);

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include <Eigen/Core>

#include "optics/display.hpp"
#include "patterns/encode.hpp"
#include "predict/node_grid.hpp"
#include "print/printer.hpp"

namespace rfd::predict {

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

/// The display directions (travel) of those offsets in the encoder's model, and the solid
/// angle each stands for (its node's square mapped to directions), normalised to mean 1.
struct SweepDirections {
    std::vector<Eigen::Vector3d> display;
    std::vector<double> weights;
};
SweepDirections sweep_directions(const patterns::Encoder& encoder, const NodeGrid& nodes, bool between);

/// The targets W_d u*_d of every direction of `op`, given its flat field.
std::vector<double> optimization_targets(const DisplayOperator& op, const std::vector<double>& flat_field,
                                         const patterns::Encoder& encoder, const print::ToneMap& tone);

/// Per direction of `op`, the PSNR of A_d u against the targets over the fitted whole cells,
/// the one PSNR of `simulate compare` (psnr_against_field_db): the peak is the largest target
/// over all of `op`'s directions, so a direction where the field is dark reads what the
/// display shows there (without the black level's b W_d on both sides, so these read a
/// little lower). NaN when every target is 0 (nothing to show); an exact match reads the
/// ceiling, optics::kPsnrCeilingDb.
std::vector<double> direction_psnr(const DisplayOperator& op, const std::vector<double>& target,
                                   std::span<const double> u, std::optional<LensletWindow> fitted = std::nullopt);

}  // namespace rfd::predict
