#include "predict/compare_angular.hpp"

#include <algorithm>
#include <cmath>

#include "core/error.hpp"
#include "core/units.hpp"
#include "patterns/angular.hpp"

namespace rfd::predict {
namespace {

// Positions in [-reach, reach] on a side x side grid, or the midpoints between them.
std::vector<double> grid_positions(int side, bool midpoints, double reach) {
    RFD_CHECK(side >= 2);
    std::vector<double> t;
    const int count = midpoints ? side - 1 : side;
    for (int i = 0; i < count; ++i) t.push_back(reach * (-1.0 + 2.0 * (i + (midpoints ? 0.5 : 0.0)) / (side - 1)));
    return t;
}

double angle_deg(const Eigen::Vector3d& d) { return radians_to_degrees(std::acos(std::clamp(d.normalized().z(), -1.0, 1.0))); }

}  // namespace

std::vector<Eigen::Vector3d> angular_light_grid(const optics::AngularDisplaySimulator& simulator, int side,
                                                bool midpoints) {
    const Eigen::Vector2d half = simulator.meso().lattice().half_extent();
    const double b = simulator.optics().paraxial_b();
    std::vector<Eigen::Vector3d> lights;
    const std::vector<double> t = grid_positions(side, midpoints, 0.9);
    for (double ty : t)
        for (double tx : t) lights.push_back(Eigen::Vector3d(tx * half.x() / b, ty * half.y() / b, 1.0).normalized());
    return lights;
}

std::vector<Eigen::Vector3d> angular_view_grid(const optics::AngularDisplaySimulator& simulator, int side,
                                               bool midpoints) {
    const optics::Lattice& lattice = simulator.meso().lattice();
    const double gain = std::abs(simulator.meso().output_gain());
    std::vector<Eigen::Vector3d> views;
    const std::vector<double> t = grid_positions(side, midpoints, 0.7);
    for (double ty : t)
        for (double tx : t)
            views.push_back(
                Eigen::Vector3d(gain * tx * 0.5 * lattice.pitch_x(), gain * ty * 0.5 * lattice.pitch_y(), 1.0).normalized());
    return views;
}

AngularComparison::AngularComparison(const optics::AngularDisplaySimulator& simulator,
                                     const optics::Transparency& printed, const patterns::AngularField& field,
                                     std::vector<Eigen::Vector3d> lights, const print::ToneMap& tone,
                                     const optics::AngularSimulationOptions& options)
    : simulator_(simulator), printed_(printed), lights_(std::move(lights)), tone_(tone), options_(options) {
    std::vector<patterns::LightBin> bins;
    for (const Eigen::Vector3d& d : lights_) bins.push_back({patterns::field_light_of(d)});
    lookup_ = field.bind(bins, simulator.macro_x(), simulator.macro_y());
    channels_ = field.channels();
    // The display's own bins, sampled as the encoder samples them (3 x 3 per meso cell).
    const optics::Lattice& lattice = simulator.meso().lattice();
    std::vector<patterns::LightBin> meso_bins;
    for (int j = 0; j < lattice.count_y(); ++j)
        for (int i = 0; i < lattice.count_x(); ++i) {
            patterns::LightBin bin;
            for (const Eigen::Vector3d& d : simulator.meso().bin({i, j}, options.model, 3).samples)
                bin.push_back(patterns::field_light_of(d));
            meso_bins.push_back(std::move(bin));
        }
    bin_lookup_ = field.bind(meso_bins, simulator.macro_x(), simulator.macro_y());
    lattice_cells_ = meso_bins.size();
    // A light's bin: the meso cell its chief ray (through the main lens's centre) lands in.
    for (const Eigen::Vector3d& d : lights_) {
        const optics::DesignOptics::Landing landing =
            simulator.optics().land(d, simulator.optics().centre_cell(), options.model);
        const optics::CellIndex cell = landing.cell;
        bin_of_.push_back(landing.status == optics::RayStatus::Ok && lattice.contains(cell) ? lattice.linear_index(cell)
                                                                                           : meso_bins.size());
    }
}

AngularComparison::~AngularComparison() = default;

std::vector<PairComparison> AngularComparison::compare(std::size_t light,
                                                       const std::vector<Eigen::Vector3d>& views) const {
    RFD_CHECK(light < lights_.size());
    optics::AngularSimulationOptions options = options_;
    options.views.clear();
    for (const Eigen::Vector3d& o : views) options.views.push_back(optics::Viewpoint{o, std::nullopt});
    options.distributions.clear();
    const std::vector<optics::DisplayLight> lit{optics::DisplayLight{lights_[light], {1.0, 1.0, 1.0}, 0.0}};
    const optics::AngularDisplayOutput shown = simulator_.simulate(printed_, lit, options);
    const optics::ClearTransparency clear;
    const optics::AngularDisplayOutput flat = simulator_.simulate(clear, lit, options);

    std::vector<PairComparison> out;
    std::vector<float> value(static_cast<std::size_t>(channels_)), bin_value(static_cast<std::size_t>(channels_));
    for (std::size_t k = 0; k < views.size(); ++k) {
        PairComparison pair;
        pair.light = lights_[light];
        pair.view = views[k];
        pair.light_angle_deg = angle_deg(pair.light);
        pair.view_angle_deg = angle_deg(pair.view);
        pair.prediction = simulator_.per_macro_pixel(shown.views[k]);
        pair.flat = simulator_.per_macro_pixel(flat.views[k]);
        pair.reference = Image(pair.flat.width(), pair.flat.height(), pair.flat.channels());
        pair.ceiling = Image(pair.flat.width(), pair.flat.height(), pair.flat.channels());
        const bool binned = bin_of_[light] < lattice_cells_;
        for (int v = 0; v < simulator_.macro_y(); ++v)
            for (int u = 0; u < simulator_.macro_x(); ++u) {
                const int row = simulator_.macro_y() - 1 - v;
                lookup_->value(light, views[k], u, v, value);
                if (binned) bin_lookup_->value(bin_of_[light], views[k], u, v, bin_value);
                for (int c = 0; c < pair.reference.channels(); ++c) {
                    const auto channel = static_cast<std::size_t>(channels_ == 1 ? 0 : c);
                    const double w = pair.flat.at(u, row, c);
                    pair.reference.at(u, row, c) = static_cast<float>(w * tone_.stack_transmittance(value[channel]));
                    pair.ceiling.at(u, row, c) =
                        binned ? static_cast<float>(w * tone_.stack_transmittance(bin_value[channel])) : 0.0f;
                }
            }
        pair.comparison = compare_images(pair.prediction, pair.reference);
        pair.ceiling_comparison = compare_images(pair.ceiling, pair.reference);
        pair.crossed_fraction = shown.crossed_fraction;
        out.push_back(std::move(pair));
    }
    return out;
}

}  // namespace rfd::predict
