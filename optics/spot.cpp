#include "optics/spot.hpp"

#include <cmath>
#include <vector>

#include "core/error.hpp"
#include "core/units.hpp"
#include "optics/paraxial.hpp"

namespace rfd::optics {

Eigen::Vector3d point_at_z(const Ray& ray, double z) {
    return ray.origin + ((z - ray.origin.z()) / ray.direction.z()) * ray.direction;
}

SpotStatistics spot_statistics(const std::vector<Eigen::Vector2d>& points) {
    SpotStatistics spot;
    if (points.empty()) return spot;
    spot.centroid.setZero();
    for (const auto& p : points) spot.centroid += p;
    spot.centroid /= static_cast<double>(points.size());
    double spread = 0.0;
    for (const auto& p : points) spread += (p - spot.centroid).squaredNorm();
    spot.rms_radius = std::sqrt(spread / static_cast<double>(points.size()));
    return spot;
}

SpotReport spot_report(const SequentialSystem& system, double field_angle_deg,
                       double pupil_semi_diameter, int rays) {
    RFD_CHECK(!system.surfaces.empty() && rays > 0);
    SpotReport report;
    report.field_angle_deg = field_angle_deg;
    const CardinalPoints points = cardinal_points(system);
    if (points.afocal)
        throw InputError("system '" + system.name + "' is afocal: it has no focal plane to trace to");
    report.focal_plane_z = points.rear_focal_z;
    const Surface& first = system.surfaces.front();
    if (pupil_semi_diameter <= 0.0) {
        const auto* circle = std::get_if<CircularAperture>(&first.aperture);
        if (!circle) throw InputError("system '" + system.name + "': give --pupil, the first surface has no round aperture");
        pupil_semi_diameter = circle->semi_diameter;
    }
    report.pupil_semi_diameter = pupil_semi_diameter;
    const double theta = degrees_to_radians(field_angle_deg);
    const Eigen::Vector3d direction(0.0, std::sin(theta), std::cos(theta));
    const std::size_t last = system.surfaces.size() - 1;
    const double z0 = first.z;
    // Start one millimetre in front of the first vertex plane, aimed through the pupil point.
    auto ray_through = [&](double px, double py) {
        const Eigen::Vector3d pupil_point(px, py, z0);
        const double back = 1.0 + std::max(0.0, -sag(first.profile, px * px + py * py).value_or(0.0));
        return Ray{pupil_point - (back / direction.z()) * direction, direction};
    };

    const TraceResult chief = trace(system, ray_through(0.0, 0.0));
    report.chief_status = chief.status;
    // A ray that leaves parallel to the focal plane never gets there: no height (not NaN).
    if (chief.status == RayStatus::Ok) {
        const double y = point_at_z(chief.ray, report.focal_plane_z).y();
        if (std::isfinite(y)) report.chief_height_exact = y;
    }
    const ParaxialResult paraxial =
        trace_paraxial(system, {0.0, 0.0, 0.0, std::tan(theta)}, z0, 0, last);
    report.chief_height_paraxial =
        paraxial.ray.y + (report.focal_plane_z - system.surfaces[last].z) * paraxial.ray.ty;

    const int side = std::max(1, static_cast<int>(std::lround(std::sqrt(rays * 4.0 / kPi))));
    std::vector<Eigen::Vector2d> landed;
    for (int iy = 0; iy < side; ++iy) {
        for (int ix = 0; ix < side; ++ix) {
            const double px = side == 1 ? 0.0 : pupil_semi_diameter * (2.0 * ix / (side - 1) - 1.0);
            const double py = side == 1 ? 0.0 : pupil_semi_diameter * (2.0 * iy / (side - 1) - 1.0);
            if (std::hypot(px, py) > pupil_semi_diameter * (1.0 + kApertureTolerance)) continue;
            const TraceResult result = trace(system, ray_through(px, py));
            ++report.rays_traced;
            ++report.status_counts[static_cast<std::size_t>(result.status)];
            if (result.status != RayStatus::Ok) continue;
            const Eigen::Vector2d at = point_at_z(result.ray, report.focal_plane_z).head<2>();
            if (at.allFinite()) landed.push_back(at);
        }
    }
    if (!landed.empty()) {
        const SpotStatistics spot = spot_statistics(landed);
        report.centroid_y = spot.centroid.y();
        report.rms_spot_radius = spot.rms_radius;
    }
    return report;
}

}  // namespace rfd::optics
