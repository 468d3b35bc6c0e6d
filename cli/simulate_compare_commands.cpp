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
#include "predict/summaries.hpp"
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
std::string optional_text(const std::optional<double>& value) {
    return value ? format_fixed(*value, 4) : std::string();
}

// directions.csv: summary.json's directions as a table (no times: byte-identical reruns).
std::string directions_csv(const predict::CompareSummary& summary) {
    std::string csv = "index,field_theta_deg,field_phi_deg,display_angle_deg,inside_fov,crosstalk_free,efficiency,"
                      "peak,mse,psnr_db,psnr_own_peak_db,fitted_gain,psnr_fitted_db,psnr_cell_db\n";
    for (std::size_t k = 0; k < summary.directions.size(); ++k) {
        const predict::CompareDirection& d = summary.directions[k];
        csv += std::to_string(k) + "," + format_fixed(d.field_theta_deg, 4) + "," + format_fixed(d.field_phi_deg, 4) +
               "," + format_fixed(d.display_angle_deg, 4) + "," + (d.inside_fov ? "1" : "0") + "," +
               (d.crosstalk_free ? "1" : "0") + "," + format_number(d.efficiency) + "," + format_number(d.peak) + "," +
               format_number(d.mse) + "," + optional_text(d.psnr_db) + "," + optional_text(d.psnr_own_peak_db) + "," +
               format_number(d.fitted_gain) + "," + optional_text(d.psnr_fitted_db) + "," +
               optional_text(d.psnr_cell_db) + "\n";
    }
    return csv;
}

// PSNR against the light's angle from the display's axis, inside and outside the FOV.
LineChart psnr_chart(const predict::CompareSummary& summary, bool cores) {
    std::vector<const predict::CompareDirection*> order;
    for (const auto& d : summary.directions) order.push_back(&d);
    std::stable_sort(order.begin(), order.end(),
                     [](const auto* a, const auto* b) { return a->display_angle_deg < b->display_angle_deg; });
    LineChart chart;
    chart.title = "Predicted output against software relighting: " + summary.design;
    chart.x_label = "light's angle to the display's axis (degrees)";
    chart.y_label = "PSNR against the field's brightest (dB)";
    chart.key_position = "bottom left";
    PlotSeries clean{"crosstalk-free", {}, {}}, crosstalk{"inside the FOV, with crosstalk", {}, {}},
        outside{"outside the FOV (wrap-over)", {}, {}}, cells{"over whole cells", {}, {}};
    const auto value = [](const std::optional<double>& v) { return v.value_or(std::nan("")); };
    for (const predict::CompareDirection* d : order) {
        PlotSeries& zone = d->crosstalk_free ? clean : d->inside_fov ? crosstalk : outside;
        zone.x.push_back(d->display_angle_deg);
        zone.y.push_back(value(d->psnr_db));
        if (cores) {
            cells.x.push_back(d->display_angle_deg);
            cells.y.push_back(value(d->psnr_cell_db));
        }
    }
    for (PlotSeries* series : {&clean, &crosstalk, &outside, &cells})
        if (!series->x.empty()) chart.series.push_back(*series);
    return chart;
}

std::optional<double> finite(double value) {
    return std::isfinite(value) ? std::optional<double>(value) : std::nullopt;
}

// One accuracy point as summary.json records it; `angles` are its directions' angles.
predict::AccuracyRecord accuracy_record(const predict::AccuracyPoint& p, const std::vector<double>& angles) {
    predict::AccuracyRecord record{p.label, p.rays_per_side, static_cast<long long>(p.rays), p.seconds, p.mse,
                                   finite(p.psnr_db), finite(p.worst_psnr_db), finite(p.fitted_psnr_db), {}};
    for (std::size_t k = 0; k < p.psnr_per_direction_db.size() && k < angles.size(); ++k)
        record.per_direction.push_back(
            {angles[k], finite(p.psnr_per_direction_db[k]), finite(p.fitted_psnr_per_direction_db[k])});
    return record;
}

std::string accuracy_csv(const std::vector<predict::AccuracyPoint>& points) {
    std::string table = "model,rays_per_side,rays,seconds,mse,psnr_db,worst_psnr_db,fitted_psnr_db\n";
    for (const auto& p : points)
        table += p.label + "," + std::to_string(p.rays_per_side) + "," + std::to_string(p.rays) + "," +
                 format_fixed(p.seconds, 5) + "," + format_number(p.mse) + "," + format_fixed(p.psnr_db, 4) + "," +
                 format_fixed(p.worst_psnr_db, 4) + "," + format_fixed(p.fitted_psnr_db, 4) + "\n";
    return table;
}

LineChart accuracy_chart(const std::string& design, const std::vector<predict::AccuracyModel>& models,
                         const std::vector<predict::AccuracyPoint>& points, std::size_t directions, int reference_rays) {
    LineChart speed;
    speed.title = "Simulator speed against accuracy: " + design;
    speed.x_label = "simulation time over " + std::to_string(directions) + " directions in the field of view (s)";
    speed.y_label = "PSNR per lenslet against exact, " + std::to_string(reference_rays) + " rays per side (dB)";
    speed.key_position = "bottom right";
    for (const auto& model : models) {
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
    return speed;
}

void print_comparison(const std::string& out, const predict::CompareSummary& s,
                      const std::vector<predict::AccuracyPoint>& points, int reference_rays) {
    const auto db = [](const std::optional<double>& v) { return v ? format_fixed(*v, 2) : std::string("-"); };
    std::printf("%s: '%s' predicted against the relit field at %d x %d lenslets (model %s, %d rays per side)\n",
                out.c_str(), s.design.c_str(), s.lenslets[0], s.lenslets[1], s.model.c_str(), s.rays_per_side);
    if (s.core_fraction < 1.0)
        std::printf("  macro-pixels %.3fx their cells: PSNR over each cell's core (%.0f %% of its width), "
                    "\"cell\" over whole cells\n",
                    s.core_magnification, 100.0 * s.core_fraction);
    std::printf("  PSNR against the field's brightest value, %s\n", format_number(s.field_peak).c_str());
    std::printf("  %-5s %8s %8s %8s %9s %8s %9s %9s %9s %9s\n", "light", "theta", "phi", "angle", "fov", "eta",
                "PSNR dB", "own peak", "fitted dB", "cell dB");
    for (std::size_t k = 0; k < s.directions.size(); ++k) {
        const predict::CompareDirection& d = s.directions[k];
        std::printf("  %-5zu %8.2f %8.2f %8.2f %9s %8.4f %9s %9s %9s %9s\n", k, d.field_theta_deg, d.field_phi_deg,
                    d.display_angle_deg, d.crosstalk_free ? "in" : d.inside_fov ? "crosstalk" : "out", d.efficiency,
                    db(d.psnr_db).c_str(), db(d.psnr_own_peak_db).c_str(), db(d.psnr_fitted_db).c_str(),
                    db(d.psnr_cell_db).c_str());
    }
    const std::size_t count = s.directions.size();
    if (s.crosstalk_free.count)
        std::printf("  crosstalk-free (%d of %zu): PSNR min %s dB, mean %s dB (cells: min %s dB)\n",
                    s.crosstalk_free.count, count, db(s.crosstalk_free.min_psnr_db).c_str(),
                    db(s.crosstalk_free.mean_psnr_db).c_str(), db(s.crosstalk_free.min_psnr_cell_db).c_str());
    if (s.in_fov.count)
        std::printf("  inside the field of view (%d of %zu): PSNR min %s dB, mean %s dB (fitted gain: min %s, "
                    "mean %s; cells: min %s dB)\n",
                    s.in_fov.count, count, db(s.in_fov.min_psnr_db).c_str(), db(s.in_fov.mean_psnr_db).c_str(),
                    db(s.in_fov.min_psnr_fitted_db).c_str(), db(s.in_fov.mean_psnr_fitted_db).c_str(),
                    db(s.in_fov.min_psnr_cell_db).c_str());
    else
        std::printf("  no direction inside the field of view\n");
    if (!points.empty()) {
        std::printf("  speed against accuracy over %zu directions (reference: exact, %d rays per side):\n",
                    s.accuracy_directions, reference_rays);
        std::printf("  %-16s %6s %10s %10s %9s %9s %10s\n", "model", "rays", "traced", "seconds", "PSNR dB", "worst dB",
                    "fitted dB");
        for (const auto& p : points)
            std::printf("  %-16s %6d %10zu %10.4f %9.2f %9.2f %10.2f\n", p.label.c_str(), p.rays_per_side, p.rays,
                        p.seconds, p.psnr_db, p.worst_psnr_db, p.fitted_psnr_db);
    }
}

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
        std::vector<std::string> images;
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
            images.push_back(std::string(stem) + ".png");
        }
        predict::CompareSummary summary = predict::summarise_comparison(results, images);
        summary.design = design.name;
        summary.pattern = opt->pattern;
        summary.field = opt->field;
        summary.model = std::string(optics::to_string(options.model));
        summary.model_choice = std::string(name_of(optics::kModelChoiceNames, opt->model));
        summary.paraxial_error_dots = choice.paraxial_error_dots;
        summary.rays_per_side = options.rays_per_side;
        summary.lenslets = {count_x, encoder.lattice().count_y()};
        summary.display_range_deg = radians_to_degrees(encoder.display_range().max_angle_rad);
        write_text_file(out / "directions.csv", directions_csv(summary));
        // Every direction's panels on one page, in the order of directions.csv.
        write_image(out / "contact_sheet.png", tiled(panels, 3, 4, 1.0f));

        std::vector<predict::AccuracyPoint> points;
        if (opt->chart_accuracy) {
            // Inside the field of view, where a model's error matters (all when none is).
            std::vector<Eigen::Vector3d> display_directions;
            for (const auto& r : results)
                if (r.inside_field_of_view) display_directions.push_back(r.display_direction);
            if (display_directions.empty())
                for (const auto& r : results) display_directions.push_back(r.display_direction);
            summary.accuracy_directions = display_directions.size();
            points = predict::accuracy_sweep(simulator, pattern, display_directions, accuracy_models, accuracy_rays,
                                              opt->reference_rays, options);
            std::vector<double> angles;
            for (const auto& r : results)
                if (r.inside_field_of_view || summary.accuracy_directions == results.size())
                    angles.push_back(r.display_angle_deg);
            for (const auto& p : points) summary.accuracy.push_back(accuracy_record(p, angles));
            write_text_file(out / "accuracy_points.csv", accuracy_csv(points));
        }
        predict::write_summary(out / "summary.json", summary);
        // Charts last: a missing gnuplot still leaves every number on disk.
        write_line_chart(psnr_chart(summary, comparison.core().fraction < 1.0), out / "psnr");
        if (opt->chart_accuracy)
            write_line_chart(accuracy_chart(design.name, accuracy_models, points, summary.accuracy_directions,
                                            opt->reference_rays),
                             out / "accuracy");

        if (opt->json) {
            std::printf("%s", predict::summary_text(summary).c_str());
            return;
        }
        print_comparison(opt->out, summary, points, opt->reference_rays);
        const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        std::printf("  time         %.2f s\n", seconds);
    });
}

}  // namespace rfd::cli
