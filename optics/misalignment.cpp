#include "optics/misalignment.hpp"

#include <cmath>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "core/error.hpp"

namespace rfd::optics {

MisalignedTransparency::MisalignedTransparency(const Transparency& pattern, const Mounting& mounting)
    : pattern_(pattern), mounting_(mounting) {
    RFD_CHECK(std::isfinite(mounting.shift_mm.x()) && std::isfinite(mounting.shift_mm.y()) &&
              std::isfinite(mounting.rotation_rad) && std::isfinite(mounting.pitch_error) &&
              mounting.pitch_error > -1.0);
    inverse_ = Eigen::Rotation2Dd(-mounting.rotation_rad).toRotationMatrix() / (1.0 + mounting.pitch_error);
}

Eigen::Vector2d MisalignedTransparency::to_pattern(const Eigen::Vector2d& point) const {
    return inverse_ * (point - mounting_.shift_mm);
}

void MisalignedTransparency::sample(std::span<const Eigen::Vector2d> points, std::span<float> out) const {
    std::vector<Eigen::Vector2d> moved(points.size());
    for (std::size_t k = 0; k < points.size(); ++k) moved[k] = to_pattern(points[k]);
    pattern_.sample(moved, out);
}

double pattern_to_diffuser_mm(const Design& design) {
    const Plane* diffuser = design.diffuser_plane();
    if (!diffuser)
        throw InputError(SourceLocation{design.file, 0, 0, "planes"}, "the design has no diffuser plane");
    return diffuser->z - design.pattern_plane().z;
}

Design with_spacer_error(const Design& design, double delta_mm) {
    RFD_CHECK(std::isfinite(delta_mm));
    Design changed = design;
    const double pattern_z = design.pattern_plane().z;
    for (Plane& plane : changed.planes) {
        if (plane.pattern && plane.part)
            if (auto* sheet = std::get_if<SheetPart>(&*plane.part)) {
                sheet->thickness += delta_mm;
                if (!(sheet->thickness > 0.0))
                    throw InputError(SourceLocation{design.file, plane.where.line, 0, "planes." + plane.name},
                                     "a spacer error of " + std::to_string(delta_mm) + " mm leaves the " +
                                         plane.part_name + " sheet without thickness");
            }
        if (plane.z > pattern_z) plane.z += delta_mm;
    }
    // The planes were checked in order when the design was read; check again after the move.
    for (std::size_t k = 1; k < changed.planes.size(); ++k) {
        const Plane& a = changed.planes[k - 1];
        const Plane& b = changed.planes[k];
        if (axial_extent(a)[1] - axial_extent(b)[0] > 1e-6 || b.z <= a.z)
            throw InputError(SourceLocation{design.file, b.where.line, 0, "planes." + b.name + ".z_mm"},
                             "a spacer error of " + std::to_string(delta_mm) + " mm makes plane " + b.name +
                                 " overlap plane " + a.name);
    }
    return changed;
}

}  // namespace rfd::optics
