// The Design III/IV forward simulator (optics/display_angular.hpp) against closed forms and
// round trips: a clear pattern's radiance cos(theta_l) / cos^4(theta_v) under paraxial
// optics, the lit output directions of a meso-pixel against MesoPixelOptics's dot statuses
// and the front-focal-plane rule tan = -p / f, a field encoded by the pattern encoder and
// seen again through the simulated display, linearity in lights, a light outside the
// display's acceptance, eyes against distant views, the distribution images against the
// view images, determinism and bad input.

#include <cmath>
#include <cstring>
#include <fstream>
#include <sstream>
#include <string>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "core/error.hpp"
#include "core/image.hpp"
#include "core/units.hpp"
#include "optics/display_angular.hpp"
#include "patterns/angular.hpp"
#include "tests/support/temp_dir.hpp"
#include "tests/support/bundled.hpp"

namespace rfd::optics {
namespace {

using ::testing::HasSubstr;
using rfd::testing::bundled_design;
using rfd::testing::TempDir;

// Design IV with 2 x 2 macro-pixels instead of 7 x 7: the same optics, a smaller pattern.
Design small_design4(const TempDir& dir) {
    std::ifstream in(std::string(RFD_SOURCE_DIR) + "/designs/design4.toml");
    std::stringstream text;
    text << in.rdbuf();
    std::string s = text.str();
    const std::string grid = "count = [7, 7]";
    const auto at = s.find(grid);
    EXPECT_NE(at, std::string::npos);
    s.replace(at, grid.size(), "count = [2, 2]");
    const auto path = dir.path() / "design4_small.toml";
    std::ofstream(path) << s;
    return load_design(path.string());
}

// An encoded pattern as an ideal printer prints it: transmittance = value / white.
RasterTransparency printed(const patterns::PatternSource& source, double white) {
    const auto& g = source.geometry();
    const std::size_t row = static_cast<std::size_t>(g.width) * static_cast<std::size_t>(source.channels());
    std::vector<float> values(row * static_cast<std::size_t>(g.height));
    for (int y = 0; y < g.height; ++y) source.render_row(y, std::span<float>(values.data() + y * row, row));
    for (float& v : values) v = static_cast<float>(v / white);
    return RasterTransparency(g.width, g.height, source.channels(), g.dot_x, g.dot_y, std::move(values));
}

Eigen::Vector3d from_slopes(double tx, double ty) { return Eigen::Vector3d(tx, ty, 1.0).normalized(); }
float largest(const Image& image) {
    float most = 0.0f;
    for (int c = 0; c < image.channels(); ++c)
        for (const float v : image.plane(c)) most = std::max(most, v);
    return most;
}

bool same_bits(const Image& a, const Image& b) {
    if (a.width() != b.width() || a.height() != b.height() || a.channels() != b.channels()) return false;
    for (int c = 0; c < a.channels(); ++c)
        if (std::memcmp(a.plane(c).data(), b.plane(c).data(), a.plane(c).size_bytes()) != 0) return false;
    return true;
}

double inverse_cos4(const Eigen::Vector3d& d) { return 1.0 / std::pow(d.normalized().z(), 4); }

// The meso-pixel (cell) pixel of macro-pixel (u, v) in a view image.
float pixel(const Image& view, const Lattice& lattice, int macro_y, int u, int v, CellIndex cell, int c = 0) {
    const int height = macro_y * lattice.count_y();
    return view.at(u * lattice.count_x() + cell.i, height - 1 - (v * lattice.count_y() + cell.j), c);
}

// A smooth positive field that varies with the light, the view and the macro-pixel.
void smooth(const Eigen::Vector3d& light, const Eigen::Vector3d& view, int u, int v, std::span<float> out) {
    out[0] = static_cast<float>(0.8 + 1.5 * view.x() - 1.0 * view.y() + 0.3 * light.x() + 0.2 * light.y() + 0.1 * u +
                                0.15 * v);
}

TEST(AngularDisplay, ClearPatternGivesTheClosedFormRadiance) {
    const AngularDisplaySimulator sim(bundled_design(3));
    const Lattice& lattice = sim.meso().lattice();
    const CellIndex cell{1, 2};
    const Eigen::Vector3d light = sim.meso().bin(cell, Model::Paraxial, 1).centre;
    AngularSimulationOptions options;
    options.rays_per_side = 96;
    for (const auto& [tx, ty] : {std::pair{0.0, 0.0}, {0.05, -0.03}, {-0.08, 0.06}})
        options.views.push_back({from_slopes(tx, ty), std::nullopt});
    const AngularDisplayOutput out = sim.simulate(ClearTransparency(), {{light, {1, 1, 1}, 0.0}}, options);
    ASSERT_EQ(out.views.size(), 3u);
    for (std::size_t w = 0; w < options.views.size(); ++w) {
        const double expected = light.z() * inverse_cos4(options.views[w].direction);
        for (int j = 0; j < lattice.count_y(); ++j)
            for (int i = 0; i < lattice.count_x(); ++i) {
                const float value = pixel(out.views[w], lattice, 1, 0, 0, {i, j});
                if (CellIndex{i, j} == cell)
                    EXPECT_NEAR(value, expected, 1e-5 * expected) << "view " << w;
                else
                    EXPECT_LT(value, 1e-6) << "cell " << i << "," << j << " view " << w;
            }
    }
    // The reference radiance is 1 / (a_E G^2).
    EXPECT_NEAR(out.reference_radiance_per_sr, 1.0 / (lattice.cell_area() * sim.slope_gain() * sim.slope_gain()), 1e-9);
    // Every entering ray is accounted for: it leaves, or is lost at one surface.
    double lost = 0.0;
    for (const auto& [surface, fraction] : out.lost_fraction) lost += fraction;
    EXPECT_NEAR(out.optical_efficiency + lost, 1.0, 1e-12);
    EXPECT_GT(out.optical_efficiency, 0.5);
}

// Which output directions a meso-pixel sends light into, against the chief-ray statuses of
// MesoPixelOptics (an independent tracer) and the front-focal-plane rule tan = gain * p.
TEST(AngularDisplay, LitOutputDirectionsMatchTheMesoPixelOptics) {
    const AngularDisplaySimulator sim(bundled_design(3));
    const MesoPixelOptics& meso = sim.meso();
    const Lattice& lattice = meso.lattice();
    const CellIndex cell{3, 2};
    const Eigen::Vector3d light = meso.bin(cell, Model::Paraxial, 1).centre;
    AngularSimulationOptions options;
    options.rays_per_side = 96;
    const double gain = meso.output_gain();
    // Offsets on D over 1.3 cells, each seen as the view direction tan = gain * p.
    std::vector<Eigen::Vector2d> offsets;
    const int steps = 17;
    for (int iy = 0; iy < steps; ++iy)
        for (int ix = 0; ix < steps; ++ix)
            offsets.push_back(Eigen::Vector2d((ix / (steps - 1.0) - 0.5) * 1.3 * lattice.pitch_x(),
                                              (iy / (steps - 1.0) - 0.5) * 1.3 * lattice.pitch_y()));
    for (const auto& p : offsets) options.views.push_back({from_slopes(gain * p.x(), gain * p.y()), std::nullopt});
    const AngularDisplayOutput out = sim.simulate(ClearTransparency(), {{light, {1, 1, 1}, 0.0}}, options);
    // Away from a change of status by more than the kernel (in mm on D) plus a ray spacing.
    const double margin = 1.5 * out.kernel_half_tan / std::abs(gain);
    auto lit = [&](const Eigen::Vector2d& p) {
        return lattice.cell_contains(cell, lattice.center(cell) + p) && meso.dot(p, cell, Model::Paraxial).light == DotLight::Lit;
    };
    int lit_count = 0, dark_count = 0, outside_cell = 0;
    for (std::size_t w = 0; w < offsets.size(); ++w) {
        const Eigen::Vector2d& p = offsets[w];
        const bool here = lit(p);
        bool clear_of_edges = true;
        for (const auto& step : {Eigen::Vector2d(1, 0), Eigen::Vector2d(-1, 0), Eigen::Vector2d(0, 1), Eigen::Vector2d(0, -1),
                                 Eigen::Vector2d(0.7, 0.7), Eigen::Vector2d(-0.7, 0.7), Eigen::Vector2d(0.7, -0.7),
                                 Eigen::Vector2d(-0.7, -0.7)})
            clear_of_edges = clear_of_edges && lit(p + margin * step) == here;
        if (!clear_of_edges) continue;
        const float value = pixel(out.views[w], lattice, 1, 0, 0, cell);
        if (here) {
            EXPECT_NEAR(value, light.z() * inverse_cos4(options.views[w].direction), 1e-4) << p.transpose();
            ++lit_count;
        } else {
            EXPECT_LT(value, 1e-6) << p.transpose();
            ++dark_count;
            // tan = -p / f: beyond half a pitch the light belongs to the neighbouring cell.
            if (std::abs(p.x()) > 0.5 * lattice.pitch_x() || std::abs(p.y()) > 0.5 * lattice.pitch_y()) ++outside_cell;
        }
    }
    EXPECT_GT(lit_count, 60);
    EXPECT_GT(dark_count, 40);
    EXPECT_GT(outside_cell, 30);
    // And the corners of the cell are dark: outside the image of the main lens (Unlit).
    const Eigen::Vector2d corner(0.45 * lattice.pitch_x(), 0.45 * lattice.pitch_y());
    EXPECT_EQ(meso.dot(corner, cell, Model::Paraxial).light, DotLight::Unlit);
}

// A pattern with its own optics and field, shared by the round-trip tests (slow to build).
struct Encoded {
    explicit Encoded(Design design, Model model, double dpi)
        : optics(std::move(design)), field(1, smooth), pattern(optics, field, [&] {
              patterns::AngularOptions o;
              o.model = model;
              o.table_size = 65;
              o.dpi_x = o.dpi_y = dpi;
              return o;
          }()) {
        white = patterns::estimate_white(pattern, 100.0);
    }
    DesignOptics optics;
    patterns::FunctionField field;
    patterns::AngularPattern pattern;
    double white = 1.0;

    // What the encoder meant macro-pixel (u, v) to show toward `view` under bin `cell`.
    double meant(CellIndex cell, const Eigen::Vector3d& view, int u, int v) const {
        const std::size_t bin = pattern.meso().lattice().linear_index(cell);
        double sum = 0.0;
        float one = 0.0f;
        for (const auto& light : pattern.field_bins()[bin]) {
            smooth(light, view, u, v, std::span<float>(&one, 1));
            sum += one;
        }
        return sum / static_cast<double>(pattern.field_bins()[bin].size()) / white;
    }
};

double psnr_of(const std::vector<double>& got, const std::vector<double>& want, double peak) {
    double mse = 0.0;
    for (std::size_t k = 0; k < got.size(); ++k) mse += (got[k] - want[k]) * (got[k] - want[k]);
    mse /= static_cast<double>(got.size());
    return 10.0 * std::log10(peak * peak / std::max(mse, 1e-30));
}

// Encode -> print (ideal) -> simulate -> the field's value for (bin of L, V), Design III. The
// display shows R averaged over the incident bin (its lights are binned by meso cell), at
// the dot whose output direction is V, scaled by cos(theta_l) / cos^4(theta_v).
TEST(AngularDisplay, ReproducesAnEncodedFieldThroughThePrintedPattern) {
    const Encoded encoded(bundled_design(3), Model::Paraxial, 600);
    const AngularDisplaySimulator sim(encoded.optics.design());
    const RasterTransparency transparency = printed(encoded.pattern, encoded.white);
    const Lattice& lattice = sim.meso().lattice();
    const double edge_x = std::abs(sim.meso().output_gain()) * 0.5 * lattice.pitch_x();
    const double edge_y = std::abs(sim.meso().output_gain()) * 0.5 * lattice.pitch_y();
    AngularSimulationOptions options;
    options.rays_per_side = 128;
    for (int iy = -2; iy <= 2; ++iy)
        for (int ix = -2; ix <= 2; ++ix)
            options.views.push_back({from_slopes(0.3 * ix * edge_x, 0.25 * iy * edge_y), std::nullopt});
    std::vector<double> got, want;
    for (const CellIndex cell : {CellIndex{1, 1}, CellIndex{4, 3}, CellIndex{2, 0}}) {
        const Eigen::Vector3d light = sim.meso().bin(cell, Model::Paraxial, 1).centre;
        const AngularDisplayOutput out = sim.simulate(transparency, {{light, {1, 1, 1}, 0.0}}, options);
        for (std::size_t w = 0; w < options.views.size(); ++w) {
            const Eigen::Vector3d& view = options.views[w].direction;
            got.push_back(pixel(out.views[w], lattice, 1, 0, 0, cell));
            want.push_back(encoded.meant(cell, view, 0, 0) * light.z() * inverse_cos4(view));
        }
    }
    double worst = 0.0;
    for (std::size_t k = 0; k < got.size(); ++k) worst = std::max(worst, std::abs(got[k] - want[k]));
    const double psnr = psnr_of(got, want, 1.0);
    // The printed dots are 42 um: the field changes by up to 0.02 of white from dot to dot
    // (dR/dtan ~ 1.8 / white, |gain| * 42 um of slope); the kernel spans several dots and
    // averages the steps of a linear field out, leaving a fraction of that.
    EXPECT_GT(psnr, 50.0);  // measured 60 dB
    EXPECT_LT(worst, 0.01);
    RecordProperty("psnr_db", std::to_string(psnr));
}

// The same with the exact optics on both sides, flat-fielded by the clear pattern (the
// exact optics lose light to Fresnel reflections and distort the slope grid): what a
// calibrated display shows.
TEST(AngularDisplay, ReproducesAnEncodedFieldWithTheExactOptics) {
    const Encoded encoded(bundled_design(3), Model::Exact, 600);
    const AngularDisplaySimulator sim(encoded.optics.design());
    const RasterTransparency transparency = printed(encoded.pattern, encoded.white);
    const Lattice& lattice = sim.meso().lattice();
    const double edge_x = std::abs(sim.meso().output_gain()) * 0.5 * lattice.pitch_x();
    const double edge_y = std::abs(sim.meso().output_gain()) * 0.5 * lattice.pitch_y();
    AngularSimulationOptions options;
    options.model = Model::Exact;
    options.rays_per_side = 128;
    for (int iy = -1; iy <= 1; ++iy)
        for (int ix = -2; ix <= 2; ++ix)
            options.views.push_back({from_slopes(0.3 * ix * edge_x, 0.3 * iy * edge_y), std::nullopt});
    std::vector<double> got, want;
    for (const CellIndex cell : {CellIndex{2, 2}, CellIndex{4, 1}}) {
        const Eigen::Vector3d light = sim.meso().bin(cell, Model::Exact, 1).centre;
        const AngularDisplayOutput out = sim.simulate(transparency, {{light, {1, 1, 1}, 0.0}}, options);
        const AngularDisplayOutput clear = sim.simulate(ClearTransparency(), {{light, {1, 1, 1}, 0.0}}, options);
        EXPECT_LT(out.optical_efficiency, 0.95);  // Fresnel reflections at 14 surfaces
        for (std::size_t w = 0; w < options.views.size(); ++w) {
            const double reference = pixel(clear.views[w], lattice, 1, 0, 0, cell);
            ASSERT_GT(reference, 0.5);
            got.push_back(pixel(out.views[w], lattice, 1, 0, 0, cell) / reference);
            want.push_back(encoded.meant(cell, options.views[w].direction, 0, 0));
        }
    }
    const double psnr = psnr_of(got, want, 1.0);
    EXPECT_GT(psnr, 45.0);  // measured 57 dB
    RecordProperty("psnr_db", std::to_string(psnr));
}

// Design IV: every macro-pixel shows its own (u, v) values, and the macro-resolution picture
// is the mean over the meso-pixels (only the bin's one is lit).
TEST(AngularDisplay, DesignFourMacroPixelsShowTheirOwnValues) {
    TempDir dir;
    const Encoded encoded(small_design4(dir), Model::Paraxial, 200);
    const AngularDisplaySimulator sim(encoded.optics.design());
    ASSERT_EQ(sim.macro_x(), 2);
    const RasterTransparency transparency = printed(encoded.pattern, encoded.white);
    const Lattice& lattice = sim.meso().lattice();
    const CellIndex cell{2, 3};
    const Eigen::Vector3d light = sim.meso().bin(cell, Model::Paraxial, 1).centre;
    AngularSimulationOptions options;
    options.views = {{from_slopes(0.0, 0.0), std::nullopt}, {from_slopes(0.06, -0.04), std::nullopt}};
    const AngularDisplayOutput out = sim.simulate(transparency, {{light, {1, 1, 1}, 0.0}}, options);
    for (std::size_t w = 0; w < options.views.size(); ++w) {
        const Image macro = sim.per_macro_pixel(out.views[w]);
        ASSERT_EQ(macro.width(), 2);
        for (int v = 0; v < 2; ++v)
            for (int u = 0; u < 2; ++u) {
                const Eigen::Vector3d& view = options.views[w].direction;
                const double want = encoded.meant(cell, view, u, v) * light.z() * inverse_cos4(view);
                const float got = pixel(out.views[w], lattice, 2, u, v, cell);
                // 127 um dots: the pattern is coarser here than in the Design III test.
                EXPECT_NEAR(got, want, 0.03) << "macro " << u << "," << v << " view " << w;
                EXPECT_NEAR(macro.at(u, 1 - v, 0), got / static_cast<float>(lattice.count_x() * lattice.count_y()), 1e-5);
            }
    }
}

TEST(AngularDisplay, IsLinearInTheLights) {
    const AngularDisplaySimulator sim(bundled_design(3));
    const Lattice& lattice = sim.meso().lattice();
    const Eigen::Vector3d a = sim.meso().bin({1, 1}, Model::Exact, 1).centre;
    const Eigen::Vector3d b = (sim.meso().bin({2, 1}, Model::Exact, 1).centre + Eigen::Vector3d(0.01, 0.005, 0)).normalized();
    AngularSimulationOptions options;
    options.model = Model::Exact;
    options.rays_per_side = 48;
    options.views = {{from_slopes(0.0, 0.0), std::nullopt}, {from_slopes(-0.1, 0.05), std::nullopt},
                     {from_slopes(0.12, 0.1), std::nullopt}};
    // A pattern that varies over every cell, so that the lights meet different dots.
    std::vector<float> values(200 * 200 * 3);
    for (std::size_t k = 0; k < values.size(); ++k) values[k] = static_cast<float>(0.5 + 0.5 * std::sin(0.37 * double(k)));
    const RasterTransparency pattern(200, 200, 3, 0.13, 0.13, values);
    const auto both = sim.simulate(pattern, {{a, {1, 0, 0}, 0.0}, {b, {0, 0, 2}, 0.0}}, options);
    const auto first = sim.simulate(pattern, {{a, {1, 0, 0}, 0.0}}, options);
    const auto second = sim.simulate(pattern, {{b, {0, 0, 1}, 0.0}}, options);
    double largest = 0.0;
    for (std::size_t w = 0; w < options.views.size(); ++w)
        for (int y = 0; y < lattice.count_y(); ++y)
            for (int x = 0; x < lattice.count_x(); ++x) {
                EXPECT_NEAR(both.views[w].at(x, y, 0), first.views[w].at(x, y, 0), 1e-5);
                EXPECT_NEAR(both.views[w].at(x, y, 2), 2.0f * second.views[w].at(x, y, 2), 1e-5);
                EXPECT_EQ(both.views[w].at(x, y, 1), 0.0f);
                largest = std::max(largest, double(both.views[w].at(x, y, 2)));
            }
    EXPECT_GT(largest, 0.1);  // the test saw light
}

TEST(AngularDisplay, ALightOutsideTheAcceptanceLeavesTheDisplayDark) {
    const AngularDisplaySimulator sim(bundled_design(3));
    AngularSimulationOptions options;
    options.rays_per_side = 32;
    options.views = {{from_slopes(0.0, 0.0), std::nullopt}, {from_slopes(0.1, 0.1), std::nullopt}};
    options.distributions = {{0, 0}};
    for (const Model model : {Model::Paraxial, Model::Exact}) {
        options.model = model;
        // 30 degrees: the main lens focuses it 29 mm off axis, beyond the field lens.
        const auto out = sim.simulate(ClearTransparency(), {{incident_direction(degrees_to_radians(30), 0.4), {1, 1, 1}, 0.0}}, options);
        EXPECT_EQ(out.optical_efficiency, 0.0);
        EXPECT_EQ(out.lost, out.rays);
        for (const Image& image : out.views) EXPECT_EQ(largest(image), 0.0f);
        EXPECT_EQ(largest(out.distributions[0]), 0.0f);
    }
}

// An eye far away sees what a distant observer in its direction sees; a near eye sees each
// meso-pixel along the line from it.
TEST(AngularDisplay, EyesSeeEachMesoPixelAlongTheirOwnLine) {
    const AngularDisplaySimulator sim(bundled_design(3));
    const Lattice& lattice = sim.meso().lattice();
    const CellIndex cell{3, 2};
    const Eigen::Vector3d light = sim.meso().bin(cell, Model::Paraxial, 1).centre;
    std::vector<float> values(300 * 300);
    for (std::size_t k = 0; k < values.size(); ++k) values[k] = static_cast<float>(0.5 + 0.5 * std::cos(0.011 * double(k)));
    const RasterTransparency pattern(300, 300, 1, 0.09, 0.09, values);
    const Eigen::Vector3d near_eye(30.0, -20.0, 400.0);
    AngularSimulationOptions options;
    options.rays_per_side = 64;
    options.views = {{Eigen::Vector3d(0.05, 0.02, 1.0).normalized(), std::nullopt},
                     {Eigen::Vector3d::UnitZ(), Eigen::Vector3d(0.05e8, 0.02e8, 1e8)},
                     {Eigen::Vector3d::UnitZ(), near_eye}};
    const Eigen::Vector2d centre = lattice.center(cell);
    const Eigen::Vector3d line = (near_eye - Eigen::Vector3d(centre.x(), centre.y(), 0.0)).normalized();
    options.views.push_back({line, std::nullopt});
    const auto out = sim.simulate(pattern, {{light, {1, 1, 1}, 0.0}}, options);
    const float distant = pixel(out.views[0], lattice, 1, 0, 0, cell);
    ASSERT_GT(distant, 0.05f);
    EXPECT_NEAR(pixel(out.views[1], lattice, 1, 0, 0, cell), distant, 1e-4);
    EXPECT_NEAR(pixel(out.views[2], lattice, 1, 0, 0, cell), pixel(out.views[3], lattice, 1, 0, 0, cell), 1e-5);
}

// A distribution image holds, at each pixel centre, what a distant observer there sees of
// the whole macro-pixel (when its pixels are finer than the kernel, so both use one kernel).
TEST(AngularDisplay, DistributionImagesAgreeWithTheViews) {
    const AngularDisplaySimulator sim(bundled_design(3));
    const Eigen::Vector3d light = sim.meso().bin({2, 2}, Model::Paraxial, 1).centre;
    AngularSimulationOptions options;
    options.rays_per_side = 64;
    options.distribution_pixels = 200;
    options.distributions = {{0, 0}};
    const auto probe = sim.simulate(ClearTransparency(), {{light, {1, 1, 1}, 0.0}}, options);
    const double T = probe.distribution_half_tan, step = 2.0 * T / options.distribution_pixels;
    ASSERT_LT(step, probe.kernel_half_tan);
    const std::vector<std::pair<int, int>> nodes{{100, 100}, {80, 110}, {120, 95}, {30, 40}};
    for (const auto& [x, y] : nodes)
        options.views.push_back({from_slopes(-T + (x + 0.5) * step, T - (y + 0.5) * step), std::nullopt});
    const auto out = sim.simulate(ClearTransparency(), {{light, {1, 1, 1}, 0.0}}, options);
    double lit = 0.0;
    for (std::size_t w = 0; w < nodes.size(); ++w) {
        const float macro = sim.per_macro_pixel(out.views[w]).at(0, 0, 0);
        EXPECT_NEAR(out.distributions[0].at(nodes[w].first, nodes[w].second, 0), macro, 1e-5 + 1e-5 * macro);
        lit = std::max(lit, double(macro));
    }
    EXPECT_GT(lit, 0.01);
}

TEST(AngularDisplay, IsDeterministic) {
    const AngularDisplaySimulator sim(bundled_design(3));
    AngularSimulationOptions options;
    options.model = Model::Exact;
    options.rays_per_side = 48;
    options.area_samples_per_side = 3;
    options.views = {{from_slopes(0.02, -0.05), std::nullopt}};
    options.distributions = {{0, 0}};
    std::vector<float> values(100 * 100);
    for (std::size_t k = 0; k < values.size(); ++k) values[k] = static_cast<float>(k % 7) / 7.0f;
    const RasterTransparency pattern(100, 100, 1, 0.26, 0.26, values);
    const std::vector<DisplayLight> lights{{incident_direction(0.1, 1.0), {1, 0.5, 0.2}, degrees_to_radians(3)}};
    const auto a = sim.simulate(pattern, lights, options);
    const auto b = sim.simulate(pattern, lights, options);
    EXPECT_TRUE(same_bits(a.views[0], b.views[0]));
    EXPECT_TRUE(same_bits(a.distributions[0], b.distributions[0]));
    EXPECT_EQ(a.pattern_efficiency, b.pattern_efficiency);
    EXPECT_GT(a.directions, 1u);
}

TEST(AngularDisplay, BadInputIsRefusedWithTheReason) {
    EXPECT_THAT([] { AngularDisplaySimulator sim(bundled_design(2)); },
                ::testing::ThrowsMessage<InputError>(HasSubstr("Design III or IV")));
    const AngularDisplaySimulator sim(bundled_design(3));
    const ClearTransparency clear;
    AngularSimulationOptions options;
    options.rays_per_side = 8;
    const std::vector<DisplayLight> good{{Eigen::Vector3d::UnitZ(), {1, 1, 1}, 0.0}};
    EXPECT_THAT([&] { sim.simulate(clear, {{-Eigen::Vector3d::UnitZ(), {1, 1, 1}, 0.0}}, options); },
                ::testing::ThrowsMessage<InputError>(HasSubstr("light 1: a light must shine through the display from behind")));
    auto with = [&](auto change) {
        AngularSimulationOptions o = options;
        change(o);
        return [&sim, &clear, &good, o] { sim.simulate(clear, good, o); };
    };
    EXPECT_THAT(with([](auto& o) { o.views = {{Eigen::Vector3d(0, 0.5, -1), std::nullopt}}; }),
                ::testing::ThrowsMessage<InputError>(HasSubstr("view 1: a view direction must point out of the display's front")));
    EXPECT_THAT(with([](auto& o) { o.views = {{Eigen::Vector3d::UnitZ(), Eigen::Vector3d(0, 0, -5)}}; }),
                ::testing::ThrowsMessage<InputError>(HasSubstr("an eye must be in front of the display")));
    EXPECT_THAT(with([](auto& o) { o.distributions = {{1, 0}}; }),
                ::testing::ThrowsMessage<InputError>(HasSubstr("macro-pixel 1,0 is off the 1 x 1 grid")));
    EXPECT_THAT(with([](auto& o) { o.rays_per_side = 1; }), ::testing::ThrowsMessage<InputError>(HasSubstr("rays per side")));
}

}  // namespace
}  // namespace rfd::optics
