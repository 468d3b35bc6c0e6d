#include "patterns/encode.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iterator>
#include <limits>
#include <map>

#include "core/error.hpp"
#include "core/image_io.hpp"
#include "core/parallel.hpp"
#include "core/sphere.hpp"
#include "core/text.hpp"

namespace rfd::patterns {
namespace {

using optics::CellIndex;
using optics::LatticeKind;

// Offsets probed per cell to find the display's range: azimuths around the cell and
// fractions of the way from the centre to the boundary.

const optics::Plane& check_design(const optics::Design& design) {
    if (design.kind != optics::DesignKind::I && design.kind != optics::DesignKind::II)
        throw InputError(SourceLocation{design.file, 0, 0, "design.kind"},
                         "this encoder handles Designs I and II (spatial macro-pixels); Design " +
                             std::string(optics::to_string(design.kind)) +
                             " needs the angular encoder");
    return design.pattern_plane();
}

// Incident directions from the paraxial map; the exact model refines them with a table.
Eigen::Vector3d from_slopes(const Eigen::Vector2d& slopes) {
    return Eigen::Vector3d(slopes.x(), slopes.y(), 1.0).normalized();
}

}  // namespace

Eigen::Matrix3d AngularMapping::rotation() const {
    return (Eigen::AngleAxisd(degrees_to_radians(turn_deg), Eigen::Vector3d::UnitZ()) *
            Eigen::AngleAxisd(-degrees_to_radians(tilt_deg), Eigen::Vector3d::UnitX()))
        .toRotationMatrix();
}

Eigen::Vector3d AngularMapping::field_direction(const Eigen::Vector3d& incident) const {
    return field_direction(incident, rotation());
}

Eigen::Vector3d AngularMapping::field_direction(const Eigen::Vector3d& incident, const Eigen::Matrix3d& rotation) const {
    Eigen::Vector3d v(-incident.x(), -incident.y(), incident.z());
    if (angle_scale != 1.0) {
        const SphericalAngles a = angles_of(v);
        v = direction_from_angles(angle_scale * a.theta, a.phi);
    }
    return rotation * v;
}

Eigen::Vector3d AngularMapping::display_direction(const Eigen::Vector3d& field) const {
    Eigen::Vector3d v = field.normalized();
    if (turn_deg != 0.0) v = Eigen::AngleAxisd(-degrees_to_radians(turn_deg), Eigen::Vector3d::UnitZ()) * v;
    if (tilt_deg != 0.0) v = Eigen::AngleAxisd(degrees_to_radians(tilt_deg), Eigen::Vector3d::UnitX()) * v;
    if (angle_scale != 1.0) {
        const SphericalAngles a = angles_of(v);
        v = direction_from_angles(a.theta / angle_scale, a.phi);
    }
    return {-v.x(), -v.y(), v.z()};
}

// ---------------------------------------------------------------------------------------

struct Encoder::Tables {
    explicit Tables(const optics::Design& design) : optics(design) {}

    optics::DesignOptics optics;
    CellIndex centre_cell{};
    Eigen::Vector2d centre_of_centre_cell = Eigen::Vector2d::Zero();
    double b = 0.0;  // paraxial offset per slope, mm

    // Exact model: slopes at nodes (origin + k * step) over one cell, row-major, x fastest.
    int nodes = 0;
    double table_origin = 0.0, table_step = 0.0;
    std::vector<Eigen::Vector2d> slopes;

    std::unique_ptr<relight::SphericalInterpolator> interpolator;
    // Full field index -> column in the lenslet table (-1: never needed).
    std::vector<int> column_of;
    int columns = 0;
    // samples[(lenslet * columns + column) * channels + c]
    std::vector<float> samples;
    Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();  // AngularMapping::rotation()

    Eigen::Vector2d table_slopes(const Eigen::Vector2d& offset) const {
        const double fx = std::clamp((offset.x() - table_origin) / table_step, 0.0, nodes - 1.000001);
        const double fy = std::clamp((offset.y() - table_origin) / table_step, 0.0, nodes - 1.000001);
        const int ix = static_cast<int>(fx), iy = static_cast<int>(fy);
        const double tx = fx - ix, ty = fy - iy;
        const std::size_t k = static_cast<std::size_t>(iy) * static_cast<std::size_t>(nodes) + static_cast<std::size_t>(ix);
        const std::size_t n = static_cast<std::size_t>(nodes);
        return (1 - ty) * ((1 - tx) * slopes[k] + tx * slopes[k + 1]) +
               ty * ((1 - tx) * slopes[k + n] + tx * slopes[k + n + 1]);
    }
};

namespace {

// The exact inverse map over one cell, from Newton solves at every node. Nodes where the
// solve fails (outside the cell, beyond wrap-over) take the paraxial slopes plus the mean
// exact-minus-paraxial correction of their solved neighbours, so bilinear lookups near the
// boundary stay smooth.
void tabulate_exact(Encoder::Tables& t, const optics::Lattice& lattice, int nodes) {
    RFD_CHECK(nodes >= 3);
    const double reach = 1.05 * lattice.circumradius();
    t.nodes = nodes;
    t.table_origin = -reach;
    t.table_step = 2.0 * reach / (nodes - 1);
    const std::size_t count = static_cast<std::size_t>(nodes) * static_cast<std::size_t>(nodes);
    t.slopes.assign(count, Eigen::Vector2d::Zero());
    std::vector<char> solved(count, 0);
    parallel_for_chunks(count, 64, [&](std::size_t begin, std::size_t end) {
        for (std::size_t k = begin; k < end; ++k) {
            const Eigen::Vector2d offset(t.table_origin + static_cast<double>(k % static_cast<std::size_t>(nodes)) * t.table_step,
                                         t.table_origin + static_cast<double>(k / static_cast<std::size_t>(nodes)) * t.table_step);
            const auto d = t.optics.direction_for(offset, t.centre_cell, optics::Model::Exact);
            if (d) {
                t.slopes[k] = {d->x() / d->z(), d->y() / d->z()};
                solved[k] = 1;
            }
        }
    });
    // Grow the corrections outward, ring by ring, in a fixed order (deterministic).
    std::vector<Eigen::Vector2d> correction(count, Eigen::Vector2d::Zero());
    for (std::size_t k = 0; k < count; ++k) {
        const Eigen::Vector2d offset(t.table_origin + static_cast<double>(k % static_cast<std::size_t>(nodes)) * t.table_step,
                                     t.table_origin + static_cast<double>(k / static_cast<std::size_t>(nodes)) * t.table_step);
        if (solved[k]) correction[k] = t.slopes[k] - offset / t.b;
    }
    bool any_unsolved = true;
    while (any_unsolved) {
        any_unsolved = false;
        std::vector<char> next = solved;
        bool progress = false;
        for (int y = 0; y < nodes; ++y)
            for (int x = 0; x < nodes; ++x) {
                const std::size_t k = static_cast<std::size_t>(y * nodes + x);
                if (solved[k]) continue;
                Eigen::Vector2d sum = Eigen::Vector2d::Zero();
                int n = 0;
                for (int dy = -1; dy <= 1; ++dy)
                    for (int dx = -1; dx <= 1; ++dx) {
                        const int xx = x + dx, yy = y + dy;
                        if (xx < 0 || yy < 0 || xx >= nodes || yy >= nodes) continue;
                        const std::size_t j = static_cast<std::size_t>(yy * nodes + xx);
                        if (solved[j]) {
                            sum += correction[j];
                            ++n;
                        }
                    }
                if (n == 0) {
                    any_unsolved = true;
                    continue;
                }
                correction[k] = sum / n;
                next[k] = 1;
                progress = true;
            }
        solved.swap(next);
        if (!progress) break;  // nothing solved at all: stay paraxial
    }
    for (std::size_t k = 0; k < count; ++k) {
        const Eigen::Vector2d offset(t.table_origin + static_cast<double>(k % static_cast<std::size_t>(nodes)) * t.table_step,
                                     t.table_origin + static_cast<double>(k / static_cast<std::size_t>(nodes)) * t.table_step);
        t.slopes[k] = offset / t.b + correction[k];
    }
}

// The paraxial part of a design's inverse map, for needed_field_directions before any
// table exists: it only needs a bound, and the exact map stays within a few percent of it
// inside a cell.
double paraxial_max_angle(const optics::DesignOptics& optics) {
    double largest = 0.0;
    for (const Eigen::Vector2d& offset : optics::probe_offsets(optics.lattice()))
        largest = std::max(largest, std::atan(offset.norm() / std::abs(optics.paraxial_b())));
    return largest;
}

// Field directions within `radius` of the cone around the mapped display axis, plus the
// longest triangle edge there (every triangle that can hold a needed direction).
std::vector<std::size_t> directions_near_cone(const std::vector<Eigen::Vector3d>& directions,
                                              const relight::SphericalInterpolator& interpolator,
                                              const Eigen::Vector3d& axis, double radius) {
    double longest = 0.0;
    for (const relight::Triangle& t : interpolator.triangles()) {
        bool near = false;
        for (std::size_t v : t) near = near || angle_between(interpolator.directions()[v], axis) <= radius;
        if (!near) continue;
        for (int e = 0; e < 3; ++e)
            longest = std::max(longest, angle_between(interpolator.directions()[t[static_cast<std::size_t>(e)]],
                                                      interpolator.directions()[t[static_cast<std::size_t>((e + 1) % 3)]]));
    }
    std::vector<std::size_t> kept;
    for (std::size_t i = 0; i < directions.size(); ++i)
        if (angle_between(directions[i].normalized(), axis) <= radius + longest + 1e-9) kept.push_back(i);
    return kept;
}

// Field-frame cone a design needs: its axis and half-angle, with a margin for the exact
// map and the angle scale.
std::pair<Eigen::Vector3d, double> needed_cone(const optics::DesignOptics& optics, const EncodeOptions& options) {
    const double display_angle = 1.1 * paraxial_max_angle(optics) + degrees_to_radians(1.0);
    const Eigen::Vector3d axis = options.mapping.field_direction(Eigen::Vector3d::UnitZ());
    return {axis, std::abs(options.mapping.angle_scale) * display_angle};
}

// Fit of the field image onto the array: image coordinates (pixel centres at integers) of a
// lattice-frame point.
struct ImageFitTransform {
    double mm_per_px_x = 1.0, mm_per_px_y = 1.0;
    int width = 0, height = 0;
    Eigen::Vector2d to_image(const Eigen::Vector2d& mm) const {
        return {mm.x() / mm_per_px_x + 0.5 * width - 0.5, 0.5 * height - mm.y() / mm_per_px_y - 0.5};
    }
};

ImageFitTransform fit_image(const Eigen::Vector2d& half_extent, int width, int height, ImageFit fit) {
    ImageFitTransform t;
    t.width = width;
    t.height = height;
    const double sx = 2.0 * half_extent.x() / width, sy = 2.0 * half_extent.y() / height;
    switch (fit) {
        case ImageFit::Cover: t.mm_per_px_x = t.mm_per_px_y = std::max(sx, sy); break;
        case ImageFit::Contain: t.mm_per_px_x = t.mm_per_px_y = std::min(sx, sy); break;
        case ImageFit::Stretch: t.mm_per_px_x = sx; t.mm_per_px_y = sy; break;
    }
    return t;
}

// The field at one lenslet. Where a lenslet covers a pixel or more, a box filter of its
// footprint: the pixels under an 8 x 8 grid of points over the cell's bounding box, those
// inside the cell, each weighing what it covers (outside the image counts as black). Where
// a lenslet is smaller than a pixel, a bilinear read at its centre.
std::vector<std::pair<std::size_t, float>> footprint_taps(const optics::Lattice& lattice, CellIndex cell,
                                                          const ImageFitTransform& fit) {
    const Eigen::Vector2d centre = lattice.center(cell);
    std::map<std::size_t, double> weights;
    auto pixel = [&](int x, int y) {
        return static_cast<std::size_t>(y) * static_cast<std::size_t>(fit.width) + static_cast<std::size_t>(x);
    };
    if (lattice.pitch_x() < fit.mm_per_px_x && lattice.pitch_y() < fit.mm_per_px_y) {
        const Eigen::Vector2d uv = fit.to_image(centre);
        if (uv.x() >= -0.5 && uv.y() >= -0.5 && uv.x() <= fit.width - 0.5 && uv.y() <= fit.height - 0.5) {
            const double u = std::clamp(uv.x(), 0.0, fit.width - 1.0), v = std::clamp(uv.y(), 0.0, fit.height - 1.0);
            const int x0 = static_cast<int>(u), y0 = static_cast<int>(v);
            const int x1 = std::min(x0 + 1, fit.width - 1), y1 = std::min(y0 + 1, fit.height - 1);
            const double tx = u - x0, ty = v - y0;
            weights[pixel(x0, y0)] += (1 - tx) * (1 - ty);
            weights[pixel(x1, y0)] += tx * (1 - ty);
            weights[pixel(x0, y1)] += (1 - tx) * ty;
            weights[pixel(x1, y1)] += tx * ty;
        }
    } else {
        constexpr int kGrid = 8;
        const double half_x = 0.5 * lattice.pitch_x();
        const double half_y = lattice.kind() == LatticeKind::Hexagonal ? lattice.circumradius() : 0.5 * lattice.pitch_y();
        int inside = 0;
        for (int gy = 0; gy < kGrid; ++gy)
            for (int gx = 0; gx < kGrid; ++gx) {
                const Eigen::Vector2d p = centre + Eigen::Vector2d((2.0 * (gx + 0.5) / kGrid - 1.0) * half_x,
                                                                   (2.0 * (gy + 0.5) / kGrid - 1.0) * half_y);
                if (!lattice.cell_contains(cell, p)) continue;
                ++inside;
                const Eigen::Vector2d uv = fit.to_image(p);
                const double x = std::floor(uv.x() + 0.5), y = std::floor(uv.y() + 0.5);
                if (x < 0 || y < 0 || x >= fit.width || y >= fit.height) continue;
                weights[pixel(static_cast<int>(x), static_cast<int>(y))] += 1.0;
            }
        for (auto& entry : weights) entry.second /= std::max(inside, 1);
    }
    std::vector<std::pair<std::size_t, float>> taps;
    for (const auto& [index, w] : weights)
        if (w > 0) taps.emplace_back(index, static_cast<float>(w));
    return taps;
}

}  // namespace

std::vector<std::size_t> needed_field_directions(const optics::Design& design,
                                                 const std::vector<Eigen::Vector3d>& field_directions,
                                                 const EncodeOptions& options) {
    check_design(design);
    const optics::DesignOptics optics(design);
    const relight::SphericalInterpolator interpolator(field_directions);
    const auto [axis, radius] = needed_cone(optics, options);
    return directions_near_cone(field_directions, interpolator, axis, radius);
}

relight::ReflectanceField load_field_for(const optics::Design& design, const std::filesystem::path& field,
                                         const EncodeOptions& options) {
    const std::filesystem::path lp = relight::light_file_of(field);
    const std::vector<relight::LightEntry> entries = relight::read_light_file(lp);
    std::vector<Eigen::Vector3d> directions;
    for (const auto& e : entries) directions.push_back(e.direction);
    const std::vector<std::size_t> needed = needed_field_directions(design, directions, options);
    if (needed.empty())
        throw InputError(SourceLocation{lp.string()}, "no light direction of the field lies near the display's range");
    relight::check_field_images(lp, entries);  // every image, also those the display does not need
    relight::ReflectanceField out;
    for (std::size_t i : needed) {
        const relight::LightEntry& e = entries[i];
        Image image;
        try {
            image = relight::apply_window(read_image(e.path), options.window, e.path.string());
        } catch (const Error& error) {
            rethrow_at(error, SourceLocation{lp.string(), e.line}, "image '" + e.file + "': " + error.what());
        }
        if (!out.images.empty() && !image.same_shape(out.images.front()))
            throw InputError(SourceLocation{lp.string(), e.line},
                             "image '" + e.file + "' differs in size or channels from the field's first image");
        out.directions.push_back(e.direction);
        out.images.push_back(std::move(image));
    }
    apply_light_model(out, options);
    return out;
}

std::string apply_light_model(relight::ReflectanceField& field, const EncodeOptions& options) {
    if (!options.light_model) return "";
    const relight::LightModel& model = *options.light_model;
    // Four times the field's directions inside its hull, at most 1 GB of images.
    const relight::SphericalInterpolator hull(field.directions);
    const std::vector<Eigen::Vector3d> probe = fibonacci_hemisphere(4096);
    const auto inside = static_cast<double>(
        std::count_if(probe.begin(), probe.end(), [&](const Eigen::Vector3d& d) { return hull.covers(d); }));
    const double image_bytes = static_cast<double>(field.images.front().samples().size()) * sizeof(float);
    const double wanted = std::min(4.0 * static_cast<double>(field.size()), std::max(1.0, 1e9 / image_bytes));
    const auto total = static_cast<std::size_t>(std::ceil(wanted * 4096.0 / std::max(inside, 1.0)));
    std::vector<Eigen::Vector3d> directions = field.directions;
    for (const Eigen::Vector3d& d : fibonacci_hemisphere(total))
        if (hull.covers(d)) directions.push_back(d);
    const std::size_t captured = field.size();
    field = relight::resampled_field(field, relight::LightWeights(model, field.directions), directions);
    return model.name() + " fitted to the " + std::to_string(captured) + " lights, sampled at " +
           std::to_string(directions.size()) + " directions";
}

Encoder::Encoder(const optics::Design& design, const relight::ReflectanceField& field,
                 const PatternGeometry& geometry, const EncodeOptions& options)
    : geometry_(geometry), options_(options) {
    check_design(design);
    if (field.size() < 3 || field.images.size() != field.size())
        throw InputError(SourceLocation{options.field_name},
                         "a field needs at least three light directions with one image each");
    if (!(options.mapping.angle_scale > 0.0))
        throw InputError(SourceLocation{options.field_name, 0, 0, "angle scale"}, "the angle scale must be positive");
    require_printable_channels(field.channels(), SourceLocation{options.field_name});
    tables_ = std::make_unique<Tables>(design);
    Tables& t = *tables_;
    t.rotation = options.mapping.rotation();
    channels_ = field.channels();
    const optics::Lattice& lattice = t.optics.lattice();
    t.centre_cell = t.optics.centre_cell();
    t.centre_of_centre_cell = lattice.center(t.centre_cell);
    t.b = t.optics.paraxial_b();
    if (options.model == optics::Model::Exact) tabulate_exact(t, lattice, options.exact_table_nodes);

    // The display's range: probes over one cell.
    for (const Eigen::Vector2d& offset : optics::probe_offsets(lattice)) {
        const Eigen::Vector3d d = incident_direction(offset);
        range_.probes.push_back(d);
        range_.max_angle_rad = std::max(range_.max_angle_rad, std::acos(std::clamp(d.z(), -1.0, 1.0)));
    }

    t.interpolator = std::make_unique<relight::SphericalInterpolator>(field.directions);
    std::vector<std::string> missing;
    std::size_t missing_count = 0;
    double highest_needed_theta = 0.0;
    for (const Eigen::Vector3d& d : range_.probes) {
        const Eigen::Vector3d v = options.mapping.field_direction(d);
        highest_needed_theta = std::max(highest_needed_theta, angles_of(v).theta);
        if (t.interpolator->covers(v)) continue;
        ++missing_count;
        if (missing.size() < 4) missing.push_back("display " + format_direction(d) + " -> field " + format_direction(v));
    }
    if (missing_count > 0 && !options.allow_partial_coverage) {
        double field_highest = 0.0;
        for (const auto& v : field.directions) field_highest = std::max(field_highest, angles_of(v).theta);
        std::string list;
        for (const auto& m : missing) list += "\n  " + m;
        throw InputError(SourceLocation{options.field_name},
                         "the field does not cover the display's angular range: " + std::to_string(missing_count) +
                             " of " + std::to_string(range_.probes.size()) +
                             " probed incident directions (up to " + format_number(radians_to_degrees(range_.max_angle_rad), 3) +
                             " deg from the display axis; field theta up to " + format_number(radians_to_degrees(highest_needed_theta), 3) +
                             " deg) fall outside the field's light directions (theta up to " +
                             format_number(radians_to_degrees(field_highest), 3) + " deg), e.g.:" + list +
                             "\n  capture those directions, change --tilt/--angle-scale, or pass --allow-partial");
    }

    // Which field directions any dot can need, and their samples at every lenslet. (Not a
    // structured binding: clang 14, the fuzz preset, cannot capture one in the lambda.)
    const std::pair<Eigen::Vector3d, double> needed = needed_cone(t.optics, options);
    const Eigen::Vector3d& axis = needed.first;
    const double radius = needed.second;
    const double cone = std::max(radius, [&] {
        double r = 0.0;
        for (const auto& d : range_.probes) r = std::max(r, angle_between(options.mapping.field_direction(d), axis));
        return r;
    }());
    std::vector<std::size_t> kept = options.allow_partial_coverage && missing_count > 0
                                        ? std::vector<std::size_t>{}
                                        : directions_near_cone(field.directions, *t.interpolator, axis, cone);
    if (kept.empty())
        for (std::size_t i = 0; i < field.size(); ++i) kept.push_back(i);
    t.column_of.assign(field.size(), -1);
    for (std::size_t c = 0; c < kept.size(); ++c) t.column_of[kept[c]] = static_cast<int>(c);
    t.columns = static_cast<int>(kept.size());

    const Eigen::Vector2d half = lattice.half_extent();
    const ImageFitTransform fit = fit_image(half, field.width(), field.height(), options.fit);
    const std::size_t lenslets = static_cast<std::size_t>(lattice.count_x()) * static_cast<std::size_t>(lattice.count_y());
    const std::size_t columns = kept.size();
    const std::size_t channels = static_cast<std::size_t>(channels_);
    t.samples.assign(lenslets * columns * channels, 0.0f);
    parallel_for_chunks(lenslets, 16, [&](std::size_t begin, std::size_t end) {
        for (std::size_t l = begin; l < end; ++l) {
            const CellIndex cell{static_cast<int>(l % static_cast<std::size_t>(lattice.count_x())),
                                 static_cast<int>(l / static_cast<std::size_t>(lattice.count_x()))};
            const auto taps = footprint_taps(lattice, cell, fit);
            float* row = t.samples.data() + l * columns * channels;
            for (std::size_t c = 0; c < columns; ++c) {
                const Image& image = field.images[kept[c]];
                for (std::size_t ch = 0; ch < channels; ++ch) {
                    const std::span<const float> plane = image.plane(static_cast<int>(ch));
                    double sum = 0.0;
                    for (const auto& [pixel, w] : taps) sum += static_cast<double>(w) * plane[pixel];
                    row[c * channels + ch] = static_cast<float>(sum);
                }
            }
        }
    });

    // White: the 99.5th percentile of the brightest channel over every 16th row and 4th dot.
    const int rows = (geometry_.height + 15) / 16;
    std::vector<std::vector<float>> per_row(static_cast<std::size_t>(rows));
    parallel_for_chunks(static_cast<std::size_t>(rows), 1, [&](std::size_t begin, std::size_t end) {
        std::vector<float> buffer(static_cast<std::size_t>(geometry_.width) * channels);
        for (std::size_t r = begin; r < end; ++r) {
            const int py = std::min(geometry_.height - 1, static_cast<int>(r) * 16 + 8);
            render_row(py, buffer);
            const double y = geometry_.dot_centre(0, py).y();
            for (int px = 0; px < geometry_.width; px += 4) {
                if (!lattice.contains(lattice.cell_at({geometry_.dot_centre(px, py).x(), y}))) continue;
                float brightest = 0.0f;
                for (std::size_t ch = 0; ch < channels; ++ch)
                    brightest = std::max(brightest, buffer[static_cast<std::size_t>(px) * channels + ch]);
                per_row[r].push_back(brightest);
            }
        }
    });
    std::vector<float> values;
    for (const auto& v : per_row) values.insert(values.end(), v.begin(), v.end());
    if (!values.empty()) {
        const std::size_t k = std::min(values.size() - 1, static_cast<std::size_t>(0.995 * static_cast<double>(values.size())));
        std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(k), values.end());
        white_ = values[k] > 0.0f ? values[k] : 1.0;
    }
}

Encoder::~Encoder() = default;

const optics::Lattice& Encoder::lattice() const { return tables_->optics.lattice(); }
const optics::DesignOptics& Encoder::optics() const { return tables_->optics; }
const relight::SphericalInterpolator& Encoder::interpolator() const { return *tables_->interpolator; }

Eigen::Vector3d Encoder::incident_direction(const Eigen::Vector2d& offset) const {
    const Tables& t = *tables_;
    if (options_.model == optics::Model::Exact) return from_slopes(t.table_slopes(offset));
    return from_slopes(offset / t.b);
}

double Encoder::exact_table_error(int samples) const {
    if (options_.model != optics::Model::Exact) return 0.0;
    const Tables& t = *tables_;
    const optics::Lattice& lattice = t.optics.lattice();
    double worst = 0.0;
    // A deterministic low-discrepancy set over the cell (golden-ratio sequence).
    for (int k = 0; k < samples; ++k) {
        const double u = std::fmod(0.5 + k * 0.6180339887498949, 1.0);
        const double v = std::fmod(0.5 + k * 0.7548776662466927, 1.0);
        const double r = std::sqrt(v), phi = 2.0 * kPi * u;
        const Eigen::Vector2d dir(std::cos(phi), std::sin(phi));
        const Eigen::Vector2d offset = 0.999 * r * lattice.boundary_distance(dir) * dir;
        const auto direct = t.optics.direction_for(offset, t.centre_cell, optics::Model::Exact);
        if (!direct) continue;
        worst = std::max(worst, angle_between(*direct, incident_direction(offset)));
    }
    return worst;
}

float Encoder::lenslet_sample(CellIndex cell, std::size_t index, int channel) const {
    const Tables& t = *tables_;
    const int column = t.column_of.at(index);
    if (column < 0) return 0.0f;
    const std::size_t l = lattice().linear_index(cell);
    return t.samples[(l * static_cast<std::size_t>(t.columns) + static_cast<std::size_t>(column)) *
                         static_cast<std::size_t>(channels_) +
                     static_cast<std::size_t>(channel)];
}

void Encoder::render_row(int py, std::span<float> out) const {
    if (tables_->optics.lattice().kind() == LatticeKind::Hexagonal)
        render_row_of<LatticeKind::Hexagonal>(py, out);
    else
        render_row_of<LatticeKind::Rectangular>(py, out);
}

namespace {

// The lights of up to kChunk consecutive dots of a run, in the field frame (unnormalised),
// and their 1/cos(kappa): filled a chunk at a time so the arithmetic (square roots above
// all) runs as vector instructions rather than one dot after another.
constexpr int kChunk = 64;
struct ChunkLights {
    double x[kChunk], y[kChunk], z[kChunk], inverse_cos[kChunk];
    // For lights R (-s, 1): |R (-s, 1)| = sqrt(1 + s^2) = 1/cos(kappa).
    void norms(int n) {
        for (int i = 0; i < n; ++i) inverse_cos[i] = std::sqrt(x[i] * x[i] + y[i] * y[i] + z[i] * z[i]);
    }
};

const float kZeroSample[4] = {0.0f, 0.0f, 0.0f, 0.0f};

// Renders the dots [begin, end) of a print row that lie in one lenslet (a run) from that
// lenslet's samples. `fill(first, n, lights)` gives the lights of dots first .. first+n-1.
// Neighbouring dots nearly always share a triangle of the interpolation, so its planes and
// sample pointers stay loaded and a dot costs three dot products and the blend; a dot that
// leaves the triangle (or any dot for other interpolations) goes through the
// interpolator's full query. `start_triangle` is the hint for the first dot and is left
// holding that dot's triangle: the next lenslet of the same lattice row starts at nearly
// the same direction.
template <class Fill>
void render_run(const Encoder::Tables& t, relight::Interpolation method, std::size_t channels,
                const float* lenslet_samples, int begin, int end, const Fill& fill, float* out,
                std::size_t& start_triangle) {
    RFD_CHECK(channels <= std::size(kZeroSample));
    std::size_t triangle = start_triangle;
    const relight::SphericalInterpolator& interpolator = *t.interpolator;
    const bool delaunay = method == relight::Interpolation::Delaunay;
    // Plain doubles (zeroed): Eigen members here trip GCC 12's maybe-uninitialized.
    double planes[3][3] = {};
    std::array<const float*, 3> sample{};
    bool loaded = false;
    auto load = [&] {
        loaded = delaunay && triangle != relight::SphericalInterpolator::kNoTriangle;
        if (!loaded) return;
        for (std::size_t j = 0; j < 3; ++j) {
            for (Eigen::Index k = 0; k < 3; ++k) planes[j][k] = interpolator.edge_planes(triangle)[j][k];
            const int column = t.column_of[interpolator.triangles()[triangle][j]];
            sample[j] = column < 0 ? kZeroSample : lenslet_samples + static_cast<std::size_t>(column) * channels;
        }
    };
    load();
    ChunkLights lights;
    for (int first = begin; first < end; first += kChunk) {
        const int n = std::min(kChunk, end - first);
        fill(first, n, lights);
        for (int i = 0; i < n; ++i) {
            const int px = first + i;
            float* dot = out + static_cast<std::size_t>(px) * channels;
            const double vx = lights.x[i], vy = lights.y[i], vz = lights.z[i];
            if (loaded) {
                const double a0 = vx * planes[0][0] + vy * planes[0][1] + vz * planes[0][2];
                const double a1 = vx * planes[1][0] + vy * planes[1][1] + vz * planes[1][2];
                const double a2 = vx * planes[2][0] + vy * planes[2][1] + vz * planes[2][2];
                const double sum = a0 + a1 + a2;
                if (a0 >= 0.0 && a1 >= 0.0 && a2 >= 0.0 && sum > 0.0) {
                    const double scale = lights.inverse_cos[i] / sum;
                    const float w0 = static_cast<float>(a0 * scale), w1 = static_cast<float>(a1 * scale),
                                w2 = static_cast<float>(a2 * scale);
                    for (std::size_t c = 0; c < channels; ++c)
                        dot[c] = w0 * sample[0][c] + w1 * sample[1][c] + w2 * sample[2][c];
                    continue;
                }
            }
            const relight::InterpolationWeights w = interpolator.weights(Eigen::Vector3d(vx, vy, vz), method, triangle);
            for (std::size_t k = 0; k < w.count; ++k) {
                const int column = t.column_of[w.index[k]];
                if (column < 0 || w.weight[k] == 0.0) continue;
                const float weight = static_cast<float>(w.weight[k] * lights.inverse_cos[i]);
                const float* s = lenslet_samples + static_cast<std::size_t>(column) * channels;
                for (std::size_t c = 0; c < channels; ++c) dot[c] += weight * s[c];
            }
            load();
            if (px == begin) start_triangle = triangle;
        }
    }
}

}  // namespace

// A print row is a sequence of runs, one per lenslet it crosses. Within a run the offset
// from the lenslet axis moves by dot_x per dot, so the paraxial direction is linear in px
// and the exact one is a lerp along one line of the table (the table's bilinear lookup at
// the run's fixed y, prepared once per lattice row). Angle scaling is not linear: it
// takes the general path per dot.
template <LatticeKind K>
void Encoder::render_row_of(int py, std::span<float> out) const {
    const Tables& t = *tables_;
    const optics::Lattice& lattice = t.optics.lattice();
    const std::size_t channels = static_cast<std::size_t>(channels_);
    const std::size_t stride = static_cast<std::size_t>(t.columns) * channels;
    const double y = geometry_.dot_centre(0, py).y();
    const double x0 = geometry_.dot_centre(0, py).x();
    const double dx = geometry_.dot_x;
    const int width = geometry_.width;
    const bool exact = options_.model == optics::Model::Exact;
    const bool scaled = options_.mapping.angle_scale != 1.0;
    const Eigen::Matrix3d& rotation = t.rotation;
    auto field_light = [&](const Eigen::Vector2d& slopes) -> Eigen::Vector3d {
        return rotation * Eigen::Vector3d(-slopes.x(), -slopes.y(), 1.0);
    };

    // Exact model: the table's rows interpolated at this print row's offset from the axes
    // of the (at most two) lattice rows it crosses, as field-frame lights.
    std::array<int, 2> line_row{std::numeric_limits<int>::min(), std::numeric_limits<int>::min()};
    std::array<std::vector<Eigen::Vector3d>, 2> lines;
    auto table_line = [&](int j, double offset_y) -> const std::vector<Eigen::Vector3d>& {
        const std::size_t slot = static_cast<std::size_t>(j & 1);
        if (line_row[slot] != j) {
            const std::size_t n = static_cast<std::size_t>(t.nodes);
            const double fy = std::clamp((offset_y - t.table_origin) / t.table_step, 0.0, t.nodes - 1.000001);
            const std::size_t iy = static_cast<std::size_t>(fy);
            const double ty = fy - static_cast<double>(iy);
            lines[slot].resize(n);
            for (std::size_t ix = 0; ix < n; ++ix)
                lines[slot][ix] = field_light((1 - ty) * t.slopes[iy * n + ix] + ty * t.slopes[(iy + 1) * n + ix]);
            line_row[slot] = j;
        }
        return lines[slot];
    };

    // Per lattice-row parity, the triangle of the last run's first dot.
    std::array<std::size_t, 2> start_triangle{relight::SphericalInterpolator::kNoTriangle,
                                              relight::SphericalInterpolator::kNoTriangle};
    std::fill(out.begin(), out.end(), 0.0f);
    for (int px = 0; px < width;) {
        const double x = x0 + px * dx;
        const CellIndex cell = lattice.cell_at_of<K>({x, y});
        // The run's end from the cell's chord, then checked against cell_at on both sides.
        const double reach = std::min((lattice.cell_exit_x_of<K>(cell, y) - x) / dx, static_cast<double>(width));
        int end = std::clamp(px + 1 + static_cast<int>(std::floor(reach)), px + 1, width);
        while (end > px + 1 && !(lattice.cell_at_of<K>({x0 + (end - 1) * dx, y}) == cell)) --end;
        while (end < width && lattice.cell_at_of<K>({x0 + end * dx, y}) == cell) ++end;
        if (lattice.contains(cell)) {
            const Eigen::Vector2d centre = lattice.center_of<K>(cell);
            const double offset_y = y - centre.y();
            const double offset_x0 = x0 - centre.x();  // the offset of dot px is offset_x0 + px * dx
            const float* samples = t.samples.data() + lattice.linear_index(cell) * stride;
            std::size_t& triangle = start_triangle[static_cast<std::size_t>(cell.j & 1)];
            if (scaled) {
                render_run(t, options_.interpolation, channels, samples, px, end, [&](int first, int n, ChunkLights& l) {
                    for (int i = 0; i < n; ++i) {
                        const Eigen::Vector2d offset(offset_x0 + (first + i) * dx, offset_y);
                        const Eigen::Vector2d slopes = exact ? t.table_slopes(offset) : Eigen::Vector2d(offset / t.b);
                        const Eigen::Vector3d v = options_.mapping.field_direction(from_slopes(slopes), rotation);
                        l.x[i] = v.x(), l.y[i] = v.y(), l.z[i] = v.z();
                        l.inverse_cos[i] = std::sqrt(1.0 + slopes.squaredNorm());
                    }
                }, out.data(), triangle);
            } else if (exact) {
                const std::vector<Eigen::Vector3d>& line = table_line(cell.j, offset_y);
                const double fx0 = (offset_x0 - t.table_origin) / t.table_step, fdx = dx / t.table_step;
                const double last = t.nodes - 1.000001;
                render_run(t, options_.interpolation, channels, samples, px, end, [&](int first, int n, ChunkLights& l) {
                    for (int i = 0; i < n; ++i) {
                        const double fx = std::clamp(fx0 + (first + i) * fdx, 0.0, last);
                        const std::size_t ix = static_cast<std::size_t>(fx);
                        const double f = fx - static_cast<double>(ix);
                        const Eigen::Vector3d& a = line[ix];
                        const Eigen::Vector3d& b = line[ix + 1];
                        l.x[i] = a.x() + f * (b.x() - a.x());
                        l.y[i] = a.y() + f * (b.y() - a.y());
                        l.z[i] = a.z() + f * (b.z() - a.z());
                    }
                    l.norms(n);
                }, out.data(), triangle);
            } else {
                const Eigen::Vector3d start = field_light(Eigen::Vector2d(offset_x0, offset_y) / t.b);
                const Eigen::Vector3d step = rotation.col(0) * (-dx / t.b);
                render_run(t, options_.interpolation, channels, samples, px, end, [&](int first, int n, ChunkLights& l) {
                    for (int i = 0; i < n; ++i) {
                        const double k = first + i;
                        l.x[i] = start.x() + k * step.x();
                        l.y[i] = start.y() + k * step.y();
                        l.z[i] = start.z() + k * step.z();
                    }
                    l.norms(n);
                }, out.data(), triangle);
            }
        }
        px = end;
    }
}

PatternAttributes Encoder::attributes() const {
    const optics::Design& design = tables_->optics.design();
    PatternAttributes attributes = encode_attributes(options_);
    attributes["design"] = design.name;
    attributes["design_file"] = design.file;
    attributes["kind"] = std::string(optics::to_string(design.kind));
    attributes["white"] = format_number(white_, 9);
    // The printer's tools rebuild the raster from the design, the resolution and this.
    if (geometry_.margin_mm > 0.0) attributes["margin_mm"] = format_number(geometry_.margin_mm, 17);
    return attributes;
}

DecodeComparison decode_and_compare(const Encoder& encoder, const std::vector<float>& pattern_rows,
                                    double border_dots) {
    const PatternGeometry& g = encoder.geometry();
    const std::size_t channels = static_cast<std::size_t>(encoder.channels());
    RFD_CHECK(pattern_rows.size() == g.dot_count() * channels);
    const optics::Lattice& lattice = encoder.lattice();
    const optics::DesignOptics& optics = encoder.optics();
    const auto& directions = encoder.interpolator().directions();
    const AngularMapping& mapping = encoder.options().mapping;
    const double border = border_dots * std::max(g.dot_x, g.dot_y);

    auto value_at = [&](const Eigen::Vector2d& raster, std::size_t c) {
        const int x0 = static_cast<int>(std::floor(raster.x())), y0 = static_cast<int>(std::floor(raster.y()));
        const double tx = raster.x() - x0, ty = raster.y() - y0;
        auto at = [&](int x, int y) {
            x = std::clamp(x, 0, g.width - 1);
            y = std::clamp(y, 0, g.height - 1);
            return static_cast<double>(
                pattern_rows[(static_cast<std::size_t>(y) * static_cast<std::size_t>(g.width) + static_cast<std::size_t>(x)) *
                                 channels + c]);
        };
        return (1 - ty) * ((1 - tx) * at(x0, y0) + tx * at(x0 + 1, y0)) +
               ty * ((1 - tx) * at(x0, y0 + 1) + tx * at(x0 + 1, y0 + 1));
    };

    double sum = 0.0, peak = 0.0;
    std::size_t n = 0;
    for (std::size_t i = 0; i < directions.size(); ++i) {
        const Eigen::Vector3d d = mapping.display_direction(directions[i]);
        if (!(d.z() > 0.0)) continue;
        for (int cj = 0; cj < lattice.count_y(); ++cj)
            for (int ci = 0; ci < lattice.count_x(); ++ci) {
                const CellIndex cell{ci, cj};
                const optics::DesignOptics::Landing landing = optics.land(d, cell, encoder.options().model);
                if (landing.status != optics::RayStatus::Ok || !(landing.cell == cell)) continue;
                const Eigen::Vector2d p = lattice.center(cell) + landing.offset;
                // Far enough inside the cell that the bilinear read stays in it.
                bool inside = true;
                for (int k = 0; k < 8 && inside; ++k) {
                    const double a = 2.0 * kPi * k / 8;
                    inside = lattice.cell_contains(cell, p + border * Eigen::Vector2d(std::cos(a), std::sin(a)));
                }
                if (!inside) continue;
                const Eigen::Vector2d raster = g.raster_position(p);
                for (std::size_t c = 0; c < channels; ++c) {
                    const double decoded = value_at(raster, c) * d.z();
                    const double direct = encoder.lenslet_sample(cell, i, static_cast<int>(c));
                    sum += (decoded - direct) * (decoded - direct);
                    peak = std::max(peak, direct);
                    ++n;
                }
            }
    }
    DecodeComparison result;
    result.samples = n;
    result.mse = n ? sum / static_cast<double>(n) : 0.0;
    result.peak = peak;
    result.psnr_db = result.mse > 0 ? 10.0 * std::log10(peak * peak / result.mse)
                                    : std::numeric_limits<double>::infinity();
    return result;
}

AngularMapping mapping_of(const PatternFileInfo& info, const std::string& file) {
    AngularMapping mapping;
    mapping.tilt_deg = number_attribute(info, "tilt_deg", file, 0.0);
    mapping.turn_deg = number_attribute(info, "turn_deg", file, 0.0);
    mapping.angle_scale = number_attribute(info, "angle_scale", file, 1.0, NumberRange::Positive);
    return mapping;
}

PatternAttributes encode_attributes(const EncodeOptions& options) {
    const auto number = [](double v) { return format_number(v, 6); };
    PatternAttributes attributes{{"model", std::string(optics::to_string(options.model))},
            {"field", options.field_name},
            {"tilt_deg", number(options.mapping.tilt_deg)},
            {"turn_deg", number(options.mapping.turn_deg)},
            {"angle_scale", number(options.mapping.angle_scale)},
            {"interpolation", std::string(name_of(relight::kInterpolationNames, options.interpolation))},
            {"fit", std::string(name_of(kImageFitNames, options.fit))}};
    const relight::ImageWindow& w = options.window;
    if (w.width > 0 || w.height > 0)
        attributes["region"] = std::to_string(w.x) + "," + std::to_string(w.y) + "," + std::to_string(w.width) + "," +
                               std::to_string(w.height);
    if (w.scale != 1.0) attributes["scale"] = format_number(w.scale, 17);
    if (const auto& m = options.light_model) {
        attributes["basis"] = m->base_name();
        if (m->has_sigma()) attributes["rbf_sigma"] = format_number(m->sigma, 17);
    }
    return attributes;
}

EncodeOptions encode_options_of(const PatternFileInfo& info, const std::string& file) {
    const auto text = [&](const std::string& key, const std::string& fallback) {
        const auto it = info.attributes.find(key);
        return it == info.attributes.end() ? fallback : it->second;
    };
    const auto where = [&](const std::string& key) { return SourceLocation{file, 0, 0, "rfd:" + key}; };
    EncodeOptions options;
    options.field_name = text("field", file);
    options.model = value_of(optics::kModelNames, text("model", "paraxial"), where("model"));
    options.mapping = mapping_of(info, file);
    options.interpolation = value_of(relight::kInterpolationNames, text("interpolation", "delaunay"), where("interpolation"));
    options.fit = value_of(kImageFitNames, text("fit", "cover"), where("fit"));
    options.allow_partial_coverage = true;
    if (const auto region = info.attributes.find("region"); region != info.attributes.end())
        options.window = relight::parse_region(region->second, file + ": rfd:region");
    options.window.scale = number_attribute(info, "scale", file, 1.0, NumberRange::Positive);
    if (const auto basis = info.attributes.find("basis"); basis != info.attributes.end()) {
        relight::LightModel model = relight::parse_light_model(basis->second, file + ": rfd:basis");
        if (model.has_sigma())
            model.sigma = number_attribute(info, "rbf_sigma", file, 0.0, NumberRange::Positive);
        if (model.kind == relight::LightModel::Kind::Interpolation) options.interpolation = model.interpolation;
        else options.light_model = model;
    }
    return options;
}

}  // namespace rfd::patterns
