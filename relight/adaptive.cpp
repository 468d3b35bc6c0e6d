#include "relight/adaptive.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <numeric>
#include <set>

#include <Eigen/Eigenvalues>

#include "core/error.hpp"
#include "core/parallel.hpp"
#include "core/sphere.hpp"

namespace rfd::relight {

std::vector<Triangle> canonical_order(std::vector<Triangle> triangles) {
    for (Triangle& t : triangles) {
        const auto smallest = std::min_element(t.begin(), t.end());
        std::rotate(t.begin(), smallest, t.end());
    }
    std::sort(triangles.begin(), triangles.end());
    return triangles;
}

std::vector<std::vector<std::size_t>> one_rings(std::size_t vertex_count,
                                                const std::vector<Triangle>& triangles) {
    std::vector<std::set<std::size_t>> sets(vertex_count);
    for (const Triangle& t : triangles)
        for (int e = 0; e < 3; ++e) {
            const std::size_t a = t[e], b = t[(e + 1) % 3];
            RFD_CHECK(a < vertex_count && b < vertex_count && a != b);
            sets[a].insert(b);
            sets[b].insert(a);
        }
    std::vector<std::vector<std::size_t>> rings(vertex_count);
    for (std::size_t v = 0; v < vertex_count; ++v) rings[v].assign(sets[v].begin(), sets[v].end());
    return rings;
}

double image_dot(const Image& a, const Image& b) {
    RFD_CHECK(a.same_shape(b));
    const auto sa = a.samples(), sb = b.samples();
    // Double accumulation: the residual of eq. 5.2 is a difference of such sums and must
    // not drown in their rounding. Fixed order, so results are deterministic.
    // Four interleaved partial sums keep the adder pipeline busy.
    double partial[4] = {0.0, 0.0, 0.0, 0.0};
    const std::size_t n = sa.size(), whole = n - n % 4;
    for (std::size_t k = 0; k < whole; k += 4)
        for (std::size_t lane = 0; lane < 4; ++lane)
            partial[lane] += static_cast<double>(sa[k + lane]) * static_cast<double>(sb[k + lane]);
    for (std::size_t k = whole; k < n; ++k)
        partial[0] += static_cast<double>(sa[k]) * static_cast<double>(sb[k]);
    return (partial[0] + partial[1]) + (partial[2] + partial[3]);
}

double ProjectionErrors::dot(std::size_t a, std::size_t b) const {
    return dots_.at({std::min(a, b), std::max(a, b)});
}

std::vector<double> ProjectionErrors::update(const std::vector<Image>& images,
                                             const std::vector<std::vector<std::size_t>>& rings) {
    RFD_CHECK(rings.size() == images.size());
    // Every pair the analysis needs: (i, i), (i, k) and (k, l) for k, l in N_i.
    std::set<std::pair<std::size_t, std::size_t>> needed;
    auto want = [&](std::size_t a, std::size_t b) {
        const std::pair<std::size_t, std::size_t> key{std::min(a, b), std::max(a, b)};
        if (!dots_.contains(key)) needed.insert(key);
    };
    for (std::size_t i = 0; i < images.size(); ++i) {
        want(i, i);
        for (const std::size_t k : rings[i]) {
            want(i, k);
            for (const std::size_t l : rings[i]) want(k, l);
        }
    }
    const std::vector<std::pair<std::size_t, std::size_t>> pairs(needed.begin(), needed.end());
    std::vector<double> values(pairs.size());
    parallel_for_chunks(pairs.size(), 1, [&](std::size_t begin, std::size_t end) {
        for (std::size_t p = begin; p < end; ++p)
            values[p] = image_dot(images[pairs[p].first], images[pairs[p].second]);
    });
    for (std::size_t p = 0; p < pairs.size(); ++p) dots_.emplace(pairs[p], values[p]);

    std::vector<double> errors(images.size(), 0.0);
    for (std::size_t i = 0; i < images.size(); ++i) {
        const auto& ring = rings[i];
        const auto k = static_cast<Eigen::Index>(ring.size());
        Eigen::MatrixXd gram(k, k);
        Eigen::VectorXd cross(k);
        for (Eigen::Index r = 0; r < k; ++r) {
            cross(r) = dot(i, ring[r]);
            for (Eigen::Index c = 0; c < k; ++c) gram(r, c) = dot(ring[r], ring[c]);
        }
        errors[i] = projection_residual(dot(i, i), gram, cross);
    }
    return errors;
}

double projection_residual(double self, const Eigen::MatrixXd& gram, const Eigen::VectorXd& cross) {
    if (gram.rows() == 0) return std::max(self, 0.0);
    // min_mu ||x - A mu||^2 = ||x||^2 - b^T G^+ b. G = A^T A is symmetric positive
    // semi-definite: its eigen-decomposition is its SVD; tiny eigenvalues (dependent
    // neighbour images, black images) are dropped as a pseudo-inverse does.
    const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(gram);
    const Eigen::VectorXd& values = eigen.eigenvalues();
    const double cutoff = std::max(values.maxCoeff(), 0.0) * 1e-12;
    const Eigen::VectorXd projected = eigen.eigenvectors().transpose() * cross;
    double explained = 0.0;
    for (Eigen::Index k = 0; k < values.size(); ++k)
        if (values(k) > cutoff) explained += projected(k) * projected(k) / values(k);
    return std::max(self - explained, 0.0);
}

bool spherical_circumcentre(const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                            const Eigen::Vector3d& c, Eigen::Vector3d& centre) {
    // The circumcentre is equidistant from the three vertices: it lies on the normal of
    // the plane through them.
    Eigen::Vector3d normal = (b - a).cross(c - a);
    const double length = normal.norm();
    if (!(length > 1e-15)) return false;
    normal /= length;
    if (normal.dot(a + b + c) < 0.0) normal = -normal;
    centre = normal;
    return true;
}

std::vector<std::array<std::size_t, 2>> boundary_edges(const std::vector<Triangle>& triangles) {
    std::map<std::pair<std::size_t, std::size_t>, int> uses;
    for (const Triangle& t : triangles)
        for (int k = 0; k < 3; ++k) {
            const std::size_t a = t[k], b = t[(k + 1) % 3];
            ++uses[{std::min(a, b), std::max(a, b)}];
        }
    std::vector<std::array<std::size_t, 2>> rim;
    for (const Triangle& t : triangles)
        for (int k = 0; k < 3; ++k) {
            const std::size_t a = t[k], b = t[(k + 1) % 3];
            if (uses[{std::min(a, b), std::max(a, b)}] == 1) rim.push_back({a, b});
        }
    return rim;
}

Insertion choose_new_directions(const std::vector<Eigen::Vector3d>& directions,
                                const std::vector<Triangle>& triangles,
                                const std::vector<double>& vertex_errors,
                                const InsertionOptions& options) {
    RFD_CHECK(vertex_errors.size() == directions.size());
    std::vector<double> triangle_errors(triangles.size());
    for (std::size_t t = 0; t < triangles.size(); ++t)
        triangle_errors[t] = vertex_errors[triangles[t][0]] + vertex_errors[triangles[t][1]] +
                             vertex_errors[triangles[t][2]];
    const std::vector<std::array<std::size_t, 2>> rim =
        options.horizon_band ? boundary_edges(triangles) : std::vector<std::array<std::size_t, 2>>{};
    for (const auto& [a, b] : rim)
        triangle_errors.push_back(1.5 * (vertex_errors[a] + vertex_errors[b]));
    std::vector<std::size_t> order(triangle_errors.size());
    std::iota(order.begin(), order.end(), std::size_t{0});
    std::stable_sort(order.begin(), order.end(), [&](std::size_t l, std::size_t r) {
        return triangle_errors[l] > triangle_errors[r];
    });
    // Comparing cosines avoids an acos per pair.
    const double cos_limit = std::cos(options.min_separation);
    auto too_close = [&](const Eigen::Vector3d& d, const std::vector<Eigen::Vector3d>& set) {
        for (const Eigen::Vector3d& e : set)
            if (d.dot(e) > cos_limit) return true;
        return false;
    };
    Insertion result;
    for (const std::size_t t : order) {
        if (result.directions.size() >= options.count) break;
        Eigen::Vector3d centre;
        if (t < triangles.size()) {
            const Triangle& tri = triangles[t];
            if (!spherical_circumcentre(directions[tri[0]], directions[tri[1]], directions[tri[2]], centre) ||
                angle_between(centre, directions[tri[0]]) < options.min_separation) {
                ++result.skipped_small;
                continue;
            }
        } else {
            const auto& [a, b] = rim[t - triangles.size()];
            const Eigen::Vector3d middle = directions[a] + directions[b];
            if (middle.head<2>().norm() == 0.0) {  // the edge spans the pole: no horizon below
                ++result.skipped_small;
                continue;
            }
            // A rim within the density limit of the horizon leaves no band to sample.
            if (std::min(directions[a].z(), directions[b].z()) < std::sin(options.min_separation)) {
                ++result.skipped_small;
                continue;
            }
            const Eigen::Vector3d horizon(middle.x(), middle.y(), 0.0);
            centre = (directions[a] + directions[b] + horizon.normalized()).normalized();
            if (angle_between(centre, directions[a]) < options.min_separation) {
                ++result.skipped_small;
                continue;
            }
        }
        if (centre.z() < 0.0) {
            ++result.skipped_below_horizon;
            continue;
        }
        if (too_close(centre, directions) || too_close(centre, result.directions)) {
            ++result.skipped_close;
            continue;
        }
        result.directions.push_back(centre);
        result.from_triangle.push_back(t);
    }
    return result;
}

std::vector<std::size_t> sparse_directions(const std::vector<Eigen::Vector3d>& directions,
                                           const std::vector<std::vector<std::size_t>>& rings,
                                           const std::vector<std::size_t>& candidates,
                                           double threshold) {
    std::vector<std::size_t> sparse;
    for (const std::size_t i : candidates) {
        RFD_CHECK(i < directions.size() && i < rings.size());
        const bool isolated = std::all_of(rings[i].begin(), rings[i].end(), [&](std::size_t k) {
            return angle_between(directions[i], directions[k]) > threshold;
        });
        if (isolated) sparse.push_back(i);
    }
    return sparse;
}

Image matched_to_mean(const Image& wide, const Image& narrow) {
    RFD_CHECK(wide.same_shape(narrow));
    double sum_wide = 0.0, sum_narrow = 0.0;
    for (const float v : wide.samples()) sum_wide += v;
    for (const float v : narrow.samples()) sum_narrow += v;
    Image scaled = wide;
    if (sum_wide <= 0.0) return scaled;
    const auto factor = static_cast<float>(sum_narrow / sum_wide);
    for (float& v : scaled.samples()) v *= factor;
    return scaled;
}

AdaptiveRun adaptive_capture(CaptureDevice& device, const std::vector<Eigen::Vector3d>& initial,
                             const Triangulate& triangulate, const AdaptiveOptions& options,
                             const std::function<void(const AdaptiveRun&)>& after_iteration) {
    RFD_CHECK(options.per_iteration > 0);
    AdaptiveRun run;
    const std::size_t first = std::min(initial.size(), options.total);
    run.field.directions.assign(initial.begin(), initial.begin() + static_cast<std::ptrdiff_t>(first));
    run.field.images = device.capture(run.field.directions, KernelChoice::Narrow);
    run.iteration.assign(first, 0);
    run.images_after.push_back(first);
    if (after_iteration) after_iteration(run);
    ProjectionErrors errors;
    for (std::size_t iteration = 1; run.field.size() < options.total; ++iteration) {
        const auto start = std::chrono::steady_clock::now();
        const std::vector<Triangle> triangles = canonical_order(triangulate(run.field.directions));
        const auto rings = one_rings(run.field.size(), triangles);
        const std::vector<double> vertex_errors = errors.update(run.field.images, rings);
        InsertionOptions insertion_options;
        insertion_options.count = std::min(options.per_iteration, options.total - run.field.size());
        insertion_options.min_separation = options.min_separation;
        insertion_options.horizon_band = options.horizon_band;
        const Insertion insertion =
            choose_new_directions(run.field.directions, triangles, vertex_errors, insertion_options);
        run.analysis_seconds.push_back(
            std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
        if (insertion.directions.empty()) {
            run.density_limit_reached = true;
            break;
        }
        std::vector<Image> images = device.capture(insertion.directions, KernelChoice::Narrow);
        for (std::size_t k = 0; k < images.size(); ++k) {
            run.field.directions.push_back(insertion.directions[k]);
            run.field.images.push_back(std::move(images[k]));
            run.iteration.push_back(iteration);
        }
        run.images_after.push_back(run.field.size());
        if (after_iteration) after_iteration(run);
    }
    return run;
}

std::vector<std::size_t> make_two_level(ReflectanceField& field, std::size_t initial_count,
                                        CaptureDevice& device, const Triangulate& triangulate,
                                        double threshold) {
    RFD_CHECK(initial_count <= field.size());
    const auto rings = one_rings(field.size(), triangulate(field.directions));
    std::vector<std::size_t> candidates(initial_count);
    std::iota(candidates.begin(), candidates.end(), std::size_t{0});
    const std::vector<std::size_t> replaced =
        sparse_directions(field.directions, rings, candidates, threshold);
    std::vector<Eigen::Vector3d> directions;
    for (const std::size_t i : replaced) directions.push_back(field.directions[i]);
    const std::vector<Image> wide = device.capture(directions, KernelChoice::Wide);
    if (field.kernel_radii.empty())
        field.kernel_radii.assign(field.size(), device.kernel_radius(KernelChoice::Narrow));
    for (std::size_t k = 0; k < replaced.size(); ++k) {
        const std::size_t i = replaced[k];
        field.images[i] = matched_to_mean(wide[k], field.images[i]);
        field.kernel_radii[i] = device.kernel_radius(KernelChoice::Wide);
    }
    return replaced;
}

}  // namespace rfd::relight
