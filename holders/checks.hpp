#pragma once
// The checks of a built holder, on its STLs:
//  - every printed part's mesh is a solid a slicer takes (mesh_check.hpp), with the volume
//    and bounding box the holder's closed form gives;
//  - every seat is where its plane needs it: a line along z through a point of the seat
//    face, followed from inside the pocket, meets the mesh at the seat's z (within 0.05 mm);
//  - beam clearance: the rays of the design's full field of view that pass the clear
//    apertures (beam.hpp, traced again on a finer grid than the generator used) do not
//    touch holder material, and how close they come.

#include <array>
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "holders/beam.hpp"
#include "holders/holder.hpp"
#include "holders/mesh_check.hpp"
#include "optics/design.hpp"

namespace rfd::holders {

struct PartCheck {
    std::string name;
    std::filesystem::path stl;
    MeshCheck mesh;
    double expected_volume = 0.0;             ///< mm^3, closed form
    std::array<Eigen::Vector3d, 2> expected_box;
    double volume_error = 0.0;                ///< relative, mesh against closed form
    double box_error = 0.0;                   ///< mm, largest corner difference
};

struct SeatCheck {
    std::string plane, what, part;
    double expected_z = 0.0;
    std::optional<double> measured_z;         ///< nullopt: the probe met no face
    double error() const { return measured_z ? *measured_z - expected_z : 1e300; }
};

struct ClearanceCheck {
    std::size_t rays = 0;                     ///< rays of the field of view inside the clear apertures
    std::size_t segments = 0;                 ///< straight pieces tested against the parts
    std::size_t blocked = 0;                  ///< rays that touch holder material
    double min_clearance = 1e300;             ///< mm, closest approach of any ray to the holder
    Eigen::Vector3d closest = Eigen::Vector3d::Zero();  ///< where
    std::string closest_part;
};

struct Tolerances {
    double volume = 0.005;    ///< relative
    double box = 0.02;        ///< mm
    double seat = 0.05;       ///< mm
};

struct HolderCheck {
    std::vector<PartCheck> parts;
    std::vector<SeatCheck> seats;
    ClearanceCheck clearance;
    /// Every failed check, one sentence each; empty when the holder passes.
    std::vector<std::string> problems(const Tolerances& tolerances = {}) const;
};

/// Checks the STLs of `holder`'s printed parts: (part, stl path) for each.
HolderCheck check_holder(const Holder& holder, const optics::Design& design,
                         const std::vector<std::pair<PrintedPart, std::filesystem::path>>& stls,
                         const BeamSampling& sampling = {9, 12});

}  // namespace rfd::holders
