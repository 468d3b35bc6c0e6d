#include "relight/render.hpp"

#include <algorithm>
#include <cmath>
#include <functional>
#include <memory>
#include <string>
#include <type_traits>
#include <utility>

#include "core/error.hpp"
#include "core/image_io.hpp"
#include "core/parallel.hpp"
#include "core/progress.hpp"
#include "core/sphere.hpp"
#include "core/units.hpp"

namespace rfd::relight {
namespace {

// Mean angular spacing of n directions over the hemisphere (2 pi sr), radians.
double mean_spacing(std::size_t n) { return std::sqrt(2.0 * kPi / static_cast<double>(n)); }

void check_irradiance(const Eigen::Vector3d& irradiance, const char* what) {
    if (!irradiance.allFinite() || (irradiance.array() < 0.0).any())
        throw InputError(std::string(what) + ": the colour must be finite and non-negative");
}

void check_direction(const Eigen::Vector3d& direction, const char* what) {
    if (!direction.allFinite() || direction.norm() == 0.0)
        throw InputError(std::string(what) + ": the direction must be a non-zero vector");
}

void add_weights(Eigen::MatrixX3d& k, const InterpolationWeights& w, const Eigen::Vector3d& scale) {
    for (std::size_t j = 0; j < w.count; ++j)
        k.row(static_cast<Eigen::Index>(w.index[j])) += w.weight[j] * scale.transpose();
}

// Two unit vectors completing d to a right-handed orthonormal frame.
std::pair<Eigen::Vector3d, Eigen::Vector3d> frame_around(const Eigen::Vector3d& d) {
    const Eigen::Vector3d helper = std::abs(d.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
    const Eigen::Vector3d u = d.cross(helper).normalized();
    return {u, d.cross(u)};
}

// k += w(d) scale^T for a unit d: a model's weights, added.
using AddWeightsAt = std::function<void(Eigen::MatrixX3d& k, const Eigen::Vector3d& d, const Eigen::Vector3d& scale)>;

std::size_t add_directional(Eigen::MatrixX3d& k, const AddWeightsAt& add_at, const DirectionalLight& light) {
    check_light(light);
    const Eigen::Vector3d d = light.direction.normalized();
    if (d.z() < 0.0) return 0;  // below the horizon: dropped
    add_at(k, d, light.irradiance);
    return 1;
}

std::size_t add_disk(Eigen::MatrixX3d& k, const AddWeightsAt& add_at, const DiskLight& light) {
    check_light(light);
    const Eigen::Vector3d d = light.direction.normalized();
    const double solid_angle = 2.0 * kPi * (1.0 - std::cos(light.radius));
    const double step = 0.25 * mean_spacing(static_cast<std::size_t>(k.rows()));
    const auto count = static_cast<std::size_t>(
        std::clamp(std::ceil(solid_angle / (step * step)), 16.0, 4096.0));
    const Eigen::Vector3d share = light.irradiance / static_cast<double>(count);
    for (const Eigen::Vector3d& p : cap_points(d, light.radius, count)) {
        if (p.z() < 0.0) continue;
        add_at(k, p, share);
    }
    return count;
}

std::size_t add_environment(Eigen::MatrixX3d& k, const AddWeightsAt& add_at, const EnvironmentMap& map) {
    const Image& image = map.radiance;
    check_environment_map(image);
    const int width = image.width(), height = image.height();
    const double pixel_phi = 2.0 * kPi / width, pixel_theta = kPi / height;
    const double step = 0.25 * mean_spacing(static_cast<std::size_t>(k.rows()));
    const int sub_theta = static_cast<int>(std::clamp(std::ceil(pixel_theta / step), 1.0, 16.0));
    const int sub_phi = static_cast<int>(std::clamp(std::ceil(pixel_phi / step), 1.0, 16.0));
    // Rows above the horizon only; each row accumulates its own k, summed in row order.
    const int rows = std::min(height, static_cast<int>(std::ceil(0.5 * height - 1e-9)));
    std::vector<Eigen::MatrixX3d> row_k(static_cast<std::size_t>(rows));
    Progress progress("environment map", static_cast<std::size_t>(rows));
    parallel_for_chunks(static_cast<std::size_t>(rows), 1, [&](std::size_t begin, std::size_t end) {
        for (std::size_t row = begin; row < end; ++row) {
            Eigen::MatrixX3d& kr = row_k[row];
            kr.setZero(k.rows(), 3);
            const double theta0 = pixel_theta * static_cast<double>(row);
            const double theta1 = std::min(theta0 + pixel_theta, 0.5 * kPi);
            const double sub_height = (theta1 - theta0) / sub_theta, sub_width = pixel_phi / sub_phi;
            for (int a = 0; a < sub_theta; ++a) {
                const double ta = theta0 + a * sub_height, tb = ta + sub_height;
                const double solid_angle = sub_width * (std::cos(ta) - std::cos(tb));
                const double theta = 0.5 * (ta + tb);
                for (int u = 0; u < width; ++u) {
                    Eigen::Vector3d radiance;
                    for (int c = 0; c < 3; ++c)
                        radiance[c] = image.at(u, static_cast<int>(row), image.channels() == 1 ? 0 : c);
                    if (radiance.isZero()) continue;
                    for (int b = 0; b < sub_phi; ++b) {
                        const double phi = -kPi + u * pixel_phi + (b + 0.5) * sub_width;
                        add_at(kr, direction_from_angles(theta, phi), solid_angle * radiance);
                    }
                }
            }
            progress.advance();
        }
    });
    progress.finish();
    for (const auto& kr : row_k) k += kr;
    return static_cast<std::size_t>(rows) * static_cast<std::size_t>(width * sub_theta * sub_phi);
}

}  // namespace

std::vector<Eigen::Vector3d> cap_points(const Eigen::Vector3d& centre, double radius, std::size_t count) {
    const auto [u, v] = frame_around(centre);
    const double golden_angle = kPi * (3.0 - std::sqrt(5.0));
    std::vector<Eigen::Vector3d> points;
    points.reserve(count);
    for (std::size_t s = 0; s < count; ++s) {
        // Equal solid angle per point: cos(alpha) uniform over [cos r, 1].
        const double cos_alpha = 1.0 - (static_cast<double>(s) + 0.5) / static_cast<double>(count) *
                                           (1.0 - std::cos(radius));
        const double sin_alpha = std::sqrt(std::max(0.0, 1.0 - cos_alpha * cos_alpha));
        const double beta = golden_angle * static_cast<double>(s);
        points.push_back(cos_alpha * centre + sin_alpha * (std::cos(beta) * u + std::sin(beta) * v));
    }
    return points;
}

void check_light(const Light& light) {
    std::visit(
        [](const auto& l) {
            using T = std::decay_t<decltype(l)>;
            if constexpr (std::is_same_v<T, DirectionalLight>) {
                check_irradiance(l.irradiance, "directional light");
                check_direction(l.direction, "directional light");
            } else if constexpr (std::is_same_v<T, DiskLight>) {
                check_irradiance(l.irradiance, "disk light");
                if (!(l.radius > 0.0 && l.radius <= 0.5 * kPi))
                    throw InputError("disk light: the angular radius must be within (0, 90] degrees, got " +
                                     std::to_string(radians_to_degrees(l.radius)));
                check_direction(l.direction, "disk light");
            } else {
                check_environment_map(l.radiance);
            }
        },
        light);
}

void check_environment_map(const Image& radiance) {
    if (radiance.empty() || (radiance.channels() != 1 && radiance.channels() != 3))
        throw InputError("environment map: expected a latitude-longitude image with 1 or 3 channels, got " +
                         std::to_string(radiance.channels()) + " channel(s)");
    for (const float s : radiance.samples())
        if (!(s >= 0.0f) || !std::isfinite(s))
            throw InputError("environment map: radiance must be finite and non-negative (found " +
                             std::to_string(s) + ")");
}

namespace {

LightCoefficients coefficients_of(std::size_t images, const AddWeightsAt& add_at, const std::vector<Light>& lights) {
    LightCoefficients out;
    out.k.setZero(static_cast<Eigen::Index>(images), 3);
    for (const Light& light : lights) {
        out.weight_evaluations += std::visit(
            [&](const auto& l) -> std::size_t {
                using T = std::decay_t<decltype(l)>;
                if constexpr (std::is_same_v<T, DirectionalLight>) return add_directional(out.k, add_at, l);
                else if constexpr (std::is_same_v<T, DiskLight>) return add_disk(out.k, add_at, l);
                else return add_environment(out.k, add_at, l);
            },
            light);
    }
    const std::size_t evaluations = out.weight_evaluations;
    out = coefficients_from(std::move(out.k));
    out.weight_evaluations = evaluations;
    return out;
}

}  // namespace

LightCoefficients light_coefficients(const SphericalInterpolator& interpolator, const std::vector<Light>& lights,
                                     Interpolation method) {
    return coefficients_of(
        interpolator.size(),
        [&](Eigen::MatrixX3d& k, const Eigen::Vector3d& d, const Eigen::Vector3d& scale) {
            add_weights(k, interpolator.weights(d, method), scale);
        },
        lights);
}

LightCoefficients light_coefficients(const LightWeights& weights, const std::vector<Light>& lights) {
    return coefficients_of(
        weights.size(),
        [&](Eigen::MatrixX3d& k, const Eigen::Vector3d& d, const Eigen::Vector3d& scale) {
            k += weights.at(d) * scale.transpose();
        },
        lights);
}

LightCoefficients coefficients_from(Eigen::MatrixX3d k) {
    LightCoefficients out;
    out.k = std::move(k);
    for (Eigen::Index i = 0; i < out.k.rows(); ++i) {
        if ((out.k.row(i).array() != 0.0).any()) ++out.nonzero;
        out.grey = out.grey && out.k(i, 0) == out.k(i, 1) && out.k(i, 1) == out.k(i, 2);
    }
    return out;
}

Image relight(const ReflectanceField& field, const LightCoefficients& coefficients) {
    RFD_CHECK(static_cast<std::size_t>(coefficients.k.rows()) == field.size());
    return relight(field.images, coefficients);
}

namespace {

// One image's share of an output channel.
struct Term {
    const float* plane;
    float k;
};

// Per channel of one output image, the images with a non-zero coefficient, in image order;
// those with only zero coefficients may be empty (a band of the images a light needs).
struct Terms {
    int width = 0, height = 0;
    std::vector<std::vector<Term>> channels;
};

Terms terms_of(const std::vector<Image>& images, const LightCoefficients& coefficients) {
    RFD_CHECK(static_cast<std::size_t>(coefficients.k.rows()) == images.size());
    const auto found = std::find_if(images.begin(), images.end(), [](const Image& image) { return !image.empty(); });
    RFD_CHECK(found != images.end());
    const Image& shape = *found;
    for (std::size_t i = 0; i < images.size(); ++i)
        RFD_CHECK(images[i].empty() ? coefficients.k.row(static_cast<Eigen::Index>(i)).isZero()
                                    : images[i].same_shape(shape));
    const int field_channels = shape.channels();
    const bool colour_light = !coefficients.grey;
    if (colour_light && field_channels != 1 && field_channels != 3)
        throw InputError("coloured light needs a field with 1 or 3 channels; this one has " +
                         std::to_string(field_channels));
    Terms terms{shape.width(), shape.height(), {}};
    terms.channels.resize(static_cast<std::size_t>(colour_light ? 3 : field_channels));
    for (int c = 0; c < static_cast<int>(terms.channels.size()); ++c) {
        const int light_channel = colour_light ? c : (field_channels == 3 ? c : 0);
        const int field_channel = field_channels == 1 ? 0 : c;
        for (std::size_t i = 0; i < images.size(); ++i) {
            const double k = coefficients.k(static_cast<Eigen::Index>(i), light_channel);
            if (k != 0.0) terms.channels[static_cast<std::size_t>(c)].push_back({images[i].plane(field_channel).data(),
                                                                                 static_cast<float>(k)});
        }
    }
    return terms;
}

// acc[p] = sum of k * plane[first + p] over `list`, p < count, each pixel summed in image
// order: the bits depend on neither the block nor the thread. Compiled for AVX2 machines and
// for the baseline, bit-identical without contraction (cmake/flags.cmake); Clang 14 cannot
// flatten a multiversioned function, as optics/paraxial.cpp says.
#ifndef __clang__
__attribute__((target_clones("arch=x86-64-v3", "default")))
#endif
void accumulate(const std::vector<Term>& list, std::size_t first, std::size_t count, float* __restrict acc) {
    // Four images per sweep of the accumulator (a quarter of its loads and stores); the
    // additions stay in image order, so the bits do not change.
    std::size_t t = 0;
    for (; t + 4 <= list.size(); t += 4) {
        const float* __restrict s0 = list[t].plane + first;
        const float* __restrict s1 = list[t + 1].plane + first;
        const float* __restrict s2 = list[t + 2].plane + first;
        const float* __restrict s3 = list[t + 3].plane + first;
        const float k0 = list[t].k, k1 = list[t + 1].k, k2 = list[t + 2].k, k3 = list[t + 3].k;
        for (std::size_t p = 0; p < count; ++p) {
            float a = acc[p];
            a += k0 * s0[p];
            a += k1 * s1[p];
            a += k2 * s2[p];
            a += k3 * s3[p];
            acc[p] = a;
        }
    }
    for (; t < list.size(); ++t) {
        const float* __restrict src = list[t].plane + first;
        const float k = list[t].k;
        for (std::size_t p = 0; p < count; ++p) acc[p] += k * src[p];
    }
}

// Every output of `terms` over its pixels, in blocks small enough that the accumulators
// stay in the L1 cache and the images' block in L2 while every output reads it.
std::vector<Image> relight_blocks(const std::vector<Terms>& terms, Progress* progress) {
    std::vector<Image> out;
    for (const Terms& t : terms) out.emplace_back(t.width, t.height, static_cast<int>(t.channels.size()));
    const std::size_t block = terms.size() == 1 ? 4096 : 1024;
    const std::size_t pixels = out.front().pixel_count();
    const std::size_t blocks = (pixels + block - 1) / block;
    parallel_for_chunks(blocks, 1, [&](std::size_t begin, std::size_t end) {
        for (std::size_t b = begin; b < end; ++b) {
            const std::size_t first = b * block, count = std::min(block, pixels - first);
            for (std::size_t j = 0; j < terms.size(); ++j)
                for (std::size_t c = 0; c < terms[j].channels.size(); ++c)
                    accumulate(terms[j].channels[c], first, count, out[j].plane(static_cast<int>(c)).data() + first);
            if (progress != nullptr) progress->advance();
        }
    });
    return out;
}

}  // namespace

Image relight(const std::vector<Image>& images, const LightCoefficients& coefficients) {
    const Terms terms = terms_of(images, coefficients);
    Progress progress("relighting", (static_cast<std::size_t>(terms.width) * terms.height + 4095) / 4096);
    Image out = std::move(relight_blocks({terms}, &progress).front());
    progress.finish();
    return out;
}

std::size_t relight_to_files(FieldReader& reader, const std::vector<LightCoefficients>& coefficients,
                      const std::vector<std::filesystem::path>& outs, std::size_t band_bytes) {
    RFD_CHECK(coefficients.size() == outs.size() && !outs.empty());
    // The images some light needs: the others are never decoded.
    std::vector<bool> wanted(reader.size(), false);
    std::size_t images = 0, planes = 0;
    for (const LightCoefficients& k : coefficients) {
        RFD_CHECK(static_cast<std::size_t>(k.k.rows()) == reader.size());
        planes += static_cast<std::size_t>(k.grey ? reader.channels() : 3);
        for (std::size_t i = 0; i < reader.size(); ++i) wanted[i] = wanted[i] || !k.k.row(static_cast<Eigen::Index>(i)).isZero();
    }
    images = static_cast<std::size_t>(std::count(wanted.begin(), wanted.end(), true));
    if (images == 0) wanted[0] = true;  // every light below the horizon: black images of the field's shape
    std::vector<std::unique_ptr<ImageBandWriter>> writers;
    for (std::size_t j = 0; j < outs.size(); ++j) {
        const int channels = coefficients[j].grey ? reader.channels() : 3;
        writers.push_back(std::make_unique<ImageBandWriter>(outs[j], reader.width(), reader.height(), channels));
    }
    const int rows = reader.band_rows(std::max<std::size_t>(images, 1), planes, band_bytes);
    Progress progress("relighting", static_cast<std::size_t>((reader.height() + rows - 1) / rows));
    for (int y0 = 0; y0 < reader.height(); y0 += rows) {
        const int y1 = std::min(y0 + rows, reader.height());
        const std::vector<Image> band = reader.read_band(y0, y1, wanted);
        std::vector<Terms> terms;
        for (const LightCoefficients& k : coefficients) terms.push_back(terms_of(band, k));
        const std::vector<Image> relit = relight_blocks(terms, nullptr);
        // The outputs' encoders (zlib, libjpeg) are single-threaded: one output per task.
        parallel_for_chunks(outs.size(), 1, [&](std::size_t begin, std::size_t end) {
            for (std::size_t j = begin; j < end; ++j) writers[j]->write(relit[j]);
        });
        progress.advance();
    }
    for (auto& writer : writers) writer->finish();
    progress.finish();
    return images;
}

Image render(const ReflectanceField& field, const std::vector<Light>& lights, Interpolation method) {
    const SphericalInterpolator interpolator(field.directions);
    return relight(field, light_coefficients(interpolator, lights, method));
}

}  // namespace rfd::relight
