// Evaluation of a sparse field against a reference (thesis 5.2, figure 5.4).

#include <cmath>
#include <limits>

#include <gtest/gtest.h>

#include "core/error.hpp"
#include "core/sphere.hpp"
#include "core/units.hpp"
#include "relight/evaluate.hpp"
#include "relight/render.hpp"
#include "tests/support/lambertian_sphere.hpp"

namespace rfd::relight {
namespace {

using rfd::testing::fibonacci_hemisphere;
using rfd::testing::lambertian_sphere_field;

// Reference directions that no Fibonacci set contains: a rotated, denser spiral.
std::vector<Eigen::Vector3d> reference_directions() {
    std::vector<Eigen::Vector3d> out;
    const Eigen::Matrix3d turn = Eigen::AngleAxisd(0.37, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    for (const auto& d : fibonacci_hemisphere(150)) out.push_back(turn * d);
    return out;
}

TEST(Evaluate, FieldAgainstItselfHasNoError) {
    const ReflectanceField field = lambertian_sphere_field(fibonacci_hemisphere(60), 24);
    for (const auto method : {Interpolation::Delaunay, Interpolation::Nearest}) {
        const Evaluation e = evaluate(field, field, method);
        EXPECT_EQ(e.total_squared_error, 0.0);
        EXPECT_EQ(e.psnr, std::numeric_limits<double>::infinity());
        ASSERT_EQ(e.per_direction.size(), field.size());
        for (const double v : e.per_direction) EXPECT_EQ(v, 0.0);
    }
}

TEST(Evaluate, MatchesAnIndependentRelightAndThePsnrFormula) {
    const ReflectanceField sparse = lambertian_sphere_field(fibonacci_hemisphere(40), 24);
    const ReflectanceField reference = lambertian_sphere_field(reference_directions(), 24);
    const Evaluation e = evaluate(sparse, reference);
    double total = 0.0, peak = 0.0;
    for (std::size_t j = 0; j < reference.size(); j += 7) {
        const Image relit = render(sparse, {DirectionalLight{reference.directions[j], Eigen::Vector3d::Ones()}});
        double error = 0.0;
        for (std::size_t k = 0; k < relit.samples().size(); ++k) {
            const double diff = static_cast<double>(relit.samples()[k]) - reference.images[j].samples()[k];
            error += diff * diff;
        }
        EXPECT_NEAR(e.per_direction[j], error, 1e-6 * error + 1e-12) << "direction " << j;
    }
    for (std::size_t j = 0; j < reference.size(); ++j) {
        total += e.per_direction[j];
        for (const float s : reference.images[j].samples()) peak = std::max(peak, static_cast<double>(s));
    }
    EXPECT_DOUBLE_EQ(e.total_squared_error, total);
    const double samples = static_cast<double>(reference.size() * reference.images[0].samples().size());
    EXPECT_NEAR(e.psnr, 10.0 * std::log10(peak * peak * samples / total), 1e-9);
    EXPECT_GT(e.total_squared_error, 0.0);
    EXPECT_EQ(e.peak, peak);
    const double per_image = static_cast<double>(reference.images[0].samples().size());
    EXPECT_NEAR(e.entry_psnr(5), 10.0 * std::log10(peak * peak * per_image / e.per_direction[5]), 1e-9);
}

TEST(Evaluate, ErrorFallsAsTheSparseSetDensifies) {
    const ReflectanceField reference = lambertian_sphere_field(reference_directions(), 24);
    double previous = std::numeric_limits<double>::infinity(), previous_nearest = previous;
    for (const std::size_t count : {12u, 40u, 120u, 360u}) {
        const ReflectanceField sparse = lambertian_sphere_field(fibonacci_hemisphere(count), 24);
        const double error = evaluate(sparse, reference).total_squared_error;
        const double nearest = evaluate(sparse, reference, Interpolation::Nearest).total_squared_error;
        EXPECT_LT(error, previous) << count << " directions";
        EXPECT_LT(nearest, previous_nearest) << count << " directions";
        EXPECT_LT(error, nearest) << count << " directions";  // interpolation beats the baseline
        previous = error;
        previous_nearest = nearest;
    }
}

TEST(Evaluate, DeterministicAndShapeChecked) {
    const ReflectanceField sparse = lambertian_sphere_field(fibonacci_hemisphere(30), 20);
    const ReflectanceField reference = lambertian_sphere_field(reference_directions(), 20);
    const Evaluation a = evaluate(sparse, reference), b = evaluate(sparse, reference);
    EXPECT_EQ(a.total_squared_error, b.total_squared_error);
    EXPECT_EQ(a.per_direction, b.per_direction);
    const ReflectanceField other_size = lambertian_sphere_field(reference_directions(), 21);
    try {
        evaluate(sparse, other_size);
        FAIL() << "images of different sizes were compared";
    } catch (const InputError& error) {
        EXPECT_NE(std::string(error.what()).find("21x21x1"), std::string::npos) << error.what();
    }
    EXPECT_THROW(evaluate(sparse, ReflectanceField{}), InputError);
}

TEST(Evaluate, UnderLightsAgreesWithTheDirectionScoreAndWithRendering) {
    const ReflectanceField sparse = lambertian_sphere_field(fibonacci_hemisphere(40), 24);
    const ReflectanceField reference = lambertian_sphere_field(reference_directions(), 24);
    const Evaluation per_direction = evaluate(sparse, reference);
    // A point light from a reference direction relights the reference to its own image there.
    for (const std::size_t j : {3u, 77u}) {
        const LightEvaluation e =
            evaluate_under_lights(sparse, reference, {DirectionalLight{reference.directions[j], Eigen::Vector3d::Ones()}});
        EXPECT_NEAR(e.score.per_direction.at(0), per_direction.per_direction[j], 1e-6 * per_direction.per_direction[j]);
    }
    // A disk: the error of the two renderings, computed here independently.
    const Light disk = DiskLight{Eigen::Vector3d(0.3, 0.1, 1.0).normalized(), degrees_to_radians(10.0),
                                 Eigen::Vector3d::Ones()};
    const LightEvaluation e = evaluate_under_lights(sparse, reference, {disk});
    const Image a = render(sparse, {disk}), b = render(reference, {disk});
    double error = 0.0, peak = 0.0;
    for (std::size_t k = 0; k < a.samples().size(); ++k) {
        const double diff = static_cast<double>(a.samples()[k]) - b.samples()[k];
        error += diff * diff;
        peak = std::max(peak, static_cast<double>(b.samples()[k]));
    }
    EXPECT_NEAR(e.score.total_squared_error, error, 1e-9 * error);
    EXPECT_GT(error, 0.0);
    EXPECT_NEAR(e.score.psnr, 10.0 * std::log10(peak * peak * static_cast<double>(a.samples().size()) / error), 1e-9);
    EXPECT_NEAR(e.score.entry_psnr(0), e.score.psnr, 1e-9);  // one light: the entry is the whole
    EXPECT_EQ(e.relit.at(0), a);
    EXPECT_EQ(e.reference_relit.at(0), b);
    EXPECT_EQ(evaluate_under_lights(reference, reference, {disk}).score.total_squared_error, 0.0);
    EXPECT_THROW(evaluate_under_lights(sparse, reference, {}), InputError);
}

}  // namespace
}  // namespace rfd::relight
