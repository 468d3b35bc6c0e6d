// The Design III/IV encoder (patterns/angular.hpp) and its fields: round trips from a field
// through the pattern file back to the field at dots found with the forward optics, letters
// that decode to the right bin, diamonds that behave as figure 8.15 says, view sets read
// and rejected with file:line, and the coverage check naming the missing directions.

#include <cmath>
#include <fstream>
#include <string>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "core/error.hpp"
#include "core/image_io.hpp"
#include "core/sphere.hpp"
#include "patterns/angular.hpp"
#include "relight/field.hpp"
#include "tests/support/temp_dir.hpp"
#include "tests/support/bundled.hpp"

namespace rfd::patterns {
namespace {

using ::testing::HasSubstr;
using rfd::testing::bundled_design;
using rfd::testing::TempDir;

// A smooth field, so that what the encoder does is checked, not the sampling of edges.
void smooth(const Eigen::Vector3d& light, const Eigen::Vector3d& view, int u, int v, std::span<float> out) {
    out[0] = static_cast<float>(0.5 + 2.0 * view.x() - 1.5 * view.y() + 0.8 * light.y() + 0.05 * u + 0.03 * v);
    out[1] = static_cast<float>(0.4 + light.x() * (1.0 + view.y()));
    out[2] = static_cast<float>(0.3 + 0.5 * light.y() * view.x() + 0.02 * u);
}

std::vector<float> render(const PatternSource& source) {
    const auto& g = source.geometry();
    std::vector<float> all(g.dot_count() * static_cast<std::size_t>(source.channels()));
    const std::size_t row = static_cast<std::size_t>(g.width) * static_cast<std::size_t>(source.channels());
    for (int y = 0; y < g.height; ++y) source.render_row(y, std::span<float>(all.data() + y * row, row));
    return all;
}

TEST(AngularPattern, RoundTripThroughTheFileAtDotsFoundByTheForwardMaps) {
    const optics::DesignOptics optics(bundled_design(3));
    const FunctionField field(3, smooth);
    TempDir dir;
    for (const optics::Model model : {optics::Model::Paraxial, optics::Model::Exact}) {
        AngularOptions options;
        options.model = model;
        options.table_size = 65;
        options.dpi_x = options.dpi_y = 300;
        const AngularPattern pattern(optics, field, options);
        const auto path = dir.path() / "round.exr";
        WriteOptions write;
        write.half_float = false;
        write_pattern(path, pattern, pattern.attributes(), write);
        PatternReader reader(path);
        const auto& g = pattern.geometry();
        std::vector<float> rows(g.dot_count() * 3);
        reader.read_rows(0, g.height, rows);
        EXPECT_EQ(reader.info().attributes.at("kind"), "angular");
        EXPECT_EQ(reader.info().attributes.at("model"), optics::to_string(model));
        const optics::MesoPixelOptics& meso = pattern.meso();
        int checked = 0;
        for (const optics::CellIndex cell : {optics::CellIndex{1, 1}, optics::CellIndex{3, 2}, optics::CellIndex{4, 3}})
            for (const Eigen::Vector2d& slope : {Eigen::Vector2d(0.05, -0.08), Eigen::Vector2d(-0.12, 0.1), Eigen::Vector2d(0.0, 0.0)}) {
                // The dot that sends bin `cell`'s light toward `slope`.
                const Eigen::Vector3d wanted = Eigen::Vector3d(slope.x(), slope.y(), 1.0).normalized();
                const auto offset = meso.offset_for(wanted, cell, model);
                ASSERT_TRUE(offset.has_value());
                const Eigen::Vector2d at = g.raster_position(meso.lattice().center(cell) + *offset);
                const int px = static_cast<int>(std::lround(at.x())), py = static_cast<int>(std::lround(at.y()));
                const auto place = pattern.place(g.dot_centre(px, py));
                ASSERT_TRUE(place.has_value());
                ASSERT_EQ(place->cell, cell);
                // That dot's own chief ray, traced directly (no table): within half a dot of
                // the wanted direction, and the field there is what the file holds.
                const optics::DotRay ray = meso.dot(place->offset, cell, model);
                ASSERT_EQ(ray.light, optics::DotLight::Lit);
                EXPECT_LT(angle_between(ray.output, wanted), std::abs(meso.output_gain()) * g.dot_x);
                std::array<float, 3> expected{0, 0, 0}, one{};
                const auto bin = meso.bin(cell, model, options.bin_samples);
                for (const auto& d : bin.samples) {
                    smooth(field_light_of(d), ray.output, 0, 0, one);
                    for (int c = 0; c < 3; ++c)
                        expected[static_cast<std::size_t>(c)] += one[static_cast<std::size_t>(c)] / static_cast<float>(bin.samples.size());
                }
                // Paraxial tables are exact (a linear map); exact ones interpolate to ~1e-5.
                const double tolerance = model == optics::Model::Paraxial ? 1e-5 : 2e-4;
                for (int c = 0; c < 3; ++c)
                    EXPECT_NEAR(rows[(static_cast<std::size_t>(py) * g.width + px) * 3 + c], expected[static_cast<std::size_t>(c)], tolerance)
                        << optics::to_string(model) << " cell " << cell.i << "," << cell.j;
                ++checked;
            }
        EXPECT_EQ(checked, 9);
    }
}

TEST(AngularPattern, OnlyLitDotsCarryLightAndTheTablesAgreeWithTheOptics) {
    const optics::DesignOptics optics(bundled_design(3));
    const FunctionField field(1, [](const Eigen::Vector3d&, const Eigen::Vector3d&, int, int, std::span<float> out) { out[0] = 1.0f; });
    AngularOptions options;
    options.table_size = 129;
    options.dpi_x = options.dpi_y = 200;
    const AngularPattern pattern(optics, field, options);
    const auto values = render(pattern);
    const auto& g = pattern.geometry();
    std::size_t lit = 0, disagree = 0, inside = 0;
    for (int py = 0; py < g.height; ++py)
        for (int px = 0; px < g.width; ++px) {
            const auto place = pattern.place(g.dot_centre(px, py));
            const float value = values[static_cast<std::size_t>(py) * g.width + px];
            if (!place) {
                EXPECT_EQ(value, 0.0f);
                continue;
            }
            ++inside;
            const bool direct = pattern.meso().dot(place->offset, place->cell, optics::Model::Paraxial).light == optics::DotLight::Lit;
            lit += value > 0.0f;
            disagree += direct != (value > 0.0f);
        }
    // Nearest-node flags misplace the boundary by at most half a node (16 um) in a few dots.
    EXPECT_LT(double(disagree), 0.01 * double(inside));
    const double fraction = double(lit) / double(inside);
    EXPECT_NEAR(fraction, pattern.counts().lit_fraction(), 0.02);
    EXPECT_GT(fraction, 0.6);  // the main lens's image covers most of each cell ...
    EXPECT_LT(fraction, 0.85); // ... but not its corners
    // The white point of a field that is 1 wherever lit.
    EXPECT_FLOAT_EQ(static_cast<float>(estimate_white(pattern, 99.5)), 1.0f);
    // Deterministic: the same rows again, bit for bit.
    EXPECT_EQ(render(pattern), values);
}

TEST(AngularPattern, LetterPatternDecodesToTheRightLetterInEveryBin) {
    const optics::DesignOptics optics(bundled_design(3));
    const optics::MesoPixelOptics meso(optics);
    const std::string characters = "0123456789ABCDEFGHIJKLMNOPQRST";
    std::vector<Eigen::Vector3d> centres;
    for (int j = 0; j < 5; ++j)
        for (int i = 0; i < 6; ++i) centres.push_back(field_light_of(meso.bin({i, j}, optics::Model::Paraxial, 1).centre));
    const double half = std::abs(meso.output_gain()) * 1.5;
    const LetterField letters(centres, characters, {half, half});
    AngularOptions options;
    options.table_size = 65;
    options.dpi_x = options.dpi_y = 720;
    const AngularPattern pattern(optics, letters, options);
    const auto values = render(pattern);
    const auto& g = pattern.geometry();
    // Decode: every lit dot of a bin drawn at its output slope into a 16 x 16 picture of
    // the letter box; the letter whose mask correlates best must be the bin's.
    constexpr int kSide = 16;
    std::vector<std::vector<double>> pictures(30, std::vector<double>(kSide * kSide, 0.0));
    std::vector<std::vector<int>> hits(30, std::vector<int>(kSide * kSide, 0));
    for (int py = 0; py < g.height; ++py)
        for (int px = 0; px < g.width; ++px) {
            const auto place = pattern.place(g.dot_centre(px, py));
            if (!place) continue;
            const auto dot = pattern.table_dot(*place);
            if (!dot.lit) continue;
            const double tx = dot.output.x() / dot.output.z() / half, ty = dot.output.y() / dot.output.z() / half;
            if (std::abs(tx) >= 1 || std::abs(ty) >= 1) continue;
            const int x = static_cast<int>((tx + 1) / 2 * kSide), y = static_cast<int>((1 - ty) / 2 * kSide);
            const std::size_t bin = meso.lattice().linear_index(place->cell);
            pictures[bin][static_cast<std::size_t>(y * kSide + x)] += values[static_cast<std::size_t>(py) * g.width + px];
            hits[bin][static_cast<std::size_t>(y * kSide + x)] += 1;
        }
    auto correlation = [](const std::vector<double>& a, const std::vector<double>& b) {
        double ma = 0, mb = 0;
        for (std::size_t k = 0; k < a.size(); ++k) ma += a[k], mb += b[k];
        ma /= double(a.size()), mb /= double(b.size());
        double ab = 0, aa = 0, bb = 0;
        for (std::size_t k = 0; k < a.size(); ++k)
            ab += (a[k] - ma) * (b[k] - mb), aa += (a[k] - ma) * (a[k] - ma), bb += (b[k] - mb) * (b[k] - mb);
        return ab / std::sqrt(aa * bb + 1e-300);
    };
    std::vector<std::vector<double>> masks;
    for (std::size_t k = 0; k < characters.size(); ++k) {
        std::vector<double> m(kSide * kSide);
        for (int y = 0; y < kSide; ++y)
            for (int x = 0; x < kSide; ++x) {
                const double tx = ((x + 0.5) / kSide * 2 - 1) * half, ty = (1 - (y + 0.5) / kSide * 2) * half;
                m[static_cast<std::size_t>(y * kSide + x)] = letters.sample(k, Eigen::Vector3d(tx, ty, 1).normalized());
            }
        masks.push_back(m);
    }
    for (std::size_t bin = 0; bin < 30; ++bin) {
        for (std::size_t k = 0; k < pictures[bin].size(); ++k)
            if (hits[bin][k] > 0) pictures[bin][k] /= hits[bin][k];
        std::size_t best = 0;
        double best_score = -2;
        for (std::size_t k = 0; k < masks.size(); ++k) {
            const double score = correlation(pictures[bin], masks[k]);
            if (score > best_score) best_score = score, best = k;
        }
        EXPECT_EQ(characters[best], characters[bin]) << "bin " << bin;
        EXPECT_GT(best_score, 0.8) << "bin " << bin;
    }
}

TEST(DiamondField, GrowsAsTheLightMovesDownHollowsFromTheSidesTintsByView) {
    const DiamondField diamonds(0.2, 0.2);
    auto area = [&](const Eigen::Vector3d& light) {
        double sum = 0;
        for (int v = 0; v < 7; ++v)
            for (int u = 0; u < 7; ++u) sum += diamonds.coverage(light.normalized(), u, v, 7, 7);
        return sum;
    };
    const Eigen::Vector3d up(0, 0.2, 1), centre(0, 0, 1), down(0, -0.2, 1), side(0.2, 0, 1);
    EXPECT_LT(area(up), area(centre));
    EXPECT_LT(area(centre), area(down));
    // Lit head-on the centre macro-pixel is full; lit from the side it is empty (hollow).
    EXPECT_DOUBLE_EQ(diamonds.coverage(centre, 3, 3, 7, 7), 1.0);
    EXPECT_DOUBLE_EQ(diamonds.coverage(side.normalized(), 3, 3, 7, 7), 0.0);
    EXPECT_GT(area(side), 0.0);  // the outline remains
    // Closed-form areas of the L1 ball |x|+|y| <= s on the 2 x 2 square: 2 s^2 of 4, times 49.
    EXPECT_NEAR(area(centre), 49.0 * 2 * 0.575 * 0.575 / 4, 1.5);
    // At and beyond the view range the tint saturates.
    const auto right = diamonds.colour(Eigen::Vector3d(0.3, 0, 1).normalized());
    const auto head_on = diamonds.colour(Eigen::Vector3d::UnitZ());
    const auto left = diamonds.colour(Eigen::Vector3d(-0.3, 0, 1).normalized());
    const auto halfway = diamonds.colour(Eigen::Vector3d(0.1, 0, 1).normalized());
    EXPECT_NEAR(halfway[1], 0.5f, 1e-6f);
    EXPECT_EQ(right, (std::array<float, 3>{1, 0, 1}));   // magenta
    EXPECT_EQ(head_on, (std::array<float, 3>{1, 1, 1})); // white
    EXPECT_EQ(left, (std::array<float, 3>{0, 1, 0}));    // green
}

TEST(AngularPattern, DesignFourDotsCarryTheirMacroPixelsDiamond) {
    const optics::DesignOptics optics(bundled_design(4));
    const DiamondField diamonds(0.25, 0.25);
    AngularOptions options;
    options.table_size = 33;
    options.dpi_x = options.dpi_y = 60;
    const AngularPattern pattern(optics, diamonds, options);
    const auto& g = pattern.geometry();
    EXPECT_EQ(pattern.macro_x(), 7);
    const auto values = render(pattern);
    int checked = 0;
    for (int py = 0; py < g.height; py += 7)
        for (int px = 0; px < g.width; px += 5) {
            const auto place = pattern.place(g.dot_centre(px, py));
            if (!place) continue;
            const auto dot = pattern.table_dot(*place);
            if (!dot.lit) continue;
            const std::size_t bin = pattern.meso().lattice().linear_index(place->cell);
            double coverage = 0;
            for (const auto& light : pattern.field_bins()[bin]) coverage += diamonds.coverage(light, place->u, place->v, 7, 7);
            coverage /= double(pattern.field_bins()[bin].size());
            const auto tint = diamonds.colour(dot.output);
            for (int c = 0; c < 3; ++c)
                EXPECT_NEAR(values[(static_cast<std::size_t>(py) * g.width + px) * 3 + c], coverage * tint[static_cast<std::size_t>(c)], 1e-6);
            ++checked;
        }
    EXPECT_GT(checked, 100);
}

// ----- view sets -----

void write_lines(const std::filesystem::path& path, const std::string& text) {
    std::ofstream(path) << text;
}

// A view folder with `lights` lights whose images hold `value` (w x h, 3 channels).
void write_view(const std::filesystem::path& folder, const std::vector<Eigen::Vector3d>& lights, float value, int w = 14, int h = 14) {
    relight::ReflectanceField field;
    field.directions = lights;
    for (std::size_t k = 0; k < lights.size(); ++k) {
        Image image(w, h, 3, value);
        // Quadrants differ, so the macro grid's box filter shows in the values.
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x) image.at(x, y, 1) = value + (x < w / 2 ? 0.0f : 1.0f) + (y < h / 2 ? 10.0f : 0.0f);
        field.images.push_back(image);
    }
    relight::write_field(folder, field);
}

TEST(ViewSet, RoundTripsThroughTheEncoderWithViewInterpolation) {
    TempDir dir;
    const auto lights = fibonacci_hemisphere(60);
    const std::vector<Eigen::Vector3d> views = {Eigen::Vector3d(0, 0, 1), Eigen::Vector3d(0.3, 0, 1).normalized(),
                                                Eigen::Vector3d(-0.3, 0.05, 1).normalized(), Eigen::Vector3d(0, 0.3, 1).normalized(),
                                                Eigen::Vector3d(0.02, -0.3, 1).normalized()};
    std::vector<relight::ViewEntry> entries;
    for (std::size_t k = 0; k < views.size(); ++k) {
        const std::string name = "view_0" + std::to_string(k);
        write_view(dir.path() / name, lights, static_cast<float>(k + 1));
        entries.push_back({name, views[k], Eigen::Matrix3d::Identity(), 0});
    }
    relight::write_view_file(dir.path() / "views.txt", entries);
    const ViewSetField field(relight::read_view_set(dir.path()));
    EXPECT_EQ(field.views().views.size(), 5u);
    const optics::DesignOptics optics(bundled_design(3));
    AngularOptions options;
    options.table_size = 33;
    options.dpi_x = options.dpi_y = 150;
    const AngularPattern pattern(optics, field, options);
    const auto values = render(pattern);
    const relight::SphericalInterpolator interpolator(views);
    const auto& g = pattern.geometry();
    int checked = 0;
    for (int py = 0; py < g.height; py += 3)
        for (int px = 0; px < g.width; px += 3) {
            const auto place = pattern.place(g.dot_centre(px, py));
            if (!place) continue;
            const auto dot = pattern.table_dot(*place);
            if (!dot.lit) continue;
            const auto w = interpolator.weights(dot.output);
            double expected = 0;  // channel 0: the view's number, whatever the light
            for (std::size_t k = 0; k < w.count; ++k) expected += w.weight[k] * double(w.index[k] + 1);
            const std::size_t at = (static_cast<std::size_t>(py) * g.width + px) * 3;
            EXPECT_NEAR(values[at], expected, 1e-5);
            // Channel 1: Design III is one macro-pixel: the mean over the image (+0.5 +5).
            EXPECT_NEAR(values[at + 1], expected + 5.5, 1e-5);
            ++checked;
        }
    EXPECT_GT(checked, 50);
}

TEST(ViewSet, FieldThatMissesTheIncidentBinsNamesTheDirections) {
    TempDir dir;
    // Lights within 5 degrees of the pole: the display's bins reach 17 degrees.
    std::vector<Eigen::Vector3d> lights;
    for (int k = 0; k < 6; ++k) lights.push_back(direction_from_angles(degrees_to_radians(5.0), k * kPi / 3));
    lights.push_back(Eigen::Vector3d::UnitZ());
    write_view(dir.path() / "only", lights, 1.0f);
    write_lines(dir.path() / "views.txt", "1\nonly 0 0 1\n");
    const ViewSetField field(relight::read_view_set(dir.path()));
    const optics::DesignOptics optics(bundled_design(3));
    try {
        AngularOptions options;
        options.table_size = 5;
        options.dpi_x = options.dpi_y = 50;
        const AngularPattern pattern(optics, field, options);
        FAIL() << "accepted";
    } catch (const InputError& error) {
        EXPECT_THAT(error.what(), HasSubstr("views.txt:2"));
        EXPECT_THAT(error.what(), HasSubstr("has no lights around the display's incident directions bin 0 (theta"));
        EXPECT_THAT(error.what(), HasSubstr("in all)"));
    }
}

TEST(ViewSet, BadViewFilesAreInputErrorsWithFileAndLine) {
    TempDir dir;
    const auto lights = fibonacci_hemisphere(8);
    write_view(dir.path() / "a", lights, 1.0f);
    write_view(dir.path() / "b", lights, 1.0f, 10, 14);
    auto message = [&](const std::string& text) -> std::string {
        write_lines(dir.path() / "views.txt", text);
        try {
            relight::read_view_set(dir.path());
        } catch (const InputError& error) {
            return error.what();
        }
        return "accepted";
    };
    EXPECT_THAT(message("3\na 0 0 1\na 0 0.1 1\n"), HasSubstr("views.txt:1: the file declares 3 view(s) but lists 2"));
    EXPECT_THAT(message("1\na 0 0 x\n"), HasSubstr("views.txt:2: 'x' is not a number"));
    EXPECT_THAT(message("2\na 0 0 1\nb 0.1 0 1\n"), HasSubstr("views.txt:3: view 'b' has images of 10 x 14 x 3 but view 'a' has 14 x 14 x 3"));
    EXPECT_THAT(message("1\na 0 0 -1\n"), HasSubstr("z > 0"));
    EXPECT_THAT(message("1\na 0 0 1 1 0 0 0 1 0 0 0 2\n"), HasSubstr("not a rotation"));
    EXPECT_THAT(message("1\na 0 0 1 5\n"), HasSubstr("got 4 number(s)"));
    // A folder the file names that is not there is an I/O error, at the line that names it.
    write_lines(dir.path() / "views.txt", "# c\n1\nmissing 0 0 1\n");
    try {
        relight::read_view_set(dir.path());
        ADD_FAILURE() << "a missing view folder was accepted";
    } catch (const IoError& error) {
        EXPECT_THAT(error.what(), HasSubstr("views.txt:3: view folder"));
    }
    // Two views cannot be interpolated.
    write_lines(dir.path() / "views.txt", "2\na 0 0 1\na 0.1 0 1\n");
    EXPECT_THROW(ViewSetField(relight::read_view_set(dir.path())), InputError);
}

TEST(ViewSet, RotationsTurnEachViewsLightsIntoTheDisplayFrame) {
    TempDir dir;
    const auto lights = fibonacci_hemisphere(8);
    write_view(dir.path() / "a", lights, 1.0f);
    const Eigen::Matrix3d rotation = Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitY()).toRotationMatrix();
    relight::write_view_file(dir.path() / "views.txt", {{"a", Eigen::Vector3d(0.1, 0, 1).normalized(), rotation, 0}});
    const relight::ViewSet set = relight::read_view_set(dir.path() / "views.txt");
    ASSERT_EQ(set.fields.size(), 1u);
    for (std::size_t k = 0; k < lights.size(); ++k) EXPECT_NEAR((set.fields[0].directions[k] - rotation * lights[k]).norm(), 0.0, 1e-12);
    EXPECT_NEAR((set.views[0].direction - Eigen::Vector3d(0.1, 0, 1).normalized()).norm(), 0.0, 1e-15);
}

}  // namespace
}  // namespace rfd::patterns
