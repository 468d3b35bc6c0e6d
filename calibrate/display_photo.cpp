#include "calibrate/display_photo.hpp"

#include <algorithm>
#include <cmath>

#include "calibrate/sheet_finder.hpp"
#include "core/error.hpp"

namespace rfd::calibrate {
namespace {

constexpr double kPlanePixelsPerMm = 10.0;  // finer than a photograph's pixel on the display
constexpr int kMacroPixelRays = 64;          // per side of a Design II lenslet

// The array's bounding box in its frame: its outermost cells' corners.
std::pair<Eigen::Vector2d, Eigen::Vector2d> array_box(const optics::Lattice& lattice) {
    Eigen::Vector2d low = Eigen::Vector2d::Constant(HUGE_VAL), high = -low;
    const std::vector<Eigen::Vector2d> corners = lattice.cell_corners();
    for (const int j : {0, 1, lattice.count_y() - 2, lattice.count_y() - 1})
        for (const int i : {0, lattice.count_x() - 1}) {
            if (j < 0 || j >= lattice.count_y()) continue;
            for (const Eigen::Vector2d& corner : corners) {
                low = low.cwiseMin(lattice.center({i, j}) + corner);
                high = high.cwiseMax(lattice.center({i, j}) + corner);
            }
        }
    return {low, high};
}

}  // namespace

double diffuser_at(const optics::DiffuserImage& diffuser, const Eigen::Vector2d& a) {
    const double u = (a.x() - diffuser.first_pixel.x()) / diffuser.pixel_mm;
    const double v = (diffuser.first_pixel.y() - a.y()) / diffuser.pixel_mm;
    double sum = 0.0;
    for (int c = 0; c < diffuser.image.channels(); ++c) sum += sample_bilinear(diffuser.image, u, v, c);
    return sum / diffuser.image.channels();
}

print::Paper display_paper(const optics::Design& design) {
    const auto [low, high] = array_box(optics::DesignOptics(design).lattice());
    const double half_x = std::max(high.x(), -low.x()), half_y = std::max(high.y(), -low.y());
    print::Paper paper;
    paper.name = "display";
    paper.width = 2.0 * (half_x + kHolderMm);
    paper.height = 2.0 * (half_y + kHolderMm);
    paper.margin = 0.0;
    return paper;
}

Eigen::Vector2d display_plane_point(const optics::Design& design, const Eigen::Vector2d& a) {
    const print::Paper paper = display_paper(design);
    return {0.5 * paper.width + a.x(), 0.5 * paper.height - a.y()};
}

Image simulated_display_photo(const optics::Design& design, const optics::Transparency& mounted,
                              const DisplayScene& scene, const Camera& camera) {
    RFD_CHECK(!camera.pose.from_back && scene.light.z() > 0.0);
    const optics::DisplaySimulator simulator(design);  // InputError unless Design I or II
    optics::SimulationOptions options;
    options.model = optics::Model::Exact;
    // Design II's corrective pair spreads each lenslet's light over the image of its whole
    // aperture, a cell 16 diffuser pixels across and more: with few rays it would be a grid
    // of dots, not the even macro-pixel the display shows.
    options.rays_per_side = design.kind == optics::DesignKind::II ? std::max(scene.rays_per_side, kMacroPixelRays)
                                                                  : scene.rays_per_side;
    options.pixels_per_pitch = 16.0;
    const optics::DiffuserImage diffuser = simulator.simulate(
        mounted, {{scene.light.normalized(), {1.0, 1.0, 1.0}, scene.light_radius_rad}}, options);
    const double transmittance = optics::DiffuserScatter{}.transmittance;

    const print::Paper paper = display_paper(design);
    const int width = static_cast<int>(std::ceil(paper.width * kPlanePixelsPerMm));
    const int height = static_cast<int>(std::ceil(paper.height * kPlanePixelsPerMm));
    Image seen(width, height, 1);
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x) {
            // Array point of this pixel, then the diffuser's pixel there.
            const Eigen::Vector2d a((x + 0.5) / kPlanePixelsPerMm - 0.5 * paper.width,
                                    0.5 * paper.height - (y + 0.5) / kPlanePixelsPerMm);
            const double value = diffuser_at(diffuser, a);
            seen.at(x, y, 0) =
                static_cast<float>(std::isfinite(value) ? std::max(scene.holder, transmittance * value) : scene.holder);
        }
    return photograph(seen, kPlanePixelsPerMm, camera);
}

}  // namespace rfd::calibrate
