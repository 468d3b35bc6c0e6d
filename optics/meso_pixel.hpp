#pragma once
// The optics behind one print dot of Designs III and IV (thesis 8.3.1, figure 8.11): which
// incident directions light it, whether its light leaves the display, and in which output
// direction.
//
// Layout (designs/design3.toml): main lens A, field lens B, meso-pixel lenslets C (the
// encoding surface of DesignOptics: one incident-direction bin per meso cell), the pattern
// D between a back-to-back pair of arrays, projection lenslets E. All arrays share one
// lattice, so meso cell k of C sits above cell k of D and of E.
//
// The chief ray of a dot. Light of every incident direction of bin k is focused somewhere
// on C_k; C_k images the main lens onto D, so the light reaching a dot at offset p from the
// centre of D_k comes through the whole of C_k. Its central ray, the one through the centre
// (vertex) of C_k, is the dot's chief ray: it fixes the dot's output direction (the
// direction of travel after E_k) and the incident direction that sends it (traced back
// through B and A). The other rays of the dot leave within `output_spread` of it.
//
// Paraxial model (closed form, optics/paraxial.hpp, real slopes): with M_cd the matrix from
// C's vertex plane to D (on the lenslet's axis) and M_de from D to E's last surface, a ray
// through the centre of C_k with slope s lands at p = B_cd s with slope u_D = D_cd s in the
// glass, and leaves with slope
//     u_out = C_de p + D_de u_D = (C_de + D_de D_cd / B_cd) p = gain * p        (both axes).
// When D lies in the front focal plane of the optics behind it, D_de = 0 and gain = -1/f:
// the dot leaves as a parallel beam with tan = -p / f, whatever the incident direction.
// Exact model: the chief ray through C_k's vertex that lands at p is found by Newton
// iteration on its slope (started from the paraxial answer), then traced on through E and
// back through B and A with Snell's law.
//
// What becomes of a dot (DotLight): Lit when its chief ray passes every aperture from A to
// E inside lenslet k; Unlit when A or B stop it (the dot lies outside the image of the main
// lens: no light ever reaches it, as in the corners of the 4 x 4.8 mm cells of design3);
// Crossed when it leaves through a neighbouring lenslet of D or E (it would send the wrong
// output direction: crosstalk); Lost for a miss, total internal reflection or the array's
// edge. Only Lit dots are worth printing.
//
// Frames: the system frame of surface.hpp (z the way light travels, toward the observer;
// x right, y up as the observer sees the display). Offsets are millimetres in the plane of
// D from the centre of cell k. Directions are unit vectors of travel.
//
// Example: MesoPixelOptics meso(DesignOptics(load_design("designs/design3.toml")));
//          DotRay ray = meso.dot({0.5, -0.2}, {2, 2}, Model::Paraxial);

#include <cstdint>
#include <optional>
#include <string_view>
#include <vector>

#include <Eigen/Core>

#include "optics/analysis.hpp"

namespace rfd::optics {

enum class DotLight : std::uint8_t { Lit, Unlit, Crossed, Lost };
std::string_view to_string(DotLight light);

/// What the chief ray of one dot does.
struct DotRay {
    DotLight light = DotLight::Lost;
    Eigen::Vector3d incident = Eigen::Vector3d::UnitZ();  ///< unit travel direction before A
    Eigen::Vector3d output = Eigen::Vector3d::UnitZ();    ///< unit travel direction after E
    RayStatus status = RayStatus::Ok;  ///< of the first failing trace (Ok when Lit)
    int surface = -1;                  ///< surface where it stopped (-1 when Lit)
};

/// One incident-direction bin: the directions the main lens sends into meso cell `cell`.
struct IncidentBin {
    CellIndex cell{};
    Eigen::Vector3d centre = Eigen::Vector3d::UnitZ();  ///< travel direction to the cell centre
    /// Travel directions to an n x n grid of points at the centres of n x n equal parts of
    /// the cell's bounding box (inside the cell; the ones the model cannot map are left out).
    std::vector<Eigen::Vector3d> samples;
    /// Angular half-widths of the bin about its centre: the mean angle to the directions of
    /// the two opposite edge midpoints that the model maps (0 when neither is).
    double half_width_x_deg = 0.0;
    double half_width_y_deg = 0.0;
};

class MesoPixelOptics {
public:
    /// Throws InputError (naming the design file) unless the design is III or IV with the
    /// planes A (main lens), B (field lens), C (meso array), D (pattern pair), E (projection).
    explicit MesoPixelOptics(const DesignOptics& optics);

    const DesignOptics& optics() const { return optics_; }
    const Lattice& lattice() const { return optics_.lattice(); }

    /// The chief ray of the dot at `offset` (mm) from the centre of cell `cell` on D.
    DotRay dot(const Eigen::Vector2d& offset, CellIndex cell, Model model) const;

    /// Paraxial output slope per millimetre of offset (the `gain` above), 1/mm.
    double output_gain() const { return gain_; }
    /// Paraxial half-width (tan) of the output slopes of all rays of one dot: rays from one
    /// point of D through the whole of C_k (half a pitch either side of its centre) leave
    /// with slopes gain * p +- |D_de (C_cd - D_cd A_cd / B_cd)| * pitch / 2, along x and y.
    /// The angular blur the design leaves in every dot; 0 when D is in focus for E.
    Eigen::Vector2d output_spread() const { return spread_; }

    /// Inverse of the output map: the offset from the cell centre whose chief ray leaves in
    /// direction `output` (unit, travel). Paraxial: p = u_out / gain. Exact: Newton on the
    /// exact map, from the paraxial answer; nullopt where it does not converge.
    std::optional<Eigen::Vector2d> offset_for(const Eigen::Vector3d& output, CellIndex cell,
                                              Model model) const;

    /// The incident bin of meso cell `cell` with samples_per_side^2 samples.
    IncidentBin bin(CellIndex cell, Model model, int samples_per_side) const;

    /// Surface indices in the system (for reports and tests).
    std::size_t meso_front() const { return c_front_; }
    std::size_t pattern_surface() const { return d_pattern_; }
    std::size_t last_surface() const { return last_; }

    /// The two halves of dot(), for callers that tabulate: the slope (air, at C's vertex
    /// plane) of the ray through C_k's vertex that lands at `offset` on D (exact: Newton;
    /// nullopt when it does not arrive or converge), and what that ray does. The slope does
    /// not depend on the cell (all arrays share one lattice) except at the array's edge.
    std::optional<Eigen::Vector2d> chief_slope(const Eigen::Vector2d& offset, CellIndex cell,
                                               Model model) const;
    DotRay follow(const Eigen::Vector2d& slope, CellIndex cell, Model model) const;

private:
    const DesignOptics& optics_;
    SequentialSystem backward_;  // reversed system, for tracing from C back to A
    std::size_t c_front_ = 0, d_pattern_ = 0, last_ = 0;
    RayMatrix cd_, de_;
    double gain_ = 0.0;
    Eigen::Vector2d spread_ = Eigen::Vector2d::Zero();
};

}  // namespace rfd::optics
