// rfd simulate compare: the predicted display output beside the software relighting of the
// same field at the display's resolution (predict/compare.hpp), for a sweep of light
// directions; and the simulator's speed-versus-accuracy chart.

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "cli/arguments.hpp"
#include "cli/commands.hpp"
#include "core/error.hpp"
#include "core/files.hpp"
#include "core/image_io.hpp"
#include "core/plot.hpp"
#include "core/progress.hpp"
#include "core/sphere.hpp"
#include "core/units.hpp"
#include "optics/display.hpp"
#include "predict/compare.hpp"
#include "patterns/encode.hpp"
#include "print/printed.hpp"
#include "core/text.hpp"

namespace rfd::cli {
namespace {

std::vector<int> parse_ray_counts(const std::string& text) {
    std::vector<int> counts;
    std::stringstream in(text);
    std::string item;
    while (std::getline(in, item, ',')) {
        std::size_t used = 0;
        int value = 0;
        try {
            value = std::stoi(item, &used);
        } catch (const std::exception&) {
            used = 0;
        }
        if (used != item.size() || value < 1 || value > 256)
            throw InputError("--accuracy-rays: expected ray counts per side in [1, 256] separated by commas, got '" +
                             text + "'");
        counts.push_back(value);
    }
    if (counts.empty()) throw InputError("--accuracy-rays: expected at least one ray count");
    return counts;
}

// Min and mean PSNR over the directions a predicate keeps.
struct Stats {
    int count = 0;
    double min = std::numeric_limits<double>::infinity(), sum = 0.0;
    void add(double value) {
        ++count;
        min = std::min(min, value);
        sum += value;
    }
    double mean() const { return count ? sum / count : std::nan(""); }
};

}  // namespace

void add_simulate_compare_command(CLI::App& simulate) {
    auto* cmd = simulate.add_subcommand(
        "compare", "Predicted display output beside the software relighting of the same field, at the display's "
                   "resolution, with PSNR and error maps, for a sweep of light directions (Designs I and II)");
    struct Options {
        PrintOptions print;
        std::string design, pattern, field, out, models = "paraxial,exact,auto", accuracy_rays = "2,4,8,16";
        optics::ModelChoice model = optics::ModelChoice::Auto;
        std::vector<std::string> lights;
        predict::LightFrame frame = predict::LightFrame::Display;
        double pixels_per_lenslet = 16.0;
        int sweep = 9, rays = 0, reference_rays = 32, view_pixels = 0;
        double tolerance_dots = 0.25, error_gain = 4.0;
        bool json = false, chart_accuracy = false;
    };
    auto opt = std::make_shared<Options>();
    cmd->add_option("DESIGN", opt->design, "Design TOML file (Design I or II)")->required();
    cmd->add_option("PATTERN", opt->pattern, "Pattern file from `rfd pattern encode`")->required();
    cmd->add_option("FIELD", opt->field, "The reflectance field the pattern was encoded from (folder or .lp)")->required();
    cmd->add_option("--out", opt->out, "Output folder")->required();
    cmd->add_option("--light", opt->lights,
                    "Also compare under a white light from THETA,PHI (degrees, in the frame --frame names, default "
                    "the display's: 0,0 is straight behind it); repeat for several");
    add_frame_option(*cmd, opt->frame);
    cmd->add_option("--sweep", opt->sweep,
                    "Light directions spread over the display's range, the first on its axis (default 9; 0: only --light)")
        ->check(CLI::Range(0, 1000));
    add_model_option(*cmd, opt->model);
    cmd->add_option("--tolerance", opt->tolerance_dots,
                    "auto: largest paraxial error on the pattern plane, in print dots (default 0.25)")
        ->check(positive_number());
    cmd->add_option("--rays", opt->rays,
                    "Rays per side of each lenslet's grid (default 32 where macro-pixel cores are compared, "
                    "Design II; 8 otherwise)")
        ->check(CLI::Range(1, 256));
    cmd->add_option("--pixels-per-lenslet", opt->pixels_per_lenslet,
                    "Diffuser pixels per lenslet pitch in the simulation (default 16)")
        ->check(CLI::Range(4.0, 64.0));
    add_print_options(*cmd, opt->print);
    cmd->add_option("--view-pixels", opt->view_pixels,
                    "Pixels per lenslet in the side-by-side PNGs (default: about 240 pixels per panel)")
        ->check(CLI::Range(0, 256));
    cmd->add_option("--error-gain", opt->error_gain, "Error panel of the PNGs: |error| times this (default 4)")
        ->check(positive_number());
    cmd->add_flag("--chart-accuracy", opt->chart_accuracy,
                  "Also the speed-versus-accuracy chart: each of --models at each of --accuracy-rays against a "
                  "converged exact prediction (--reference-rays), simulation time measured in the same run");
    cmd->add_option("--models", opt->models, "Models for --chart-accuracy (default paraxial,exact,auto)");
    cmd->add_option("--accuracy-rays", opt->accuracy_rays, "Rays per side for --chart-accuracy (default 2,4,8,16)");
    cmd->add_option("--reference-rays", opt->reference_rays, "Rays per side of the converged prediction (default 32)")
        ->check(CLI::Range(1, 512));
    cmd->add_flag("--json", opt->json, "Machine-readable summary on stdout (also written to OUT/summary.json)");
    cmd->callback([opt] {
        const auto start = std::chrono::steady_clock::now();
        const optics::Design design = optics::load_design(opt->design);
        const optics::DisplaySimulator simulator(design);
        const print::PrintedTransparency pattern = printed_pattern(design, opt->pattern, opt->print);
        if (opt->sweep == 0 && opt->lights.empty()) throw InputError("--sweep 0 needs at least one --light");
        std::vector<predict::AccuracyModel> accuracy_models;
        std::vector<int> accuracy_rays;
        const Eigen::Vector2d dot_mm(pattern.geometry().dot_x, pattern.geometry().dot_y);
        const optics::ResolvedModel choice = optics::resolve(opt->model, simulator.optics(), dot_mm, opt->tolerance_dots);
        if (opt->chart_accuracy) {
            accuracy_rays = parse_ray_counts(opt->accuracy_rays);
            std::stringstream in(opt->models);
            std::string name;
            while (std::getline(in, name, ',')) {
                const optics::ModelChoice asked =
                    value_of(optics::kModelChoiceNames, name, SourceLocation{"", 0, 0, "--models"});
                const optics::Model model = optics::resolve(asked, simulator.optics(), dot_mm, opt->tolerance_dots).model;
                accuracy_models.push_back({asked == optics::ModelChoice::Auto
                                               ? "auto (" + std::string(optics::to_string(model)) + ")"
                                               : name,
                                           model});
            }
            if (accuracy_models.empty()) throw InputError("--models: expected at least one model");
        }

        // The field as the encoder saw it: same options, same lenslet samples.
        const predict::EncodedField reference(design, opt->pattern, pattern.geometry(), pattern.tone().white, opt->field);
        const patterns::Encoder& encoder = reference.encoder();
        const predict::DisplayComparison comparison(simulator, pattern, encoder, pattern.tone());

        std::vector<Eigen::Vector3d> directions = comparison.sweep(opt->sweep);
        for (const std::string& text : opt->lights) {
            const relight::Light named = parse_light(text);
            const auto* point = std::get_if<relight::DirectionalLight>(&named);
            if (!point || point->irradiance != Eigen::Vector3d::Ones())
                throw InputError("--light " + text + ": compare takes point lights of white light (THETA,PHI)");
            // Compared in the field's frame: a display-frame light is the field light it shows.
            const relight::Light light = predict::light_in_field_frame(named, opt->frame, encoder.options().mapping);
            directions.push_back(std::get<relight::DirectionalLight>(light).direction.normalized());
        }

        optics::SimulationOptions options;
        // A core's mean needs many rays (8 per side alias against the pixels: +-10 dB);
        // whole cells are within a dB at 8 (Design I, tests/test_compare.cpp).
        options.rays_per_side = opt->rays > 0 ? opt->rays : comparison.core().fraction < 1.0 ? 32 : 8;
        options.pixels_per_pitch = opt->pixels_per_lenslet;
        options.model = choice.model;
        const int count_x = encoder.lattice().count_x();
        const int view_pixels = opt->view_pixels > 0 ? opt->view_pixels : std::max(1, 240 / std::max(count_x, 1));

        std::vector<predict::DirectionComparison> results;
        {
            Progress progress("comparing", directions.size());
            for (const Eigen::Vector3d& v : directions) {
                results.push_back(comparison.compare(v, options));
                progress.advance();
            }
        }
        // Everything computed: now the files (no half-written folder on a refused input).
        ensure_directory(opt->out);
        const std::filesystem::path out(opt->out);
        nlohmann::json rows = nlohmann::json::array();
        std::string csv = "index,field_theta_deg,field_phi_deg,display_angle_deg,inside_fov,crosstalk_free,efficiency,"
                          "peak,mse,psnr_db,fitted_gain,psnr_fitted_db,psnr_cell_db\n";
        Stats fov, fov_fitted, fov_cell, clean, clean_cell;
        std::vector<Image> panels;  // prediction | reference | error, per direction
        for (std::size_t k = 0; k < results.size(); ++k) {
            const predict::DirectionComparison& r = results[k];
            char stem[32];
            std::snprintf(stem, sizeof stem, "light_%02zu", k);
            write_image(out / (std::string(stem) + "_prediction.exr"), r.prediction);
            write_image(out / (std::string(stem) + "_reference.exr"), r.reference);
            write_image(out / (std::string(stem) + "_error.exr"), r.comparison.error);
            panels.push_back(predict::side_by_side(r, view_pixels, opt->error_gain));
            write_image(out / (std::string(stem) + ".png"), panels.back());
            const SphericalAngles a = angles_of(r.field_direction);
            const double theta = radians_to_degrees(a.theta), phi = radians_to_degrees(a.phi);
            if (r.inside_field_of_view) {
                fov.add(r.comparison.psnr_db);
                fov_fitted.add(r.comparison.psnr_fitted_db);
                fov_cell.add(r.cell_comparison.psnr_db);
            }
            if (r.crosstalk_free) {
                clean.add(r.comparison.psnr_db);
                clean_cell.add(r.cell_comparison.psnr_db);
            }
            rows.push_back({{"image", std::string(stem) + ".png"},
                            {"field_theta_deg", theta},
                            {"field_phi_deg", phi},
                            {"display_angle_deg", r.display_angle_deg},
                            {"inside_fov", r.inside_field_of_view},
                            {"crosstalk_free", r.crosstalk_free},
                            {"efficiency", r.efficiency},
                            {"peak", r.comparison.peak},
                            {"mse", r.comparison.mse},
                            {"psnr_db", finite_or_null(r.comparison.psnr_db)},
                            {"fitted_gain", r.comparison.fitted_gain},
                            {"psnr_fitted_db", finite_or_null(r.comparison.psnr_fitted_db)},
                            {"psnr_cell_db", finite_or_null(r.cell_comparison.psnr_db)},
                            {"rays", r.rays}});
            csv += std::to_string(k) + "," + format_fixed(theta, 4) + "," + format_fixed(phi, 4) + "," +
                   format_fixed(r.display_angle_deg, 4) + "," + (r.inside_field_of_view ? "1" : "0") + "," +
                   (r.crosstalk_free ? "1" : "0") + "," +
                   format_number(r.efficiency) + "," + format_number(r.comparison.peak) + "," +
                   format_number(r.comparison.mse) + "," + format_fixed(r.comparison.psnr_db, 4) + "," +
                   format_number(r.comparison.fitted_gain) + "," + format_fixed(r.comparison.psnr_fitted_db, 4) + "," +
                   format_fixed(r.cell_comparison.psnr_db, 4) + "\n";  // no times: byte-identical reruns
        }
        write_text_file(out / "directions.csv", csv);
        // Every direction's panels on one page, in the order of directions.csv.
        write_image(out / "contact_sheet.png", tiled(panels, 3, 4, 1.0f));

        // PSNR against the light's angle from the display's axis, inside and outside the FOV.
        std::vector<std::size_t> order(results.size());
        for (std::size_t k = 0; k < order.size(); ++k) order[k] = k;
        std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
            return results[a].display_angle_deg < results[b].display_angle_deg;
        });
        LineChart chart;
        chart.title = "Predicted output against software relighting: " + design.name;
        chart.x_label = "light's angle to the display's axis (degrees)";
        chart.y_label = "PSNR per lenslet (dB)";
        chart.key_position = "bottom left";
        PlotSeries all{"PSNR", {}, {}}, clean_series{"crosstalk-free", {}, {}},
            crosstalk{"inside the FOV, with crosstalk", {}, {}}, outside{"outside the FOV (wrap-over)", {}, {}},
            cells{"over whole cells", {}, {}};
        auto finite = [](double v) { return std::isfinite(v) ? v : std::nan(""); };
        for (std::size_t k : order) {
            const auto& r = results[k];
            all.x.push_back(r.display_angle_deg);
            all.y.push_back(finite(r.comparison.psnr_db));
            PlotSeries& zone = r.crosstalk_free ? clean_series : r.inside_field_of_view ? crosstalk : outside;
            zone.x.push_back(r.display_angle_deg);
            zone.y.push_back(finite(r.comparison.psnr_db));
            if (comparison.core().fraction < 1.0) {
                cells.x.push_back(r.display_angle_deg);
                cells.y.push_back(finite(r.cell_comparison.psnr_db));
            }
        }
        for (PlotSeries* series : {&clean_series, &crosstalk, &outside, &cells})
            if (!series->x.empty()) chart.series.push_back(*series);

        nlohmann::json accuracy = nlohmann::json::array();
        std::vector<predict::AccuracyPoint> points;
        std::size_t accuracy_directions = 0;
        if (opt->chart_accuracy) {
            // Inside the field of view, where a model's error matters (all when none is).
            std::vector<Eigen::Vector3d> display_directions;
            for (const auto& r : results)
                if (r.inside_field_of_view) display_directions.push_back(r.display_direction);
            if (display_directions.empty())
                for (const auto& r : results) display_directions.push_back(r.display_direction);
            accuracy_directions = display_directions.size();
            points = predict::accuracy_sweep(simulator, pattern, display_directions, accuracy_models, accuracy_rays,
                                              opt->reference_rays, options);
        }
        // Charts last: a missing gnuplot still leaves every number on disk.
        std::string table = "model,rays_per_side,rays,seconds,mse,psnr_db,worst_psnr_db,fitted_psnr_db\n";
        for (const auto& p : points) {
            table += p.label + "," + std::to_string(p.rays_per_side) + "," + std::to_string(p.rays) + "," +
                     format_fixed(p.seconds, 5) + "," + format_number(p.mse) + "," + format_fixed(p.psnr_db, 4) + "," +
                     format_fixed(p.worst_psnr_db, 4) + "," + format_fixed(p.fitted_psnr_db, 4) + "\n";
            nlohmann::json per_direction = nlohmann::json::array();
            std::vector<const predict::DirectionComparison*> used;
            for (const auto& r : results)
                if (r.inside_field_of_view || accuracy_directions == results.size()) used.push_back(&r);
            for (std::size_t k = 0; k < p.psnr_per_direction_db.size(); ++k)
                per_direction.push_back({{"display_angle_deg", used[k]->display_angle_deg},
                                         {"psnr_db", finite_or_null(p.psnr_per_direction_db[k])},
                                         {"fitted_psnr_db", finite_or_null(p.fitted_psnr_per_direction_db[k])}});
            accuracy.push_back({{"model", p.label},
                                {"rays_per_side", p.rays_per_side},
                                {"rays", p.rays},
                                {"seconds", p.seconds},
                                {"mse", p.mse},
                                {"psnr_db", finite_or_null(p.psnr_db)},
                                {"worst_psnr_db", finite_or_null(p.worst_psnr_db)},
                                {"fitted_psnr_db", finite_or_null(p.fitted_psnr_db)},
                                {"per_direction", per_direction}});
        }
        if (opt->chart_accuracy) write_text_file(out / "accuracy_points.csv", table);

        const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        const nlohmann::json summary = {
            {"design", design.name},
            {"pattern", opt->pattern},
            {"field", opt->field},
            {"out", opt->out},
            {"model", std::string(optics::to_string(options.model))},
            {"model_choice", std::string(name_of(optics::kModelChoiceNames, opt->model))},
            {"paraxial_error_dots", json_or_null(choice.paraxial_error_dots)},
            {"rays_per_side", options.rays_per_side},
            {"lenslets", {count_x, encoder.lattice().count_y()}},
            {"display_range_deg", radians_to_degrees(encoder.display_range().max_angle_rad)},
            {"peak", "largest reference value per direction"},
            {"reference_scale", "the display's simulated response to a clear print under the same light (not fitted)"},
            {"directions", rows},
            {"macro_pixel_core", {{"fraction", comparison.core().fraction},
                                  {"magnification", comparison.core().magnification}}},
            {"inside_fov", fov.count},
            {"min_psnr_in_fov_db", fov.count ? finite_or_null(fov.min) : nlohmann::json(nullptr)},
            {"mean_psnr_in_fov_db", fov.count ? finite_or_null(fov.mean()) : nlohmann::json(nullptr)},
            {"min_psnr_fitted_in_fov_db", fov.count ? finite_or_null(fov_fitted.min) : nlohmann::json(nullptr)},
            {"mean_psnr_fitted_in_fov_db", fov.count ? finite_or_null(fov_fitted.mean()) : nlohmann::json(nullptr)},
            {"min_psnr_cell_in_fov_db", fov.count ? finite_or_null(fov_cell.min) : nlohmann::json(nullptr)},
            {"crosstalk_free", clean.count},
            {"min_psnr_crosstalk_free_db", clean.count ? finite_or_null(clean.min) : nlohmann::json(nullptr)},
            {"mean_psnr_crosstalk_free_db", clean.count ? finite_or_null(clean.mean()) : nlohmann::json(nullptr)},
            {"min_psnr_cell_crosstalk_free_db", clean.count ? finite_or_null(clean_cell.min) : nlohmann::json(nullptr)},
            {"accuracy_directions", accuracy_directions},
            {"accuracy", accuracy}};
        write_text_file(out / "summary.json", summary.dump(2) + "\n");
        write_line_chart(chart, out / "psnr");
        if (opt->chart_accuracy) {
            LineChart speed;
            speed.title = "Simulator speed against accuracy: " + design.name;
            speed.x_label = "simulation time over " + std::to_string(accuracy_directions) +
                            " directions in the field of view (s)";
            speed.y_label = "PSNR per lenslet against exact, " + std::to_string(opt->reference_rays) + " rays per side (dB)";
            speed.key_position = "bottom right";
            for (const auto& model : accuracy_models) {
                PlotSeries raw{model.label, {}, {}}, fitted{model.label + ", scale fitted", {}, {}};
                for (const auto& p : points)
                    if (p.label == model.label) {
                        raw.x.push_back(p.seconds);
                        raw.y.push_back(std::isfinite(p.psnr_db) ? p.psnr_db : std::nan(""));
                        fitted.x.push_back(p.seconds);
                        fitted.y.push_back(std::isfinite(p.fitted_psnr_db) ? p.fitted_psnr_db : std::nan(""));
                    }
                speed.series.push_back(raw);
                speed.series.push_back(fitted);
            }
            write_line_chart(speed, out / "accuracy");
        }

        if (opt->json) {
            std::printf("%s\n", summary.dump(2).c_str());
            return;
        }
        std::printf("%s: '%s' predicted against the relit field at %d x %d lenslets (model %s, %d rays per side)\n",
                    opt->out.c_str(), design.name.c_str(), count_x, encoder.lattice().count_y(),
                    std::string(optics::to_string(options.model)).c_str(), options.rays_per_side);
        if (comparison.core().fraction < 1.0)
            std::printf("  macro-pixels %.3fx their cells: PSNR over each cell's core (%.0f %% of its width), "
                        "\"cell\" over whole cells\n",
                        comparison.core().magnification, 100.0 * comparison.core().fraction);
        std::printf("  %-5s %8s %8s %8s %9s %8s %9s %9s %9s\n", "light", "theta", "phi", "angle", "fov", "eta", "PSNR dB",
                    "fitted dB", "cell dB");
        for (std::size_t k = 0; k < results.size(); ++k) {
            const auto& r = results[k];
            const SphericalAngles a = angles_of(r.field_direction);
            std::printf("  %-5zu %8.2f %8.2f %8.2f %9s %8.4f %9.2f %9.2f %9.2f\n", k, radians_to_degrees(a.theta),
                        radians_to_degrees(a.phi), r.display_angle_deg,
                        r.crosstalk_free ? "in" : r.inside_field_of_view ? "crosstalk" : "out", r.efficiency,
                        r.comparison.psnr_db, r.comparison.psnr_fitted_db, r.cell_comparison.psnr_db);
        }
        if (clean.count)
            std::printf("  crosstalk-free (%d of %zu): PSNR min %.2f dB, mean %.2f dB (cells: min %.2f dB)\n", clean.count,
                        results.size(), clean.min, clean.mean(), clean_cell.min);
        if (fov.count)
            std::printf("  inside the field of view (%d of %zu): PSNR min %.2f dB, mean %.2f dB (fitted gain: min %.2f, "
                        "mean %.2f; cells: min %.2f dB)\n",
                        fov.count, results.size(), fov.min, fov.mean(), fov_fitted.min, fov_fitted.mean(), fov_cell.min);
        else
            std::printf("  no direction inside the field of view\n");
        if (!points.empty()) {
            std::printf("  speed against accuracy over %zu directions (reference: exact, %d rays per side):\n",
                        accuracy_directions, opt->reference_rays);
            std::printf("  %-16s %6s %10s %10s %9s %9s %10s\n", "model", "rays", "traced", "seconds", "PSNR dB", "worst dB",
                        "fitted dB");
            for (const auto& p : points)
                std::printf("  %-16s %6d %10zu %10.4f %9.2f %9.2f %10.2f\n", p.label.c_str(), p.rays_per_side, p.rays,
                            p.seconds, p.psnr_db, p.worst_psnr_db, p.fitted_psnr_db);
        }
        std::printf("  time         %.2f s\n", seconds);
    });
}

}  // namespace rfd::cli
