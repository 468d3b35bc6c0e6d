#pragma once
// A design prepared for analysis and simulation: the sequential system of its surfaces, the
// plane where incident direction becomes position (the encoding plane: the pattern plane
// of Designs I/II, the meso-pixel plane of III/IV), and the maps between the two in both
// models of light (optics/model.hpp).
//
// Directions: the incident light travels along d = (tan_x, tan_y, 1)/|.| in the system
// frame (surface.hpp). An incident angle (theta, phi) means d = (sin theta cos phi,
// sin theta sin phi, cos theta): theta from the axis, phi counter-clockwise from +x as the
// observer sees it. Positions on the encoding plane are relative to the lenslet's centre,
// in mm.
//
// Example: DesignOptics optics(load_design("designs/design1.toml"));
//          auto landing = optics.land(incident_direction(0.1, 0.0), optics.centre_cell(), Model::Exact);

#include <array>
#include <cstddef>
#include <optional>
#include <vector>

#include <Eigen/Core>

#include "optics/design.hpp"
#include "optics/exact.hpp"
#include "optics/model.hpp"

namespace rfd::optics {

/// Unit direction of travel for incident angles theta (from the axis) and phi (azimuth).
Eigen::Vector3d incident_direction(double theta_rad, double phi_rad);

/// A design prepared for analysis: the sequential system and the surfaces that matter.
class DesignOptics {
public:
    explicit DesignOptics(const Design& design);

    const Design& design() const { return design_; }
    const SequentialSystem& system() const { return system_; }
    /// Surface where incident direction becomes position.
    std::size_t encoding_surface() const { return encoding_surface_; }
    /// First surface whose lattice defines the lenslets (the first arrayed surface).
    std::size_t first_arrayed_surface() const { return first_arrayed_; }
    /// Lattice of the lenslets; for Designs III/IV the meso-pixel lattice.
    const Lattice& lattice() const;
    /// Print dot size on the pattern plane along x and y, mm.
    Eigen::Vector2d dot_mm() const;

    /// Where the chief ray of direction d (through the centre of the entrance element: the
    /// vertex of lenslet `cell` for I/II, the main lens's centre for III/IV) meets the
    /// encoding plane, relative to the centre of `cell`. nullopt if the ray does not arrive
    /// (the status says why).
    struct Landing {
        Eigen::Vector2d offset = Eigen::Vector2d::Zero();  ///< mm from the cell centre
        RayStatus status = RayStatus::Ok;
        CellIndex cell{};  ///< cell the ray arrived under (== entry cell unless wrap-over)
        int surface = -1;  ///< surface where the ray stopped (the encoding surface if it got there)
    };
    Landing land(const Eigen::Vector3d& direction, CellIndex cell, Model model) const;

    /// Inverse map: the incident direction whose chief ray lands at `offset` from the
    /// centre of `cell` on the encoding plane. Paraxial: closed form from the lenslet's
    /// matrix. Exact: Newton iteration on the exact forward map, started from the paraxial
    /// answer; nullopt where it does not converge to within 1e-9 mm (beyond wrap-over).
    std::optional<Eigen::Vector3d> direction_for(const Eigen::Vector2d& offset, CellIndex cell,
                                                 Model model) const;

    /// Slope-per-offset of the paraxial map: offset = B * (tan_x, tan_y); B in mm.
    double paraxial_b() const { return paraxial_b_; }

    /// Fraction of a uniform bundle filling the entry lenslet (or the main lens) at the
    /// given direction that reaches the last surface, and where the rest was lost.
    struct BundleReport {
        std::size_t rays = 0;
        std::size_t arrived = 0;
        std::size_t crossed = 0;  ///< landed under a neighbouring lenslet (wrap-over)
        double transmitted = 0.0; ///< sum of Fresnel transmittances of the rays that arrived
        std::vector<std::array<std::size_t, kRayStatusCount>> lost_per_surface;
        double rms_spot_radius = 0.0;  ///< mm, on the encoding plane, rays that got there
    };
    BundleReport trace_bundle(const Eigen::Vector3d& direction, CellIndex cell,
                              int rays_per_side) const;

    /// Whether any ray of a parallel beam along `direction` that enters the lenslet `cell`
    /// (I/II; the main lens for III/IV) crosses into a neighbouring lenslet. The beam is
    /// sampled where it meets the entry surface, not in its vertex plane: on the aperture's
    /// rim (every corner of the cell and `rays_per_side` points along each edge), where the
    /// steep edge of a lenslet sends the light furthest, and on a grid of `rays_per_side`
    /// squared points spanning the aperture edge to edge. Stops at the first ray that crosses.
    bool bundle_crosses(const Eigen::Vector3d& direction, CellIndex cell, int rays_per_side) const;

    /// Centre cell of the lattice (the lenslet nearest the axis).
    CellIndex centre_cell() const;

private:
    Ray chief_ray(const Eigen::Vector3d& direction, CellIndex cell) const;

    Design design_;
    SequentialSystem system_;
    std::size_t encoding_surface_ = 0;
    std::size_t first_arrayed_ = 0;
    double paraxial_b_ = 0.0;
    double entry_z_ = 0.0;  // plane where chief rays are aimed (entrance element's vertex)
};

}  // namespace rfd::optics
