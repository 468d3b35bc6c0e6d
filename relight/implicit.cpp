#include "relight/implicit.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <fstream>
#include <sstream>
#include <string>
#include <type_traits>
#include <utility>

#include <Eigen/SVD>
#include <nlohmann/json.hpp>

#include "core/error.hpp"
#include "core/files.hpp"
#include "core/image_io.hpp"
#include "core/parallel.hpp"
#include "core/sphere.hpp"
#include "core/units.hpp"
#include "relight/field.hpp"
#include "relight/vision.hpp"

namespace rfd::relight {
namespace {

constexpr const char* kModelFile = "implicit.json";
constexpr const char* kModelFormat = "rfd implicit relighting model";
constexpr const char* kProbeFormat = "rfd implicit relighting probe";
constexpr int kModelVersion = 1;

void check_finite(const Image& image, const std::string& what) {
    for (const float s : image.samples())
        if (!std::isfinite(s)) throw InputError(what + ": non-finite sample");
}

// The masked samples of one channel.
Eigen::VectorXd masked(const Image& probe, int channel, const std::vector<int>& mask) {
    const auto plane = probe.plane(channel);
    Eigen::VectorXd out(static_cast<Eigen::Index>(mask.size()));
    for (std::size_t i = 0; i < mask.size(); ++i)
        out[static_cast<Eigen::Index>(i)] = plane[static_cast<std::size_t>(mask[i])];
    return out;
}

// Eq. 7.11 and 7.12: the MAP coefficients of the training images for the masked probe s.
Eigen::VectorXd map_coefficients(const ImplicitModel::Channel& pca, const Eigen::VectorXd& s, double eta,
                                 std::size_t n) {
    const double nd = static_cast<double>(n);
    Eigen::VectorXd t = pca.u.transpose() * (s - pca.mean);
    for (Eigen::Index i = 0; i < t.size(); ++i) t[i] *= pca.w[i] / (pca.w[i] * pca.w[i] + nd * eta);
    // A 1 = 0 makes V's columns orthogonal to 1, so l~ sums to 0 and l to 1.
    const Eigen::VectorXd l_tilde = pca.v * t;
    return l_tilde.array() + (1.0 - l_tilde.sum()) / nd;
}

// The change of light that adds `lift` (>= 0) to the fitted probe, for the second pass.
// Fitting the lift with eq. 7.12 itself would add a whole mean light (its coefficients sum to
// 1, and the mean lies outside the centred span U): the scene would come out twice as
// bright. Instead the lift is explained by the training probes themselves, S dl = A dl_c +
// alpha mean, with dl = dl_c + alpha / n: a ridge solve on the centred span for the part
// U can give (prior centred on no change), and the amount alpha of the mean light for the
// part it cannot, by least squares on what U leaves over.
Eigen::VectorXd map_lift(const ImplicitModel::Channel& pca, const Eigen::VectorXd& lift, double eta,
                         std::size_t n) {
    const double nd = static_cast<double>(n);
    const Eigen::VectorXd mean_outside = pca.mean - pca.u * (pca.u.transpose() * pca.mean);
    const double outside = mean_outside.squaredNorm();
    const double alpha = outside > 0.0 ? std::max(0.0, mean_outside.dot(lift) / outside) : 0.0;
    Eigen::VectorXd t = pca.u.transpose() * (lift - alpha * pca.mean);
    for (Eigen::Index i = 0; i < t.size(); ++i) t[i] *= pca.w[i] / (pca.w[i] * pca.w[i] + nd * eta);
    return (pca.v * t).array() + alpha / nd;
}

// sum_i l_i S_i = A l + mean sum_i l_i, with A = U W V^T.
Eigen::VectorXd fitted_probe(const ImplicitModel::Channel& pca, const Eigen::VectorXd& l) {
    return pca.u * (pca.w.asDiagonal() * (pca.v.transpose() * l)) + pca.mean * l.sum();
}

std::size_t count_negative(const Eigen::VectorXd& values) {
    return static_cast<std::size_t>((values.array() < 0.0).count());
}

// A light as weighted directions: (unit direction toward the light, irradiance per channel).
using LightSamples = std::vector<std::pair<Eigen::Vector3d, Eigen::Array3d>>;

// The environment map, averaged down to at most kMapWidth x kMapWidth / 2 pixels (the probe's
// Phong lobe is several degrees wide), one sample per pixel weighted by its solid angle.
void add_environment_samples(const Image& radiance, LightSamples& samples) {
    constexpr int kMapWidth = 64;
    const int width = radiance.width(), height = radiance.height();
    const int out_width = std::min(width, kMapWidth), out_height = std::max(1, std::min(height, kMapWidth / 2));
    for (int v = 0; v < out_height; ++v) {
        const int y0 = v * height / out_height, y1 = (v + 1) * height / out_height;
        for (int u = 0; u < out_width; ++u) {
            const int x0 = u * width / out_width, x1 = (u + 1) * width / out_width;
            // Power of the block: radiance times each source pixel's solid angle.
            Eigen::Array3d power = Eigen::Array3d::Zero();
            for (int y = y0; y < y1; ++y) {
                const double solid_angle = (2.0 * kPi / width) * (std::cos(kPi * y / height) - std::cos(kPi * (y + 1) / height));
                for (int x = x0; x < x1; ++x)
                    for (int c = 0; c < 3; ++c)
                        power[c] += solid_angle * radiance.at(x, y, radiance.channels() == 1 ? 0 : c);
            }
            if ((power == 0.0).all()) continue;
            const double theta = kPi * (v + 0.5) / out_height;
            const double phi = -kPi + 2.0 * kPi * (u + 0.5) / out_width;
            samples.emplace_back(direction_from_angles(theta, phi), power);
        }
    }
}

LightSamples light_samples(const std::vector<Light>& lights) {
    constexpr std::size_t kDiskPoints = 1024;
    LightSamples samples;
    for (const Light& light : lights) {
        check_light(light);
        std::visit(
            [&](const auto& l) {
                using T = std::decay_t<decltype(l)>;
                if constexpr (std::is_same_v<T, DirectionalLight>) {
                    samples.emplace_back(l.direction.normalized(), l.irradiance.array());
                } else if constexpr (std::is_same_v<T, DiskLight>) {
                    const Eigen::Array3d share = l.irradiance.array() / static_cast<double>(kDiskPoints);
                    for (const Eigen::Vector3d& p : cap_points(l.direction.normalized(), l.radius, kDiskPoints))
                        samples.emplace_back(p, share);
                } else {
                    add_environment_samples(l.radiance, samples);
                }
            },
            light);
    }
    return samples;
}

// --- model files ---

nlohmann::json read_json(const std::filesystem::path& path) {
    std::ifstream in(path);
    if (!in) throw IoError(SourceLocation{path.string()}, "cannot read the model (is this an implicit-relighting model folder?)");
    try {
        return nlohmann::json::parse(in);
    } catch (const nlohmann::json::exception& e) {
        throw InputError(SourceLocation{path.string()}, std::string("not valid JSON: ") + e.what());
    }
}

template <typename T>
T field_of(const nlohmann::json& j, const char* key, const std::filesystem::path& file) {
    if (!j.contains(key)) throw InputError(SourceLocation{file.string(), 0, 0, key}, "missing");
    try {
        return j.at(key).get<T>();
    } catch (const nlohmann::json::exception&) {
        throw InputError(SourceLocation{file.string(), 0, 0, key}, "has the wrong type");
    }
}

// The probe's box and material, as implicit.json and probe.json both store them.
void put_probe(nlohmann::json& j, const ProbeDescription& probe) {
    j["probe_box"] = {probe.box.x, probe.box.y, probe.box.width, probe.box.height};
    if (probe.material) {
        const PhongMaterial& m = *probe.material;
        const Rgb* albedo = std::get_if<Rgb>(&m.albedo);
        if (!albedo) throw InputError("the probe's material must have a constant albedo, not a texture");
        j["probe_material"] = {{"type", "phong"},
                               {"albedo", {(*albedo)[0], (*albedo)[1], (*albedo)[2]}},
                               {"exponent", m.exponent},
                               {"ior", m.ior}};
    }
}

ProbeDescription get_probe(const nlohmann::json& j, const std::filesystem::path& file) {
    const auto where = [&](const char* key) { return SourceLocation{file.string(), 0, 0, key}; };
    ProbeDescription probe;
    const auto box = field_of<std::vector<double>>(j, "probe_box", file);
    if (box.size() != 4 || !(box[2] > 0.0 && box[3] > 0.0) ||
        std::any_of(box.begin(), box.end(), [](double x) { return !std::isfinite(x); }))
        throw InputError(where("probe_box"), "expected [x, y, width, height] with positive width and height");
    probe.box = {box[0], box[1], box[2], box[3]};
    if (j.contains("probe_material")) {
        const auto& m = j.at("probe_material");
        if (field_of<std::string>(m, "type", file) != "phong")
            throw InputError(where("probe_material"), "type: expected \"phong\"");
        PhongMaterial phong;
        const auto albedo = field_of<std::vector<double>>(m, "albedo", file);
        if (albedo.size() != 3 || std::any_of(albedo.begin(), albedo.end(), [](double x) { return !(x >= 0.0 && x <= 1.0); }))
            throw InputError(where("probe_material"), "albedo: expected 3 values within [0, 1]");
        phong.albedo = Rgb(albedo[0], albedo[1], albedo[2]);
        phong.exponent = field_of<double>(m, "exponent", file);
        phong.ior = field_of<double>(m, "ior", file);
        if (!(phong.exponent > 0.0 && phong.ior > 1.0 && std::isfinite(phong.exponent) && std::isfinite(phong.ior)))
            throw InputError(where("probe_material"), "expected a positive exponent and an ior above 1");
        probe.material = phong;
    }
    return probe;
}

// A matrix stored as an image: columns across, rows down, one channel per colour channel.
Image matrices_to_image(const std::vector<const Eigen::MatrixXd*>& matrices) {
    const auto rows = static_cast<int>(matrices.front()->rows()), cols = static_cast<int>(matrices.front()->cols());
    Image image(cols, rows, static_cast<int>(matrices.size()));
    for (std::size_t c = 0; c < matrices.size(); ++c)
        for (int y = 0; y < rows; ++y)
            for (int x = 0; x < cols; ++x)
                image.at(x, y, static_cast<int>(c)) = static_cast<float>((*matrices[c])(y, x));
    return image;
}

Eigen::MatrixXd image_to_matrix(const Image& image, int channel, int cols) {
    Eigen::MatrixXd m(image.height(), cols);
    for (int y = 0; y < image.height(); ++y)
        for (int x = 0; x < cols; ++x) m(y, x) = image.at(x, y, channel);
    return m;
}

Image read_model_image(const std::filesystem::path& path, int width, int height, int channels) {
    const Image image = read_image(path);
    if (image.width() != width || image.height() != height || image.channels() != channels)
        throw InputError(SourceLocation{path.string()},
                         "expected " + std::to_string(width) + " x " + std::to_string(height) + " with " +
                             std::to_string(channels) + " channel(s), as implicit.json says; found " +
                             std::to_string(image.width()) + " x " + std::to_string(image.height()) + " with " +
                             std::to_string(image.channels()));
    check_finite(image, path.string());
    return image;
}

}  // namespace

std::vector<int> probe_mask(int size) {
    std::vector<int> mask;
    const double centre = 0.5 * size, radius = 0.5 * size - 1.0;
    for (int y = 0; y < size; ++y)
        for (int x = 0; x < size; ++x) {
            const double dx = x + 0.5 - centre, dy = y + 0.5 - centre;
            if (dx * dx + dy * dy <= radius * radius) mask.push_back(y * size + x);
        }
    return mask;
}

Image crop_probe(const Image& image, const ProbeBox& box, int size) {
    if (size < 4) throw InputError("probe size must be at least 4 pixels, got " + std::to_string(size));
    std::ostringstream where;
    where << "probe box " << box.x << "," << box.y << "," << box.width << "," << box.height;
    if (!(std::isfinite(box.x) && std::isfinite(box.y) && box.width > 0.0 && box.height > 0.0 &&
          std::isfinite(box.width) && std::isfinite(box.height)))
        throw InputError(where.str() + ": expected a finite box of positive width and height");
    const double tolerance = 1e-6;
    if (box.x < -tolerance || box.y < -tolerance || box.x + box.width > image.width() + tolerance ||
        box.y + box.height > image.height() + tolerance)
        throw InputError(where.str() + ": reaches outside the " + std::to_string(image.width()) + " x " +
                         std::to_string(image.height()) + " image");

    // Shrinking: a gaussian low-pass of about half the scale first, so that each probe pixel
    // averages its footprint rather than sampling it.
    const double scale_x = box.width / size, scale_y = box.height / size;
    const double sigma_x = std::max(0.0, 0.5 * (scale_x - 1.0)), sigma_y = std::max(0.0, 0.5 * (scale_y - 1.0));
    const int margin = static_cast<int>(std::ceil(3.0 * std::max(sigma_x, sigma_y))) + 2;
    const int x0 = std::max(0, static_cast<int>(std::floor(box.x)) - margin);
    const int y0 = std::max(0, static_cast<int>(std::floor(box.y)) - margin);
    const int x1 = std::min(image.width(), static_cast<int>(std::ceil(box.x + box.width)) + margin);
    const int y1 = std::min(image.height(), static_cast<int>(std::ceil(box.y + box.height)) + margin);

    // The warp puts pixel centres at integers, continuous coordinates at +0.5: probe pixel j
    // samples the image at box.x + (j + 0.5) scale_x, which is the warp's x - 0.5.
    const std::array<double, 6> to_source = {scale_x, 0.0, box.x + 0.5 * scale_x - 0.5 - x0,  //
                                             0.0, scale_y, box.y + 0.5 * scale_y - 0.5 - y0};
    Image out(size, size, image.channels());
    const PlaneSize region_size{x1 - x0, y1 - y0};
    std::vector<float> region(region_size.area());
    for (int c = 0; c < image.channels(); ++c) {
        for (int y = y0; y < y1; ++y)
            for (int x = x0; x < x1; ++x)
                region[static_cast<std::size_t>(y - y0) * static_cast<std::size_t>(region_size.width) +
                       static_cast<std::size_t>(x - x0)] = image.at(x, y, c);
        if (sigma_x > 0.0 || sigma_y > 0.0)
            vision().gaussian_blur(region_size, region, region, 0, std::max(sigma_x, 1e-3), std::max(sigma_y, 1e-3),
                                   Border::Replicate);
        vision().warp_affine(region_size, region, to_source, {size, size}, out.plane(c), Border::Replicate);
    }
    std::vector<char> inside(static_cast<std::size_t>(size * size), 0);
    for (const int i : probe_mask(size)) inside[static_cast<std::size_t>(i)] = 1;
    for (int c = 0; c < out.channels(); ++c) {
        auto plane = out.plane(c);
        for (std::size_t i = 0; i < plane.size(); ++i)
            if (!inside[i]) plane[i] = 0.0f;
    }
    return out;
}

ImplicitModel train_implicit(const std::vector<Image>& probes) {
    if (probes.size() < 2)
        throw InputError("implicit relighting needs at least 2 training images, got " + std::to_string(probes.size()));
    const Image& first = probes.front();
    if (first.width() != first.height() || first.width() < 4)
        throw InputError("training probes must be square and at least 4 pixels wide");
    for (std::size_t i = 0; i < probes.size(); ++i) {
        if (!probes[i].same_shape(first))
            throw InputError("training probe " + std::to_string(i) + " differs in size or channels from the first");
        check_finite(probes[i], "training probe " + std::to_string(i));
    }
    ImplicitModel model;
    model.size = first.width();
    model.channels = first.channels();
    model.mask = probe_mask(model.size);
    model.count = probes.size();
    model.pca.resize(static_cast<std::size_t>(model.channels));
    const auto n = static_cast<Eigen::Index>(probes.size());
    const auto pixels = static_cast<Eigen::Index>(model.mask.size());
    std::vector<double> noise(static_cast<std::size_t>(model.channels), 0.0);

    parallel_for_chunks(static_cast<std::size_t>(model.channels), 1, [&](std::size_t begin, std::size_t end) {
        for (std::size_t c = begin; c < end; ++c) {
            Eigen::MatrixXd a(pixels, n);
            for (Eigen::Index i = 0; i < n; ++i)
                a.col(i) = masked(probes[static_cast<std::size_t>(i)], static_cast<int>(c), model.mask);
            ImplicitModel::Channel& pca = model.pca[c];
            pca.mean = a.rowwise().mean();
            a.colwise() -= pca.mean;
            // Jacobi rather than divide-and-conquer (BDCSVD): as accurate or more, fast enough
            // for a few hundred probes, and a third of the compile time (BDCSVD alone took 37 s
            // of this file's build, 94 s under the sanitizers).
            const Eigen::JacobiSVD<Eigen::MatrixXd> svd(a, Eigen::ComputeThinU | Eigen::ComputeThinV);
            const Eigen::VectorXd& w = svd.singularValues();
            // Directions the probes do not vary along (the centring removes one) carry no
            // light: dropped, so that eta = 0 is the pseudo-inverse rather than a division by 0.
            Eigen::Index rank = 0;
            while (rank < w.size() && w[rank] > 1e-9 * w[0]) ++rank;
            pca.w = w.head(rank);
            pca.u = svd.matrixU().leftCols(rank);
            pca.v = svd.matrixV().leftCols(rank);
            // Noise: the median squared singular value of the spectrum's lower half (rank
            // n - 1 after centring), per masked pixel.
            const Eigen::Index last = std::min<Eigen::Index>(w.size(), n - 1);
            std::vector<double> tail;
            for (Eigen::Index i = last / 2; i < last; ++i) tail.push_back(w[i] * w[i]);
            if (!tail.empty()) {
                std::nth_element(tail.begin(), tail.begin() + static_cast<std::ptrdiff_t>(tail.size() / 2), tail.end());
                noise[c] = tail[tail.size() / 2] / static_cast<double>(pixels);
            }
        }
    });
    for (const double v : noise) model.noise_variance += v / static_cast<double>(noise.size());
    return model;
}

LightCoefficients ImplicitFit::coefficients() const {
    Eigen::MatrixX3d k(l.rows(), 3);
    for (int c = 0; c < 3; ++c) k.col(c) = l.col(l.cols() == 1 ? 0 : c);
    return coefficients_from(std::move(k));
}

ImplicitFit implicit_fit(const ImplicitModel& model, const Image& probe, const ImplicitOptions& options) {
    if (probe.width() != model.size || probe.height() != model.size || probe.channels() != model.channels)
        throw InputError("the probe image is " + std::to_string(probe.width()) + " x " + std::to_string(probe.height()) +
                         " with " + std::to_string(probe.channels()) + " channel(s); the model expects " +
                         std::to_string(model.size) + " x " + std::to_string(model.size) + " with " +
                         std::to_string(model.channels));
    if (!(options.eta >= 0.0) || !std::isfinite(options.eta))
        throw InputError("eta must be finite and non-negative, got " + std::to_string(options.eta));
    if (!(options.second_pass_eta_scale >= 0.0)) throw InputError("the second pass's eta scale must be non-negative");
    check_finite(probe, "probe image");

    ImplicitFit fit;
    fit.l.resize(static_cast<Eigen::Index>(model.count), model.channels);
    fit.probe = Image(model.size, model.size, model.channels);
    double squared_residual = 0.0;
    for (int c = 0; c < model.channels; ++c) {
        const ImplicitModel::Channel& pca = model.pca[static_cast<std::size_t>(c)];
        const Eigen::VectorXd s = masked(probe, c, model.mask);
        Eigen::VectorXd l = map_coefficients(pca, s, options.eta, model.count);
        Eigen::VectorXd fitted = fitted_probe(pca, l);
        fit.negative_first += count_negative(fitted);
        if (options.second_pass && (fitted.array() < 0.0).any()) {
            const Eigen::VectorXd lift = (-fitted).cwiseMax(0.0);
            l += map_lift(pca, lift, options.eta * options.second_pass_eta_scale, model.count);
            fitted = fitted_probe(pca, l);
        }
        fit.negative_final += count_negative(fitted);
        squared_residual += (fitted - s).squaredNorm();
        fit.l.col(c) = l;
        auto plane = fit.probe.plane(c);
        for (std::size_t i = 0; i < model.mask.size(); ++i)
            plane[static_cast<std::size_t>(model.mask[i])] = static_cast<float>(fitted[static_cast<Eigen::Index>(i)]);
    }
    fit.residual_rms =
        std::sqrt(squared_residual / static_cast<double>(model.mask.size() * static_cast<std::size_t>(model.channels)));
    return fit;
}

Image render_probe(const std::vector<Light>& lights, const Material& material, int size) {
    if (size < 4) throw InputError("probe size must be at least 4 pixels, got " + std::to_string(size));
    const Albedo* albedo = albedo_of(material);
    if (!albedo)
        throw InputError("a synthetic probe needs a diffuse, glossy or phong material (mirror and glass are not "
                         "rendered)");
    const Rgb* colour = std::get_if<Rgb>(albedo);
    if (!colour) throw InputError("a synthetic probe needs a constant albedo, not a texture");
    const LightSamples samples = light_samples(lights);
    Image out(size, size, 3);
    const Eigen::Vector3d view = Eigen::Vector3d::UnitZ();
    parallel_for_chunks(static_cast<std::size_t>(size), 1, [&](std::size_t begin, std::size_t end) {
        for (std::size_t row = begin; row < end; ++row) {
            const int y = static_cast<int>(row);
            for (int x = 0; x < size; ++x) {
                const double u = 2.0 * (x + 0.5) / size - 1.0, v = 1.0 - 2.0 * (y + 0.5) / size;
                const double r2 = u * u + v * v;
                if (r2 >= 1.0) continue;
                const Eigen::Vector3d n(u, v, std::sqrt(1.0 - r2));
                Eigen::Array3d radiance = Eigen::Array3d::Zero();
                for (const auto& [w, irradiance] : samples) {
                    const double cosine = n.dot(w);
                    if (cosine <= 0.0) continue;
                    radiance += surface_brdf(material, n, view, w, *colour) * cosine * irradiance;
                }
                for (int c = 0; c < 3; ++c) out.at(x, y, c) = static_cast<float>(radiance[c]);
            }
        }
    });
    return out;
}

void write_implicit_model(const std::filesystem::path& folder, const ImplicitModelFiles& files) {
    const ImplicitModel& model = files.model;
    RFD_CHECK(model.channels > 0 && static_cast<std::size_t>(model.channels) == model.pca.size());
    RFD_CHECK(files.images.size() == model.count);
    ensure_directory(folder);
    std::error_code ignored;
    std::filesystem::remove(folder / kModelFile, ignored);  // a reader never sees old json with new matrices

    // Every channel is stored with the largest rank; the missing columns are zero.
    Eigen::Index rank = 0;
    for (const auto& pca : model.pca) rank = std::max(rank, pca.w.size());
    std::vector<Eigen::MatrixXd> us, vs;
    nlohmann::json singular = nlohmann::json::array();
    Image mean(model.size, model.size, model.channels);
    for (int c = 0; c < model.channels; ++c) {
        const auto& pca = model.pca[static_cast<std::size_t>(c)];
        Eigen::MatrixXd u = Eigen::MatrixXd::Zero(pca.u.rows(), rank), v = Eigen::MatrixXd::Zero(pca.v.rows(), rank);
        u.leftCols(pca.w.size()) = pca.u;
        v.leftCols(pca.w.size()) = pca.v;
        us.push_back(std::move(u));
        vs.push_back(std::move(v));
        singular.push_back(std::vector<double>(pca.w.data(), pca.w.data() + pca.w.size()));
        auto plane = mean.plane(c);
        for (std::size_t i = 0; i < model.mask.size(); ++i)
            plane[static_cast<std::size_t>(model.mask[i])] = static_cast<float>(pca.mean[static_cast<Eigen::Index>(i)]);
    }
    std::vector<const Eigen::MatrixXd*> u_ptrs, v_ptrs;
    for (const auto& u : us) u_ptrs.push_back(&u);
    for (const auto& v : vs) v_ptrs.push_back(&v);
    write_image(folder / "probe_mean.exr", mean);
    write_image(folder / "probe_u.exr", matrices_to_image(u_ptrs));
    write_image(folder / "probe_v.exr", matrices_to_image(v_ptrs));

    const std::filesystem::path base = std::filesystem::absolute(folder).lexically_normal();
    nlohmann::json images = nlohmann::json::array();
    for (const auto& image : files.images)
        images.push_back(std::filesystem::absolute(image).lexically_normal().lexically_relative(base).generic_string());
    nlohmann::json j = {{"format", kModelFormat},
                        {"version", kModelVersion},
                        {"probe_size", model.size},
                        {"channels", model.channels},
                        {"training_images", images},
                        {"rank", rank},
                        {"singular_values", singular},
                        {"noise_variance", model.noise_variance}};
    put_probe(j, {files.box, files.probe_material});
    write_text_file(folder / kModelFile, j.dump(2) + "\n");
}

ImplicitModelFiles read_implicit_model(const std::filesystem::path& folder) {
    const std::filesystem::path file = folder / kModelFile;
    const nlohmann::json j = read_json(file);
    const auto where = [&](const char* key) { return SourceLocation{file.string(), 0, 0, key}; };
    if (field_of<std::string>(j, "format", file) != kModelFormat)
        throw InputError(where("format"), std::string("expected \"") + kModelFormat + "\"");
    if (field_of<int>(j, "version", file) != kModelVersion)
        throw InputError(where("version"), "this rfd reads version " + std::to_string(kModelVersion));
    ImplicitModelFiles files;
    ImplicitModel& model = files.model;
    model.size = field_of<int>(j, "probe_size", file);
    if (model.size < 4 || model.size > 4096) throw InputError(where("probe_size"), "expected 4..4096");
    model.channels = field_of<int>(j, "channels", file);
    if (model.channels != 1 && model.channels != 3) throw InputError(where("channels"), "expected 1 or 3");
    const ProbeDescription probe = get_probe(j, file);
    files.box = probe.box;
    files.probe_material = probe.material;
    for (const auto& name : field_of<std::vector<std::string>>(j, "training_images", file))
        files.images.push_back((folder / name).lexically_normal());
    model.count = files.images.size();
    if (model.count < 2) throw InputError(where("training_images"), "expected at least 2 images");
    const int rank = field_of<int>(j, "rank", file);
    if (rank < 1 || static_cast<std::size_t>(rank) > model.count) throw InputError(where("rank"), "expected 1..n");
    const auto singular = field_of<std::vector<std::vector<double>>>(j, "singular_values", file);
    if (singular.size() != static_cast<std::size_t>(model.channels))
        throw InputError(where("singular_values"), "expected one list per channel");
    model.noise_variance = field_of<double>(j, "noise_variance", file);
    model.mask = probe_mask(model.size);
    const auto pixels = static_cast<int>(model.mask.size());
    const Image mean = read_model_image(folder / "probe_mean.exr", model.size, model.size, model.channels);
    const Image u = read_model_image(folder / "probe_u.exr", rank, pixels, model.channels);
    const Image v = read_model_image(folder / "probe_v.exr", rank, static_cast<int>(model.count), model.channels);
    for (int c = 0; c < model.channels; ++c) {
        ImplicitModel::Channel pca;
        const auto& w = singular[static_cast<std::size_t>(c)];
        if (w.empty() || w.size() > static_cast<std::size_t>(rank) ||
            std::any_of(w.begin(), w.end(), [](double x) { return !(x > 0.0) || !std::isfinite(x); }))
            throw InputError(where("singular_values"), "expected 1..rank positive values per channel");
        const auto k = static_cast<int>(w.size());
        pca.w = Eigen::Map<const Eigen::VectorXd>(w.data(), k);
        pca.u = image_to_matrix(u, c, k);
        pca.v = image_to_matrix(v, c, k);
        pca.mean = masked(mean, c, model.mask);
        model.pca.push_back(std::move(pca));
    }
    return files;
}

void write_probe_description(const std::filesystem::path& file, const ProbeDescription& probe) {
    nlohmann::json j = {{"format", kProbeFormat}};
    put_probe(j, probe);
    write_text_file(file, j.dump(2) + "\n");
}

ProbeDescription read_probe_description(const std::filesystem::path& file) {
    const nlohmann::json j = read_json(file);
    if (field_of<std::string>(j, "format", file) != kProbeFormat)
        throw InputError(SourceLocation{file.string(), 0, 0, "format"}, std::string("expected \"") + kProbeFormat + "\"");
    return get_probe(j, file);
}

namespace {

bool is_image_file(const std::filesystem::path& path) {
    const std::string ext = lower_extension(path);
    return ext == ".exr" || ext == ".hdr" || ext == ".png" || ext == ".jpg" || ext == ".jpeg" || ext == ".tif" ||
           ext == ".tiff";
}

}  // namespace

std::vector<std::filesystem::path> field_image_files(const std::filesystem::path& field) {
    const std::filesystem::path lp = light_file_of(field);
    std::vector<std::filesystem::path> files;
    for (const auto& entry : read_light_file(lp)) files.push_back(entry.path);
    return files;
}

std::vector<std::filesystem::path> training_image_files(const std::filesystem::path& training) {
    std::vector<std::filesystem::path> lp_files;
    if (std::filesystem::is_directory(training)) {
        for (const auto& entry : std::filesystem::directory_iterator(training))
            if (entry.path().extension() == ".lp") lp_files.push_back(entry.path());
    } else if (training.extension() == ".lp") {
        lp_files.push_back(training);
    } else {
        throw InputError(SourceLocation{training.string()}, "expected a folder of images or a .lp light file");
    }
    std::vector<std::filesystem::path> images;
    if (!lp_files.empty()) {
        images = field_image_files(training);
    } else {
        for (const auto& entry : std::filesystem::directory_iterator(training))
            if (entry.is_regular_file() && is_image_file(entry.path())) images.push_back(entry.path());
        std::sort(images.begin(), images.end());
    }
    if (images.size() < 2)
        throw InputError(SourceLocation{training.string()},
                         "implicit relighting needs at least 2 training images, found " + std::to_string(images.size()));
    return images;
}

const SceneObject& probe_object(const Scene& scene, const std::string& name, const std::string& scene_file) {
    const SceneObject* found = nullptr;
    std::size_t phong_spheres = 0;
    for (const auto& object : scene.objects) {
        if (!name.empty()) {
            if (object.name == name) found = &object;
            continue;
        }
        if (std::holds_alternative<SphereShape>(object.shape) &&
            std::holds_alternative<PhongMaterial>(scene.materials[object.material])) {
            found = &object;
            ++phong_spheres;
        }
    }
    if (!name.empty() && !found)
        throw InputError(SourceLocation{scene_file}, "--probe " + name + ": no object of that name");
    if (name.empty() && phong_spheres != 1)
        throw InputError(SourceLocation{scene_file},
                         "found " + std::to_string(phong_spheres) +
                             " spheres of a phong material; name the probe object with --probe NAME");
    if (!std::holds_alternative<SphereShape>(found->shape))
        throw InputError(SourceLocation{scene_file}, "--probe " + found->name + ": the probe must be a sphere");
    return *found;
}

}  // namespace rfd::relight
