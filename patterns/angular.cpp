#include "patterns/angular.hpp"

#include <algorithm>
#include <cmath>

#include "core/error.hpp"
#include "core/parallel.hpp"

namespace rfd::patterns {

struct AngularPattern::CellTable {
    std::vector<std::uint8_t> light;  // optics::DotLight per node
    std::vector<float> tx, ty;        // output slopes per node
};

AngularPattern::AngularPattern(const optics::DesignOptics& optics, const AngularField& field,
                               const AngularOptions& options)
    : optics_(optics), meso_(optics), field_(field), options_(options) {
    const optics::Design& design = optics.design();
    const SourceLocation where{design.file};
    require_printable_channels(field.channels(), SourceLocation{});
    if (options.bin_samples < 1 || options.bin_samples > 16)
        throw InputError(where, "bin samples per side must be in [1, 16], got " + std::to_string(options.bin_samples));
    if (options.table_size < 3 || options.table_size > 4097)
        throw InputError(where, "optics table size must be in [3, 4097], got " + std::to_string(options.table_size));
    const Dpi dpi_x{options.dpi_x > 0.0 ? options.dpi_x : design.printer.dpi_x.value};
    const Dpi dpi_y{options.dpi_y > 0.0 ? options.dpi_y : design.printer.dpi_y.value};
    geometry_ = pattern_geometry(design, dpi_x, dpi_y);
    if (design.macro) {
        macro_x_ = design.macro->count_x;
        macro_y_ = design.macro->count_y;
        macro_pitch_x_ = design.macro->pitch_x;
        macro_pitch_y_ = design.macro->pitch_y;
    }

    const optics::Lattice& lattice = meso_.lattice();
    const int cells = lattice.count_x() * lattice.count_y();
    for (int j = 0; j < lattice.count_y(); ++j)
        for (int i = 0; i < lattice.count_x(); ++i) {
            optics::IncidentBin bin = meso_.bin({i, j}, options.model, options.bin_samples);
            LightBin lights;
            for (const auto& d : bin.samples) lights.push_back(field_light_of(d));
            if (lights.empty()) lights.push_back(field_light_of(bin.centre));
            bins_.push_back(std::move(bin));
            field_bins_.push_back(std::move(lights));
        }
    lookup_ = field.bind(field_bins_, macro_x_, macro_y_);

    // The optics tables, one per meso cell, over the cell's bounding box.
    for (const auto& corner : lattice.cell_corners()) half_box_ = half_box_.cwiseMax(corner.cwiseAbs());
    const int n = options.table_size;
    const std::size_t nodes = static_cast<std::size_t>(n) * static_cast<std::size_t>(n);
    auto node_offset = [&](int ix, int iy) {
        return Eigen::Vector2d(-half_box_.x() + 2.0 * half_box_.x() * ix / (n - 1),
                               -half_box_.y() + 2.0 * half_box_.y() * iy / (n - 1));
    };
    // The chief slopes do not depend on the cell: solve them once, under the centre cell.
    const optics::CellIndex centre = optics.centre_cell();
    std::vector<std::optional<Eigen::Vector2d>> slopes(nodes);
    parallel_for_chunks(nodes, 256, [&](std::size_t begin, std::size_t end) {
        for (std::size_t k = begin; k < end; ++k)
            slopes[k] = meso_.chief_slope(node_offset(static_cast<int>(k % n), static_cast<int>(k / n)), centre,
                                          options.model);
    });
    tables_.resize(static_cast<std::size_t>(cells));
    for (CellTable& table : tables_) {
        table.light.assign(nodes, static_cast<std::uint8_t>(optics::DotLight::Lost));
        table.tx.assign(nodes, 0.0f);
        table.ty.assign(nodes, 0.0f);
    }
    parallel_for_chunks(static_cast<std::size_t>(cells) * static_cast<std::size_t>(n), 16,
                        [&](std::size_t begin, std::size_t end) {
        for (std::size_t task = begin; task < end; ++task) {
            const std::size_t c = task / static_cast<std::size_t>(n);
            const int iy = static_cast<int>(task % static_cast<std::size_t>(n));
            const optics::CellIndex cell{static_cast<int>(c % static_cast<std::size_t>(lattice.count_x())),
                                         static_cast<int>(c / static_cast<std::size_t>(lattice.count_x()))};
            CellTable& table = tables_[c];
            for (int ix = 0; ix < n; ++ix) {
                const std::size_t k = static_cast<std::size_t>(iy) * static_cast<std::size_t>(n) + static_cast<std::size_t>(ix);
                optics::DotRay ray;
                if (slopes[k]) ray = meso_.follow(*slopes[k], cell, options.model);
                // Each node is written by one task only, into vectors sized above.
                table.light[k] = static_cast<std::uint8_t>(ray.light);
                table.tx[k] = static_cast<float>(ray.output.x() / ray.output.z());
                table.ty[k] = static_cast<float>(ray.output.y() / ray.output.z());
            }
        }
    });
}

AngularPattern::~AngularPattern() = default;

std::optional<AngularPattern::DotPlace> AngularPattern::place(const Eigen::Vector2d& mm) const {
    DotPlace place;
    Eigen::Vector2d local = mm;
    if (optics_.design().macro) {
        const double w = macro_x_ * macro_pitch_x_, h = macro_y_ * macro_pitch_y_;
        const double fu = std::floor((mm.x() + 0.5 * w) / macro_pitch_x_);
        const double fv = std::floor((mm.y() + 0.5 * h) / macro_pitch_y_);
        if (!(fu >= 0.0 && fu < macro_x_ && fv >= 0.0 && fv < macro_y_)) return std::nullopt;
        place.u = static_cast<int>(fu);
        place.v = static_cast<int>(fv);
        local -= Eigen::Vector2d((place.u + 0.5) * macro_pitch_x_ - 0.5 * w, (place.v + 0.5) * macro_pitch_y_ - 0.5 * h);
    }
    const optics::Lattice& lattice = meso_.lattice();
    place.cell = lattice.cell_at(local);
    if (!lattice.contains(place.cell)) return std::nullopt;
    place.offset = local - lattice.center(place.cell);
    return place;
}

AngularPattern::TableDot AngularPattern::table_dot(const DotPlace& place) const {
    const CellTable& table = tables_[meso_.lattice().linear_index(place.cell)];
    const int n = options_.table_size;
    const double fx = std::clamp((place.offset.x() + half_box_.x()) / (2.0 * half_box_.x()) * (n - 1), 0.0, n - 1.0);
    const double fy = std::clamp((place.offset.y() + half_box_.y()) / (2.0 * half_box_.y()) * (n - 1), 0.0, n - 1.0);
    auto index = [n](int ix, int iy) {
        return static_cast<std::size_t>(iy) * static_cast<std::size_t>(n) + static_cast<std::size_t>(ix);
    };
    const auto lit = static_cast<std::uint8_t>(optics::DotLight::Lit);
    const std::size_t nearest = index(static_cast<int>(std::lround(fx)), static_cast<int>(std::lround(fy)));
    TableDot dot;
    dot.lit = table.light[nearest] == lit;
    if (!dot.lit) return dot;
    const int x0 = std::min(static_cast<int>(fx), n - 2), y0 = std::min(static_cast<int>(fy), n - 2);
    const std::size_t k00 = index(x0, y0), k10 = index(x0 + 1, y0), k01 = index(x0, y0 + 1), k11 = index(x0 + 1, y0 + 1);
    double tx = table.tx[nearest], ty = table.ty[nearest];
    if (table.light[k00] == lit && table.light[k10] == lit && table.light[k01] == lit && table.light[k11] == lit) {
        const double ax = fx - x0, ay = fy - y0;
        auto blend = [&](const std::vector<float>& t) {
            return (1 - ay) * ((1 - ax) * t[k00] + ax * t[k10]) + ay * ((1 - ax) * t[k01] + ax * t[k11]);
        };
        tx = blend(table.tx);
        ty = blend(table.ty);
    }
    dot.output = Eigen::Vector3d(tx, ty, 1.0).normalized();
    return dot;
}

void AngularPattern::render_row(int py, std::span<float> out) const {
    const int ch = channels();
    std::fill(out.begin(), out.end(), 0.0f);
    for (int px = 0; px < geometry_.width; ++px) {
        const auto where = place(geometry_.dot_centre(px, py));
        if (!where) continue;
        const TableDot dot = table_dot(*where);
        if (!dot.lit) continue;
        const std::size_t bin = meso_.lattice().linear_index(where->cell);
        lookup_->value(bin, dot.output, where->u, where->v,
                       out.subspan(static_cast<std::size_t>(px) * static_cast<std::size_t>(ch), static_cast<std::size_t>(ch)));
    }
}

DotCounts AngularPattern::counts() const {
    DotCounts counts;
    const optics::Lattice& lattice = meso_.lattice();
    const int n = options_.table_size;
    for (std::size_t c = 0; c < tables_.size(); ++c) {
        const optics::CellIndex cell{static_cast<int>(c % static_cast<std::size_t>(lattice.count_x())),
                                     static_cast<int>(c / static_cast<std::size_t>(lattice.count_x()))};
        for (int iy = 0; iy < n; ++iy)
            for (int ix = 0; ix < n; ++ix) {
                const Eigen::Vector2d offset(-half_box_.x() + 2.0 * half_box_.x() * ix / (n - 1),
                                             -half_box_.y() + 2.0 * half_box_.y() * iy / (n - 1));
                if (!lattice.cell_contains(cell, lattice.center(cell) + offset)) continue;
                switch (static_cast<optics::DotLight>(tables_[c].light[static_cast<std::size_t>(iy * n + ix)])) {
                    case optics::DotLight::Lit: ++counts.lit; break;
                    case optics::DotLight::Unlit: ++counts.unlit; break;
                    case optics::DotLight::Crossed: ++counts.crossed; break;
                    case optics::DotLight::Lost: ++counts.lost; break;
                }
            }
    }
    return counts;
}

PatternAttributes AngularPattern::attributes() const {
    const optics::Design& design = optics_.design();
    const optics::Lattice& lattice = meso_.lattice();
    return {{"design", design.file},
            {"design_kind", std::string(optics::to_string(design.kind))},
            {"kind", "angular"},
            {"model", std::string(optics::to_string(options_.model))},
            {"bins", std::to_string(lattice.count_x()) + "x" + std::to_string(lattice.count_y())},
            {"macro_grid", std::to_string(macro_x_) + "x" + std::to_string(macro_y_)},
            {"bin_samples", std::to_string(options_.bin_samples)}};
}

LetterField letter_field_for(const optics::MesoPixelOptics& meso, optics::Model model,
                             const std::string& characters) {
    const optics::Lattice& lattice = meso.lattice();
    std::vector<Eigen::Vector3d> centres;
    for (int j = 0; j < lattice.count_y(); ++j)
        for (int i = 0; i < lattice.count_x(); ++i) centres.push_back(field_light_of(meso.bin({i, j}, model, 1).centre));
    if (characters.size() < centres.size())
        throw InputError("--text: " + std::to_string(centres.size()) + " incident bins need " +
                         std::to_string(centres.size()) + " characters, got " + std::to_string(characters.size()));
    const double half = std::abs(meso.output_gain()) * 0.375 * std::min(lattice.pitch_x(), lattice.pitch_y());
    return LetterField(centres, characters, {half, half});
}

DiamondField diamond_field_for(const optics::MesoPixelOptics& meso, optics::Model model) {
    const optics::Lattice& lattice = meso.lattice();
    double light = 0.0;
    for (int j = 0; j < lattice.count_y(); ++j)
        for (int i = 0; i < lattice.count_x(); ++i) {
            const Eigen::Vector3d d = meso.bin({i, j}, model, 1).centre;
            light = std::max({light, std::abs(d.x() / d.z()), std::abs(d.y() / d.z())});
        }
    const double view = std::abs(meso.output_gain()) * 0.375 * lattice.pitch_x();
    return DiamondField(light > 0.0 ? light : 0.1, view);
}

double estimate_white(const PatternSource& source, double percentile, int rows) {
    const PatternGeometry& g = source.geometry();
    const int ch = source.channels();
    const int count = std::min(rows, g.height);
    std::vector<float> values(static_cast<std::size_t>(count) * static_cast<std::size_t>(g.width) * static_cast<std::size_t>(ch));
    const std::size_t row_size = static_cast<std::size_t>(g.width) * static_cast<std::size_t>(ch);
    parallel_for_chunks(static_cast<std::size_t>(count), 1, [&](std::size_t begin, std::size_t end) {
        for (std::size_t k = begin; k < end; ++k) {
            const int py = static_cast<int>((static_cast<double>(k) + 0.5) * g.height / count);
            source.render_row(py, std::span<float>(values.data() + k * row_size, row_size));
        }
    });
    if (values.empty()) return 0.0;
    const double q = std::clamp(percentile, 0.0, 100.0) / 100.0;
    const auto nth = values.begin() + static_cast<std::ptrdiff_t>(std::floor(q * double(values.size() - 1)));
    std::nth_element(values.begin(), nth, values.end());
    return *nth;
}

}  // namespace rfd::patterns
