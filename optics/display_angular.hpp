#pragma once
// Forward simulation of the observer-variant displays (Designs III and IV, thesis 8.3): light
// from distant sources behind the display, through the main lens (A), the field lens (B),
// the meso-pixel lenslets (C), the printed pattern between the back-to-back pair (D) and the
// projection lenslets (E), out toward the observer. Design III is one macro-pixel; Design
// IV is a grid of them (the design's [macro] table), each with its own optics.
//
// Method (forward, then binned by output direction). For every light direction a square
// grid of rays over the main lens's clear aperture (spacing delta, mm) is traced to the
// pattern plane, takes the transmittance of the dot it crosses, and is traced on out of
// the last surface of E. A ray that leaves its lenslet on D or E goes on through the one it
// crossed into and is counted as crosstalk (it lights the neighbour's meso-pixel, through
// dots encoded for another incident bin); a ray stopped by an aperture or the array's edge
// is lost (vignetting). The macro-pixels of Design IV see the same distant light through
// identical optics, so the rays are traced once and only the dots they cross differ.
//
// Why forward and not back from the viewpoint: a point light is a delta in incident
// direction and a distant observer a delta in output direction; one side must be smoothed.
// Traced forward, the rays of a point light form a regular grid in output slope space (the
// paraxial map from main-lens position y_A to output slope is linear, tan_out = G y_A +
// const, the same in x and y), so a tent kernel whose radius is a whole number of ray
// spacings |G| delta sums to the exact density there: a clear pattern gives the closed form
// below, no noise. Tracing back would need a kernel over incident directions instead, and
// would lose the efficiency and crosstalk bookkeeping that the forward rays give for free.
//
// Output unit: relative radiance. A meso-pixel's radiance toward a viewpoint is the power
// its lenslet E_k sends into the solid angle around that direction divided by the solid
// angle and by the lenslet's area projected toward it (the observer sees E_k filled, as
// the thesis's distant camera did). With P_r the power of a ray and K the tent kernel over
// output slopes (unit integral):
//     radiance / irradiance = sum_r (P_r / E) K(tan_r - tan_view) / (a_E cos^4 theta_view)
// and the value reported is that over the reference 1 / (a_E G^2): the radiance per unit
// irradiance of a lossless display with a clear pattern, lit and seen head-on. So a clear
// pattern under paraxial optics gives cos(theta_light) / cos^4(theta_view) where its dots
// are lit, and a printed transmittance t gives t times that: what the pattern encoder's
// field value / white stands for.
//
// Viewpoints: a distant observer (one output direction for every meso-pixel), or an eye at
// a point in front of the display (each meso-pixel seen along the line from its centre on
// E's last vertex plane to the eye). Directions are unit vectors of travel in the system
// frame (surface.hpp: z toward the observer, x right, y up as the observer sees the
// display), which is the field frame of patterns/angular.hpp for views.
//
// Example: AngularDisplaySimulator sim(load_design("designs/design3.toml"));
//          AngularSimulationOptions o; o.views = {Viewpoint{}};
//          AngularDisplayOutput out = sim.simulate(pattern, {{incident_direction(0.1, 0.0)}}, o);

#include <array>
#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/options.hpp"
#include "core/image.hpp"
#include "optics/analysis.hpp"
#include "optics/design.hpp"
#include "optics/display.hpp"
#include "optics/meso_pixel.hpp"

namespace rfd::optics {

/// A macro-pixel of Design IV: u to the right, v up, (0, 0) bottom left. Design III has one.
struct MacroPixel {
    int u = 0, v = 0;
    friend bool operator==(MacroPixel, MacroPixel) = default;
};

/// Where the observer is.
struct Viewpoint {
    /// Unit direction from the display toward a distant observer (z > 0): the output
    /// direction of travel every meso-pixel is seen along.
    Eigen::Vector3d direction = Eigen::Vector3d::UnitZ();
    /// Or an eye at this point, mm: x, y in the display frame (origin on the axis of the
    /// macro grid), z in front of the last surface's vertex plane (> 0).
    std::optional<Eigen::Vector3d> eye_mm;
};

/// The rays of a Design III/IV prediction: one grid over the main lens.
inline constexpr IntegerOption kLensRaysOption{"--lens-rays", "", "", 2, 4096, 128,
                                               "Designs III/IV: rays per side across the main lens"};

struct AngularSimulationOptions {
    Model model = Model::Paraxial;
    int rays_per_side = static_cast<int>(kLensRaysOption.fallback);  ///< across the main lens's clear diameter
    /// Radius of the tent kernel over output slopes, in paraxial ray spacings |G| delta
    /// (a whole number keeps the paraxial density exact).
    double kernel_spacings = 2.0;
    int area_samples_per_side = 5;  ///< directions per side of the grid over an area light
    std::vector<Viewpoint> views;   ///< an image per viewpoint
    std::vector<MacroPixel> distributions;  ///< an angular distribution image per macro-pixel
    int distribution_pixels = 64;   ///< per side of a distribution image
};

/// What leaves the display.
struct AngularDisplayOutput {
    /// Per viewpoint: the relative radiance of every meso-pixel toward it, RGB,
    /// (macro_x * count_x) x (macro_y * count_y) pixels, row 0 at the top; macro-pixel (u, v)
    /// holds columns u * count_x ... and its meso cell (i, j) column u * count_x + i.
    std::vector<Image> views;
    /// Per requested macro-pixel: its relative radiance (the mean over its meso-pixels, as
    /// an observer too far away to resolve them sees it) toward the output directions with
    /// slopes (tan_x, tan_y) on a square grid over [-half_tan, half_tan]^2; pixel centres,
    /// row 0 at +tan_y, x right. A screen in front of the display shows this (figure 8.13).
    std::vector<Image> distributions;
    double distribution_half_tan = 0.0;
    double kernel_half_tan = 0.0;  ///< radius of the kernel over output slopes
    double slope_gain = 0.0;       ///< G: output slope per mm on the main lens (paraxial), 1/mm
    /// The radiance a value of 1 stands for, per unit irradiance of the light: 1 / (a_E G^2), 1/sr.
    double reference_radiance_per_sr = 0.0;
    std::size_t rays = 0;          ///< rays traced (the optics are shared by all macro-pixels)
    std::size_t directions = 0;    ///< light directions sampled
    std::size_t lost = 0;          ///< rays that did not leave the display
    std::size_t crossed = 0;       ///< rays that left through a neighbouring lenslet
    /// Power leaving the last surface over the power entering the main lens: with the
    /// pattern clear (the optics' efficiency), and as printed (per channel, all macro-pixels).
    double optical_efficiency = 0.0;
    std::array<double, 3> pattern_efficiency{};
    double crossed_fraction = 0.0;  ///< of the entering power, leaving through a neighbour
    /// Fraction of the entering power lost at each surface where any is lost (label, fraction).
    std::vector<std::pair<std::string, double>> lost_fraction;
};

class AngularDisplaySimulator {
public:
    /// Designs III and IV only; InputError otherwise.
    explicit AngularDisplaySimulator(const Design& design);
    AngularDisplaySimulator(const AngularDisplaySimulator&) = delete;
    AngularDisplaySimulator& operator=(const AngularDisplaySimulator&) = delete;

    const DesignOptics& optics() const { return optics_; }
    const MesoPixelOptics& meso() const { return meso_; }
    int macro_x() const { return macro_x_; }
    int macro_y() const { return macro_y_; }
    /// Centre of macro-pixel (u, v) on the pattern plane, mm (the layout of patterns/angular.hpp).
    Eigen::Vector2d macro_centre(MacroPixel m) const;
    /// Output slope per mm of main-lens position, paraxial (the G above), 1/mm.
    double slope_gain() const { return slope_gain_; }

    /// What leaves the display under `lights` (each with d.z() > 0), seen from the options'
    /// viewpoints. InputError for a light from the front, a bad colour or radius, a
    /// viewpoint behind the display, a macro-pixel off the grid or bad sampling options.
    AngularDisplayOutput simulate(const Transparency& pattern, const std::vector<DisplayLight>& lights,
                                  const AngularSimulationOptions& options) const;

    /// The picture of a view image at the macro-pixel resolution (macro_x x macro_y, row 0
    /// at the top): the mean over each macro-pixel's meso-pixels.
    Image per_macro_pixel(const Image& view) const;

private:
    DesignOptics optics_;
    MesoPixelOptics meso_;
    int macro_x_ = 1, macro_y_ = 1;
    double macro_pitch_x_ = 0.0, macro_pitch_y_ = 0.0;
    double slope_gain_ = 0.0;
};

}  // namespace rfd::optics
