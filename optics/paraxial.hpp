#pragma once
// The paraxial model: ray-transfer (ABCD) matrices on (height y in mm, slope u = tan of the
// angle to the axis), valid for rays close to the axis at small angles.
//
// Angles are not reduced: in a medium of index n a ray keeps its real slope, so a system
// between media n_in and n_out has det M = n_in / n_out. Refraction at a surface of
// curvature c from n1 to n2:   y' = y,   u' = (n1 u - (n2 - n1) c y) / n2.
// Transfer over a distance d:  y' = y + d u,   u' = u.
// A lenslet whose axis sits at height h (an element of an array) is exact in its own frame:
// its augmented (affine) matrix is  y' = A y + B u + h (1 - A),  u' = C y + D u - C h.
// Rotational symmetry makes x and y independent: both use the same matrices.

#include <array>
#include <cstdint>
#include <vector>

#include "optics/exact.hpp"
#include "optics/system.hpp"

namespace rfd::optics {

/// A 2x2 ray-transfer matrix acting on (y, u).
struct RayMatrix {
    double a = 1.0, b = 0.0, c = 0.0, d = 1.0;

    double determinant() const { return a * d - b * c; }
    /// Applies the matrix: returns (y', u').
    std::array<double, 2> apply(double y, double u) const {
        return {a * y + b * u, c * y + d * u};
    }
};
/// `later * earlier`: first earlier, then later.
RayMatrix operator*(const RayMatrix& later, const RayMatrix& earlier);

RayMatrix translation(double distance);
RayMatrix refraction(double curvature, double n_before, double n_after);

/// A ray-transfer matrix plus a constant term: the matrix of an element decentred from the
/// axis, in 3x3 augmented form [[a b e] [c d f] [0 0 1]] on (y, u, 1).
struct AffineRayMatrix {
    RayMatrix m;
    double e = 0.0;  ///< added to y
    double f = 0.0;  ///< added to u

    std::array<double, 2> apply(double y, double u) const {
        return {m.a * y + m.b * u + e, m.c * y + m.d * u + f};
    }
};
/// The matrix of a centred element moved so that its axis lies at height `offset`.
AffineRayMatrix decentred(const RayMatrix& centred, double offset);
AffineRayMatrix operator*(const AffineRayMatrix& later, const AffineRayMatrix& earlier);

/// Matrix from the vertex of surface `first` (just in front of it) to the vertex of
/// surface `last` (just behind it); arrayed surfaces are taken on their lenslet's own axis.
RayMatrix vertex_matrix(const SequentialSystem& system, std::size_t first, std::size_t last);

/// Gaussian properties of surfaces [first, last]. Positions are absolute z in mm.
struct CardinalPoints {
    RayMatrix matrix;           ///< vertex-to-vertex
    double n_in = 1.0, n_out = 1.0;
    bool afocal = false;        ///< C == 0: no finite focal points; the fields below are NaN
    double power = 0.0;         ///< optical power in 1/mm (dioptres / 1000)
    double efl = 0.0;           ///< effective focal length 1/power
    double rear_focal_length = 0.0;   ///< n_out / power, from the rear principal plane
    double front_focal_length = 0.0;  ///< n_in / power, from the front principal plane
    double bfl = 0.0;           ///< back focal length: last vertex to rear focal point
    double ffl = 0.0;           ///< front focal length: front focal point to first vertex
    double first_vertex_z = 0.0, last_vertex_z = 0.0;
    double front_focal_z = 0.0, rear_focal_z = 0.0;
    double front_principal_z = 0.0, rear_principal_z = 0.0;
};
CardinalPoints cardinal_points(const SequentialSystem& system, std::size_t first,
                               std::size_t last);
CardinalPoints cardinal_points(const SequentialSystem& system);

/// Conjugate of an object `object_distance` mm in front of the first vertex (positive in
/// front): image distance behind the last vertex (negative: virtual image in front) and
/// lateral magnification. nullopt for an object imaged to infinity.
struct Conjugate {
    double image_distance = 0.0;
    double magnification = 0.0;
};
std::optional<Conjugate> conjugate(const CardinalPoints& points, double object_distance);

/// A paraxial ray at a transverse plane: heights (mm) and slopes (tan) in x and y.
struct ParaxialRay {
    double x = 0.0, y = 0.0, tx = 0.0, ty = 0.0;
};

struct ParaxialResult {
    ParaxialRay ray;  ///< at the vertex plane of the last surface reached (after refraction)
    RayStatus status = RayStatus::Ok;
    int surface = -1;
    CellIndex cell{};
    bool has_cell = false;
};

/// Traces a paraxial ray given at plane z = `z_start` through surfaces [first, last],
/// surface by surface with each lenslet's augmented matrix. Apertures are tested at the
/// vertex planes; a lenslet is entered at the first arrayed surface and leaving it later
/// is CrossedCell. Missed and TotalInternalReflection never occur in this model.
ParaxialResult trace_paraxial(const SequentialSystem& system, const ParaxialRay& ray,
                              double z_start, std::size_t first, std::size_t last);

/// Paraxial rays in structure-of-arrays form.
struct ParaxialBatch {
    std::vector<double> x, y, tx, ty;
    std::vector<RayStatus> status;
    std::vector<std::int32_t> cell_i, cell_j;
    std::size_t size() const { return x.size(); }
    void resize(std::size_t n);
};
/// trace_paraxial() for every ray of the batch, in place, in parallel over rays.
void trace_paraxial_batch(const SequentialSystem& system, ParaxialBatch& batch, double z_start,
                          std::size_t first, std::size_t last);

/// Slope form of a direction (dx/dz, dy/dz); requires d.z() > 0.
inline ParaxialRay paraxial_from(const Ray& ray) {
    return {ray.origin.x(), ray.origin.y(), ray.direction.x() / ray.direction.z(),
            ray.direction.y() / ray.direction.z()};
}

}  // namespace rfd::optics
