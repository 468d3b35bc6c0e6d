#pragma once
// The fit-test coupon: before printing a holder, print this and find which clearance makes
// a slip fit on your printer. Two rows of seats, one round (a lens of the given diameter)
// and one square (a lenslet array of the given side), stepping the radial clearance by
// 0.05 mm from 0.2 mm below the profile's clearance to 0.2 mm above it (never below 0).
// Seat k carries k + 1 dimples on its front edge. Put the value that fits into the
// printer profile's clearance_mm.
//
// Frame: the coupon lies on z = 0, rows along x, millimetres.

#include <array>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "holders/profile.hpp"

namespace rfd::holders {

struct Coupon {
    std::string scad;
    std::vector<double> clearances;   ///< radial clearance of seat k, mm
    double volume = 0.0;              ///< mm^3, closed form
    std::array<Eigen::Vector3d, 2> box;
};

Coupon make_coupon(double diameter, double square, const HolderProfile& profile);

}  // namespace rfd::holders
