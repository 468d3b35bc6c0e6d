#include "optics/model.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "core/error.hpp"
#include "optics/analysis.hpp"
#include "optics/diffraction.hpp"

namespace rfd::optics {

std::string_view to_string(Model model) { return name_of(kModelNames, model); }

ResolvedModel resolve(ModelChoice choice, const DesignOptics& optics, const Eigen::Vector2d& dot_mm,
                      double tolerance_dots) {
    RFD_CHECK(dot_mm.x() > 0.0 && dot_mm.y() > 0.0 && tolerance_dots >= 0.0);
    ResolvedModel out;
    out.choice = choice;
    const DesignKind kind = optics.design().kind;
    if (kind == DesignKind::I || kind == DesignKind::II) {
        // Where the direction the paraxial map assigns to each probed offset really lands.
        const CellIndex centre = optics.centre_cell();
        double error = 0.0;
        for (const Eigen::Vector2d& offset : probe_offsets(optics.lattice())) {
            const Eigen::Vector2d slopes = offset / optics.paraxial_b();
            const Eigen::Vector3d d = Eigen::Vector3d(slopes.x(), slopes.y(), 1.0).normalized();
            const DesignOptics::Landing landing = optics.land(d, centre, Model::Exact);
            if (landing.status != RayStatus::Ok) continue;
            const Eigen::Vector2d miss = landing.offset - offset;
            error = std::max({error, std::abs(miss.x()) / dot_mm.x(), std::abs(miss.y()) / dot_mm.y()});
        }
        out.paraxial_error_dots = error;
    }
    if (choice == ModelChoice::Auto || choice == ModelChoice::Diffraction) {
        const Psf psf = pattern_psf(optics, kDiffractionWavelengthsMm[2]);
        out.diffraction_lobe_dots = std::max(psf.lobe_radius_x / dot_mm.x(), psf.lobe_radius_y / dot_mm.y());
        out.diffraction = *out.diffraction_lobe_dots > tolerance_dots;
    }
    char text[200];
    switch (choice) {
        case ModelChoice::Paraxial: out.model = Model::Paraxial; out.reason = "as asked"; break;
        case ModelChoice::Exact: out.model = Model::Exact; out.reason = "as asked"; break;
        case ModelChoice::Diffraction:
            out.model = Model::Exact;
            out.diffraction = true;
            out.reason = "as asked: exact rays, the pattern seen through the lenslets' diffraction";
            break;
        case ModelChoice::Auto:
            if (!out.paraxial_error_dots) {
                out.model = Model::Exact;
                out.reason = "auto: exact for Designs III and IV";
            } else {
                out.model = *out.paraxial_error_dots <= tolerance_dots ? Model::Paraxial : Model::Exact;
                std::snprintf(text, sizeof text, "auto: paraxial error %.2f dots %s the tolerance of %g",
                              *out.paraxial_error_dots, out.model == Model::Paraxial ? "within" : "beyond",
                              tolerance_dots);
                out.reason = text;
            }
            if (out.diffraction) {
                std::snprintf(text, sizeof text, "; diffraction: central lobe %.2f dots, beyond the tolerance: the "
                              "pattern is seen through it", *out.diffraction_lobe_dots);
                out.reason += text;
            }
            break;
    }
    return out;
}

}  // namespace rfd::optics
