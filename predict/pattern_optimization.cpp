#include "predict/pattern_optimization.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <numeric>
#include <span>

#include "core/json.hpp"
#include "core/csv.hpp"
#include "core/error.hpp"
#include "core/files.hpp"
#include "core/plot.hpp"
#include "core/progress.hpp"
#include "core/text.hpp"
#include "predict/compare.hpp"
#include "predict/display_operator.hpp"
#include "predict/summaries.hpp"
#include "relight/field.hpp"

namespace rfd::predict {
namespace {

using Clock = std::chrono::steady_clock;

// Over the directions with a finite PSNR: a direction whose picture is black (a letter
// field between its letters) or matched exactly says nothing of the others.
double mean_of(const std::vector<double>& values) {
    double sum = 0.0;
    int count = 0;
    for (double v : values)
        if (std::isfinite(v)) sum += v, ++count;
    return count ? sum / count : std::nan("");
}

// The directions to fit: the nodes' own (weighted by the solid angle each stands for), or a
// light file's inside the field of view, equally weighted.
SweepDirections fit_directions(const optics::DisplaySimulator& simulator, const print::PrintedTransparency& direct,
                               const patterns::Encoder& encoder, const NodeGrid& nodes, const std::string& lights) {
    if (lights == "sweep") return sweep_directions(encoder, nodes, false);
    SweepDirections sweep;
    const DisplayComparison fov(simulator, direct, encoder, direct.tone());
    for (const relight::LightEntry& light : relight::read_light_file(lights)) {
        const Eigen::Vector3d d = encoder.options().mapping.display_direction(light.direction);
        if (d.z() > 0.0 && fov.inside_field_of_view(d)) sweep.display.push_back(d.normalized());
    }
    if (sweep.display.empty())
        throw InputError(SourceLocation{lights}, "--lights: no light of the file lies inside the display's "
                                                 "field of view (through the pattern's tilt and turn)");
    sweep.weights.assign(sweep.display.size(), 1.0);
    return sweep;
}

}  // namespace

PatternOptimization optimize_pattern(const optics::DisplaySimulator& simulator, const print::PrintedTransparency& direct,
                                     const patterns::Encoder& encoder, const PatternOptimizationSettings& settings) {
    const auto start = Clock::now();
    const auto seconds = [&] { return std::chrono::duration<double>(Clock::now() - start).count(); };
    const print::ToneMap& tone = direct.tone();
    PatternOptimization run{NodeGrid(encoder.lattice(), direct.geometry(), settings.spacing_mm), {}, {}, {}, 0, 0, 0,
                            false, 0.0, 0.0};
    const NodeGrid& nodes = run.nodes;

    optics::SimulationOptions options;
    options.rays_per_side = settings.rays_per_side;
    // The operator follows rays; the diffraction blur is the judge's (simulate compare), not
    // the optimiser's: where auto would add it, the optimiser still fits the geometric model.
    if (settings.model == optics::ModelChoice::Diffraction)
        throw InputError("--model diffraction: the optimiser's forward model follows rays only; judge its pattern "
                         "with `rfd simulate compare --model diffraction`");
    options.model =
        optics::resolve(settings.model, simulator.optics(), {direct.geometry().dot_x, direct.geometry().dot_y}).model;
    run.model = options.model;
    const SweepDirections fit_sweep = fit_directions(simulator, direct, encoder, nodes, settings.lights);
    const SweepDirections held_sweep = sweep_directions(encoder, nodes, true);
    if (fit_sweep.display.empty()) throw InputError("--spacing: no node lies inside a lenslet's cell; use a smaller one");
    run.directions = fit_sweep.display.size();
    run.held_out_directions = held_sweep.display.size();

    // A crop follows the light of the lenslets around it that reaches its cells.
    const std::optional<LensletWindow>& fitted = settings.crop;
    std::optional<LensletWindow> sources;
    if (fitted) {
        const DisplayOperator probe(simulator, nodes, {fit_sweep.display.front()}, options);
        sources = fitted->grown(probe.reach_rows() + 1);
    }
    Progress preparing("tracing and targets", 5);
    const DisplayOperator fit_op(simulator, nodes, fit_sweep.display, options, sources, settings.core_weight > 0.0);
    preparing.advance();
    const DisplayOperator held_op(simulator, nodes, held_sweep.display, options, sources);
    preparing.advance();
    const std::vector<double> fit_target = optimization_targets(fit_op, fit_op.flat_field(), encoder, tone);
    preparing.advance();
    const std::vector<double> held_target = optimization_targets(held_op, held_op.flat_field(), encoder, tone);
    preparing.advance();
    const OptimizationProblem problem(fit_op, fit_target, fit_sweep.weights, fitted, settings.core_weight);
    const std::vector<double> u0 = nodes_from_pattern(nodes, direct, tone);
    preparing.finish();
    run.prepare_seconds = seconds();

    // A chart point: the solver's time so far (without these evaluations) and the mean PSNR
    // over the fitted and the held-out directions.
    double eval_seconds = 0.0;
    const auto record = [&](int it, double f, std::span<const double> u) {
        const double now = seconds() - eval_seconds;
        const auto t0 = Clock::now();
        run.points.push_back({it, now, f, mean_of(direction_psnr(fit_op, fit_target, u, fitted)),
                              mean_of(direction_psnr(held_op, held_target, u, fitted))});
        eval_seconds += std::chrono::duration<double>(Clock::now() - t0).count();
    };
    record(0, std::nan(""), u0);  // f at the start: the solver's first figure, below
    SolverOptions solver;
    solver.iterations = settings.iterations;
    solver.tolerance = settings.stop_fraction;
    solver.bounded = !settings.unbounded;
    Progress progress("optimizing", static_cast<std::size_t>(settings.iterations));
    solver.on_iteration = [&](int it, double f, std::span<const double> u) {
        progress.advance();
        if (it % settings.chart_every == 0) record(it, f, u);
    };
    const auto solve_start = Clock::now();
    const double start_eval = eval_seconds;
    OptimizationResult result = solve(problem, u0, solver);
    progress.finish();
    run.points.front().objective = result.objective.front();
    run.solve_seconds =
        std::chrono::duration<double>(Clock::now() - solve_start).count() - (eval_seconds - start_eval);
    if (run.points.back().iteration != result.iterations) record(result.iterations, result.objective.back(), result.u);
    for (double v : result.u)
        if (!std::isfinite(v)) throw Error("the optimiser produced a value that is not a number");
    run.u = std::move(result.u);
    run.iterations = result.iterations;
    run.converged = result.converged;
    return run;
}

void write_optimized_pattern(const std::filesystem::path& file, const PatternOptimization& run,
                             const PatternOptimizationSettings& settings, const print::ToneMap& tone) {
    const patterns::PatternFileInfo info = patterns::read_pattern_info(settings.from);
    patterns::PatternAttributes attributes = info.attributes;
    attributes["optimized"] = settings.unbounded ? "unbounded" : "bounded";
    attributes["optimized_from"] = settings.from;
    attributes["optimized_spacing_mm"] = format_number(settings.spacing_mm);
    attributes["optimized_iterations"] = std::to_string(run.iterations);
    attributes["optimized_rays"] = std::to_string(settings.rays_per_side);
    attributes["optimized_model"] = std::string(optics::to_string(run.model));
    attributes["optimized_directions"] = std::to_string(run.directions);
    attributes["optimized_lights"] = settings.lights;
    attributes["optimized_brightness"] = format_number(tone.brightness);
    attributes["optimized_core_weight"] = format_number(settings.core_weight);
    if (settings.crop) attributes["optimized_crop"] = settings.crop_text;
    std::vector<double> printable = run.u;
    if (settings.unbounded)
        for (double& v : printable) v = std::clamp(v, 0.0, 1.0);
    const NodePattern pattern(run.nodes, std::move(printable), info.channels, tone.white, tone.brightness);
    patterns::write_pattern(file.string(), pattern, attributes);
}

std::vector<JudgedDirection> judge_patterns(const optics::DisplaySimulator& simulator,
                                            const print::PrintedTransparency& direct,
                                            const print::PrintedTransparency& optimized,
                                            const patterns::Encoder& encoder, int count) {
    const DisplayComparison judge_direct(simulator, direct, encoder, direct.tone());
    const DisplayComparison judge_optimized(simulator, optimized, encoder, optimized.tone());
    optics::SimulationOptions judge;
    judge.model = optics::Model::Exact;
    judge.rays_per_side = judge_direct.core().fraction < 1.0 ? 32 : 16;
    judge.pixels_per_pitch = 16.0;
    const std::vector<Eigen::Vector3d> sweep = judge_direct.sweep(count);
    std::vector<DirectionComparison> direct_results, optimized_results;
    Progress judging("judging", sweep.size());
    for (const Eigen::Vector3d& v : sweep) {
        direct_results.push_back(judge_direct.compare(v, judge));
        optimized_results.push_back(judge_optimized.compare(v, judge));
        judging.advance();
    }
    // Both patterns are judged against the same reference, and so against one field peak.
    const double field_peak = field_peak_of(direct_results);
    std::vector<JudgedDirection> judged;
    for (std::size_t k = 0; k < sweep.size(); ++k)
        judged.push_back(judge_direction(direct_results[k], optimized_results[k], field_peak));
    return judged;
}

JudgedDirection judge_direction(const DirectionComparison& direct, const DirectionComparison& optimized,
                                double field_peak) {
    const auto psnr = [&](double mse) { return psnr_against_field_db(mse, field_peak).value_or(0.0); };
    return {direct.display_angle_deg, direct.inside_field_of_view, direct.crosstalk_free,
            psnr(direct.comparison.mse), psnr(optimized.comparison.mse),
            psnr(direct.cell_comparison.mse), psnr(optimized.cell_comparison.mse), direct.core.fraction < 1.0};
}

JudgedMeans judged_means(const std::vector<JudgedDirection>& judged) {
    JudgedMeans m;
    for (const JudgedDirection& j : judged) {
        if (j.inside_field_of_view) {
            m.in_fov_direct_db += j.direct_psnr_db;
            m.in_fov_optimized_db += j.optimized_psnr_db;
            ++m.in_fov_count;
        }
        if (j.crosstalk_free) {
            m.clean_cells_direct_db += j.direct_cell_psnr_db;
            m.clean_cells_optimized_db += j.optimized_cell_psnr_db;
            ++m.clean_cells_count;
        }
    }
    const auto mean = [](double& sum, int count) { sum = count ? sum / count : std::nan(""); };
    mean(m.in_fov_direct_db, m.in_fov_count);
    mean(m.in_fov_optimized_db, m.in_fov_count);
    mean(m.clean_cells_direct_db, m.clean_cells_count);
    mean(m.clean_cells_optimized_db, m.clean_cells_count);
    return m;
}

void write_optimization_report(const std::filesystem::path& folder, const std::string& design_name,
                               const PatternOptimization& run, const std::vector<JudgedDirection>& judged,
                               bool timings) {
    ensure_directory(folder);
    const PatternOptimization::Point& first = run.points.front();
    LineChart chart;
    chart.title = "Pattern optimisation: " + design_name;
    chart.x_label = timings ? "solver time (s)" : "iteration";
    chart.y_label = "mean PSNR per direction (dB)";
    chart.y2_label = "objective / objective at the start";
    chart.key_position = "bottom right";
    PlotSeries held{"held-out directions", {}, {}}, fit{"optimised directions", {}, {}},
        objective{"objective", {}, {}, true};
    std::vector<std::string> columns{"iteration"};
    if (timings) columns.push_back("seconds");
    columns.insert(columns.end(), {"objective", "fitted_psnr_db", "held_out_psnr_db"});
    CsvTable iterations(std::move(columns));
    for (const PatternOptimization::Point& p : run.points) {
        const double x = timings ? p.seconds - first.seconds : static_cast<double>(p.iteration);
        held.x.push_back(x), held.y.push_back(p.held_psnr);
        fit.x.push_back(x), fit.y.push_back(p.fitted_psnr);
        objective.x.push_back(x), objective.y.push_back(p.objective / first.objective);
        std::vector<std::string> row{std::to_string(p.iteration)};
        if (timings) row.push_back(format_fixed(p.seconds - first.seconds, 3));
        row.insert(row.end(), {format_number(p.objective), format_fixed(p.fitted_psnr, 4), format_fixed(p.held_psnr, 4)});
        iterations.add_row(std::move(row));
    }
    chart.series = {held, fit, objective};
    iterations.write(folder / "iterations.csv");
    write_line_chart(chart, folder / "convergence");
    if (judged.empty()) return;

    CsvTable table({"index", "display_angle_deg", "inside_fov", "crosstalk_free", "direct_psnr_db",
                    "optimized_psnr_db", "direct_cell_psnr_db", "optimized_cell_psnr_db"});
    for (std::size_t k = 0; k < judged.size(); ++k) {
        const JudgedDirection& j = judged[k];
        table.add_row({std::to_string(k), format_fixed(j.display_angle_deg, 4), csv_flag(j.inside_field_of_view),
                       csv_flag(j.crosstalk_free), format_fixed(j.direct_psnr_db, 4),
                       format_fixed(j.optimized_psnr_db, 4), format_fixed(j.direct_cell_psnr_db, 4),
                       format_fixed(j.optimized_cell_psnr_db, 4)});
    }
    std::vector<std::size_t> order(judged.size());
    std::iota(order.begin(), order.end(), std::size_t{0});
    std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
        return judged[a].display_angle_deg < judged[b].display_angle_deg;
    });
    LineChart angles;
    angles.title = "Direct and optimised pattern, judged by the simulator: " + design_name;
    angles.x_label = "light's angle to the display's axis (degrees)";
    angles.y_label = "PSNR per lenslet (dB)";
    angles.key_position = "bottom left";
    const bool cores = judged.front().cores;
    PlotSeries d{cores ? "direct, cores" : "direct", {}, {}}, o{cores ? "optimised, cores" : "optimised", {}, {}},
        dc{"direct, whole cells", {}, {}}, oc{"optimised, whole cells", {}, {}};
    for (std::size_t k : order) {
        const JudgedDirection& j = judged[k];
        d.x.push_back(j.display_angle_deg), d.y.push_back(j.direct_psnr_db);
        o.x.push_back(j.display_angle_deg), o.y.push_back(j.optimized_psnr_db);
        dc.x.push_back(j.display_angle_deg), dc.y.push_back(j.direct_cell_psnr_db);
        oc.x.push_back(j.display_angle_deg), oc.y.push_back(j.optimized_cell_psnr_db);
    }
    angles.series = {d, o};
    if (cores) angles.series.insert(angles.series.end(), {dc, oc});
    table.write(folder / "directions.csv");
    write_line_chart(angles, folder / "compare");
}

nlohmann::json optimization_json(const PatternOptimization& run, const PatternOptimizationSettings& settings,
                                 const std::string& out, const std::vector<JudgedDirection>& judged) {
    const PatternOptimization::Point& first = run.points.front();
    const PatternOptimization::Point& last = run.points.back();
    const JudgedMeans m = judged_means(judged);
    return {
        {"pattern", out},
        {"from", settings.from},
        {"bounded", !settings.unbounded},
        {"spacing_mm", settings.spacing_mm},
        {"nodes_per_lenslet", {run.nodes.nodes_x(), run.nodes.nodes_y()}},
        {"unknowns", run.nodes.size()},
        {"directions", run.directions},
        {"held_out_directions", run.held_out_directions},
        {"rays_per_side", settings.rays_per_side},
        {"model", std::string(optics::to_string(run.model))},
        {"iterations", run.iterations},
        {"converged", run.converged},
        {"objective_start", first.objective},
        {"objective_end", last.objective},
        {"fitted_psnr_start_db", finite_or_null(first.fitted_psnr)},
        {"fitted_psnr_end_db", finite_or_null(last.fitted_psnr)},
        {"held_out_psnr_start_db", finite_or_null(first.held_psnr)},
        {"held_out_psnr_end_db", finite_or_null(last.held_psnr)},
        {"prepare_seconds", run.prepare_seconds},
        {"solve_seconds", run.solve_seconds},
        {"judged_directions", judged.size()},
        {"judged_in_fov_psnr_direct_db", finite_or_null(m.in_fov_direct_db)},
        {"judged_in_fov_psnr_optimized_db", finite_or_null(m.in_fov_optimized_db)},
        {"judged_crosstalk_free_cell_psnr_direct_db", finite_or_null(m.clean_cells_direct_db)},
        {"judged_crosstalk_free_cell_psnr_optimized_db", finite_or_null(m.clean_cells_optimized_db)},
    };
}

std::string optimization_text(const PatternOptimization& run, const PatternOptimizationSettings& settings,
                              const std::string& out, const std::vector<JudgedDirection>& judged) {
    const PatternOptimization::Point& first = run.points.front();
    const PatternOptimization::Point& last = run.points.back();
    std::string text;
    text += format_text("pattern %s: optimised from %s (%s)\n", out.c_str(), settings.from.c_str(),
         settings.unbounded ? "unbounded: the ceiling, clamped to print" : "within the printer's range");
    text += format_text("  unknowns          %d x %d nodes per lenslet, %.3g mm apart: %zu values\n", run.nodes.nodes_x(),
         run.nodes.nodes_y(), settings.spacing_mm, run.nodes.size());
    text += format_text("  directions        %zu optimised, %zu held out (in between), %d rays per side, %s model\n", run.directions,
         run.held_out_directions, settings.rays_per_side, std::string(optics::to_string(run.model)).c_str());
    text += format_text("  objective         %.6g -> %.6g in %d iterations%s\n", first.objective, last.objective, run.iterations,
         run.converged ? " (converged)" : "");
    text += format_text("  mean PSNR         optimised directions %.2f -> %.2f dB, held out %.2f -> %.2f dB\n", first.fitted_psnr,
         last.fitted_psnr, first.held_psnr, last.held_psnr);
    text += format_text("  time              %.1f s to prepare, %.1f s to solve\n", run.prepare_seconds, run.solve_seconds);
    if (!judged.empty()) {
        const JudgedMeans m = judged_means(judged);
        text += format_text("  judged            mean PSNR inside the field of view %.2f dB direct, %.2f dB optimised "
             "(%d of %zu directions); whole cells in the crosstalk-free cone %.2f -> %.2f dB\n",
             m.in_fov_direct_db, m.in_fov_optimized_db, m.in_fov_count, judged.size(), m.clean_cells_direct_db,
             m.clean_cells_optimized_db);
    }
    return text;
}

}  // namespace rfd::predict
