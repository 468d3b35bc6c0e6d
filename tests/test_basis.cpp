// Fitted bases (relight/basis.hpp): the functions against OpenLIME's and the closed-form
// Legendre functions, a field made of a basis fitted back exactly, and the closed-form
// leave-one-out against refitting without each light.

#include <cmath>
#include <random>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "core/error.hpp"
#include "core/sphere.hpp"
#include "core/units.hpp"
#include "relight/basis.hpp"
#include "relight/evaluate.hpp"
#include "relight/field.hpp"
#include "tests/support/error_of.hpp"
#include "tests/support/scattered_lights.hpp"
#include "tests/support/temp_dir.hpp"

namespace rfd::relight {
namespace {

using ::testing::HasSubstr;
using rfd::testing::error_of;
using rfd::testing::scattered_lights;
using rfd::testing::TempDir;

TEST(Basis, HemisphericalHarmonicsAreOpenLimesAndTheLegendreFunctions) {
    int checked = 0;
    for (const Eigen::Vector3d& d : scattered_lights(50, 3)) {
        const Eigen::VectorXd b = basis_values(Basis::Hsh4, d);
        ASSERT_EQ(b.size(), 16);
        // OpenLIME's ShaderRTI HSH.lightWeights, term by term (with pi exact).
        const double phi = std::atan2(d.y(), d.x()), theta = std::min(std::acos(d.z()), kPi / 2 - 0.15);
        const double c = std::cos(theta), c2 = c * c, root = std::sqrt(c - c2);
        const std::vector<double> openlime{
            1.0 / std::sqrt(2 * kPi),
            std::sqrt(6 / kPi) * std::cos(phi) * root,
            std::sqrt(3 / (2 * kPi)) * (-1 + 2 * c),
            std::sqrt(6 / kPi) * root * std::sin(phi),
            std::sqrt(30 / kPi) * std::cos(2 * phi) * (-c + c2),
            std::sqrt(30 / kPi) * std::cos(phi) * (-1 + 2 * c) * root,
            std::sqrt(5 / (2 * kPi)) * (1 - 6 * c + 6 * c2),
            std::sqrt(30 / kPi) * (-1 + 2 * c) * root * std::sin(phi),
            std::sqrt(30 / kPi) * (-c + c2) * std::sin(2 * phi)};
        for (std::size_t k = 0; k < openlime.size(); ++k) EXPECT_NEAR(b[static_cast<Eigen::Index>(k)], openlime[k], 1e-12) << k;
        // Degree 3: P_3^m of the shifted argument t = 2c - 1 in closed form, s = sqrt(1 - t^2).
        const double t = 2 * c - 1, s = std::sqrt(1 - t * t);
        const double p[4] = {(5 * t * t * t - 3 * t) / 2, 1.5 * (5 * t * t - 1) * s, 15 * t * s * s, 15 * s * s * s};
        const double fact[7] = {1, 1, 2, 6, 24, 120, 720};
        for (int m = 3; m >= -3; --m) {
            const int a = std::abs(m);
            const double k = std::sqrt(7.0 / (2 * kPi) * fact[3 - a] / fact[3 + a]);
            const double az = m > 0 ? std::sqrt(2.0) * std::cos(m * phi) : m < 0 ? std::sqrt(2.0) * std::sin(a * phi) : 1.0;
            EXPECT_NEAR(b[9 + 3 - m], (a == 2 ? -1 : 1) * k * p[a] * az, 1e-12) << "m " << m;
        }
        ++checked;
    }
    EXPECT_EQ(checked, 50);
    const Eigen::Vector3d d = direction_from_angles(0.4, 1.1);
    const Eigen::VectorXd ptm = basis_values(Basis::Ptm, d);
    EXPECT_EQ(ptm, (Eigen::VectorXd(6) << 1, d.x(), d.y(), d.x() * d.x(), d.x() * d.y(), d.y() * d.y()).finished());
}

// A field of `lights` images, 12 x 9 x 3, on disk as EXR: each pixel and channel the basis's
// functions with random coefficients, plus noise of `noise` (0: exactly the basis).
std::filesystem::path basis_field(const TempDir& dir, Basis basis, const std::vector<Eigen::Vector3d>& lights,
                                  double noise) {
    std::mt19937 random(11);
    std::normal_distribution<double> gauss(0.0, 1.0);
    const int m = basis_size(basis);
    std::vector<Eigen::VectorXd> coefficients;
    for (int k = 0; k < 12 * 9 * 3; ++k) coefficients.push_back(Eigen::VectorXd::NullaryExpr(m, [&] { return gauss(random); }));
    FieldWriter out(dir / "f");
    for (const Eigen::Vector3d& d : lights) {
        const Eigen::VectorXd b = basis_values(basis, d);
        Image image(12, 9, 3);
        for (std::size_t k = 0; k < coefficients.size(); ++k)
            image.samples()[k] = static_cast<float>(5.0 + coefficients[k].dot(b) + noise * gauss(random));
        out.add(image, d);
    }
    out.finish();
    return dir / "f";
}

TEST(Basis, AFieldMadeOfTheBasisIsPredictedExactlyWithoutEachLight) {
    for (const Basis basis : {Basis::Ptm, Basis::Hsh3}) {
        TempDir dir;
        const auto lights = scattered_lights(30, 5);
        FieldReader field(basis_field(dir, basis, lights, 0.0));
        const LeaveOneOut loo = leave_one_out(field, BasisFit(basis, lights));
        for (std::size_t j = 0; j < lights.size(); ++j)
            EXPECT_LT(loo.squared_error[j] / loo.samples_per_image, 1e-9) << name_of(kBasisNames, basis) << " light " << j;
    }
}

TEST(Basis, LeaveOneOutInClosedFormIsTheFitWithoutTheLight) {
    TempDir dir;
    const auto lights = scattered_lights(20, 7);
    const auto path = basis_field(dir, Basis::Hsh3, lights, 0.3);
    const ReflectanceField field = read_field(path);
    FieldReader reader(path);
    const LeaveOneOut loo = leave_one_out(reader, BasisFit(Basis::Hsh2, lights), 12 * 9 * 3 * 4 * 20 * 2);
    std::size_t checked = 0;
    for (std::size_t j = 0; j < lights.size(); ++j) {
        std::vector<Eigen::Vector3d> others;
        for (std::size_t i = 0; i < lights.size(); ++i)
            if (i != j) others.push_back(lights[i]);
        const BasisFit without(Basis::Hsh2, others);
        const Eigen::RowVectorXd at_j = basis_values(Basis::Hsh2, lights[j]).transpose() * without.solve();
        double squared = 0.0;
        for (std::size_t k = 0; k < field.images[j].samples().size(); ++k) {
            Eigen::VectorXd y(static_cast<Eigen::Index>(others.size()));
            for (std::size_t i = 0, row = 0; i < lights.size(); ++i)
                if (i != j) y[static_cast<Eigen::Index>(row++)] = field.images[i].samples()[k];
            const double e = static_cast<double>(static_cast<float>(at_j.dot(y))) - field.images[j].samples()[k];
            squared += e * e;
        }
        EXPECT_NEAR(loo.squared_error[j], squared, 1e-5 * squared) << "light " << j;
        ++checked;
    }
    EXPECT_EQ(checked, 20u);
}

TEST(Basis, LightsThatCannotDetermineABasisAreRefused) {
    EXPECT_THAT(error_of([] { BasisFit(Basis::Hsh3, scattered_lights(8, 1)); }),
                HasSubstr("basis hsh3 has 9 functions; the field has 8 lights"));
    // Every light at one elevation: cos(theta) is constant, so the zonal functions coincide.
    std::vector<Eigen::Vector3d> ring;
    for (int i = 0; i < 24; ++i) ring.push_back(direction_from_angles(0.6, 2.0 * kPi * i / 24));
    EXPECT_THAT(error_of([&] { BasisFit(Basis::Hsh3, ring); }), HasSubstr("combination(s) of basis hsh3's functions unseen"));
    EXPECT_NO_THROW(BasisFit(Basis::Hsh3, scattered_lights(9, 2)));
}

}  // namespace
}  // namespace rfd::relight
