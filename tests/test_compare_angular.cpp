// Designs III and IV judged as a viewer sees them: the reference is the display's flat field
// times the field at the light itself, so a clear print of a field of ones matches exactly,
// an encoded smooth field matches well at its bins' centres, and less well across the
// borders between bins (the display shows one value per bin: the quantisation the judge
// exists to measure).

#include <cmath>
#include <span>
#include <vector>

#include <gtest/gtest.h>

#include "optics/display_angular.hpp"
#include "patterns/angular.hpp"
#include "patterns/angular_fields.hpp"
#include "predict/compare_angular.hpp"
#include "print/printer.hpp"

#include "tests/support/bundled.hpp"

namespace rfd::predict {
namespace {

using rfd::testing::bundled_design;

// Smooth in the view, and in the light across the bins: what a bin's mean misses grows with
// the distance from its centre.
void smooth(const Eigen::Vector3d& light, const Eigen::Vector3d& view, int, int, std::span<float> out) {
    out[0] = static_cast<float>(0.6 + 1.5 * view.x() - 1.0 * view.y() + 2.0 * light.x() + 1.5 * light.y());
}

optics::AngularSimulationOptions few_rays() {
    optics::AngularSimulationOptions o;
    o.rays_per_side = 96;
    return o;
}

TEST(AngularComparison, AClearPrintOfAFieldOfOnesIsItsOwnReference) {
    const optics::AngularDisplaySimulator sim(bundled_design(3));
    const patterns::FunctionField ones(1, [](const Eigen::Vector3d&, const Eigen::Vector3d&, int, int,
                                             std::span<float> out) { out[0] = 1.0f; });
    const optics::ClearTransparency clear;
    const print::ToneMap tone{print::default_printer(Dpi(600), Dpi(600)), 1.0, 1.0, 1};
    const AngularComparison cmp(sim, clear, ones, angular_light_grid(sim, 3), tone, few_rays());
    const std::vector<Eigen::Vector3d> views = angular_view_grid(sim, 3);
    int compared = 0, lit = 0;
    for (std::size_t light = 0; light < cmp.lights().size(); ++light)
        for (const PairComparison& pair : cmp.compare(light, views)) {
            EXPECT_LT(pair.comparison.mse, 1e-12);
            // Some pairs are dark: the corner bins are vignetted, and a light on a border
            // between bins sends part of its light out through the neighbours.
            lit += pair.comparison.peak > 0.0 ? 1 : 0;
            ++compared;
        }
    EXPECT_EQ(compared, 81);
    EXPECT_GT(lit, 30);
}

TEST(AngularComparison, AnEncodedFieldMatchesBestAtItsBinsCentres) {
    const optics::DesignOptics optics(bundled_design(3));
    const patterns::FunctionField field(1, smooth);
    patterns::AngularOptions options;
    options.table_size = 65;
    options.dpi_x = options.dpi_y = 600;
    const patterns::AngularPattern pattern(optics, field, options);
    const double white = patterns::estimate_white(pattern, 100.0);
    const print::ToneMap tone{print::default_printer(Dpi(600), Dpi(600)), 1.0, white, 1};
    // The print as the tone map makes it.
    const auto& g = pattern.geometry();
    const std::size_t row = static_cast<std::size_t>(g.width);
    std::vector<float> values(row * static_cast<std::size_t>(g.height));
    for (int y = 0; y < g.height; ++y) pattern.render_row(y, std::span<float>(values.data() + y * row, row));
    for (float& v : values) v = static_cast<float>(tone.stack_transmittance(v));
    const optics::RasterTransparency printed(g.width, g.height, 1, g.dot_x, g.dot_y, std::move(values));

    const optics::AngularDisplaySimulator sim(optics.design());
    std::vector<Eigen::Vector3d> lights;
    for (const optics::CellIndex cell : {optics::CellIndex{1, 1}, optics::CellIndex{3, 2}})
        lights.push_back(sim.meso().bin(cell, optics::Model::Paraxial, 1).centre);
    // Halfway between bins (2, 2) and (3, 2): the border.
    lights.push_back((sim.meso().bin({2, 2}, optics::Model::Paraxial, 1).centre +
                      sim.meso().bin({3, 2}, optics::Model::Paraxial, 1).centre)
                         .normalized());
    const AngularComparison cmp(sim, printed, field, lights, tone, few_rays());
    const std::vector<Eigen::Vector3d> views = angular_view_grid(sim, 3);
    double centre_mse = 0.0, border_mse = 0.0, border_ceiling_mse = 0.0, peak = 0.0;
    for (std::size_t light = 0; light < lights.size(); ++light)
        for (const PairComparison& pair : cmp.compare(light, views)) {
            peak = std::max(peak, pair.comparison.peak);
            (light < 2 ? centre_mse : border_mse) += pair.comparison.mse / (light < 2 ? 2.0 : 1.0);
            if (light == 2) border_ceiling_mse += pair.ceiling_comparison.mse;
        }
    const auto db = [&](double mse) { return 10 * std::log10(peak * peak / mse * static_cast<double>(views.size())); };
    EXPECT_GT(db(centre_mse), 30.0);
    EXPECT_LT(db(border_mse), db(centre_mse) - 6.0);
    // On the border the best pattern falls as far: the error is the bins', not the print's.
    EXPECT_LT(db(border_ceiling_mse), db(centre_mse) - 6.0);
}

}  // namespace
}  // namespace rfd::predict
