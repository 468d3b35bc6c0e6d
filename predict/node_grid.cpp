#include "predict/node_grid.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "core/error.hpp"
#include "core/parallel.hpp"

namespace rfd::predict {
namespace {

// Nodes per side of a lenslet's grid at most: a finer grid than this is finer than any
// printer resolves under a lenslet of a few millimetres.
constexpr int kMaxNodesPerSide = 256;

}  // namespace

NodeGrid::NodeGrid(const optics::Lattice& lattice, const patterns::PatternGeometry& geometry, double spacing_mm)
    : lattice_(lattice), geometry_(geometry), spacing_(spacing_mm) {
    if (!(spacing_mm > 0.0) || !std::isfinite(spacing_mm))
        throw InputError("the node spacing must be a positive number of millimetres, got " + std::to_string(spacing_mm));
    const double half_w = 0.5 * lattice.pitch_x();
    const double half_h =
        lattice.kind() == optics::LatticeKind::Hexagonal ? lattice.circumradius() : 0.5 * lattice.pitch_y();
    // An even count per side: the outer nodes lie within half a spacing of the cell's
    // bounding box, and the axis between the middle two.
    const double per_side = 2.0 * std::ceil(std::max(half_w, half_h) / spacing_mm);
    if (per_side > kMaxNodesPerSide)
        throw InputError("a node spacing of " + std::to_string(spacing_mm) + " mm gives more than " +
                         std::to_string(kMaxNodesPerSide) + " nodes per side of a lenslet: use a larger one");
    nodes_x_ = 2 * static_cast<int>(std::ceil(half_w / spacing_mm));
    nodes_y_ = 2 * static_cast<int>(std::ceil(half_h / spacing_mm));
}

bool NodeGrid::stencil(const Eigen::Vector2d& point, Stencil& out) const {
    const double fx = point.x() / geometry_.dot_x + 0.5 * geometry_.width;
    const double fy = 0.5 * geometry_.height - point.y() / geometry_.dot_y;
    if (!(fx >= 0.0 && fy >= 0.0 && fx < geometry_.width && fy < geometry_.height)) return false;
    return dot_stencil(static_cast<int>(fx), static_cast<int>(fy), out);
}

void NodeGrid::local_stencil(const Eigen::Vector2d& offset, std::array<std::uint32_t, 4>& index,
                             std::array<double, 4>& weight) const {
    const double ga = std::clamp(offset.x() / spacing_ + 0.5 * (nodes_x_ - 1), 0.0, nodes_x_ - 1.0);
    const double gb = std::clamp(offset.y() / spacing_ + 0.5 * (nodes_y_ - 1), 0.0, nodes_y_ - 1.0);
    const int a = std::min(static_cast<int>(ga), nodes_x_ - 2), b = std::min(static_cast<int>(gb), nodes_y_ - 2);
    const double ta = ga - a, tb = gb - b;
    const auto base = static_cast<std::uint32_t>((b * nodes_x_ + a) * 3);
    const auto row = static_cast<std::uint32_t>(nodes_x_ * 3);
    index = {base, base + 3, base + row, base + row + 3};
    weight = {(1.0 - ta) * (1.0 - tb), ta * (1.0 - tb), (1.0 - ta) * tb, ta * tb};
}

bool NodeGrid::dot_stencil(int px, int py, Stencil& out) const {
    const Eigen::Vector2d centre = geometry_.dot_centre(px, py);
    out.cell = lattice_.cell_at(centre);
    if (!lattice_.contains(out.cell)) return false;
    std::array<std::uint32_t, 4> local{};
    local_stencil(centre - lattice_.center(out.cell), local, out.weight);
    const std::size_t base = lattice_.linear_index(out.cell) * per_lenslet() * 3;
    for (int n = 0; n < 4; ++n) out.index[n] = base + local[n];
    return true;
}

std::vector<Eigen::Vector2d> cell_offsets(const NodeGrid& nodes, bool between) {
    const optics::Lattice& lattice = nodes.lattice();
    const optics::CellIndex cell{0, 0};
    const Eigen::Vector2d centre = lattice.center(cell);
    std::vector<Eigen::Vector2d> offsets;
    const int shift = between ? 1 : 0;
    for (int b = 0; b < nodes.nodes_y() - shift; ++b)
        for (int a = 0; a < nodes.nodes_x() - shift; ++a) {
            const Eigen::Vector2d offset = nodes.node_offset(a, b) + 0.5 * shift * Eigen::Vector2d::Constant(nodes.spacing());
            if (lattice.cell_contains(cell, centre + offset)) offsets.push_back(offset);
        }
    return offsets;
}

std::vector<double> desired_transmittance(const patterns::Encoder& encoder, const print::ToneMap& tone,
                                          const Eigen::Vector3d& display_direction) {
    const optics::Lattice& lattice = encoder.lattice();
    const std::size_t lenslets = static_cast<std::size_t>(lattice.count_x()) * static_cast<std::size_t>(lattice.count_y());
    std::vector<double> out(lenslets * 3, 0.0);
    const Eigen::Vector3d d = display_direction.normalized();
    if (!(d.z() > 0.0)) return out;
    const Eigen::Vector3d v = encoder.options().mapping.field_direction(d);
    const relight::InterpolationWeights w = encoder.interpolator().weights(v, encoder.options().interpolation);
    const int channels = encoder.channels();
    const double scale = tone.brightness / (tone.white * d.z());
    for (int j = 0; j < lattice.count_y(); ++j)
        for (int i = 0; i < lattice.count_x(); ++i) {
            const std::size_t l = lattice.linear_index({i, j});
            for (int c = 0; c < 3; ++c) {
                double value = 0.0;
                for (std::size_t k = 0; k < w.count; ++k)
                    value += w.weight[k] * encoder.lenslet_sample({i, j}, w.index[k], channels == 3 ? c : 0);
                out[l * 3 + static_cast<std::size_t>(c)] = std::clamp(scale * value, 0.0, 1.0);
            }
        }
    return out;
}

std::vector<double> direct_nodes(const NodeGrid& nodes, const patterns::Encoder& encoder, const print::ToneMap& tone) {
    std::vector<double> u(nodes.size());
    const std::size_t per_lenslet = nodes.per_lenslet();
    parallel_for_chunks(per_lenslet, 4, [&](std::size_t begin, std::size_t end) {
        for (std::size_t n = begin; n < end; ++n) {
            const int a = static_cast<int>(n % static_cast<std::size_t>(nodes.nodes_x()));
            const int b = static_cast<int>(n / static_cast<std::size_t>(nodes.nodes_x()));
            const std::vector<double> desired =
                desired_transmittance(encoder, tone, encoder.incident_direction(nodes.node_offset(a, b)));
            for (std::size_t l = 0; l < nodes.lenslets(); ++l)
                for (std::size_t c = 0; c < 3; ++c) u[(l * per_lenslet + n) * 3 + c] = desired[l * 3 + c];
        }
    });
    return u;
}

std::vector<double> nodes_from_pattern(const NodeGrid& nodes, const optics::Transparency& pattern,
                                       const print::ToneMap& tone) {
    const optics::Lattice& lattice = nodes.lattice();
    std::vector<Eigen::Vector2d> points;
    points.reserve(nodes.size() / 3);
    for (int j = 0; j < lattice.count_y(); ++j)
        for (int i = 0; i < lattice.count_x(); ++i)
            for (int b = 0; b < nodes.nodes_y(); ++b)
                for (int a = 0; a < nodes.nodes_x(); ++a) points.push_back(lattice.center({i, j}) + nodes.node_offset(a, b));
    // Points in linear_index order: j outer, i inner, as the values are laid out.
    const std::size_t channels = static_cast<std::size_t>(pattern.channels());
    std::vector<float> sampled(points.size() * channels);
    pattern.sample(points, sampled);
    const double black = tone.stack_transmittance(0.0);
    std::vector<double> u(nodes.size());
    for (std::size_t p = 0; p < points.size(); ++p)
        for (std::size_t c = 0; c < 3; ++c)
            u[p * 3 + c] = std::clamp((sampled[p * channels + (channels == 3 ? c : 0)] - black) / (1.0 - black), 0.0, 1.0);
    return u;
}

NodeTransparency::NodeTransparency(const NodeGrid& nodes, std::vector<double> u, double black)
    : nodes_(nodes), u_(std::move(u)), black_(black) {
    RFD_CHECK(u_.size() == nodes.size() && black >= 0.0 && black < 1.0);
}

void NodeTransparency::sample(std::span<const Eigen::Vector2d> points, std::span<float> out) const {
    RFD_CHECK(out.size() == points.size() * 3);
    const patterns::PatternGeometry& g = nodes_.geometry();
    parallel_for_chunks(points.size(), 1 << 12, [&](std::size_t begin, std::size_t end) {
        NodeGrid::Stencil s;
        for (std::size_t k = begin; k < end; ++k) {
            const double fx = points[k].x() / g.dot_x + 0.5 * g.width, fy = 0.5 * g.height - points[k].y() / g.dot_y;
            const bool on_sheet = fx >= 0.0 && fy >= 0.0 && fx < g.width && fy < g.height;
            const bool printed = on_sheet && nodes_.dot_stencil(static_cast<int>(fx), static_cast<int>(fy), s);
            for (std::size_t c = 0; c < 3; ++c) {
                double u = 0.0;
                if (printed)
                    for (int n = 0; n < 4; ++n) u += s.weight[n] * u_[s.index[n] + c];
                out[k * 3 + c] = on_sheet ? static_cast<float>(black_ + (1.0 - black_) * u) : 0.0f;
            }
        }
    });
}

NodePattern::NodePattern(const NodeGrid& nodes, std::vector<double> u, int channels, double white, double brightness)
    : nodes_(nodes), u_(std::move(u)), channels_(channels), scale_(white / brightness) {
    RFD_CHECK(u_.size() == nodes.size() && (channels == 1 || channels == 3) && white > 0.0 && brightness > 0.0);
}

void NodePattern::render_row(int py, std::span<float> out) const {
    const int width = nodes_.geometry().width;
    const std::size_t channels = static_cast<std::size_t>(channels_);
    RFD_CHECK(out.size() == static_cast<std::size_t>(width) * channels);
    NodeGrid::Stencil s;
    for (int px = 0; px < width; ++px) {
        float* dot = out.data() + static_cast<std::size_t>(px) * channels;
        const bool printed = nodes_.dot_stencil(px, py, s);
        for (std::size_t c = 0; c < channels; ++c) {
            double value = 0.0;
            if (printed)
                for (int n = 0; n < 4; ++n) value += s.weight[n] * u_[s.index[n] + c];
            dot[c] = static_cast<float>(value * scale_);
        }
    }
}

}  // namespace rfd::predict
