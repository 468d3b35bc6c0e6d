// Assembly tolerances (optics/misalignment.hpp, optics/tolerance.hpp): the mounted pattern
// against closed forms (a shift by one dot samples the neighbour dot, a quarter turn, a
// scaling), the spacer's effect on where the light lands against the ray matrix, and the
// sweep's tolerances against closed forms for a pattern whose transmittance is a linear ramp
// across each lenslet's cell (the picture then changes by slope x drift x the light each
// lenslet passes). Small arrays keep it fast.

#include <cmath>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "core/units.hpp"
#include "optics/misalignment.hpp"
#include "optics/paraxial.hpp"
#include "optics/tolerance.hpp"
#include "tests/support/error_of.hpp"
#include "tests/support/bundled.hpp"

namespace rfd::optics {
namespace {

using ::testing::HasSubstr;
using rfd::testing::bundled_design;
using rfd::testing::error_of;


Design small_design1(int count) { return with_lenslet_count(bundled_design(1), count, count); }

// Transmittance as a function of the offset from the centre of the lenslet cell a point
// lies under (0 outside the array): an analytic pattern that repeats with the lattice.
template <class Profile>
class CellPattern final : public Transparency {
public:
    CellPattern(const Lattice& lattice, Profile profile) : lattice_(lattice), profile_(profile) {}
    int channels() const override { return 1; }
    void sample(std::span<const Eigen::Vector2d> points, std::span<float> out) const override {
        for (std::size_t k = 0; k < points.size(); ++k) {
            const CellIndex cell = lattice_.cell_at(points[k]);
            out[k] = lattice_.contains(cell) ? static_cast<float>(profile_(points[k] - lattice_.center(cell))) : 0.0f;
        }
    }

private:
    Lattice lattice_;
    Profile profile_;
};

// 0.5 + slope * x across each cell (0.2 .. 0.8 over a hexagonal cell's width).
auto ramp(const Lattice& lattice) {
    const double slope = 0.6 / lattice.pitch_x();
    return CellPattern(lattice, [slope](const Eigen::Vector2d& offset) { return 0.5 + slope * offset.x(); });
}

// A dot raster whose every dot holds its own index, to see which dot a point samples.
RasterTransparency numbered_raster(int width, int height, double dot_x, double dot_y) {
    std::vector<float> values(static_cast<std::size_t>(width * height));
    for (std::size_t k = 0; k < values.size(); ++k) values[k] = static_cast<float>(k);
    return RasterTransparency(width, height, 1, dot_x, dot_y, std::move(values));
}

// Centre of dot (px, py) of a centred raster, row 0 at the top.
Eigen::Vector2d dot_centre(int px, int py, int width, int height, double dot_x, double dot_y) {
    return {(px + 0.5 - 0.5 * width) * dot_x, (0.5 * height - py - 0.5) * dot_y};
}

float sample_one(const Transparency& t, const Eigen::Vector2d& p) {
    float value = -1.0f;
    t.sample(std::span<const Eigen::Vector2d>(&p, 1), std::span<float>(&value, 1));
    return value;
}

TEST(MisalignedTransparency, ShiftByOneDotSamplesTheNeighbourDot) {
    const int w = 9, h = 7;
    const double dx = 0.01, dy = 0.02;
    const RasterTransparency raster = numbered_raster(w, h, dx, dy);
    const MisalignedTransparency right(raster, Mounting{{dx, 0.0}, 0.0, 0.0});
    const MisalignedTransparency up(raster, Mounting{{0.0, dy}, 0.0, 0.0});
    for (int py = 1; py < h - 1; ++py)
        for (int px = 1; px < w - 1; ++px) {
            const Eigen::Vector2d q = dot_centre(px, py, w, h, dx, dy);
            // Moved right by a dot: the dot now over q is the one left of it.
            EXPECT_EQ(sample_one(right, q), static_cast<float>(py * w + px - 1));
            // Moved up by a dot: the dot from one row lower (row index + 1).
            EXPECT_EQ(sample_one(up, q), static_cast<float>((py + 1) * w + px));
        }
}

TEST(MisalignedTransparency, QuarterTurnCounterClockwise) {
    const int n = 9;
    const double dot = 0.05;
    const RasterTransparency raster = numbered_raster(n, n, dot, dot);
    const MisalignedTransparency turned(raster, Mounting{{0.0, 0.0}, kPi / 2, 0.0});
    for (int py = 0; py < n; ++py)
        for (int px = 0; px < n; ++px) {
            const Eigen::Vector2d q = dot_centre(px, py, n, n, dot, dot);
            // The print turned by +90 degrees puts the dot from (x, y) at (-y, x): at q the
            // dot that was at (q.y, -q.x).
            const Eigen::Vector2d from(q.y(), -q.x());
            EXPECT_EQ(sample_one(turned, q), sample_one(raster, from)) << px << ", " << py;
        }
    // A full turn is the identity; a half turn mirrors through the centre.
    const MisalignedTransparency half(raster, Mounting{{0.0, 0.0}, kPi, 0.0});
    EXPECT_EQ(sample_one(half, dot_centre(1, 2, n, n, dot, dot)), sample_one(raster, dot_centre(n - 2, n - 3, n, n, dot, dot)));
}

TEST(MisalignedTransparency, PitchErrorScalesAboutTheAxis) {
    const int n = 41;
    const double dot = 0.1;
    const RasterTransparency raster = numbered_raster(n, n, dot, dot);
    const double e = 0.05;  // 5 %: dot k from the centre lands at 1.05 k
    const MisalignedTransparency larger(raster, Mounting{{0.0, 0.0}, 0.0, e});
    for (int k = -15; k <= 15; ++k) {
        const Eigen::Vector2d p = dot_centre(20 + k, 20 - k, n, n, dot, dot);
        EXPECT_EQ(sample_one(larger, (1.0 + e) * p), sample_one(raster, p)) << k;
        EXPECT_TRUE(larger.to_pattern((1.0 + e) * p).isApprox(p, 1e-12));
    }
    // The drift at distance r is e r: at dot 20 from the centre it is one whole dot.
    const Eigen::Vector2d edge = dot_centre(40, 20, n, n, dot, dot);
    EXPECT_EQ(sample_one(larger, edge), sample_one(raster, dot_centre(39, 20, n, n, dot, dot)));
}

TEST(SpacerError, MovesTheDiffuserAndThickensTheSpacer) {
    const Design nominal = small_design1(3);
    const Design thicker = with_spacer_error(nominal, 0.4);
    EXPECT_NEAR(pattern_to_diffuser_mm(thicker) - pattern_to_diffuser_mm(nominal), 0.4, 1e-12);
    EXPECT_NEAR(std::get<SheetPart>(*thicker.plane("B").part).thickness, 3.4, 1e-12);
    EXPECT_EQ(thicker.plane("A").z, nominal.plane("A").z);  // the focus on the pattern stays
    EXPECT_EQ(thicker.plane("B").z, nominal.plane("B").z);
    EXPECT_THAT(error_of([&] { with_spacer_error(nominal, -3.0); }), HasSubstr("without thickness"));
    // Design II: the diffuser hangs in air behind the corrective pair; too thin runs into it.
    const Design two = bundled_design(2);
    EXPECT_NEAR(with_spacer_error(two, -1.0).plane("C").z, two.plane("C").z - 1.0, 1e-12);
    EXPECT_THAT(error_of([&] { with_spacer_error(two, -12.0); }), HasSubstr("overlap"));
}

TEST(Tolerance, PsnrOfIdenticalPicturesIsTheCeilingNeverInfinity) {
    Image a(3, 2, 3, 0.5f);
    EXPECT_EQ(stacked_psnr({a}, {a}), kPsnrCeilingDb);
    Image b = a;
    b.at(0, 0, 0) = 0.4f;  // MSE 0.01 / 18, peak 0.5
    EXPECT_NEAR(stacked_psnr({a}, {b}), 10 * std::log10(0.25 / (0.01 / 18)), 1e-4);
}

// Design I: a pattern shift s makes each lenslet show what belongs to tan(theta) - s / B.
// The total power through the pattern does not depend on where the beams land on the
// diffuser, so it tests the sampled direction alone.
TEST(Tolerance, DesignOneShiftSelectsTheDirectionOfTheClosedForm) {
    const DisplaySimulator sim(small_design1(5));
    const DesignOptics& optics = sim.optics();
    const double pitch = optics.lattice().pitch_x();
    const auto wave = CellPattern(optics.lattice(), [pitch](const Eigen::Vector2d& offset) {
        return 0.5 + 0.4 * std::sin(2 * kPi * offset.x() / pitch);
    });
    auto power = [&](const Transparency& t, double tan_x) {
        const DiffuserImage out = sim.simulate(t, {{Eigen::Vector3d(tan_x, 0.0, 1.0).normalized(), {1, 1, 1}, 0.0}}, {});
        double total = 0.0;
        for (float v : out.image.plane(0)) total += v;
        return total;
    };
    const double b = optics.paraxial_b();
    for (double s : {0.1, -0.2}) {
        const MisalignedTransparency shifted(wave, Mounting{{s, 0.0}, 0.0, 0.0});
        for (double tan_x : {0.0, 0.05}) {
            const double moved = power(shifted, tan_x);
            const double expected = power(wave, tan_x - s / b);
            EXPECT_NEAR(moved / expected, 1.0, 0.01) << "s " << s << ", tan " << tan_x;
            EXPECT_GT(std::abs(moved / power(wave, tan_x) - 1.0), 0.1) << "the shift changes the picture";
        }
    }
}

// With the ramp, a drift delta_x of the pattern under lenslet n changes the light it
// passes by slope * delta_x * F_n, F_n the light that lenslet passes with no pattern; so
// MSE = slope^2 mean(delta_x^2 F^2) and the PSNR's closed form follows. For a shift,
// delta_x = s; for a pitch error, delta_x = e c_x (c the lenslet centre).
struct Closed {
    double shift_mm, pitch_error;
};

Closed closed_form_tolerances(const DisplaySimulator& sim, const std::vector<DisplayLight>& lights, double peak,
                              double threshold_db) {
    const Lattice& lattice = sim.optics().lattice();
    const double slope = 0.6 / lattice.pitch_x();
    const auto clear = CellPattern(lattice, [](const Eigen::Vector2d&) { return 1.0; });
    double f2 = 0.0, cf2 = 0.0;
    std::size_t count = 0;
    for (const DisplayLight& light : lights) {
        const Image f = sim.per_lenslet(sim.simulate(clear, {light}, {}));
        for (int y = 0; y < f.height(); ++y)
            for (int x = 0; x < f.width(); ++x) {
                // per_lenslet's row 0 is the top row of cells (cell row count_y - 1).
                const double cx = lattice.center({x, lattice.count_y() - 1 - y}).x();
                for (int c = 0; c < f.channels(); ++c) {
                    const double v = f.at(x, y, c);
                    f2 += v * v;
                    cf2 += cx * cx * v * v;
                    ++count;
                }
            }
    }
    const double allowed_rms = peak / std::pow(10.0, threshold_db / 20.0);  // sqrt(MSE) at the threshold
    const double n = static_cast<double>(count);
    return {allowed_rms / (slope * std::sqrt(f2 / n)), allowed_rms / (slope * std::sqrt(cf2 / n))};
}

TEST(Tolerance, ShiftAndPitchToleranceMatchTheClosedForm) {
    const Design design = small_design1(6);
    const DisplaySimulator sim(design);
    const auto pattern = ramp(sim.optics().lattice());
    const std::vector<DisplayLight> lights = default_tolerance_lights(sim.optics(), Model::Paraxial);
    ToleranceOptions options;
    options.max_shift_mm = 0.3;
    options.max_pitch_error = 0.03;
    options.steps = 4;
    options.refinements = 6;
    const ToleranceReport report = sweep_tolerances(design, pattern, lights, options);
    ASSERT_EQ(report.curves.size(), 2u);
    const Closed closed = closed_form_tolerances(sim, lights, report.nominal_peak, options.threshold_db);
    ASSERT_TRUE(report.curves[0].tolerance && report.curves[1].tolerance);
    RecordProperty("shift_tolerance_um", std::to_string(1000 * *report.curves[0].tolerance));
    RecordProperty("shift_closed_form_um", std::to_string(1000 * closed.shift_mm));
    // Within 10 %: the bisection's resolution (0.3 / 4 / 64 mm) and beams spilling into
    // neighbouring cells on the diffuser.
    EXPECT_NEAR(*report.curves[0].tolerance / closed.shift_mm, 1.0, 0.1);
    EXPECT_NEAR(*report.curves[1].tolerance / closed.pitch_error, 1.0, 0.1);
    for (const ToleranceCurve& curve : report.curves) {
        EXPECT_EQ(curve.sweep.front().psnr_db, kPsnrCeilingDb);  // no error: the same picture
        for (std::size_t k = 1; k < curve.sweep.size(); ++k) {
            EXPECT_TRUE(std::isfinite(curve.sweep[k].psnr_db));
            EXPECT_LT(curve.sweep[k].psnr_db, curve.sweep[k - 1].psnr_db) << to_string(curve.kind) << " step " << k;
        }
    }
}

// The moire of thesis 8.4.1: the drift grows with the lenslet's distance from the axis,
// so twice the lenslets across halve the tolerable pitch error (and rotation).
TEST(Tolerance, PitchAndRotationToleranceScaleWithOneOverTheLensletCount) {
    auto tolerances = [](int count) {
        const Design design = small_design1(count);
        const DisplaySimulator sim(design);
        const auto pattern = ramp(sim.optics().lattice());
        ToleranceOptions options;
        options.max_pitch_error = 0.06;
        options.max_rotation_rad = 0.06;
        options.steps = 4;
        options.refinements = 6;
        const ToleranceReport report =
            sweep_tolerances(design, pattern, default_tolerance_lights(sim.optics(), Model::Paraxial), options);
        return std::pair(report.curves[0].tolerance.value(), report.curves[1].tolerance.value());
    };
    const auto [rotation4, pitch4] = tolerances(4);
    const auto [rotation8, pitch8] = tolerances(8);
    RecordProperty("pitch_ratio", std::to_string(pitch4 / pitch8));
    // The rms lenslet-centre coordinate grows from 1.12 to 2.29 pitches: a ratio of 2.05.
    EXPECT_NEAR(pitch4 / pitch8, 2.05, 0.25);
    EXPECT_NEAR(rotation4 / rotation8, 2.0, 0.3);
}

// Design I's spacer: the beam of a light at theta leaves the pattern at the angle it has
// in the PMMA, so a spacer t thicker moves every picture by t tan(theta) / n (paraxial),
// measured by the ray matrix independently; the axis light does not move.
TEST(Tolerance, SpacerMovesThePictureByTheRayMatrixPrediction) {
    const Design design = small_design1(5);
    const DisplaySimulator sim(design);
    const auto clear = CellPattern(sim.optics().lattice(), [](const Eigen::Vector2d&) { return 1.0; });
    const std::vector<DisplayLight> lights = default_tolerance_lights(sim.optics(), Model::Paraxial);
    ToleranceOptions options;
    options.max_spacer_mm = 0.5;
    options.steps = 2;
    options.refinements = 0;
    const ToleranceReport report = sweep_tolerances(design, clear, lights, options);
    const TolerancePoint& last = report.curves[0].sweep.back();
    // B to the diffuser, from the ray matrix of each design: its change is where the beam moves.
    const DisplaySimulator thicker(with_spacer_error(design, 0.5));
    const double db = vertex_matrix(thicker.optics().system(), 0, thicker.diffuser_surface()).b -
                      vertex_matrix(sim.optics().system(), 0, sim.diffuser_surface()).b;
    const double n = std::get<SheetPart>(*design.plane("B").part).index;
    EXPECT_NEAR(db, 0.5 / n, 1e-9);
    double expected = 0.0;  // mean over the lights of |db tan(theta)|, in pitches
    for (const DisplayLight& light : lights) expected += std::abs(db) * light.direction.head<2>().norm() / light.direction.z();
    expected /= static_cast<double>(lights.size()) * sim.optics().lattice().pitch_x();
    EXPECT_NEAR(last.shift_lenslets, expected, 0.1 * expected);
    EXPECT_LT(last.psnr_db, kPsnrCeilingDb);
}

TEST(Tolerance, BadRangesAreInputErrors) {
    const Design design = small_design1(3);
    const DisplaySimulator sim(design);
    const auto pattern = ramp(sim.optics().lattice());
    const std::vector<DisplayLight> lights = default_tolerance_lights(sim.optics(), Model::Paraxial);
    auto message = [&](auto change) {
        ToleranceOptions options;
        options.max_shift_mm = 0.1;
        change(options);
        return error_of([&] { sweep_tolerances(design, pattern, lights, options); });
    };
    EXPECT_THAT(message([](ToleranceOptions& o) { o.max_shift_mm = -0.1; }),
                HasSubstr("largest shift (mm): expected a finite number >= 0"));
    EXPECT_THAT(message([](ToleranceOptions& o) { o.max_rotation_rad = std::nan(""); }),
                HasSubstr("largest rotation: expected a finite number >= 0"));
    EXPECT_THAT(message([](ToleranceOptions& o) { o.steps = 0; }), HasSubstr("steps: expected at least 1"));
    EXPECT_THAT(message([](ToleranceOptions& o) { o.threshold_db = std::nan(""); }), HasSubstr("threshold (dB)"));
    EXPECT_THAT(message([](ToleranceOptions& o) { o.max_shift_mm = 0.0; }), HasSubstr("nothing to sweep"));
    EXPECT_THAT(message([](ToleranceOptions& o) { o.max_spacer_mm = 5.0; }), HasSubstr("without thickness"));
    const auto black = CellPattern(sim.optics().lattice(), [](const Eigen::Vector2d&) { return 0.0; });
    EXPECT_THAT(error_of([&] {
                    ToleranceOptions options;
                    options.max_shift_mm = 0.1;
                    sweep_tolerances(design, black, lights, options);
                }),
                HasSubstr("black picture"));
}

}  // namespace
}  // namespace rfd::optics
