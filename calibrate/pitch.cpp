#include "calibrate/pitch.hpp"

#include <algorithm>
#include <cmath>
#include <complex>
#include <limits>
#include <numeric>
#include <numbers>

#include <Eigen/Dense>
#include <unsupported/Eigen/NonLinearOptimization>

#include "calibrate/camera.hpp"
#include "calibrate/sheet_finder.hpp"
#include "core/error.hpp"
#include "core/text.hpp"
#include "core/units.hpp"
#include "optics/display.hpp"
#include "relight/vision.hpp"

namespace rfd::calibrate {
namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;
constexpr double kCoarsePixelsPerMm = 4.0;  // the page resampled to find the array and its lattice
constexpr double kMaxScaleOff = 0.05;       // lattice search: +-5 % of the design's pitch
constexpr double kMaxTurnDeg = 12.0;        // and +-12 deg
constexpr double kCoreFraction = 0.3;       // radius read of each lenslet image, of its smaller spacing
constexpr int kMinLenslets = 12;            // per axis
constexpr double kStartSpot = 0.03;         // the fit starts from this spot, periods
constexpr int kJackknifeGroups = 8;
constexpr double kMarginMm = 1.5;           // lenslets read this far inside a band, beyond a lenslet
constexpr double kEdgeLenslets = 1.6;       // lenslets at the array's edge (fewer neighbours) left out
constexpr int kPhaseBins = 20;              // the lenslets must read 16 of 20 phase bins
constexpr int kMinPhaseBins = 16;
constexpr double kPitchPrior = 0.01;        // the array's pitch within +-1 % of the design's
constexpr double kTurnPrior = 0.003;        // its rows within +-0.17 deg of the lenslet images' rows
constexpr double kReadableDepth = 4.0;      // the profile's depth, in noise standard deviations
constexpr int kLightTerms = 5;              // E = 1 + u + v + u^2 + uv + v^2 terms
constexpr double kOutlierSigmas = 5.0;
// An array laid whole on each band (print::MoireSheet::whole_array):
constexpr double kWholeInset = 0.25;        // its region kept this many lenslets inside the dark's edge
constexpr double kMinTiltDeg = 10.0;        // the camera's height needs a tilted photograph
constexpr int kMinWholeLenslets = 24;       // twice the fit's parameters
constexpr double kWholeFloorX = 2e-5;       // its scale's least uncertainty along a row
constexpr double kWholeFloorRows = 3e-5;    // and across the rows (fit_axis says why)
constexpr double kWholeMaxContrast = 1.05;  // a fit whose profile dips below no light,
constexpr double kWholeMaxResidual = 0.02;  // or misses the readings by this much, settled wrong
constexpr double kHolderDark = 0.1;         // a reading under this part of the brightest: the holder
constexpr double kWholePhaseShare = 0.3;    // of the phase bins 30 random phases fill, needed
constexpr int kWholeTurnSteps = 5;          // its lattice tried at up to this many steps either way
constexpr double kWholeTurnStepDeg = 1.0;   // of this turn from the spectrum's (read_pitch_photo)
constexpr double kMaxHarmonic = 0.5;        // graded lines: the second harmonic's most, of the first
constexpr double kWholeMaxTurnOff = 0.035;  // a whole array's fitted rows within 2 deg of its images'

// The page resampled on a grid of `px_per_mm` over a rectangle.
struct PageRaster {
    Image image;
    Eigen::Vector2d origin;  // page point of pixel (0, 0)'s corner
    double px_per_mm = 1.0;
    Eigen::Vector2d page(int x, int y) const { return origin + Eigen::Vector2d(x + 0.5, y + 0.5) / px_per_mm; }
};

PageRaster resample(const Image& luminance, const Eigen::Matrix3d& page_to_photo, const Eigen::Vector2d& from,
                    const Eigen::Vector2d& to, double px_per_mm) {
    PageRaster raster;
    raster.origin = from;
    raster.px_per_mm = px_per_mm;
    raster.image = Image(static_cast<int>(std::ceil((to.x() - from.x()) * px_per_mm)),
                         static_cast<int>(std::ceil((to.y() - from.y()) * px_per_mm)), 1);
    for (int y = 0; y < raster.image.height(); ++y)
        for (int x = 0; x < raster.image.width(); ++x)
            raster.image.at(x, y, 0) = static_cast<float>(photo_at_page(luminance, page_to_photo, raster.page(x, y)));
    return raster;
}

// The diffuser: the largest dark region of the resampled page, shrunk by `inset_mm` so that
// lenslet images near its edge are left out. Returns one byte per raster pixel.
std::vector<std::uint8_t> diffuser_region(const PageRaster& raster, double smoothing_mm, double inset_mm,
                                          const std::string& name) {
    const relight::PlaneSize size{raster.image.width(), raster.image.height()};
    Image smooth(size.width, size.height, 1);
    std::vector<float> filled(raster.image.plane(0).begin(), raster.image.plane(0).end());
    float brightest = 0.0f;
    for (const float v : filled)
        if (std::isfinite(v)) brightest = std::max(brightest, v);
    for (float& v : filled)
        if (!std::isfinite(v)) v = brightest;  // beyond the photo: not the diffuser
    const double sigma = smoothing_mm * raster.px_per_mm;
    relight::vision().gaussian_blur(size, filled, smooth.plane(0), 0, sigma, sigma, relight::Border::Replicate);
    const double threshold = otsu_threshold(smooth.plane(0));
    std::vector<std::uint8_t> dark(filled.size());
    for (std::size_t k = 0; k < dark.size(); ++k) dark[k] = smooth.plane(0)[k] < threshold ? 1 : 0;
    std::vector<int> labels(dark.size());
    const int count = relight::vision().connected_components(size, dark, labels);
    std::vector<std::size_t> area(static_cast<std::size_t>(count), 0);
    for (const int label : labels) ++area[static_cast<std::size_t>(label)];
    std::size_t largest = 0;
    for (std::size_t label = 1; label < area.size(); ++label)
        if (area[label] > (largest == 0 ? 0 : area[largest])) largest = label;
    if (largest == 0) throw InputError(SourceLocation{name}, "no darker diffuser region over the bands");
    for (std::size_t k = 0; k < dark.size(); ++k) dark[k] = labels[k] == static_cast<int>(largest) ? 1 : 0;
    std::vector<float> distance(dark.size());
    relight::vision().distance_transform(size, dark, distance);
    for (std::size_t k = 0; k < dark.size(); ++k) dark[k] = distance[k] >= inset_mm * raster.px_per_mm ? 1 : 0;
    return dark;
}

// The Fourier transform of the region's values (mean removed) at spatial frequencies g
// (cycles per page mm): the strength of a lattice with that reciprocal vector.
class RegionSpectrum {
public:
    /// `values`: one per raster pixel.
    RegionSpectrum(const PageRaster& raster, std::span<const float> values, const std::vector<std::uint8_t>& region)
        : raster_(raster) {
        double sum = 0.0;
        std::size_t n = 0;
        for (std::size_t k = 0; k < region.size(); ++k)
            if (region[k]) sum += values[k], ++n;
        mean_ = n ? sum / static_cast<double>(n) : 0.0;
        rows_.resize(static_cast<std::size_t>(raster.image.height()));
        for (int y = 0; y < raster.image.height(); ++y)
            for (int x = 0; x < raster.image.width(); ++x) {
                const std::size_t k = static_cast<std::size_t>(y) * static_cast<std::size_t>(raster.image.width()) +
                                      static_cast<std::size_t>(x);
                if (region[k]) rows_[static_cast<std::size_t>(y)].push_back({x, values[k] - mean_});
            }
        pixels_ = n;
    }
    std::size_t pixels() const { return pixels_; }


    std::complex<double> at(const Eigen::Vector2d& g) const {
        const int width = raster_.image.width();
        std::vector<std::complex<double>> column(static_cast<std::size_t>(width));
        for (int x = 0; x < width; ++x) column[static_cast<std::size_t>(x)] = std::polar(1.0, -kTwoPi * g.x() * raster_.page(x, 0).x());
        std::complex<double> total = 0.0;
        for (std::size_t y = 0; y < rows_.size(); ++y) {
            if (rows_[y].empty()) continue;
            std::complex<double> row = 0.0;
            for (const auto& [x, value] : rows_[y]) row += value * column[static_cast<std::size_t>(x)];
            total += row * std::polar(1.0, -kTwoPi * g.y() * raster_.page(0, static_cast<int>(y)).y());
        }
        return total;
    }

private:
    const PageRaster& raster_;
    double mean_ = 0.0;
    std::size_t pixels_ = 0;
    std::vector<std::vector<std::pair<int, double>>> rows_;
};

// The reciprocal vector of the strongest lattice near `nominal`: a grid over +-kMaxScaleOff
// in length and +-kMaxTurnDeg in angle, then a pattern search.
Eigen::Vector2d strongest_frequency(const RegionSpectrum& spectrum, const Eigen::Vector2d& nominal, double extent_mm) {
    const double step = 0.4 / extent_mm;
    const double length = nominal.norm();
    const Eigen::Vector2d along = nominal / length, across(-along.y(), along.x());
    const int n_along = static_cast<int>(std::ceil(kMaxScaleOff * length / step));
    const int n_across = static_cast<int>(std::ceil(std::tan(degrees_to_radians(kMaxTurnDeg)) * length / step));
    Eigen::Vector2d best = nominal;
    double best_power = -1.0;
    for (int i = -n_along; i <= n_along; ++i)
        for (int j = -n_across; j <= n_across; ++j) {
            const Eigen::Vector2d g = nominal + i * step * along + j * step * across;
            const double power = std::norm(spectrum.at(g));
            if (power > best_power) best_power = power, best = g;
        }
    for (double s = 0.5 * step; s > 1e-4 / extent_mm; s *= 0.5) {
        bool moved = true;
        while (moved) {
            moved = false;
            for (const Eigen::Vector2d& d : {Eigen::Vector2d(s, 0), Eigen::Vector2d(-s, 0), Eigen::Vector2d(0, s),
                                             Eigen::Vector2d(0, -s)}) {
                const double power = std::norm(spectrum.at(best + d));
                if (power > best_power) best_power = power, best += d, moved = true;
            }
        }
    }
    return best;
}

// The lattice of lenslet images on the page: page = origin + basis n for integer n.
struct ImageLattice {
    Eigen::Matrix2d basis;
    Eigen::Vector2d origin;
};


// The lenslets one axis fits: position label in the design's array frame (relative to a
// reference lenslet), the light falloff's terms where their light is seen, value, and the
// band's line period and centre line.
struct AxisData {
    std::vector<Eigen::Vector2d> label;
    std::vector<std::array<double, kLightTerms>> light;
    std::vector<Eigen::Vector2d> where;  // page, where the lenslet's light is seen

    // The light falloff's terms over the lenslets' own box (E = 1 in its middle).
    void set_light_terms() {
        Eigen::Vector2d low = Eigen::Vector2d::Constant(HUGE_VAL), high = -low;
        for (const Eigen::Vector2d& w : where) low = low.cwiseMin(w), high = high.cwiseMax(w);
        const Eigen::Vector2d middle = 0.5 * (low + high);
        const Eigen::Vector2d half = (0.5 * (high - low)).cwiseMax(Eigen::Vector2d::Constant(1.0));
        light.clear();
        for (const Eigen::Vector2d& w : where) {
            const double u = (w.x() - middle.x()) / half.x(), v = (w.y() - middle.y()) / half.y();
            light.push_back({u, v, u * u, u * v, v * v});
        }
    }
    std::vector<double> value, period, origin;
    std::vector<std::size_t> lenslet;  // index into the reading's lenslets
    bool graded = false;                               // the band's lines (print::MoireBand::graded)
};

// The lines as a lenslet's spot sees them: a line of width w (periods) centred on phase 0,
// blurred by a Gaussian spot of standard deviation s (periods): the part of the spot on ink,
// and its derivatives in the phase, w and log s.
struct Coverage {
    double value = 0.0, d_phase = 0.0, d_width = 0.0, d_log_spot = 0.0;
};
Coverage line_coverage(double phase, double width, double spot) {
    constexpr double kInvSqrt2Pi = 0.3989422804014327;
    const auto cdf = [](double x) { return 0.5 * std::erfc(-x / std::numbers::sqrt2); };
    const auto pdf = [&](double x) { return kInvSqrt2Pi * std::exp(-0.5 * x * x); };
    const double d = phase - std::round(phase);
    Coverage c;
    for (int n = -2; n <= 2; ++n) {  // the neighbouring lines reach a wide spot
        const double a = (0.5 * width - (d + n)) / spot, b = (-0.5 * width - (d + n)) / spot;
        c.value += cdf(a) - cdf(b);
        c.d_phase += (pdf(b) - pdf(a)) / spot;
        c.d_width += 0.5 * (pdf(a) + pdf(b)) / spot;
        c.d_log_spot += b * pdf(b) - a * pdf(a);
    }
    return c;
}

// Graded lines as a lenslet sees them: the cosine of print::MoireBand::ink, whatever its spot
// (a blur only lowers the cosine's depth, which the fitted levels take up).
Coverage graded_coverage(double phase) {
    const double angle = kTwoPi * phase;
    return {0.5 * (1.0 + std::cos(angle)), -0.5 * kTwoPi * std::sin(angle), 0.0, 0.0};
}

// Parameters: c, m1, m2 (the phase), w, log s (sharp lines: the lines' width and the spot;
// graded lines: the second harmonic's cosine and sine terms, which a printer's tone curve off
// its profile adds to the cosine), B, D (the readings off and on a line), e_1..e_5 (the light
// falloff E).
constexpr int kWidth = 3, kLogSpot = 4, kBright = 5, kDark = 6, kLight = 7;
constexpr int kCos2 = kWidth, kSin2 = kLogSpot;
constexpr int kParameters = kLight + kLightTerms;

// The model of the header comment for Eigen's Levenberg-Marquardt: residuals over the used
// lenslets and their Jacobian.
struct AxisModel {
    const AxisData* data;
    std::vector<char> used;
    std::vector<std::size_t> rows;  // the used lenslets
    bool harmonics = true;          // graded lines: the second harmonic free (else held at 0)
    AxisModel(const AxisData& d, std::vector<char> use) : data(&d), used(std::move(use)) {
        for (std::size_t k = 0; k < used.size(); ++k)
            if (used[k]) rows.push_back(k);
    }
    int inputs() const { return kParameters; }
    int values() const { return static_cast<int>(rows.size()); }
    double phase(const Eigen::VectorXd& p, std::size_t k) const {
        return (p(0) + p(1) * data->label[k].x() + p(2) * data->label[k].y() - data->origin[k]) / data->period[k];
    }
    double light(const Eigen::VectorXd& p, std::size_t k) const {
        double e = 1.0;
        for (int t = 0; t < kLightTerms; ++t) e += p(kLight + t) * data->light[k][static_cast<std::size_t>(t)];
        return e;
    }
    // The part of the way to full ink a lenslet sees at `phase`.
    Coverage covered(const Eigen::VectorXd& p, double phase) const {
        return data->graded ? graded_coverage(phase)
                            : line_coverage(phase, p(kWidth), std::exp(p(kLogSpot)));
    }
    // Graded lines' second harmonic at `phase`, and its slope in the phase.
    std::pair<double, double> harmonic(const Eigen::VectorXd& p, double phase) const {
        if (!data->graded || !harmonics) return {0.0, 0.0};
        const double c = std::cos(2.0 * kTwoPi * phase), s = std::sin(2.0 * kTwoPi * phase);
        return {p(kCos2) * c + p(kSin2) * s, 2.0 * kTwoPi * (p(kSin2) * c - p(kCos2) * s)};
    }
    double profile(const Eigen::VectorXd& p, double phase) const {
        return p(kBright) - (p(kBright) - p(kDark)) * covered(p, phase).value +
               harmonic(p, phase).first;
    }
    double predict(const Eigen::VectorXd& p, std::size_t k) const { return light(p, k) * profile(p, phase(p, k)); }
    int operator()(const Eigen::VectorXd& p, Eigen::VectorXd& residual) const {
        for (std::size_t r = 0; r < rows.size(); ++r)
            residual(static_cast<Eigen::Index>(r)) = predict(p, rows[r]) - data->value[rows[r]];
        return 0;
    }
    int df(const Eigen::VectorXd& p, Eigen::MatrixXd& jacobian) const {
        for (std::size_t r = 0; r < rows.size(); ++r) {
            const std::size_t k = rows[r];
            const auto row = static_cast<Eigen::Index>(r);
            const double e = light(p, k), phi = phase(p, k);
            const Coverage c = covered(p, phi);
            const auto [h, d_h] = harmonic(p, phi);
            const double depth = p(kBright) - p(kDark), g = p(kBright) - depth * c.value + h;
            const double d_phase = e * (d_h - depth * c.d_phase) / data->period[k];
            jacobian(row, 0) = d_phase;
            jacobian(row, 1) = d_phase * data->label[k].x();
            jacobian(row, 2) = d_phase * data->label[k].y();
            if (data->graded) {
                jacobian(row, kCos2) = harmonics ? e * std::cos(2.0 * kTwoPi * phi) : 0.0;
                jacobian(row, kSin2) = harmonics ? e * std::sin(2.0 * kTwoPi * phi) : 0.0;
            } else {
                jacobian(row, kWidth) = -e * depth * c.d_width;
                jacobian(row, kLogSpot) = -e * depth * c.d_log_spot;
            }
            jacobian(row, kBright) = e * (1.0 - c.value);
            jacobian(row, kDark) = e * c.value;
            for (int t = 0; t < kLightTerms; ++t)
                jacobian(row, kLight + t) = g * data->light[k][static_cast<std::size_t>(t)];
        }
        return 0;
    }
};

// B and D that explain the readings best for the phases, width and spot of `p` (E = 1), by
// least squares; returns the residual sum of squares.
double fit_levels(const AxisModel& model, Eigen::VectorXd& p) {
    Eigen::Matrix2d normal = Eigen::Matrix2d::Zero();
    Eigen::Vector2d right = Eigen::Vector2d::Zero();
    double values2 = 0.0;
    for (const std::size_t k : model.rows) {
        const double phase = model.phase(p, k);
        const double covered = model.covered(p, phase).value;
        const double value = model.data->value[k] - model.harmonic(p, phase).first;
        const Eigen::Vector2d basis(1.0 - covered, covered);
        normal += basis * basis.transpose();
        right += basis * value;
        values2 += value * value;
    }
    const Eigen::Vector2d levels = normal.ldlt().solve(right);
    p(kBright) = levels(0);
    p(kDark) = levels(1);
    return values2 - levels.dot(right);
}

// The row (m1, m2) near `guess` that scores highest, c held at `offset`: along the guess,
// its length within +-kPitchPrior; across it, within +-kTurnPrior; on a grid fine enough that
// the phase moves by `step` of a period between its points anywhere in the bands. `score`
// takes each lenslet's phase (periods) and returns the row's score.
template <typename Score>
Eigen::Vector2d best_row(const AxisData& data, double offset, const Eigen::Vector2d& guess, double scale, double step,
                         Score score) {
    const Eigen::Vector2d along = guess.normalized(), across(-along.y(), along.x());
    double span_along = 0.0, span_across = 0.0;
    for (const Eigen::Vector2d& a : data.label) {
        span_along = std::max(span_along, std::abs(a.dot(along)));
        span_across = std::max(span_across, std::abs(a.dot(across)));
    }
    const double period = data.period.front();
    const double step_along = step * period / std::max(span_along, period);
    const double step_across = step * period / std::max(span_across, period);
    const int n_along = static_cast<int>(std::ceil(kPitchPrior / step_along));
    const int n_across = static_cast<int>(std::ceil(kTurnPrior / step_across));
    std::vector<double> phases(data.value.size());
    Eigen::Vector2d best = guess;
    double best_score = -HUGE_VAL;
    for (int i = -n_along; i <= n_along; ++i)
        for (int j = -n_across; j <= n_across; ++j) {
            const Eigen::Vector2d row = (scale + i * step_along) * along + j * step_across * across;
            for (std::size_t k = 0; k < data.value.size(); ++k)
                phases[k] = (offset + row.dot(data.label[k]) - data.origin[k]) / data.period[k];
            const double value = score(phases);
            if (value > best_score) best_score = value, best = row;
        }
    return best;
}

// The row with the most coherent readings: the power of their Fourier sum at the lines'
// frequency, on a grid of a tenth of a period.
Eigen::Vector2d coherent_row(const AxisData& data, double offset, const Eigen::Vector2d& guess, double scale) {
    double mean = 0.0;
    for (const double v : data.value) mean += v;
    mean /= static_cast<double>(data.value.size());
    return best_row(data, offset, guess, scale, 0.1, [&](const std::vector<double>& phases) {
        std::complex<double> sum = 0.0;
        for (std::size_t k = 0; k < phases.size(); ++k)
            sum += (data.value[k] - mean) * std::polar(1.0, kTwoPi * phases[k]);
        return std::norm(sum);
    });
}

// The row with the smoothest readings in the order of their phases (phase dispersion
// minimisation, Stellingwerf 1978): the least sum of squared steps between readings
// neighbouring in phase, on a grid of a twentieth of a period. A few lenslets' coherence can
// peak beside the true row, where the fit then settles in a wrong minimum.
Eigen::Vector2d smoothest_row(const AxisData& data, double offset, const Eigen::Vector2d& guess, double scale) {
    std::vector<std::pair<double, double>> ordered(data.value.size());
    return best_row(data, offset, guess, scale, 0.05, [&](const std::vector<double>& phases) {
        for (std::size_t k = 0; k < phases.size(); ++k)
            ordered[k] = {phases[k] - std::floor(phases[k]), data.value[k]};
        std::sort(ordered.begin(), ordered.end());
        double length = 0.0;
        for (std::size_t k = 0; k < ordered.size(); ++k) {
            const double step = ordered[(k + 1) % ordered.size()].second - ordered[k].second;
            length += step * step;
        }
        return -length;
    });
}

// The fit from a starting row: the lines' offset searched, then Levenberg-Marquardt, outliers
// (over kOutlierSigmas robust deviations) dropped, and again. Returns the parameters and the
// lenslets used; `rms` the residual over all lenslets.
struct AxisSolution {
    Eigen::VectorXd p;
    std::vector<char> used;
    double rms = HUGE_VAL;
};
AxisSolution solve_axis(const AxisData& data, double offset, const Eigen::Vector2d& row, double line_fraction) {
    AxisSolution out;
    Eigen::VectorXd& p = out.p;
    p = Eigen::VectorXd::Zero(kParameters);
    p(1) = row.x();
    p(2) = row.y();
    if (!data.graded) {
        p(kWidth) = line_fraction;
        p(kLogSpot) = std::log(kStartSpot);
    }
    // Where the lines are: of offsets a hundredth of a period apart, the one whose lines,
    // a little blurred, explain the readings best.
    std::vector<char>& used = out.used;
    used.assign(data.value.size(), 1);
    {
        const AxisModel all(data, used);
        double best_error = HUGE_VAL, best_offset = offset;
        for (int step = 0; step < 100; ++step) {
            p(0) = offset + step / 100.0 * data.period.front();
            const double error = fit_levels(all, p);
            if (error < best_error) best_error = error, best_offset = p(0);
        }
        p(0) = best_offset;
        fit_levels(all, p);
    }
    // Graded lines are fitted as a cosine first, then with their second harmonic free: free
    // from the start, the harmonic could carry the lines at half the phase's pace, and a fit
    // settled there with the rows 0.7 % off (phases stepping an eighth of a period per row
    // rather than a quarter, every lenslet's reading explained).
    Eigen::VectorXd cosine;
    for (int pass = 0; pass < 2; ++pass) {
        AxisModel model(data, used);
        model.harmonics = pass == 1;
        Eigen::LevenbergMarquardt<AxisModel> solver(model);
        solver.parameters.maxfev = 400;
        solver.minimize(p);
        if (pass == 1) {
            // A harmonic as strong as half the cosine is not the tone curve's bend: the cosine's fit kept.
            if (data.graded &&
                std::hypot(p(kCos2), p(kSin2)) > kMaxHarmonic * 0.5 * std::abs(p(kBright) - p(kDark)))
                p = cosine;
            break;
        }
        cosine = p;
        Eigen::VectorXd residual(model.values());
        model(p, residual);
        std::vector<double> magnitudes(static_cast<std::size_t>(residual.size()));
        for (Eigen::Index r = 0; r < residual.size(); ++r)
            magnitudes[static_cast<std::size_t>(r)] = std::abs(residual(r));
        const auto middle = magnitudes.begin() + static_cast<std::ptrdiff_t>(magnitudes.size() / 2);
        std::nth_element(magnitudes.begin(), middle, magnitudes.end());
        const double sigma = 1.4826 * *middle;
        for (std::size_t k = 0; k < data.value.size(); ++k)
            if (std::abs(model.predict(p, k) - data.value[k]) > kOutlierSigmas * sigma) used[k] = 0;
    }
    const AxisModel model(data, std::vector<char>(data.value.size(), 1));
    double sum = 0.0;
    for (std::size_t k = 0; k < data.value.size(); ++k) sum += std::pow(model.predict(p, k) - data.value[k], 2);
    out.rms = std::sqrt(sum / static_cast<double>(data.value.size()));
    return out;
}

// Fits one axis; fills `fit` and the lenslets' phases and fitted values. `guess` is the row
// of the lattice of lenslet images, `scale` the design's expected length of it. A few
// lenslets (`few`: a whole small array) are fitted from the smoothest row too, and the better
// fit kept.
void fit_axis(AxisData& data, double offset, const Eigen::Vector2d& guess, double scale, double line_fraction,
              bool along_x, bool few, AxisFit& fit, std::vector<LensletReading>& lenslets, const std::string& name) {
    fit.along_x = along_x;
    if (static_cast<int>(data.value.size()) < kMinLenslets) return;  // this axis's band not under the array
    data.set_light_terms();
    AxisSolution solution = solve_axis(data, offset, coherent_row(data, offset, guess, scale), line_fraction);
    if (few) {
        AxisSolution other = solve_axis(data, offset, smoothest_row(data, offset, guess, scale), line_fraction);
        if (other.rms < solution.rms) solution = std::move(other);
    }
    Eigen::VectorXd& p = solution.p;
    const std::vector<char>& used = solution.used;
    double mean = 0.0;
    for (const double v : data.value) mean += v;
    mean /= static_cast<double>(data.value.size());
    Eigen::VectorXd residual;
    AxisModel model(data, used);
    residual.resize(model.values());
    model(p, residual);
    Eigen::MatrixXd jacobian(model.values(), kParameters);
    model.df(p, jacobian);
    const auto n = static_cast<double>(model.values());
    const double variance = residual.squaredNorm() / std::max(1.0, n - kParameters);
    const Eigen::MatrixXd normal = jacobian.transpose() * jacobian;
    const Eigen::MatrixXd covariance = variance * normal.completeOrthogonalDecomposition().pseudoInverse();

    // The row's uncertainty: the fit's own (residual variance through the inverse normal
    // matrix) understates it when the lines are sharp (a lenslet informs only near an edge),
    // so the delete-a-group jackknife's, over groups of interleaved lenslets, when larger.
    Eigen::Matrix2d jackknife = Eigen::Matrix2d::Zero();
    {
        std::vector<Eigen::Vector2d> rows_without;
        for (int group = 0; group < kJackknifeGroups; ++group) {
            std::vector<char> subset = used;
            for (std::size_t k = static_cast<std::size_t>(group); k < subset.size(); k += kJackknifeGroups) subset[k] = 0;
            AxisModel part(data, subset);
            Eigen::VectorXd q = p;
            Eigen::LevenbergMarquardt<AxisModel> solver(part);
            solver.parameters.maxfev = 200;
            solver.minimize(q);
            rows_without.emplace_back(q(1), q(2));
        }
        Eigen::Vector2d average = Eigen::Vector2d::Zero();
        for (const Eigen::Vector2d& r : rows_without) average += r / kJackknifeGroups;
        for (const Eigen::Vector2d& r : rows_without) jackknife += (r - average) * (r - average).transpose();
        jackknife *= (kJackknifeGroups - 1.0) / kJackknifeGroups;
    }
    fit.offset = p(0);
    fit.row = {p(1), p(2)};
    const Eigen::Matrix2d analytic = covariance.block<2, 2>(1, 1);
    fit.row_covariance = jackknife.trace() > analytic.trace() ? jackknife : analytic;
    // A whole small array's photograph scatters more than some fits say: where each reading
    // disc lies in its lenslet image moves the phase it reads a little (the image shows the
    // sheet through the lenslet's aberrations), and over 12 simulated placements one pair's
    // scale scattered 0.0016 % (along a row) and 0.0021 % (across the rows) RMS
    // (docs/results.md). The row's length, which is the scale, gets at least about that
    // scatter; every one of those readings is then within 1.8 of its stated uncertainty.
    if (few) {
        const Eigen::Vector2d along = fit.row.normalized();
        const double scale_variance = along.dot(fit.row_covariance * along);
        const double floor = along_x ? kWholeFloorX : kWholeFloorRows;
        if (scale_variance < floor * floor)
            fit.row_covariance += (floor * floor - scale_variance) * along * along.transpose();
    }
    fit.lenslets = static_cast<int>(n);
    fit.outliers = static_cast<int>(data.value.size()) - fit.lenslets;
    fit.rms = std::sqrt(residual.squaredNorm() / n) / mean;
    fit.profile.clear();
    for (int k = 0; k < 64; ++k) fit.profile.push_back(model.profile(p, k / 64.0));
    const auto [lo, hi] = std::minmax_element(fit.profile.begin(), fit.profile.end());
    const double depth = *hi - *lo;
    fit.contrast = *hi > 0.0 ? depth / *hi : 0.0;
    // A whole small array's fit that settled wrong shows it: a profile that dips below no light
    // or readings far off it (over the simulated placements of docs/results.md, good fits to
    // the graded lines: residual 0.1-0.4 %, contrast at most 0.99; lattices of lenslet images
    // found wrong: 3.6 % and more).
    // Or one that wandered beyond what the lattice of lenslet images allows (tried with the
    // bands slanted 3 deg, one fit settled far off and read the pitch 18 % off at +-0.002 %).
    const double off_scale = fit.row.norm() / scale - 1.0;
    const double off_turn = std::atan2(guess.x() * fit.row.y() - guess.y() * fit.row.x(), guess.dot(fit.row));
    if (few && (std::abs(off_scale) > 2.0 * kPitchPrior || std::abs(off_turn) > kWholeMaxTurnOff))
        throw InputError(SourceLocation{name},
                         format_text("the lenslets over the %s measuring band fit the lines only %.2f %% and %.1f deg "
                                     "off their images' lattice (the fit settled wrong): lay the array down again and "
                                     "take another photograph",
                                     along_x ? "x" : "rows", 100.0 * off_scale, radians_to_degrees(off_turn)));
    if (few && (fit.contrast > kWholeMaxContrast || fit.rms > kWholeMaxResidual))
        throw InputError(SourceLocation{name},
                         format_text("the lenslets over the %s measuring band do not fit the lines' profile "
                                     "(residual %.1f %%, contrast %.2f): the array's lenslet images were probably "
                                     "not found; lay the array down again and take another photograph",
                                     along_x ? "x" : "rows", 100.0 * fit.rms, fit.contrast));
    for (std::size_t k = 0; k < data.value.size(); ++k) {
        LensletReading& l = lenslets[data.lenslet[k]];
        l.phase = model.phase(p, k);
        l.light = model.light(p, k);
        l.fitted = model.predict(p, k);
        l.outlier = !used[k];
    }
    // Lenslets that read too few of the lines' phases (an array turned against the slant):
    // the phase's slope is then poorly held.
    std::array<bool, kPhaseBins> seen{};
    for (const std::size_t k : model.rows) {
        const double phi = model.phase(p, k);
        seen[static_cast<std::size_t>(std::min(kPhaseBins - 1.0, (phi - std::floor(phi)) * kPhaseBins))] = true;
    }
    const auto bins = std::count(seen.begin(), seen.end(), true);
    // A small array's few lenslets fill fewer bins even at random phases (30 fill 15.7 of 20
    // on average): four fifths of that, and at most kMinPhaseBins. A whole small array's phases
    // follow its two steps, one per lenslet along a row and one per row, and at some turns of
    // the array these nearly repeat; its graded lines inform at every phase, and fits from 6
    // to 8 of 20 bins read as well as the others (docs/results.md), so it needs
    // kWholePhaseShare of the random fill (5 bins).
    const double at_random =
        kPhaseBins * (1.0 - std::pow(1.0 - 1.0 / kPhaseBins, static_cast<double>(model.rows.size())));
    const auto needed = few ? static_cast<std::ptrdiff_t>(std::ceil(kWholePhaseShare * at_random))
                            : std::min<std::ptrdiff_t>(kMinPhaseBins, static_cast<std::ptrdiff_t>(0.8 * at_random));
    if (bins < needed)
        throw InputError(SourceLocation{name},
                         format_text("the lenslets over the %s measuring band read only %td of %d phases of its "
                                     "lines (%td needed): turn the array a degree or two and photograph it again",
                                     along_x ? "x" : "rows", bins, kPhaseBins, needed));
    // Lines too blurred or too dark to read: the profile no stronger than the noise.
    const double noise = std::sqrt(variance);
    if (!(depth > kReadableDepth * noise))
        throw InputError(SourceLocation{name},
                         format_text("the %s measuring band's lines are not readable through the lenslets (their "
                                     "depth %.4f is within %.0f times the noise %.4f): is the array over the measuring "
                                     "bands, the sheet in its focus, the sun behind it, the photograph sharp?",
                                     along_x ? "x" : "rows", depth, kReadableDepth, noise));
}

// A whole array: of the lattice points read inside the darker region (which also holds the
// dark around the array, and the band's lines beside it), the design's count_x x count_y
// block of points read whole whose ring of points around it is darkest (the holder, where no
// light comes through), each point in it brighter than a lenslet image can be (the bare
// sheet, which reads about twice the brightest image: 1.4 times the 90th percentile of the
// readings that are not the holder's dark) counting as ten rings' light. The graded lines
// spread the images' light from none to full as a cosine: 1.4 times their 70th percentile
// (0.79 of the brightest) fell below the brightest images once the light's falloff was
// added, and pushed a block off their row onto the holder. A hexagonal array's rows are
// offset by half a pitch: its block is counted in columns i + floor(j / 2). Returns the
// indices of the block's points read (fewer than the array's lenslets when the region holds
// no whole block).
std::vector<std::size_t> array_block(const std::vector<LensletReading>& lenslets,
                                     const std::vector<Eigen::Vector2d>& labels, const Eigen::Matrix2d& design_basis,
                                     const optics::Lattice& lattice) {
    const bool hex = lattice.kind() == optics::LatticeKind::Hexagonal;
    std::vector<Eigen::Vector2i> cells;
    Eigen::Vector2i low = Eigen::Vector2i::Constant(std::numeric_limits<int>::max()), high = -low;
    for (const Eigen::Vector2d& label : labels) {
        const Eigen::Vector2d n = design_basis.inverse() * label;
        const int j = static_cast<int>(std::lround(n.y()));
        const int i = static_cast<int>(std::lround(n.x())) + (hex ? static_cast<int>(std::floor(0.5 * j)) : 0);
        cells.emplace_back(i, j);
        low = low.cwiseMin(cells.back());
        high = high.cwiseMax(cells.back());
    }
    // The percentile is taken over the light: points on the holder read nothing, and where
    // they are many (the array laid near the band's edge) the percentile of all points fell
    // below the brightest lenslets, which then counted as bare sheet and pushed the block a
    // lenslet onto the holder.
    double brightest = 0.0;
    for (const LensletReading& l : lenslets) brightest = std::max(brightest, l.value);
    std::vector<double> values;
    for (const LensletReading& l : lenslets)
        if (l.value >= kHolderDark * brightest) values.push_back(l.value);
    std::sort(values.begin(), values.end());
    const double bright = 1.4 * values[static_cast<std::size_t>(0.9 * static_cast<double>(values.size() - 1))];
    const int width = lattice.count_x(), height = lattice.count_y();
    Eigen::Vector2i best(0, 0);
    double best_score = HUGE_VAL;
    std::size_t best_count = 0;
    for (int j0 = low.y(); j0 + height - 1 <= high.y(); ++j0)
        for (int i0 = low.x(); i0 + width - 1 <= high.x(); ++i0) {
            double ring = 0.0;
            std::size_t count = 0, ring_count = 0, too_bright = 0;
            for (std::size_t k = 0; k < cells.size(); ++k) {
                const int i = cells[k].x() - i0, j = cells[k].y() - j0;
                if (i >= 0 && i < width && j >= 0 && j < height)
                    ++count, too_bright += lenslets[k].value > bright ? 1 : 0;
                else if (i >= -1 && i <= width && j >= -1 && j <= height)
                    ring += lenslets[k].value, ++ring_count;
            }
            if (count < best_count) continue;  // a whole block in view is the array's
            const double score = (ring_count ? ring / static_cast<double>(ring_count) : 0.0) +
                                 10.0 * static_cast<double>(too_bright);
            if (count > best_count || score < best_score) best_score = score, best = {i0, j0}, best_count = count;
        }
    std::vector<std::size_t> kept;
    for (std::size_t k = 0; k < cells.size(); ++k)
        if (cells[k].x() >= best.x() && cells[k].x() < best.x() + width && cells[k].y() >= best.y() &&
            cells[k].y() < best.y() + height)
            kept.push_back(k);
    return kept;
}

}  // namespace

void check_pitch_readable(const optics::Design& design) {
    const optics::Lattice& lattice = print::moire_lattice(design);
    // An array too small for the bands' cross is laid whole on each band and read whole.
    const int count = lattice.count_x() * lattice.count_y();
    if (count < kMinWholeLenslets)
        throw InputError(SourceLocation{design.file},
                         format_text("the lens array (%d x %d lenslets) is too small for the moire sheet's measuring "
                                     "bands (%d lenslets, %d needed): read the sheet's hypothesis bands by eye (the "
                                     "band whose fringes vanish has the array's pitch)",
                                     lattice.count_x(), lattice.count_y(), count, kMinWholeLenslets));
}

PitchReading read_pitch_photo(const Image& photo, const std::string& name, const optics::Design& design,
                              const print::MoireSheet& sheet, int page) {
    RFD_CHECK(page >= 0 && page < sheet.pages);
    check_pitch_readable(design);
    const optics::Lattice& lattice = print::moire_lattice(design);
    const bool hex = lattice.kind() == optics::LatticeKind::Hexagonal;
    const Image luminance = photo_luminance(photo);
    const SheetLocation where = find_sheet(luminance, sheet.marks, name);
    PitchReading start;
    start.name = name;
    start.mirrored = where.mirrored;
    start.mm_per_pixel = where.mm_per_pixel;
    // An array laid whole on a band is read whole. Its few lenslet images lie on the diffuser,
    // `height` above the sheet, and the photograph sees them magnified about the camera's foot
    // by kappa = Z / (Z - height), Z the camera's height: too little lattice for its spectrum
    // to give that magnification to the 0.5 % the reading needs (a 1 % error biases the
    // pitch by 0.012 %), so it comes from the camera's pose, which a tilted photograph's
    // homography tells.
    const bool whole = sheet.whole_array;
    Eigen::Vector2d foot = Eigen::Vector2d::Zero();
    double kappa = 1.0;
    if (whole) {
        const optics::Plane* diffuser = design.diffuser_plane();
        const double height = diffuser ? diffuser->z - design.pattern_plane().z : 0.0;
        const std::optional<EstimatedPose> pose =
            estimate_pose(where.page_to_photo, luminance.width(), luminance.height(), kMinTiltDeg);
        if (!pose)
            throw InputError(SourceLocation{name},
                             format_text("the photograph is within %.0f deg of frontal: the array's lenslet images lie "
                                         "%.1f mm above the sheet and the camera's height, which tells how much "
                                         "larger they look, shows only in a tilted photograph: take it again from "
                                         "20 to 40 deg off the vertical",
                                         kMinTiltDeg, height));
        foot = pose->centre.head<2>();
        kappa = -pose->centre.z() / (-pose->centre.z() - height);
    }

    // The array's design frame: A1 along a row, A2 to the next row; on the page (y down) the
    // nominal images of these (the lattice search starts from them).
    const double px = lattice.pitch_x(), py = lattice.pitch_y();
    Eigen::Matrix2d design_basis, page_basis;
    design_basis << px, hex ? 0.5 * px : 0.0, 0.0, py;
    page_basis << px, hex ? 0.5 * px : 0.0, 0.0, -py;

    // The measuring bands' area on this page, resampled coarsely; the diffuser in it.
    Eigen::Vector2d from = Eigen::Vector2d::Constant(HUGE_VAL), to = -from;
    for (const print::MoireBand& band : sheet.measuring)
        if (band.page == page) {
            from = from.cwiseMin(Eigen::Vector2d(band.left, band.top));
            to = to.cwiseMax(Eigen::Vector2d(band.left + band.width, band.top + band.height));
        }
    from -= Eigen::Vector2d::Constant(5.0);
    to += Eigen::Vector2d::Constant(5.0);
    const PageRaster coarse = resample(luminance, where.page_to_photo, from, to, kCoarsePixelsPerMm);
    const std::vector<std::uint8_t> region = diffuser_region(
        coarse, 1.5 * px, whole ? kWholeInset * std::min(px, py) : kEdgeLenslets * std::max(px, py), name);
    // The lenslet images' lattice shows in their edges and gaps; the moire modulates their
    // brightness slowly, which would add peaks beside the lattice's: each pixel over the mean
    // around it (a lenslet wide) keeps the edges and drops the modulation.
    std::vector<float> contrast(region.size());
    {
        const relight::PlaneSize size{coarse.image.width(), coarse.image.height()};
        std::vector<float> local(coarse.image.plane(0).begin(), coarse.image.plane(0).end());
        for (float& v : local)
            if (!std::isfinite(v)) v = 0.0f;
        std::vector<float> mean(local.size());
        const double sigma = px * kCoarsePixelsPerMm;
        relight::vision().gaussian_blur(size, local, mean, 0, sigma, sigma, relight::Border::Replicate);
        for (std::size_t k = 0; k < local.size(); ++k)
            contrast[k] = mean[k] > 0.0f ? local[k] / mean[k] - 1.0f : 0.0f;
    }
    const RegionSpectrum spectrum(coarse, contrast, region);

    const double cell_pixels = lattice.cell_area() * kCoarsePixelsPerMm * kCoarsePixelsPerMm;
    if (static_cast<double>(spectrum.pixels()) < (whole ? kMinWholeLenslets : 4.0 * kMinLenslets) * cell_pixels)
        throw InputError(SourceLocation{name}, "no lens array found over the bands (the darker region is " +
                                                   format_fixed(static_cast<double>(spectrum.pixels()) / cell_pixels, 0) +
                                                   " lenslets large)");

    // The lattice of lenslet images: its reciprocal vectors where the spectrum peaks.
    int x0 = coarse.image.width(), x1 = 0, y0 = coarse.image.height(), y1 = 0;
    for (int y = 0; y < coarse.image.height(); ++y)
        for (int x = 0; x < coarse.image.width(); ++x)
            if (region[static_cast<std::size_t>(y) * static_cast<std::size_t>(coarse.image.width()) + static_cast<std::size_t>(x)])
                x0 = std::min(x0, x), x1 = std::max(x1, x), y0 = std::min(y0, y), y1 = std::max(y1, y);
    const double extent = std::max(x1 - x0, y1 - y0) / kCoarsePixelsPerMm;
    const Eigen::Matrix2d nominal_reciprocal = page_basis.inverse();  // rows b1, b2
    Eigen::Matrix2d reciprocal;
    for (int i = 0; i < 2; ++i)
        reciprocal.row(i) = strongest_frequency(spectrum, nominal_reciprocal.row(i).transpose(), extent).transpose();
    // The lenslet images read on a lattice: the readings, their labels in the design's array
    // frame, the lattice, and how evenly lit the reading discs are.
    struct LatticeReading {
        PitchReading reading;
        std::vector<Eigen::Vector2d> labels;
        ImageLattice images;
        double spread = HUGE_VAL;  // the light varying inside the reading discs, against the light they read
    };
    // Reads the lenslet images on the lattice of `basis` (its reciprocal vectors the rows of
    // `reciprocal_rows`); a whole array's block of them.
    const auto read_lattice = [&](const Eigen::Matrix2d& basis, const Eigen::Matrix2d& reciprocal_rows) {
        PitchReading reading = start;
        ImageLattice images;
        images.basis = basis;
        const Eigen::Vector2d phases(-std::arg(spectrum.at(reciprocal_rows.row(0).transpose())) / kTwoPi,
                                     -std::arg(spectrum.at(reciprocal_rows.row(1).transpose())) / kTwoPi);
        // The lattice points (i, j) whose middle lies in the region, for a lattice origin.
        struct LatticePoint {
            int i, j;
            Eigen::Vector2d at;
        };
        const auto points_in_region = [&](const Eigen::Vector2d& origin) {
            const Eigen::Matrix2d to_index = images.basis.inverse();
            Eigen::Vector2d n_low = Eigen::Vector2d::Constant(HUGE_VAL), n_high = -n_low;
            for (const Eigen::Vector2d& corner :
                 {coarse.page(x0, y0), coarse.page(x1, y0), coarse.page(x0, y1), coarse.page(x1, y1)}) {
                const Eigen::Vector2d n = to_index * (corner - origin);
                n_low = n_low.cwiseMin(n);
                n_high = n_high.cwiseMax(n);
            }
            std::vector<LatticePoint> points;
            const int i_low = static_cast<int>(std::floor(n_low.x())), i_high = static_cast<int>(std::ceil(n_high.x()));
            for (int j = static_cast<int>(std::floor(n_low.y())); j <= static_cast<int>(std::ceil(n_high.y())); ++j)
                for (int i = i_low; i <= i_high; ++i) {
                    const Eigen::Vector2d at = origin + images.basis * Eigen::Vector2d(i, j);
                    const int cx = static_cast<int>(std::floor((at.x() - coarse.origin.x()) * kCoarsePixelsPerMm));
                    const int cy = static_cast<int>(std::floor((at.y() - coarse.origin.y()) * kCoarsePixelsPerMm));
                    if (cx < 0 || cy < 0 || cx >= coarse.image.width() || cy >= coarse.image.height()) continue;
                    if (region[static_cast<std::size_t>(cy) * static_cast<std::size_t>(coarse.image.width()) +
                               static_cast<std::size_t>(cx)])
                        points.push_back({i, j, at});
                }
            return points;
        };
        const double core = kCoreFraction * std::min(images.basis.col(0).norm(),
                                                     std::abs(images.basis.determinant()) / images.basis.col(0).norm());
        const double step = std::max(where.mm_per_pixel, core / 8.0);
        // Every lenslet image inside the region for a lattice origin, read over its central
        // part; a whole array's block of them.
        const auto read_images = [&](const Eigen::Vector2d& origin) {
            LatticeReading found{start, {}, {images.basis, origin}};
            std::vector<double> variances;
            for (const LatticePoint& point : points_in_region(origin)) {
                const auto [mean, variance] = disc_statistics(luminance, where.page_to_photo, point.at, core, step);
                if (!std::isfinite(mean)) continue;
                LensletReading l;
                l.page = point.at;
                l.value = mean;
                found.reading.lenslets.push_back(l);
                found.labels.push_back(design_basis * Eigen::Vector2d(point.i, point.j));
                variances.push_back(variance);
            }
            std::vector<std::size_t> kept(found.labels.size());
            std::iota(kept.begin(), kept.end(), std::size_t{0});
            if (whole && !kept.empty()) kept = array_block(found.reading.lenslets, found.labels, design_basis, lattice);
            double variance = 0.0, light = 0.0;
            std::vector<LensletReading> lenslets;
            std::vector<Eigen::Vector2d> labels;
            for (const std::size_t k : kept) {
                variance += variances[k];
                light += found.reading.lenslets[k].value * found.reading.lenslets[k].value;
                lenslets.push_back(found.reading.lenslets[k]);
                labels.push_back(found.labels[k]);
            }
            found.reading.lenslets = std::move(lenslets);
            found.labels = std::move(labels);
            if (light > 0.0) found.spread = variance / light;
            return found;
        };
        // The transform's phase places the lattice up to half a period along each basis vector
        // (a lenslet image may be bright in the middle or at its rim, where images overlap). Of
        // the four candidates, the one whose reading discs see single lenslets: their readings
        // then differ most from one lenslet to the next (a disc across two mixes them), sampled
        // every 2.5 lenslets.
        if (!whole) {
            const int stride = std::max(1, static_cast<int>(std::lround(2.5 * px * kCoarsePixelsPerMm)));
            double best_variation = -1.0;
            for (const Eigen::Vector2d& shift : {Eigen::Vector2d(0, 0), Eigen::Vector2d(0.5, 0),
                                                Eigen::Vector2d(0, 0.5), Eigen::Vector2d(0.5, 0.5)}) {
                const Eigen::Vector2d origin = images.basis * (phases + shift);
                double sum = 0.0, sum2 = 0.0;
                int cells = 0;
                for (int y = y0; y <= y1; y += stride)
                    for (int x = x0; x <= x1; x += stride) {
                        if (!region[static_cast<std::size_t>(y) * static_cast<std::size_t>(coarse.image.width()) +
                                    static_cast<std::size_t>(x)])
                            continue;
                        const Eigen::Vector2d cell =
                            (images.basis.inverse() * (coarse.page(x, y) - origin)).array().round().matrix();
                        const double mean =
                            disc_statistics(luminance, where.page_to_photo, origin + images.basis * cell, core, step)
                                .first;
                        if (std::isfinite(mean)) sum += mean, sum2 += mean * mean, ++cells;
                    }
                if (cells < 2) continue;
                const double mean = sum / cells, variation = (sum2 / cells - mean * mean) / (mean * mean);
                if (variation > best_variation) best_variation = variation, images.origin = origin;
            }
            LatticeReading found = read_images(images.origin);
            if (found.labels.empty()) throw InputError(SourceLocation{name}, "no lenslet images found");
            return found;
        }
        // A whole small array's few images give the phase only roughly, and the graded lines
        // make its lenslets' light differ as much as a disc across two does (a quarter of the
        // hand-held placements of docs/results.md found no lattice that way): its origin is
        // searched over the cell, a fifth, a twentieth and a fiftieth of it apart, each around
        // the best of the one before, for the block of discs that see the least light varying
        // inside them against the light they read (a lenslet image is evenly lit; a disc across
        // two sees an edge). A disc of 0.3 of a cell sees a single image over about 0.4 of it,
        // wider than the first spacing.
        LatticeReading best{start, {}, images};
        const std::size_t count = static_cast<std::size_t>(lattice.count_x()) * static_cast<std::size_t>(lattice.count_y());
        const auto search = [&](const Eigen::Vector2d& around, double spacing, int reach) {
            Eigen::Vector2d best_shift = around;
            for (int a = -reach; a <= reach; ++a)
                for (int b = -reach; b <= reach; ++b) {
                    const Eigen::Vector2d shift = around + spacing * Eigen::Vector2d(a, b);
                    LatticeReading found = read_images(images.basis * shift);
                    if (found.labels.size() == count && (best.labels.size() < count || found.spread < best.spread))
                        best = std::move(found), best_shift = shift;
                }
            return best_shift;
        };
        search(search(search(phases, 0.2, 2), 0.05, 2), 0.02, 1);
        if (best.labels.size() < count)
            throw InputError(SourceLocation{name},
                             format_text("the array's %d x %d lenslet images are not all in view in the darker region "
                                         "(%zu found): photograph the whole array on the band, lit from behind",
                                         lattice.count_x(), lattice.count_y(), best.labels.size()));
        return best;
    };
    // Fits the bands' lines to the lenslets read.
    const auto fit_lattice = [&](LatticeReading found) {
        PitchReading& reading = found.reading;
        const std::vector<Eigen::Vector2d>& labels = found.labels;
        const ImageLattice& images = found.images;
        // Each lenslet's measuring band: its light seen well inside the band (the light lies up
        // to a lenslet from where the lenslet focuses, so the band's edges are left out).
        // The light of a lenslet is seen up to a millimetre or two from where it focuses (the
        // diffuser's parallax, the light's slant), and a lenslet of a large array beside bare film
        // mixes it in. A whole array's images are its own (its corrective pair), and where it
        // focuses is where its image is seen with the parallax undone.
        const double margin = (whole ? 0.0 : std::max(px, py)) + kMarginMm;
        AxisData along_x, along_y;
        Eigen::Vector2d low = Eigen::Vector2d::Constant(HUGE_VAL), high = -low;
        for (const LensletReading& l : reading.lenslets) low = low.cwiseMin(l.page), high = high.cwiseMax(l.page);
        const Eigen::Vector2d centre = 0.5 * (low + high);
        // The reference lenslet: nearest the middle (labels are taken from it, so c is where it focuses).
        std::size_t reference = 0;
        for (std::size_t k = 0; k < reading.lenslets.size(); ++k)
            if ((reading.lenslets[k].page - centre).squaredNorm() <
                (reading.lenslets[reference].page - centre).squaredNorm())
                reference = k;
        const Eigen::Vector2d reference_label = labels[reference];
        for (std::size_t k = 0; k < reading.lenslets.size(); ++k) {
            LensletReading& l = reading.lenslets[k];
            for (std::size_t b = 0; b < sheet.measuring.size(); ++b) {
                const print::MoireBand& band = sheet.measuring[b];
                // Well inside: the band holds the square about it.
                bool inside = band.page == page;
                const Eigen::Vector2d focus = whole ? Eigen::Vector2d(foot + (l.page - foot) / kappa) : l.page;
                for (const double dx : {-margin, margin})
                    for (const double dy : {-margin, margin})
                        inside = inside && band.inside(focus.x() + dx, focus.y() + dy);
                if (!inside) continue;
                l.band = static_cast<int>(b);
                l.along_x = band.along_x;
                AxisData& data = band.along_x ? along_x : along_y;
                data.label.push_back(labels[k] - reference_label);
                data.where.push_back(l.page);
                data.value.push_back(l.value);
                data.period.push_back(band.period);
                data.origin.push_back(
                    band.normal().dot(Eigen::Vector2d(band.left + 0.5 * band.width, band.top + 0.5 * band.height)));
                data.lenslet.push_back(k);
            }
        }
        if (static_cast<int>(std::max(along_x.value.size(), along_y.value.size())) < kMinLenslets)
            throw InputError(SourceLocation{name},
                             format_text("only %zu and %zu lenslets lie inside the x and rows measuring bands "
                                         "(at least %d needed in one): lay the array over them",
                                         along_x.value.size(), along_y.value.size(), kMinLenslets));
        // Start from the lattice of lenslet images: its rows give the directions (the parallax
        // magnifies it about the camera's foot but does not turn it), the design the lengths.
        // A band's lines measure their normal's row of the map: n^T M.
        const Eigen::Matrix2d image_map = images.basis * design_basis.inverse();
        const Eigen::Vector2d reference_page = reading.lenslets[reference].page;
        for (const print::MoireBand& band : sheet.measuring) {
            if (band.page != page) continue;
            const Eigen::Vector2d n = band.normal();
            AxisFit& fit = band.along_x ? reading.x : reading.y;
            fit.normal_angle = std::atan2(n.y(), n.x());
            AxisData& data = band.along_x ? along_x : along_y;
            data.graded = band.graded;
            fit_axis(data, n.dot(reference_page), (n.transpose() * image_map).transpose(), 1.0,
                     band.line_fraction, band.along_x, whole, fit, reading.lenslets, name);
        }
        for (const print::MoireBand& band : sheet.measuring)
            if (band.page == page) ++(band.along_x ? reading.x.bands : reading.y.bands);
        return reading;
    };
    if (!whole) {
        PitchReading reading = fit_lattice(read_lattice(reciprocal.inverse(), reciprocal));
        if (reading.x.lenslets == 0 || reading.y.lenslets == 0) return reading;
        // The lenslet images' lattice is the array's magnified about the camera's foot, the
        // same shape as the lattice the lines measure; where a reading disc lies in its image
        // moves the phase it reads, so discs placed on a lattice that departs from it drift
        // across the images and bias the scale. With the sun 28-30 deg off the axis or a
        // hand-held photograph unevenly lit, the spectrum's lattice departed 0.06-0.23 % and
        // the row spacing read 0.015-0.044 % off at +-0.001 % (docs/results.md); the scale moved
        // by up to half the departure. In good photographs it departs at most 0.04 %
        // (kLatticeMismatchNoise): beyond that, each scale's uncertainty grows by the excess.
        Eigen::Matrix2d normals, rows;
        normals << std::cos(reading.x.normal_angle), std::sin(reading.x.normal_angle),
            std::cos(reading.y.normal_angle), std::sin(reading.y.normal_angle);
        rows << reading.x.row.transpose(), reading.y.row.transpose();
        const Eigen::Matrix2d shape = reciprocal.inverse() * (normals.inverse() * rows * design_basis).inverse();
        const Eigen::Vector2d stretch = Eigen::JacobiSVD<Eigen::Matrix2d>(shape).singularValues();
        reading.lattice_mismatch = stretch(0) / stretch(1) - 1.0;
        const double excess = reading.lattice_mismatch - kLatticeMismatchNoise;
        if (excess > 0.0)
            for (AxisFit* fit : {&reading.x, &reading.y}) {
                const Eigen::Vector2d along = fit->row.normalized();
                fit->row_covariance += std::pow(excess * fit->row.norm(), 2) * along * along.transpose();
            }
        return reading;
    }
    // A whole small array's few lenslet images give the spectrum broad peaks, which the
    // moire's modulation of their brightness pulls aside: its turn came out up to 3 deg off in
    // hand-held photographs, enough for the reading discs of the outer lenslets to straddle two
    // images (the fit then missed the readings by half their spread, and the photograph was
    // refused). So the lattice is tried at turns a degree apart around the spectrum's, its
    // magnification from the pose and its cells from the design, and the one whose discs see
    // single images is kept: the least light varying inside the discs against the light they
    // read (a lenslet image is evenly lit; a disc across two sees an edge).
    const Eigen::Matrix2d spectrum_basis = reciprocal.inverse();
    const double spectrum_turn = std::atan2(spectrum_basis(1, 0), spectrum_basis(0, 0));
    std::vector<LatticeReading> candidates;
    std::optional<InputError> first_error;
    for (int k = 0; k <= 2 * kWholeTurnSteps; ++k) {
        const int steps = (k + 1) / 2 * (k % 2 ? 1 : -1);  // 0, +1, -1, +2, ...
        const double turn = spectrum_turn + degrees_to_radians(kWholeTurnStepDeg * steps);
        const Eigen::Matrix2d basis = kappa * Eigen::Rotation2Dd(turn).toRotationMatrix() * page_basis;
        try {
            candidates.push_back(read_lattice(basis, basis.inverse()));
        } catch (const InputError& e) {
            if (!first_error) first_error = e;
        }
    }
    // The lattices in the order of how well their discs see single images; the first whose
    // readings fit the lines is kept.
    std::stable_sort(candidates.begin(), candidates.end(),
                     [](const LatticeReading& a, const LatticeReading& b) { return a.spread < b.spread; });
    std::optional<InputError> fit_error;
    for (LatticeReading& candidate : candidates) {
        try {
            PitchReading reading = fit_lattice(std::move(candidate));
            // The reading discs placed again, on the lattice of the array the lines measured: its
            // turn and scale (the lattice tried is up to half a degree and the pitch error off,
            // and where a disc lies in its lenslet image moves the phase it reads).
            const AxisFit& fit = reading.x.lenslets > 0 ? reading.x : reading.y;
            const double turn = std::atan2(-fit.row.y(), fit.row.x()) - fit.normal_angle;
            const Eigen::Matrix2d basis =
                kappa * fit.row.norm() * Eigen::Rotation2Dd(-turn).toRotationMatrix() * page_basis;
            try {
                return fit_lattice(read_lattice(basis, basis.inverse()));
            } catch (const InputError&) {
                return reading;  // the discs placed again read worse: the first placement's reading
            }
        } catch (const InputError& e) {
            if (!fit_error) fit_error = e;
        }
    }
    throw fit_error ? *fit_error : *first_error;
}

PitchCalibration calibrate_pitch(const optics::Design& design, const std::vector<PitchReading>& readings,
                                 const Eigen::Vector2d& sheet_scale) {
    RFD_CHECK(!readings.empty());
    const optics::Lattice& lattice = print::moire_lattice(design);
    PitchCalibration out;
    out.design_pitch_x = lattice.pitch_x();
    out.design_pitch_y = lattice.pitch_y();
    out.sheet_scale_x = sheet_scale.x();
    out.sheet_scale_y = sheet_scale.y();
    const auto measured = [](const AxisFit& fit) { return fit.lenslets > 0; };
    bool any_x = false, any_y = false;
    for (const PitchReading& r : readings) any_x |= measured(r.x), any_y |= measured(r.y);
    if (!any_x || !any_y)
        throw InputError(SourceLocation{readings.front().name},
                         std::string("no photograph shows the array over the ") + (any_x ? "rows" : "x") +
                             " measuring band: photograph it there too");
    // M = F R(theta) diag(sx, sy), and a band whose lines have the normal at angle beta
    // measures n^T M = (sx cos psi, -sy sin psi), psi = beta + theta. The x band (psi near 0)
    // gives sx once sin psi is known from its second entry over sy; the rows band (psi near
    // 90 deg) gives sy once cos psi is known from its first entry over sx. Three passes
    // settle both from 1.
    out.scale_x = out.scale_y = 1.0;
    for (int pass = 0; pass < 3; ++pass) {
        double wx = 0.0, sx = 0.0, wy = 0.0, sy = 0.0;
        out.rotation_deg.clear();
        out.sigma_rotation_deg.clear();
        out.shear_deg.clear();
        for (const PitchReading& r : readings) {
            double turn_sum = 0.0, turn_weight = 0.0;
            std::vector<double> turns;
            if (measured(r.x)) {
                const Eigen::Vector2d u = sheet_scale.cwiseProduct(r.x.row);
                const Eigen::Matrix2d cov = sheet_scale.asDiagonal() * r.x.row_covariance * sheet_scale.asDiagonal();
                const double psi = std::asin(std::clamp(-u.y() / out.scale_y, -1.0, 1.0));
                const double turn_var = cov(1, 1) / std::pow(out.scale_y * std::cos(psi), 2);
                // The scale's variance: its own entry's, and the turn's through the slant.
                const double var = cov(0, 0) / std::pow(std::cos(psi), 2) +
                                   std::pow(u.x() * std::tan(psi) / std::cos(psi), 2) * turn_var;
                wx += 1.0 / var, sx += u.x() / std::cos(psi) / var;
                turn_sum += (psi - r.x.normal_angle) / turn_var, turn_weight += 1.0 / turn_var;
                turns.push_back(psi - r.x.normal_angle);
            }
            if (measured(r.y)) {
                const Eigen::Vector2d u = sheet_scale.cwiseProduct(r.y.row);
                const Eigen::Matrix2d cov = sheet_scale.asDiagonal() * r.y.row_covariance * sheet_scale.asDiagonal();
                const double psi = std::acos(std::clamp(u.x() / out.scale_x, -1.0, 1.0));
                const double turn_var = cov(0, 0) / std::pow(out.scale_x * std::sin(psi), 2);
                const double var = cov(1, 1) / std::pow(std::sin(psi), 2) +
                                   std::pow(u.y() / (std::tan(psi) * std::sin(psi)), 2) * turn_var;
                wy += 1.0 / var, sy += -u.y() / std::sin(psi) / var;
                turn_sum += (psi - r.y.normal_angle) / turn_var, turn_weight += 1.0 / turn_var;
                turns.push_back(psi - r.y.normal_angle);
            }
            out.rotation_deg.push_back(radians_to_degrees(turn_sum / turn_weight));
            out.sigma_rotation_deg.push_back(radians_to_degrees(std::sqrt(1.0 / turn_weight)));
            // The rows' turn from the x band less the columns' from the rows band: the axes'
            // departure from square (0 for a true array; NaN when a photo shows one band).
            out.shear_deg.push_back(turns.size() == 2 ? radians_to_degrees(turns[0] - turns[1]) : NAN);
        }
        if (wx > 0.0) out.scale_x = sx / wx, out.sigma_scale_x = std::sqrt(1.0 / wx);
        if (wy > 0.0) out.scale_y = sy / wy, out.sigma_scale_y = std::sqrt(1.0 / wy);
    }
    // Never a NaN written as a pitch: readings that do not determine one are refused.
    if (!std::isfinite(out.scale_x) || !std::isfinite(out.scale_y) || !std::isfinite(out.sigma_scale_x) ||
        !std::isfinite(out.sigma_scale_y))
        throw InputError(SourceLocation{readings.front().name},
                         "the photographs do not determine the pitch (a scale or its uncertainty is not a number)");
    return out;
}

}  // namespace rfd::calibrate
