#include "optics/system.hpp"

#include "core/error.hpp"

namespace rfd::optics {

std::size_t SequentialSystem::find(const std::string& label) const {
    for (std::size_t s = 0; s < surfaces.size(); ++s)
        if (surfaces[s].label == label) return s;
    throw InputError("system '" + name + "' has no surface labelled '" + label + "'");
}

const Lattice* SequentialSystem::lattice() const {
    for (const auto& surface : surfaces)
        if (const auto* arrayed = std::get_if<LatticeAperture>(&surface.aperture))
            return &arrayed->lattice;
    return nullptr;
}

void SequentialSystem::validate() const {
    const Lattice* first = lattice();
    for (std::size_t s = 0; s < surfaces.size(); ++s) {
        RFD_CHECK_MSG(surfaces[s].index_after >= 1.0, surfaces[s].label);
        if (s > 0) RFD_CHECK_MSG(surfaces[s].z >= surfaces[s - 1].z, surfaces[s].label);
        if (const auto* arrayed = std::get_if<LatticeAperture>(&surfaces[s].aperture)) {
            const Lattice& l = arrayed->lattice;
            RFD_CHECK_MSG(l.kind() == first->kind() && l.pitch_x() == first->pitch_x() &&
                              l.pitch_y() == first->pitch_y() &&
                              l.count_x() == first->count_x() && l.count_y() == first->count_y(),
                          "arrayed surfaces of one system must share their lattice");
        }
    }
}

SequentialSystem reversed(const SequentialSystem& system) {
    SequentialSystem back;
    back.name = system.name + " (reversed)";
    back.index_before = system.surfaces.empty() ? system.index_before : system.surfaces.back().index_after;
    for (std::size_t k = system.surfaces.size(); k-- > 0;) {
        Surface surface = system.surfaces[k];
        surface.z = -surface.z;
        if (auto* conic = std::get_if<Conic>(&surface.profile)) conic->curvature = -conic->curvature;
        surface.index_after = system.index_in_front(k);
        back.surfaces.push_back(std::move(surface));
    }
    return back;
}

}  // namespace rfd::optics
