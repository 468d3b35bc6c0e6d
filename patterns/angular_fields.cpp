#include "patterns/angular_fields.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

#include "core/error.hpp"
#include "core/sphere.hpp"
#include "core/units.hpp"
#include "patterns/glyphs.hpp"
#include "core/text.hpp"

namespace rfd::patterns {
namespace {

// ----- view sets -----

class ViewSetLookup : public AngularLookup {
public:
    ViewSetLookup(std::vector<float> table, std::size_t views, int cells, int channels,
                  std::unique_ptr<relight::SphericalInterpolator> interpolator, int macro_x)
        : table_(std::move(table)), views_(views), cells_(cells), channels_(channels),
          interpolator_(std::move(interpolator)), macro_x_(macro_x) {}

    void value(std::size_t bin, const Eigen::Vector3d& view, int u, int v,
               std::span<float> out) const override {
        const std::size_t cell = static_cast<std::size_t>(v) * static_cast<std::size_t>(macro_x_) +
                                 static_cast<std::size_t>(u);
        std::fill(out.begin(), out.end(), 0.0f);
        auto add = [&](std::size_t view_index, double weight) {
            const float* values = &table_[((bin * views_ + view_index) * static_cast<std::size_t>(cells_) + cell) *
                                          static_cast<std::size_t>(channels_)];
            for (int c = 0; c < channels_; ++c) out[static_cast<std::size_t>(c)] += static_cast<float>(weight * values[c]);
        };
        if (!interpolator_) {
            add(0, 1.0);
            return;
        }
        const relight::InterpolationWeights w = interpolator_->weights(view);
        for (std::size_t k = 0; k < w.count; ++k) add(w.index[k], w.weight[k]);
    }

private:
    std::vector<float> table_;  // [bin][view][macro cell][channel]
    std::size_t views_;
    int cells_, channels_;
    std::unique_ptr<relight::SphericalInterpolator> interpolator_;
    int macro_x_;
};

// ----- letters -----

class LetterLookup : public AngularLookup {
public:
    LetterLookup(const LetterField& field, std::vector<std::vector<double>> fractions)
        : field_(field), fractions_(std::move(fractions)) {}
    void value(std::size_t bin, const Eigen::Vector3d& view, int, int, std::span<float> out) const override {
        double sum = 0.0;
        const auto& f = fractions_[bin];
        for (std::size_t k = 0; k < f.size(); ++k)
            if (f[k] > 0.0) sum += f[k] * field_.sample(k, view);
        out[0] = static_cast<float>(sum);
    }

private:
    const LetterField& field_;
    std::vector<std::vector<double>> fractions_;  // [bin][letter]: share of the bin's lights
};

// ----- diamonds -----

class DiamondLookup : public AngularLookup {
public:
    DiamondLookup(const DiamondField& field, std::vector<double> coverage, int cells, int macro_x)
        : field_(field), coverage_(std::move(coverage)), cells_(cells), macro_x_(macro_x) {}
    void value(std::size_t bin, const Eigen::Vector3d& view, int u, int v, std::span<float> out) const override {
        const double c = coverage_[bin * static_cast<std::size_t>(cells_) + static_cast<std::size_t>(v * macro_x_ + u)];
        const auto tint = field_.colour(view);
        for (int k = 0; k < 3; ++k) out[static_cast<std::size_t>(k)] = static_cast<float>(c * tint[static_cast<std::size_t>(k)]);
    }

private:
    const DiamondField& field_;
    std::vector<double> coverage_;  // [bin][macro cell]
    int cells_, macro_x_;
};

// ----- functions -----

class FunctionLookup : public AngularLookup {
public:
    FunctionLookup(const FunctionField::Function& function, std::vector<LightBin> bins, int channels)
        : function_(function), bins_(std::move(bins)), channels_(channels) {}
    void value(std::size_t bin, const Eigen::Vector3d& view, int u, int v, std::span<float> out) const override {
        std::fill(out.begin(), out.end(), 0.0f);
        std::array<float, 16> sample{};
        const LightBin& lights = bins_[bin];
        for (const auto& light : lights) {
            function_(light, view, u, v, std::span<float>(sample.data(), static_cast<std::size_t>(channels_)));
            for (int c = 0; c < channels_; ++c) out[static_cast<std::size_t>(c)] += sample[static_cast<std::size_t>(c)];
        }
        const float scale = lights.empty() ? 0.0f : 1.0f / static_cast<float>(lights.size());
        for (int c = 0; c < channels_; ++c) out[static_cast<std::size_t>(c)] *= scale;
    }

private:
    const FunctionField::Function& function_;
    std::vector<LightBin> bins_;
    int channels_;
};

}  // namespace

// ----- ViewSetField -----

ViewSetField::ViewSetField(relight::ViewSet views, double region) : views_(std::move(views)), region_(region) {
    RFD_CHECK(!views_.fields.empty());
    if (!(region_ > 0.0 && region_ <= 1.0))
        throw InputError(SourceLocation{views_.file.string()}, "the image region must be in (0, 1], got " +
                                                                   std::to_string(region_));
    if (views_.views.size() == 2)
        throw InputError(SourceLocation{views_.file.string()},
                         "a view set needs one view or at least three (the views are interpolated "
                         "over a triangulation), got two");
}

int ViewSetField::channels() const { return views_.fields.front().channels(); }

std::unique_ptr<AngularLookup> ViewSetField::bind(const std::vector<LightBin>& bins, int macro_x,
                                                  int macro_y) const {
    RFD_CHECK(macro_x >= 1 && macro_y >= 1);
    const std::size_t view_count = views_.views.size();
    const int cells = macro_x * macro_y;
    const int ch = channels();
    const auto& first = views_.fields.front();
    if (first.width() < macro_x || first.height() < macro_y)
        throw InputError(SourceLocation{views_.file.string()},
                         "view images of " + std::to_string(first.width()) + " x " + std::to_string(first.height()) +
                             " pixels are smaller than the " + std::to_string(macro_x) + " x " +
                             std::to_string(macro_y) + " macro-pixel grid");
    // Pixel box of each macro cell, over the centre region of the image; v counts up from
    // the bottom row of the image.
    const double x0 = 0.5 * (1.0 - region_) * first.width(), y0 = 0.5 * (1.0 - region_) * first.height();
    const double box_w = region_ * first.width() / macro_x, box_h = region_ * first.height() / macro_y;
    auto pixel_range = [](double from, double to) {
        const int a = static_cast<int>(std::floor(from + 0.5));
        const int b = std::max(a + 1, static_cast<int>(std::floor(to + 0.5)));
        return std::array<int, 2>{a, b};
    };

    std::vector<float> table(bins.size() * view_count * static_cast<std::size_t>(cells) * static_cast<std::size_t>(ch), 0.0f);
    for (std::size_t view = 0; view < view_count; ++view) {
        const relight::ReflectanceField& field = views_.fields[view];
        const relight::SphericalInterpolator lights(field.directions);
        // Every image reduced to the macro grid once.
        std::vector<double> reduced(field.size() * static_cast<std::size_t>(cells * ch), 0.0);
        for (std::size_t l = 0; l < field.size(); ++l)
            for (int v = 0; v < macro_y; ++v)
                for (int u = 0; u < macro_x; ++u) {
                    const auto xs = pixel_range(x0 + u * box_w, x0 + (u + 1) * box_w);
                    const int row = macro_y - 1 - v;
                    const auto ys = pixel_range(y0 + row * box_h, y0 + (row + 1) * box_h);
                    for (int c = 0; c < ch; ++c) {
                        double sum = 0.0;
                        for (int y = ys[0]; y < ys[1]; ++y)
                            for (int x = xs[0]; x < xs[1]; ++x) sum += field.images[l].at(x, y, c);
                        reduced[(l * static_cast<std::size_t>(cells) + static_cast<std::size_t>(v * macro_x + u)) * static_cast<std::size_t>(ch) + static_cast<std::size_t>(c)] =
                            sum / double((xs[1] - xs[0]) * (ys[1] - ys[0]));
                    }
                }
        std::vector<std::string> missing;
        for (std::size_t b = 0; b < bins.size(); ++b) {
            std::vector<double> weights(field.size(), 0.0);
            for (const auto& light : bins[b]) {
                if (!lights.covers(light)) {
                    missing.push_back("bin " + std::to_string(b) + " (" + format_direction(light) + ")");
                    continue;
                }
                const relight::InterpolationWeights w = lights.weights(light);
                for (std::size_t k = 0; k < w.count; ++k) weights[w.index[k]] += w.weight[k] / double(bins[b].size());
            }
            for (std::size_t l = 0; l < field.size(); ++l) {
                if (weights[l] == 0.0) continue;
                for (int i = 0; i < cells * ch; ++i)
                    table[(b * view_count + view) * static_cast<std::size_t>(cells * ch) + static_cast<std::size_t>(i)] +=
                        static_cast<float>(weights[l] * reduced[l * static_cast<std::size_t>(cells * ch) + static_cast<std::size_t>(i)]);
            }
        }
        if (!missing.empty()) {
            std::string list;
            for (std::size_t k = 0; k < missing.size() && k < 6; ++k) list += (k ? ", " : "") + missing[k];
            if (missing.size() > 6) list += ", ... (" + std::to_string(missing.size()) + " in all)";
            throw InputError(SourceLocation{views_.file.string(), views_.views[view].line},
                             "view '" + views_.views[view].folder + "' has no lights around the display's " +
                                 "incident directions " + list + " (light directions in the field frame; the " +
                                 "field must surround them)");
        }
    }
    std::unique_ptr<relight::SphericalInterpolator> interpolator;
    if (view_count >= 3) {
        std::vector<Eigen::Vector3d> directions;
        for (const auto& v : views_.views) directions.push_back(v.direction);
        interpolator = std::make_unique<relight::SphericalInterpolator>(directions);
    }
    return std::make_unique<ViewSetLookup>(std::move(table), view_count, cells, ch, std::move(interpolator), macro_x);
}

// ----- LetterField -----

LetterField::LetterField(std::vector<Eigen::Vector3d> lights, const std::string& characters,
                         std::array<double, 2> half_tan, int mask_size)
    : lights_(std::move(lights)), characters_(characters), half_tan_(half_tan) {
    if (lights_.empty() || characters_.size() < lights_.size())
        throw InputError("letter field: " + std::to_string(lights_.size()) + " light direction(s) need as many characters, got '" +
                         characters_ + "'");
    if (!(half_tan_[0] > 0.0) || !(half_tan_[1] > 0.0))
        throw InputError("letter field: the box of output directions must have a positive size");
    for (std::size_t k = 0; k < lights_.size(); ++k) {
        lights_[k].normalize();
        masks_.push_back(text_mask(std::string(1, characters_[k]), mask_size, mask_size, 0.8));
    }
}

std::size_t LetterField::letter_of(const Eigen::Vector3d& light) const {
    std::size_t best = 0;
    double best_dot = -std::numeric_limits<double>::infinity();
    for (std::size_t k = 0; k < lights_.size(); ++k) {
        const double d = lights_[k].dot(light);
        if (d > best_dot) {  // ties: the lowest index
            best_dot = d;
            best = k;
        }
    }
    return best;
}

float LetterField::sample(std::size_t k, const Eigen::Vector3d& view) const {
    if (!(view.z() > 0.0)) return 0.0f;
    const Image& mask = masks_[k];
    const double tx = view.x() / view.z() / half_tan_[0], ty = view.y() / view.z() / half_tan_[1];
    if (std::abs(tx) > 1.0 || std::abs(ty) > 1.0) return 0.0f;
    const double x = std::clamp(0.5 * (tx + 1.0) * mask.width() - 0.5, 0.0, mask.width() - 1.0);
    const double y = std::clamp(0.5 * (1.0 - ty) * mask.height() - 0.5, 0.0, mask.height() - 1.0);
    const int x0 = std::min(static_cast<int>(x), mask.width() - 2), y0 = std::min(static_cast<int>(y), mask.height() - 2);
    const double fx = x - x0, fy = y - y0;
    const double top = (1 - fx) * mask.at(x0, y0, 0) + fx * mask.at(x0 + 1, y0, 0);
    const double bottom = (1 - fx) * mask.at(x0, y0 + 1, 0) + fx * mask.at(x0 + 1, y0 + 1, 0);
    return static_cast<float>((1 - fy) * top + fy * bottom);
}

std::unique_ptr<AngularLookup> LetterField::bind(const std::vector<LightBin>& bins, int, int) const {
    std::vector<std::vector<double>> fractions(bins.size(), std::vector<double>(lights_.size(), 0.0));
    for (std::size_t b = 0; b < bins.size(); ++b)
        for (const auto& light : bins[b]) fractions[b][letter_of(light)] += 1.0 / double(bins[b].size());
    return std::make_unique<LetterLookup>(*this, std::move(fractions));
}

// ----- DiamondField -----

DiamondField::DiamondField(double light_half_tan, double view_half_tan)
    : light_half_tan_(light_half_tan), view_half_tan_(view_half_tan) {
    if (!(light_half_tan_ > 0.0) || !(view_half_tan_ > 0.0))
        throw InputError("diamond field: the light and view ranges must be positive");
}

double DiamondField::coverage(const Eigen::Vector3d& light, int u, int v, int macro_x, int macro_y) const {
    if (!(light.z() > 0.0)) return 0.0;
    const double tx = std::clamp(light.x() / light.z() / light_half_tan_, -1.0, 1.0);
    const double ty = std::clamp(light.y() / light.z() / light_half_tan_, -1.0, 1.0);
    const double size = 0.35 + 0.45 * 0.5 * (1.0 - ty);
    const double hole = 0.75 * size * std::abs(tx);
    constexpr int kSamples = 4;
    int inside = 0;
    for (int sy = 0; sy < kSamples; ++sy)
        for (int sx = 0; sx < kSamples; ++sx) {
            const double x = 2.0 * (u + (sx + 0.5) / kSamples) / macro_x - 1.0;
            const double y = 2.0 * (v + (sy + 0.5) / kSamples) / macro_y - 1.0;
            const double r = std::abs(x) + std::abs(y);
            inside += (r <= size) && (r >= hole);
        }
    return double(inside) / (kSamples * kSamples);
}

std::array<float, 3> DiamondField::colour(const Eigen::Vector3d& view) const {
    const double a = view.z() > 0.0 ? std::clamp(view.x() / view.z() / view_half_tan_, -1.0, 1.0) : 0.0;
    if (a > 0.0) return {1.0f, static_cast<float>(1.0 - a), 1.0f};
    return {static_cast<float>(1.0 + a), 1.0f, static_cast<float>(1.0 + a)};
}

std::unique_ptr<AngularLookup> DiamondField::bind(const std::vector<LightBin>& bins, int macro_x,
                                                  int macro_y) const {
    const int cells = macro_x * macro_y;
    std::vector<double> table(bins.size() * static_cast<std::size_t>(cells), 0.0);
    for (std::size_t b = 0; b < bins.size(); ++b)
        for (int v = 0; v < macro_y; ++v)
            for (int u = 0; u < macro_x; ++u) {
                double sum = 0.0;
                for (const auto& light : bins[b]) sum += coverage(light, u, v, macro_x, macro_y);
                table[b * static_cast<std::size_t>(cells) + static_cast<std::size_t>(v * macro_x + u)] =
                    bins[b].empty() ? 0.0 : sum / double(bins[b].size());
            }
    return std::make_unique<DiamondLookup>(*this, std::move(table), cells, macro_x);
}

// ----- FunctionField -----

FunctionField::FunctionField(int channels, Function function) : channels_(channels), function_(std::move(function)) {
    RFD_CHECK(channels_ >= 1 && channels_ <= 16);
}

std::unique_ptr<AngularLookup> FunctionField::bind(const std::vector<LightBin>& bins, int, int) const {
    return std::make_unique<FunctionLookup>(function_, bins, channels_);
}

}  // namespace rfd::patterns
