#pragma once
// Fitted bases of a reflectance field, as RTI tools fit them: per pixel and channel,
// R(d) ~ sum_k c_k b_k(d), the same functions b_k of the light direction d for every pixel,
// the coefficients c by least squares over the field's lights. The fit is linear in the
// samples, so one matrix serves every pixel: c = A^+ y, A (lights x functions) the design
// matrix, and leaving light j out has a closed form (the PRESS residual of linear
// regression): y_j - prediction without j = r_j / (1 - h_jj), r the residual of the full fit
// and h_jj the leverage of light j (the diagonal of A A^+).
//
// The functions, as OpenLIME evaluates them (its ShaderRTI, the reference for the files CNR
// relight writes), so that a fit exported for it renders as it was fitted:
//  - ptm: 1, x, y, x^2, x y, y^2 of the direction's (x, y) (Malzbender et al. 2001,
//    biquadratic; 6 functions);
//  - hsh2, hsh3, hsh4: hemispherical harmonics (Gautron et al. 2004) up to degree 1, 2, 3
//    (4, 9, 16 functions): K_l^m P_l^|m|(2 cos(theta) - 1) times sqrt(2) cos(m phi) (m > 0),
//    1 (m = 0) or sqrt(2) sin(|m| phi) (m < 0), ordered m = l, ..., -l within each degree,
//    theta clamped to 90 - 8.6 degrees (OpenLIME's minimum elevation, 0.15 rad). OpenLIME
//    flips the sign of the two m = +-2 functions; so does rfd, so coefficients carry over.
//    OpenLIME renders up to hsh3.
//
// Example: const BasisFit fit(Basis::Ptm, field.directions());
//          fit.values(d)  // the 6 function values at d

#include <array>
#include <cstddef>
#include <vector>

#include <Eigen/Core>

#include "core/names.hpp"

namespace rfd::relight {

enum class Basis { Ptm, Hsh2, Hsh3, Hsh4 };
inline constexpr std::array kBasisNames{Named{Basis::Ptm, "ptm"}, Named{Basis::Hsh2, "hsh2"},
                                        Named{Basis::Hsh3, "hsh3"}, Named{Basis::Hsh4, "hsh4"}};

/// Functions in `basis`: 6, 4, 9, 16.
int basis_size(Basis basis);

/// The functions of `basis` at unit direction `d` (toward the light, field frame).
Eigen::VectorXd basis_values(Basis basis, const Eigen::Vector3d& d);

/// The least-squares fit of a basis over a set of light directions.
class BasisFit {
public:
    /// InputError when the lights cannot determine the basis: fewer lights than functions,
    /// or lights that leave a combination of the functions unseen (rank below their count).
    BasisFit(Basis basis, const std::vector<Eigen::Vector3d>& directions);

    Basis basis() const { return basis_; }
    int size() const { return static_cast<int>(solve_.rows()); }
    std::size_t lights() const { return static_cast<std::size_t>(design_.rows()); }
    /// A (lights x functions).
    const Eigen::MatrixXd& design() const { return design_; }
    /// A^+ (functions x lights): coefficients = solve() * samples of the lights.
    const Eigen::MatrixXd& solve() const { return solve_; }
    /// h_jj per light; 1 where a light alone pins a combination (no prediction without it).
    const Eigen::VectorXd& leverage() const { return leverage_; }
    /// True when light j can be predicted from the others (leverage below 1 - 1e-9).
    bool predictable_without(std::size_t j) const { return leverage_[static_cast<Eigen::Index>(j)] < 1.0 - 1e-9; }

private:
    Basis basis_;
    Eigen::MatrixXd design_, solve_;
    Eigen::VectorXd leverage_;
};

}  // namespace rfd::relight
