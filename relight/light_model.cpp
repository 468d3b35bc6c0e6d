#include "relight/light_model.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <span>

#include "core/error.hpp"
#include "core/image.hpp"
#include "core/parallel.hpp"
#include "core/progress.hpp"
#include "relight/field.hpp"

namespace rfd::relight {

std::string LightModel::base_name() const {
    switch (kind) {
    case Kind::Interpolation: return std::string(name_of(kInterpolationNames, interpolation));
    case Kind::Basis: return std::string(name_of(kBasisNames, basis));
    case Kind::Rbf: return "rbf";
    case Kind::Bilinear: return "bilinear";
    }
    return "";
}

std::string LightModel::name() const {
    if (!has_sigma() || sigma <= 0.0) return base_name();
    char text[32];
    std::snprintf(text, sizeof text, " %.3g", sigma);
    return base_name() + text;
}

std::vector<std::string> light_model_names() {
    std::vector<std::string> names;
    for (const auto& method : kInterpolationNames) names.emplace_back(method.name);
    for (const auto& basis : kBasisNames) names.emplace_back(basis.name);
    names.emplace_back("rbf");
    names.emplace_back("bilinear");
    return names;
}

LightModel parse_light_model(const std::string& name, const std::string& option) {
    LightModel model;
    for (const auto& method : kInterpolationNames)
        if (name == method.name) {
            model.interpolation = method.value;
            return model;
        }
    for (const auto& basis : kBasisNames)
        if (name == basis.name) {
            model.kind = LightModel::Kind::Basis;
            model.basis = basis.value;
            return model;
        }
    if (name == "rbf" || name == "bilinear") {
        model.kind = name == "rbf" ? LightModel::Kind::Rbf : LightModel::Kind::Bilinear;
        return model;
    }
    std::string choices;
    for (const std::string& n : light_model_names()) choices += (choices.empty() ? "" : ", ") + n;
    throw InputError(option + ": expected one of " + choices + ", got '" + name + "'");
}

Eigen::VectorXd rbf_weights(const std::vector<Eigen::Vector3d>& directions, double sigma, const Eigen::Vector3d& d,
                            std::size_t skip) {
    RFD_CHECK(sigma > 0.0);
    const std::size_t n = directions.size();
    Eigen::VectorXd w = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(n));
    // exp(-(d2 - nearest d2) / sigma^2): the same weights once normalised, without the
    // underflow to 0 / 0 that a narrow sigma far from every light would give.
    double nearest = std::numeric_limits<double>::infinity();
    for (std::size_t i = 0; i < n; ++i)
        if (i != skip) nearest = std::min(nearest, (directions[i] - d).squaredNorm());
    double total = 0.0;
    for (std::size_t i = 0; i < n; ++i) {
        if (i == skip) continue;
        const double v = std::exp(-((directions[i] - d).squaredNorm() - nearest) / (sigma * sigma));
        w[static_cast<Eigen::Index>(i)] = v;
        total += v;
    }
    w /= total;
    // OpenLIME keeps the weights above 0.001 and normalises them again.
    double kept = 0.0;
    for (Eigen::Index i = 0; i < w.size(); ++i) {
        if (w[i] <= 0.001) w[i] = 0.0;
        kept += w[i];
    }
    return w / kept;
}

GridCell octahedral_cell(const Eigen::Vector3d& d, int resolution) {
    RFD_CHECK(resolution >= 2);
    const double s = d.cwiseAbs().sum(), side = resolution - 1.0;
    // The |x|+|y|+|z| = 1 diamond rotated 45 degrees onto [-1, 1]^2, then onto the nodes.
    const double u = std::clamp(((d.x() + d.y()) / s + 1.0) / 2.0 * side, 0.0, side);
    const double v = std::clamp(((d.y() - d.x()) / s + 1.0) / 2.0 * side, 0.0, side);
    const int x = std::min(resolution - 2, static_cast<int>(std::floor(u)));
    const int y = std::min(resolution - 2, static_cast<int>(std::floor(v)));
    const double dx = u - x, dy = v - y;
    return {{x + y * resolution, x + 1 + y * resolution, x + (y + 1) * resolution, x + 1 + (y + 1) * resolution},
            {(1 - dx) * (1 - dy), dx * (1 - dy), (1 - dx) * dy, dx * dy}};
}

Eigen::Vector3d octahedral_node(int x, int y, int resolution) {
    const double side = resolution - 1.0;
    const double u = 2.0 * x / side - 1.0, v = 2.0 * y / side - 1.0;
    const double dx = (u - v) / 2.0, dy = (u + v) / 2.0;
    return Eigen::Vector3d(dx, dy, std::max(0.0, 1.0 - std::abs(dx) - std::abs(dy))).normalized();
}

Eigen::MatrixXd bilinear_grid(const std::vector<Eigen::Vector3d>& directions, const LightModel& model,
                              std::size_t skip) {
    RFD_CHECK(model.kind == LightModel::Kind::Bilinear && model.sigma > 0.0);
    const int r = model.resolution;
    const Eigen::Index nodes = r * r, n = static_cast<Eigen::Index>(directions.size());
    // A^T (the lights' bilinear weights, four per light) and A^T A, built from the four.
    Eigen::MatrixXd at = Eigen::MatrixXd::Zero(nodes, n), ata = Eigen::MatrixXd::Zero(nodes, nodes), b(nodes, n);
    for (Eigen::Index i = 0; i < n; ++i) {
        if (static_cast<std::size_t>(i) == skip) continue;
        const GridCell cell = octahedral_cell(directions[static_cast<std::size_t>(i)], r);
        for (int k = 0; k < 4; ++k) {
            at(cell.node[k], i) += cell.weight[k];
            for (int l = 0; l < 4; ++l) ata(cell.node[k], cell.node[l]) += cell.weight[k] * cell.weight[l];
        }
    }
    for (int y = 0; y < r; ++y)
        for (int x = 0; x < r; ++x)
            b.row(x + y * r) = rbf_weights(directions, model.sigma, octahedral_node(x, y, r), skip).transpose();
    // The grid nearest the prior B y that fits the lights, argmin |A g - y|^2 + k |g - B y|^2:
    // g = (B + (A^T A + k I)^-1 A^T (I - A B)) y, and A^T (I - A B) = A^T - (A^T A) B.
    const Eigen::MatrixXd normal = ata + model.regularization * Eigen::MatrixXd::Identity(nodes, nodes);
    return b + normal.ldlt().solve(at - ata * b);
}

LightWeights::LightWeights(const LightModel& model, const std::vector<Eigen::Vector3d>& directions)
    : model_(model), directions_(directions) {
    for (Eigen::Vector3d& d : directions_) d.normalize();
    switch (model.kind) {
    case LightModel::Kind::Interpolation:
        interpolator_ = std::make_unique<SphericalInterpolator>(directions_);
        break;
    case LightModel::Kind::Basis:
        fit_ = std::make_unique<BasisFit>(model.basis, directions_);
        break;
    case LightModel::Kind::Rbf:
        if (!(model.sigma > 0.0)) throw InputError("rbf needs its width sigma (> 0), chosen on the field");
        if (directions_.size() < 2) throw InputError("rbf needs at least two lights");
        break;
    case LightModel::Kind::Bilinear:
        if (!(model.sigma > 0.0)) throw InputError("bilinear needs the width sigma of its prior (> 0), chosen on the field");
        if (model.resolution < kMinBilinearResolution || model.resolution > kMaxBilinearResolution)
            throw InputError("bilinear: the grid's side is " + std::to_string(kMinBilinearResolution) + " to " +
                             std::to_string(kMaxBilinearResolution) + ", got " + std::to_string(model.resolution));
        if (!(model.regularization > 0.0)) throw InputError("bilinear: the pull toward the prior is positive");
        if (directions_.size() < 2) throw InputError("bilinear needs at least two lights");
        grid_ = bilinear_grid(directions_, model_);
        break;
    }
}

LightWeights::~LightWeights() = default;
LightWeights::LightWeights(LightWeights&&) noexcept = default;
LightWeights& LightWeights::operator=(LightWeights&&) noexcept = default;

Eigen::VectorXd LightWeights::at(const Eigen::Vector3d& d) const {
    const Eigen::Vector3d unit = d.normalized();
    switch (model_.kind) {
    case LightModel::Kind::Interpolation: {
        Eigen::VectorXd w = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(size()));
        const InterpolationWeights iw = interpolator_->weights(unit, model_.interpolation);
        for (std::size_t k = 0; k < iw.count; ++k) w[static_cast<Eigen::Index>(iw.index[k])] += iw.weight[k];
        return w;
    }
    case LightModel::Kind::Basis: return fit_->solve().transpose() * basis_values(model_.basis, unit);
    case LightModel::Kind::Rbf: return rbf_weights(directions_, model_.sigma, unit);
    case LightModel::Kind::Bilinear: break;
    }
    const GridCell cell = octahedral_cell(unit, model_.resolution);
    Eigen::VectorXd w = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(size()));
    for (int k = 0; k < 4; ++k) w += cell.weight[k] * grid_.row(cell.node[k]).transpose();
    return w;
}

Eigen::MatrixXd LightWeights::leave_one_out(std::vector<bool>& predictable) const {
    const std::size_t n = size();
    const auto N = static_cast<Eigen::Index>(n);
    Eigen::MatrixXd w = Eigen::MatrixXd::Zero(N, N);
    predictable.assign(n, true);
    switch (model_.kind) {
    case LightModel::Kind::Interpolation:
        for (std::size_t j = 0; j < n; ++j) {
            std::vector<Eigen::Vector3d> others;
            for (std::size_t i = 0; i < n; ++i)
                if (i != j) others.push_back(directions_[i]);
            const InterpolationWeights iw =
                SphericalInterpolator(others).weights(directions_[j], model_.interpolation);
            for (std::size_t k = 0; k < iw.count; ++k) {
                const std::size_t i = iw.index[k] + (iw.index[k] >= j ? 1 : 0);
                w(static_cast<Eigen::Index>(j), static_cast<Eigen::Index>(i)) += iw.weight[k];
            }
        }
        break;
    case LightModel::Kind::Basis: {
        // The PRESS residual: y_j - prediction without j = r_j / (1 - h_jj), r = (I - H) y.
        const Eigen::MatrixXd residual = Eigen::MatrixXd::Identity(N, N) - fit_->design() * fit_->solve();
        for (std::size_t j = 0; j < n; ++j) {
            const auto J = static_cast<Eigen::Index>(j);
            predictable[j] = fit_->predictable_without(j);
            if (!predictable[j]) continue;
            w.row(J) = -residual.row(J) / (1.0 - fit_->leverage()[J]);
            w(J, J) += 1.0;
            w(J, J) = 0.0;  // exactly: 1 - (1 - h_jj) / (1 - h_jj)
        }
        break;
    }
    case LightModel::Kind::Rbf:
        for (std::size_t j = 0; j < n; ++j)
            w.row(static_cast<Eigen::Index>(j)) = rbf_weights(directions_, model_.sigma, directions_[j], j).transpose();
        break;
    case LightModel::Kind::Bilinear:
        // The grid refitted without light j, read at light j.
        parallel_for_chunks(n, 1, [&](std::size_t begin, std::size_t end) {
            for (std::size_t j = begin; j < end; ++j) {
                const Eigen::MatrixXd grid = bilinear_grid(directions_, model_, j);
                const GridCell cell = octahedral_cell(directions_[j], model_.resolution);
                for (int k = 0; k < 4; ++k)
                    w.row(static_cast<Eigen::Index>(j)) += cell.weight[k] * grid.row(cell.node[k]);
            }
        });
        break;
    }
    return w;
}

namespace {

// G += Y^T Y over `images` (one shape), Y one row per sample, and the peak: chunks of
// samples in parallel, summed in chunk order, so the sum does not depend on the threads.
void add_to_gram(const std::vector<Image>& images, FieldGram& out) {
    const std::size_t n = images.size();
    const auto N = static_cast<Eigen::Index>(n);
    constexpr std::size_t kChunk = 4096;
    const std::size_t samples = images.front().samples().size(), chunks = (samples + kChunk - 1) / kChunk;
    std::vector<Eigen::MatrixXd> parts(chunks);
    std::vector<double> peaks(chunks, 0.0);
    parallel_for_chunks(chunks, 1, [&](std::size_t begin, std::size_t end) {
        Eigen::MatrixXd y;
        for (std::size_t chunk = begin; chunk < end; ++chunk) {
            const std::size_t first = chunk * kChunk, count = std::min(kChunk, samples - first);
            y.resize(static_cast<Eigen::Index>(count), N);
            for (std::size_t i = 0; i < n; ++i) {
                const float* s = images[i].samples().data() + first;
                for (std::size_t k = 0; k < count; ++k) {
                    y(static_cast<Eigen::Index>(k), static_cast<Eigen::Index>(i)) = s[k];
                    peaks[chunk] = std::max(peaks[chunk], static_cast<double>(s[k]));
                }
            }
            parts[chunk].noalias() = y.transpose() * y;
        }
    });
    for (std::size_t chunk = 0; chunk < chunks; ++chunk) {
        out.gram += parts[chunk];
        out.peak = std::max(out.peak, peaks[chunk]);
    }
}

FieldGram empty_gram(std::size_t lights, double samples_per_image) {
    FieldGram out;
    out.gram = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(lights), static_cast<Eigen::Index>(lights));
    out.samples_per_image = samples_per_image;
    return out;
}

}  // namespace

FieldGram field_gram(FieldReader& field) {
    const std::size_t n = field.size();
    FieldGram out = empty_gram(n, static_cast<double>(field.width()) * field.height() * field.channels());
    const int rows = field.band_rows(n);
    Progress progress("gram", static_cast<std::size_t>((field.height() + rows - 1) / rows));
    for (int y0 = 0; y0 < field.height(); y0 += rows) {
        add_to_gram(field.read_band(y0, std::min(field.height(), y0 + rows)), out);
        progress.advance();
    }
    progress.finish();
    return out;
}

FieldGram field_gram(const ReflectanceField& field) {
    if (field.size() == 0) return empty_gram(0, 0.0);
    FieldGram out = empty_gram(field.size(), static_cast<double>(field.images.front().samples().size()));
    add_to_gram(field.images, out);
    return out;
}

ModelChoice choose_light_model(const FieldGram& gram, const std::vector<Eigen::Vector3d>& directions,
                               const std::vector<std::string>& names) {
    ModelChoice choice;
    double best = std::numeric_limits<double>::infinity();
    for (const std::string& name : names) {
        LightModel model = parse_light_model(name);
        try {
            if (model.has_sigma()) model.sigma = best_sigma(gram, directions, model);
            std::vector<bool> predictable;
            const Eigen::MatrixXd w = LightWeights(model, directions).leave_one_out(predictable);
            if (std::find(predictable.begin(), predictable.end(), false) != predictable.end()) continue;
            const double error = leave_one_out_errors(gram, w).sum();
            choice.candidates.push_back(model);
            choice.psnr.push_back(
                psnr_from_mse(error / (gram.samples_per_image * static_cast<double>(directions.size())), gram.peak));
            if (error < best) {
                best = error;
                choice.model = model;
            }
        } catch (const InputError&) {
            // lights this model cannot use: not a candidate
        }
    }
    if (choice.candidates.empty()) throw InputError("no way of predicting the field's lights from one another fits them");
    return choice;
}

ReflectanceField resampled_field(const ReflectanceField& field, const LightWeights& weights,
                                 const std::vector<Eigen::Vector3d>& directions) {
    RFD_CHECK(weights.size() == field.size());
    ReflectanceField out;
    out.directions = directions;
    out.images.resize(directions.size());
    parallel_for_chunks(directions.size(), 1, [&](std::size_t begin, std::size_t end) {
        for (std::size_t k = begin; k < end; ++k) {
            const Eigen::VectorXd w = weights.at(directions[k]);
            Image image(field.width(), field.height(), field.channels());
            for (std::size_t i = 0; i < field.size(); ++i) {
                const auto wi = static_cast<float>(w[static_cast<Eigen::Index>(i)]);
                if (wi == 0.0f) continue;
                const std::span<const float> from = field.images[i].samples();
                for (std::size_t s = 0; s < from.size(); ++s) image.samples()[s] += wi * from[s];
            }
            out.images[k] = std::move(image);
        }
    });
    return out;
}

Eigen::VectorXd leave_one_out_errors(const FieldGram& gram, const Eigen::MatrixXd& w) {
    const Eigen::MatrixXd e = Eigen::MatrixXd::Identity(w.rows(), w.cols()) - w;
    return ((e * gram.gram).array() * e.array()).rowwise().sum().matrix();
}

double best_sigma(const FieldGram& gram, const std::vector<Eigen::Vector3d>& directions, LightModel model) {
    RFD_CHECK(model.has_sigma());
    std::vector<bool> predictable;
    const auto error_at = [&](double log_sigma) {
        model.sigma = std::exp(log_sigma);
        return leave_one_out_errors(gram, LightWeights(model, directions).leave_one_out(predictable)).sum();
    };
    const double lo = std::log(0.02), hi = std::log(1.5);
    constexpr int kScan = 24;
    int best = 0;
    std::vector<double> errors(kScan + 1);
    for (int s = 0; s <= kScan; ++s) {
        errors[static_cast<std::size_t>(s)] = error_at(lo + (hi - lo) * s / kScan);
        if (errors[static_cast<std::size_t>(s)] < errors[static_cast<std::size_t>(best)]) best = s;
    }
    // Golden-section search between the best scan point's neighbours.
    double a = lo + (hi - lo) * std::max(0, best - 1) / kScan, b = lo + (hi - lo) * std::min(kScan, best + 1) / kScan;
    const double ratio = (std::sqrt(5.0) - 1.0) / 2.0;
    double c = b - ratio * (b - a), d = a + ratio * (b - a);
    double fc = error_at(c), fd = error_at(d);
    for (int iteration = 0; iteration < 30; ++iteration) {
        if (fc < fd) {
            b = d;
            d = c;
            fd = fc;
            c = b - ratio * (b - a);
            fc = error_at(c);
        } else {
            a = c;
            c = d;
            fc = fd;
            d = a + ratio * (b - a);
            fd = error_at(d);
        }
    }
    const double found = fc < fd ? c : d;
    const double scanned = lo + (hi - lo) * best / kScan;
    return std::exp(std::min(fc, fd) <= errors[static_cast<std::size_t>(best)] ? found : scanned);
}

}  // namespace rfd::relight
