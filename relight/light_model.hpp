#pragma once
// How a field predicts a light direction it was not captured under: every way rfd knows is a
// weighted sum of the captured images, R(d) ~ sum_i w_i(d) R_i, with weights that depend on
// the directions alone:
//  - interpolation (relight/interpolation.hpp): the Delaunay triangle's barycentric weights
//    (delaunay), eq. 4.6 as written (solid-angle), the nearest light (nearest);
//  - a fitted basis (relight/basis.hpp): c = A^+ y, R(d) = b(d)^T c, so w(d) = A^+^T b(d);
//  - radial basis functions as OpenLIME and CNR relight blend them (rbf): Gaussian weights
//    exp(-|d - d_i|^2 / sigma^2) over the lights, normalised, those below 0.001 dropped and
//    the rest normalised again;
//  - CNR relight's bilinear resampling (bilinear): the field resampled onto an R x R grid of
//    directions (the octahedral map OpenLIME's 'bln' shader reads: the hemisphere's |x|+|y|+|z|
//    = 1 diamond rotated 45 degrees onto a square) and blended bilinearly there. The grid's
//    values are linear in the images, g = M y with M = B + (A^T A + k I)^-1 A^T (I - A B): A
//    the bilinear weights of the captured lights in the grid, B the rbf weights of the grid's
//    nodes over the lights (a prior for nodes no light reaches), k the pull toward it; so
//    w(d) = a(d)^T M.
// So each relights a field through the same streamed pass (relight/render.hpp), and each has
// a leave-one-out matrix W (row j: the weights that predict light j from the others), whose
// error on a field follows from the field's Gram matrix G = sum over pixels and channels of
// y y^T (y the samples of one pixel's channel under every light): the squared errors are the
// diagonal of (I - W) G (I - W)^T. One pass over a field therefore ranks every model and
// tunes the RBF's sigma exactly.
//
// Example: LightModel model = parse_light_model("hsh3");
//          LightWeights weights(model, field.directions());
//          Eigen::VectorXd w = weights.at(d);

#include <cstddef>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "relight/basis.hpp"
#include "relight/field.hpp"
#include "relight/interpolation.hpp"

namespace rfd::relight {

struct LightModel {
    enum class Kind { Interpolation, Basis, Rbf, Bilinear };
    Kind kind = Kind::Interpolation;
    Interpolation interpolation = Interpolation::Delaunay;
    Basis basis = Basis::Ptm;
    double sigma = 0.0;  ///< rbf, bilinear (its prior): the Gaussian's width (unit-vector distance); 0 until chosen
    int resolution = 8;  ///< bilinear: the grid's side (CNR relight's default)
    double regularization = 0.1;  ///< bilinear: k, the pull toward the rbf prior (CNR relight's default)

    /// Whether the model has a width sigma to choose on the field (rbf, bilinear).
    bool has_sigma() const { return kind == Kind::Rbf || kind == Kind::Bilinear; }
    /// "delaunay", "hsh3", "rbf", "bilinear": the name --basis takes.
    std::string base_name() const;
    /// base_name(), and the width once chosen ("rbf 0.21"), for reports.
    std::string name() const;
};

/// The bilinear grid's sides allowed (the grid's fit solves a side^2 x side^2 system per light).
constexpr int kMinBilinearResolution = 2, kMaxBilinearResolution = 16;

/// Where unit d falls in the R x R octahedral grid: the four nodes (x + R y) around it and
/// their bilinear weights, as OpenLIME's 'bln' shader computes them.
struct GridCell {
    int node[4];
    double weight[4];
};
GridCell octahedral_cell(const Eigen::Vector3d& d, int resolution);
/// The unit direction of grid node (x, y).
Eigen::Vector3d octahedral_node(int x, int y, int resolution);
/// M (R^2 x lights): the grid's values from the lights' (see the header); `skip` (an index, or
/// none) is left out, its column zero.
Eigen::MatrixXd bilinear_grid(const std::vector<Eigen::Vector3d>& directions, const LightModel& model,
                              std::size_t skip = static_cast<std::size_t>(-1));

/// The names --basis takes, in the order reports list them.
std::vector<std::string> light_model_names();
/// One of light_model_names(); InputError naming `option` and the choices otherwise.
LightModel parse_light_model(const std::string& name, const std::string& option = "--basis");

/// OpenLIME's radial basis weights of `directions` at unit d (see the header); `skip` (an
/// index, or none) is left out, as leave-one-out needs.
Eigen::VectorXd rbf_weights(const std::vector<Eigen::Vector3d>& directions, double sigma, const Eigen::Vector3d& d,
                            std::size_t skip = static_cast<std::size_t>(-1));

/// A model's weights over one set of directions.
class LightWeights {
public:
    /// InputError when the directions cannot carry the model (a basis with more functions
    /// than lights, lights that do not triangulate, an rbf without its sigma).
    LightWeights(const LightModel& model, const std::vector<Eigen::Vector3d>& directions);
    ~LightWeights();
    LightWeights(LightWeights&&) noexcept;
    LightWeights& operator=(LightWeights&&) noexcept;

    const LightModel& model() const { return model_; }
    std::size_t size() const { return directions_.size(); }
    /// w(d), one weight per direction, for a unit d.
    Eigen::VectorXd at(const Eigen::Vector3d& d) const;
    /// Row j: the weights predicting light j from the others (0 on the diagonal). Rows of
    /// lights the others cannot predict (a basis' leverage of 1) are zero and
    /// `predictable[j]` false.
    Eigen::MatrixXd leave_one_out(std::vector<bool>& predictable) const;
    /// bilinear: M, the grid's values from the lights' (R^2 x lights).
    const Eigen::MatrixXd& grid() const { return grid_; }

private:
    LightModel model_;
    std::vector<Eigen::Vector3d> directions_;
    std::unique_ptr<SphericalInterpolator> interpolator_;
    std::unique_ptr<BasisFit> fit_;
    Eigen::MatrixXd grid_;  ///< bilinear: M
};

/// What one pass over a field tells every model: G (lights x lights, summed over pixels and
/// channels), the samples behind it, the brightest sample.
struct FieldGram {
    Eigen::MatrixXd gram;
    double samples_per_image = 0.0;
    double peak = 0.0;
};
/// G of `field`, read a band of rows at a time; pixels summed in a fixed order (the result
/// does not depend on the threads).
FieldGram field_gram(FieldReader& field);

/// G of a field held in memory.
FieldGram field_gram(const ReflectanceField& field);

/// Per light, the squared error of predicting it from the others with leave-one-out matrix W
/// (LightWeights::leave_one_out), summed over the field's samples: diag((I - W) G (I - W)^T).
Eigen::VectorXd leave_one_out_errors(const FieldGram& gram, const Eigen::MatrixXd& w);

/// The sigma of `model` (rbf, or bilinear's prior) with the least leave-one-out error on the
/// field: a golden-section search of log sigma over [0.02, 1.5] after a coarse scan (the
/// error is not convex in sigma).
double best_sigma(const FieldGram& gram, const std::vector<Eigen::Vector3d>& directions, LightModel model);

/// A model chosen by leave-one-out: the one of least summed error (linear) among `names`
/// (light_model_names()), the widths of rbf and bilinear tuned first. Models the lights cannot carry, or that
/// leave a light unpredictable, are not candidates; InputError when none is.
struct ModelChoice {
    LightModel model;
    std::vector<LightModel> candidates;
    std::vector<double> psnr;  ///< per candidate: PSNR of its summed error (linear, peak the brightest sample)
};
ModelChoice choose_light_model(const FieldGram& gram, const std::vector<Eigen::Vector3d>& directions,
                               const std::vector<std::string>& names);

/// `field` as `weights` predicts it at each of `directions`: image k = sum_i w_i(d_k) R_i.
ReflectanceField resampled_field(const ReflectanceField& field, const LightWeights& weights,
                                 const std::vector<Eigen::Vector3d>& directions);

}  // namespace rfd::relight
