#pragma once
// The printer's tone curve from scans or photographs of its printed step wedge
// (print/wedge.hpp): each patch's transmittance against bare film, and the measured curve
// written into a printer profile (print/printer.hpp, [tone]) that encoding, simulation and
// sheets then use.
//
// Light: a photograph makes no scene evenly lit (vignetting, a light box's falloff), so the
// light is measured on the sheet itself: the bare film between and around the patches is
// sampled and a smooth surface (a cubic in page x and y, refitted without outliers such as
// dust) gives the light behind every patch; a patch's transmittance is its brightness over that
// light, normalised by the bare-film patch (code 255). Against a white backing the light
// crosses the film twice, so the transmittance is the square root of that ratio.
//
// Example: auto reading = measure_wedge(read_image("scan.jpg"), "scan.jpg", sheet, printer,
//                                       ScanLight::Back);
//          ToneCalibration fit = calibrate_tone(printer, {reading});

#include <string>
#include <vector>

#include "calibrate/camera.hpp"
#include "core/image.hpp"
#include "print/printer.hpp"
#include "print/wedge.hpp"

namespace rfd::calibrate {

/// How the scan or photograph was lit.
enum class ScanLight {
    Back,      ///< from behind: a light box or a scanner's transparency unit (the
               ///< light crosses the film once)
    Reflected  ///< film on a white backing, lit from the front (the light crosses
               ///< it twice)
};

/// A simulated photograph of the wedge's page `page` as `truth` prints it (its tone curve,
/// not the profile's), lit as `light` says and taken by `camera`: linear, one channel, before
/// the camera stores it. The test photographs of the calibration and of its docs.
Image simulated_wedge_photo(const print::WedgeSheet& sheet, const print::PrinterProfile& printer,
                            const print::PrinterProfile& truth, const Camera& camera, ScanLight light, int page = 0);

struct PatchReading {
    int code = 255;               ///< printer code of the patch
    double ink = 0.0;             ///< printer value 1 - code / 255
    double transmittance = 1.0;   ///< measured, against bare film
    double standard_error = 0.0;  ///< of the transmittance, from the patch's pixels
};

/// One scan's reading of the wedge.
struct WedgeReading {
    std::string name;                   ///< the scan, for messages
    std::vector<PatchReading> patches;  ///< in the wedge's order (code 255 first)
    bool mirrored = false;              ///< seen from the film's back
    double mm_per_pixel = 0.0;
    double light_spread = 0.0;    ///< the fitted light's range over the sheet, fraction of its mean
    double light_residual = 0.0;  ///< bare film's RMS departure from the fitted light, fraction
    double exposure = 0.0;        ///< linear pixel value of bare film (mean)
};

/// Reads page `page` (0-based) of a wedge from one linear photograph. InputError, naming
/// `name`, when the sheet is not found, the photo is over- or under-exposed, the patches are
/// too small in it, or the light is too uneven to model.
WedgeReading measure_wedge(const Image& photo, const std::string& name, const print::WedgeSheet& sheet,
                           const print::PrinterProfile& printer, ScanLight light, int page = 0);

struct ToneCalibration {
    print::PrinterProfile profile;      ///< the input profile with the measured curve,
                                        ///< max_density and black level
    std::vector<PatchReading> patches;  ///< the readings combined (mean of the
                                        ///< scans; error from their spread)
    double power_law_gamma = 0.0;       ///< the power law of print/printer.hpp fitted to the readings
    double power_law_rms = 0.0;         ///< its RMS departure from the readings, transmittance
    double nominal_rms = 0.0;           ///< the input profile's RMS departure from the
                                        ///< readings, transmittance

    /// The measured profile with the fitted power law in place of its table.
    print::PrinterProfile power_law() const;
};

/// Combines the readings of one or more scans of the same wedge into a profile: the measured
/// curve (made monotonic), max_density from full ink, the black level with the input profile's
/// head room above full ink, and gamma fitted for reference.
ToneCalibration calibrate_tone(const print::PrinterProfile& printer, const std::vector<WedgeReading>& readings);

}  // namespace rfd::calibrate
