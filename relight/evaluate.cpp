#include "relight/evaluate.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "core/error.hpp"
#include "core/parallel.hpp"

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

}  // namespace rfd::relight
