// The Design I/II pattern encoder (thesis 8.4): the display-to-field direction mapping, the
// 1/cos(kappa) factor, lenslet sampling, the decode round trip (paraxial and exact), and
// the error for a field that does not cover the display's range.

#include <array>
#include <cmath>
#include <fstream>
#include <random>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "core/sphere.hpp"
#include "optics/design.hpp"
#include "patterns/encode.hpp"
#include "tests/support/error_of.hpp"
#include "tests/support/bundled.hpp"

namespace rfd::patterns {
namespace {

using ::testing::HasSubstr;
using rfd::testing::bundled_design;
using rfd::testing::error_of;


// Design I with a small array (the preset's 63 x 73 lenslets are 143 million dots).
optics::Design small_design1(int count_x, int count_y) {
    return optics::with_lenslet_count(bundled_design(1), count_x, count_y);
}

// A smooth, colourful field: every pixel a Lambertian patch with its own normal and colour.
relight::ReflectanceField smooth_field(std::size_t lights, int width, int height) {
    relight::ReflectanceField field;
    field.directions = fibonacci_hemisphere(lights);
    for (const Eigen::Vector3d& d : field.directions) {
        Image image(width, height, 3);
        for (int y = 0; y < height; ++y)
            for (int x = 0; x < width; ++x) {
                const Eigen::Vector3d normal = Eigen::Vector3d(0.6 * (x + 0.5) / width - 0.3,
                                                               0.3 - 0.6 * (y + 0.5) / height, 1.0).normalized();
                const double shade = std::max(0.0, normal.dot(d));
                for (int c = 0; c < 3; ++c)
                    image.at(x, y, c) = static_cast<float>(shade * (0.4 + 0.2 * c + 0.3 * ((x + y + c) % 3) / 2.0));
            }
        field.images.push_back(std::move(image));
    }
    return field;
}

std::vector<float> render_all(const Encoder& encoder) {
    const PatternGeometry& g = encoder.geometry();
    const std::size_t row = static_cast<std::size_t>(g.width * encoder.channels());
    std::vector<float> rows(row * static_cast<std::size_t>(g.height));
    for (int y = 0; y < g.height; ++y)
        encoder.render_row(y, std::span<float>(rows.data() + row * static_cast<std::size_t>(y), row));
    return rows;
}

TEST(AngularMapping, LightAboveTheDisplayLightsTheFieldFromAbove) {
    const AngularMapping identity;
    // Light from above and behind travels down (-y) through the display.
    const Eigen::Vector3d down = Eigen::Vector3d(0.0, -0.3, 1.0).normalized();
    const Eigen::Vector3d v = identity.field_direction(down);
    EXPECT_GT(v.y(), 0.0);
    EXPECT_NEAR(v.z(), down.z(), 1e-15);
    // A 45-degree tilt sends the display axis to 45 degrees above the field's horizon, +y.
    AngularMapping tilted;
    tilted.tilt_deg = 45;
    const Eigen::Vector3d axis = tilted.field_direction(Eigen::Vector3d::UnitZ());
    EXPECT_NEAR(axis.y(), std::sqrt(0.5), 1e-12);
    EXPECT_NEAR(axis.z(), std::sqrt(0.5), 1e-12);
    // Scaling doubles the polar angle about the display axis.
    AngularMapping scaled;
    scaled.angle_scale = 2.0;
    const Eigen::Vector3d ten = direction_from_angles(degrees_to_radians(10), 0.4);
    EXPECT_NEAR(radians_to_degrees(angles_of(scaled.field_direction(ten)).theta), 20.0, 1e-9);
}

TEST(AngularMapping, DisplayDirectionInvertsFieldDirection) {
    AngularMapping mapping;
    mapping.tilt_deg = 30;
    mapping.turn_deg = -70;
    mapping.angle_scale = 1.7;
    std::mt19937 random(5);
    std::uniform_real_distribution<double> theta(0.0, 0.5), phi(-kPi, kPi);
    for (int k = 0; k < 200; ++k) {
        const Eigen::Vector3d d = direction_from_angles(theta(random), phi(random));
        EXPECT_LT(angle_between(mapping.display_direction(mapping.field_direction(d)), d), 1e-12);
    }
}

TEST(Encoder, ConstantFieldGivesOneOverCosKappa) {
    const optics::Design design = bundled_design(2);
    relight::ReflectanceField field;
    field.directions = fibonacci_hemisphere(200);
    for (std::size_t i = 0; i < field.size(); ++i) field.images.emplace_back(6, 5, 1, 0.5f);
    const PatternGeometry g = pattern_geometry(design, Dpi{720}, Dpi{360});
    const Encoder encoder(design, field, g, EncodeOptions{});
    const std::vector<float> rows = render_all(encoder);
    const double b = encoder.optics().paraxial_b();
    int checked = 0;
    for (int py = 3; py < g.height; py += 37)
        for (int px = 5; px < g.width; px += 41) {
            const Eigen::Vector2d p = g.dot_centre(px, py);
            const optics::CellIndex cell = encoder.lattice().cell_at(p);
            const float value = rows[static_cast<std::size_t>(py * g.width + px)];
            if (!encoder.lattice().contains(cell)) {
                EXPECT_EQ(value, 0.0f);
                continue;
            }
            const Eigen::Vector2d slopes = (p - encoder.lattice().center(cell)) / b;
            EXPECT_NEAR(value, 0.5 * std::sqrt(1.0 + slopes.squaredNorm()), 1e-5) << px << ", " << py;
            ++checked;
        }
    EXPECT_GT(checked, 100);
}

TEST(Encoder, LensletSamplesAreTheFieldPixelsWhenTheyAlign) {
    // Design II's 6 x 5 rectangular array, a 6 x 5 image stretched over it: lenslet (i, j)
    // sees exactly pixel (i, 4 - j) (rows run up the array and down the image).
    const optics::Design design = bundled_design(2);
    relight::ReflectanceField field;
    field.directions = fibonacci_hemisphere(64);
    for (std::size_t i = 0; i < field.size(); ++i) {
        Image image(6, 5, 1);
        for (int y = 0; y < 5; ++y)
            for (int x = 0; x < 6; ++x) image.at(x, y, 0) = static_cast<float>(i * 100 + static_cast<std::size_t>(y * 6 + x));
        field.images.push_back(std::move(image));
    }
    EncodeOptions options;
    options.fit = ImageFit::Stretch;
    const Encoder encoder(design, field, pattern_geometry(design, Dpi{360}, Dpi{360}), options);
    int checked = 0;
    for (std::size_t i = 0; i < field.size(); ++i) {
        if (angle_between(field.directions[i], Eigen::Vector3d::UnitZ()) > 0.2) continue;
        for (int j = 0; j < 5; ++j)
            for (int k = 0; k < 6; ++k) {
                EXPECT_EQ(encoder.lenslet_sample({k, j}, i, 0), static_cast<float>(i * 100 + static_cast<std::size_t>((4 - j) * 6 + k)));
                ++checked;
            }
    }
    EXPECT_GT(checked, 0);
}

struct RoundTripCase {
    const char* name;
    bool hexagonal;
    optics::Model model;
    double tilt_deg;
};

class DecodeRoundTrip : public ::testing::TestWithParam<RoundTripCase> {};

TEST_P(DecodeRoundTrip, RecoversTheFieldSamplesAtEveryLenslet) {
    const RoundTripCase& param = GetParam();
    const optics::Design design = param.hexagonal ? small_design1(9, 10) : bundled_design(2);
    const relight::ReflectanceField field = smooth_field(1024, 16, 12);
    EncodeOptions options;
    options.model = param.model;
    options.mapping.tilt_deg = param.tilt_deg;
    const PatternGeometry g = pattern_geometry(design, Dpi{2880}, Dpi{1440});
    const Encoder encoder(design, field, g, options);
    const DecodeComparison result = decode_and_compare(encoder, render_all(encoder));
    // Every lenslet contributes: at least a handful of field directions each.
    const std::size_t lenslets = static_cast<std::size_t>(encoder.lattice().count_x() * encoder.lattice().count_y());
    EXPECT_GT(result.samples, 3 * 5 * lenslets);
    RecordProperty("psnr_db", std::to_string(result.psnr_db));
    EXPECT_GE(result.psnr_db, 40.0) << "samples " << result.samples << " mse " << result.mse;
}

INSTANTIATE_TEST_SUITE_P(Designs, DecodeRoundTrip,
                         ::testing::Values(RoundTripCase{"hex_paraxial", true, optics::Model::Paraxial, 0.0},
                                           RoundTripCase{"hex_exact_tilted", true, optics::Model::Exact, 45.0},
                                           RoundTripCase{"rect_paraxial_tilted", false, optics::Model::Paraxial, 45.0},
                                           RoundTripCase{"rect_exact", false, optics::Model::Exact, 0.0}),
                         [](const auto& test) { return std::string(test.param.name); });

// render_row walks each print row lenslet by lenslet with incremental directions and a
// cached triangle; every dot must still be what the per-dot definition gives: its cell by
// nearest centre, its incident direction, the mapping, the interpolation weights and the
// lenslet's samples, times 1/cos(kappa).
struct PerDotCase {
    const char* name;
    bool hexagonal;
    optics::Model model;
    double tilt_deg;
    double angle_scale;
    relight::Interpolation interpolation;
    friend void PrintTo(const PerDotCase& c, std::ostream* os) { *os << c.name; }
};

class RenderRow : public ::testing::TestWithParam<PerDotCase> {};

TEST_P(RenderRow, EveryDotIsThePerDotBlendOfItsLenslet) {
    const PerDotCase& param = GetParam();
    const optics::Design design = param.hexagonal ? small_design1(5, 4) : bundled_design(2);
    const relight::ReflectanceField field = smooth_field(600, 8, 6);
    EncodeOptions options;
    options.model = param.model;
    options.mapping.tilt_deg = param.tilt_deg;
    options.mapping.angle_scale = param.angle_scale;
    options.interpolation = param.interpolation;
    options.allow_partial_coverage = true;  // angle_scale > 1 reaches past the field's horizon
    const PatternGeometry g = param.hexagonal ? pattern_geometry(design, Dpi{2880}, Dpi{1440})
                                              : pattern_geometry(design, Dpi{240}, Dpi{200});
    const Encoder encoder(design, field, g, options);
    const std::size_t row_floats = static_cast<std::size_t>(g.width) * 3;
    std::vector<float> row(row_floats);
    std::size_t inside = 0, outside = 0;
    double worst = 0.0;
    for (int py = 1; py < g.height; py += 11) {
        encoder.render_row(py, row);
        for (int px = 0; px < g.width; ++px) {
            const Eigen::Vector2d p = g.dot_centre(px, py);
            const optics::CellIndex cell = encoder.lattice().cell_at(p);
            std::array<double, 3> expected{};
            if (encoder.lattice().contains(cell)) {
                const Eigen::Vector3d d = encoder.incident_direction(p - encoder.lattice().center(cell));
                const relight::InterpolationWeights w =
                    encoder.interpolator().weights(options.mapping.field_direction(d), param.interpolation);
                for (std::size_t k = 0; k < w.count; ++k)
                    for (int c = 0; c < 3; ++c)
                        expected[static_cast<std::size_t>(c)] += w.weight[k] * encoder.lenslet_sample(cell, w.index[k], c) / d.z();
                ++inside;
            } else {
                ++outside;
            }
            for (std::size_t c = 0; c < 3; ++c) {
                const double got = row[static_cast<std::size_t>(px) * 3 + c];
                worst = std::max(worst, std::abs(got - expected[c]) / std::max(1.0, std::abs(expected[c])));
                ASSERT_NEAR(got, expected[c], 2e-5 * std::max(1.0, std::abs(expected[c]))) << "dot " << px << ", " << py;
            }
        }
    }
    EXPECT_GT(inside, 1000u);
    RecordProperty("worst_relative_error", std::to_string(worst));
}

INSTANTIATE_TEST_SUITE_P(
    Mappings, RenderRow,
    ::testing::Values(PerDotCase{"hex_paraxial", true, optics::Model::Paraxial, 0.0, 1.0, relight::Interpolation::Delaunay},
                      PerDotCase{"hex_exact_tilted", true, optics::Model::Exact, 45.0, 1.0, relight::Interpolation::Delaunay},
                      PerDotCase{"hex_paraxial_scaled", true, optics::Model::Paraxial, 20.0, 1.6, relight::Interpolation::Delaunay},
                      PerDotCase{"hex_exact_nearest", true, optics::Model::Exact, 10.0, 1.0, relight::Interpolation::Nearest},
                      PerDotCase{"rect_exact_tilted", false, optics::Model::Exact, 45.0, 1.0, relight::Interpolation::Delaunay},
                      PerDotCase{"rect_paraxial_solid_angle", false, optics::Model::Paraxial, 0.0, 1.0,
                                 relight::Interpolation::SolidAngle}),
    [](const auto& test) { return std::string(test.param.name); });

TEST(Encoder, ExactTableMatchesDirectNewtonSolves) {
    const optics::Design design = small_design1(5, 5);
    const relight::ReflectanceField field = smooth_field(400, 4, 4);
    EncodeOptions options;
    options.model = optics::Model::Exact;
    const Encoder encoder(design, field, pattern_geometry(design, Dpi{720}, Dpi{720}), options);
    // A fraction of the angle one print dot spans (about 0.17 degrees at 2880 dpi, f = 3 mm).
    EXPECT_LT(radians_to_degrees(encoder.exact_table_error(300)), 0.005);
    // And the exact map differs from the paraxial one where the design says it does.
    const Eigen::Vector2d corner = encoder.lattice().cell_corners().front() * 0.95;
    const EncodeOptions paraxial;
    const Encoder reference(design, field, pattern_geometry(design, Dpi{720}, Dpi{720}), paraxial);
    EXPECT_GT(radians_to_degrees(angle_between(encoder.incident_direction(corner), reference.incident_direction(corner))), 0.1);
}

TEST(Encoder, FieldThatMissesTheDisplayRangeIsRefusedWithTheDirections) {
    const optics::Design design = bundled_design(2);
    relight::ReflectanceField field;
    for (const Eigen::Vector3d& d : fibonacci_hemisphere(400))
        if (angle_between(d, Eigen::Vector3d::UnitZ()) < degrees_to_radians(8)) field.directions.push_back(d);
    for (std::size_t i = 0; i < field.size(); ++i) field.images.emplace_back(4, 4, 1, 1.0f);
    EncodeOptions options;
    options.field_name = "narrow-field";
    const PatternGeometry g = pattern_geometry(design, Dpi{360}, Dpi{360});
    const std::string message = error_of([&] { Encoder(design, field, g, options); });
    EXPECT_THAT(message, HasSubstr("narrow-field"));
    EXPECT_THAT(message, HasSubstr("does not cover the display's angular range"));
    EXPECT_THAT(message, HasSubstr("display theta"));
    EXPECT_THAT(message, HasSubstr("-> field theta"));
    options.allow_partial_coverage = true;
    EXPECT_EQ(error_of([&] { Encoder(design, field, g, options); }), "");
}

TEST(Encoder, FieldsThatCannotBePrintedAreRefused) {
    // A transparency is grey or R, G, B: two channels, or five (a multispectral capture),
    // are an input error naming the field, not an internal check failing mid-encode.
    const optics::Design design = bundled_design(2);
    const PatternGeometry g = pattern_geometry(design, Dpi{360}, Dpi{360});
    EncodeOptions options;
    options.field_name = "five-channel-field";
    for (const int channels : {2, 4, 5}) {
        relight::ReflectanceField field;
        field.directions = fibonacci_hemisphere(200);
        for (std::size_t i = 0; i < field.size(); ++i) field.images.emplace_back(4, 4, channels, 0.5f);
        EXPECT_THAT(error_of([&] { Encoder(design, field, g, options); }),
                    HasSubstr("five-channel-field: the field's images have " + std::to_string(channels) + " channels"));
    }
}

TEST(Encoder, RefusesAngularDesigns) {
    const optics::Design design = bundled_design(3);
    const relight::ReflectanceField field = smooth_field(64, 2, 2);
    EXPECT_THAT(error_of([&] { Encoder(design, field, PatternGeometry{}, EncodeOptions{}); }),
                HasSubstr("Designs I and II"));
}

TEST(Encoder, NeededDirectionsAreEnoughForAnIdenticalPattern) {
    const optics::Design design = small_design1(4, 4);
    const relight::ReflectanceField field = smooth_field(1024, 8, 8);
    EncodeOptions options;
    options.mapping.tilt_deg = 30;
    const std::vector<std::size_t> needed = needed_field_directions(design, field.directions, options);
    EXPECT_LT(needed.size(), field.size() / 3);
    relight::ReflectanceField subset;
    for (std::size_t i : needed) {
        subset.directions.push_back(field.directions[i]);
        subset.images.push_back(field.images[i]);
    }
    const PatternGeometry g = pattern_geometry(design, Dpi{720}, Dpi{720});
    EXPECT_EQ(render_all(Encoder(design, field, g, options)), render_all(Encoder(design, subset, g, options)));
}

}  // namespace
}  // namespace rfd::patterns

namespace rfd::patterns {
namespace {

optics::ResolvedModel resolve_at(const optics::Design& design, double dpi, optics::ModelChoice choice) {
    const PatternGeometry g = pattern_geometry(design, Dpi{dpi}, Dpi{dpi});
    return optics::resolve(choice, optics::DesignOptics(design), {g.dot_x, g.dot_y});
}

TEST(ResolveModel, AutoIsParaxialOnlyWhereItIsWithinAQuarterDot) {
    const optics::Design design = bundled_design(2);
    const optics::ResolvedModel fine = resolve_at(design, 2880, optics::ModelChoice::Auto);
    const optics::ResolvedModel coarse = resolve_at(design, 20, optics::ModelChoice::Auto);
    EXPECT_EQ(fine.model, optics::Model::Exact);
    EXPECT_EQ(coarse.model, optics::Model::Paraxial);
    ASSERT_TRUE(fine.paraxial_error_dots && coarse.paraxial_error_dots);
    // The same error in millimetres, counted in dots of two sizes.
    EXPECT_NEAR(*fine.paraxial_error_dots / *coarse.paraxial_error_dots, 2880.0 / 20.0, 1e-6);
    EXPECT_GT(*fine.paraxial_error_dots, 0.25);
    EXPECT_LT(*coarse.paraxial_error_dots, 0.25);
    EXPECT_THAT(fine.reason, HasSubstr("beyond the tolerance"));
}

TEST(ResolveModel, AChoiceMadeByHandIsKeptAndDesignsIIIAndIVAreExactUnderAuto) {
    const optics::Design design2 = bundled_design(2);
    EXPECT_EQ(resolve_at(design2, 2880, optics::ModelChoice::Paraxial).model, optics::Model::Paraxial);
    EXPECT_EQ(resolve_at(design2, 20, optics::ModelChoice::Exact).model, optics::Model::Exact);
    const optics::Design design3 = bundled_design(3);
    const optics::DesignOptics optics3(design3);
    const optics::ResolvedModel automatic = optics::resolve(optics::ModelChoice::Auto, optics3, optics3.dot_mm());
    EXPECT_EQ(automatic.model, optics::Model::Exact);
    EXPECT_FALSE(automatic.paraxial_error_dots);
    EXPECT_THAT(automatic.reason, HasSubstr("Designs III and IV"));
    EXPECT_EQ(optics::resolve(optics::ModelChoice::Paraxial, optics3, optics3.dot_mm()).model, optics::Model::Paraxial);
}

}  // namespace
}  // namespace rfd::patterns
