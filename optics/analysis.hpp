#pragma once
// Analyses of a display design, in both models of light (paraxial and exact):
//  - the forward map: where light from an incident direction lands on the encoding plane
//    of a lenslet (the pattern plane of Designs I/II, the meso-pixel plane of III/IV);
//  - the inverse map the pattern encoder needs (thesis 8.4): encoding-plane position ->
//    incident direction;
//  - wrap-over: the incident angle where light entering one lenslet starts to land under
//    its neighbour, along the flat and the corner directions of the cell;
//  - field of view, spot size, vignetting and the fraction of rays lost at each surface.
//
// Directions: the incident light travels along d = (tan_x, tan_y, 1)/|.| in the system
// frame (surface.hpp). An incident angle (theta, phi) means d = (sin theta cos phi,
// sin theta sin phi, cos theta): theta from the axis, phi counter-clockwise from +x as the
// observer sees it. Positions on the encoding plane are relative to the lenslet's centre.

#include <array>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/LU>

#include "optics/design.hpp"
#include "optics/exact.hpp"
#include "optics/model.hpp"
#include "optics/paraxial.hpp"

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

/// Incident angle (degrees) along azimuth phi where the chief ray of the centre lenslet
/// first lands outside its cell on the encoding plane, by bisection. nullopt if it stays
/// inside up to 89 degrees.
std::optional<double> wrap_over_angle(const DesignOptics& optics, double phi_rad, Model model);

/// Incident angle (degrees) along phi where the first ray of a full bundle is lost or
/// crosses into a neighbour (crosstalk begins); exact model.
std::optional<double> first_loss_angle(const DesignOptics& optics, double phi_rad,
                                       int rays_per_side);

/// A pair of planes the design needs to be conjugate (or a plane that must lie in a
/// focal plane), and how far the prescription puts it from there.
struct ConjugateCheck {
    std::string description;  ///< e.g. "diffuser C = image of A through B"
    double plane_z = 0.0;     ///< where the plane is, mm
    double target_z = 0.0;    ///< where the paraxial optics want it, mm (NaN: at infinity)
    double magnification = std::numeric_limits<double>::quiet_NaN();  ///< NaN if n/a
    double tolerance = 0.0;   ///< mm; beyond it the design rule warns
};

/// z of the paraxial image of the plane `object_z` through surfaces [first, last];
/// nullopt when it is imaged to infinity. The magnification goes to `magnification`.
std::optional<double> image_z(const SequentialSystem& system, std::size_t first,
                              std::size_t last, double object_z, double* magnification);

/// The summary `rfd design show` prints.
struct DesignSummary {
    std::string name;
    std::string kind;
    std::string lattice;            ///< "hexagonal" or "rectangular"
    double pitch_x = 0, pitch_y = 0;   ///< mm (pitch_y: row spacing)
    int count_x = 0, count_y = 0;
    std::optional<MacroGrid> macro;    ///< Design IV's grid of Design III cells
    double focal_length_nominal = 0;   ///< mm, the maker's value for the encoding lens
    double focal_length_paraxial = 0;  ///< mm, EFL from the prescription
    double dpi_x = 0, dpi_y = 0;
    double directions_per_lenslet = 0; ///< print pixels under one lenslet cell
    double angular_step_x_deg = 0, angular_step_y_deg = 0;  ///< per print pixel, on axis
    std::vector<std::pair<std::string, double>> wrap_over_paraxial_deg;  ///< per direction
    std::vector<std::pair<std::string, double>> wrap_over_exact_deg;
    std::vector<std::pair<std::string, double>> crosstalk_exact_deg;
    double field_of_view_deg = 0;      ///< full cone where no direction wraps (exact, min)
    double efficiency_on_axis = 0;     ///< fraction of light on the entry aperture arriving
    double efficiency_at_half_fov = 0;
    double efficiency_fresnel_on_axis = 0;      ///< the same with Fresnel reflection losses
    double efficiency_fresnel_at_half_fov = 0;
    /// Where the rays of a full bundle are lost, on axis and at half the field of view:
    /// (angle in degrees, surface label, status, fraction of the bundle).
    struct Loss {
        double angle_deg = 0;
        std::string surface;
        RayStatus status = RayStatus::Ok;
        double fraction = 0;
    };
    std::vector<Loss> losses;
    double spot_rms_on_axis_um = 0;
    double spot_rms_at_half_fov_um = 0;
    double focus_error_mm = 0;         ///< encoding plane minus paraxial focus (z)
    std::vector<ConjugateCheck> conjugates;
    std::vector<std::string> warnings;
};
DesignSummary summarise(const DesignOptics& optics);

/// One line of the speed-versus-accuracy chart: paraxial against exact landing position.
struct ChartRow {
    double angle_deg = 0;
    double paraxial_mm = 0, exact_mm = 0;  ///< landing offset along the sweep direction
    double error_um = 0;
    double error_pixels = 0;               ///< in print dots along the sweep direction
    RayStatus exact_status = RayStatus::Ok;
};
struct Chart {
    std::string direction;  ///< "x" or "y" (the flat or corner direction for hex cells)
    std::vector<ChartRow> rows;
    std::optional<double> half_pixel_angle_deg;  ///< where |error| first exceeds 0.5 px
};
Chart accuracy_chart(const DesignOptics& optics, double phi_rad, const std::string& name,
                     double max_angle_deg, int steps);

/// Rays per second each model traces from the entrance to the encoding plane, measured
/// on `rays` rays spread over the array within +-`max_angle_deg`, with the batch tracers
/// (all cores). A wall-clock measurement: it varies from machine to machine and run to run.
double measure_rays_per_second(const DesignOptics& optics, Model model, std::size_t rays,
                               double max_angle_deg);

}  // namespace rfd::optics
