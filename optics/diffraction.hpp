#pragma once
// The third model of light: where geometric optics stops. A lens of effective focal length
// f and aperture D cannot focus a parallel beam to a point: its focal plane holds the
// aperture's Fraunhofer pattern, of scale lambda f / D (an Airy pattern for a disc, with
// its first dark ring at 1.22 lambda N, N = f / D; sinc^2 across a square). Symmetrically,
// a point of a pattern in a lens's front focal plane leaves as a beam the aperture cuts,
// spread over lambda / D: the pattern is seen through the same point-spread function.
//
// rfd's patterns lie where a lenslet array focuses (Designs I/II: the entry lenslets;
// Designs III/IV: the projection lenslets E, whose front focal plane holds the pattern), so
// the estimate is the lenslet cell's PSF on the pattern plane, from the FFT of the cell
// (Eigen's FFT), at 450, 550 and 650 nm. Where its central lobe exceeds a tolerance in
// print dots, the simulators see the pattern through it (DiffractedTransparency).
//
// Example: const DiffractionEstimate e = estimate_diffraction(DesignOptics(design));
//          // e.lobe_radius_mm[2]: the central lobe's radius at 650 nm on the pattern

#include <array>
#include <functional>
#include <memory>
#include <vector>

#include <Eigen/Core>

#include "optics/design_optics.hpp"
#include "optics/display.hpp"

namespace rfd::optics {

/// The wavelengths of the estimate, mm (blue, green, red).
inline constexpr std::array<double, 3> kDiffractionWavelengthsMm{450e-6, 550e-6, 650e-6};

/// Radius of the first dark ring of a disc's Airy pattern: 1.22 lambda N (any length unit).
double airy_radius(double wavelength, double f_number);
/// The Airy pattern, 1 at its centre: (2 J1(x) / x)^2, x = pi r / (lambda N).
double airy_psf(double r, double wavelength, double f_number);
/// A rectangular aperture a x b's Fraunhofer pattern at focal length f, 1 at its centre:
/// sinc^2(pi a x / (lambda f)) sinc^2(pi b y / (lambda f)); its first zeros at lambda f / a
/// and lambda f / b.
double rectangle_psf(double x, double y, double wavelength, double focal, double a, double b);

/// A point-spread function sampled on a square grid centred on the middle sample.
struct Psf {
    int size = 0;          ///< samples per side (odd: the centre is a sample)
    double step = 0.0;     ///< mm between samples
    std::vector<double> values;  ///< row-major, row 0 at -y; sums to 1
    double lobe_radius_x = 0.0;  ///< mm from the centre to the first minimum along x
    double lobe_radius_y = 0.0;  ///< along y

    double at(int ix, int iy) const { return values[static_cast<std::size_t>(iy * size + ix)]; }
};

/// The Fraunhofer pattern in the focal plane of a lens of effective focal length `focal`
/// whose aperture is { p : inside(p) }, within |x|, |y| <= half_extent: |FFT of the pupil|^2
/// on a grid padded `padding` times the aperture, so that the focal-plane step is
/// lambda f / (2 half_extent padding). `grid` (a power of two) samples the padded pupil;
/// the result keeps `keep` samples per side (odd) around the centre.
Psf fraunhofer_psf(const std::function<bool(const Eigen::Vector2d&)>& inside, double half_extent,
                   double wavelength, double focal, int grid = 256, int padding = 4, int keep = 65);

/// What diffraction does to one design's pattern.
struct DiffractionEstimate {
    std::string element;        ///< which lenses, e.g. "entry lenslets (A)"
    double focal_length = 0.0;  ///< mm, effective
    double aperture_x = 0.0, aperture_y = 0.0;  ///< mm, the cell's width and height
    /// Radius of the PSF's central lobe on the pattern per wavelength (along the cell's
    /// narrower side, where it is widest), mm.
    std::array<double, 3> lobe_radius_mm{};
    Eigen::Vector2d dot_mm = Eigen::Vector2d::Zero();  ///< the design printer's dot
    /// The lobe at 650 nm in print dots (along x, along y).
    Eigen::Vector2d lobe_dots() const;
    /// The dot size below which diffraction blurs more than one dot: the lobe at 650 nm, mm.
    double critical_dot_mm() const { return lobe_radius_mm[2]; }
    /// Half-width of the light a pattern feature `feature_mm` wide spreads over on the
    /// lenses one focal length away at 650 nm (lambda f / w), mm: light a small feature
    /// diffracts beyond a lenslet's cell leaves through its neighbour (Designs III/IV).
    double feature_spread_mm(double feature_mm) const {
        return kDiffractionWavelengthsMm[2] * focal_length / feature_mm;
    }
};
DiffractionEstimate estimate_diffraction(const DesignOptics& optics);

/// The lens cell's PSF at one wavelength on the pattern plane (for DiffractedTransparency).
Psf pattern_psf(const DesignOptics& optics, double wavelength);

/// A transparency seen through PSFs, one per channel (one for all: a single PSF): each
/// sample the PSF-weighted mean of the inner transparency around the point, over 9 x 9 taps
/// spanning two lobe radii of the widest PSF. The diffraction model of the simulators.
class DiffractedTransparency final : public Transparency {
public:
    DiffractedTransparency(const Transparency& inner, const std::vector<Psf>& psfs);
    int channels() const override { return inner_.channels(); }
    void sample(std::span<const Eigen::Vector2d> points, std::span<float> out) const override;

private:
    const Transparency& inner_;
    std::vector<Eigen::Vector2d> offsets_;
    std::vector<std::vector<double>> weights_;  ///< per channel, per offset
};

/// The pattern as the simulators see it when the resolved model includes diffraction:
/// through the design's PSF at 650, 550 and 450 nm (red, green and blue channels; 550 nm for
/// a grey pattern). Keeps a reference: `pattern` must outlive it.
std::unique_ptr<Transparency> diffracted(const Transparency& pattern, const DesignOptics& optics);

}  // namespace rfd::optics
