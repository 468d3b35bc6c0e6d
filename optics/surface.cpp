#include "optics/surface.hpp"

#include <cmath>

namespace rfd::optics {

double curvature_of(const Profile& profile) {
    if (const auto* conic = std::get_if<Conic>(&profile)) return conic->curvature;
    return 0.0;
}

double conic_of(const Profile& profile) {
    if (const auto* conic = std::get_if<Conic>(&profile)) return conic->conic_constant;
    return 0.0;
}

std::optional<double> sag(const Profile& profile, double r2) {
    const double c = curvature_of(profile);
    if (c == 0.0) return 0.0;
    const double k = conic_of(profile);
    const double root = 1.0 - (1.0 + k) * c * c * r2;
    if (root < 0.0) return std::nullopt;
    return c * r2 / (1.0 + std::sqrt(root));
}

Eigen::Vector3d normal_at(const Profile& profile, const Eigen::Vector3d& p) {
    const double c = curvature_of(profile);
    if (c == 0.0) return Eigen::Vector3d::UnitZ();
    const double k = conic_of(profile);
    // Gradient of F = c (x^2 + y^2 + (1+k) z^2) - 2 z, negated so that it points to +z
    // at the vertex where the gradient is (0, 0, -2).
    Eigen::Vector3d n(-c * p.x(), -c * p.y(), 1.0 - c * (1.0 + k) * p.z());
    return n.normalized();
}

std::optional<double> intersect(const Profile& profile, const Eigen::Vector3d& o,
                                const Eigen::Vector3d& d, double t_min) {
    const double c = curvature_of(profile);
    if (c == 0.0) {
        if (d.z() == 0.0) return std::nullopt;
        const double t = -o.z() / d.z();
        if (t > t_min) return t;
        return std::nullopt;
    }
    const double k1 = 1.0 + conic_of(profile);
    // F(o + t d) = a t^2 + 2 b t + q = 0 with F = c (x^2 + y^2 + (1+k) z^2) - 2 z.
    const double a = c * (d.x() * d.x() + d.y() * d.y() + k1 * d.z() * d.z());
    const double b = c * (o.x() * d.x() + o.y() * d.y() + k1 * o.z() * d.z()) - d.z();
    const double q = c * (o.x() * o.x() + o.y() * o.y() + k1 * o.z() * o.z()) - 2.0 * o.z();
    const double discriminant = b * b - a * q;
    if (discriminant < 0.0) return std::nullopt;
    // Roots without cancellation: t1 = q / s and t2 = s / a with s = -(b + sign(b) sqrt(D)).
    // t1 is the root that stays finite as c -> 0 (the plane's root).
    const double s = -(b + std::copysign(std::sqrt(discriminant), b));
    double roots[2] = {HUGE_VAL, HUGE_VAL};
    if (s != 0.0) roots[0] = q / s;
    if (a != 0.0) roots[1] = s / a;
    if (roots[0] > roots[1]) std::swap(roots[0], roots[1]);
    // A ray that starts on the surface has a root at t = 0 that rounding turns into
    // +-1e-17. Leaving the surface (t_min >= 0), that root is where it came from: no hit
    // closer than kSelfIntersection. Not yet across it (t_min < 0: it sits where the
    // surface touches the one it came through), that root is the crossing when the ray
    // goes from the front (F > 0) to the back (F < 0) there: dF/dt = 2 (a t + b) < 0.
    for (double t : roots) {
        if (!(t > t_min) || !std::isfinite(t)) continue;
        if (t <= kSelfIntersection && !(t_min < 0.0 && a * t + b < 0.0)) continue;
        // Keep only the vertex branch: there, (1+k) c z <= 1 (the far sheet of a sphere
        // or ellipsoid and the second sheet of a hyperboloid lie beyond).
        const double z = o.z() + t * d.z();
        if (k1 * c * z <= 1.0) return t;
    }
    return std::nullopt;
}

std::optional<Eigen::Vector3d> refract(const Eigen::Vector3d& d, const Eigen::Vector3d& n,
                                       double eta) {
    // Orient the normal against the incoming ray.
    Eigen::Vector3d normal = n;
    double cos_i = -normal.dot(d);
    if (cos_i < 0.0) {
        normal = -normal;
        cos_i = -cos_i;
    }
    const double sin2_t = eta * eta * (1.0 - cos_i * cos_i);
    if (sin2_t > 1.0) return std::nullopt;
    const double cos_t = std::sqrt(1.0 - sin2_t);
    Eigen::Vector3d t = eta * d + (eta * cos_i - cos_t) * normal;
    return t.normalized();
}

double fresnel_transmittance(double cos_i, double cos_t, double n1, double n2) {
    const double rs = (n1 * cos_i - n2 * cos_t) / (n1 * cos_i + n2 * cos_t);
    const double rp = (n2 * cos_i - n1 * cos_t) / (n2 * cos_i + n1 * cos_t);
    return 1.0 - 0.5 * (rs * rs + rp * rp);
}

}  // namespace rfd::optics
