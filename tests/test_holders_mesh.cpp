// The mesh checks of holders/mesh_check.hpp on STLs whose answers are known: a cube
// (closed, outward, one piece, volume and box exact), the same with a face missing, turned
// inside out, two cubes apart and two cubes overlapping.

#include <algorithm>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "core/error.hpp"
#include "holders/mesh_check.hpp"
#include "tests/support/temp_dir.hpp"

namespace rfd::holders {
namespace {

using ::testing::Contains;
using ::testing::HasSubstr;

using Triangle = std::array<Eigen::Vector3d, 3>;

// The 12 outward triangles of an axis-aligned box.
std::vector<Triangle> box(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi) {
    auto p = [&](int x, int y, int z) { return Eigen::Vector3d(x ? hi.x() : lo.x(), y ? hi.y() : lo.y(), z ? hi.z() : lo.z()); };
    // Each face as a quad counter-clockwise seen from outside.
    const int quads[6][4][3] = {{{0, 0, 0}, {0, 1, 0}, {1, 1, 0}, {1, 0, 0}}, {{0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}},
                                {{0, 0, 0}, {1, 0, 0}, {1, 0, 1}, {0, 0, 1}}, {{0, 1, 0}, {0, 1, 1}, {1, 1, 1}, {1, 1, 0}},
                                {{0, 0, 0}, {0, 0, 1}, {0, 1, 1}, {0, 1, 0}}, {{1, 0, 0}, {1, 1, 0}, {1, 1, 1}, {1, 0, 1}}};
    std::vector<Triangle> out;
    for (const auto& q : quads) {
        const Eigen::Vector3d a = p(q[0][0], q[0][1], q[0][2]), b = p(q[1][0], q[1][1], q[1][2]),
                              c = p(q[2][0], q[2][1], q[2][2]), d = p(q[3][0], q[3][1], q[3][2]);
        out.push_back({a, b, c});
        out.push_back({a, c, d});
    }
    return out;
}

std::filesystem::path write_stl(const std::filesystem::path& path, const std::vector<Triangle>& triangles) {
    std::ofstream out(path);
    out << "solid test\n";
    for (const Triangle& t : triangles) {
        const Eigen::Vector3d n = (t[1] - t[0]).cross(t[2] - t[0]).normalized();
        out << "facet normal " << n.x() << ' ' << n.y() << ' ' << n.z() << "\n outer loop\n";
        for (const Eigen::Vector3d& v : t) out << "  vertex " << v.x() << ' ' << v.y() << ' ' << v.z() << '\n';
        out << " endloop\nendfacet\n";
    }
    out << "endsolid test\n";
    return path;
}

TEST(MeshCheck, ABoxIsAGoodSolidWithItsVolumeAndBounds) {
    const rfd::testing::TempDir dir;
    const MeshCheck c = check_stl(write_stl(dir.path() / "box.stl", box({1, 2, 3}, {11, 7, 5})));
    EXPECT_TRUE(c.problems().empty()) << c.problems().front();
    EXPECT_EQ(c.vertices, 8u);
    EXPECT_EQ(c.faces, 12u);
    EXPECT_TRUE(c.closed && c.bounds_volume && c.outward && c.manifold);
    EXPECT_EQ(c.components, 1u);
    EXPECT_NEAR(c.volume_mm3, 10.0 * 5.0 * 2.0, 1e-9);
    EXPECT_EQ(c.min_mm, (std::array<double, 3>{1, 2, 3}));
    EXPECT_EQ(c.max_mm, (std::array<double, 3>{11, 7, 5}));
}

TEST(MeshCheck, FlawsAreNamed) {
    const rfd::testing::TempDir dir;
    std::vector<Triangle> open = box({0, 0, 0}, {1, 1, 1});
    open.pop_back();
    open.pop_back();
    EXPECT_THAT(check_stl(write_stl(dir.path() / "open.stl", open)).problems(), Contains(HasSubstr("not closed")));

    std::vector<Triangle> inverted = box({0, 0, 0}, {1, 1, 1});
    for (Triangle& t : inverted) std::swap(t[1], t[2]);
    const MeshCheck inside_out = check_stl(write_stl(dir.path() / "inverted.stl", inverted));
    EXPECT_TRUE(inside_out.closed);
    EXPECT_FALSE(inside_out.outward);
    EXPECT_THAT(inside_out.problems(), Contains(HasSubstr("inside out")));
    EXPECT_NEAR(inside_out.volume_mm3, 1.0, 1e-9);

    std::vector<Triangle> two = box({0, 0, 0}, {1, 1, 1});
    for (const Triangle& t : box({3, 0, 0}, {4, 1, 1})) two.push_back(t);
    const MeshCheck apart = check_stl(write_stl(dir.path() / "two.stl", two));
    EXPECT_EQ(apart.components, 2u);
    EXPECT_THAT(apart.problems(), Contains(HasSubstr("2 separate pieces")));

    std::vector<Triangle> overlapping = box({0, 0, 0}, {1, 1, 1});
    for (const Triangle& t : box({0.5, 0.5, 0.5}, {1.5, 1.5, 1.5})) overlapping.push_back(t);
    EXPECT_THAT(check_stl(write_stl(dir.path() / "overlap.stl", overlapping)).problems(),
                Contains(HasSubstr("intersects itself")));
}

// OpenSCAD writes a part's triangles in an order that changes from run to run; the STL that
// remove_slivers writes back depends only on the surface. The same two boxes written in
// another order, every triangle starting at another corner, give the same bytes.
TEST(RemoveSlivers, TheSameSurfaceInAnotherOrderGivesTheSameFile) {
    const rfd::testing::TempDir dir;
    std::vector<Triangle> first = box({0, 0, 0}, {10, 6, 4});
    const std::vector<Triangle> second_box = box({20, 0, 0}, {23, 2, 5});
    first.insert(first.end(), second_box.begin(), second_box.end());
    std::vector<Triangle> shuffled(first.rbegin(), first.rend());
    for (std::size_t k = 0; k < shuffled.size(); ++k)
        std::rotate(shuffled[k].begin(), shuffled[k].begin() + static_cast<std::ptrdiff_t>(k % 3), shuffled[k].end());
    const auto a = write_stl(dir.path() / "a.stl", first), b = write_stl(dir.path() / "b.stl", shuffled);
    EXPECT_EQ(remove_slivers(a), 0u);
    EXPECT_EQ(remove_slivers(b), 0u);
    const auto bytes = [](const std::filesystem::path& p) {
        std::ifstream in(p, std::ios::binary);
        return std::string(std::istreambuf_iterator<char>(in), {});
    };
    EXPECT_EQ(bytes(a), bytes(b));
    // Still the two boxes, outward: the order changed, not the surface.
    const MeshCheck c = check_stl(b);
    EXPECT_EQ(c.faces, 24u);
    EXPECT_EQ(c.components, 2u);
    EXPECT_TRUE(c.outward);
    EXPECT_NEAR(c.volume_mm3, 10.0 * 6 * 4 + 3.0 * 2 * 5, 1e-9);
}

TEST(MeshCheck, AFileThatIsNoMeshIsAnIoError) {
    const rfd::testing::TempDir dir;
    std::ofstream(dir.path() / "text.stl") << "not a mesh\n";
    EXPECT_THROW(check_stl(dir.path() / "text.stl"), IoError);
    EXPECT_THROW(check_stl(dir.path() / "missing.stl"), IoError);
}

}  // namespace
}  // namespace rfd::holders
