#include "predict/display_lights.hpp"

#include <algorithm>
#include <cmath>
#include <variant>

#include "core/error.hpp"
#include "core/sequence.hpp"
#include "core/sphere.hpp"
#include "core/text.hpp"
#include "core/units.hpp"
#include "optics/analysis.hpp"

namespace rfd::predict {
namespace {

// An environment map as power per pixel (radiance x solid angle, per channel), box-filtered
// `reduction` x `reduction`: pixel (u, v) covers the original columns [u r, (u + 1) r) and
// rows [v r, (v + 1) r), clipped to the map.
struct PowerMap {
    int width = 0, height = 0, reduction = 1;
    int source_width = 0, source_height = 0;
    std::vector<Eigen::Vector3d> power;  // row-major

    Eigen::Vector3d& at(int u, int v) { return power[static_cast<std::size_t>(v) * static_cast<std::size_t>(width) + static_cast<std::size_t>(u)]; }
    const Eigen::Vector3d& at(int u, int v) const {
        return power[static_cast<std::size_t>(v) * static_cast<std::size_t>(width) + static_cast<std::size_t>(u)];
    }
    // The pixel's ranges of theta and phi, radians.
    double theta0(int v) const { return kPi * (v * reduction) / source_height; }
    double theta1(int v) const { return kPi * std::min((v + 1) * reduction, source_height) / source_height; }
    double phi0(int u) const { return -kPi + 2.0 * kPi * (u * reduction) / source_width; }
    double phi1(int u) const { return -kPi + 2.0 * kPi * std::min((u + 1) * reduction, source_width) / source_width; }
    // The finest angle a pixel spans: its phi extent on the equator or its theta extent.
    double pixel_angle() const {
        return std::min(2.0 * kPi * reduction / source_width, kPi * reduction / source_height);
    }
    // A direction inside pixel (u, v), uniform in solid angle: a low-discrepancy point of
    // its cos(theta) x phi rectangle, the sequence indexed by the pixel.
    Eigen::Vector3d direction(int u, int v) const {
        const Eigen::Vector2d s = r2_point(static_cast<std::size_t>(v) * static_cast<std::size_t>(width) + static_cast<std::size_t>(u));
        const double c0 = std::cos(theta0(v)), c1 = std::cos(theta1(v));
        const double cos_theta = c0 + s.y() * (c1 - c0);
        const double phi = phi0(u) + s.x() * (phi1(u) - phi0(u));
        return direction_from_angles(std::acos(std::clamp(cos_theta, -1.0, 1.0)), phi);
    }
};

PowerMap power_of(const Image& radiance) {
    PowerMap map;
    map.width = map.source_width = radiance.width();
    map.height = map.source_height = radiance.height();
    map.power.resize(static_cast<std::size_t>(map.width) * static_cast<std::size_t>(map.height));
    const int channels = radiance.channels();
    for (int v = 0; v < map.height; ++v) {
        const double solid_angle = (2.0 * kPi / map.width) * (std::cos(map.theta0(v)) - std::cos(map.theta1(v)));
        for (int u = 0; u < map.width; ++u)
            for (int c = 0; c < 3; ++c)
                map.at(u, v)[c] = solid_angle * radiance.at(u, v, channels == 1 ? 0 : c);
    }
    return map;
}

PowerMap halve(const PowerMap& fine) {
    PowerMap coarse;
    coarse.source_width = fine.source_width;
    coarse.source_height = fine.source_height;
    coarse.reduction = 2 * fine.reduction;
    coarse.width = (fine.width + 1) / 2;
    coarse.height = (fine.height + 1) / 2;
    coarse.power.assign(static_cast<std::size_t>(coarse.width) * static_cast<std::size_t>(coarse.height),
                        Eigen::Vector3d::Zero());
    for (int v = 0; v < fine.height; ++v)
        for (int u = 0; u < fine.width; ++u) coarse.at(u / 2, v / 2) += fine.at(u, v);
    return coarse;
}

struct Count {
    std::size_t behind = 0, in_front = 0;
};

// Pixels with light, by the side of the display their light meets.
Count count_lit(const PowerMap& map, const FieldToDisplay& to_display) {
    Count count;
    for (int v = 0; v < map.height; ++v)
        for (int u = 0; u < map.width; ++u) {
            if (map.at(u, v).isZero()) continue;
            if (to_display(map.direction(u, v)).z() > 1e-9) ++count.behind;
            else ++count.in_front;
        }
    return count;
}

}  // namespace

optics::DisplayLight display_light(const relight::Light& light, const AngularMapping& mapping) {
    optics::DisplayLight d;
    Eigen::Vector3d colour;
    if (const auto* point = std::get_if<relight::DirectionalLight>(&light)) {
        d.direction = mapping.display_direction(point->direction);
        colour = point->irradiance;
    } else if (const auto* disc = std::get_if<relight::DiskLight>(&light)) {
        d.direction = mapping.display_direction(disc->direction);
        d.angular_radius_rad = disc->radius / mapping.angle_scale;
        colour = disc->irradiance;
    } else {
        throw InputError("an environment map is not a single light: sample it with environment_lights()");
    }
    d.colour = {colour.x(), colour.y(), colour.z()};
    return d;
}

relight::Light light_in_field_frame(const relight::Light& light, LightFrame frame, const AngularMapping& mapping) {
    if (frame == LightFrame::Field) return light;
    // Toward the light in the display's frame -> direction of travel -> the field direction
    // the pattern shows for it.
    const auto to_field = [&](const Eigen::Vector3d& toward) {
        return mapping.field_direction(travel_from(toward).normalized());
    };
    if (const auto* point = std::get_if<relight::DirectionalLight>(&light)) {
        relight::DirectionalLight field = *point;
        field.direction = to_field(point->direction);
        return field;
    }
    if (const auto* disc = std::get_if<relight::DiskLight>(&light)) {
        relight::DiskLight field = *disc;
        field.direction = to_field(disc->direction);
        field.radius = disc->radius * mapping.angle_scale;
        return field;
    }
    throw InputError("an environment map is not a single light: sample it with environment_lights()");
}

std::string LightCheck::warning() const {
    const std::string where = format_fixed(display_theta_deg, 1) + " deg from the display's axis";
    if (from_front) return where + ": the light meets the display from the front, and the display shows nothing of it";
    if (outside_field_of_view())
        return where + ", outside its field of view (wrap-over at " + format_fixed(*wrap_over_deg, 1) +
               " deg along this azimuth): each lenslet shows its neighbour's pattern";
    if (beyond_crosstalk_onset())
        return where + ", beyond the crosstalk onset (" + format_fixed(*crosstalk_deg, 1) +
               " deg along this azimuth): part of the light reaches the diffuser through a neighbouring lenslet";
    return {};
}

LightCheck check_light(const optics::DesignOptics& optics, const optics::DisplayLight& light,
                       const AngularMapping& mapping) {
    const Eigen::Vector3d travel = light.direction.normalized();
    LightCheck check;
    const SphericalAngles display = angles_of(travel_from(travel));
    const SphericalAngles field = angles_of(mapping.field_direction(travel));
    check.display_theta_deg = radians_to_degrees(display.theta);
    check.display_phi_deg = display.theta < 1e-12 ? 0.0 : radians_to_degrees(display.phi);  // no azimuth on the axis
    check.field_theta_deg = radians_to_degrees(field.theta);
    check.field_phi_deg = radians_to_degrees(field.phi);
    check.from_front = travel.z() <= 0.0;
    if (check.from_front) return check;
    const double azimuth = std::atan2(travel.y(), travel.x());  // of the direction of travel
    check.wrap_over_deg = optics::wrap_over_angle(optics, azimuth, optics::Model::Exact);
    check.crosstalk_deg = optics::first_loss_angle(optics, azimuth, 15);
    return check;
}

double display_resolution_rad(const optics::DesignOptics& optics, const AngularMapping& mapping) {
    return mapping.angle_scale * optics.dot_mm().minCoeff() / std::abs(optics.paraxial_b());
}

std::vector<optics::DisplayLight> environment_lights(const Image& radiance, const std::string& name,
                                                     const AngularMapping& mapping, double resolution_rad,
                                                     std::size_t max_directions, EnvironmentSampling* report) {
    return environment_lights(
        radiance, name, [&](const Eigen::Vector3d& field) { return mapping.display_direction(field); }, resolution_rad,
        max_directions, report);
}

std::vector<optics::DisplayLight> environment_lights(const Image& radiance, const std::string& name,
                                                     const FieldToDisplay& to_display, double resolution_rad,
                                                     std::size_t max_directions, EnvironmentSampling* report) {
    if (radiance.empty() || (radiance.channels() != 1 && radiance.channels() != 3))
        throw InputError(SourceLocation{name, 0, 0, ""},
                         "an environment map is a latitude-longitude image with 1 or 3 channels, got " +
                             std::to_string(radiance.channels()) + " channel(s)");
    if (radiance.width() != 2 * radiance.height())
        throw InputError(SourceLocation{name, 0, 0, ""},
                         "a latitude-longitude environment map is twice as wide as high, got " +
                             std::to_string(radiance.width()) + " x " + std::to_string(radiance.height()));
    for (int v = 0; v < radiance.height(); ++v)
        for (int u = 0; u < radiance.width(); ++u)
            for (int c = 0; c < radiance.channels(); ++c) {
                const float s = radiance.at(u, v, c);
                if (std::isfinite(s) && s >= 0.0f) continue;
                throw InputError(SourceLocation{name, 0, 0, ""},
                                 "pixel (" + std::to_string(u) + ", " + std::to_string(v) + ") channel " +
                                     std::to_string(c) + " is " + (std::isnan(s) ? "NaN" : std::to_string(s)) +
                                     ": an environment map holds radiance, finite and not negative");
            }
    RFD_CHECK(max_directions > 0 && resolution_rad >= 0.0);

    PowerMap map = power_of(radiance);
    Count count = count_lit(map, to_display);
    std::string reason;
    while ((map.pixel_angle() < resolution_rad || count.behind > max_directions) && (map.width > 1 || map.height > 1)) {
        reason = map.pixel_angle() < resolution_rad ? "finer than the display resolves" : "more lit directions than the ray budget";
        map = halve(map);
        count = count_lit(map, to_display);
    }

    std::vector<optics::DisplayLight> lights;
    for (int v = 0; v < map.height; ++v)
        for (int u = 0; u < map.width; ++u) {
            const Eigen::Vector3d& power = map.at(u, v);
            if (power.isZero()) continue;
            const Eigen::Vector3d direction = to_display(map.direction(u, v));
            if (!(direction.z() > 1e-9)) continue;
            optics::DisplayLight light;
            light.direction = direction;
            light.colour = {power.x(), power.y(), power.z()};
            lights.push_back(light);
        }
    if (report) {
        report->width = radiance.width();
        report->height = radiance.height();
        report->sampled_width = map.width;
        report->sampled_height = map.height;
        report->reduction = map.reduction;
        report->reason = reason;
        report->directions = lights.size();
        report->in_front = count.in_front;
    }
    return lights;
}

}  // namespace rfd::predict
