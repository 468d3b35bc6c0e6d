// rfd pattern optimize: a Design I/II pattern chosen through the display's own forward
// model (predict/optimize.hpp), starting from the direct encoding.

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "cli/arguments.hpp"
#include "cli/commands.hpp"
#include "core/error.hpp"
#include "core/files.hpp"
#include "core/plot.hpp"
#include "core/progress.hpp"
#include "core/text.hpp"
#include "optics/display.hpp"
#include "patterns/encode.hpp"
#include "predict/compare.hpp"
#include "predict/optimize.hpp"
#include "print/printed.hpp"
#include "relight/field.hpp"

namespace rfd::cli {
namespace {

using Clock = std::chrono::steady_clock;

// --crop I,J,W,H: whole lenslets, from the bottom-left lenslet of the array.
predict::LensletWindow parse_crop(const std::string& text, const optics::Lattice& lattice) {
    int i = 0, j = 0, w = 0, h = 0;
    char tail = 0;
    if (std::sscanf(text.c_str(), "%d,%d,%d,%d%c", &i, &j, &w, &h, &tail) != 4 || i < 0 || j < 0 || w < 1 || h < 1 ||
        i + w > lattice.count_x() || j + h > lattice.count_y())
        throw InputError("--crop: expected I,J,W,H, whole lenslets inside the " + std::to_string(lattice.count_x()) +
                         " x " + std::to_string(lattice.count_y()) + " array, got '" + text + "'");
    return {i, j, i + w, j + h};
}

// Over the directions with a finite PSNR: a direction whose picture is black (a letter
// field between its letters) or matched exactly says nothing of the others.
double mean_of(const std::vector<double>& values) {
    double sum = 0.0;
    int count = 0;
    for (double v : values)
        if (std::isfinite(v)) sum += v, ++count;
    return count ? sum / count : std::nan("");
}

}  // namespace

void add_pattern_optimize_command(CLI::App& pattern) {
    auto* cmd = pattern.add_subcommand(
        "optimize", "Choose a Design I/II pattern through the display's own forward model: the printable pattern whose "
                    "predicted output comes closest to the field relit in software, over the field of view");
    struct Options {
        std::string design, field, from, out, report, crop, lights = "sweep";
        PrintOptions print;
        optics::ModelChoice model = optics::ModelChoice::Auto;
        double spacing = 0.1, tolerance = 1e-5, core_weight = 0.0;
        int iterations = 40, rays = 8, chart_every = 5, judge_sweep = 9;
        bool unbounded = false, json = false, timings = false;
    };
    auto opt = std::make_shared<Options>();
    cmd->add_option("DESIGN", opt->design, "Design TOML file (Design I or II)")->required();
    cmd->add_option("FIELD", opt->field, "The reflectance field (folder or .lp) the --from pattern was encoded from")
        ->required();
    cmd->add_option("--from", opt->from,
                    "The direct encoding (`rfd pattern encode`): its encoder's options, white and printer are kept, "
                    "its values are the start")
        ->required();
    cmd->add_option("--out", opt->out, "Optimised pattern file (.exr)")->required();
    cmd->add_option("--lights", opt->lights,
                    "The light directions to fit: sweep (the default: one per node inside a lenslet's cell, each "
                    "weighted by the solid angle it stands for) or a light file (.lp, the field's frame: the lights "
                    "the display will meet, equally weighted; those outside its field of view are left out)");
    cmd->add_option("--spacing", opt->spacing,
                    "Node spacing on the pattern plane, mm: the pattern's unknowns, per lenslet (default 0.1)")
        ->check(positive_number());
    cmd->add_option("--iterations", opt->iterations, "At most this many solver iterations (default 40)")
        ->check(CLI::Range(0, 100000));
    cmd->add_option("--tolerance", opt->tolerance,
                    "Stop when an iteration lowers the objective by less than this fraction (default 1e-5)")
        ->check(CLI::Range(0.0, 1.0));
    cmd->add_option("--rays", opt->rays, "Rays per side of each lenslet's grid, per direction (default 8)")
        ->check(CLI::Range(1, 64));
    cmd->add_option("--core-weight", opt->core_weight,
                    "Design II: also fit the macro-pixels' cores, where no neighbour reaches, this much beside the "
                    "whole cells (default 0: whole cells, the picture at the display's resolution)")
        ->check(CLI::Range(0.0, 1e6));
    add_model_option(*cmd, opt->model);
    add_print_options(*cmd, opt->print);
    cmd->add_option("--crop", opt->crop,
                    "Only fit the cells of lenslets I,J,W,H (from the bottom-left lenslet): a quick trial");
    cmd->add_flag("--unbounded", opt->unbounded,
                  "Drop the printer's bounds (CGLS): the unconstrained optimum, the ceiling; not printable as is");
    cmd->add_option("--report", opt->report,
                    "Also write a folder with the objective and the held-out PSNR against iterations");
    cmd->add_flag("--timings", opt->timings,
                  "With --report: chart against the solver's time, and add its seconds to iterations.csv (a report "
                  "with timings differs from run to run)");
    cmd->add_option("--judge-sweep", opt->judge_sweep,
                    "With --report: the simulator's judgement of the direct and the optimised pattern over this many "
                    "light directions (default 9; 0: none)")
        ->check(CLI::Range(0, 1000));
    cmd->add_option("--chart-every", opt->chart_every, "Held-out PSNR every this many iterations (default 5)")
        ->check(CLI::Range(1, 100000));
    cmd->add_flag("--json", opt->json, "Machine-readable summary on stdout");
    cmd->callback([opt] {
        const auto start = Clock::now();
        auto seconds = [&] { return std::chrono::duration<double>(Clock::now() - start).count(); };
        const optics::Design design = optics::load_design(opt->design);
        const optics::DisplaySimulator simulator(design);
        const print::PrintedTransparency direct = printed_pattern(design, opt->from, opt->print);
        const predict::EncodedField reference(design, opt->from, direct.geometry(), direct.tone().white, opt->field);
        const patterns::Encoder& encoder = reference.encoder();
        const print::ToneMap& tone = direct.tone();
        const optics::Lattice& lattice = encoder.lattice();
        const predict::NodeGrid nodes(lattice, direct.geometry(), opt->spacing);
        std::optional<predict::LensletWindow> fitted;
        if (!opt->crop.empty()) fitted = parse_crop(opt->crop, lattice);

        optics::SimulationOptions options;
        options.rays_per_side = opt->rays;
        options.model = optics::resolve(opt->model, simulator.optics(),
                                        {direct.geometry().dot_x, direct.geometry().dot_y})
                            .model;
        predict::SweepDirections fit_sweep;
        if (opt->lights == "sweep") {
            fit_sweep = predict::sweep_directions(encoder, nodes, false);
        } else {
            const predict::DisplayComparison fov(simulator, direct, encoder, tone);
            for (const relight::LightEntry& light : relight::read_light_file(opt->lights)) {
                const Eigen::Vector3d d = encoder.options().mapping.display_direction(light.direction);
                if (d.z() > 0.0 && fov.inside_field_of_view(d)) fit_sweep.display.push_back(d.normalized());
            }
            if (fit_sweep.display.empty())
                throw InputError(SourceLocation{opt->lights}, "--lights: no light of the file lies inside the display's "
                                                              "field of view (through the pattern's tilt and turn)");
            fit_sweep.weights.assign(fit_sweep.display.size(), 1.0);
        }
        const predict::SweepDirections held_sweep = predict::sweep_directions(encoder, nodes, true);
        if (fit_sweep.display.empty()) throw InputError("--spacing: no node lies inside a lenslet's cell; use a smaller one");

        // A crop follows the light of the lenslets around it that reaches its cells.
        std::optional<predict::LensletWindow> sources;
        predict::DisplayOperator probe(simulator, nodes, {fit_sweep.display.front()}, options);
        if (fitted) sources = fitted->grown(probe.reach_rows() + 1);
        const bool fit_cores = opt->core_weight > 0.0;
        Progress preparing("tracing and targets", 5);
        const predict::DisplayOperator fit_op(simulator, nodes, fit_sweep.display, options, sources, fit_cores);
        preparing.advance();
        const predict::DisplayOperator held_op(simulator, nodes, held_sweep.display, options, sources);
        preparing.advance();
        const std::vector<double> fit_target =
            predict::optimization_targets(fit_op, fit_op.flat_field(), encoder, tone);
        preparing.advance();
        const std::vector<double> held_target =
            predict::optimization_targets(held_op, held_op.flat_field(), encoder, tone);
        preparing.advance();
        const predict::OptimizationProblem problem(fit_op, fit_target, fit_sweep.weights, fitted, opt->core_weight);
        const std::vector<double> u0 = predict::nodes_from_pattern(nodes, direct, tone);
        preparing.finish();
        const double prepare_s = seconds();

        struct ChartPoint {
            int iteration;
            double seconds, objective, fitted_psnr, held_psnr;
        };
        std::vector<ChartPoint> points;
        auto held_mean = [&](std::span<const double> u) {
            return mean_of(predict::direction_psnr(held_op, held_target, u, fitted));
        };
        auto fit_mean = [&](std::span<const double> u) {
            return mean_of(predict::direction_psnr(fit_op, fit_target, u, fitted));
        };
        // A chart point: the solver's time so far (without these evaluations) and the mean PSNR
        // over the fitted and the held-out directions.
        double eval_seconds = 0.0;
        auto record = [&](int it, double f, std::span<const double> u) {
            const double now = seconds() - eval_seconds;
            const auto t0 = Clock::now();
            points.push_back({it, now, f, fit_mean(u), held_mean(u)});
            eval_seconds += std::chrono::duration<double>(Clock::now() - t0).count();
        };
        record(0, std::nan(""), u0);  // f at the start: the solver's first figure, below
        predict::SolverOptions solver;
        solver.iterations = opt->iterations;
        solver.tolerance = opt->tolerance;
        solver.bounded = !opt->unbounded;
        Progress progress("optimizing", static_cast<std::size_t>(opt->iterations));
        solver.on_iteration = [&](int it, double f, std::span<const double> u) {
            progress.advance();
            if (it % opt->chart_every == 0) record(it, f, u);
        };
        const auto solve_start = Clock::now();
        const double start_eval = eval_seconds;
        predict::OptimizationResult result = predict::solve(problem, u0, solver);
        progress.finish();
        points.front().objective = result.objective.front();
        const double solve_s = std::chrono::duration<double>(Clock::now() - solve_start).count() - (eval_seconds - start_eval);
        if (points.back().iteration != result.iterations) record(result.iterations, result.objective.back(), result.u);
        for (double v : result.u)
            if (!std::isfinite(v)) throw Error("the optimiser produced a value that is not a number");

        // The pattern: the encoder's attributes and the optimiser's settings.
        const patterns::PatternFileInfo info = patterns::read_pattern_info(opt->from);
        patterns::PatternAttributes attributes = info.attributes;
        attributes["optimized"] = opt->unbounded ? "unbounded" : "bounded";
        attributes["optimized_from"] = opt->from;
        attributes["optimized_spacing_mm"] = format_number(opt->spacing);
        attributes["optimized_iterations"] = std::to_string(result.iterations);
        attributes["optimized_rays"] = std::to_string(opt->rays);
        attributes["optimized_model"] = std::string(optics::to_string(options.model));
        attributes["optimized_directions"] = std::to_string(fit_sweep.display.size());
        attributes["optimized_lights"] = opt->lights;
        attributes["optimized_brightness"] = format_number(tone.brightness);
        attributes["optimized_core_weight"] = format_number(opt->core_weight);
        if (fitted) attributes["optimized_crop"] = opt->crop;
        std::vector<double> printable = result.u;
        if (opt->unbounded)
            for (double& v : printable) v = std::clamp(v, 0.0, 1.0);
        const predict::NodePattern out_pattern(nodes, std::move(printable), info.channels, tone.white, tone.brightness);
        patterns::write_pattern(opt->out, out_pattern, attributes);

        const ChartPoint& first = points.front();
        const ChartPoint& last = points.back();
        // The simulator's judgement, as simulate compare measures: the print of each pattern.
        struct Judged {
            predict::DirectionComparison direct, optimised;
        };
        std::vector<Judged> judged;
        if (!opt->report.empty() && opt->judge_sweep > 0) {
            const print::PrintedTransparency optimised = printed_pattern(design, opt->out, opt->print);
            const predict::DisplayComparison judge_direct(simulator, direct, encoder, tone);
            const predict::DisplayComparison judge_optimised(simulator, optimised, encoder, optimised.tone());
            optics::SimulationOptions judge;
            judge.model = optics::Model::Exact;
            judge.rays_per_side = judge_direct.core().fraction < 1.0 ? 32 : 16;
            judge.pixels_per_pitch = 16.0;
            const std::vector<Eigen::Vector3d> sweep = judge_direct.sweep(opt->judge_sweep);
            Progress judging("judging", sweep.size());
            for (const Eigen::Vector3d& v : sweep) {
                judged.push_back({judge_direct.compare(v, judge), judge_optimised.compare(v, judge)});
                judging.advance();
            }
        }
        struct Means {
            double direct = 0.0, optimised = 0.0;
            int count = 0;
        };
        Means in_fov, clean_cells;
        for (const Judged& j : judged) {
            if (j.direct.inside_field_of_view) {
                in_fov.direct += j.direct.comparison.psnr_db;
                in_fov.optimised += j.optimised.comparison.psnr_db;
                ++in_fov.count;
            }
            if (j.direct.crosstalk_free) {
                clean_cells.direct += j.direct.cell_comparison.psnr_db;
                clean_cells.optimised += j.optimised.cell_comparison.psnr_db;
                ++clean_cells.count;
            }
        }
        auto mean_db = [](double sum, int count) { return count ? sum / count : std::nan(""); };
        if (!opt->report.empty()) {
            ensure_directory(opt->report);
            const std::filesystem::path dir(opt->report);
            LineChart chart;
            chart.title = "Pattern optimisation: " + design.name;
            chart.x_label = opt->timings ? "solver time (s)" : "iteration";
            chart.y_label = "mean PSNR per direction (dB)";
            chart.y2_label = "objective / objective at the start";
            chart.key_position = "bottom right";
            PlotSeries held{"held-out directions", {}, {}}, fit{"optimised directions", {}, {}},
                objective{"objective", {}, {}, true};
            std::string csv = std::string("iteration,") + (opt->timings ? "seconds," : "") +
                              "objective,fitted_psnr_db,held_out_psnr_db\n";
            for (const ChartPoint& p : points) {
                const double x = opt->timings ? p.seconds - first.seconds : static_cast<double>(p.iteration);
                held.x.push_back(x);
                held.y.push_back(p.held_psnr);
                fit.x.push_back(x);
                fit.y.push_back(p.fitted_psnr);
                objective.x.push_back(x);
                objective.y.push_back(p.objective / first.objective);
                csv += std::to_string(p.iteration) + "," +
                       (opt->timings ? format_fixed(p.seconds - first.seconds, 3) + "," : std::string()) +
                       format_number(p.objective) + "," + format_fixed(p.fitted_psnr, 4) + "," +
                       format_fixed(p.held_psnr, 4) + "\n";
            }
            chart.series = {held, fit, objective};
            write_text_file(dir / "iterations.csv", csv);
            write_line_chart(chart, dir / "convergence");
            if (!judged.empty()) {
                std::string table =
                    "index,display_angle_deg,inside_fov,crosstalk_free,direct_psnr_db,optimized_psnr_db,"
                    "direct_cell_psnr_db,optimized_cell_psnr_db\n";
                std::vector<std::size_t> order(judged.size());
                for (std::size_t k = 0; k < order.size(); ++k) order[k] = k;
                std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
                    return judged[a].direct.display_angle_deg < judged[b].direct.display_angle_deg;
                });
                LineChart angles;
                angles.title = "Direct and optimised pattern, judged by the simulator: " + design.name;
                angles.x_label = "light's angle to the display's axis (degrees)";
                angles.y_label = "PSNR per lenslet (dB)";
                angles.key_position = "bottom left";
                const bool cores = judged.front().direct.core.fraction < 1.0;
                PlotSeries d{cores ? "direct, cores" : "direct", {}, {}}, o{cores ? "optimised, cores" : "optimised", {}, {}},
                    dc{"direct, whole cells", {}, {}}, oc{"optimised, whole cells", {}, {}};
                for (std::size_t k = 0; k < judged.size(); ++k) {
                    const Judged& j = judged[k];
                    table += std::to_string(k) + "," + format_fixed(j.direct.display_angle_deg, 4) + "," +
                             (j.direct.inside_field_of_view ? "1" : "0") + "," + (j.direct.crosstalk_free ? "1" : "0") +
                             "," + format_fixed(j.direct.comparison.psnr_db, 4) + "," +
                             format_fixed(j.optimised.comparison.psnr_db, 4) + "," +
                             format_fixed(j.direct.cell_comparison.psnr_db, 4) + "," +
                             format_fixed(j.optimised.cell_comparison.psnr_db, 4) + "\n";
                }
                for (std::size_t k : order) {
                    const Judged& j = judged[k];
                    const double angle = j.direct.display_angle_deg;
                    d.x.push_back(angle), d.y.push_back(j.direct.comparison.psnr_db);
                    o.x.push_back(angle), o.y.push_back(j.optimised.comparison.psnr_db);
                    dc.x.push_back(angle), dc.y.push_back(j.direct.cell_comparison.psnr_db);
                    oc.x.push_back(angle), oc.y.push_back(j.optimised.cell_comparison.psnr_db);
                }
                angles.series = {d, o};
                if (cores) angles.series.insert(angles.series.end(), {dc, oc});
                write_text_file(dir / "directions.csv", table);
                write_line_chart(angles, dir / "compare");
            }
        }
        if (opt->json) {
            const nlohmann::json summary = {
                {"pattern", opt->out},
                {"from", opt->from},
                {"bounded", !opt->unbounded},
                {"spacing_mm", opt->spacing},
                {"nodes_per_lenslet", {nodes.nodes_x(), nodes.nodes_y()}},
                {"unknowns", nodes.size()},
                {"directions", fit_sweep.display.size()},
                {"held_out_directions", held_sweep.display.size()},
                {"rays_per_side", opt->rays},
                {"model", std::string(optics::to_string(options.model))},
                {"iterations", result.iterations},
                {"converged", result.converged},
                {"objective_start", first.objective},
                {"objective_end", last.objective},
                {"fitted_psnr_start_db", finite_or_null(first.fitted_psnr)},
                {"fitted_psnr_end_db", finite_or_null(last.fitted_psnr)},
                {"held_out_psnr_start_db", finite_or_null(first.held_psnr)},
                {"held_out_psnr_end_db", finite_or_null(last.held_psnr)},
                {"prepare_seconds", prepare_s},
                {"solve_seconds", solve_s},
                {"judged_directions", judged.size()},
                {"judged_in_fov_psnr_direct_db", finite_or_null(mean_db(in_fov.direct, in_fov.count))},
                {"judged_in_fov_psnr_optimized_db", finite_or_null(mean_db(in_fov.optimised, in_fov.count))},
                {"judged_crosstalk_free_cell_psnr_direct_db", finite_or_null(mean_db(clean_cells.direct, clean_cells.count))},
                {"judged_crosstalk_free_cell_psnr_optimized_db", finite_or_null(mean_db(clean_cells.optimised, clean_cells.count))},
            };
            std::printf("%s\n", summary.dump(2).c_str());
            return;
        }
        std::printf("pattern %s: optimised from %s (%s)\n", opt->out.c_str(), opt->from.c_str(),
                    opt->unbounded ? "unbounded: the ceiling, clamped to print" : "within the printer's range");
        std::printf("  unknowns          %d x %d nodes per lenslet, %.3g mm apart: %zu values\n", nodes.nodes_x(),
                    nodes.nodes_y(), opt->spacing, nodes.size());
        std::printf("  directions        %zu optimised, %zu held out (in between), %d rays per side, %s model\n",
                    fit_sweep.display.size(), held_sweep.display.size(), opt->rays,
                    std::string(optics::to_string(options.model)).c_str());
        std::printf("  objective         %.6g -> %.6g in %d iterations%s\n", first.objective, last.objective,
                    result.iterations, result.converged ? " (converged)" : "");
        std::printf("  mean PSNR         optimised directions %.2f -> %.2f dB, held out %.2f -> %.2f dB\n",
                    first.fitted_psnr, last.fitted_psnr, first.held_psnr, last.held_psnr);
        std::printf("  time              %.1f s to prepare, %.1f s to solve\n", prepare_s, solve_s);
        if (!judged.empty())
            std::printf("  judged            mean PSNR inside the field of view %.2f dB direct, %.2f dB optimised "
                        "(%d of %zu directions); whole cells in the crosstalk-free cone %.2f -> %.2f dB\n",
                        mean_db(in_fov.direct, in_fov.count), mean_db(in_fov.optimised, in_fov.count), in_fov.count,
                        judged.size(), mean_db(clean_cells.direct, clean_cells.count),
                        mean_db(clean_cells.optimised, clean_cells.count));
    });
}

}  // namespace rfd::cli
