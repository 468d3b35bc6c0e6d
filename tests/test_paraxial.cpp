#include <gtest/gtest.h>

#include "optics/lens_file.hpp"
#include "optics/paraxial.hpp"

namespace rfd::optics {
namespace {

// Edmund-style plano-convex N-BK7 lens, curved side first. Closed forms:
// EFL = R / (n - 1), BFL = EFL - t / n.
constexpr const char* kPlanoConvex = R"(
name = "PCX N-BK7"
[[surface]]
radius_mm = 25.8
thickness_mm = 5.3
index = 1.5168
semi_diameter_mm = 12.5
[[surface]]
radius = "flat"
material = "air"
semi_diameter_mm = 12.5
)";

TEST(Paraxial, PlanoConvexCatalogueValues) {
    const auto system = parse_lens_system(kPlanoConvex, "pcx.toml");
    const auto p = cardinal_points(system);
    EXPECT_NEAR(p.efl, 49.9226, 5e-5);
    EXPECT_NEAR(p.bfl, 46.4284, 5e-5);
    EXPECT_NEAR(p.matrix.determinant(), 1.0, 1e-12);
}

}  // namespace
}  // namespace rfd::optics
