#include "optics/diffraction.hpp"

#include <algorithm>
#include <cmath>
#include <complex>

#include <unsupported/Eigen/FFT>

#include "core/error.hpp"
#include "core/units.hpp"
#include "optics/paraxial.hpp"

namespace rfd::optics {
namespace {

// The darkest sample before the intensity first rises again, from the centre outward.
int first_minimum(const std::function<double(int)>& value, int limit) {
    for (int i = 1; i + 1 <= limit; ++i)
        if (value(i + 1) >= value(i)) return i;
    return limit;
}

// The intensity along one axis of the focal plane, |sum_u m(u) exp(-2 pi i u x / (lambda f))|^2,
// from the pupil's marginal m along that axis (sampled at du): the FFT's value between its
// samples, exactly, for the ring's position.
double axis_intensity(const std::vector<double>& marginal, double du, double lambda_f, double x) {
    std::complex<double> sum = 0.0;
    const int grid = static_cast<int>(marginal.size());
    for (int k = 0; k < grid; ++k) {
        const double u = (k - grid / 2) * du;
        sum += marginal[static_cast<std::size_t>(k)] * std::polar(1.0, -2.0 * kPi * u * x / lambda_f);
    }
    return std::norm(sum);
}

// The minimum of f on [lo, hi] by golden-section search (f unimodal there).
double golden_minimum(const std::function<double(double)>& f, double lo, double hi) {
    const double ratio = 0.5 * (std::sqrt(5.0) - 1.0);
    double a = lo, b = hi;
    double c = b - ratio * (b - a), d = a + ratio * (b - a);
    double fc = f(c), fd = f(d);
    for (int k = 0; k < 60; ++k) {
        if (fc < fd) {
            b = d, d = c, fd = fc;
            c = b - ratio * (b - a), fc = f(c);
        } else {
            a = c, c = d, fc = fd;
            d = a + ratio * (b - a), fd = f(d);
        }
    }
    return 0.5 * (a + b);
}

// The elements that put the pattern where they focus, as surfaces [first, last].
struct PatternLens {
    std::string element;
    std::size_t first = 0, last = 0;
};

PatternLens pattern_lens(const DesignOptics& optics) {
    const Design& design = optics.design();
    const SequentialSystem& system = optics.system();
    if (!is_observer_variant(design.kind))
        return {"lenslets in front of the pattern (" + design.planes.front().name + ")", 0,
                optics.encoding_surface() - 1};
    const std::size_t pattern = system.find(design.pattern_plane().name + " pattern");
    return {"lenslets behind the pattern (" + design.pattern_plane().name + " back, " + design.planes.back().name + ")",
            pattern + 1, system.surfaces.size() - 1};
}

}  // namespace

double airy_radius(double wavelength, double f_number) { return 1.22 * wavelength * f_number; }

double airy_psf(double r, double wavelength, double f_number) {
    const double x = kPi * r / (wavelength * f_number);
    if (std::abs(x) < 1e-8) return 1.0;
    const double amplitude = 2.0 * std::cyl_bessel_j(1.0, std::abs(x)) / std::abs(x);
    return amplitude * amplitude;
}

double rectangle_psf(double x, double y, double wavelength, double focal, double a, double b) {
    auto sinc2 = [](double t) {
        if (std::abs(t) < 1e-8) return 1.0;
        const double s = std::sin(t) / t;
        return s * s;
    };
    return sinc2(kPi * a * x / (wavelength * focal)) * sinc2(kPi * b * y / (wavelength * focal));
}

Psf fraunhofer_psf(const std::function<bool(const Eigen::Vector2d&)>& inside, double half_extent,
                   double wavelength, double focal, int grid, int padding, int keep) {
    RFD_CHECK(grid >= 16 && (grid & (grid - 1)) == 0 && padding >= 2 && keep % 2 == 1 && keep < grid);
    RFD_CHECK(half_extent > 0 && wavelength > 0 && focal > 0);
    const double window = 2.0 * half_extent * padding;
    const double du = window / grid;
    const auto n = static_cast<std::size_t>(grid);
    // The pupil, each sample the fraction of 4 x 4 sub-samples inside: edges that do not
    // fall on the grid still have their area.
    std::vector<std::complex<double>> field(n * n);
    std::vector<double> marginal_x(n, 0.0), marginal_y(n, 0.0);
    for (int iy = 0; iy < grid; ++iy)
        for (int ix = 0; ix < grid; ++ix) {
            int count = 0;
            for (int sy = 0; sy < 4; ++sy)
                for (int sx = 0; sx < 4; ++sx) {
                    const Eigen::Vector2d p((ix - grid / 2 + (sx + 0.5) / 4 - 0.5) * du,
                                            (iy - grid / 2 + (sy + 0.5) / 4 - 0.5) * du);
                    count += inside(p) ? 1 : 0;
                }
            field[static_cast<std::size_t>(iy) * n + static_cast<std::size_t>(ix)] = count / 16.0;
            marginal_x[static_cast<std::size_t>(ix)] += count / 16.0;
            marginal_y[static_cast<std::size_t>(iy)] += count / 16.0;
        }
    Eigen::FFT<double> fft;
    std::vector<std::complex<double>> line(n), transformed(n);
    for (std::size_t row = 0; row < n; ++row) {
        std::copy_n(field.begin() + static_cast<std::ptrdiff_t>(row * n), n, line.begin());
        fft.fwd(transformed, line);
        std::copy_n(transformed.begin(), n, field.begin() + static_cast<std::ptrdiff_t>(row * n));
    }
    for (std::size_t col = 0; col < n; ++col) {
        for (std::size_t row = 0; row < n; ++row) line[row] = field[row * n + col];
        fft.fwd(transformed, line);
        for (std::size_t row = 0; row < n; ++row) field[row * n + col] = transformed[row];
    }
    // Frequency k (cycles per window) lies at lambda f k / window in the focal plane.
    Psf psf;
    psf.size = keep;
    psf.step = wavelength * focal / window;
    psf.values.resize(static_cast<std::size_t>(keep) * static_cast<std::size_t>(keep));
    double sum = 0.0;
    for (int iy = 0; iy < keep; ++iy)
        for (int ix = 0; ix < keep; ++ix) {
            const auto fx = static_cast<std::size_t>((ix - keep / 2 + grid) % grid);
            const auto fy = static_cast<std::size_t>((iy - keep / 2 + grid) % grid);
            const double v = std::norm(field[fy * n + fx]);
            psf.values[static_cast<std::size_t>(iy * keep + ix)] = v;
            sum += v;
        }
    for (double& v : psf.values) v /= sum;
    // The first dark ring along each axis: near the darkest sample, where the Fraunhofer
    // integral along that axis is least.
    const int c = keep / 2;
    const double lambda_f = wavelength * focal;
    const int ix = first_minimum([&](int i) { return psf.at(c + i, c); }, c - 1);
    const int iy = first_minimum([&](int i) { return psf.at(c, c + i); }, c - 1);
    psf.lobe_radius_x = golden_minimum([&](double x) { return axis_intensity(marginal_x, du, lambda_f, x); },
                                       (ix - 1) * psf.step, (ix + 1) * psf.step);
    psf.lobe_radius_y = golden_minimum([&](double y) { return axis_intensity(marginal_y, du, lambda_f, y); },
                                       (iy - 1) * psf.step, (iy + 1) * psf.step);
    return psf;
}

Psf pattern_psf(const DesignOptics& optics, double wavelength) {
    const PatternLens lens = pattern_lens(optics);
    const double focal = std::abs(cardinal_points(optics.system(), lens.first, lens.last).efl);
    const Lattice& lattice = optics.lattice();
    const CellIndex cell = optics.centre_cell();
    const Eigen::Vector2d centre = lattice.center(cell);
    return fraunhofer_psf([&](const Eigen::Vector2d& p) { return lattice.cell_contains(cell, centre + p); },
                          lattice.circumradius(), wavelength, focal);
}

Eigen::Vector2d DiffractionEstimate::lobe_dots() const {
    return {lobe_radius_mm[2] / dot_mm.x(), lobe_radius_mm[2] / dot_mm.y()};
}

DiffractionEstimate estimate_diffraction(const DesignOptics& optics) {
    const PatternLens lens = pattern_lens(optics);
    DiffractionEstimate e;
    e.element = lens.element;
    e.focal_length = std::abs(cardinal_points(optics.system(), lens.first, lens.last).efl);
    const Lattice& lattice = optics.lattice();
    e.aperture_x = lattice.pitch_x();  // a hexagon's width across its flats
    e.aperture_y = lattice.kind() == LatticeKind::Hexagonal ? 2.0 * lattice.circumradius() : lattice.pitch_y();
    for (std::size_t k = 0; k < kDiffractionWavelengthsMm.size(); ++k) {
        const Psf psf = pattern_psf(optics, kDiffractionWavelengthsMm[k]);
        e.lobe_radius_mm[k] = std::max(psf.lobe_radius_x, psf.lobe_radius_y);
    }
    e.dot_mm = optics.dot_mm();
    return e;
}

DiffractedTransparency::DiffractedTransparency(const Transparency& inner, const std::vector<Psf>& psfs)
    : inner_(inner) {
    RFD_CHECK(psfs.size() == 1 || psfs.size() == static_cast<std::size_t>(inner.channels()));
    constexpr int kTaps = 9;
    // The PSF between its samples, bilinearly; 0 outside.
    auto value = [](const Psf& psf, const Eigen::Vector2d& p) {
        const int c = psf.size / 2;
        const double gx = p.x() / psf.step + c, gy = p.y() / psf.step + c;
        const int x0 = static_cast<int>(std::floor(gx)), y0 = static_cast<int>(std::floor(gy));
        if (x0 < 0 || y0 < 0 || x0 + 1 >= psf.size || y0 + 1 >= psf.size) return 0.0;
        const double fx = gx - x0, fy = gy - y0;
        return (1 - fx) * (1 - fy) * psf.at(x0, y0) + fx * (1 - fy) * psf.at(x0 + 1, y0) +
               (1 - fx) * fy * psf.at(x0, y0 + 1) + fx * fy * psf.at(x0 + 1, y0 + 1);
    };
    double reach_x = 0, reach_y = 0;
    for (const Psf& psf : psfs) {
        reach_x = std::max(reach_x, 2.0 * psf.lobe_radius_x);
        reach_y = std::max(reach_y, 2.0 * psf.lobe_radius_y);
    }
    for (int iy = 0; iy < kTaps; ++iy)
        for (int ix = 0; ix < kTaps; ++ix)
            offsets_.emplace_back(reach_x * (ix - kTaps / 2) / (kTaps / 2), reach_y * (iy - kTaps / 2) / (kTaps / 2));
    for (int channel = 0; channel < inner.channels(); ++channel) {
        const Psf& psf = psfs.size() == 1 ? psfs.front() : psfs[static_cast<std::size_t>(channel)];
        std::vector<double> w;
        double sum = 0.0;
        for (const auto& offset : offsets_) {
            w.push_back(value(psf, offset));
            sum += w.back();
        }
        RFD_CHECK(sum > 0);
        for (double& v : w) v /= sum;
        weights_.push_back(std::move(w));
    }
}

void DiffractedTransparency::sample(std::span<const Eigen::Vector2d> points, std::span<float> out) const {
    const auto channels = static_cast<std::size_t>(inner_.channels());
    std::vector<Eigen::Vector2d> shifted(points.size());
    std::vector<float> values(points.size() * channels);
    std::vector<double> sum(points.size() * channels, 0.0);
    for (std::size_t t = 0; t < offsets_.size(); ++t) {
        for (std::size_t i = 0; i < points.size(); ++i) shifted[i] = points[i] + offsets_[t];
        inner_.sample(shifted, values);
        for (std::size_t i = 0; i < points.size(); ++i)
            for (std::size_t c = 0; c < channels; ++c) sum[i * channels + c] += weights_[c][t] * values[i * channels + c];
    }
    for (std::size_t i = 0; i < sum.size(); ++i) out[i] = static_cast<float>(sum[i]);
}

std::unique_ptr<Transparency> diffracted(const Transparency& pattern, const DesignOptics& optics) {
    std::vector<Psf> psfs;
    if (pattern.channels() == 3)
        for (int k = 2; k >= 0; --k) psfs.push_back(pattern_psf(optics, kDiffractionWavelengthsMm[static_cast<std::size_t>(k)]));
    else
        psfs.push_back(pattern_psf(optics, kDiffractionWavelengthsMm[1]));
    return std::make_unique<DiffractedTransparency>(pattern, psfs);
}

}  // namespace rfd::optics
