// The display simulator for Designs I and II (optics/display.hpp) against what the thesis
// observed, as numbers: Design I's image of a lenslet moves on the diffuser by what the
// ray-transfer matrix predicts, Design II's stays on its macro-pixel, crosstalk begins at
// the wrap-over angle and not before, lights add up, and light is conserved.

#include <cmath>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "core/units.hpp"
#include "optics/display.hpp"
#include "optics/paraxial.hpp"
#include "tests/support/error_of.hpp"
#include "tests/support/bundled.hpp"

namespace rfd::optics {
namespace {

using ::testing::HasSubstr;
using rfd::testing::bundled_design;
using rfd::testing::error_of;


Design small_design1() { return with_lenslet_count(bundled_design(1), 5, 5); }
Design design2() { return bundled_design(2); }

// A one-channel transparency at the design's print resolution, centred like a pattern:
// transmittance `inside` under the cells `keep` accepts, 0 elsewhere.
template <class Keep>
RasterTransparency transparency(const DesignOptics& optics, Keep keep) {
    const Eigen::Vector2d dot = optics.dot_mm();
    const Eigen::Vector2d half = optics.lattice().half_extent();
    const int width = static_cast<int>(std::ceil(2.0 * half.x() / dot.x()));
    const int height = static_cast<int>(std::ceil(2.0 * half.y() / dot.y()));
    std::vector<float> values(static_cast<std::size_t>(width) * static_cast<std::size_t>(height));
    for (int py = 0; py < height; ++py)
        for (int px = 0; px < width; ++px) {
            const Eigen::Vector2d p((px + 0.5 - 0.5 * width) * dot.x(), (0.5 * height - py - 0.5) * dot.y());
            const CellIndex cell = optics.lattice().cell_at(p);
            values[static_cast<std::size_t>(py) * static_cast<std::size_t>(width) + static_cast<std::size_t>(px)] =
                optics.lattice().contains(cell) && keep(cell) ? 1.0f : 0.0f;
        }
    return RasterTransparency(width, height, 1, dot.x(), dot.y(), std::move(values));
}

// Intensity-weighted centroid of channel 0, mm.
Eigen::Vector2d centroid(const DiffuserImage& image) {
    Eigen::Vector2d sum = Eigen::Vector2d::Zero();
    double total = 0.0;
    for (int y = 0; y < image.image.height(); ++y)
        for (int x = 0; x < image.image.width(); ++x) {
            const double v = image.image.at(x, y, 0);
            sum += v * image.pixel_centre(x, y);
            total += v;
        }
    return sum / total;
}

double total_power(const DiffuserImage& image, int channel) {
    double total = 0.0;
    for (int y = 0; y < image.image.height(); ++y)
        for (int x = 0; x < image.image.width(); ++x) total += image.image.at(x, y, channel);
    return total * image.pixel_mm * image.pixel_mm;
}

TEST(DisplaySimulator, DesignOneImageMovesAsTheRayMatrixPredicts) {
    const DisplaySimulator sim(small_design1());
    const DesignOptics& optics = sim.optics();
    const CellIndex centre = optics.centre_cell();
    const RasterTransparency only_centre = transparency(optics, [&](CellIndex c) { return c == centre; });
    // The centroid of a lenslet's beam follows the ray through the centre of its aperture:
    // y_diffuser = B tan(theta), B from the matrix from the entrance to the diffuser.
    const double b = vertex_matrix(optics.system(), 0, sim.diffuser_surface()).b;
    SimulationOptions options;
    options.rays_per_side = 16;
    for (double degrees : {0.0, 4.0, 8.0}) {
        for (double phi : {0.0, kPi / 2}) {
            const Eigen::Vector3d d = incident_direction(degrees_to_radians(degrees), phi);
            const DiffuserImage image = sim.simulate(only_centre, {{d, {1, 1, 1}, 0.0}}, options);
            const Eigen::Vector2d shift = centroid(image) - optics.lattice().center(centre);
            const Eigen::Vector2d expected = b * Eigen::Vector2d(d.x() / d.z(), d.y() / d.z());
            EXPECT_NEAR(shift.x(), expected.x(), 0.01 * optics.lattice().pitch_x()) << degrees << " deg, phi " << phi;
            EXPECT_NEAR(shift.y(), expected.y(), 0.01 * optics.lattice().pitch_x()) << degrees << " deg, phi " << phi;
            // The exact model agrees to a few percent of a pitch (aberrations, Fresnel weights).
            options.model = Model::Exact;
            const Eigen::Vector2d exact_shift =
                centroid(sim.simulate(only_centre, {{d, {1, 1, 1}, 0.0}}, options)) - optics.lattice().center(centre);
            options.model = Model::Paraxial;
            RecordProperty("exact_minus_paraxial_um_" + std::to_string(static_cast<int>(degrees)),
                           std::to_string(1000 * (exact_shift - shift).norm()));
            EXPECT_NEAR((exact_shift - shift).norm(), 0.0, 0.05 * optics.lattice().pitch_x()) << degrees << " deg";
            if (degrees == 8.0) {
                EXPECT_GT(shift.norm(), 0.25 * optics.lattice().pitch_x());  // it does move
            }
        }
    }
}

TEST(DisplaySimulator, DesignTwoKeepsEachImageOnItsMacroPixel) {
    const DisplaySimulator sim(design2());
    const DesignOptics& optics = sim.optics();
    const CellIndex centre = optics.centre_cell();
    const RasterTransparency only_centre = transparency(optics, [&](CellIndex c) { return c == centre; });
    for (Model model : {Model::Paraxial, Model::Exact}) {
        SimulationOptions options;
        options.model = model;
        options.rays_per_side = 16;
        for (double degrees : {0.0, 4.0, 8.0}) {
            for (double phi : {0.0, kPi / 2, kPi / 4}) {
                const Eigen::Vector3d d = incident_direction(degrees_to_radians(degrees), phi);
                const DiffuserImage image = sim.simulate(only_centre, {{d, {1, 1, 1}, 0.0}}, options);
                const Eigen::Vector2d shift = centroid(image) - optics.lattice().center(centre);
                EXPECT_LT(shift.norm(), 0.1 * optics.lattice().pitch_x())
                    << to_string(model) << " " << degrees << " deg, phi " << phi;
            }
        }
    }
}

TEST(DisplaySimulator, CrosstalkBeginsAtTheWrapOverAngleNotBefore) {
    const DisplaySimulator sim(small_design1());
    const DesignOptics& optics = sim.optics();
    const RasterTransparency clear = transparency(optics, [](CellIndex) { return true; });
    for (double phi : {0.0, kPi / 2}) {
        // Paraxial: the whole bundle meets at one point of the pattern plane, so it crosses
        // at the chief ray's wrap-over angle. Exact: spherical aberration spreads it, and
        // the first rays cross where the full-bundle analysis says.
        const double paraxial_wrap = *wrap_over_angle(optics, phi, Model::Paraxial);
        const double exact_first = *first_loss_angle(optics, phi, 12);
        const double exact_wrap = *wrap_over_angle(optics, phi, Model::Exact);
        auto crossed = [&](Model model, double degrees) {
            SimulationOptions options;
            options.model = model;
            return sim.simulate(clear, {{incident_direction(degrees_to_radians(degrees), phi), {1, 1, 1}, 0.0}}, options)
                .crossed;
        };
        EXPECT_EQ(crossed(Model::Paraxial, 0.97 * paraxial_wrap), 0u) << phi;
        EXPECT_GT(crossed(Model::Paraxial, 1.03 * paraxial_wrap), 0u) << phi;
        EXPECT_EQ(crossed(Model::Exact, 0.9 * exact_first), 0u) << phi;
        EXPECT_GT(crossed(Model::Exact, exact_wrap), 0u) << phi;
    }
}

TEST(DisplaySimulator, LightsAddUpAndLightIsConserved) {
    const DisplaySimulator sim(design2());
    const DesignOptics& optics = sim.optics();
    const RasterTransparency half_clear =
        transparency(optics, [](CellIndex c) { return (c.i + c.j) % 2 == 0; });
    const DisplayLight red{incident_direction(degrees_to_radians(6.0), kPi), {1, 0, 0}, 0.0};
    const DisplayLight green{incident_direction(degrees_to_radians(6.0), 0.0), {0, 1, 0}, 0.0};
    const SimulationOptions options;
    const DiffuserImage both = sim.simulate(half_clear, {red, green}, options);
    const DiffuserImage only_red = sim.simulate(half_clear, {red}, options);
    const DiffuserImage only_green = sim.simulate(half_clear, {green}, options);
    double worst = 0.0;
    for (int c = 0; c < 3; ++c)
        for (int y = 0; y < both.image.height(); ++y)
            for (int x = 0; x < both.image.width(); ++x)
                worst = std::max(worst, std::abs(static_cast<double>(both.image.at(x, y, c)) - only_red.image.at(x, y, c) -
                                                 only_green.image.at(x, y, c)));
    EXPECT_LT(worst, 1e-5);
    // Where both reach, red and green: yellow.
    EXPECT_GT(total_power(both, 0), 0.0);
    EXPECT_GT(total_power(both, 1), 0.0);
    EXPECT_EQ(total_power(both, 2), 0.0);

    // Paraxial optics lose nothing at small angles: everything entering the lenslets
    // reaches the diffuser, and the image holds that power (the pattern passes half).
    EXPECT_NEAR(only_red.optical_efficiency, 1.0, 1e-12);
    const double area = optics.lattice().cell_area() * optics.lattice().count_x() * optics.lattice().count_y();
    const double entering = area * red.direction.z();
    EXPECT_NEAR(total_power(only_red, 0), only_red.pattern_efficiency[0] * entering, 1e-3 * entering);
    EXPECT_NEAR(only_red.pattern_efficiency[0], 0.5, 0.05);
}

TEST(DisplaySimulator, AnAreaLightBlursWhatAPointLightKeepsSharp) {
    // Design I's images shift with the direction, so a disc of directions smears a
    // lenslet's image over the diffuser: the spread grows with the light's size.
    const DisplaySimulator sim(small_design1());
    const DesignOptics& optics = sim.optics();
    const CellIndex centre = optics.centre_cell();
    const RasterTransparency only_centre = transparency(optics, [&](CellIndex c) { return c == centre; });
    auto spread = [&](double radius_deg) {
        const DiffuserImage image =
            sim.simulate(only_centre, {{Eigen::Vector3d::UnitZ(), {1, 1, 1}, degrees_to_radians(radius_deg)}}, {});
        const Eigen::Vector2d mean = centroid(image);
        double sum = 0.0, total = 0.0;
        for (int y = 0; y < image.image.height(); ++y)
            for (int x = 0; x < image.image.width(); ++x) {
                sum += image.image.at(x, y, 0) * (image.pixel_centre(x, y) - mean).squaredNorm();
                total += image.image.at(x, y, 0);
            }
        return std::sqrt(sum / total);
    };
    EXPECT_GT(spread(6.0), 1.1 * spread(0.0));
}

// The simulator traces one lenslet and repeats its rays over the array. Against tracing
// every ray of every lenslet through the real (finite) array, as a direct computation:
// the same rays arrive, including at the array's edge under light steep enough to cross
// into neighbouring lenslets (where the neighbour beyond the edge does not exist).
TEST(DisplaySimulator, RepeatingOneLensletEqualsTracingEveryLenslet) {
    const DisplaySimulator sim(small_design1());
    const DesignOptics& optics = sim.optics();
    const SequentialSystem& system = optics.system();
    const Lattice& lattice = optics.lattice();
    const RasterTransparency clear = transparency(optics, [](CellIndex) { return true; });
    const double wrap = *wrap_over_angle(optics, 0.3, Model::Exact);
    for (double angle : {0.5 * wrap, 1.15 * wrap}) {
        const Eigen::Vector3d d = incident_direction(angle, 0.3);
        SimulationOptions options;
        options.model = Model::Exact;
        options.rays_per_side = 6;
        const DiffuserImage image = sim.simulate(clear, {{d, {1, 1, 1}, 0.0}}, options);
        std::size_t arrived = 0, crossed = 0;
        const int n = options.rays_per_side;
        const double half_w = 0.5 * lattice.pitch_x(), half_h = lattice.circumradius();
        for (int j = 0; j < lattice.count_y(); ++j)
            for (int i = 0; i < lattice.count_x(); ++i)
                for (int iy = 0; iy < n; ++iy)
                    for (int ix = 0; ix < n; ++ix) {
                        const Eigen::Vector2d point =
                            lattice.center({i, j}) + Eigen::Vector2d(((ix + 0.5) / n * 2 - 1) * half_w, ((iy + 0.5) / n * 2 - 1) * half_h);
                        if (!lattice.cell_contains({i, j}, point)) continue;
                        Ray ray{Eigen::Vector3d(point.x(), point.y(), system.surfaces.front().z) - (2.0 / d.z()) * d, d};
                        std::size_t first = 0;
                        bool crossing = false, ok = false;
                        for (int restart = 0; restart <= 4; ++restart) {
                            const TraceResult r = trace(system, ray, first, sim.diffuser_surface());
                            ray = r.ray;
                            if (r.status == RayStatus::Ok) {
                                ok = true;
                                break;
                            }
                            if (r.status != RayStatus::CrossedCell) break;
                            crossing = true;
                            first = static_cast<std::size_t>(r.surface);
                            ray.origin -= 1e-7 * ray.direction;
                        }
                        arrived += ok;
                        crossed += ok && crossing;
                    }
        EXPECT_EQ(image.rays - image.lost, arrived) << angle;
        EXPECT_EQ(image.crossed, crossed) << angle;
        if (angle > wrap) {
            EXPECT_GT(crossed, 0u);
        }
    }
}

TEST(DisplaySimulator, ManyDirectionsShareTheRayBudgetAndConverge) {
    // 400 directions over a cone: with a budget of one ray per direction and lenslet the
    // picture per lenslet is already close to that of 64 rays per direction; light
    // entering is the same whatever the budget.
    const DisplaySimulator sim(small_design1());
    const DesignOptics& optics = sim.optics();
    const RasterTransparency checker = transparency(optics, [](CellIndex c) { return (c.i + 2 * c.j) % 3 != 0; });
    std::vector<DisplayLight> sky;
    for (int k = 0; k < 400; ++k) {
        const double r = 0.25 * std::sqrt((k + 0.5) / 400.0), a = 2.39996322972865332 * k;
        sky.push_back({Eigen::Vector3d(r * std::cos(a), r * std::sin(a), 1.0).normalized(), {0.0025, 0.0025, 0.0025}, 0.0});
    }
    SimulationOptions coarse, fine;
    coarse.max_rays_per_lenslet = 400;
    fine.max_rays_per_lenslet = 400 * 64;
    const DiffuserImage a = sim.simulate(checker, sky, coarse);
    const DiffuserImage b = sim.simulate(checker, sky, fine);
    EXPECT_EQ(a.rays_per_direction, 1u);
    EXPECT_EQ(b.rays_per_direction, 64u);
    EXPECT_NEAR(a.pattern_efficiency[0], b.pattern_efficiency[0], 0.01);
    const double agreement = psnr(sim.per_lenslet(a), sim.per_lenslet(b), 1.0);
    RecordProperty("one_ray_per_direction_psnr_db", std::to_string(agreement));
    EXPECT_GT(agreement, 35.0);
}

TEST(DisplaySimulator, DesignTwoVignettesAtTheMacroPixelBorders) {
    // Thesis 8.2.4: "some vignetting is noticeable at the borders of the macro-pixels". One
    // clear macro-pixel: the real lenses (Fresnel losses and aberrations grow toward the
    // lenslet's rim) light its border ring less than its centre; paraxial optics do not.
    const DisplaySimulator sim(design2());
    const DesignOptics& optics = sim.optics();
    const Lattice& lattice = optics.lattice();
    const CellIndex centre = optics.centre_cell();
    const RasterTransparency only_centre = transparency(optics, [&](CellIndex c) { return c == centre; });
    auto border_over_centre = [&](Model model) {
        SimulationOptions options;
        options.model = model;
        options.rays_per_side = 48;
        options.pixels_per_pitch = 16;
        const DiffuserImage image = sim.simulate(only_centre, {{Eigen::Vector3d::UnitZ(), {1, 1, 1}, 0.0}}, options);
        double inner = 0.0, outer = 0.0;
        int inner_count = 0, outer_count = 0;
        for (int y = 0; y < image.image.height(); ++y)
            for (int x = 0; x < image.image.width(); ++x) {
                const Eigen::Vector2d p = image.pixel_centre(x, y);
                if (!(lattice.cell_at(p) == centre)) continue;
                const Eigen::Vector2d q = (p - lattice.center(centre)).cwiseAbs();
                const double f = std::max(q.x() / (0.5 * lattice.pitch_x()), q.y() / (0.5 * lattice.pitch_y()));
                if (f < 0.6) {
                    inner += image.image.at(x, y, 0);
                    ++inner_count;
                } else if (f > 0.8) {
                    outer += image.image.at(x, y, 0);
                    ++outer_count;
                }
            }
        return (outer / outer_count) / (inner / inner_count);
    };
    const double exact = border_over_centre(Model::Exact);
    RecordProperty("exact_border_over_centre", std::to_string(exact));
    EXPECT_LT(exact, 0.97);
    EXPECT_GT(exact, 0.8);
    EXPECT_NEAR(border_over_centre(Model::Paraxial), 1.0, 0.02);
}

TEST(PictureContrast, FrontLightFillsInTheBlacksAsTheDiffuserScattersIt) {
    // A picture of 100 lenslets: 50 at 0.4, 50 at 0.01 (grey). Percentiles: white 0.4,
    // black 0.01; the closed form of the header for each ratio, and the dark room w / b.
    Image picture(10, 10, 3);
    for (int y = 0; y < 10; ++y)
        for (int x = 0; x < 10; ++x)
            for (int c = 0; c < 3; ++c) picture.at(x, y, c) = y < 5 ? 0.4f : 0.01f;
    const DiffuserScatter diffuser{0.5, 0.4};
    const std::vector<double> ratios{0.0, 0.1, 1.0};
    const PictureContrast contrast = picture_contrast(picture, diffuser, ratios);
    EXPECT_NEAR(contrast.white, 0.4, 1e-6);
    EXPECT_NEAR(contrast.black, 0.01, 1e-6);
    EXPECT_NEAR(contrast.transmissivity, 0.2, 1e-6);
    ASSERT_EQ(contrast.with_front.size(), 3u);
    EXPECT_NEAR(contrast.with_front[0].contrast, 40.0, 1e-4);
    EXPECT_NEAR(contrast.with_front[1].contrast, (0.2 + 0.04) / (0.005 + 0.04), 1e-4);
    EXPECT_NEAR(contrast.with_front[2].contrast, (0.2 + 0.4) / (0.005 + 0.4), 1e-4);
    // A black that is truly black: infinite in the dark room, finite once the front is lit.
    Image black_and_white(2, 100, 1);
    for (int y = 0; y < 100; ++y) black_and_white.at(1, y, 0) = 1.0f;
    const PictureContrast ideal = picture_contrast(black_and_white, diffuser, ratios);
    EXPECT_TRUE(std::isinf(ideal.with_front[0].contrast));
    EXPECT_NEAR(ideal.with_front[2].contrast, (0.5 + 0.4) / 0.4, 1e-9);
}

TEST(DisplaySimulator, BadInputIsNamed) {
    const DisplaySimulator sim(design2());
    const RasterTransparency clear = transparency(sim.optics(), [](CellIndex) { return true; });
    EXPECT_THAT(error_of([&] { sim.simulate(clear, {{{0.1, 0.0, -1.0}, {1, 1, 1}, 0.0}}, {}); }),
                HasSubstr("light 1: a light must shine through the display from behind"));
    EXPECT_THAT(error_of([&] { sim.simulate(clear, {{{0.0, 0.0, 1.0}, {1, -1, 1}, 0.0}}, {}); }),
                HasSubstr("not negative"));
    EXPECT_THAT(error_of([&] { DisplaySimulator(bundled_design(3)); }),
                HasSubstr("Designs I and II"));
}

}  // namespace
}  // namespace rfd::optics
