#include "predict/rti_export.hpp"

#include <cmath>

#include "core/error.hpp"
#include "core/progress.hpp"
#include "core/sphere.hpp"
#include "core/text.hpp"
#include "core/units.hpp"
#include "predict/display_lights.hpp"
#include "relight/sampling.hpp"

namespace rfd::predict {

std::vector<Eigen::Vector3d> cone_directions(std::size_t count, double half_angle_rad, std::uint64_t seed) {
    if (count == 0) return {};
    if (!(half_angle_rad > 0.0 && half_angle_rad < kPi / 2))
        throw InputError("the cone's half angle must be in (0, 90) degrees, got " +
                         std::to_string(radians_to_degrees(half_angle_rad)));
    std::vector<Eigen::Vector3d> directions = relight::repulsion_pattern(count, seed);
    for (Eigen::Vector3d& d : directions) {
        const SphericalAngles a = angles_of(d);
        d = direction_from_angles(a.theta * half_angle_rad / (kPi / 2), a.phi);
    }
    return directions;
}

relight::ReflectanceField predicted_field(const optics::DisplaySimulator& simulator, const optics::Transparency& pattern,
                                          const std::vector<Eigen::Vector3d>& toward_lights,
                                          const optics::SimulationOptions& options, bool per_lenslet) {
    relight::ReflectanceField field;
    Progress progress("predicting the display's pictures", toward_lights.size());
    for (const Eigen::Vector3d& toward : toward_lights) {
        const Eigen::Vector3d unit = toward.normalized();
        if (!(unit.z() > 0.0))
            throw InputError("a light of the display's frame must shine from behind it (z > 0), got " +
                             format_direction(unit));
        const optics::DisplayLight light{travel_from(unit), {1.0, 1.0, 1.0}};
        const optics::DiffuserImage shown = simulator.simulate(pattern, {light}, options);
        field.images.push_back(per_lenslet ? simulator.per_lenslet(shown) : shown.image);
        field.directions.push_back(unit);
        progress.advance();
    }
    progress.finish();
    return field;
}

}  // namespace rfd::predict
