// The diffraction model against closed forms: the Airy pattern of a disc (first dark ring at
// 1.22 lambda N), sinc^2 across a rectangle, the presets' lenslet cells, and the blur the
// simulators see a pattern through (it keeps a uniform sheet uniform and conserves light).

#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "core/units.hpp"
#include "optics/diffraction.hpp"
#include "optics/model.hpp"
#include "optics/paraxial.hpp"

#include "tests/support/bundled.hpp"

namespace rfd::optics {
namespace {

using rfd::testing::bundled_design;

TEST(Diffraction, TheAiryPatternIsDarkAtItsFirstRing) {
    // The first zero of J1 is 3.8317, so the ring is at 3.8317 / pi = 1.2197 lambda N.
    const double lambda = 550e-6, n = 4.0;
    EXPECT_NEAR(airy_radius(lambda, n), 1.22 * lambda * n, 1e-15);
    EXPECT_NEAR(airy_psf(3.83171 / kPi * lambda * n, lambda, n), 0.0, 1e-10);
    EXPECT_NEAR(airy_psf(0.0, lambda, n), 1.0, 1e-15);
    // Half power at 0.5145 lambda N (FWHM 1.029 lambda N).
    EXPECT_NEAR(airy_psf(0.51445 * lambda * n, lambda, n), 0.5, 1e-4);
}

TEST(Diffraction, TheFftOfADiscIsItsAiryPattern) {
    const double lambda = 650e-6, focal = 10.0, radius = 1.0;  // N = 5
    const double f_number = focal / (2 * radius);
    const Psf psf = fraunhofer_psf([&](const Eigen::Vector2d& p) { return p.norm() <= radius; }, radius, lambda,
                                   focal, 256, 8, 129);
    const int c = psf.size / 2;
    int checked = 0;
    for (int i = 0; i <= 3 * 8; ++i) {
        const double r = i * psf.step;
        EXPECT_NEAR(psf.at(c + i, c) / psf.at(c, c), airy_psf(r, lambda, f_number), 0.01) << r;
        EXPECT_NEAR(psf.at(c, c + i) / psf.at(c, c), airy_psf(r, lambda, f_number), 0.01) << r;
        ++checked;
    }
    EXPECT_EQ(checked, 25);
    EXPECT_NEAR(psf.lobe_radius_x, airy_radius(lambda, f_number), 0.02 * airy_radius(lambda, f_number));
    EXPECT_NEAR(psf.lobe_radius_y, airy_radius(lambda, f_number), 0.02 * airy_radius(lambda, f_number));
}

TEST(Diffraction, TheFftOfARectangleIsSincSquared) {
    const double lambda = 450e-6, focal = 3.0, a = 2.0, b = 1.0;
    const Psf psf = fraunhofer_psf(
        [&](const Eigen::Vector2d& p) { return std::abs(p.x()) <= a / 2 && std::abs(p.y()) <= b / 2; }, a / 2,
        lambda, focal, 256, 4, 65);
    const int c = psf.size / 2;
    for (int iy = -8; iy <= 8; iy += 2)
        for (int ix = -12; ix <= 12; ix += 3)
            EXPECT_NEAR(psf.at(c + ix, c + iy) / psf.at(c, c),
                        rectangle_psf(ix * psf.step, iy * psf.step, lambda, focal, a, b), 2e-3)
                << ix << ", " << iy;
    EXPECT_NEAR(psf.lobe_radius_x, lambda * focal / a, 0.01 * lambda * focal / a);
    EXPECT_NEAR(psf.lobe_radius_y, lambda * focal / b, 0.01 * lambda * focal / b);
}

TEST(Diffraction, TheRectangularCellsOfDesignIIIGiveLambdaFOverTheirWidth) {
    // The projection lenslets' cells are 4.0 x 4.8 mm: the lobe is widest across 4.0 mm.
    const DesignOptics optics(bundled_design(3));
    const DiffractionEstimate e = estimate_diffraction(optics);
    EXPECT_DOUBLE_EQ(e.aperture_x, 4.0);
    EXPECT_DOUBLE_EQ(e.aperture_y, 4.8);
    for (std::size_t k = 0; k < 3; ++k)
        EXPECT_NEAR(e.lobe_radius_mm[k], kDiffractionWavelengthsMm[k] * e.focal_length / 4.0,
                    0.01 * kDiffractionWavelengthsMm[k] * e.focal_length / 4.0);
    // Two lenslets back to back and one more: shorter than one 10.5 mm lenslet, longer than
    // two back to back.
    EXPECT_GT(e.focal_length, 3.0);
    EXPECT_LT(e.focal_length, 10.5);
}

TEST(Diffraction, DesignIsHexagonalLensletsBlurLessThanAPrintDot) {
    // A hexagon a = 2.36 mm across its flats (at +-x): across x its height tapers from
    // corner to flat, so its lobe along x is wider than a square's of side a (lambda f / a)
    // and narrower than the inscribed disc's (1.22 lambda f / a), which tapers to nothing.
    const DesignOptics optics(bundled_design(1));
    const DiffractionEstimate e = estimate_diffraction(optics);
    const double lambda = kDiffractionWavelengthsMm[2];
    EXPECT_GT(e.lobe_radius_mm[2], lambda * e.focal_length / e.aperture_x);
    EXPECT_LT(e.lobe_radius_mm[2], airy_radius(lambda, e.focal_length / e.aperture_x));
    EXPECT_NEAR(e.focal_length, 3.0, 1e-3);
    EXPECT_LT(e.lobe_dots().maxCoeff(), 0.25);  // far below the 0.25-dot tolerance
}

TEST(Diffraction, TheBlurKeepsAUniformSheetAndConservesLight) {
    const double dot = 0.01;
    const int side = 64;
    std::vector<float> uniform(side * side, 0.5f), spot(side * side, 0.0f);
    spot[(side / 2) * side + side / 2] = 1.0f;
    const RasterTransparency flat(side, side, 1, dot, dot, uniform);
    const RasterTransparency one(side, side, 1, dot, dot, spot);
    const Psf psf = fraunhofer_psf([](const Eigen::Vector2d& p) { return p.norm() <= 0.5; }, 0.5, 650e-6, 20.0);
    const DiffractedTransparency blurred_flat(flat, {psf}), blurred_one(one, {psf});
    std::vector<Eigen::Vector2d> points;
    for (int iy = -40; iy <= 40; ++iy)
        for (int ix = -40; ix <= 40; ++ix) points.emplace_back(ix * 0.001, iy * 0.001);
    std::vector<float> a(points.size()), b(points.size()), c(points.size());
    blurred_flat.sample(points, a);
    blurred_one.sample(points, b);
    one.sample(points, c);
    double sum_blurred = 0, sum_sharp = 0;
    for (std::size_t i = 0; i < points.size(); ++i) {
        EXPECT_NEAR(a[i], 0.5f, 1e-6);
        sum_blurred += b[i];
        sum_sharp += c[i];
    }
    EXPECT_NEAR(sum_blurred, sum_sharp, 0.02 * sum_sharp);
    // Blurred: light outside the dot, less at its centre.
    const std::size_t centre = points.size() / 2;
    EXPECT_LT(b[centre], c[centre]);
    EXPECT_GT(b[centre + 8], 0.0f);
}

}  // namespace
}  // namespace rfd::optics

namespace rfd::optics {
namespace {

TEST(Diffraction, AutoSeesThePatternThroughThePsfOnlyWhereItExceedsTheTolerance) {
    // Design I's central lobe is about 1 um at 650 nm: a tenth of a dot at the Epson's
    // 2880 dpi, about four dots at 100 000 dpi.
    Design design = with_lenslet_count(rfd::testing::bundled_design(1), 5, 5);
    const DesignOptics coarse(design);
    const ResolvedModel at_2880 = resolve(ModelChoice::Auto, coarse, coarse.dot_mm());
    ASSERT_TRUE(at_2880.diffraction_lobe_dots);
    EXPECT_FALSE(at_2880.diffraction);
    EXPECT_LT(*at_2880.diffraction_lobe_dots, 0.25);
    design.printer.dpi_x = Dpi(100000);
    design.printer.dpi_y = Dpi(100000);
    const DesignOptics fine(design);
    const ResolvedModel at_100k = resolve(ModelChoice::Auto, fine, fine.dot_mm());
    EXPECT_TRUE(at_100k.diffraction);
    EXPECT_NEAR(*at_100k.diffraction_lobe_dots, estimate_diffraction(fine).lobe_dots().maxCoeff(), 1e-9);
    EXPECT_NE(at_100k.reason.find("diffraction"), std::string::npos);
    // Asked for, it is used whatever its size; paraxial and exact never use it.
    EXPECT_TRUE(resolve(ModelChoice::Diffraction, coarse, coarse.dot_mm()).diffraction);
    EXPECT_EQ(resolve(ModelChoice::Diffraction, coarse, coarse.dot_mm()).model, Model::Exact);
    EXPECT_FALSE(resolve(ModelChoice::Exact, fine, fine.dot_mm()).diffraction);
}

}  // namespace
}  // namespace rfd::optics
