#pragma once
// A sequential optical system: surfaces met in order by every ray, in one shared frame
// (see surface.hpp: z along the axis in the direction light travels, millimetres).
//
// Invariants (checked by validate()): vertex positions never decrease, indices are >= 1,
// every arrayed surface of one system uses the same lattice geometry, so a lenslet index
// means the same lenslet on every arrayed surface.

#include <string>
#include <vector>

#include "optics/surface.hpp"

namespace rfd::optics {

struct SequentialSystem {
    std::string name;
    double index_before = 1.0;      ///< medium the light comes from
    std::vector<Surface> surfaces;  ///< in the order light meets them

    /// Index of the medium in front of surface s.
    double index_in_front(std::size_t s) const {
        return s == 0 ? index_before : surfaces[s - 1].index_after;
    }
    /// Index of the first surface with this label; throws InputError if none.
    std::size_t find(const std::string& label) const;
    /// The lattice of the first arrayed surface, or nullptr for a system of plain lenses.
    const Lattice* lattice() const;
    /// Programmer check of the invariants above.
    void validate() const;
};

/// The same system traversed backwards: z -> -z (surface order and the media reversed),
/// every curvature's sign flipped, apertures kept. A ray leaving the original system and
/// sent back (z and direction negated) retraces its path through the reversed system.
/// The reversed system's medium in front is the original's last medium.
SequentialSystem reversed(const SequentialSystem& system);

}  // namespace rfd::optics
