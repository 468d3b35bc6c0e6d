#pragma once
// The pattern of Designs III and IV (thesis 8.3): every print dot of plane D gets
//     value = R(lights of its meso cell's incident bin; macro-pixel u, v; its output direction)
// from an AngularField (patterns/angular_fields.hpp), and 0 where the dot is not Lit
// (optics/meso_pixel.hpp: outside the main lens's image, or its light leaves through a
// neighbouring lenslet, or outside the arrays).
//
// Layout on D (lattice frame of patterns/raster.hpp, mm): Design IV's macro-pixels tile the
// raster, macro-pixel (u, v) centred at ((u + 0.5) pitch_x - W/2, (v + 0.5) pitch_y - H/2)
// with W, H the grid's extent (u right, v up); inside each (and for Design III, around the
// origin) the meso lattice; a dot at offset p from the centre of meso cell k belongs to the
// incident bin of k and leaves in the output direction of its chief ray.
//
// Display to field (the convention this encoder fixes; docs/formats.md):
//   - a light behind the display whose light travels along d (system frame) lights the
//     field as a light at (-d_x, -d_y, d_z): mirrored through the display plane, so a lamp
//     behind and above the display lights the scene from above, as if the display were a
//     window onto the object lit from the observer's side;
//   - the output direction of travel o is the field's view direction as is (the display
//     faces the field's camera; relight/view_set.hpp).
//
// Speed: the optics are tabulated once over a grid of nodes spanning one meso cell (one
// table per meso cell, shared by all macro-pixels): the Lit flag of the nearest node and
// the output slopes interpolated bilinearly between Lit nodes (the paraxial map is linear,
// so paraxial tables are exact to rounding; the exact map is smooth). Rows then cost a
// table lookup and one field lookup per dot. Deterministic: every dot is computed alone.
//
// Example: AngularPattern pattern(optics, DiamondField(0.2, 0.2), {});
//          write_pattern("design4.exr", pattern, pattern.attributes());

#include <memory>
#include <vector>

#include "optics/meso_pixel.hpp"
#include "patterns/angular_fields.hpp"
#include "patterns/raster.hpp"

namespace rfd::patterns {

/// Field light direction (toward the light) of a display's incident travel direction.
inline Eigen::Vector3d field_light_of(const Eigen::Vector3d& incident) {
    return Eigen::Vector3d(-incident.x(), -incident.y(), incident.z()).normalized();
}

struct AngularOptions {
    optics::Model model = optics::Model::Paraxial;
    int bin_samples = 3;     ///< incident directions per side of each bin (n x n, in the cell)
    int table_size = 257;    ///< optics table nodes per side of a meso cell
    double dpi_x = 0.0;      ///< print resolution; 0: the design's printer
    double dpi_y = 0.0;
};

/// How many dots of one meso cell are lit, crossed, ... (from the tables: per node).
struct DotCounts {
    std::size_t lit = 0, unlit = 0, crossed = 0, lost = 0;
    double lit_fraction() const {
        const std::size_t all = lit + unlit + crossed + lost;
        return all ? double(lit) / double(all) : 0.0;
    }
};

class AngularPattern : public PatternSource {
public:
    /// Throws InputError for a design that is not III/IV, bad options, or a field that
    /// cannot serve the display's bins. Keeps references to `optics` and `field`.
    AngularPattern(const optics::DesignOptics& optics, const AngularField& field,
                   const AngularOptions& options);
    ~AngularPattern() override;

    const PatternGeometry& geometry() const override { return geometry_; }
    int channels() const override { return field_.channels(); }
    void render_row(int py, std::span<float> out) const override;

    /// Incident bins, one per meso cell (linear index of the lattice).
    const std::vector<optics::IncidentBin>& bins() const { return bins_; }
    /// Light directions of each bin in the field frame (what the field was bound with).
    const std::vector<LightBin>& field_bins() const { return field_bins_; }
    const optics::MesoPixelOptics& meso() const { return meso_; }
    int macro_x() const { return macro_x_; }
    int macro_y() const { return macro_y_; }
    /// Table node counts over all meso cells.
    DotCounts counts() const;
    /// rfd: attributes: design, kind ("angular"), model, bins, macro grid.
    PatternAttributes attributes() const;

    /// Where a dot lies: macro-pixel, meso cell, offset (mm) from the cell's centre;
    /// nullopt outside the grid or the lattice. Exposed for tests and the simulator.
    struct DotPlace {
        int u = 0, v = 0;
        optics::CellIndex cell{};
        Eigen::Vector2d offset = Eigen::Vector2d::Zero();
    };
    std::optional<DotPlace> place(const Eigen::Vector2d& mm) const;
    /// The tabulated optics at a place: Lit or not, and the output direction (travel, unit).
    struct TableDot {
        bool lit = false;
        Eigen::Vector3d output = Eigen::Vector3d::UnitZ();
    };
    TableDot table_dot(const DotPlace& place) const;

private:
    struct CellTable;
    const optics::DesignOptics& optics_;
    optics::MesoPixelOptics meso_;
    const AngularField& field_;
    AngularOptions options_;
    PatternGeometry geometry_;
    int macro_x_ = 1, macro_y_ = 1;
    double macro_pitch_x_ = 0.0, macro_pitch_y_ = 0.0;
    std::vector<optics::IncidentBin> bins_;
    std::vector<LightBin> field_bins_;
    std::unique_ptr<AngularLookup> lookup_;
    Eigen::Vector2d half_box_ = Eigen::Vector2d::Zero();  // half-size of the tabulated box
    std::vector<CellTable> tables_;
};

/// Figure 8.13's field for this display: one character per meso cell (in lattice order,
/// row by row from the bottom left), centred on its bin's centre direction, drawn over the
/// output directions of the inner 3/4 of a cell (|tan| <= |gain| * 0.375 * min pitch).
/// Throws InputError when `characters` is shorter than the number of bins.
LetterField letter_field_for(const optics::MesoPixelOptics& meso, optics::Model model,
                             const std::string& characters);
/// Figure 8.15's field for this display: the light range is the largest bin-centre slope,
/// the view range the output slope of 3/4 of half a cell along x.
DiamondField diamond_field_for(const optics::MesoPixelOptics& meso, optics::Model model);

/// The value that should print as full transmittance: the given percentile (e.g. 99.5) of
/// all samples of `rows` rows spread evenly over the raster (every row when rows >= height).
/// Deterministic; 0 for a blank pattern.
double estimate_white(const PatternSource& source, double percentile, int rows = 256);

}  // namespace rfd::patterns
