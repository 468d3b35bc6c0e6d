#pragma once
// Analyses of a display design, in both models of light (paraxial and exact):
//  (the forward and inverse maps between incident direction and encoding-plane position
//  are DesignOptics, optics/design_optics.hpp, whose frame and conventions hold here)
//  - wrap-over: the incident angle where light entering one lenslet starts to land under
//    its neighbour, along the flat and the corner directions of the cell;
//  - field of view, spot size, vignetting and the fraction of rays lost at each surface.
// The paraxial model's error against the exact one, charted, is optics/accuracy_chart.hpp.

#include <array>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/LU>

#include "optics/design.hpp"
#include "optics/design_optics.hpp"
#include "optics/exact.hpp"
#include "optics/model.hpp"
#include "optics/paraxial.hpp"

namespace rfd::optics {

/// The largest incident angle the searches below look at, degrees.
inline constexpr double kWrapOverSearchLimitDeg = 89.0;

/// The azimuths the analyses sweep for a lattice: the flat and corner directions of a
/// hexagonal cell; x, y and the diagonal of a rectangular one.
struct SweepDirection {
    std::string name;  ///< for reports, e.g. "flat (x)"
    std::string file;  ///< for file names, e.g. "x"
    double phi = 0.0;  ///< radians, counter-clockwise from +x
};
std::vector<SweepDirection> sweep_directions(const Lattice& lattice);

/// Incident angle (degrees) along azimuth phi where the chief ray of the centre lenslet
/// first lands outside its cell on the encoding plane, by bisection. nullopt if it stays
/// inside up to kWrapOverSearchLimitDeg.
std::optional<double> wrap_over_angle(const DesignOptics& optics, double phi_rad, Model model);

/// Incident angle (degrees) along phi where the first ray of the beam entering the centre
/// lenslet crosses into a neighbour (crosstalk begins), with bundle_crosses(); exact model.
std::optional<double> first_loss_angle(const DesignOptics& optics, double phi_rad,
                                       int rays_per_side);

/// A pair of planes the design needs to be conjugate (or a plane that must lie in a
/// focal plane), and how far the prescription puts it from there.
struct ConjugateCheck {
    std::string key;          ///< short name for options, e.g. "diffuser-image"
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
    /// Per sweep direction; nullopt: none up to kWrapOverSearchLimitDeg.
    std::vector<std::pair<std::string, std::optional<double>>> wrap_over_paraxial_deg;
    std::vector<std::pair<std::string, std::optional<double>>> wrap_over_exact_deg;
    std::vector<std::pair<std::string, std::optional<double>>> crosstalk_exact_deg;
    /// Full cone where no direction wraps over (exact, min); nullopt when none does.
    std::optional<double> field_of_view_deg;
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

}  // namespace rfd::optics
