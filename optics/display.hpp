#pragma once
// Forward simulation of the observer-invariant displays (Designs I and II, thesis 8.2):
// light from distant sources behind the display, through the lens array (A), modulated by
// the printed transparency in the encoding plane (B), onto the diffuser (C), where the
// observer sees it. Everything the thesis observed follows from tracing it: Design I's
// per-direction images shifting on the diffuser as the light moves, Design II's corrective
// lenslets holding them on their macro-pixel, wrap-over into the neighbouring lenslet at
// steep angles, vignetting, several lights adding up.
//
// Method: for every light direction, a square grid of rays over a lenslet's cell at the
// entrance plane (the rays inside the cell; the grids of neighbouring cells tile the
// plane) is traced to the encoding surface, takes the transmittance of the print dot it
// lands on, and is traced on to the diffuser's face, where its power is splatted
// (bilinearly) into the output image. A ray that leaves its lenslet is not lost: it goes
// on through the lenslet it has crossed into (wrap-over is crosstalk, not darkness).
// Paraxial: each lenslet's augmented matrices, no Fresnel losses. Exact: real surfaces,
// Snell's law, apertures, total internal reflection, Fresnel transmittance.
// Every lenslet is identical and sits among identical neighbours, so the rays are traced
// once, through the centre lenslet of a wide reference array, and every lenslet of the
// display repeats them shifted to its centre; the cost of the optics (either model) is
// then independent of the lenslet count, and what remains per lenslet is one pattern
// lookup and one splat per ray. At the array's edge a ray that would cross into a
// lenslet beyond it is lost. Many directions (an environment map) share a budget of rays
// per lenslet (SimulationOptions::max_rays_per_lenslet) instead of a full grid each.
//
// Units: an output value is the irradiance on the diffuser divided by the light's
// irradiance on a plane facing it; a fully transparent pattern lit head-on averages the
// display's light efficiency. Directions: d is the direction the light travels
// (d.z() > 0: from the back toward the observer), as in analysis.hpp.
//
// Example: RasterTransparency t(w, h, 3, dot_x, dot_y, values);
//          DisplaySimulator sim(design);
//          DiffuserImage out = sim.simulate(t, {{incident_direction(0.2, 0.0), {1, 1, 1}}}, {});

#include <array>
#include <cmath>
#include <cstddef>
#include <memory>
#include <span>
#include <vector>

#include <Eigen/Core>

#include "core/options.hpp"
#include "core/image.hpp"
#include "optics/analysis.hpp"
#include "optics/design.hpp"

namespace rfd::optics {

/// The printed pattern as light meets it: the transmittance of each print dot.
class Transparency {
public:
    virtual ~Transparency() = default;
    virtual int channels() const = 0;
    /// For each point (mm, the encoding plane's frame: origin on the array's axis, x right,
    /// y up) the transmittance in [0, 1] of the dot under it, `channels()` values per point
    /// (channel fastest); 0 off the sheet. Called once per batch of rays, so an
    /// implementation may stream its dots (sorting the points by row).
    virtual void sample(std::span<const Eigen::Vector2d> points, std::span<float> out) const = 0;
};

/// A transparency held in memory: width x height dots of dot_x by dot_y mm, centred on the
/// axis, row 0 at the top (the layout of patterns::PatternGeometry), values interleaved.
class RasterTransparency final : public Transparency {
public:
    RasterTransparency(int width, int height, int channels, double dot_x, double dot_y, std::vector<float> values);
    int channels() const override { return channels_; }
    void sample(std::span<const Eigen::Vector2d> points, std::span<float> out) const override;

private:
    int width_, height_, channels_;
    double dot_x_, dot_y_;
    std::vector<float> values_;
};

/// A print that transmits everything: the display's own response to a light (its flat
/// field), the reference every comparison scales by. Points at 1e20 mm or beyond (the
/// simulators' mark for a ray that never reached the pattern) read 0.
class ClearTransparency final : public Transparency {
public:
    int channels() const override { return 1; }
    void sample(std::span<const Eigen::Vector2d> points, std::span<float> out) const override {
        for (std::size_t k = 0; k < points.size(); ++k) out[k] = points[k].norm() < 1e20 ? 1.0f : 0.0f;
    }
};

/// A distant light: a direction of travel, a colour (its irradiance per channel on a plane
/// facing it) and, for an area source, an angular radius (a uniform disc of directions).
struct DisplayLight {
    Eigen::Vector3d direction = Eigen::Vector3d::UnitZ();
    std::array<double, 3> colour{1.0, 1.0, 1.0};
    double angular_radius_rad = 0.0;
};

/// The rays of a Design I/II prediction: a grid per lenslet and light direction.
inline constexpr IntegerOption kRaysPerSideOption{"--rays-per-side", "", "", 1, 256, 8,
                                                  "Rays per side of each lenslet's grid, per light direction",
                                                  "--rays"};

struct SimulationOptions {
    Model model = Model::Paraxial;
    int rays_per_side = static_cast<int>(kRaysPerSideOption.fallback);  ///< per lenslet, over the cell's bounding box
    double pixels_per_pitch = 8.0;  ///< output pixels per lenslet pitch along x
    /// At most this many directions per side of the square grid over an area light's disc;
    /// fewer when the disc spans fewer print dots on the pattern plane (1 for points).
    int area_samples_per_side = 5;
    /// Rays per lenslet over all directions together. While every direction's full grid
    /// fits, each gets it; beyond (an environment map's many directions), each direction
    /// gets an equal share, at offsets that continue one low-discrepancy sequence.
    std::size_t max_rays_per_lenslet = 4096;
};

/// What the diffuser shows.
struct DiffuserImage {
    Image image;                 ///< relative irradiance (RGB), row 0 at the top
    double pixel_mm = 0.0;       ///< square pixels
    Eigen::Vector2d first_pixel = Eigen::Vector2d::Zero();  ///< centre of pixel (0, 0), mm
    std::size_t rays = 0;        ///< rays traced
    std::size_t directions = 0;  ///< light directions sampled
    std::size_t rays_per_direction = 0;  ///< per lenslet (over its cell's bounding box)
    std::size_t lost = 0;        ///< rays that did not reach the diffuser
    std::size_t crossed = 0;     ///< rays that reached it through a neighbouring lenslet
    /// Power reaching the diffuser over the power entering the lenslets, per channel, with
    /// the pattern taken as fully transparent (the optics' efficiency) and as printed.
    double optical_efficiency = 0.0;
    std::array<double, 3> pattern_efficiency{};

    /// The centre of pixel (x, y), mm.
    Eigen::Vector2d pixel_centre(int x, int y) const {
        return first_pixel + Eigen::Vector2d(x * pixel_mm, -y * pixel_mm);
    }
};

/// What the observer sees when light also falls on the display's front (thesis 8.2.2,
/// figure 8.7): the diffuser passes a fraction `transmittance` of the irradiance reaching it
/// from behind toward the observer and scatters back a fraction `reflectance` of the
/// illuminance on its front, both as Lambertian sources. With the back light's irradiance
/// as unit and r = front illuminance / back irradiance, a place of relative irradiance E
/// (DiffuserImage units) looks like T E + rho r, so
///     contrast(r) = (T white + rho r) / (T black + rho r),
/// white and black being the 99th and 1st percentiles of the picture's luminance (Rec. 709
/// weights) over its lenslets. r = 0 is the dark room; contrast is infinite when black is 0.
struct DiffuserScatter {
    double transmittance = 0.47;  ///< figure 8.7: 28 % with the Intellicoat film vs 60 % without
    double reflectance = 0.5;     ///< nominal: film diffusers send back about half the front light
};
struct FrontLightContrast {
    double front_ratio = 0.0;
    double contrast = 0.0;
};
struct PictureContrast {
    double white = 0.0, black = 0.0;  ///< relative irradiance on the diffuser
    double transmissivity = 0.0;      ///< T white: the display's brightness over its back light's
    std::vector<FrontLightContrast> with_front;
};
PictureContrast picture_contrast(const Image& per_lenslet, const DiffuserScatter& diffuser,
                                 std::span<const double> front_ratios);

/// The mean of `image` over each lenslet's cell, or over its core (the cell shrunk by
/// `core_fraction` about its centre, where a Design II macro-pixel's neighbours do not
/// reach): the picture at the display's own resolution, count_x by count_y, row 0 at the
/// top (cell row count_y - 1). For hexagonal lattices odd rows are shifted by half a pixel
/// on screen; here each lenslet simply takes its column. A lenslet whose region holds no
/// pixel centre reads 0.
Image per_lenslet(const Lattice& lattice, const DiffuserImage& image, double core_fraction = 1.0);

/// The directions sampling a light: its own for a point source, a square grid of
/// per_side x per_side over the disc of an area source (those inside it, equal weights).
std::vector<Eigen::Vector3d> disc_directions(const DisplayLight& light, int per_side);

/// One ray of a lenslet as every lenslet of the display repeats it, shifted to its centre:
/// where it meets the pattern and the diffuser, what it carries and, for a ray that crossed
/// into neighbouring lenslets, where those lie relative to its own.
struct LensletRay {
    Eigen::Vector2d on_pattern = Eigen::Vector2d::Zero();   ///< mm from its lenslet's centre
    Eigen::Vector2d on_diffuser = Eigen::Vector2d::Zero();  ///< likewise
    double entering = 0.0;            ///< power entering the lenslet: ray area (mm^2) x cos(incidence)
    double reaching = 0.0;            ///< of which reaches the diffuser (Fresnel losses)
    std::array<double, 3> colour{};   ///< the light's irradiance share per channel
    std::size_t first_neighbour = 0, neighbours = 0;  ///< into RepeatedRays::neighbour_offsets
    bool crossed = false;             ///< passed from one lenslet into another (wrap-over)
};

/// What every lenslet repeats under a set of lights: the rays that reach the diffuser,
/// sorted by where they land along y (descending), and the light entering a lenslet in all.
/// A ray exists at a lenslet only when every neighbour it passes through is in the array.
struct RepeatedRays {
    std::vector<LensletRay> rays;
    std::vector<Eigen::Vector2d> neighbour_offsets;  ///< mm, from a lenslet's centre to its neighbours'
    double entering = 0.0;                           ///< per lenslet
    std::array<double, 3> entering_colour{};         ///< per lenslet and channel
    std::size_t lost = 0;                            ///< per lenslet: rays that do not reach the diffuser
    /// The box the rays land in on the diffuser, mm from their lenslet's centre.
    Eigen::Vector2d reach_min = Eigen::Vector2d::Constant(HUGE_VAL), reach_max = -reach_min;
};

class DisplaySimulator {
public:
    /// Designs I and II only; InputError otherwise.
    explicit DisplaySimulator(const Design& design);

    const DesignOptics& optics() const { return optics_; }
    /// Index of the diffuser's light-side face in the system.
    std::size_t diffuser_surface() const { return diffuser_surface_; }

    /// The diffuser image under `lights` (each with d.z() > 0; InputError otherwise).
    DiffuserImage simulate(const Transparency& pattern, const std::vector<DisplayLight>& lights,
                           const SimulationOptions& options) const;

    /// The rays one lenslet repeats under `lights` (simulate()'s, before any pattern): for
    /// callers that apply the same optics to many patterns (predict/optimize.hpp).
    RepeatedRays trace_lenslet(const std::vector<DisplayLight>& lights, const SimulationOptions& options) const;

    /// The mean of `image` over each lenslet's cell: the picture at the display's own
    /// resolution (one value per lenslet), see optics::per_lenslet.
    Image per_lenslet(const DiffuserImage& image) const;

private:
    DesignOptics optics_;
    /// The design with wide lenslet arrays, whose centre lenslet's rays every lenslet repeats.
    std::shared_ptr<const DesignOptics> reference_;
    std::size_t diffuser_surface_ = 0;
};

}  // namespace rfd::optics
