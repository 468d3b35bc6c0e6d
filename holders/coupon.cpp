#include "holders/coupon.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <sstream>

#include "holders/expr.hpp"

namespace rfd::holders {

Coupon make_coupon(double diameter, double square, const HolderProfile& profile) {
    Coupon c;
    for (int k = -4; k <= 4; ++k) {
        const double value = std::round((profile.clearance + 0.05 * k) * 1000) / 1000;
        if (value >= 0) c.clearances.push_back(value);
    }
    const double height = 4.0, dimple_d = 1.0, dimple_depth = 0.6;
    const double cell = std::max(diameter, square) + 2 * c.clearances.back() + 2 * profile.min_wall + 2.0;
    const int n = static_cast<int>(c.clearances.size());
    const int fn = circle_facets(diameter + 1.0, profile.circle_tolerance);
    const int dimple_fn = 16;
    const double pi = std::numbers::pi;

    std::ostringstream out;
    out << "// Fit-test coupon (rfd holder coupon): seats for a " << scad_number(diameter) << " mm round part and a "
        << scad_number(square) << " mm square part,\n// stepping the radial clearance. Seat k (k + 1 dimples on its front "
        << "edge) has clearance clearances[k].\n// Print it lying flat; the clearance whose seat takes the part with a "
           "slip fit goes into the\n// printer profile (clearance_mm).\n\n"
        << "part = \"coupon\";\n\n"
        << "diameter = " << scad_number(diameter) << ";  // round part (lens)\n"
        << "square = " << scad_number(square) << ";  // square part (lenslet array)\n"
        << "clearances = [";
    for (int k = 0; k < n; ++k) out << (k ? ", " : "") << scad_number(c.clearances[static_cast<std::size_t>(k)]);
    out << "];\n"
        << "height = " << scad_number(height) << ";\n"
        << "cell = " << scad_number(cell) << ";  // one seat with its walls\n"
        << "eps = 0.01;\n\n"
        << "difference() {\n    cube([len(clearances) * cell, 2 * cell, height]);\n"
        << "    for (k = [0 : len(clearances) - 1]) {\n"
        << "        // Bores are circumscribed polygons, so never smaller than their diameter.\n"
        << "        translate([(k + 0.5) * cell, 0.5 * cell, -1])\n"
        << "            cylinder(d = (diameter + 2 * clearances[k]) / cos(180 / " << fn << "), h = height + 2, $fn = " << fn << ");\n"
        << "        translate([(k + 0.5) * cell, 1.5 * cell, height / 2])\n"
        << "            cube([square + 2 * clearances[k], square + 2 * clearances[k], height + 2], center = true);\n"
        << "        for (p = [0 : k])\n"
        << "            translate([k * cell + 1.5 + 1.6 * p, 1.0, height - " << scad_number(dimple_depth) << "])\n"
        << "                cylinder(d = " << scad_number(dimple_d) << ", h = " << scad_number(dimple_depth) << " + 1, $fn = "
        << dimple_fn << ");\n    }\n}\n";
    c.scad = out.str();

    double volume = n * cell * 2 * cell * height;
    for (int k = 0; k < n; ++k) {
        const double clearance = c.clearances[static_cast<std::size_t>(k)];
        const double r = (diameter + 2 * clearance) / 2;
        volume -= fn * r * r * std::tan(pi / fn) * height;
        volume -= (square + 2 * clearance) * (square + 2 * clearance) * height;
        const double dr = dimple_d / 2;
        volume -= (k + 1) * dimple_fn / 2.0 * dr * dr * std::sin(2 * pi / dimple_fn) * dimple_depth;
    }
    c.volume = volume;
    c.box = {Eigen::Vector3d::Zero(), Eigen::Vector3d(n * cell, 2 * cell, height)};
    return c;
}

}  // namespace rfd::holders
