#pragma once
// Adaptive sampling of a reflectance field (thesis 5.3) and two-level fields (5.4).
//
// Each iteration analyses the images taken so far and proposes m new light directions:
//  1. the one-ring N_i of every direction in the interpolation triangulation (4.4);
//  2. the local error of direction i: the squared residual of projecting R_i onto the span
//     of its neighbours' images, min_mu || R_i - sum_k mu_k R_k ||^2 (eq. 5.2). It is low
//     when R_i resembles some neighbour (one-sided discontinuities such as a shadow edge do
//     not trigger endless subdivision) and high when R_i differs from all of them (a moving
//     highlight). Computed from dot products: ||R_i||^2 - b^T G^+ b with G_kl = <R_k, R_l>
//     and b_k = <R_k, R_i>, G^+ from G's eigen-decomposition (its SVD, G being symmetric);
//     the dot products are cached across iterations, so an iteration only computes those
//     of the new images;
//  3. the error of a triangle: the sum of its corners' errors;
//  4. new directions at the circumcentres of the worst triangles, skipping triangles whose
//     circumradius is under the density limit (2 degrees in the thesis), circumcentres
//     below the horizon, and any closer than the limit to an existing or newly chosen
//     direction (the next worst triangle is taken instead).
//     Beyond the thesis: the band between the triangulation and the horizon (interpolated
//     along arcs, 4.4) holds no triangles, so as written the method can never sample it,
//     although grazing light is where shadows are longest. Each boundary edge (a, b) of the
//     triangulation therefore also ranks as a horizon triangle (a, b, h), h the horizon
//     point below the edge's midpoint, with error e_a + e_b + (e_a + e_b) / 2 (h taking its
//     neighbours' mean); its new direction is the triangle's centroid, which lies above the
//     horizon. InsertionOptions::horizon_band turns this off.
// Two-level fields: directions of the initial set whose one-ring neighbours are all farther
// than a threshold (9 degrees in the thesis) are re-captured with a wide kernel, scaled to
// the narrow image's mean, and replace it.
//
// Directions are unit vectors in the field frame (core/sphere.hpp); angles are radians.
//
// Example: ProjectionErrors errors; auto e = errors.update(field.images, one_rings(n, tris));

#include <array>
#include <functional>
#include <cstddef>
#include <map>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "core/image.hpp"
#include "relight/capture_device.hpp"
#include "relight/field.hpp"

namespace rfd::relight {

using Triangle = std::array<std::size_t, 3>;

/// The same triangles in an order that depends only on the triangles themselves: each
/// rotated (orientation kept) so that its smallest index comes first, then sorted.
/// Triangulators may list faces in an order that depends on hidden state (CGAL's
/// randomised point location); ranking and ties must not.
std::vector<Triangle> canonical_order(std::vector<Triangle> triangles);

/// The one-ring of every vertex: the vertices it shares a triangle edge with, ascending.
std::vector<std::vector<std::size_t>> one_rings(std::size_t vertex_count,
                                                const std::vector<Triangle>& triangles);

/// <a, b> over every sample of two images of the same shape, accumulated in double in a
/// fixed order (deterministic).
double image_dot(const Image& a, const Image& b);

/// Local projection errors (eq. 5.2) with the image dot products kept between calls.
/// Images are identified by their index; an index must keep referring to the same image.
class ProjectionErrors {
public:
    /// Error of every image against the span of its one-ring's images. Computes (in
    /// parallel) only the dot products not seen before.
    std::vector<double> update(const std::vector<Image>& images,
                               const std::vector<std::vector<std::size_t>>& rings);
    std::size_t cached_products() const { return dots_.size(); }

private:
    double dot(std::size_t a, std::size_t b) const;
    std::map<std::pair<std::size_t, std::size_t>, double> dots_;
};

/// Residual of projecting a vector with squared norm `self` onto the span of vectors with
/// Gram matrix `gram` and cross products `cross`; >= 0.
double projection_residual(double self, const Eigen::MatrixXd& gram, const Eigen::VectorXd& cross);

/// Circumcentre of a spherical triangle (unit vertices) on the unit sphere, on the side of
/// the triangle itself; returns false for a degenerate (collinear) triangle.
bool spherical_circumcentre(const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                            const Eigen::Vector3d& c, Eigen::Vector3d& centre);

struct InsertionOptions {
    std::size_t count = 16;                            ///< m, directions per iteration
    double min_separation = 0.034906585039886591;      ///< 2 degrees, radians
    bool horizon_band = true;                          ///< also rank horizon triangles
};

/// What the insertion step decided, for reports and tests.
struct Insertion {
    std::vector<Eigen::Vector3d> directions;   ///< new directions, worst triangle first
    std::vector<std::size_t> from_triangle;    ///< index of the triangle each came from;
                                               ///< triangles.size() + k: the k-th boundary edge
                                               ///< of boundary_edges(triangles)
    std::size_t skipped_small = 0;             ///< triangles under the density limit
    std::size_t skipped_close = 0;             ///< circumcentres too close to a direction
    std::size_t skipped_below_horizon = 0;
};

/// Edges of exactly one triangle (the triangulation's rim), as (a, b) in the triangle's
/// orientation, in the triangles' order.
std::vector<std::array<std::size_t, 2>> boundary_edges(const std::vector<Triangle>& triangles);

/// Step 3 and 4 above. Triangles are ranked by summed corner error, ties by index.
Insertion choose_new_directions(const std::vector<Eigen::Vector3d>& directions,
                                const std::vector<Triangle>& triangles,
                                const std::vector<double>& vertex_errors,
                                const InsertionOptions& options);

/// Two-level selection (5.4): indices among `candidates` whose one-ring neighbours are all
/// farther than `threshold` (radians) away.
std::vector<std::size_t> sparse_directions(const std::vector<Eigen::Vector3d>& directions,
                                           const std::vector<std::vector<std::size_t>>& rings,
                                           const std::vector<std::size_t>& candidates,
                                           double threshold);

/// `wide` scaled so that its mean over all samples equals `narrow`'s (5.4). A black wide
/// image stays black.
Image matched_to_mean(const Image& wide, const Image& narrow);

/// The interpolation triangulation of a direction set (hull triangles of the upper
/// hemisphere, thesis 4.4), supplied by the caller so this file does not depend on how it
/// is computed.
using Triangulate = std::function<std::vector<Triangle>(const std::vector<Eigen::Vector3d>&)>;

struct AdaptiveOptions {
    std::size_t per_iteration = 16;  ///< m
    std::size_t total = 1024;        ///< stop at this many images
    double min_separation = 0.034906585039886591;  ///< density limit, radians (2 degrees)
    bool horizon_band = true;                      ///< see InsertionOptions
};

/// The state after an iteration, for progress reports, error-versus-count charts and tests.
struct AdaptiveRun {
    ReflectanceField field;                  ///< all images so far, initial set first
    std::vector<std::size_t> iteration;      ///< per image: 0 for the initial set, then 1, 2...
    std::vector<std::size_t> images_after;   ///< image count after each iteration (0 = initial)
    std::vector<double> analysis_seconds;    ///< analysis + insertion time per iteration
    bool density_limit_reached = false;      ///< stopped because nothing could be inserted
};

/// Adaptive capture (5.3): captures `initial` with the device's narrow light, then iterates
/// analysis and insertion until `options.total` images or the density limit. Calls
/// `after_iteration` (may be empty) after the initial capture and every iteration.
AdaptiveRun adaptive_capture(CaptureDevice& device, const std::vector<Eigen::Vector3d>& initial,
                             const Triangulate& triangulate, const AdaptiveOptions& options,
                             const std::function<void(const AdaptiveRun&)>& after_iteration = {});

/// Two-level field (5.4): for the first `initial_count` directions of `field` whose one-ring
/// neighbours (in the triangulation of all its directions) are all farther than
/// `threshold`, captures a wide-kernel image, scales it to the narrow image's mean and
/// replaces the narrow image; records the wide kernel radius. Returns the replaced indices.
std::vector<std::size_t> make_two_level(ReflectanceField& field, std::size_t initial_count,
                                        CaptureDevice& device, const Triangulate& triangulate,
                                        double threshold);

}  // namespace rfd::relight
