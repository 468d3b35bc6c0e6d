#pragma once
// A reflectance field built in closed form: an orthographic view of a Lambertian sphere
// filling the image, normal n(x, y) = (X, Y, sqrt(1 - X^2 - Y^2)) with X, Y in [-1, 1]
// (x right, y up, the field frame), R_i = albedo / pi * max(0, n . d_i) (unit irradiance
// from d_i); black outside the sphere.

#include <cmath>
#include <optional>
#include <vector>

#include <Eigen/Core>

#include "core/sphere.hpp"
#include "core/units.hpp"
#include "relight/field.hpp"

namespace rfd::testing {

/// Normal of pixel (x, y) of a size x size image, or nullopt off the sphere.
inline std::optional<Eigen::Vector3d> sphere_normal(int x, int y, int size) {
    const double X = (x + 0.5) / size * 2.0 - 1.0, Y = 1.0 - (y + 0.5) / size * 2.0;
    const double r2 = X * X + Y * Y;
    if (r2 >= 1.0) return std::nullopt;
    return Eigen::Vector3d(X, Y, std::sqrt(1.0 - r2));
}

inline relight::ReflectanceField lambertian_sphere_field(const std::vector<Eigen::Vector3d>& directions,
                                                        int size, double albedo = 0.8) {
    relight::ReflectanceField field;
    for (const Eigen::Vector3d& d : directions) {
        field.directions.push_back(d.normalized());
        Image image(size, size, 1);
        for (int y = 0; y < size; ++y)
            for (int x = 0; x < size; ++x)
                if (const auto n = sphere_normal(x, y, size))
                    image.at(x, y, 0) = static_cast<float>(albedo / kPi * std::max(0.0, n->dot(d.normalized())));
        field.images.push_back(std::move(image));
    }
    return field;
}

using rfd::fibonacci_hemisphere;

}  // namespace rfd::testing
