#include "calibrate/registration.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <numeric>

#include <Eigen/Dense>
#include <Eigen/Geometry>

#include "calibrate/camera.hpp"
#include "calibrate/marker_tiles.hpp"
#include "calibrate/mounting_fit.hpp"
#include "calibrate/sheet_finder.hpp"
#include "core/error.hpp"
#include "core/parallel.hpp"
#include "core/text.hpp"
#include "core/units.hpp"
#include "optics/display.hpp"
#include "relight/vision.hpp"

namespace rfd::calibrate {
namespace {

constexpr int kPatternSamples = 2;         // pattern samples per grid step along each axis
constexpr double kReadRadius = 1.0 / 6.0;  // radius read of each lenslet image, of its pitch
constexpr double kCentroidRadius = 0.5;   // of the pitch: the window a lenslet image's centroid is taken over
// The homography's refinement: lenslets within these fractions of the half-width from the
// middle (a square), one centroid pass each.
constexpr std::array<double, 8> kGrowth{0.3, 0.4, 0.55, 0.7, 0.85, 1.0, 1.0, 1.0};
constexpr double kLightRadius = 0.4;      // of the pitch: a lenslet's light on the diffuser, about
constexpr int kTileRays = 32;             // per side of a lenslet, tracing Design II's tile
constexpr double kSearchStepMm = 0.02;    // the shift's first search
constexpr int kGainTerms = 6;            // gain: 1, u, v, u^2, uv, v^2
constexpr int kSmallArrayGainTerms = 3;  // 1, u, v: a small array's light falls off little across it
constexpr std::size_t kSmallArray = 100; // lenslets: fewer cannot spare readings for a curved falloff
constexpr int kGroups = 8;
constexpr double kTurnMargin = 0.05;       // the best quarter turn's correlation over the next's
constexpr double kDistinctShiftMm = 0.06;   // shifts this far apart are different readings
constexpr std::size_t kMinReadLenslets = 16;  // readings a fit needs (shift, turn, scale, light falloff)
constexpr double kAmbiguousChi2 = 25.0;     // a second shift fitting within 5 noise sigmas
// A lit piece of the display: at least this share of the photo and of its largest piece.
constexpr double kMinPieceShare = 0.001;
constexpr double kMinPieceOfLargest = 0.02;
constexpr double kTilePieceFraction = 0.1;  // of those, for Design II's tiles
constexpr std::size_t kMinRefineLenslets = 9;  // a centroid pass needs (a homography from them)
constexpr double kRunTurnDeg = 4.0;         // a straight run of the lit outline's hull
constexpr double kParallelSine = 1e-6;       // lines closer to parallel do not meet
constexpr double kHullSlackPixels = 2.0;    // how far the hull may poke out of its enclosing quadrilateral
constexpr double kEdgeReachMm = 1.2;       // Design II's outer edges: profiles this far either side
constexpr double kFirstEdgeReach = 0.9;    // around the markers, at first: of the pitch
constexpr double kEdgeStepMm = 0.2;        // between profiles along a side
constexpr std::size_t kMinEdgePoints = 10;  // crossings a side's line needs
// A side placed a row in shows the corner tiles' clear quadrants beyond it: photo samples over
// a corner tile's length and kBeyondStart-kBeyondDepth pitches out (the first placement is
// squeezed by up to a row), more than kLitBeyondShare of them above the outline's threshold at
// both ends (the demo's letters hand-held: 3.9 and 6.7 %; beyond the true edge, the holder: none).
constexpr int kBeyondSamples = 24;
constexpr double kBeyondStart = 0.1;
constexpr double kBeyondDepth = 1.3;
constexpr double kLitBeyondShare = 0.01;
// A side moved out a row to its corner tiles is that near (of the pitch), and read all along
// every kCornerTileStepMm: only the corner tiles' clear quadrants show it.
constexpr double kCornerTileReach = 0.5;
constexpr double kCornerTileStepMm = 0.05;
constexpr double kEdgeOutlierPixels = 0.5;  // the least distance from the line left out

// The array's lenslets and its outline (cell corners of the outermost lenslets).
struct ArrayShape {
    optics::Lattice lattice;
    std::vector<Eigen::Vector2d> centres;
    std::vector<optics::CellIndex> cells;
    Eigen::Vector2d low, high;  // bounding box of the cells
    // The corners of the largest quadrilateral on the lit footprint, as the outline's: top
    // left, top right, bottom right, bottom left when upright.
    std::array<Eigen::Vector2d, 4> corners;
    // Whether each lenslet's light is an even tile over its cell and beyond (Design II: the
    // corrective pair images the lenslet onto the diffuser), not a spot that moves with the
    // light (Design I): the array's outer edges then place the lenslets (fit_outer_edges).
    bool tiles = false;
};

std::optional<std::array<Eigen::Vector2d, 4>> quadrilateral_corners(std::vector<Eigen::Vector2d> points);

ArrayShape array_shape(const optics::Design& design) {
    ArrayShape shape{optics::DesignOptics(design).lattice(), {}, {}, {}, {}};
    const optics::Lattice& lattice = shape.lattice;
    shape.low = Eigen::Vector2d::Constant(HUGE_VAL);
    shape.high = -shape.low;
    const std::vector<Eigen::Vector2d> corners = lattice.cell_corners();
    for (int j = 0; j < lattice.count_y(); ++j)
        for (int i = 0; i < lattice.count_x(); ++i) {
            const Eigen::Vector2d c = lattice.center({i, j});
            shape.centres.push_back(c);
            shape.cells.push_back({i, j});
            for (const Eigen::Vector2d& corner : corners) {
                shape.low = shape.low.cwiseMin(c + corner);
                shape.high = shape.high.cwiseMax(c + corner);
            }
        }
    // The footprint on the screen's axes (y down), its corners back on the array's: every
    // lenslet's light a disc of kLightRadius pitches (Design I), or the box its rays land in
    // on the diffuser, traced with the light on the axis (Design II's tiles).
    std::vector<Eigen::Vector2d> footprint;
    shape.tiles = design.kind == optics::DesignKind::II;
    std::vector<Eigen::Vector2d> light;
    if (shape.tiles) {
        optics::SimulationOptions options;
        options.model = optics::Model::Exact;
        options.rays_per_side = kTileRays;
        const optics::RepeatedRays rays = optics::DisplaySimulator(design).trace_lenslet({optics::DisplayLight{}}, options);
        for (const Eigen::Vector2d& corner : {rays.reach_min, rays.reach_max, Eigen::Vector2d(rays.reach_min.x(), rays.reach_max.y()),
                                              Eigen::Vector2d(rays.reach_max.x(), rays.reach_min.y())})
            light.push_back(corner);
    } else {
        const double radius = kLightRadius * lattice.pitch_x();
        for (int k = 0; k < 16; ++k) light.emplace_back(radius * std::cos(k * kPi / 8), radius * std::sin(k * kPi / 8));
    }
    for (const Eigen::Vector2d& c : shape.centres)
        for (const Eigen::Vector2d& d : light) footprint.emplace_back(c.x() + d.x(), -(c.y() + d.y()));
    const auto quadrilateral = quadrilateral_corners(footprint);
    RFD_CHECK(quadrilateral.has_value());
    for (std::size_t k = 0; k < 4; ++k) shape.corners[k] = Eigen::Vector2d((*quadrilateral)[k].x(), -(*quadrilateral)[k].y());
    return shape;
}

// Plane mm per photo pixel at a plane point (the geometric mean over the two axes).
double mm_per_pixel_at(const Eigen::Matrix3d& plane_to_photo, const Eigen::Vector2d& point) {
    const Eigen::Vector2d at = apply(plane_to_photo, point);
    const Eigen::Vector2d ax = apply(plane_to_photo, point + Eigen::Vector2d::UnitX()) - at;
    const Eigen::Vector2d ay = apply(plane_to_photo, point + Eigen::Vector2d::UnitY()) - at;
    return 1.0 / std::sqrt(std::abs(ax.x() * ay.y() - ax.y() * ay.x()));
}

// The homography of weighted least squares taking `from` to `to`: the normalised direct
// linear transform, reweighted twice by the inverse square of each point's projective depth so
// that its algebraic residuals weigh as the pixels' (under perspective they differ).
Eigen::Matrix3d fit_homography(const std::vector<Eigen::Vector2d>& from, const std::vector<Eigen::Vector2d>& to,
                               const std::vector<double>& weight) {
    const auto normaliser = [&](const std::vector<Eigen::Vector2d>& points) {
        Eigen::Vector2d mean = Eigen::Vector2d::Zero();
        double total = 0.0, spread = 0.0;
        for (std::size_t k = 0; k < points.size(); ++k) mean += weight[k] * points[k], total += weight[k];
        mean /= total;
        for (std::size_t k = 0; k < points.size(); ++k) spread += weight[k] * (points[k] - mean).norm();
        const double scale = std::sqrt(2.0) * total / spread;
        Eigen::Matrix3d n;
        n << scale, 0, -scale * mean.x(), 0, scale, -scale * mean.y(), 0, 0, 1;
        return n;
    };
    const Eigen::Matrix3d nf = normaliser(from), nt = normaliser(to);
    std::vector<double> depth(from.size(), 1.0);
    Eigen::Matrix3d m = Eigen::Matrix3d::Identity();
    for (int pass = 0; pass < 3; ++pass) {
        Eigen::Matrix<double, 9, 9> normal = Eigen::Matrix<double, 9, 9>::Zero();
        for (std::size_t k = 0; k < from.size(); ++k) {
            const Eigen::Vector3d p = nf * from[k].homogeneous();
            const Eigen::Vector3d q = nt * to[k].homogeneous();
            Eigen::Matrix<double, 2, 9> rows;
            rows << p.transpose(), 0, 0, 0, -q.x() * p.transpose(), 0, 0, 0, p.transpose(), -q.y() * p.transpose();
            normal += weight[k] / (depth[k] * depth[k]) * rows.transpose() * rows;
        }
        const Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 9, 9>> solver(normal);
        const Eigen::Matrix<double, 9, 1> h = solver.eigenvectors().col(0);
        m << h(0), h(1), h(2), h(3), h(4), h(5), h(6), h(7), h(8);
        double mean_depth = 0.0;
        for (std::size_t k = 0; k < from.size(); ++k)
            depth[k] = std::abs(m.row(2).dot(nf * from[k].homogeneous())), mean_depth += depth[k] / static_cast<double>(from.size());
        for (double& d : depth) d /= mean_depth;
    }
    return nt.inverse() * m * nf;
}

// The lit display: every sizeable region brighter than Otsu's threshold of the smoothed photo,
// and the four corners of their convex hull (the largest quadrilateral on it, or for Design
// II's tiles where its longest straight runs meet), in clockwise order on the screen starting
// from the one nearest the photo's +x axis direction.
struct Outline {
    std::array<Eigen::Vector2d, 4> corners;
    double threshold = 0.0;  // Otsu's, between the lit display and the rest
    double dark = 0.0;  // the mean of the darker class: the holder
    double pixels = 0.0;
};

double cross(const Eigen::Vector2d& o, const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
    return (a - o).x() * (b - o).y() - (a - o).y() * (b - o).x();
}

// Where the line through `a` along `a_direction` meets the one through `b` along
// `b_direction` (Eigen's hyperplanes); nullopt for lines within kParallelSine of parallel.
std::optional<Eigen::Vector2d> meet(const Eigen::Vector2d& a, const Eigen::Vector2d& a_direction, const Eigen::Vector2d& b,
                                    const Eigen::Vector2d& b_direction) {
    using Line = Eigen::Hyperplane<double, 2>;
    const Eigen::Vector2d u = a_direction.normalized(), v = b_direction.normalized();
    if (std::abs(u.x() * v.y() - u.y() * v.x()) < kParallelSine) return std::nullopt;
    return Line::Through(a, a + u).intersection(Line::Through(b, b + v));
}

// The convex hull of `points` (Andrew's monotone chain), clockwise on the screen (y down);
// empty when it has fewer than four corners.
std::vector<Eigen::Vector2d> convex_hull(std::vector<Eigen::Vector2d> points) {
    std::sort(points.begin(), points.end(),
              [](const Eigen::Vector2d& a, const Eigen::Vector2d& b) { return a.x() < b.x() || (a.x() == b.x() && a.y() < b.y()); });
    std::vector<Eigen::Vector2d> hull(2 * points.size() + 1);
    std::size_t k = 0;
    for (std::size_t i = 0; i < points.size(); ++i) {
        while (k >= 2 && cross(hull[k - 2], hull[k - 1], points[i]) <= 0) --k;
        hull[k++] = points[i];
    }
    for (std::size_t i = points.size() - 1, lower = k + 1; i > 0; --i) {
        while (k >= lower && cross(hull[k - 2], hull[k - 1], points[i - 1]) <= 0) --k;
        hull[k++] = points[i - 1];
    }
    if (k < 5) return {};
    hull.resize(k - 1);
    return hull;
}

// Four corners in clockwise order on the screen (y down) from the one whose direction from
// their middle has the smallest angle (-pi .. pi): for an upright rectangle, top left, top
// right, bottom right, bottom left.
std::array<Eigen::Vector2d, 4> in_screen_order(std::array<Eigen::Vector2d, 4> corners) {
    Eigen::Vector2d middle = Eigen::Vector2d::Zero();
    for (const Eigen::Vector2d& c : corners) middle += 0.25 * c;
    std::sort(corners.begin(), corners.end(), [&](const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
        return std::atan2(a.y() - middle.y(), a.x() - middle.x()) < std::atan2(b.y() - middle.y(), b.x() - middle.x());
    });
    return corners;
}

// The corners of the largest quadrilateral on the convex hull of `points` (from the hull's
// widest pair and the points farthest on either side, each corner moved to the best place
// between its neighbours until none moves), in_screen_order.
std::optional<std::array<Eigen::Vector2d, 4>> quadrilateral_corners(std::vector<Eigen::Vector2d> points) {
    const std::vector<Eigen::Vector2d> hull = convex_hull(std::move(points));
    if (hull.empty()) return std::nullopt;
    const std::size_t n = hull.size();
    std::array<std::size_t, 4> q{};
    double widest = -1.0;
    for (std::size_t i = 0; i < n; ++i)
        for (std::size_t j = i + 1; j < n; ++j)
            if ((hull[i] - hull[j]).squaredNorm() > widest) widest = (hull[i] - hull[j]).squaredNorm(), q[0] = i, q[2] = j;
    const auto farthest = [&](std::size_t from, std::size_t to) {
        std::size_t best = from;
        double best_area = -1.0;
        for (std::size_t i = (from + 1) % n; i != to; i = (i + 1) % n) {
            const double a = std::abs(cross(hull[from], hull[to], hull[i]));
            if (a > best_area) best_area = a, best = i;
        }
        return best;
    };
    q[1] = farthest(q[0], q[2]);
    q[3] = farthest(q[2], q[0]);
    for (int pass = 0; pass < 20; ++pass) {
        bool moved = false;
        for (std::size_t c = 0; c < 4; ++c) {
            const std::size_t best = farthest(q[(c + 3) % 4], q[(c + 1) % 4]);
            if (best != q[c]) q[c] = best, moved = true;
        }
        if (!moved) break;
    }
    std::array<Eigen::Vector2d, 4> corners;
    for (std::size_t c = 0; c < 4; ++c) corners[c] = hull[q[c]];
    return in_screen_order(corners);
}

// The corners where the four longest straight runs of the convex hull of `points` meet (a
// run: consecutive hull edges within kRunTurnDeg of its first), in_screen_order. Where the
// array's corner tiles are partly dark the hull cuts the corners but keeps the sides, so
// this finds the corners the largest quadrilateral on the hull misses. nullopt when the
// runs do not make a convex quadrilateral around the hull.
std::optional<std::array<Eigen::Vector2d, 4>> enclosing_corners(std::vector<Eigen::Vector2d> points) {
    const std::vector<Eigen::Vector2d> hull = convex_hull(std::move(points));
    if (hull.empty()) return std::nullopt;
    const std::size_t n = hull.size();
    // Start at the longest edge, so that no run wraps around the start.
    std::size_t start = 0;
    for (std::size_t i = 0; i < n; ++i)
        if ((hull[(i + 1) % n] - hull[i]).squaredNorm() > (hull[(start + 1) % n] - hull[start]).squaredNorm()) start = i;
    struct Run {
        Eigen::Vector2d from, to;
        std::size_t order;
    };
    std::vector<Run> runs;
    const double tolerance = std::cos(degrees_to_radians(kRunTurnDeg));
    for (std::size_t k = 0; k < n;) {
        const std::size_t first = (start + k) % n;
        const Eigen::Vector2d direction = (hull[(first + 1) % n] - hull[first]).normalized();
        std::size_t last = k + 1;
        while (last < n && (hull[(start + last + 1) % n] - hull[(start + last) % n]).normalized().dot(direction) > tolerance) ++last;
        runs.push_back({hull[first], hull[(start + last) % n], runs.size()});
        k = last;
    }
    if (runs.size() < 4) return std::nullopt;
    std::partial_sort(runs.begin(), runs.begin() + 4, runs.end(),
                      [](const Run& a, const Run& b) { return (a.to - a.from).squaredNorm() > (b.to - b.from).squaredNorm(); });
    runs.resize(4);
    std::sort(runs.begin(), runs.end(), [](const Run& a, const Run& b) { return a.order < b.order; });
    std::array<Eigen::Vector2d, 4> corners;
    for (std::size_t c = 0; c < 4; ++c) {
        const Run& a = runs[c];
        const Run& b = runs[(c + 1) % 4];
        const auto corner = meet(a.from, a.to - a.from, b.from, b.to - b.from);
        if (!corner) return std::nullopt;
        corners[c] = *corner;
    }
    // Around the hull: every hull point on the inner side of every side.
    for (std::size_t c = 0; c < 4; ++c)
        for (const Eigen::Vector2d& h : hull)
            if (cross(corners[c], corners[(c + 1) % 4], h) < -kHullSlackPixels * (corners[(c + 1) % 4] - corners[c]).norm())
                return std::nullopt;
    return in_screen_order(corners);
}

Outline find_outline(const Image& luminance, const std::string& name, bool tiles) {
    const int w = luminance.width(), h = luminance.height();
    const relight::PlaneSize size{w, h};
    std::vector<float> smooth(luminance.plane(0).begin(), luminance.plane(0).end());
    const double sigma = std::max(w, h) / 200.0;
    relight::vision().gaussian_blur(size, smooth, smooth, 0, sigma, sigma, relight::Border::Replicate);
    const double threshold = otsu_threshold(smooth);
    std::vector<std::uint8_t> bright(smooth.size());
    double dark_sum = 0.0, dark_count = 0.0;
    for (std::size_t k = 0; k < smooth.size(); ++k) {
        bright[k] = smooth[k] > threshold;
        if (!bright[k]) dark_sum += smooth[k], dark_count += 1.0;
    }
    std::vector<int> labels(smooth.size());
    const int count = relight::vision().connected_components(size, bright, labels);
    std::vector<double> area(static_cast<std::size_t>(count) + 1, 0.0);
    for (const int label : labels)
        if (label > 0) area[static_cast<std::size_t>(label)] += 1.0;
    const auto largest = static_cast<int>(std::max_element(area.begin(), area.end()) - area.begin());
    // Every lit region of a size a lenslet's light could have: an array whose picture is
    // dark between its clear corner cells (the markers) is lit in several pieces.
    // Design II's corner tiles show their markers near the axis, mostly dark: a small piece of
    // each (the outer corner) is lit.
    const double share = tiles ? kTilePieceFraction : 1.0;
    const double piece =
        share * std::max(kMinPieceShare * w * h, kMinPieceOfLargest * area[static_cast<std::size_t>(largest)]);
    std::vector<std::uint8_t> kept(area.size(), 0);
    Outline outline;
    for (std::size_t label = 1; label < area.size(); ++label)
        if (area[label] >= piece) kept[label] = 1, outline.pixels += area[label];
    outline.dark = dark_count > 0.0 ? dark_sum / dark_count : 0.0;
    outline.threshold = threshold;
    if (largest == 0 || outline.pixels < 0.02 * w * h)
        throw InputError(SourceLocation{name}, "no lit display found: the photograph shows no bright region over 2 % of "
                                               "its area (is the display lit from behind and in view?)");
    // The regions' leftmost and rightmost pixel of every row: their hull is the regions'.
    std::vector<Eigen::Vector2d> points;
    for (int y = 0; y < h; ++y) {
        int first = -1, last = -1;
        for (int x = 0; x < w; ++x)
            if (kept[static_cast<std::size_t>(labels[static_cast<std::size_t>(y) * static_cast<std::size_t>(w) + static_cast<std::size_t>(x)])]) {
                if (first < 0) first = x;
                last = x;
            }
        if (first >= 0) points.emplace_back(first, y), points.emplace_back(last, y);
    }
    // Design II's corner tiles may be partly dark: the sides then place the corners.
    auto quadrilateral = tiles ? enclosing_corners(points) : std::nullopt;
    if (!quadrilateral) quadrilateral = quadrilateral_corners(points);
    if (!quadrilateral) throw InputError(SourceLocation{name}, "the lit region has no corners");
    outline.corners = *quadrilateral;
    return outline;
}

Eigen::Matrix3d translation(const Eigen::Vector2d& offset) {
    Eigen::Matrix3d t = Eigen::Matrix3d::Identity();
    t.topRightCorner<2, 1>() = offset;
    return t;
}

// The lattice's two shortest vectors: along a row, and to the next row.
std::array<Eigen::Vector2d, 2> lattice_vectors(const optics::Lattice& lattice) {
    const Eigen::Vector2d along = lattice.center({1, 0}) - lattice.center({0, 0});
    return {along, lattice.center({0, 1}) - lattice.center({0, 0})};
}

// The sum of the photo's brightness over discs at the array's lenslets moved by `offset`,
// those with |u| <= reach (u: array point over the half-width, from the middle).
double brightness_at(const Image& luminance, const ArrayShape& shape, const Eigen::Matrix3d& array_to_photo,
                     const Eigen::Vector2d& offset, double reach) {
    const Eigen::Vector2d middle = 0.5 * (shape.low + shape.high), half = 0.5 * (shape.high - shape.low);
    const double radius = 0.2 * shape.lattice.pitch_x();
    double sum = 0.0;
    for (const Eigen::Vector2d& c : shape.centres) {
        if ((c - middle).cwiseQuotient(half).cwiseAbs().maxCoeff() > reach) continue;
        const double v = disc_statistics(luminance, array_to_photo, c + offset, radius, 0.5 * radius).first;
        if (std::isfinite(v)) sum += v;
    }
    return sum;
}

// Where the lenslet images lie within a cell, in the array's middle: the offset over one
// cell that puts the lenslets' discs on the brightest places (the images, not the gaps).
// The outline's corners may miss by most of a pitch where the pattern is dark at the edge.
Eigen::Vector2d lattice_phase(const Image& luminance, const ArrayShape& shape, const Eigen::Matrix3d& array_to_photo) {
    const auto [a1, a2] = lattice_vectors(shape.lattice);
    constexpr int kSteps = 10;
    Eigen::Vector2d best = Eigen::Vector2d::Zero();
    double best_sum = -1.0;
    for (int j = 0; j < kSteps; ++j)
        for (int i = 0; i < kSteps; ++i) {
            const Eigen::Vector2d offset = (i - kSteps / 2) / double(kSteps) * a1 + (j - kSteps / 2) / double(kSteps) * a2;
            const double sum = brightness_at(luminance, shape, array_to_photo, offset, 0.3);
            if (sum > best_sum) best_sum = sum, best = offset;
        }
    return best;
}

// The whole-lenslet offset of the labels: the lattice of images is found up to a lattice
// vector, which only the array's edge tells (a pattern shifted by exactly one lenslet reads
// the same inside): of the offsets within two lenslets, the one whose lenslets hold the most
// light (the others put an edge row on the dark holder).
Eigen::Vector2d whole_lenslet_offset(const Image& luminance, const ArrayShape& shape,
                                     const Eigen::Matrix3d& array_to_photo) {
    const auto [a1, a2] = lattice_vectors(shape.lattice);
    Eigen::Vector2d best = Eigen::Vector2d::Zero();
    double best_sum = -1.0;
    for (int j = -2; j <= 2; ++j)
        for (int i = -2; i <= 2; ++i) {
            const Eigen::Vector2d offset = i * a1 + j * a2;
            const double sum = brightness_at(luminance, shape, array_to_photo, offset, 2.0);
            if (sum > best_sum) best_sum = sum, best = offset;
        }
    return best;
}

// Refines the array-to-photo homography from the lenslet images' centroids, growing from the
// array's middle outward: the first homography (from the outline's corners) may be off by
// most of a pitch where the pattern is dark at the array's edge, and a lenslet image then
// pulls toward its neighbour's; the middle's lenslets, where it is best, fix the map that
// places the next ring.
Eigen::Matrix3d refine_homography(const Image& luminance, const ArrayShape& shape, Eigen::Matrix3d array_to_photo,
                                  double dark) {
    const double pitch = shape.lattice.pitch_x();
    const double radius = kCentroidRadius * pitch;
    const int steps = 5;
    const Eigen::Vector2d middle = 0.5 * (shape.low + shape.high), half = 0.5 * (shape.high - shape.low);
    for (const double reach : kGrowth) {
        std::vector<Eigen::Vector2d> from, to;
        std::vector<double> weight;
        for (std::size_t k = 0; k < shape.centres.size(); ++k)
            if ((shape.centres[k] - middle).cwiseQuotient(half).cwiseAbs().maxCoeff() <= reach)
                from.push_back(shape.centres[k]);
        if (from.size() < kMinRefineLenslets) continue;  // too few to place a homography
        to.resize(from.size());
        weight.resize(from.size());
        parallel_for_chunks(from.size(), 256, [&](std::size_t begin, std::size_t end) {
            for (std::size_t k = begin; k < end; ++k) {
                const Eigen::Vector2d& c = from[k];
                Eigen::Vector2d moment = Eigen::Vector2d::Zero();
                double total = 0.0;
                for (int j = -steps; j <= steps; ++j)
                    for (int i = -steps; i <= steps; ++i) {
                        const Eigen::Vector2d d(i * radius / steps, j * radius / steps);
                        if (d.squaredNorm() > radius * radius) continue;
                        const double v = photo_at_page(luminance, array_to_photo, c + d);
                        if (!std::isfinite(v)) continue;
                        const double mass = std::max(0.0, v - dark);
                        moment += mass * d;
                        total += mass;
                    }
                to[k] = apply(array_to_photo, total > 0.0 ? Eigen::Vector2d(c + moment / total) : c);
                weight[k] = total + 1e-12;
            }
        });
        array_to_photo = fit_homography(from, to, weight);
    }
    return array_to_photo;
}

// Design II's tiles: the outline's corners move where a corner tile is partly dark (the
// marker's ring under the light's spot), so the array's four straight outer edges place it
// instead. Across each side, every kEdgeStepMm, the photo's profile from the lit tile to the
// holder gives the edge where it crosses half-way; a line fitted to each side's crossings
// (the farthest left out, twice) and the corners where the lines meet give the homography.
// Sides with fewer than kMinEdgePoints crossings keep the first homography.
std::optional<Eigen::Vector2d> edge_crossing(const Image& luminance, const Eigen::Matrix3d& array_to_photo,
                                             const Eigen::Vector2d& on_side, const Eigen::Vector2d& outward,
                                             double threshold, double reach) {
    constexpr int kSamples = 49;  // across +-reach
    std::array<double, kSamples> profile{};
    for (int k = 0; k < kSamples; ++k) {
        const double d = reach * (2.0 * k / (kSamples - 1) - 1.0);
        profile[static_cast<std::size_t>(k)] = photo_at_page(luminance, array_to_photo, on_side + d * outward);
        if (!std::isfinite(profile[static_cast<std::size_t>(k)])) return std::nullopt;
    }
    const int quarter = kSamples / 5;
    double inside = 0.0, outside = 0.0;
    for (int k = 0; k < quarter; ++k)
        inside += profile[static_cast<std::size_t>(k)] / quarter, outside += profile[static_cast<std::size_t>(kSamples - 1 - k)] / quarter;
    // A long profile may begin on a dark tile inside: the tile's light is its brightest fifth.
    if (reach > kEdgeReachMm) {
        std::array<double, kSamples> sorted = profile;
        std::sort(sorted.begin(), sorted.end());
        inside = 0.0;
        for (int k = 0; k < quarter; ++k) inside += sorted[static_cast<std::size_t>(kSamples - 1 - k)] / quarter;
    }
    if (!(inside > threshold && outside < threshold)) return std::nullopt;
    const double half = 0.5 * (inside + outside);
    // The last crossing from above half to below it, walking outward.
    std::optional<double> at;
    for (int k = 0; k + 1 < kSamples; ++k) {
        const double a = profile[static_cast<std::size_t>(k)], b = profile[static_cast<std::size_t>(k + 1)];
        if (a >= half && b < half) {
            const double d = reach * (2.0 * (k + (a - half) / (a - b)) / (kSamples - 1) - 1.0);
            at = d;
        }
    }
    if (!at) return std::nullopt;
    return apply(array_to_photo, on_side + *at * outward);
}

// A line through `points` (total least squares), refitted twice without those farther than
// three robust sigmas: a point and a unit direction. nullopt when too few are left.
std::optional<std::pair<Eigen::Vector2d, Eigen::Vector2d>> robust_line(std::vector<Eigen::Vector2d> points) {
    for (int pass = 0; pass < 3; ++pass) {
        if (points.size() < kMinEdgePoints) return std::nullopt;
        Eigen::Vector2d mean = Eigen::Vector2d::Zero();
        for (const Eigen::Vector2d& q : points) mean += q / static_cast<double>(points.size());
        Eigen::Matrix2d scatter = Eigen::Matrix2d::Zero();
        for (const Eigen::Vector2d& q : points) scatter += (q - mean) * (q - mean).transpose();
        const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> solver(scatter);
        const Eigen::Vector2d direction = solver.eigenvectors().col(1), normal = solver.eigenvectors().col(0);
        if (pass == 2) return std::make_pair(mean, direction);
        std::vector<double> distance;
        for (const Eigen::Vector2d& q : points) distance.push_back(std::abs((q - mean).dot(normal)));
        std::vector<double> sorted = distance;
        std::nth_element(sorted.begin(), sorted.begin() + static_cast<std::ptrdiff_t>(sorted.size() / 2), sorted.end());
        const double limit = std::max(kEdgeOutlierPixels, 3.0 * 1.4826 * sorted[sorted.size() / 2]);
        std::vector<Eigen::Vector2d> kept;
        for (std::size_t k = 0; k < points.size(); ++k)
            if (distance[k] <= limit) kept.push_back(points[k]);
        points = std::move(kept);
    }
    return std::nullopt;
}

// Where a side whose outer row is dark but for its corner tiles is read: at the next row's
// edge, or at the corner tiles' own edges.
enum class RowInEdge { NextRow, CornerTiles };

// One of the array's four sides in its own frame: from corner a to corner b, the unit normal
// pointing out of the array, how many lenslets run along it and the pitch across it.
struct ArraySide {
    Eigen::Vector2d a, b, outward;
    double length = 0.0;
    int lenslets = 0;
    double depth = 0.0;
};

ArraySide array_side(const ArrayShape& shape, std::size_t side) {
    Eigen::Vector2d middle = Eigen::Vector2d::Zero();
    for (const Eigen::Vector2d& c : shape.corners) middle += 0.25 * c;
    ArraySide s;
    s.a = shape.corners[side];
    s.b = shape.corners[(side + 1) % 4];
    s.length = (s.b - s.a).norm();
    s.outward = Eigen::Vector2d(-(s.b - s.a).y(), (s.b - s.a).x()).normalized();
    if (s.outward.dot(0.5 * (s.a + s.b) - middle) < 0.0) s.outward = -s.outward;
    s.lenslets = side % 2 == 0 ? shape.lattice.count_x() : shape.lattice.count_y();
    s.depth = side % 2 == 0 ? shape.lattice.pitch_y() : shape.lattice.pitch_x();
    return s;
}

// Whether the photo is lit beyond `side` at both its ends, within kBeyondDepth pitches of it:
// the corner tiles' clear quadrants lie there when the side was placed on the edge of the
// next row in (an outer row dark but for its corner tiles, whose sides are mostly dark).
// Beyond the array's true edge lies the holder, dark.
bool lit_beyond_both_ends(const Image& luminance, const Eigen::Matrix3d& array_to_photo, const ArraySide& side,
                          double threshold) {
    const double tile = side.length / side.lenslets;
    for (int end = 0; end < 2; ++end) {
        const Eigen::Vector2d from = end == 0 ? side.a : side.b, along = (end == 0 ? 1.0 : -1.0) * (side.b - side.a) / side.length;
        double samples = 0.0, lit = 0.0;
        for (int i = 0; i < kBeyondSamples; ++i)
            for (int j = 0; j < kBeyondSamples; ++j) {
                const double t = (i + 0.5) / kBeyondSamples * tile;
                const double d = (kBeyondStart + (j + 0.5) / kBeyondSamples * (kBeyondDepth - kBeyondStart)) * side.depth;
                const double v = photo_at_page(luminance, array_to_photo, from + t * along + d * side.outward);
                if (!std::isfinite(v)) continue;
                samples += 1.0;
                lit += v > threshold ? 1.0 : 0.0;
            }
        if (!(samples > 0.0 && lit > kLitBeyondShare * samples)) return false;
    }
    return true;
}

Eigen::Matrix3d fit_outer_edges(const Image& luminance, const ArrayShape& shape, Eigen::Matrix3d array_to_photo,
                                double threshold, bool around_markers, RowInEdge row_in_edge) {
    // rows_in[side]: the side's outer row is dark but for its corner tiles. Read at the next
    // row's edge, the lines are the images of the array's sides moved in so, and so are the
    // corners where they meet; read at the corner tiles, the side is moved out a row, then
    // read all along, more finely and farther either side.
    std::array<int, 4> rows_in{};
    const bool next_row = row_in_edge == RowInEdge::NextRow;
    const auto read_corners = [&] {
        std::array<Eigen::Vector2d, 4> corners = shape.corners;
        if (!next_row) return corners;
        for (std::size_t index = 0; index < 4; ++index) {
            const ArraySide side = array_side(shape, index);
            const Eigen::Vector2d in = -rows_in[index] * side.depth * side.outward;
            corners[index] += in;
            corners[(index + 1) % 4] += in;
        }
        return corners;
    };
    for (int pass = 0; pass < (around_markers ? 3 : 2); ++pass) {
        // Around the markers (the light near their crosshair: the corner tiles mostly dark, the
        // outline's corners off by up to most of a pitch) no side is read across its corner
        // tiles, and the first pass looks farther.
        const bool first = around_markers && pass == 0;
        const double reach = first ? kFirstEdgeReach * std::min(shape.lattice.pitch_x(), shape.lattice.pitch_y())
                                   : kEdgeReachMm;
        const std::array<Eigen::Vector2d, 4> corners = read_corners();
        std::array<std::optional<std::pair<Eigen::Vector2d, Eigen::Vector2d>>, 4> lines;
        for (std::size_t index = 0; index < 4; ++index) {
            const ArraySide side = array_side(shape, index);
            const Eigen::Vector2d a = corners[index], b = corners[(index + 1) % 4];
            double skip = around_markers ? std::max(kEdgeReachMm, side.length / side.lenslets) : kEdgeReachMm;
            double step = kEdgeStepMm, side_reach = reach;
            if (rows_in[index] && !next_row) skip = step = kCornerTileStepMm, side_reach = kCornerTileReach * side.depth;
            std::vector<Eigen::Vector2d> crossings;
            for (double t = skip; t <= side.length - skip; t += step)
                if (const auto q = edge_crossing(luminance, array_to_photo, a + t / side.length * (b - a), side.outward,
                                                 threshold, side_reach))
                    crossings.push_back(*q);
            lines[index] = robust_line(std::move(crossings));
        }
        std::array<Eigen::Vector2d, 4> photo_corners;
        for (std::size_t c = 0; c < 4; ++c) {
            const auto& before = lines[(c + 3) % 4];
            const auto& after = lines[c];
            photo_corners[c] = apply(array_to_photo, corners[c]);
            if (!before || !after) continue;
            if (const auto corner = meet(before->first, before->second, after->first, after->second))
                photo_corners[c] = *corner;
        }
        array_to_photo = homography_from_points(corners, photo_corners);
        if (!first) continue;
        // A side with the corner tiles lit beyond it was found a row in: its line is the edge
        // of the next row (often the better placement: the marker's ring darkens the corner
        // tiles' own edges as the spot leaves its centre), or it is moved out to them.
        std::array<Eigen::Vector2d, 4> moved_out = shape.corners;
        for (std::size_t index = 0; index < 4; ++index) {
            const ArraySide side = array_side(shape, index);
            rows_in[index] = lit_beyond_both_ends(luminance, array_to_photo, side, threshold) ? 1 : 0;
            moved_out[index] += rows_in[index] * side.depth * side.outward;
            moved_out[(index + 1) % 4] += rows_in[index] * side.depth * side.outward;
        }
        if (next_row) {
            array_to_photo = homography_from_points(read_corners(), photo_corners);
        } else {
            for (std::size_t c = 0; c < 4; ++c) photo_corners[c] = apply(array_to_photo, moved_out[c]);
            array_to_photo = homography_from_points(shape.corners, photo_corners);
        }
    }
    return array_to_photo;
}

// The model of one quarter turn: lenslets' centres and readings; the fit's parameters
// (b_x, b_y, rotation, pitch error) and the gain solved at each.
struct FitData {
    std::vector<Eigen::Vector2d> centre;
    std::vector<double> value;
    std::vector<std::array<double, kGainTerms>> terms;
    int gain_terms = kGainTerms;  // the first this many of each lenslet's terms
};

struct FitResult {
    Eigen::Vector4d parameters = Eigen::Vector4d::Zero();
    Eigen::Matrix4d covariance = Eigen::Matrix4d::Zero();
    double correlation = 0.0, rms = 0.0;
    std::vector<double> fitted;
};

// Residuals of the readings against gain x pattern + offset, the gain's terms and the offset
// solved by least squares, over lenslets `use` (all when empty).
Eigen::VectorXd residuals(const FitData& data, const PatternMap& map, const Eigen::Vector4d& p,
                          const std::vector<std::size_t>& use, std::vector<double>* fitted = nullptr) {
    const std::size_t n = use.size();
    const int g = data.gain_terms;
    Eigen::MatrixXd a(static_cast<Eigen::Index>(n), g + 1);
    Eigen::VectorXd b(static_cast<Eigen::Index>(n));
    for (std::size_t r = 0; r < n; ++r) {
        const std::size_t k = use[r];
        const double pattern = map.at(pattern_point(p, data.centre[k]));
        for (int t = 0; t < g; ++t) a(static_cast<Eigen::Index>(r), t) = data.terms[k][static_cast<std::size_t>(t)] * pattern;
        a(static_cast<Eigen::Index>(r), g) = 1.0;
        b(static_cast<Eigen::Index>(r)) = data.value[k];
    }
    const Eigen::VectorXd x = (a.transpose() * a).ldlt().solve(a.transpose() * b);
    const Eigen::VectorXd model = a * x;
    if (fitted) fitted->assign(model.data(), model.data() + model.size());
    return b - model;
}

// Pearson correlation of the readings with the pattern at shift b (no turn, no scale).
double correlation_at(const FitData& data, const PatternMap& map, const Eigen::Vector2d& b) {
    double sx = 0, sy = 0, sxx = 0, syy = 0, sxy = 0;
    const double n = static_cast<double>(data.value.size());
    for (std::size_t k = 0; k < data.value.size(); ++k) {
        const double x = map.at(data.centre[k] - b), y = data.value[k];
        sx += x, sy += y, sxx += x * x, syy += y * y, sxy += x * y;
    }
    const double vx = sxx - sx * sx / n, vy = syy - sy * sy / n;
    return vx > 0 && vy > 0 ? (sxy - sx * sy / n) / std::sqrt(vx * vy) : 0.0;
}

// Gauss-Newton from `start` over lenslets `use`; the covariance from the residuals.
FitResult gauss_newton(const FitData& data, const PatternMap& map, Eigen::Vector4d p, const std::vector<std::size_t>& use) {
    const MountingFit fit =
        fit_mounting([&](const Eigen::Vector4d& q) { return residuals(data, map, q, use); }, p, data.gain_terms + 1.0);
    FitResult result;
    result.parameters = fit.parameters;
    result.covariance = fit.covariance;
    return result;
}

struct TurnFit {
    FitResult fit;
    // How much worse the best distinct shift fits (residual sum of squares over the noise
    // variance): below kAmbiguousChi2, the pattern cannot tell them apart.
    double alternative_chi2 = HUGE_VAL;
    Eigen::Vector2d alternative = Eigen::Vector2d::Zero();
    FitData data;
    std::vector<optics::CellIndex> cells;
    Eigen::Matrix3d array_to_photo;
};

// A lenslet on a corner marker's clear cell or beside it: left out of the fit.
// Design II's tiles read their own cells while the light's spot stays inside them (lights a
// few degrees off the axis): only the marker cells are left out there.
bool near_marker(const ArrayShape& shape, const optics::CellIndex& cell) {
    const int reach = shape.tiles ? 0 : 1;
    const optics::Lattice& lattice = shape.lattice;
    return (cell.i <= reach || cell.i >= lattice.count_x() - 1 - reach) &&
           (cell.j <= reach || cell.j >= lattice.count_y() - 1 - reach);
}

// Reads the lenslets with the homography whose array corners go to the outline's corners
// turned by `quarter_turns`, and fits.
// The array-to-photo homography whose array corners go to the outline's corners turned by
// `quarter_turns`, refined by the lenslet images (Design I) or the array's edges (Design II).
Eigen::Matrix3d place_array(const Image& luminance, const ArrayShape& shape, const Outline& outline, int quarter_turns,
                            bool around_markers = false, RowInEdge row_in_edge = RowInEdge::NextRow) {
    std::array<Eigen::Vector2d, 4> photo_corners;
    for (std::size_t c = 0; c < 4; ++c) photo_corners[c] = outline.corners[(c + 4 - static_cast<std::size_t>(quarter_turns)) % 4];
    Eigen::Matrix3d to_photo = homography_from_points(shape.corners, photo_corners);
    if (shape.tiles) return fit_outer_edges(luminance, shape, to_photo, outline.threshold, around_markers, row_in_edge);
    to_photo = to_photo * translation(lattice_phase(luminance, shape, to_photo));
    to_photo = refine_homography(luminance, shape, to_photo, outline.dark);
    return to_photo * translation(whole_lenslet_offset(luminance, shape, to_photo));
}

// The labelling of the outline's corners that turns the array by `quarter_turns` (counter-
// clockwise, 0: upright) as the photograph shows it: the one whose array +y points most nearly
// the photo's up turned so. The outline's corners start only roughly at its top left (a
// square array seen turned and in perspective may start at another).
int labelling_for(const ArrayShape& shape, const Outline& outline, int quarter_turns) {
    const Eigen::Vector2d expected[] = {{0.0, -1.0}, {-1.0, 0.0}, {0.0, 1.0}, {1.0, 0.0}};  // photo y down
    const Eigen::Vector2d middle = 0.5 * (shape.low + shape.high);
    int best = quarter_turns;
    double best_dot = -HUGE_VAL;
    for (int r = 0; r < 4; ++r) {
        std::array<Eigen::Vector2d, 4> photo_corners;
        for (std::size_t c = 0; c < 4; ++c) photo_corners[c] = outline.corners[(c + 4 - static_cast<std::size_t>(r)) % 4];
        const Eigen::Matrix3d to_photo = homography_from_points(shape.corners, photo_corners);
        const Eigen::Vector2d up = (apply(to_photo, middle + Eigen::Vector2d::UnitY()) - apply(to_photo, middle)).normalized();
        const double dot = up.dot(expected[quarter_turns]);
        if (dot > best_dot) best_dot = dot, best = r;
    }
    return best;
}

// Reads the lenslets with the array placed turned by `quarter_turns`, and fits.
TurnFit fit_turn(const Image& luminance, const ArrayShape& shape, const Outline& outline, int quarter_turns,
                 const PatternMap& map) {
    TurnFit turn;
    turn.array_to_photo = place_array(luminance, shape, outline, quarter_turns);

    // Every lenslet away from the corner markers, read over its core.
    const optics::Lattice& lattice = shape.lattice;
    const double pitch = lattice.pitch_x();
    const Eigen::Vector2d half = 0.5 * (shape.high - shape.low), middle = 0.5 * (shape.high + shape.low);
    const double mm_per_pixel = mm_per_pixel_at(turn.array_to_photo, middle);
    std::vector<double> values(shape.centres.size());
    parallel_for_chunks(shape.centres.size(), 256, [&](std::size_t begin, std::size_t end) {
        for (std::size_t k = begin; k < end; ++k)
            values[k] = disc_statistics(luminance, turn.array_to_photo, shape.centres[k], kReadRadius * pitch,
                                        std::max(0.25 * mm_per_pixel, 0.02 * pitch)).first;
    });
    for (std::size_t k = 0; k < shape.centres.size(); ++k) {
        const optics::CellIndex cell = shape.cells[k];
        if (near_marker(shape, cell) || !std::isfinite(values[k])) continue;
        const Eigen::Vector2d u = (shape.centres[k] - middle).cwiseQuotient(half);
        turn.data.centre.push_back(shape.centres[k]);
        turn.data.value.push_back(values[k]);
        turn.data.terms.push_back({1.0, u.x(), u.y(), u.x() * u.x(), u.x() * u.y(), u.y() * u.y()});
        turn.cells.push_back(cell);
    }
    if (turn.data.value.size() < kMinReadLenslets) return turn;
    if (turn.data.value.size() < kSmallArray) turn.data.gain_terms = kSmallArrayGainTerms;

    // The shift with the best correlation within half a pitch, then Gauss-Newton.
    const int steps = static_cast<int>(std::ceil(0.5 * pitch / kSearchStepMm));
    std::vector<double> score(static_cast<std::size_t>((2 * steps + 1) * (2 * steps + 1)));
    parallel_for_chunks(score.size(), 16, [&](std::size_t begin, std::size_t end) {
        for (std::size_t s = begin; s < end; ++s) {
            const Eigen::Vector2d b(kSearchStepMm * (static_cast<int>(s) % (2 * steps + 1) - steps),
                                    kSearchStepMm * (static_cast<int>(s) / (2 * steps + 1) - steps));
            score[s] = correlation_at(turn.data, map, b);
        }
    });
    const auto best = static_cast<int>(std::max_element(score.begin(), score.end()) - score.begin());
    const auto shift_of = [&](int index) {
        return Eigen::Vector2d(kSearchStepMm * (index % (2 * steps + 1) - steps), kSearchStepMm * (index / (2 * steps + 1) - steps));
    };
    std::vector<std::size_t> all(turn.data.value.size());
    std::iota(all.begin(), all.end(), std::size_t{0});
    Eigen::Vector4d start = Eigen::Vector4d::Zero();
    start.head<2>() = shift_of(best);
    turn.fit = gauss_newton(turn.data, map, start, all);
    // The best other shift, away from this one (a pattern whose lenslets' images are
    // symmetric reads the same with the shift mirrored): it must fit clearly worse.
    int other = -1;
    for (int k = 0; k < static_cast<int>(score.size()); ++k)
        if ((shift_of(k) - shift_of(best)).norm() > kDistinctShiftMm &&
            (other < 0 || score[static_cast<std::size_t>(k)] > score[static_cast<std::size_t>(other)]))
            other = k;
    if (other >= 0) {
        start.head<2>() = shift_of(other);
        const FitResult alternative = gauss_newton(turn.data, map, start, all);
        const double best_rss = residuals(turn.data, map, turn.fit.parameters, all).squaredNorm();
        const double other_rss = residuals(turn.data, map, alternative.parameters, all).squaredNorm();
        if ((alternative.parameters.head<2>() - turn.fit.parameters.head<2>()).norm() > kDistinctShiftMm)
            turn.alternative_chi2 = (other_rss - best_rss) / (best_rss / static_cast<double>(all.size()));
        turn.alternative = alternative.parameters.head<2>();
    }
    const Eigen::VectorXd r = residuals(turn.data, map, turn.fit.parameters, all, &turn.fit.fitted);
    Eigen::Map<const Eigen::VectorXd> measured(turn.data.value.data(), static_cast<Eigen::Index>(turn.data.value.size()));
    const double mean = measured.mean();
    turn.fit.rms = std::sqrt(r.squaredNorm() / static_cast<double>(r.size())) / mean;
    const double spread = (measured.array() - mean).square().sum();
    turn.fit.correlation = spread > 0 ? std::sqrt(std::max(0.0, 1.0 - r.squaredNorm() / spread)) : 0.0;
    return turn;
}

// InputError naming the photograph when the shift is too uncertain along either axis.
void check_shift_certain(const Eigen::Matrix4d& covariance, const std::string& name) {
    for (int axis = 0; axis < 2; ++axis) {
        const double sigma = std::sqrt(covariance(axis, axis));
        if (!(sigma <= kMaxShiftSigmaMm))
            throw InputError(SourceLocation{name}, format_text("the shift along %s is uncertain by %.3f mm (at most %.3f mm "
                                                               "measures): the photograph is too blurred or too dark, or the "
                                                               "pattern has too little detail along %s",
                                                               axis == 0 ? "x" : "y", sigma, kMaxShiftSigmaMm,
                                                               axis == 0 ? "x" : "y"));
    }
}

}  // namespace

PatternMap::PatternMap(const optics::Transparency& printed, const optics::Design& design) {
    const ArrayShape shape = array_shape(design);
    const double reach = 0.5 * shape.lattice.pitch_x() + 0.5;  // a shifted array's lenslets read this far out
    origin_ = shape.low - Eigen::Vector2d::Constant(reach);
    width_ = static_cast<int>(std::ceil((shape.high.x() - shape.low.x() + 2 * reach) / kPatternStepMm)) + 1;
    height_ = static_cast<int>(std::ceil((shape.high.y() - shape.low.y() + 2 * reach) / kPatternStepMm)) + 1;
    values_.assign(static_cast<std::size_t>(width_) * static_cast<std::size_t>(height_), 0.0f);
    const int channels = printed.channels();
    // Row by row (a streamed pattern reads each of its rows once), each sample the mean of
    // kPatternSamples^2 points over its grid cell.
    parallel_for_chunks(static_cast<std::size_t>(height_), 8, [&](std::size_t begin, std::size_t end) {
        std::vector<Eigen::Vector2d> points(static_cast<std::size_t>(width_) * kPatternSamples * kPatternSamples);
        std::vector<float> out(points.size() * static_cast<std::size_t>(channels));
        for (auto y = static_cast<int>(begin); y < static_cast<int>(end); ++y) {
            std::size_t n = 0;
            for (int sy = 0; sy < kPatternSamples; ++sy)
                for (int x = 0; x < width_; ++x)
                    for (int sx = 0; sx < kPatternSamples; ++sx)
                        points[n++] = origin_ + kPatternStepMm * Eigen::Vector2d(x + (sx + 0.5) / kPatternSamples - 0.5,
                                                                                  y + (sy + 0.5) / kPatternSamples - 0.5);
            printed.sample(points, out);
            for (int x = 0; x < width_; ++x) {
                double sum = 0.0;
                for (int sy = 0; sy < kPatternSamples; ++sy)
                    for (int sx = 0; sx < kPatternSamples; ++sx) {
                        const std::size_t point = (static_cast<std::size_t>(sy) * static_cast<std::size_t>(width_) +
                                                   static_cast<std::size_t>(x)) * kPatternSamples + static_cast<std::size_t>(sx);
                        for (int c = 0; c < channels; ++c) sum += out[point * static_cast<std::size_t>(channels) + static_cast<std::size_t>(c)];
                    }
                values_[static_cast<std::size_t>(y) * static_cast<std::size_t>(width_) + static_cast<std::size_t>(x)] =
                    static_cast<float>(sum / (kPatternSamples * kPatternSamples * channels));
            }
        }
    });
}

double PatternMap::at(const Eigen::Vector2d& point) const {
    const double u = (point.x() - origin_.x()) / kPatternStepMm, v = (point.y() - origin_.y()) / kPatternStepMm;
    if (!(u >= 0.0 && v >= 0.0 && u < width_ - 1 && v < height_ - 1)) return 0.0;
    const int x = static_cast<int>(u), y = static_cast<int>(v);
    const double fx = u - x, fy = v - y;
    const float* row = values_.data() + static_cast<std::size_t>(y) * static_cast<std::size_t>(width_) + static_cast<std::size_t>(x);
    return (1 - fy) * ((1 - fx) * row[0] + fx * row[1]) + fy * ((1 - fx) * row[width_] + fx * row[width_ + 1]);
}

namespace {

// An array too small to spare its corners (under 16 lenslets left) does not hold enough
// readings to fit the shift, turn, scale and light falloff.
void check_readable(const ArrayShape& shape, const optics::Design& design) {
    const auto readable = static_cast<std::size_t>(std::count_if(
        shape.cells.begin(), shape.cells.end(), [&](const optics::CellIndex& c) { return !near_marker(shape, c); }));
    if (readable < kMinReadLenslets)
        throw InputError(SourceLocation{design.file},
                         format_text("the array has %zu lenslets away from its corner markers, too few to measure the "
                                     "registration from (at least %zu): centre the markers under the corner lenslets "
                                     "by eye",
                                     readable, kMinReadLenslets));
}

}  // namespace

void check_registration_readable(const optics::Design& design) { check_readable(array_shape(design), design); }

namespace {

// Design II's corner tiles read as pictures of their markers (marker_tiles.hpp), the display
// turned by `quarter_turns`: the reading, or nullopt when they do not show their markers well
// enough. `refusal` then says why a good fit was not taken (the light's spot too far from the
// crosshair), for the message should the macro-pixels fail too.
std::optional<RegistrationReading> read_markers(const Image& luminance, const std::string& name,
                                                const optics::Design& design, const ArrayShape& shape,
                                                const Outline& outline, const PatternMap& map, int quarter_turns,
                                                std::string& refusal) {
    // Where a side is dark but for its corner tiles, the array is placed both ways
    // (fit_outer_edges), and the placement the markers fit best is taken.
    const int labelling = labelling_for(shape, outline, quarter_turns);
    const MarkerTiles tiles(design);
    Eigen::Matrix3d to_photo = place_array(luminance, shape, outline, labelling, true, RowInEdge::NextRow);
    std::optional<MarkerTileFit> markers = tiles.read(luminance, to_photo, map);
    const Eigen::Matrix3d other = place_array(luminance, shape, outline, labelling, true, RowInEdge::CornerTiles);
    if (!other.isApprox(to_photo)) {
        std::optional<MarkerTileFit> other_markers = tiles.read(luminance, other, map);
        if (other_markers && (!markers || other_markers->correlation > markers->correlation))
            markers = std::move(other_markers), to_photo = other;
    }
    if (!markers || markers->correlation < kMinMarkerCorrelation ||
        std::max(markers->covariance(0, 0), markers->covariance(1, 1)) > kMaxMarkerSigmaMm * kMaxMarkerSigmaMm)
        return std::nullopt;
    const double spot_from_centre = markers->parameters.head<2>().norm();
    if (spot_from_centre > kMaxMarkerSpotMm) {
        refusal = format_text("; the corner macro-pixels show the light's spot %.2f mm from their markers' centre, "
                              "farther than the %.2f mm they are read within: move the light or tilt the display "
                              "until each shows its dark cross centred",
                              spot_from_centre, kMaxMarkerSpotMm);
        return std::nullopt;
    }
    RegistrationReading reading;
    reading.name = name;
    reading.quarter_turns = quarter_turns;
    reading.correlation = markers->correlation;
    reading.runner_up = NAN;
    reading.rms = markers->rms;
    reading.apparent_shift = markers->parameters.head<2>();
    reading.rotation_rad = markers->parameters(2);
    reading.pitch_error = markers->parameters(3);
    reading.covariance = markers->covariance;
    reading.marker_bins = markers->bins;
    reading.array_to_photo = to_photo;
    reading.mm_per_pixel = mm_per_pixel_at(to_photo, 0.5 * (shape.low + shape.high));
    check_shift_certain(reading.covariance, name);
    return reading;
}

// The macro-pixels or lenslet images read one value each and fitted, the display turned by
// `quarter_turns` or, when not given, whichever way up fits best.
RegistrationReading read_lenslets(const Image& luminance, const std::string& name, const ArrayShape& shape,
                                  const Outline& outline, const PatternMap& map, std::optional<int> quarter_turns) {
    // The quarter turns to try: the one given, or all. A small array's few readings can fit
    // well the wrong way up (the gain and geometry absorb much of them): all are tried, and the
    // one given must fit best.
    const bool small = shape.centres.size() < kSmallArray;
    std::vector<int> tried;
    for (int q = 0; q < 4; ++q)
        if (!quarter_turns || small || *quarter_turns == q) tried.push_back(q);
    std::vector<TurnFit> turns;
    for (const int q : tried) turns.push_back(fit_turn(luminance, shape, outline, q, map));
    std::vector<std::size_t> order(turns.size());
    std::iota(order.begin(), order.end(), std::size_t{0});
    std::sort(order.begin(), order.end(),
              [&](std::size_t a, std::size_t b) { return turns[a].fit.correlation > turns[b].fit.correlation; });
    TurnFit& best = turns[order[0]];
    RegistrationReading reading;
    reading.name = name;
    reading.quarter_turns = tried[order[0]];
    reading.correlation = best.fit.correlation;
    reading.runner_up = !quarter_turns && order.size() > 1 ? turns[order[1]].fit.correlation : NAN;
    if (reading.correlation < kMinCorrelation)
        throw InputError(SourceLocation{name}, format_text("the lenslets' readings do not follow the pattern (correlation "
                                                           "%.2f, at least %.2f needed): is it this pattern, lit from "
                                                           "behind by one small light, the photograph sharp, the "
                                                           "array's corners lit?",
                                                           reading.correlation, kMinCorrelation));
    if (quarter_turns && reading.quarter_turns != *quarter_turns) {
        const auto given = static_cast<std::size_t>(std::find(tried.begin(), tried.end(), *quarter_turns) - tried.begin());
        throw InputError(SourceLocation{name},
                         format_text("the display fits better turned by %d quarter turn(s) than by %d as given "
                                     "(correlations %.3f and %.3f): is the photograph the right way up?",
                                     reading.quarter_turns, *quarter_turns, reading.correlation,
                                     turns[given].fit.correlation));
    }
    if (reading.correlation < reading.runner_up + kTurnMargin)
        throw InputError(SourceLocation{name}, format_text("the pattern fits two ways up about as well (correlations "
                                                           "%.3f and %.3f): it is too symmetric to say which; say "
                                                           "which way up the display is in the photograph",
                                                           reading.correlation, reading.runner_up));
    if (best.alternative_chi2 < kAmbiguousChi2)
        throw InputError(SourceLocation{name}, format_text("the pattern reads about as well shifted by %+.3f, %+.3f mm as by "
                                                           "%+.3f, %+.3f mm (its lenslets' images are too symmetric or too "
                                                           "plain to tell): photograph it under a light off the axis, or "
                                                           "register with a picture that changes with the light",
                                                           best.alternative.x(), best.alternative.y(),
                                                           best.fit.parameters.x(), best.fit.parameters.y()));
    const Eigen::Vector4d& p = best.fit.parameters;
    reading.apparent_shift = p.head<2>();
    reading.rotation_rad = p(2);
    reading.pitch_error = p(3);
    reading.rms = best.fit.rms;
    // Uncertainty: the fit's, or the jackknife's over groups of columns when larger.
    Eigen::Matrix4d covariance = best.fit.covariance;
    {
        std::array<Eigen::Vector4d, kGroups> estimates;
        const int columns = shape.lattice.count_x();
        for (int g = 0; g < kGroups; ++g) {
            std::vector<std::size_t> use;
            for (std::size_t k = 0; k < best.cells.size(); ++k)
                if (best.cells[k].i * kGroups / columns != g) use.push_back(k);
            estimates[static_cast<std::size_t>(g)] = gauss_newton(best.data, map, p, use).parameters;
        }
        widen_by_jackknife(covariance, estimates);
    }
    reading.covariance = covariance;
    check_shift_certain(covariance, name);
    reading.array_to_photo = best.array_to_photo;
    reading.mm_per_pixel = mm_per_pixel_at(best.array_to_photo, 0.5 * (shape.low + shape.high));
    for (std::size_t k = 0; k < best.data.value.size(); ++k)
        reading.lenslets.push_back({best.data.centre[k], best.data.value[k], best.fit.fitted[k]});
    return reading;
}


}  // namespace

RegistrationReading read_registration_photo(const Image& photo, const std::string& name,
                                            const optics::Design& design, const PatternMap& map,
                                            std::optional<int> quarter_turns) {
    RFD_CHECK(!quarter_turns || (*quarter_turns >= 0 && *quarter_turns < 4));
    const ArrayShape shape = array_shape(design);
    check_readable(shape, design);
    const Image luminance = photo_luminance(photo);
    const Outline outline = find_outline(luminance, name, shape.tiles);
    // With the light near the axis Design II's corner tiles show their markers, magnified:
    // they place the spot on the pattern whatever the picture (marker_tiles.hpp). They look
    // the same any way up, so the way up must be given.
    std::string marker_refusal;
    if (shape.tiles && quarter_turns)
        if (auto reading = read_markers(luminance, name, design, shape, outline, map, *quarter_turns, marker_refusal))
            return *reading;
    try {
        return read_lenslets(luminance, name, shape, outline, map, quarter_turns);
    } catch (const InputError& error) {
        if (marker_refusal.empty()) throw;
        throw InputError(error.what() + marker_refusal);
    }
}

Eigen::Vector2d spot_offset(const optics::Design& design, const Eigen::Vector3d& light) {
    const optics::DisplaySimulator simulator(design);
    optics::SimulationOptions options;
    options.model = optics::Model::Exact;
    options.rays_per_side = 32;
    const optics::RepeatedRays rays = simulator.trace_lenslet({{light.normalized(), {1.0, 1.0, 1.0}, 0.0}}, options);
    // The reading is taken over a disc about the centroid of the lenslet's light on the
    // diffuser: the pattern is read where the rays landing in that disc crossed it.
    Eigen::Vector2d landing = Eigen::Vector2d::Zero();
    double total = 0.0;
    for (const optics::LensletRay& ray : rays.rays)
        if (!ray.crossed) landing += ray.reaching * ray.on_diffuser, total += ray.reaching;
    if (!(total > 0.0)) throw InputError(SourceLocation{}, "no light reaches the pattern from that direction");
    landing /= total;
    const double radius = kReadRadius * optics::DesignOptics(design).lattice().pitch_x();
    Eigen::Vector2d sum = Eigen::Vector2d::Zero();
    double read = 0.0;
    for (const optics::LensletRay& ray : rays.rays)
        if (!ray.crossed && (ray.on_diffuser - landing).norm() <= radius)
            sum += ray.reaching * ray.on_pattern, read += ray.reaching;
    if (!(read > 0.0)) throw InputError(SourceLocation{}, "the light from that direction misses the lenslets' centres");
    return sum / read;
}

Registration combine_registration(const optics::Design& design, const std::vector<RegistrationReading>& readings,
                                  const std::optional<Eigen::Vector3d>& light) {
    RFD_CHECK(!readings.empty());
    Registration result;
    // Each photograph's b, with its variance; the spot offset to add.
    Eigen::Vector2d spot = Eigen::Vector2d::Zero();
    std::vector<const RegistrationReading*> first_way, turned;
    for (const RegistrationReading& r : readings)
        ((r.quarter_turns - readings.front().quarter_turns + 4) % 4 == 2 ? turned : first_way).push_back(&r);
    const auto mean_of = [](const std::vector<const RegistrationReading*>& group) {
        Eigen::Vector4d mean = Eigen::Vector4d::Zero();
        Eigen::Matrix4d covariance = Eigen::Matrix4d::Zero();
        for (const RegistrationReading* r : group) {
            mean += Eigen::Vector4d(r->apparent_shift.x(), r->apparent_shift.y(), r->rotation_rad, r->pitch_error);
            covariance += r->covariance;
        }
        const auto n = static_cast<double>(group.size());
        return std::pair{Eigen::Vector4d(mean / n), Eigen::Matrix4d(covariance / (n * n))};
    };
    Eigen::Vector4d estimate;
    Eigen::Matrix4d covariance;
    if (light) {
        spot = spot_offset(design, *light);
        std::vector<const RegistrationReading*> all;
        for (const RegistrationReading& r : readings) all.push_back(&r);
        std::tie(estimate, covariance) = mean_of(all);
        estimate.head<2>() += spot;
        result.light = "given";
    } else if (!turned.empty()) {
        const auto [a, ca] = mean_of(first_way);
        const auto [b, cb] = mean_of(turned);
        estimate = 0.5 * (a + b);
        covariance = 0.25 * (ca + cb);
        spot = 0.5 * (b - a).head<2>();
        result.light = "turned pair";
    } else {
        std::vector<const RegistrationReading*> all;
        for (const RegistrationReading& r : readings) all.push_back(&r);
        std::tie(estimate, covariance) = mean_of(all);
        result.light = "assumed head-on";
    }
    result.spot = spot;
    result.shift_mm = estimate.head<2>();
    result.sigma_shift_mm = Eigen::Vector2d(std::sqrt(covariance(0, 0)), std::sqrt(covariance(1, 1)));
    result.rotation_deg = radians_to_degrees(estimate(2));
    result.sigma_rotation_deg = radians_to_degrees(std::sqrt(covariance(2, 2)));
    result.pitch_error = estimate(3);
    result.sigma_pitch_error = std::sqrt(covariance(3, 3));
    return result;
}

}  // namespace rfd::calibrate

namespace rfd::calibrate {

std::optional<bool> inside_tolerances(const Registration& m, const RegistrationTolerances& tolerances) {
    if (!tolerances.shift_mm && !tolerances.rotation_deg) return std::nullopt;
    return (!tolerances.shift_mm || m.shift_mm.norm() <= *tolerances.shift_mm) &&
           (!tolerances.rotation_deg || std::abs(m.rotation_deg) <= *tolerances.rotation_deg);
}

std::string registration_text(const Registration& m, const std::vector<RegistrationReading>& readings,
                              const RegistrationTolerances& tolerances) {
    std::string text;
    for (const RegistrationReading& r : readings)
        text += format_text("%s: %s, %.3f mm a pixel, turned %d quarter turn(s), fit correlation %.3f%s, "
                            "residual %.1f %%; reads shift %+.4f, %+.4f mm\n",
                            r.name.c_str(),
                            r.marker_bins > 0 ? format_text("the 4 corner markers (%zu samples)", r.marker_bins).c_str()
                                              : format_text("%zu lenslets", r.lenslets.size()).c_str(),
                            r.mm_per_pixel, r.quarter_turns, r.correlation,
                            std::isfinite(r.runner_up) ? format_text(" (next way up %.3f)", r.runner_up).c_str() : "",
                            100.0 * r.rms, r.apparent_shift.x(), r.apparent_shift.y());
    if (m.light == "given")
        text += format_text("light: as given (its spot %+.4f, %+.4f mm from the lenslets' centres)\n", m.spot.x(), m.spot.y());
    else if (m.light == "turned pair")
        text += format_text("light: from the turned pair, its spot %+.4f, %+.4f mm from the lenslets' centres\n",
                            m.spot.x(), m.spot.y());
    else
        text += "light: assumed head-on (a light tilted by 1 deg moves the reading by about f tan 1 deg; photograph "
                "the display again turned by half a turn, or give --light-tilt)\n";
    text += format_text("shift     %+.4f, %+.4f mm (+-%.4f, %.4f): the pattern lies this far right and up of where it "
                        "belongs, seen from the front\n",
                        m.shift_mm.x(), m.shift_mm.y(), m.sigma_shift_mm.x(), m.sigma_shift_mm.y());
    text += format_text("turn      %+.4f deg (+-%.4f), counter-clockwise seen from the front\n", m.rotation_deg,
                        m.sigma_rotation_deg);
    text += format_text("scale     %+.4f %% (+-%.4f): the print's size over the encoded, with the light's spread\n",
                        100.0 * m.pitch_error, 100.0 * m.sigma_pitch_error);
    const double shift = m.shift_mm.norm();
    if (tolerances.shift_mm)
        text += format_text("shift %.3f mm is %s the design's tolerance of %.3f mm\n", shift,
                            shift <= *tolerances.shift_mm ? "inside" : "OUTSIDE", *tolerances.shift_mm);
    if (tolerances.rotation_deg)
        text += format_text("turn %.3f deg is %s the design's tolerance of %.3f deg\n", std::abs(m.rotation_deg),
                            std::abs(m.rotation_deg) <= *tolerances.rotation_deg ? "inside" : "OUTSIDE",
                            *tolerances.rotation_deg);
    const std::optional<bool> inside = inside_tolerances(m, tolerances);
    if (!inside) text += "tolerances: not given (--tolerance: the folder rfd simulate tolerance wrote)\n";
    if (inside.value_or(false))
        text += "verdict: inside the tolerances; fix the pattern where it is\n";
    else
        text += format_text("to do: move the pattern by %+.3f, %+.3f mm (right, up, seen from the front) and turn it by "
                            "%+.3f deg (counter-clockwise), or reprint it shifted so\n",
                            -m.shift_mm.x(), -m.shift_mm.y(), -m.rotation_deg);
    return text;
}

}  // namespace rfd::calibrate
