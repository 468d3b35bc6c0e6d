#pragma once
// The exact model: real surfaces, Snell's law, apertures, total internal reflection and
// lenslet cells, ray by ray. Numerical code: outcomes are statuses, never exceptions.

#include <cstdint>
#include <span>
#include <string_view>
#include <vector>

#include <Eigen/Core>

#include "optics/system.hpp"

namespace rfd::optics {

/// What happened to a ray. Anything but Ok stops the ray at the surface named in the result.
enum class RayStatus : std::uint8_t {
    Ok,                      ///< reached the last requested surface
    Missed,                  ///< no intersection with the surface's vertex branch
    TotalInternalReflection, ///< no refracted ray exists at that surface
    Vignetted,               ///< hit the surface outside its clear aperture or array
    CrossedCell,             ///< left the lenslet it entered: wrap-over into a neighbour
};
inline constexpr int kRayStatusCount = 5;
std::string_view to_string(RayStatus status);

/// A ray in the system frame: origin in mm and a unit direction.
struct Ray {
    Eigen::Vector3d origin = Eigen::Vector3d::Zero();
    Eigen::Vector3d direction = Eigen::Vector3d::UnitZ();
};

struct TraceResult {
    Ray ray;                        ///< at the last surface reached (after refraction there)
    RayStatus status = RayStatus::Ok;
    int surface = -1;               ///< surface where the ray stopped (or the last one)
    CellIndex cell{};               ///< lenslet entered at the first arrayed surface
    bool has_cell = false;          ///< false until the ray meets an arrayed surface
    /// Fraction of the ray's power left after the Fresnel reflections at every refracting
    /// surface it crossed (unpolarised light, no absorption, no coatings).
    double transmittance = 1.0;
};

/// Traces one ray through surfaces [first, last] (inclusive) of the system.
/// Rays start in front of `first` (or on it); a surface touching the one before it is
/// crossed where they touch.
TraceResult trace(const SequentialSystem& system, const Ray& ray, std::size_t first,
                  std::size_t last);
/// Traces through the whole system.
TraceResult trace(const SequentialSystem& system, const Ray& ray);

/// Rays in structure-of-arrays form for batch tracing.
struct RayBatch {
    std::vector<double> x, y, z;     ///< origins, mm
    std::vector<double> dx, dy, dz;  ///< unit directions
    std::vector<RayStatus> status;
    std::vector<std::int32_t> stop_surface;
    std::vector<std::int32_t> cell_i, cell_j;

    std::size_t size() const { return x.size(); }
    void resize(std::size_t n);
    void set(std::size_t k, const Ray& ray);
    Ray get(std::size_t k) const;
};

/// Traces every ray of `batch` in place through surfaces [first, last], in parallel over
/// rays. Each ray's outcome is the same as trace() would give for it alone.
void trace_batch(const SequentialSystem& system, RayBatch& batch, std::size_t first,
                 std::size_t last);

/// Per-status counts.
std::array<std::size_t, kRayStatusCount> count_statuses(const RayBatch& batch);

}  // namespace rfd::optics
