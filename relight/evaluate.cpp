#include "relight/evaluate.hpp"

#include <algorithm>
#include <functional>
#include <limits>
#include <cmath>
#include <cstdint>
#include <span>
#include <string>

#include "core/error.hpp"
#include "core/image_io.hpp"
#include "core/parallel.hpp"
#include "core/progress.hpp"

namespace rfd::relight {

double relit_squared_error(const Image& reference, const std::array<const Image*, 3>& images,
                           const std::array<float, 3>& weights) {
    const std::span<const float> r = reference.samples();
    const std::span<const float> a = images[0]->samples(), b = images[1]->samples(), c = images[2]->samples();
    const float wa = weights[0], wb = weights[1], wc = weights[2];
    // Eight partial sums in fixed lanes: the compiler may vectorise them without
    // reassociating, and the result is the same with or without vectors.
    constexpr std::size_t kLanes = 8;
    std::array<double, kLanes> lanes{};
    const std::size_t count = r.size(), whole = count - count % kLanes;
    for (std::size_t k = 0; k < whole; k += kLanes)
        for (std::size_t l = 0; l < kLanes; ++l) {
            const float e = wa * a[k + l] + wb * b[k + l] + wc * c[k + l] - r[k + l];
            lanes[l] += static_cast<double>(e) * static_cast<double>(e);
        }
    for (std::size_t k = whole; k < count; ++k) {
        const float e = wa * a[k] + wb * b[k] + wc * c[k] - r[k];
        lanes[k % kLanes] += static_cast<double>(e) * static_cast<double>(e);
    }
    double sum = 0.0;
    for (const double lane : lanes) sum += lane;
    return sum;
}

namespace {

void check_same_view(const ReflectanceField& sparse, const ReflectanceField& reference) {
    if (sparse.images.empty() || reference.images.empty())
        throw InputError("evaluation needs two non-empty fields (sparse: " + std::to_string(sparse.size()) +
                         " images, reference: " + std::to_string(reference.size()) + ")");
    const Image& shape = sparse.images.front();
    auto shape_text = [](const Image& image) {
        return std::to_string(image.width()) + "x" + std::to_string(image.height()) + "x" +
               std::to_string(image.channels());
    };
    for (const auto* field : {&sparse, &reference})
        for (std::size_t i = 0; i < field->images.size(); ++i)
            if (!field->images[i].same_shape(shape))
                throw InputError(std::string(field == &sparse ? "sparse" : "reference") + " field image " +
                                 std::to_string(i) + " is " + shape_text(field->images[i]) +
                                 ", the sparse field's first image is " + shape_text(shape) +
                                 "; both fields must show the same view at the same size");
}

}  // namespace

double Evaluation::entry_psnr(std::size_t j) const {
    return psnr_from_mse(per_direction.at(j) / samples_per_entry, peak);
}

Evaluation evaluate(const ReflectanceField& sparse, const ReflectanceField& reference, Interpolation method) {
    check_same_view(sparse, reference);
    const Image& shape = sparse.images.front();
    RFD_CHECK(reference.directions.size() == reference.images.size());

    const SphericalInterpolator interpolator(sparse.directions);
    Evaluation result;
    result.per_direction.assign(reference.size(), 0.0);
    std::vector<float> peaks(reference.size(), 0.0f);
    parallel_for_chunks(reference.size(), 1, [&](std::size_t begin, std::size_t end) {
        for (std::size_t j = begin; j < end; ++j) {
            const InterpolationWeights w = interpolator.weights(reference.directions[j], method);
            std::array<const Image*, 3> images{};
            std::array<float, 3> weights{};
            for (std::size_t k = 0; k < 3; ++k) {
                images[k] = &sparse.images[k < w.count ? w.index[k] : w.index[0]];
                weights[k] = k < w.count ? static_cast<float>(w.weight[k]) : 0.0f;
            }
            result.per_direction[j] = relit_squared_error(reference.images[j], images, weights);
            const auto samples = reference.images[j].samples();
            peaks[j] = *std::max_element(samples.begin(), samples.end());
        }
    });
    for (const double e : result.per_direction) result.total_squared_error += e;  // fixed order
    const double peak = *std::max_element(peaks.begin(), peaks.end());
    const double samples = static_cast<double>(reference.size()) * static_cast<double>(shape.samples().size());
    result.psnr = psnr_from_mse(result.total_squared_error / samples, peak);
    result.peak = peak;
    result.samples_per_entry = static_cast<double>(shape.samples().size());
    return result;
}

LightEvaluation evaluate_under_lights(const ReflectanceField& sparse, const ReflectanceField& reference,
                                      const std::vector<Light>& lights, Interpolation method) {
    check_same_view(sparse, reference);
    if (lights.empty()) throw InputError("evaluation under lights needs at least one light");
    LightEvaluation result;
    Evaluation& score = result.score;
    score.samples_per_entry = static_cast<double>(sparse.images.front().samples().size());
    for (const Light& light : lights) {
        Image relit = render(sparse, {light}, method), truth = render(reference, {light}, method);
        score.per_direction.push_back(mean_squared_error(relit, truth) * score.samples_per_entry);
        score.total_squared_error += score.per_direction.back();
        for (const float v : truth.samples()) score.peak = std::max(score.peak, static_cast<double>(v));
        result.relit.push_back(std::move(relit));
        result.reference_relit.push_back(std::move(truth));
    }
    const double samples = static_cast<double>(lights.size()) * score.samples_per_entry;
    score.psnr = psnr_from_mse(score.total_squared_error / samples, score.peak);
    return result;
}

double LeaveOneOut::psnr_linear(std::size_t j) const {
    return psnr_from_mse(squared_error.at(j) / samples_per_image, peak);
}

double LeaveOneOut::psnr_srgb8(std::size_t j) const {
    return psnr_from_mse(code_squared_error.at(j) / samples_per_image, 255.0);
}

namespace {

// out(j, k): the prediction of held-out image j at sample first + k of a band (all its
// channels' samples, in Image order), for k < count.
using PredictChunk = std::function<void(const std::vector<Image>& band, std::size_t first, std::size_t count,
                                        Eigen::MatrixXf& out)>;

// SSIM (Wang et al. 2004) of two 8-bit pictures, `rows` rows of `width` codes, over blocks of
// kSsimBlock x kSsimBlock (the last ones narrower), summed over the blocks: per block
// (2 mu_a mu_b + C1)(2 cov + C2) / ((mu_a^2 + mu_b^2 + C1)(var_a + var_b + C2)),
// C1 = (0.01 * 255)^2, C2 = (0.03 * 255)^2.
double block_ssim_sum(std::span<const std::uint8_t> a, std::span<const std::uint8_t> b, std::size_t width, int rows) {
    constexpr double c1 = (0.01 * 255) * (0.01 * 255), c2 = (0.03 * 255) * (0.03 * 255);
    double sum = 0.0;
    for (std::size_t x0 = 0; x0 < width; x0 += kSsimBlock) {
        const std::size_t x1 = std::min(width, x0 + kSsimBlock);
        double sa = 0.0, sb = 0.0, saa = 0.0, sbb = 0.0, sab = 0.0;
        for (int y = 0; y < rows; ++y)
            for (std::size_t x = x0; x < x1; ++x) {
                const double va = a[static_cast<std::size_t>(y) * width + x], vb = b[static_cast<std::size_t>(y) * width + x];
                sa += va;
                sb += vb;
                saa += va * va;
                sbb += vb * vb;
                sab += va * vb;
            }
        const double count = static_cast<double>(rows) * static_cast<double>(x1 - x0);
        const double ma = sa / count, mb = sb / count;
        const double var_a = saa / count - ma * ma, var_b = sbb / count - mb * mb, cov = sab / count - ma * mb;
        sum += (2 * ma * mb + c1) * (2 * cov + c2) / ((ma * ma + mb * mb + c1) * (var_a + var_b + c2));
    }
    return sum;
}

// Leave-one-out scores of every predictor of `predictors`, the field read once, a band of
// rows at a time, each band cut into fixed chunks of samples, scored in parallel and summed in
// chunk order: the sums do not depend on the threads. Images `predictable[m]` says false of
// get NaN for predictor m.
std::vector<LeaveOneOut> score_left_out(FieldReader& field, const std::vector<std::vector<bool>>& predictable,
                                        std::size_t band_bytes, const std::vector<PredictChunk>& predictors) {
    const std::size_t n = field.size(), models = predictors.size();
    RFD_CHECK(predictable.size() == models);
    const bool eight_bit = field.sample_type() == SampleType::UInt8;
    const auto width = static_cast<std::size_t>(field.width());
    const int channels = field.channels();
    std::vector<LeaveOneOut> results(models);
    for (LeaveOneOut& result : results) {
        result.directions = field.directions();
        result.squared_error.assign(n, 0.0);
        if (eight_bit) result.code_squared_error.assign(n, 0.0);
        result.ssim.assign(n, 0.0);
        result.samples_per_image = static_cast<double>(field.width()) * field.height() * field.channels();
    }
    // Bands of whole SSIM blocks (kSsimBlock rows), each cut into strips of a block's rows of
    // one channel: the unit scored in parallel and summed in order.
    const int rows = std::max(kSsimBlock, field.band_rows(n, 0, band_bytes) / kSsimBlock * kSsimBlock);
    std::size_t blocks_per_image = 0;
    float peak = 0.0f;
    Progress progress("leave-one-out", static_cast<std::size_t>((field.height() + rows - 1) / rows));
    for (int y0 = 0; y0 < field.height(); y0 += rows) {
        const int y1 = std::min(field.height(), y0 + rows), band_height = y1 - y0;
        const std::vector<Image> band = field.read_band(y0, y1);
        const int strips_per_channel = (band_height + kSsimBlock - 1) / kSsimBlock;
        const std::size_t strips = static_cast<std::size_t>(strips_per_channel) * static_cast<std::size_t>(channels);
        const std::size_t blocks_per_strip = (width + kSsimBlock - 1) / kSsimBlock;
        blocks_per_image += strips * blocks_per_strip;
        const auto N = static_cast<Eigen::Index>(n), S = static_cast<Eigen::Index>(strips);
        std::vector<Eigen::MatrixXd> linear(models, Eigen::MatrixXd::Zero(N, S)), codes = linear, ssim = linear;
        std::vector<float> peaks(strips, 0.0f);
        parallel_for_chunks(strips, 1, [&](std::size_t begin, std::size_t end) {
            Eigen::MatrixXf predicted;
            std::vector<std::uint8_t> predicted_codes, true_codes;
            std::vector<float> row;
            for (std::size_t strip = begin; strip < end; ++strip) {
                const int channel = static_cast<int>(strip / static_cast<std::size_t>(strips_per_channel));
                const int strip_y = static_cast<int>(strip % static_cast<std::size_t>(strips_per_channel)) * kSsimBlock;
                const int strip_rows = std::min(kSsimBlock, band_height - strip_y);
                const std::size_t first = (static_cast<std::size_t>(channel) * static_cast<std::size_t>(band_height) +
                                           static_cast<std::size_t>(strip_y)) * width;
                const std::size_t count = static_cast<std::size_t>(strip_rows) * width;
                row.resize(count);
                predicted_codes.resize(count);
                true_codes.resize(count);
                for (std::size_t j = 0; j < n; ++j)
                    for (const float v : band[j].samples().subspan(first, count)) peaks[strip] = std::max(peaks[strip], v);
                for (std::size_t m = 0; m < models; ++m) {
                    predictors[m](band, first, count, predicted);
                    for (std::size_t j = 0; j < n; ++j) {
                        if (!predictable[m][j]) continue;
                        const std::span<const float> truth = band[j].samples().subspan(first, count);
                        double sum = 0.0;
                        for (std::size_t k = 0; k < count; ++k) {
                            row[k] = predicted(static_cast<Eigen::Index>(j), static_cast<Eigen::Index>(k));
                            const double e = static_cast<double>(row[k]) - truth[k];
                            sum += e * e;
                        }
                        const auto J = static_cast<Eigen::Index>(j), K = static_cast<Eigen::Index>(strip);
                        linear[m](J, K) = sum;
                        encode_srgb8(row, predicted_codes);
                        encode_srgb8(truth, true_codes);
                        ssim[m](J, K) = block_ssim_sum(predicted_codes, true_codes, width, strip_rows);
                        if (!eight_bit) continue;
                        double code_sum = 0.0;
                        for (std::size_t k = 0; k < count; ++k) {
                            const int c = int{predicted_codes[k]} - int{true_codes[k]};
                            code_sum += c * c;
                        }
                        codes[m](J, K) = code_sum;
                    }
                }
            }
        });
        for (std::size_t m = 0; m < models; ++m)
            for (std::size_t j = 0; j < n; ++j)
                for (std::size_t strip = 0; strip < strips; ++strip) {
                    const auto J = static_cast<Eigen::Index>(j), K = static_cast<Eigen::Index>(strip);
                    results[m].squared_error[j] += linear[m](J, K);
                    results[m].ssim[j] += ssim[m](J, K);
                    if (eight_bit) results[m].code_squared_error[j] += codes[m](J, K);
                }
        for (const float v : peaks) peak = std::max(peak, v);
        progress.advance();
    }
    progress.finish();
    for (std::size_t m = 0; m < models; ++m) {
        LeaveOneOut& result = results[m];
        result.peak = peak;
        for (std::size_t j = 0; j < n; ++j) {
            result.ssim[j] /= static_cast<double>(blocks_per_image);
            if (!predictable[m][j]) {
                result.squared_error[j] = std::numeric_limits<double>::quiet_NaN();
                result.ssim[j] = std::numeric_limits<double>::quiet_NaN();
                if (eight_bit) result.code_squared_error[j] = std::numeric_limits<double>::quiet_NaN();
            }
        }
    }
    return results;
}

LeaveOneOut score_left_out(FieldReader& field, const std::vector<bool>& predictable, std::size_t band_bytes,
                           const PredictChunk& predict) {
    return std::move(score_left_out(field, std::vector<std::vector<bool>>{predictable}, band_bytes, {predict}).front());
}

}  // namespace

LeaveOneOut leave_one_out(FieldReader& field, Interpolation method, std::size_t band_bytes) {
    const std::size_t n = field.size();
    if (n < 4)
        throw InputError(SourceLocation{field.light_file().string()},
                         "leave-one-out needs at least 4 images (3 left to interpolate from); the field has " +
                             std::to_string(n));
    const std::vector<Eigen::Vector3d> directions = field.directions();
    // Per held-out image, its weights over the others (indices into the whole field).
    std::vector<InterpolationWeights> weights(n);
    for (std::size_t j = 0; j < n; ++j) {
        std::vector<Eigen::Vector3d> others;
        for (std::size_t i = 0; i < n; ++i)
            if (i != j) others.push_back(directions[i]);
        InterpolationWeights w = SphericalInterpolator(others).weights(directions[j], method);
        for (std::size_t k = 0; k < w.count; ++k) w.index[k] += w.index[k] >= j ? 1 : 0;
        weights[j] = w;
    }
    const auto predict = [&](const std::vector<Image>& band, std::size_t first, std::size_t count,
                             Eigen::MatrixXf& out) {
        out.resize(static_cast<Eigen::Index>(n), static_cast<Eigen::Index>(count));
        for (std::size_t j = 0; j < n; ++j) {
            const InterpolationWeights& w = weights[j];
            std::array<const float*, 3> from{};
            std::array<float, 3> k{};
            for (std::size_t t = 0; t < 3; ++t) {
                from[t] = band[w.index[t < w.count ? t : 0]].samples().data() + first;
                k[t] = t < w.count ? static_cast<float>(w.weight[t]) : 0.0f;
            }
            for (std::size_t s = 0; s < count; ++s)
                out(static_cast<Eigen::Index>(j), static_cast<Eigen::Index>(s)) =
                    k[0] * from[0][s] + k[1] * from[1][s] + k[2] * from[2][s];
        }
    };
    return score_left_out(field, std::vector<bool>(n, true), band_bytes, predict);
}

LeaveOneOut leave_one_out(FieldReader& field, const BasisFit& fit, std::size_t band_bytes) {
    RFD_CHECK(fit.lights() == field.size());
    const std::size_t n = field.size();
    std::vector<bool> predictable(n);
    // The PRESS residual: y_j minus the prediction without j is r_j / (1 - h_jj).
    Eigen::VectorXd inverse_gap(static_cast<Eigen::Index>(n));
    for (std::size_t j = 0; j < n; ++j) {
        predictable[j] = fit.predictable_without(j);
        inverse_gap[static_cast<Eigen::Index>(j)] =
            predictable[j] ? 1.0 / (1.0 - fit.leverage()[static_cast<Eigen::Index>(j)]) : 0.0;
    }
    const auto predict = [&](const std::vector<Image>& band, std::size_t first, std::size_t count,
                             Eigen::MatrixXf& out) {
        Eigen::MatrixXd y(static_cast<Eigen::Index>(n), static_cast<Eigen::Index>(count));
        for (std::size_t i = 0; i < n; ++i)
            for (std::size_t s = 0; s < count; ++s)
                y(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(s)) = band[i].samples()[first + s];
        const Eigen::MatrixXd residual = y - fit.design() * (fit.solve() * y);
        out = (y - inverse_gap.asDiagonal() * residual).cast<float>();
    };
    return score_left_out(field, predictable, band_bytes, predict);
}

std::vector<LeaveOneOut> leave_one_out(FieldReader& field, const std::vector<const LightWeights*>& models,
                                       std::size_t band_bytes) {
    const std::size_t n = field.size();
    std::vector<std::vector<bool>> predictable(models.size());
    std::vector<Eigen::MatrixXd> matrices;
    for (std::size_t m = 0; m < models.size(); ++m) {
        RFD_CHECK(models[m]->size() == n);
        matrices.push_back(models[m]->leave_one_out(predictable[m]));
    }
    std::vector<PredictChunk> predictors;
    for (const Eigen::MatrixXd& w : matrices)
        predictors.emplace_back([&w, n](const std::vector<Image>& band, std::size_t first, std::size_t count,
                                        Eigen::MatrixXf& out) {
            // In double, as the fitted bases' closed form: the float the prediction rounds to
            // hardly ever depends on the order Eigen's kernel sums in.
            Eigen::MatrixXd y(static_cast<Eigen::Index>(n), static_cast<Eigen::Index>(count));
            for (std::size_t i = 0; i < n; ++i)
                y.row(static_cast<Eigen::Index>(i)) =
                    Eigen::Map<const Eigen::RowVectorXf>(band[i].samples().data() + first, static_cast<Eigen::Index>(count))
                        .cast<double>();
            out = (w * y).cast<float>();
        });
    return score_left_out(field, predictable, band_bytes, predictors);
}

namespace {

// The mean over images of the PSNR of each one's summed squared error, NaN ones left out.
double mean_psnr(const std::vector<double>& squared_errors, double samples_per_image, double peak) {
    double sum = 0.0;
    std::size_t count = 0;
    for (const double e : squared_errors)
        if (!std::isnan(e)) {
            sum += psnr_from_mse(e / samples_per_image, peak);
            ++count;
        }
    return sum / static_cast<double>(count);
}

}  // namespace

double LeaveOneOut::mean_psnr_linear() const { return mean_psnr(squared_error, samples_per_image, peak); }

double LeaveOneOut::mean_psnr_srgb8() const { return mean_psnr(code_squared_error, samples_per_image, 255.0); }

double LeaveOneOut::mean_ssim() const {
    double sum = 0.0;
    std::size_t count = 0;
    for (const double v : ssim)
        if (!std::isnan(v)) {
            sum += v;
            ++count;
        }
    return sum / static_cast<double>(count);
}

}  // namespace rfd::relight
