#pragma once
// The interpolation triangulation computed independently of relight/interpolation.cpp: the
// convex hull (CGAL's convex_hull_3, not Delaunay_triangulation_3) of the directions plus a
// guardian point at the theta = pi pole, minus the facets touching the guardian (thesis 4.4).
// Compiled apart (hull_triangles.cpp): CGAL's headers are the slowest the tests include.

#include <vector>

#include <Eigen/Core>

#include "relight/adaptive.hpp"

namespace rfd::testing {

std::vector<relight::Triangle> hull_triangles(const std::vector<Eigen::Vector3d>& directions);

}  // namespace rfd::testing
