#include "predict/preview.hpp"

#include <algorithm>
#include <cmath>

#include "core/progress.hpp"
#include "core/sphere.hpp"
#include "core/units.hpp"
#include "predict/display_lights.hpp"
#include "predict/rti_export.hpp"
#include "relight/interpolation.hpp"
#include "relight/render.hpp"

namespace rfd::predict {

PreviewSet preview_set(const optics::DisplaySimulator& simulator, const DisplayComparison& comparison,
                       const patterns::AngularMapping& mapping, std::size_t count, double max_angle_rad,
                       const optics::SimulationOptions& options, const DisplayComparison* direct) {
    PreviewSet set;
    set.max_angle_deg = radians_to_degrees(max_angle_rad);
    set.directions = cone_directions(count, max_angle_rad, 1);
    {
        Progress progress("predicting the preview's lights", set.directions.size());
        for (const Eigen::Vector3d& toward : set.directions) {
            const Eigen::Vector3d field_direction = mapping.field_direction(travel_from(toward));
            const DirectionComparison r = comparison.compare(field_direction, options);
            set.predicted.push_back(r.cell_prediction);
            set.relit.push_back(r.cell_reference);
            if (direct) set.predicted_direct.push_back(direct->compare(field_direction, options).cell_prediction);
            progress.advance();
        }
    }
    float peak = 0.0f;
    for (const Image& image : set.relit)
        for (float v : image.samples()) peak = std::max(peak, v);
    set.scale = peak > 0.0f ? 1.0 / peak : 1.0;
    for (std::size_t k = 0; k < set.directions.size(); ++k) {
        set.predicted[k] = set.predicted[k].exposed(std::log2(set.scale));
        set.relit[k] = set.relit[k].exposed(std::log2(set.scale));
        if (direct) set.predicted_direct[k] = set.predicted_direct[k].exposed(std::log2(set.scale));
    }

    const relight::SphericalInterpolator interpolator(set.directions);
    for (std::size_t t = 0; t < interpolator.triangles().size(); ++t) {
        const auto& triangle = interpolator.triangles()[t];
        set.triangles.push_back({triangle[0], triangle[1], triangle[2]});
        set.edge_planes.push_back(interpolator.edge_planes(t));
    }

    for (int k = 0; k < 24; ++k) {
        const double phi = 15.0 * k;
        const Eigen::Vector3d toward = direction_from_angles(degrees_to_radians(1.0), degrees_to_radians(phi));
        const relight::DirectionalLight light{mapping.field_direction(travel_from(toward)), Eigen::Vector3d::Ones()};
        const LightCheck check = check_light(simulator.optics(), display_light(light, mapping), mapping);
        set.rims.push_back({phi, check.wrap_over_deg, check.crosstalk_deg});
    }
    return set;
}

}  // namespace rfd::predict
