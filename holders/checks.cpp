#include "holders/checks.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "core/parallel.hpp"
#include "core/text.hpp"

namespace rfd::holders {
namespace {

}  // namespace

std::vector<std::string> HolderCheck::problems(const Tolerances& t) const {
    std::vector<std::string> out;
    for (const PartCheck& p : parts) {
        for (const std::string& m : p.mesh.problems()) out.push_back("part " + p.name + ": " + m);
        if (std::abs(p.volume_error) > t.volume)
            out.push_back("part " + p.name + ": volume " + format_fixed(p.mesh.volume_mm3, 1) + " mm^3, the design gives " +
                          format_fixed(p.expected_volume, 1) + " mm^3 (" + format_fixed(100 * p.volume_error, 2) + " %)");
        if (p.box_error > t.box)
            out.push_back("part " + p.name + ": bounding box off the design by " + format_fixed(p.box_error, 3) + " mm");
    }
    for (const SeatCheck& s : seats) {
        if (!s.measured_z)
            out.push_back("seat of plane " + s.plane + ": no face found at the seat");
        else if (std::abs(s.error()) > t.seat)
            out.push_back("seat of plane " + s.plane + " is at z = " + format_fixed(*s.measured_z, 3) + " mm, the design needs " +
                          format_fixed(s.expected_z, 3) + " mm");
    }
    if (clearance.rays == 0) out.push_back("beam clearance: no ray of the field of view passes the clear apertures");
    if (clearance.blocked > 0)
        out.push_back("beam clearance: " + std::to_string(clearance.blocked) + " of " + std::to_string(clearance.rays) +
                      " rays of the field of view touch the holder (part " + clearance.closest_part + ", near x = " +
                      format_fixed(clearance.closest.x(), 2) + ", y = " + format_fixed(clearance.closest.y(), 2) + ", z = " +
                      format_fixed(clearance.closest.z(), 2) + " mm)");
    return out;
}

HolderCheck check_holder(const Holder& holder, const optics::Design& design,
                         const std::vector<std::pair<PrintedPart, std::filesystem::path>>& stls,
                         const BeamSampling& sampling) {
    HolderCheck check;
    std::vector<MeshProbe> probes;
    for (const auto& [part, stl] : stls) {
        PartCheck p;
        p.name = part.name;
        p.stl = stl;
        p.mesh = check_stl(stl);
        p.expected_volume = holder.part_volume(part);
        p.volume_error = p.mesh.volume_mm3 / p.expected_volume - 1;
        p.expected_box = holder.part_box(part);
        for (int k = 0; k < 3; ++k)
            p.box_error = std::max({p.box_error, std::abs(p.mesh.min_mm[k] - p.expected_box[0][k]),
                                    std::abs(p.mesh.max_mm[k] - p.expected_box[1][k])});
        check.parts.push_back(p);
        probes.emplace_back(stl);
    }

    // Seats: probe each in the part that holds the probe point.
    for (const Seat& seat : holder.seats) {
        for (std::size_t k = 0; k < stls.size(); ++k) {
            const PrintedPart& part = stls[k].first;
            if (seat.probe.y() < part.y0.value || seat.probe.y() > part.y1.value) continue;
            SeatCheck s;
            s.plane = seat.plane;
            s.what = seat.what;
            s.part = part.name;
            s.expected_z = seat.z;
            const int direction = seat.z < seat.probe_from_z ? -1 : 1;
            s.measured_z = probes[k].first_hit_z(seat.probe.x(), seat.probe.y(), seat.probe_from_z, direction);
            check.seats.push_back(s);
        }
    }

    // Beam clearance, cell by cell (Design IV repeats the cell).
    const bool angular = design.kind == optics::DesignKind::III || design.kind == optics::DesignKind::IV;
    const std::vector<BeamPath> paths = beam_paths(design, holder.apertures, holder.z_front.value,
                                                   angular ? std::optional<double>(holder.z_back.value) : std::nullopt,
                                                   sampling);
    check.clearance.rays = paths.size();
    double reach = 0.0;
    for (const Section& s : holder.sections) reach = std::max(reach, s.half_height_max());
    // Per ray, in parallel; the closest approach is reduced in ray order afterwards, so the
    // report does not depend on the scheduling.
    struct RayResult {
        bool blocked = false;
        double closest = 1e300;
        Eigen::Vector3d where = Eigen::Vector3d::Zero();
        std::size_t part = 0;
        std::size_t segments = 0;
    };
    std::vector<RayResult> results(paths.size());
    for (std::size_t k = 0; k < stls.size(); ++k) {
        const PrintedPart& part = stls[k].first;
        for (const Eigen::Vector2d& cell : holder.cells) {
            if (cell.y() + reach < part.y0.value || cell.y() - reach > part.y1.value) continue;
            const Eigen::Vector3d offset(cell.x(), cell.y(), 0.0);
            parallel_for_chunks(paths.size(), 64, [&](std::size_t begin, std::size_t end) {
                for (std::size_t r = begin; r < end; ++r) {
                    RayResult& result = results[r];
                    const auto& points = paths[r].points;
                    for (std::size_t s = 0; s + 1 < points.size(); ++s) {
                        const Eigen::Vector3d a = points[s] + offset, b = points[s + 1] + offset;
                        ++result.segments;
                        if (probes[k].hits(a, b)) result.blocked = true;
                        const int samples = std::max(1, static_cast<int>(std::ceil((b - a).norm() / 0.5)));
                        for (int q = 0; q <= samples; ++q) {
                            const Eigen::Vector3d p = a + (b - a) * (static_cast<double>(q) / samples);
                            const double d = probes[k].distance(p);
                            if (d < result.closest) result.closest = d, result.where = p, result.part = k;
                        }
                    }
                }
            });
        }
    }
    for (const RayResult& r : results) {
        check.clearance.segments += r.segments;
        check.clearance.blocked += r.blocked;
        if (r.closest < check.clearance.min_clearance) {
            check.clearance.min_clearance = r.closest;
            check.clearance.closest = r.where;
            check.clearance.closest_part = stls[r.part].first.name;
        }
    }
    return check;
}

}  // namespace rfd::holders
