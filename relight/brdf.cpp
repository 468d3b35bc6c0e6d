#include "relight/brdf.hpp"

#include <algorithm>
#include <cmath>

#include "core/units.hpp"

namespace rfd::relight {
namespace {

double pow5(double x) {
    const double x2 = x * x;
    return x2 * x2 * x;
}

// Smith's Lambda for GGX, as a function of the cosine to the normal.
double smith_lambda(double cos_theta, double alpha) {
    const double c2 = cos_theta * cos_theta;
    const double tan2 = std::max(0.0, 1.0 - c2) / c2;
    return 0.5 * (std::sqrt(1.0 + alpha * alpha * tan2) - 1.0);
}

}  // namespace

Rgb lambert_brdf(const Eigen::Vector3d& n, const Eigen::Vector3d& l, const Rgb& albedo) {
    if (n.dot(l) <= 0.0) return Rgb::Zero();
    return albedo / kPi;
}

Rgb glossy_brdf(const Eigen::Vector3d& n, const Eigen::Vector3d& v, const Eigen::Vector3d& l,
                const Rgb& diffuse, const Rgb& specular, double alpha) {
    const double nl = n.dot(l);
    const double nv = n.dot(v);
    if (nl <= 0.0 || nv <= 0.0) return Rgb::Zero();
    const Rgb diffuse_term = (28.0 / (23.0 * kPi)) * diffuse * (1.0 - specular) *
                             (1.0 - pow5(1.0 - 0.5 * nl)) * (1.0 - pow5(1.0 - 0.5 * nv));
    const Eigen::Vector3d h = (v + l).normalized();
    const double nh = std::max(0.0, n.dot(h));
    const double a2 = alpha * alpha;
    const double denom = nh * nh * (a2 - 1.0) + 1.0;
    const double distribution = a2 / (kPi * denom * denom);
    const double masking = 1.0 / (1.0 + smith_lambda(nv, alpha) + smith_lambda(nl, alpha));
    const double vh = std::clamp(v.dot(h), 0.0, 1.0);
    const Rgb fresnel = specular + (1.0 - specular) * pow5(1.0 - vh);
    return diffuse_term + fresnel * (distribution * masking / (4.0 * nl * nv));
}

Rgb phong_fresnel_brdf(const Eigen::Vector3d& n, const Eigen::Vector3d& v, const Eigen::Vector3d& l,
                       const Rgb& albedo, double exponent, double ior) {
    const double nl = n.dot(l);
    if (nl <= 0.0 || n.dot(v) <= 0.0) return Rgb::Zero();
    const Eigen::Vector3d r = 2.0 * nl * n - l;
    const double rv = r.dot(v);
    double lobe = 0.0;
    if (rv > 0.0) {
        const Eigen::Vector3d h = (v + l).normalized();
        lobe = fresnel_dielectric(v.dot(h), 1.0, ior) * (exponent + 2.0) / (2.0 * kPi) * std::pow(rv, exponent);
    }
    return albedo / kPi + lobe;
}

double fresnel_dielectric(double cos_incidence, double n1, double n2) {
    const double ci = std::clamp(cos_incidence, 0.0, 1.0);
    const double eta = n1 / n2;
    const double sin2_t = eta * eta * std::max(0.0, 1.0 - ci * ci);
    if (sin2_t >= 1.0) return 1.0;
    const double ct = std::sqrt(1.0 - sin2_t);
    const double rs = (n1 * ci - n2 * ct) / (n1 * ci + n2 * ct);
    const double rp = (n2 * ci - n1 * ct) / (n2 * ci + n1 * ct);
    return 0.5 * (rs * rs + rp * rp);
}

}  // namespace rfd::relight
