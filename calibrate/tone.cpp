#include "calibrate/tone.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include <Eigen/Dense>

#include "calibrate/camera.hpp"
#include "calibrate/sheet_finder.hpp"
#include "core/error.hpp"
#include "core/text.hpp"

namespace rfd::calibrate {
namespace {

constexpr double kCodesPerMm = 2.0;      // raster of the page that says where bare film is
constexpr double kBareStep = 2.0;        // mm between bare-film samples
constexpr double kBareClearance = 1.5;   // mm of bare film all around a sample
constexpr double kBareWindow = 0.5;      // mm, half the side of a sample's square
constexpr double kPatchInset = 0.2;      // part of a patch's side left out on each side (edges, blur)
constexpr double kMinPatchPixels = 8.0;  // across a patch
constexpr double kMaxLightResidual = 0.05;
constexpr double kMinExposure = 0.02;  // bare film, linear
constexpr double kMaxClipped = 0.01;   // bare-film samples at the top of the scale
constexpr int kPatchCells = 4;         // a patch's inner square in 4 x 4 cells, for its error

// The light over the page as a cubic in page x and y, fitted by least squares.
class LightSurface {
public:
    LightSurface(double width, double height) : half_w_(0.5 * width), half_h_(0.5 * height) {}

    Eigen::Matrix<double, 10, 1> terms(const Eigen::Vector2d& p) const {
        const double u = p.x() / half_w_ - 1.0, v = p.y() / half_h_ - 1.0;
        Eigen::Matrix<double, 10, 1> t;
        t << 1, u, v, u * u, u * v, v * v, u * u * u, u * u * v, u * v * v, v * v * v;
        return t;
    }
    void fit(const std::vector<Eigen::Vector2d>& points, const std::vector<double>& values) {
        Eigen::MatrixXd a(static_cast<Eigen::Index>(points.size()), 10);
        Eigen::VectorXd b(static_cast<Eigen::Index>(points.size()));
        for (std::size_t k = 0; k < points.size(); ++k) {
            a.row(static_cast<Eigen::Index>(k)) = terms(points[k]).transpose();
            b(static_cast<Eigen::Index>(k)) = values[k];
        }
        coefficients_ = a.colPivHouseholderQr().solve(b);
    }
    double operator()(const Eigen::Vector2d& p) const { return terms(p).dot(coefficients_); }

private:
    double half_w_, half_h_;
    Eigen::Matrix<double, 10, 1> coefficients_ = Eigen::Matrix<double, 10, 1>::Zero();
};

// Page points with bare film all around them, inside the printable area.
std::vector<Eigen::Vector2d> bare_film_points(const print::WedgeSheet& sheet, const print::PrinterProfile& printer,
                                              int page) {
    const Image codes = print::wedge_page_codes(sheet, printer, page, kCodesPerMm);
    const print::Paper& paper = printer.paper;
    const int reach = static_cast<int>(std::ceil(kBareClearance * kCodesPerMm));
    std::vector<Eigen::Vector2d> points;
    for (double y = paper.margin + kBareClearance; y <= paper.height - paper.margin - kBareClearance; y += kBareStep)
        for (double x = paper.margin + kBareClearance; x <= paper.width - paper.margin - kBareClearance;
             x += kBareStep) {
            const int cx = static_cast<int>(x * kCodesPerMm), cy = static_cast<int>(y * kCodesPerMm);
            bool bare = true;
            for (int dy = -reach; dy <= reach && bare; ++dy)
                for (int dx = -reach; dx <= reach && bare; ++dx) {
                    const int px = std::clamp(cx + dx, 0, codes.width() - 1),
                              py = std::clamp(cy + dy, 0, codes.height() - 1);
                    bare = codes.at(px, py, 0) >= 1.0f;
                }
            if (bare) points.emplace_back(x, y);
        }
    return points;
}

// Pool-adjacent-violators: the non-decreasing sequence closest to `values` in weighted least
// squares.
std::vector<double> non_decreasing(const std::vector<double>& values, const std::vector<double>& weights) {
    struct Block {
        double sum, weight;
        std::size_t count;
    };
    std::vector<Block> blocks;
    for (std::size_t k = 0; k < values.size(); ++k) {
        blocks.push_back({values[k] * weights[k], weights[k], 1});
        while (blocks.size() > 1 && blocks[blocks.size() - 2].sum / blocks[blocks.size() - 2].weight >
                                        blocks.back().sum / blocks.back().weight) {
            const Block last = blocks.back();
            blocks.pop_back();
            blocks.back().sum += last.sum;
            blocks.back().weight += last.weight;
            blocks.back().count += last.count;
        }
    }
    std::vector<double> out;
    for (const Block& block : blocks) out.insert(out.end(), block.count, block.sum / block.weight);
    return out;
}

}  // namespace

Image simulated_wedge_photo(const print::WedgeSheet& sheet, const print::PrinterProfile& printer,
                            const print::PrinterProfile& truth, const Camera& camera, ScanLight light, int page) {
    constexpr double kPixelsPerMm = 4.0;  // finer than a photograph's pixel on the page
    Image transmittance = print::wedge_page_codes(sheet, printer, page, kPixelsPerMm);
    for (float& value : transmittance.plane(0)) {
        const double t = truth.transmittance(1.0 - value);
        value = static_cast<float>(light == ScanLight::Reflected ? t * t : t);
    }
    return photograph(transmittance, kPixelsPerMm, camera);
}

WedgeReading measure_wedge(const Image& photo, const std::string& name, const print::WedgeSheet& sheet,
                           const print::PrinterProfile& printer, ScanLight light, int page) {
    RFD_CHECK(page >= 0 && page < sheet.pages);
    const Image luminance = photo_luminance(photo);
    const SheetLocation where = find_sheet(luminance, sheet.marks, name);
    WedgeReading reading;
    reading.name = name;
    reading.mirrored = where.mirrored;
    reading.mm_per_pixel = where.mm_per_pixel;
    const double patch_pixels = sheet.patch_size / where.mm_per_pixel;
    if (patch_pixels < kMinPatchPixels)
        throw InputError(SourceLocation{name}, "the wedge's patches are " + format_fixed(patch_pixels, 1) +
                                                   " pixels across here; fill the frame with the sheet (at least " +
                                                   format_number(kMinPatchPixels) + ")");

    // The light, from the bare film.
    std::vector<Eigen::Vector2d> points;
    std::vector<double> values;
    int clipped = 0;
    for (const Eigen::Vector2d& p : bare_film_points(sheet, printer, page)) {
        const double value = mean_over_page_rect(luminance, where.page_to_photo, p.x() - kBareWindow,
                                                 p.y() - kBareWindow, p.x() + kBareWindow, p.y() + kBareWindow);
        if (!std::isfinite(value)) continue;
        points.push_back(p);
        values.push_back(value);
        if (value >= 0.995) ++clipped;
    }
    if (points.size() < 30)
        throw InputError(SourceLocation{name}, "too little bare film in view to measure the light (" +
                                                   std::to_string(points.size()) + " samples)");
    double mean = 0.0;
    for (const double v : values) mean += v / static_cast<double>(values.size());
    reading.exposure = mean;
    if (clipped > kMaxClipped * static_cast<double>(values.size()))
        throw InputError(SourceLocation{name},
                         "overexposed: " + format_fixed(100.0 * clipped / static_cast<double>(values.size()), 0) +
                             " % of the bare film is at the top of the scale; expose less");
    if (mean < kMinExposure)
        throw InputError(SourceLocation{name}, "too dark: bare film reaches " + format_fixed(100.0 * mean, 1) +
                                                   " % of the scale; expose longer or light the sheet more");
    LightSurface surface(printer.paper.width, printer.paper.height);
    std::vector<bool> kept(points.size(), true);
    double rms = 0.0;
    for (int pass = 0; pass < 3; ++pass) {
        std::vector<Eigen::Vector2d> fit_points;
        std::vector<double> fit_values;
        for (std::size_t k = 0; k < points.size(); ++k)
            if (kept[k]) {
                fit_points.push_back(points[k]);
                fit_values.push_back(values[k]);
            }
        surface.fit(fit_points, fit_values);
        double sum = 0.0;
        for (std::size_t k = 0; k < fit_points.size(); ++k)
            sum += std::pow(fit_values[k] / surface(fit_points[k]) - 1.0, 2);
        rms = std::sqrt(sum / static_cast<double>(fit_points.size()));
        for (std::size_t k = 0; k < points.size(); ++k)
            kept[k] = std::abs(values[k] / surface(points[k]) - 1.0) <= 3.0 * rms;
    }
    reading.light_residual = rms;
    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
    for (const Eigen::Vector2d& p : points) {
        lo = std::min(lo, surface(p));
        hi = std::max(hi, surface(p));
    }
    reading.light_spread = (hi - lo) / mean;
    if (rms > kMaxLightResidual || !(lo > 0.0))
        throw InputError(SourceLocation{name},
                         "the light behind the sheet varies too much to model "
                         "(bare film departs " +
                             format_fixed(100.0 * rms, 1) +
                             " % from a smooth light); "
                             "light it evenly and keep the film flat");

    // Each patch's inner square, in cells: its transmittance and the error of their mean.
    for (const print::WedgePatch& patch : sheet.patches) {
        if (patch.page != page) continue;
        const double inset = kPatchInset * sheet.patch_size, cell = (sheet.patch_size - 2 * inset) / kPatchCells;
        std::vector<double> ratios;
        for (int j = 0; j < kPatchCells; ++j)
            for (int i = 0; i < kPatchCells; ++i) {
                const double x0 = patch.left + inset + i * cell, y0 = patch.top + inset + j * cell;
                const double value = mean_over_page_rect(luminance, where.page_to_photo, x0, y0, x0 + cell, y0 + cell);
                if (!std::isfinite(value))
                    throw InputError(SourceLocation{name},
                                     "the patch of code " + std::to_string(patch.code) + " is not wholly in view");
                const double ratio = value / surface({x0 + 0.5 * cell, y0 + 0.5 * cell});
                ratios.push_back(light == ScanLight::Reflected ? std::sqrt(std::max(0.0, ratio)) : ratio);
            }
        double sum = 0.0, sum2 = 0.0;
        for (const double r : ratios) {
            sum += r;
            sum2 += r * r;
        }
        const double n = static_cast<double>(ratios.size());
        PatchReading out;
        out.code = patch.code;
        out.ink = patch.ink;
        out.transmittance = sum / n;
        out.standard_error = std::sqrt(std::max(0.0, sum2 / n - out.transmittance * out.transmittance) / (n - 1));
        reading.patches.push_back(out);
    }
    return reading;
}

print::PrinterProfile ToneCalibration::power_law() const {
    print::PrinterProfile power = profile;
    power.tone_ink.clear();
    power.tone_transmittance.clear();
    return power;
}

ToneCalibration calibrate_tone(const print::PrinterProfile& printer, const std::vector<WedgeReading>& readings) {
    RFD_CHECK(!readings.empty());
    const std::size_t count = readings.front().patches.size();
    for (const WedgeReading& r : readings)
        if (r.patches.size() != count)
            throw InputError(SourceLocation{r.name}, "holds " + std::to_string(r.patches.size()) + " patches, " +
                                                         readings.front().name + " " + std::to_string(count) +
                                                         ": scans of one wedge expected");
    ToneCalibration out;
    // The mean of the scans; its error from their spread when there are several.
    for (std::size_t k = 0; k < count; ++k) {
        PatchReading patch = readings.front().patches[k];
        double sum = 0.0, sum2 = 0.0, own = 0.0;
        for (const WedgeReading& r : readings) {
            sum += r.patches[k].transmittance;
            sum2 += r.patches[k].transmittance * r.patches[k].transmittance;
            own += r.patches[k].standard_error * r.patches[k].standard_error;
        }
        const double n = static_cast<double>(readings.size());
        patch.transmittance = sum / n;
        patch.standard_error =
            n > 1 ? std::sqrt(std::max(0.0, sum2 / n - patch.transmittance * patch.transmittance) / (n - 1))
                  : std::sqrt(own);
        out.patches.push_back(patch);
    }
    if (out.patches.front().code != 255 || out.patches.back().code != 0)
        throw InputError(SourceLocation{readings.front().name},
                         "a wedge from code 255 (bare film) to 0 (full ink) expected");

    // The measured curve in density, made non-decreasing (weighted by each patch's error) and
    // strictly increasing by a hair, with bare film at density 0 by definition.
    constexpr double kMinTransmittance = 1e-6, kMinStep = 1e-6;
    std::vector<double> density, weights;
    for (const PatchReading& p : out.patches) {
        density.push_back(-std::log10(std::max(p.transmittance, kMinTransmittance)));
        const double relative = p.standard_error / std::max(p.transmittance, kMinTransmittance);
        weights.push_back(1.0 / std::max(relative * relative, 1e-12));
    }
    density.front() = 0.0;
    weights.front() = 1e12;
    density = non_decreasing(density, weights);
    density.front() = 0.0;
    for (std::size_t k = 1; k < density.size(); ++k) density[k] = std::max(density[k], density[k - 1] + kMinStep);
    const double max_density = density.back();
    if (max_density < 0.05)
        throw InputError(SourceLocation{readings.front().name},
                         "full ink transmits " + format_fixed(std::pow(10.0, -max_density), 3) +
                             " of the light: no ink was measured (is this the printed wedge?)");

    print::PrinterProfile& profile = out.profile;
    profile = printer;
    profile.max_density = max_density;
    profile.tone_ink.clear();
    profile.tone_transmittance.clear();
    for (std::size_t k = 0; k < count; ++k) {
        profile.tone_ink.push_back(out.patches[k].ink);
        profile.tone_transmittance.push_back(k == 0 ? 1.0 : std::pow(10.0, -density[k]));
    }
    profile.tone_transmittance.back() = profile.ink_transmittance();
    const double headroom = printer.black_level / printer.ink_transmittance();
    profile.black_level = std::min(0.99, std::max(1.0, headroom) * profile.ink_transmittance());

    // The power law for reference: log((T - T_ink) / (1 - T_ink)) = gamma log(1 - v).
    const double ink = profile.ink_transmittance();
    double sxy = 0.0, sxx = 0.0;
    for (const PatchReading& p : out.patches) {
        if (p.ink <= 0.0 || p.ink >= 1.0 || p.transmittance <= 2.0 * ink) continue;
        const double x = std::log(1.0 - p.ink), y = std::log((p.transmittance - ink) / (1.0 - ink));
        sxy += x * y;
        sxx += x * x;
    }
    out.power_law_gamma = sxx > 0.0 ? std::clamp(sxy / sxx, 0.1, 10.0) : printer.gamma;
    profile.gamma = out.power_law_gamma;
    const print::PrinterProfile power = out.power_law();
    double power_sum = 0.0, nominal_sum = 0.0;
    for (const PatchReading& p : out.patches) {
        power_sum += std::pow(power.transmittance(p.ink) - p.transmittance, 2);
        nominal_sum += std::pow(printer.transmittance(p.ink) - p.transmittance, 2);
    }
    out.power_law_rms = std::sqrt(power_sum / static_cast<double>(count));
    out.nominal_rms = std::sqrt(nominal_sum / static_cast<double>(count));
    return out;
}

}  // namespace rfd::calibrate
