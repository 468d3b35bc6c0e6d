#include "calibrate/marker_tiles.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <utility>

#include <Eigen/Dense>

#include "calibrate/mounting_fit.hpp"
#include "calibrate/sheet_finder.hpp"
#include "core/error.hpp"
#include "core/parallel.hpp"
#include "optics/display.hpp"
#include "print/moire.hpp"

namespace rfd::calibrate {
namespace {

constexpr int kTileRaysPerSide = 40;      // over the lenslet, per direction of the sun's disc
constexpr int kBinSamplesPerSide = 3;     // photo samples per bin and side
constexpr double kMarkerSearchStepMm = 0.02;
constexpr int kTiles = 4;
constexpr std::array<double, 5> kModelBlurs{0.0, 0.5, 1.0, 1.5, 2.0};  // Gaussian sigmas tried, in bins

// Blurs a grid of columns x rows values by a Gaussian of `sigma` cells (zero beyond it).
void gaussian_blur_grid(std::vector<double>& grid, int columns, int rows, double sigma) {
    const int reach = static_cast<int>(std::ceil(3.0 * sigma));
    std::vector<double> kernel(static_cast<std::size_t>(2 * reach + 1));
    for (int t = -reach; t <= reach; ++t) kernel[static_cast<std::size_t>(t + reach)] = std::exp(-0.5 * t * t / (sigma * sigma));
    std::vector<double> out(grid.size());
    for (int pass = 0; pass < 2; ++pass) {
        const int dx = pass == 0 ? 1 : 0, dy = 1 - dx;
        for (int j = 0; j < rows; ++j)
            for (int i = 0; i < columns; ++i) {
                double sum = 0.0, weight = 0.0;
                for (int t = -reach; t <= reach; ++t) {
                    const int x = i + t * dx, y = j + t * dy;
                    const double w = kernel[static_cast<std::size_t>(t + reach)];
                    weight += w;
                    if (x >= 0 && y >= 0 && x < columns && y < rows) sum += w * grid[static_cast<std::size_t>(y * columns + x)];
                }
                out[static_cast<std::size_t>(j * columns + i)] = sum / weight;
            }
        grid.swap(out);
    }
}

}  // namespace

MarkerTiles::MarkerTiles(const optics::Design& design) {
    RFD_CHECK(design.kind == optics::DesignKind::II);
    const optics::DisplaySimulator simulator(design);
    const optics::Lattice& lattice = simulator.optics().lattice();
    const int nx = lattice.count_x(), ny = lattice.count_y();
    const optics::CellIndex corner_cells[] = {{0, 0}, {nx - 1, 0}, {0, ny - 1}, {nx - 1, ny - 1}};
    for (const optics::CellIndex cell : corner_cells) corners_.push_back(lattice.center(cell));

    optics::SimulationOptions options;
    options.model = optics::Model::Exact;
    options.rays_per_side = kTileRaysPerSide;
    options.max_rays_per_lenslet = std::size_t{1} << 20;
    const optics::RepeatedRays rays =
        simulator.trace_lenslet({{Eigen::Vector3d::UnitZ(), {1.0, 1.0, 1.0}, print::kSunRadius}}, options);
    // Bins over the box the lenslet's light lands in.
    const Eigen::Vector2d low = rays.reach_min, high = rays.reach_max;
    const int columns = static_cast<int>(std::ceil((high.x() - low.x()) / kMarkerBinMm));
    const int rows = static_cast<int>(std::ceil((high.y() - low.y()) / kMarkerBinMm));
    const Eigen::Vector2d origin = 0.5 * (low + high) - 0.5 * kMarkerBinMm * Eigen::Vector2d(columns, rows);
    columns_ = columns;
    const int cells = columns * rows;
    const auto bin_centre = [&](int index) {
        return Eigen::Vector2d(origin + kMarkerBinMm * Eigen::Vector2d(index % columns + 0.5, index / columns + 0.5));
    };
    // A bin is a corner tile's own where no neighbour's direct light lands (its outer sides,
    // toward the holder, where its outer aperture zones show the most of the marker).
    const double margin = 0.5 * kMarkerBinMm;
    for (const optics::CellIndex cell : corner_cells) {
        std::vector<TileBin> tile(static_cast<std::size_t>(cells));
        std::vector<int> own(static_cast<std::size_t>(cells), 1);
        for (int index = 0; index < cells; ++index)
            for (int dj = -1; dj <= 1; ++dj)
                for (int di = -1; di <= 1; ++di) {
                    const optics::CellIndex next{cell.i + di, cell.j + dj};
                    if ((di == 0 && dj == 0) || !lattice.contains(next)) continue;
                    const Eigen::Vector2d u = lattice.center(cell) + bin_centre(index) - lattice.center(next);
                    if ((u.array() >= low.array() - margin).all() && (u.array() <= high.array() + margin).all())
                        own[static_cast<std::size_t>(index)] = 0;
                }
        // Every ray landing in an own bin, of this lenslet or a neighbour (some cross from one
        // lenslet into the next in the corrective pair), that every lenslet it passes exists for.
        for (int dj = -1; dj <= 1; ++dj)
            for (int di = -1; di <= 1; ++di) {
                const optics::CellIndex source{cell.i + di, cell.j + dj};
                if (!lattice.contains(source)) continue;
                const Eigen::Vector2d from = lattice.center(source) - lattice.center(cell);
                for (const optics::LensletRay& ray : rays.rays) {
                    if (!(ray.reaching > 0.0)) continue;
                    const Eigen::Vector2d at = (from + ray.on_diffuser - origin) / kMarkerBinMm;
                    const int i = static_cast<int>(std::floor(at.x())), j = static_cast<int>(std::floor(at.y()));
                    if (i < 0 || j < 0 || i >= columns || j >= rows || !own[static_cast<std::size_t>(j * columns + i)]) continue;
                    bool exists = true;
                    for (std::size_t m = ray.first_neighbour; m < ray.first_neighbour + ray.neighbours; ++m)
                        exists = exists && lattice.contains(lattice.cell_at(lattice.center(source) + rays.neighbour_offsets[m]));
                    if (!exists) continue;
                    TileBin& bin = tile[static_cast<std::size_t>(j * columns + i)];
                    bin.points.push_back(from + ray.on_pattern);
                    bin.weights.push_back(ray.reaching);
                }
            }
        std::vector<TileBin> kept;
        for (int index = 0; index < cells; ++index)
            if (own[static_cast<std::size_t>(index)]) {
                tile[static_cast<std::size_t>(index)].grid = index;
                tile[static_cast<std::size_t>(index)].centre = bin_centre(index);
                kept.push_back(std::move(tile[static_cast<std::size_t>(index)]));
            }
        RFD_CHECK(!kept.empty());
        tiles_.push_back(std::move(kept));
    }
    rows_ = rows;
}

std::optional<MarkerTileFit> MarkerTiles::read(const Image& luminance, const Eigen::Matrix3d& array_to_photo,
                                              const PatternMap& map) const {
    // The photograph's mean over each bin of each tile.
    std::array<std::vector<double>, kTiles> value;
    MarkerTileFit fit;
    std::array<double, kTiles> mean{}, spread{};
    for (std::size_t k = 0; k < kTiles; ++k) {
        for (const TileBin& bin : tiles_[k]) {
            double sum = 0.0;
            for (int sy = 0; sy < kBinSamplesPerSide; ++sy)
                for (int sx = 0; sx < kBinSamplesPerSide; ++sx) {
                    const Eigen::Vector2d offset((sx + 0.5) / kBinSamplesPerSide - 0.5, (sy + 0.5) / kBinSamplesPerSide - 0.5);
                    sum += photo_at_page(luminance, array_to_photo, corners_[k] + bin.centre + kMarkerBinMm * offset);
                }
            if (!std::isfinite(sum)) return std::nullopt;
            value[k].push_back(sum / (kBinSamplesPerSide * kBinSamplesPerSide));
        }
        const auto n = static_cast<double>(value[k].size());
        for (const double v : value[k]) mean[k] += v / n;
        for (const double v : value[k]) spread[k] += (v - mean[k]) * (v - mean[k]);
        fit.contrast += std::sqrt(spread[k] / n) / std::max(mean[k], 1e-9) / kTiles;
        fit.bins += value[k].size();
    }
    if (!(fit.contrast >= kMinMarkerContrast)) return std::nullopt;

    // The model over tiles `use`: each bin's mean pattern through the mounting, then each
    // tile's gain and offset by least squares; the residuals, tile after tile.
    double blur = 0.0;  // of the model, in bins: the photograph's own (lens, diffuser, its pixels)
    const auto residuals = [&](const Eigen::Vector4d& p, const std::vector<std::size_t>& use,
                               std::vector<double>* fitted = nullptr) {
        std::size_t total = 0;
        for (const std::size_t k : use) total += value[k].size();
        Eigen::VectorXd r(static_cast<Eigen::Index>(total));
        Eigen::Index row = 0;
        std::vector<double> light(static_cast<std::size_t>(columns_ * rows_));
        for (const std::size_t k : use) {
            std::fill(light.begin(), light.end(), 0.0);
            for (const TileBin& bin : tiles_[k]) {
                double sum = 0.0;
                for (std::size_t ray = 0; ray < bin.points.size(); ++ray)
                    sum += bin.weights[ray] * map.at(pattern_point(p, corners_[k] + bin.points[ray]));
                light[static_cast<std::size_t>(bin.grid)] = sum;
            }
            if (blur > 0.0) gaussian_blur_grid(light, columns_, rows_, blur);
            const auto n = static_cast<Eigen::Index>(value[k].size());
            Eigen::MatrixXd a(n, 2);
            Eigen::VectorXd b = Eigen::Map<const Eigen::VectorXd>(value[k].data(), n);
            for (Eigen::Index j = 0; j < n; ++j) {
                a(j, 0) = light[static_cast<std::size_t>(tiles_[k][static_cast<std::size_t>(j)].grid)];
                a(j, 1) = 1.0;
            }
            const Eigen::Vector2d x = (a.transpose() * a).ldlt().solve(a.transpose() * b);
            const Eigen::VectorXd model = a * x;
            r.segment(row, n) = b - model;
            row += n;
            if (fitted) fitted->insert(fitted->end(), model.data(), model.data() + model.size());
        }
        return r;
    };
    const auto spread_of = [&](const std::vector<std::size_t>& use) {
        double s = 0.0;
        for (const std::size_t k : use) s += spread[k];
        return s;
    };
    const auto correlation_of = [&](const Eigen::VectorXd& r, const std::vector<std::size_t>& use) {
        const double s = spread_of(use);
        return s > 0 ? std::sqrt(std::max(0.0, 1.0 - r.squaredNorm() / s)) : 0.0;
    };
    // Gauss-Newton over tiles `use`, each with its gain and offset.
    const auto fit_tiles = [&](const Eigen::Vector4d& start, const std::vector<std::size_t>& use) {
        return fit_mounting([&](const Eigen::Vector4d& p) { return residuals(p, use); }, start,
                            2.0 * static_cast<double>(use.size()));
    };

    // The spot's place on the markers: the best correlation over the search square, no turn.
    const std::vector<std::size_t> all{0, 1, 2, 3};
    const int steps = static_cast<int>(std::round(kMarkerSearchMm / kMarkerSearchStepMm));
    const int side = 2 * steps + 1;
    std::vector<double> score(static_cast<std::size_t>(side * side));
    const auto shift_of = [&](std::size_t s) {
        return Eigen::Vector2d(kMarkerSearchStepMm * (static_cast<int>(s) % side - steps),
                               kMarkerSearchStepMm * (static_cast<int>(s) / side - steps));
    };
    parallel_for_chunks(score.size(), 8, [&](std::size_t begin, std::size_t end) {
        for (std::size_t s = begin; s < end; ++s) {
            Eigen::Vector4d p = Eigen::Vector4d::Zero();
            p.head<2>() = shift_of(s);
            score[s] = correlation_of(residuals(p, all), all);
        }
    });
    Eigen::Vector4d start = Eigen::Vector4d::Zero();
    start.head<2>() = shift_of(static_cast<std::size_t>(std::max_element(score.begin(), score.end()) - score.begin()));
    // The photograph's blur: the one of kModelBlurs (bins) that fits best there.
    double best_blur = 0.0, best_correlation = -1.0;
    for (const double b : kModelBlurs) {
        blur = b;
        const double c = correlation_of(residuals(start, all), all);
        if (c > best_correlation) best_correlation = c, best_blur = b;
    }
    blur = best_blur;
    const MountingFit all_tiles = fit_tiles(start, all);
    fit.parameters = all_tiles.parameters;
    fit.covariance = all_tiles.covariance;
    std::vector<double> fitted;
    const Eigen::VectorXd r = residuals(fit.parameters, all, &fitted);
    fit.correlation = correlation_of(r, all);
    double mean_value = 0.0;
    for (const double m : mean) mean_value += m / kTiles;
    fit.rms = std::sqrt(r.squaredNorm() / static_cast<double>(r.size())) / mean_value;

    // The jackknife over the tiles, each left out in turn.
    std::array<Eigen::Vector4d, kTiles> estimates;
    for (std::size_t left = 0; left < kTiles; ++left) {
        std::vector<std::size_t> use;
        for (std::size_t k = 0; k < kTiles; ++k)
            if (k != left) use.push_back(k);
        estimates[left] = fit_tiles(fit.parameters, use).parameters;
    }
    widen_by_jackknife(fit.covariance, estimates);
    return fit;
}

}  // namespace rfd::calibrate
