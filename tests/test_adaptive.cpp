// Adaptive sampling (thesis 5.3) and two-level fields (5.4): the projection error against an
// independent least-squares solve, circumcentre insertion rules, and the two-level rules.

#include <map>
#include <numeric>
#include <random>

#include <Eigen/QR>
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "core/sphere.hpp"
#include "core/units.hpp"
#include "relight/adaptive.hpp"
#include "tests/support/hull_triangles.hpp"

namespace rfd::relight {
namespace {

// A hemisphere mesh: the upper half of an octahedron, each triangle split in four `levels`
// times with midpoints pushed to the sphere. Independent of the interpolation code.
struct Mesh {
    std::vector<Eigen::Vector3d> vertices;
    std::vector<Triangle> triangles;
};

Mesh hemisphere_mesh(int levels) {
    Mesh mesh;
    mesh.vertices = {{0, 0, 1}, {1, 0, 0}, {0, 1, 0}, {-1, 0, 0}, {0, -1, 0}};
    mesh.triangles = {{0, 1, 2}, {0, 2, 3}, {0, 3, 4}, {0, 4, 1}};
    for (int level = 0; level < levels; ++level) {
        std::map<std::pair<std::size_t, std::size_t>, std::size_t> midpoints;
        auto midpoint = [&](std::size_t a, std::size_t b) {
            const auto key = std::make_pair(std::min(a, b), std::max(a, b));
            if (auto it = midpoints.find(key); it != midpoints.end()) return it->second;
            mesh.vertices.push_back((mesh.vertices[a] + mesh.vertices[b]).normalized());
            return midpoints[key] = mesh.vertices.size() - 1;
        };
        std::vector<Triangle> finer;
        for (const Triangle& t : mesh.triangles) {
            const std::size_t ab = midpoint(t[0], t[1]), bc = midpoint(t[1], t[2]), ca = midpoint(t[2], t[0]);
            finer.push_back({t[0], ab, ca});
            finer.push_back({ab, t[1], bc});
            finer.push_back({ca, bc, t[2]});
            finer.push_back({ab, bc, ca});
        }
        mesh.triangles = finer;
    }
    return mesh;
}

Image random_image(unsigned seed, int w = 6, int h = 5) {
    std::mt19937 random(seed);
    std::uniform_real_distribution<float> value(0.0f, 1.0f);
    Image image(w, h, 3);
    for (float& v : image.samples()) v = value(random);
    return image;
}

// Independent reference: least squares by column-pivoting QR on the stacked images.
double least_squares_residual(const std::vector<Image>& images, std::size_t i,
                              const std::vector<std::size_t>& ring) {
    const auto rows = static_cast<Eigen::Index>(images[i].samples().size());
    Eigen::MatrixXd a(rows, static_cast<Eigen::Index>(ring.size()));
    Eigen::VectorXd x(rows);
    for (Eigen::Index r = 0; r < rows; ++r) {
        x(r) = images[i].samples()[r];
        for (std::size_t c = 0; c < ring.size(); ++c) a(r, static_cast<Eigen::Index>(c)) = images[ring[c]].samples()[r];
    }
    if (ring.empty()) return x.squaredNorm();
    const Eigen::VectorXd mu = a.colPivHouseholderQr().solve(x);
    return (x - a * mu).squaredNorm();
}

TEST(Adaptive, OneRingsOfTheOctahedronCap) {
    const Mesh mesh = hemisphere_mesh(0);
    const auto rings = one_rings(mesh.vertices.size(), mesh.triangles);
    EXPECT_THAT(rings[0], ::testing::ElementsAre(1, 2, 3, 4));
    EXPECT_THAT(rings[1], ::testing::ElementsAre(0, 2, 4));
}

TEST(Adaptive, ProjectionErrorMatchesIndependentLeastSquares) {
    const Mesh mesh = hemisphere_mesh(1);
    const auto rings = one_rings(mesh.vertices.size(), mesh.triangles);
    std::vector<Image> images;
    for (std::size_t i = 0; i < mesh.vertices.size(); ++i) images.push_back(random_image(static_cast<unsigned>(i)));
    ProjectionErrors errors;
    const std::vector<double> e = errors.update(images, rings);
    for (std::size_t i = 0; i < images.size(); ++i) {
        const double reference = least_squares_residual(images, i, rings[i]);
        EXPECT_NEAR(e[i], reference, 1e-9 * (1.0 + reference)) << i;
        EXPECT_GT(e[i], 0.0);  // random images are not in their neighbours' span
    }
}

TEST(Adaptive, ImageInTheSpanOfItsNeighboursHasNoError) {
    const Mesh mesh = hemisphere_mesh(0);
    const auto rings = one_rings(mesh.vertices.size(), mesh.triangles);
    std::vector<Image> images;
    for (std::size_t i = 0; i < mesh.vertices.size(); ++i) images.push_back(random_image(static_cast<unsigned>(10 + i)));
    // The pole's image: a mix of its neighbours', like a highlight that only moves.
    for (std::size_t k = 0; k < images[0].samples().size(); ++k)
        images[0].samples()[k] = 0.5f * images[1].samples()[k] + 0.25f * images[3].samples()[k];
    // A one-sided discontinuity: vertex 2 equals neighbour 1 exactly (a shadow that came).
    images[2] = images[1];
    ProjectionErrors errors;
    const auto e = errors.update(images, rings);
    const double scale = image_dot(images[0], images[0]);
    EXPECT_LT(e[0], 1e-6 * scale);
    EXPECT_LT(e[2], 1e-9 * scale);
    EXPECT_GT(e[4], 1e-3 * scale);  // an unrelated image is not explained
}

TEST(Adaptive, DuplicateAndBlackNeighboursAreHandledAsAPseudoInverse) {
    std::vector<Image> images = {random_image(1), random_image(2), random_image(2), Image(6, 5, 3, 0.0f)};
    const std::vector<std::vector<std::size_t>> rings = {{1, 2, 3}, {0}, {0}, {0}};
    ProjectionErrors errors;
    const auto e = errors.update(images, rings);
    EXPECT_NEAR(e[0], least_squares_residual(images, 0, {1}), 1e-9);
    EXPECT_NEAR(e[3], 0.0, 0.0);  // a black image is explained by anything
}

TEST(Adaptive, SecondUpdateReusesEveryProduct) {
    const Mesh mesh = hemisphere_mesh(1);
    const auto rings = one_rings(mesh.vertices.size(), mesh.triangles);
    std::vector<Image> images;
    for (std::size_t i = 0; i < mesh.vertices.size(); ++i) images.push_back(random_image(static_cast<unsigned>(i)));
    ProjectionErrors errors;
    const auto first = errors.update(images, rings);
    const std::size_t cached = errors.cached_products();
    EXPECT_EQ(errors.update(images, rings), first);
    EXPECT_EQ(errors.cached_products(), cached);
}

TEST(Adaptive, CircumcentreIsEquidistantAndOnTheTrianglesSide) {
    std::mt19937 random(3);
    std::uniform_real_distribution<double> u(-1, 1);
    for (int trial = 0; trial < 100; ++trial) {
        Eigen::Vector3d a(u(random), u(random), u(random)), b(u(random), u(random), u(random)), c(u(random), u(random), u(random));
        a.normalize(); b.normalize(); c.normalize();
        Eigen::Vector3d centre;
        ASSERT_TRUE(spherical_circumcentre(a, b, c, centre));
        EXPECT_NEAR(centre.norm(), 1.0, 1e-12);
        EXPECT_NEAR(angle_between(centre, a), angle_between(centre, b), 1e-9);
        EXPECT_NEAR(angle_between(centre, a), angle_between(centre, c), 1e-9);
        EXPECT_GT(centre.dot(a + b + c), 0.0);
    }
    Eigen::Vector3d centre;
    EXPECT_FALSE(spherical_circumcentre(Eigen::Vector3d::UnitZ(), Eigen::Vector3d::UnitZ(), Eigen::Vector3d::UnitX(), centre));
}

TEST(Adaptive, NewDirectionsGoWhereTheErrorIsAndKeepTheirDistance) {
    const Mesh mesh = hemisphere_mesh(2);
    std::vector<double> errors(mesh.vertices.size(), 0.01);
    // A "highlight" around one direction: errors fall off with the angle from it.
    const Eigen::Vector3d hot = direction_from_angles(degrees_to_radians(50), degrees_to_radians(20));
    for (std::size_t v = 0; v < errors.size(); ++v) errors[v] += std::exp(-std::pow(angle_between(mesh.vertices[v], hot) / 0.3, 2));
    InsertionOptions options;
    options.count = 6;
    const Insertion insertion = choose_new_directions(mesh.vertices, mesh.triangles, errors, options);
    ASSERT_EQ(insertion.directions.size(), 6u);
    for (std::size_t n = 0; n < insertion.directions.size(); ++n) {
        const Eigen::Vector3d& d = insertion.directions[n];
        EXPECT_LT(angle_between(d, hot), 0.6) << "inserted far from the error";
        EXPECT_GE(d.z(), 0.0);
        for (const auto& v : mesh.vertices) EXPECT_GE(angle_between(d, v), options.min_separation);
        for (std::size_t m = 0; m < n; ++m) EXPECT_GE(angle_between(d, insertion.directions[m]), options.min_separation);
    }
    // The first comes from the worst triangle.
    double worst = -1;
    std::size_t worst_index = 0;
    for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
        const double e = errors[mesh.triangles[t][0]] + errors[mesh.triangles[t][1]] + errors[mesh.triangles[t][2]];
        if (e > worst) { worst = e; worst_index = t; }
    }
    EXPECT_EQ(insertion.from_triangle.front(), worst_index);
}

TEST(Adaptive, DensityLimitStopsInsertion) {
    const Mesh mesh = hemisphere_mesh(2);  // triangles of about 11 to 16 degrees
    const std::vector<double> errors(mesh.vertices.size(), 1.0);
    InsertionOptions options;
    options.count = 1000;
    options.min_separation = degrees_to_radians(20.0);  // every circumradius is below this
    const Insertion none = choose_new_directions(mesh.vertices, mesh.triangles, errors, options);
    EXPECT_TRUE(none.directions.empty());
    const std::size_t candidates = mesh.triangles.size() + boundary_edges(mesh.triangles).size();
    EXPECT_EQ(none.skipped_small, candidates);
    options.min_separation = degrees_to_radians(2.0);
    const Insertion all = choose_new_directions(mesh.vertices, mesh.triangles, errors, options);
    // One per triangle, except where two circumcentres would fall within 2 degrees.
    EXPECT_GT(all.directions.size(), mesh.triangles.size() / 2);
    EXPECT_EQ(all.directions.size() + all.skipped_close + all.skipped_small + all.skipped_below_horizon,
              candidates);
}

// The band below the triangulation's rim: with the error on two neighbouring rim vertices,
// the first new direction lies between them and below both, toward the horizon; without
// the horizon band it can only come from a triangle above them.
TEST(Adaptive, HorizonBandIsSampledBelowTheRim) {
    // The subdivided hemisphere without the triangles touching the horizon: a rim about
    // 11 to 22 degrees up (a rim on the horizon has no band below it and adds nothing).
    Mesh mesh = hemisphere_mesh(3);
    std::erase_if(mesh.triangles, [&](const Triangle& t) {
        return mesh.vertices[t[0]].z() < 1e-9 || mesh.vertices[t[1]].z() < 1e-9 || mesh.vertices[t[2]].z() < 1e-9;
    });
    {
        const Insertion on_horizon = choose_new_directions(hemisphere_mesh(3).vertices, hemisphere_mesh(3).triangles,
                                                           std::vector<double>(hemisphere_mesh(3).vertices.size(), 1.0),
                                                           InsertionOptions{1000});
        for (std::size_t t : on_horizon.from_triangle) EXPECT_LT(t, hemisphere_mesh(3).triangles.size());
    }
    const auto rim = boundary_edges(mesh.triangles);
    ASSERT_FALSE(rim.empty());
    // Every rim vertex has exactly two rim edges (a closed loop).
    std::vector<int> degree(mesh.vertices.size(), 0);
    for (const auto& [a, b] : rim) ++degree[a], ++degree[b];
    for (std::size_t i = 0; i < degree.size(); ++i) EXPECT_TRUE(degree[i] == 0 || degree[i] == 2) << i;

    const auto [a, b] = rim.front();
    std::vector<double> errors(mesh.vertices.size(), 0.0);
    errors[a] = errors[b] = 1.0;
    InsertionOptions options;
    options.count = 1;
    const Insertion with_band = choose_new_directions(mesh.vertices, mesh.triangles, errors, options);
    ASSERT_EQ(with_band.directions.size(), 1u);
    const Eigen::Vector3d d = with_band.directions.front();
    EXPECT_GT(d.z(), 0.0);
    EXPECT_LT(d.z(), std::min(mesh.vertices[a].z(), mesh.vertices[b].z()));
    EXPECT_LT(angle_between(d, mesh.vertices[a]), angle_between(mesh.vertices[a], mesh.vertices[b]));
    EXPECT_EQ(with_band.from_triangle.front(), mesh.triangles.size());

    options.horizon_band = false;
    const Insertion without = choose_new_directions(mesh.vertices, mesh.triangles, errors, options);
    ASSERT_EQ(without.directions.size(), 1u);
    EXPECT_LT(without.from_triangle.front(), mesh.triangles.size());
}

TEST(Adaptive, TwoLevelPicksIsolatedDirectionsOnly) {
    const Mesh mesh = hemisphere_mesh(1);  // neighbours 45 degrees apart or less
    const auto rings = one_rings(mesh.vertices.size(), mesh.triangles);
    std::vector<std::size_t> all(mesh.vertices.size());
    std::iota(all.begin(), all.end(), std::size_t{0});
    EXPECT_EQ(sparse_directions(mesh.vertices, rings, all, degrees_to_radians(9)).size(), all.size());
    EXPECT_TRUE(sparse_directions(mesh.vertices, rings, all, degrees_to_radians(60)).empty());
    // Only the candidates are considered.
    EXPECT_THAT(sparse_directions(mesh.vertices, rings, {2, 4}, degrees_to_radians(9)), ::testing::ElementsAre(2, 4));
}

TEST(Adaptive, WideImageIsScaledToTheNarrowMean) {
    const Image narrow = random_image(7);
    Image wide = random_image(8);
    for (float& v : wide.samples()) v *= 0.1f;
    const Image matched = matched_to_mean(wide, narrow);
    double sum_matched = 0, sum_narrow = 0;
    for (float v : matched.samples()) sum_matched += v;
    for (float v : narrow.samples()) sum_narrow += v;
    EXPECT_NEAR(sum_matched, sum_narrow, 1e-5 * sum_narrow);
    EXPECT_NEAR(matched.at(1, 2, 0) / matched.at(3, 1, 2), wide.at(1, 2, 0) / wide.at(3, 1, 2), 1e-5);  // shape kept
    EXPECT_EQ(matched_to_mean(Image(6, 5, 3, 0.0f), narrow), Image(6, 5, 3, 0.0f));
}


// ---- the capture loop, with a synthetic scene and an independent triangulation ----

using rfd::testing::hull_triangles;

// A scene whose appearance changes quickly only for lights near `hot`: every pixel has a
// narrow highlight at a direction within 25 degrees of it, and a dull diffuse term.
class HighlightScene : public CaptureDevice {
public:
    explicit HighlightScene(Eigen::Vector3d hot) : hot_(hot.normalized()) {
        std::mt19937 random(5);
        std::normal_distribution<double> jitter(0.0, 0.2);
        for (int p = 0; p < 48; ++p) peaks_.push_back((hot_ + Eigen::Vector3d(jitter(random), jitter(random), jitter(random))).normalized());
    }
    std::vector<Image> capture(const std::vector<Eigen::Vector3d>& directions, KernelChoice kernel) override {
        std::vector<Image> images;
        const double width = kernel == KernelChoice::Narrow ? 0.05 : 0.3;
        for (const auto& d : directions) {
            Image image(8, 6, 1);
            for (int p = 0; p < 48; ++p) {
                const double a = angle_between(d, peaks_[p]);
                image.at(p % 8, p / 8, 0) = static_cast<float>(0.2 * std::max(d.z(), 0.0) + std::exp(-a * a / (width * width)));
            }
            images.push_back(image);
        }
        ++calls;
        return images;
    }
    double kernel_radius(KernelChoice kernel) const override { return kernel == KernelChoice::Narrow ? 0.05 : 0.3; }
    int calls = 0;

private:
    Eigen::Vector3d hot_;
    std::vector<Eigen::Vector3d> peaks_;
};

std::vector<Eigen::Vector3d> initial_directions(std::size_t count) {
    // Fibonacci hemisphere: near-uniform and independent of the code under test.
    std::vector<Eigen::Vector3d> directions;
    const double golden = kPi * (3.0 - std::sqrt(5.0));
    for (std::size_t k = 0; k < count; ++k) {
        const double z = 1.0 - (static_cast<double>(k) + 0.5) / static_cast<double>(count);
        const double r = std::sqrt(1.0 - z * z);
        directions.emplace_back(r * std::cos(golden * static_cast<double>(k)), r * std::sin(golden * static_cast<double>(k)), z);
    }
    return directions;
}

TEST(AdaptiveCapture, InsertsWhereTheSceneChangesUntilTheBudget) {
    const Eigen::Vector3d hot = direction_from_angles(degrees_to_radians(45), degrees_to_radians(60));
    HighlightScene scene(hot);
    AdaptiveOptions options;
    options.per_iteration = 8;
    options.total = 96;
    std::size_t reports = 0;
    const AdaptiveRun run = adaptive_capture(scene, initial_directions(48), hull_triangles, options,
                                             [&](const AdaptiveRun&) { ++reports; });
    ASSERT_EQ(run.field.size(), 96u);
    EXPECT_EQ(run.images_after.front(), 48u);
    EXPECT_EQ(run.images_after.back(), 96u);
    EXPECT_EQ(reports, run.images_after.size());
    EXPECT_EQ(run.iteration[47], 0u);
    EXPECT_EQ(run.iteration[48], 1u);
    // The inserted directions crowd around the highlights; the initial ones do not.
    auto mean_angle = [&](std::size_t begin, std::size_t end) {
        double sum = 0;
        for (std::size_t i = begin; i < end; ++i) sum += angle_between(run.field.directions[i], hot);
        return sum / static_cast<double>(end - begin);
    };
    EXPECT_LT(mean_angle(48, 96), 0.5 * mean_angle(0, 48));
    for (std::size_t i = 48; i < 96; ++i)
        for (std::size_t j = 0; j < i; ++j)
            EXPECT_GE(angle_between(run.field.directions[i], run.field.directions[j]), options.min_separation);
    // Same inputs, same run.
    HighlightScene again(hot);
    const AdaptiveRun second = adaptive_capture(again, initial_directions(48), hull_triangles, options);
    EXPECT_EQ(second.field.directions, run.field.directions);
}

TEST(AdaptiveCapture, StopsAtTheDensityLimit) {
    HighlightScene scene(Eigen::Vector3d::UnitZ());
    AdaptiveOptions options;
    options.per_iteration = 64;
    options.total = 100000;
    options.min_separation = degrees_to_radians(25);  // a coarse limit the run soon reaches
    const AdaptiveRun run = adaptive_capture(scene, initial_directions(12), hull_triangles, options);
    EXPECT_TRUE(run.density_limit_reached);
    EXPECT_LT(run.field.size(), 100u);
}

TEST(AdaptiveCapture, TwoLevelReplacesIsolatedInitialImagesByScaledWideOnes) {
    HighlightScene scene(direction_from_angles(degrees_to_radians(45), 0.0));
    AdaptiveOptions options;
    options.per_iteration = 8;
    options.total = 80;
    AdaptiveRun run = adaptive_capture(scene, initial_directions(32), hull_triangles, options);
    const ReflectanceField narrow = run.field;
    const auto replaced = make_two_level(run.field, 32, scene, hull_triangles, degrees_to_radians(9));
    ASSERT_FALSE(replaced.empty());
    const auto rings = one_rings(narrow.size(), hull_triangles(narrow.directions));
    for (std::size_t i = 0; i < narrow.size(); ++i) {
        const bool was_replaced = std::find(replaced.begin(), replaced.end(), i) != replaced.end();
        if (!was_replaced) {
            EXPECT_EQ(run.field.images[i], narrow.images[i]);
            EXPECT_EQ(run.field.kernel_radius(i), 0.05);
            continue;
        }
        EXPECT_LT(i, 32u);
        for (const std::size_t k : rings[i]) EXPECT_GT(angle_between(narrow.directions[i], narrow.directions[k]), degrees_to_radians(9));
        EXPECT_EQ(run.field.kernel_radius(i), 0.3);
        EXPECT_NEAR(image_dot(run.field.images[i], Image(8, 6, 1, 1.0f)), image_dot(narrow.images[i], Image(8, 6, 1, 1.0f)), 1e-4);
    }
}

TEST(Adaptive, CanonicalOrderKeepsOrientationAndIgnoresListingOrder) {
    const std::vector<Triangle> listed = {{7, 2, 5}, {3, 9, 1}, {4, 0, 8}};
    const std::vector<Triangle> shuffled = {{1, 3, 9}, {8, 4, 0}, {2, 5, 7}};
    const std::vector<Triangle> expected = {{0, 8, 4}, {1, 3, 9}, {2, 5, 7}};
    EXPECT_EQ(canonical_order(listed), expected);
    EXPECT_EQ(canonical_order(shuffled), expected);
}

}  // namespace
}  // namespace rfd::relight
