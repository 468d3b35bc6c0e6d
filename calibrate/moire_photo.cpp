#include "calibrate/moire_photo.hpp"

#include <algorithm>
#include <cmath>

#include <Eigen/LU>

#include "calibrate/display_photo.hpp"
#include "calibrate/sheet_finder.hpp"
#include "core/error.hpp"
#include "core/units.hpp"
#include "optics/display.hpp"

namespace rfd::calibrate {
namespace {

constexpr double kPagePixelsPerMm = 10.0;  // finer than a photograph's pixel on the page

// The sheet as the lenslets see it, in the array's frame: the lines of the page's bands (the
// labels and header lie beside the array, never under a lenslet that reads a band).
class SheetUnderArray final : public optics::Transparency {
public:
    SheetUnderArray(const print::MoireSheet& sheet, int page, const ArrayMounting& mounting, double line_transmittance)
        : sheet_(sheet), page_(page), centre_(mounting.centre), to_page_(array_to_page(mounting)),
          line_(line_transmittance) {}
    int channels() const override { return 1; }
    void sample(std::span<const Eigen::Vector2d> points, std::span<float> out) const override {
        for (std::size_t k = 0; k < points.size(); ++k) {
            const Eigen::Vector2d page = centre_ + to_page_ * points[k];
            double ink = 0.0;
            for (const auto* bands : {&sheet_.measuring, &sheet_.bands})
                for (const print::MoireBand& band : *bands)
                    if (band.page == page_) ink = std::max(ink, band.ink(page.x(), page.y()));
            out[k] = static_cast<float>(line_ + (1.0 - ink) * (1.0 - line_));
        }
    }

private:
    const print::MoireSheet& sheet_;
    int page_;
    Eigen::Vector2d centre_;
    Eigen::Matrix2d to_page_;
    double line_;
};

}  // namespace

Eigen::Vector2d measuring_centre(const print::MoireSheet& sheet, MeasuringBands which) {
    Eigen::Vector2d low = Eigen::Vector2d::Constant(HUGE_VAL), high = -low;
    for (const print::MoireBand& band : sheet.measuring)
        if (which == MeasuringBands::Both || band.along_x == (which == MeasuringBands::X)) {
            low = low.cwiseMin(Eigen::Vector2d(band.left, band.top));
            high = high.cwiseMax(Eigen::Vector2d(band.left + band.width, band.top + band.height));
        }
    RFD_CHECK(low.x() <= high.x());
    return 0.5 * (low + high);
}

Eigen::Matrix2d array_to_page(const ArrayMounting& mounting) {
    const double angle = degrees_to_radians(mounting.rotation_deg);
    Eigen::Matrix2d rotation;
    rotation << std::cos(angle), -std::sin(angle), std::sin(angle), std::cos(angle);
    return Eigen::Vector2d(1.0, -1.0).asDiagonal() * rotation *
           Eigen::Vector2d(1.0 + mounting.pitch_error_x, 1.0 + mounting.pitch_error_y).asDiagonal();
}

Image simulated_moire_photo(const optics::Design& design, const print::MoireSheet& sheet,
                            const print::PrinterProfile& printer, const MoireScene& scene, const Camera& camera,
                            int page) {
    RFD_CHECK(page >= 0 && page < sheet.pages && !camera.pose.from_back && scene.light.z() > 0.0);
    const optics::DisplaySimulator simulator(design);  // InputError unless Design I or II
    const ArrayMounting& mounting = scene.mounting;

    // What the diffuser shows: every lenslet's light through the sheet's lines.
    const SheetUnderArray sheet_under_array(sheet, page, mounting, printer.transmittance(1.0));
    optics::SimulationOptions options;
    options.model = optics::Model::Exact;
    options.rays_per_side = scene.rays_per_side;
    options.pixels_per_pitch = 16.0;
    const optics::DiffuserImage diffuser =
        simulator.simulate(sheet_under_array, {{scene.light.normalized(), {1.0, 1.0, 1.0}, print::kSunRadius}}, options);
    const double diffuser_transmittance = optics::DiffuserScatter{}.transmittance;

    // The page as the camera sees it: the sheet against the light, and over it the diffuser,
    // drawn where the camera's rays through it meet the page (it lies `height` nearer).
    Image seen = print::moire_page_codes(sheet, design, printer, page, kPagePixelsPerMm);
    for (float& value : seen.plane(0)) value = static_cast<float>(printer.transmittance(1.0 - value));
    const double height = design.diffuser_plane()->z - design.pattern_plane().z;
    const Eigen::Vector3d eye = camera_centre(camera.pose);
    const double kappa = -eye.z() / (-eye.z() - height);  // page offset from the eye's foot per diffuser offset
    const Eigen::Vector2d foot = eye.head<2>();
    const Eigen::Matrix2d to_array = array_to_page(mounting).inverse();
    for (int y = 0; y < seen.height(); ++y)
        for (int x = 0; x < seen.width(); ++x) {
            const Eigen::Vector2d on_page((x + 0.5) / kPagePixelsPerMm, (y + 0.5) / kPagePixelsPerMm);
            const Eigen::Vector2d on_diffuser = foot + (on_page - foot) / kappa;
            const double value = diffuser_at(diffuser, to_array * (on_diffuser - mounting.centre));
            if (std::isfinite(value)) seen.at(x, y, 0) = static_cast<float>(diffuser_transmittance * value);
        }
    return photograph(seen, kPagePixelsPerMm, camera);
}

}  // namespace rfd::calibrate
