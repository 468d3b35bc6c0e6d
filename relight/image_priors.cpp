#include "relight/image_priors.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <string>

#include <nanoflann.hpp>

#include "core/error.hpp"

namespace rfd::relight {
namespace {

// Windows reaching past the border repeat the edge instead of needing special cases.
float sample(const Image& image, int x, int y, int c) {
    return image.at(std::clamp(x, 0, image.width() - 1), std::clamp(y, 0, image.height() - 1), c);
}

// The (2 radius + 1)^2 window of channel c around (cx, cy), row-major. Most windows lie
// inside the image and are copied row by row; this runs for every window of every source
// and query, several times per synthesised pixel.
void window_of(const Image& image, int cx, int cy, int radius, float* out, int c = 0) {
    const int width = image.width();
    if (cx - radius < 0 || cy - radius < 0 || cx + radius >= width || cy + radius >= image.height()) {
        for (int v = -radius; v <= radius; ++v)
            for (int u = -radius; u <= radius; ++u) *out++ = sample(image, cx + u, cy + v, c);
        return;
    }
    const float* row = image.plane(c).data() + static_cast<std::ptrdiff_t>(cy - radius) * width + (cx - radius);
    for (int v = -radius; v <= radius; ++v, row += width) out = std::copy(row, row + 2 * radius + 1, out);
}

// The window of every channel, channel after channel.
void windows_of(const Image& image, int cx, int cy, int radius, float* out) {
    const int side = 2 * radius + 1;
    for (int c = 0; c < image.channels(); ++c) window_of(image, cx, cy, radius, out + c * side * side, c);
}

// The sources' windows as points of the k-d tree: PCA coordinates, then position.
struct WindowCloud {
    std::size_t dims = 0;
    std::vector<float> features;  // point-major
    struct Origin {
        std::uint32_t source;
        int x, y;
    };
    std::vector<Origin> origins;

    const float* point(std::size_t index) const { return features.data() + index * dims; }
    std::size_t kdtree_get_point_count() const { return origins.size(); }
    float kdtree_get_pt(std::size_t index, std::size_t dim) const { return point(index)[dim]; }
    template <class Box>
    bool kdtree_get_bbox(Box&) const {
        return false;
    }
};

// nanoflann's L2_Simple_Adaptor, with the point's coordinates read through one pointer
// instead of one accessor call per coordinate (the searches' inner loop): the same sums in
// the same order.
struct WindowDistance {
    using ElementType = float;
    using DistanceType = float;
    const WindowCloud& cloud;
    explicit WindowDistance(const WindowCloud& windows) : cloud(windows) {}
    float evalMetric(const float* a, std::uint32_t index, std::size_t size) const {
        const float* b = cloud.point(index);
        float result = 0.0f;
        for (std::size_t i = 0; i < size; ++i) {
            const float diff = a[i] - b[i];
            result += diff * diff;
        }
        return result;
    }
    template <typename U, typename V>
    float accum_dist(U a, V b, std::size_t) const {
        return (a - b) * (a - b);
    }
};

using WindowTree = nanoflann::KDTreeSingleIndexAdaptor<WindowDistance, WindowCloud, -1, std::uint32_t>;

// Row-major mask grown by a (2 radius + 1)^2 box.
std::vector<std::uint8_t> dilated(const std::vector<std::uint8_t>& mask, int width, int height, int radius) {
    std::vector<std::uint8_t> rows(mask.size(), 0), out(mask.size(), 0);
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x) {
            if (!mask[static_cast<std::size_t>(y * width + x)]) continue;
            for (int u = std::max(0, x - radius); u <= std::min(width - 1, x + radius); ++u)
                rows[static_cast<std::size_t>(y * width + u)] = 1;
        }
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x) {
            if (!rows[static_cast<std::size_t>(y * width + x)]) continue;
            for (int v = std::max(0, y - radius); v <= std::min(height - 1, y + radius); ++v)
                out[static_cast<std::size_t>(v * width + x)] = 1;
        }
    return out;
}

// A window of the estimate matched to a source window up to the scale `lambda`.
struct Match {
    std::uint32_t source = 0;
    int dx = 0, dy = 0;          // match centre minus query centre
    float lambda = 0.0f;
    double distance = 0.0;       // d / |W_E|^2
    bool found = false;
};

}  // namespace

void check_prior_options(const PriorOptions& options) {
    if (options.iterations < 0)
        throw InputError("prior iterations must be >= 0 (0: off), got " + std::to_string(options.iterations));
    if (!(options.proximity > 0.0) || !std::isfinite(options.proximity))
        throw InputError("the prior's proximity weight must be > 0, got " + std::to_string(options.proximity));
    if (options.candidates < 1)
        throw InputError("the prior needs at least 1 candidate window, got " + std::to_string(options.candidates));
}

PatchBasis PatchBasis::fit(const std::vector<const Image*>& images, int radius, int components, int stride) {
    // The callers' own choices, not a user's: a failure is a bug.
    RFD_CHECK(!images.empty() && radius >= 1 && radius <= kMaxRadius && stride >= 1);
    const int side = 2 * radius + 1, size = side * side;
    RFD_CHECK(components >= 1 && components <= size);
    for (const Image* image : images) RFD_CHECK(image->same_shape(*images.front()));

    Eigen::MatrixXd scatter = Eigen::MatrixXd::Zero(size, size);
    std::vector<float> window(static_cast<std::size_t>(size));
    for (const Image* image : images) {
        const Image lum = luminance(*image);
        for (int y = 0; y < image->height(); y += stride)
            for (int x = 0; x < image->width(); x += stride) {
                window_of(lum, x, y, radius, window.data());
                const Eigen::Map<const Eigen::VectorXf> w(window.data(), size);
                const double norm = w.norm();
                if (norm <= 0.0) continue;
                const Eigen::VectorXd unit = w.cast<double>() / norm;
                scatter.noalias() += unit * unit.transpose();
            }
    }
    // Uncentred: the mean window (flat) is the leading axis, which is what separates a
    // bright flat patch from an edge once intensities are normalised away.
    const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> solver(scatter);
    PatchBasis basis;
    basis.radius_ = radius;
    basis.axes_ = solver.eigenvectors().rightCols(components).rowwise().reverse().cast<float>();
    return basis;
}

void PatchBasis::project(const float* window, float* out) const {
    const Eigen::Map<const Eigen::VectorXf> w(window, axes_.rows());
    const float norm = w.norm();
    Eigen::Map<Eigen::VectorXf> coordinates(out, axes_.cols());
    if (norm <= 0.0f) {
        coordinates.setZero();
        return;
    }
    // The unit window on the stack: as an expression, Eigen would copy it to the heap for
    // the product, once for every window of every source and query (millions per upsampling).
    Eigen::Matrix<float, Eigen::Dynamic, 1, 0, kMaxWindowSize, 1> unit = w / norm;
    coordinates.noalias() = axes_.transpose() * unit;
}

Image regularise_with_priors(const Image& estimate, const std::vector<std::uint8_t>& uncertain,
                             const std::vector<const Image*>& sources, const PatchBasis& basis,
                             const PriorOptions& options) {
    check_prior_options(options);
    RFD_CHECK(!sources.empty() && uncertain.size() == estimate.pixel_count());
    for (const Image* source : sources) RFD_CHECK(source->same_shape(estimate));
    if (options.iterations == 0 || std::none_of(uncertain.begin(), uncertain.end(), [](std::uint8_t u) { return u; }))
        return estimate;

    const int width = estimate.width(), height = estimate.height(), channels = estimate.channels();
    const int radius = basis.radius(), side = 2 * radius + 1;
    const auto components = static_cast<std::size_t>(basis.components());
    const auto proximity = static_cast<float>(options.proximity);
    // A window farther than this can never beat a perfect match at the query's position:
    // unit windows of non-negative values are at most sqrt(2) apart.
    const int reach = static_cast<int>(std::ceil(std::sqrt(2.0) / options.proximity));
    const std::vector<std::uint8_t> queries = dilated(uncertain, width, height, radius);
    const std::vector<std::uint8_t> offered = dilated(uncertain, width, height, radius + reach);

    WindowCloud cloud;
    cloud.dims = components + 2;
    const auto offered_count = static_cast<std::size_t>(std::count(offered.begin(), offered.end(), 1));
    cloud.features.reserve(sources.size() * offered_count * cloud.dims);
    cloud.origins.reserve(sources.size() * offered_count);
    std::vector<float> window(static_cast<std::size_t>(side * side));
    for (std::size_t s = 0; s < sources.size(); ++s) {
        const Image lum = luminance(*sources[s]);
        for (int y = 0; y < height; ++y)
            for (int x = 0; x < width; ++x) {
                if (!offered[static_cast<std::size_t>(y * width + x)]) continue;
                window_of(lum, x, y, radius, window.data());
                const std::size_t at = cloud.features.size();
                cloud.features.resize(at + cloud.dims);
                basis.project(window.data(), &cloud.features[at]);
                cloud.features[at + components] = proximity * static_cast<float>(x);
                cloud.features[at + components + 1] = proximity * static_cast<float>(y);
                cloud.origins.push_back({static_cast<std::uint32_t>(s), x, y});
            }
    }
    const WindowTree tree(static_cast<int>(cloud.dims), cloud, nanoflann::KDTreeSingleIndexAdaptorParams(16));

    const auto candidates = std::min<std::size_t>(static_cast<std::size_t>(options.candidates), cloud.origins.size());
    std::vector<std::uint32_t> found(candidates);
    std::vector<float> found_distance(candidates), query(cloud.dims);
    std::vector<float> estimate_window(static_cast<std::size_t>(channels * side * side)),
        source_window(estimate_window.size());
    std::vector<Match> matches(estimate.pixel_count());
    std::vector<double> distances;
    Image current = estimate;
    for (int iteration = 0; iteration < options.iterations; ++iteration) {
        const Image lum = luminance(current);
        distances.clear();
        for (int y = 0; y < height; ++y)
            for (int x = 0; x < width; ++x) {
                const auto p = static_cast<std::size_t>(y * width + x);
                matches[p] = Match{};
                if (!queries[p]) continue;
                window_of(lum, x, y, radius, window.data());
                basis.project(window.data(), query.data());
                query[components] = proximity * static_cast<float>(x);
                query[components + 1] = proximity * static_cast<float>(y);
                const std::size_t count = tree.knnSearch(query.data(), candidates, found.data(), found_distance.data());
                // The exact distance up to a scale, over every channel (eq. 6.1).
                windows_of(current, x, y, radius, estimate_window.data());
                double ee = 0.0;
                for (const float e : estimate_window) ee += static_cast<double>(e) * e;
                for (std::size_t k = 0; k < count; ++k) {
                    const WindowCloud::Origin& origin = cloud.origins[found[k]];
                    windows_of(*sources[origin.source], origin.x, origin.y, radius, source_window.data());
                    double ei = 0.0, ii = 0.0;
                    for (std::size_t j = 0; j < source_window.size(); ++j) {
                        const double e = estimate_window[j], i = source_window[j];
                        ei += e * i;
                        ii += i * i;
                    }
                    const double lambda = ii > 0.0 ? ei / ii : 0.0;
                    const double residual = std::max(0.0, ee - lambda * ei);
                    const double distance = ee > 0.0 ? residual / ee : 0.0;
                    if (!matches[p].found || distance < matches[p].distance)
                        matches[p] = {origin.source, origin.x - x, origin.y - y, static_cast<float>(lambda), distance,
                                      true};
                }
                if (matches[p].found) distances.push_back(matches[p].distance);
            }
        if (distances.empty()) break;
        const auto rank = static_cast<std::ptrdiff_t>(3 * distances.size() / 4);
        std::nth_element(distances.begin(), distances.begin() + rank, distances.end());
        const double sigma2 = std::max(distances[static_cast<std::size_t>(rank)], 1e-6);

        Image next = current;
        std::vector<double> sum(static_cast<std::size_t>(channels));
        for (int y = 0; y < height; ++y)
            for (int x = 0; x < width; ++x) {
                if (!uncertain[static_cast<std::size_t>(y * width + x)]) continue;
                std::fill(sum.begin(), sum.end(), 0.0);
                double weight = 0.0;
                for (int v = -radius; v <= radius; ++v)
                    for (int u = -radius; u <= radius; ++u) {
                        const int qx = x + u, qy = y + v;
                        if (qx < 0 || qy < 0 || qx >= width || qy >= height) continue;
                        const Match& m = matches[static_cast<std::size_t>(qy * width + qx)];
                        if (!m.found) continue;
                        const double s = std::exp(-m.distance / (2.0 * sigma2));
                        for (int c = 0; c < channels; ++c)
                            sum[static_cast<std::size_t>(c)] +=
                                s * m.lambda * sample(*sources[m.source], x + m.dx, y + m.dy, c);
                        weight += s;
                    }
                if (weight <= 0.0) continue;
                for (int c = 0; c < channels; ++c)
                    next.at(x, y, c) = static_cast<float>(sum[static_cast<std::size_t>(c)] / weight);
            }
        current = std::move(next);
    }
    return current;
}

}  // namespace rfd::relight
