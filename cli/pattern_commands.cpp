// rfd pattern encode / field: reflectance fields into print-resolution transparencies
// (thesis 8.4) and the procedural test fields of the thesis's demonstrations.

#include <chrono>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>

#include <nlohmann/json.hpp>

#include "cli/arguments.hpp"
#include "cli/commands.hpp"
#include "core/progress.hpp"
#include "core/error.hpp"
#include "core/files.hpp"
#include "core/sphere.hpp"
#include "core/text.hpp"
#include "optics/design.hpp"
#include "patterns/advice.hpp"
#include "patterns/encode.hpp"
#include "patterns/procedural.hpp"
#include "patterns/raster.hpp"
#include "relight/field.hpp"
#include "relight/light_model.hpp"

namespace rfd::cli {
namespace {

std::pair<double, double> parse_dpi(const std::string& text) {
    double x = 0, y = 0;
    char comma = 0, extra = 0;
    const int read = std::sscanf(text.c_str(), "%lf%c%lf%c", &x, &comma, &y, &extra);
    if (read == 1) y = x;
    if ((read != 1 && (read != 3 || (comma != 'x' && comma != ','))) || !(x > 0) || !(y > 0) || x > 1e5 || y > 1e5)
        throw InputError("--dpi: expected DPI or XDPIxYDPI such as 2880x1440, got '" + text + "'");
    return {x, y};
}

// The resolution to encode at: --printer's (recorded in the pattern), --dpi's, or the
// design's. Both options must agree on the resolution when both are given.
struct EncodingResolution {
    double dpi_x, dpi_y;
    patterns::PatternAttributes printer_record;
};
EncodingResolution encoding_resolution(const optics::Design& design, const std::string& printer_option,
                                       const std::string& dpi_option) {
    EncodingResolution resolution{design.printer.dpi_x.value, design.printer.dpi_y.value, {}};
    if (!printer_option.empty()) {
        const print::PrinterProfile printer = print::load_printer(printer_option);
        resolution = {printer.dpi_x.value, printer.dpi_y.value, print::printer_attributes(printer)};
    }
    if (!dpi_option.empty()) {
        const auto [x, y] = parse_dpi(dpi_option);
        if (!printer_option.empty() && (x != resolution.dpi_x || y != resolution.dpi_y))
            throw InputError("--dpi " + dpi_option + " disagrees with --printer " + printer_option + " (" +
                             format_number(resolution.dpi_x) + " x " + format_number(resolution.dpi_y) +
                             " dpi): give one of them");
        resolution.dpi_x = x;
        resolution.dpi_y = y;
    }
    return resolution;
}

// --basis: sets options.interpolation, or options.light_model and replaces `field` by what
// it predicts (patterns::apply_light_model); says what it chose and why.
std::string predict_between_lights(const std::string& basis, relight::ReflectanceField& field,
                                   patterns::EncodeOptions& options) {
    const std::string interpolation(name_of(relight::kInterpolationNames, options.interpolation));
    if (basis.empty()) return interpolation + " interpolation";
    std::string why;
    relight::LightModel model;
    const relight::FieldGram gram = relight::field_gram(field);
    if (basis == "auto") {
        const relight::ModelChoice choice = relight::choose_light_model(gram, field.directions, relight::light_model_names());
        model = choice.model;
        why = " (least leave-one-out error of";
        for (std::size_t c = 0; c < choice.candidates.size(); ++c)
            why += (c == 0 ? " " : ", ") + choice.candidates[c].name() + " " + format_number(choice.psnr[c], 4) + " dB";
        why += ", linear PSNR)";
    } else {
        model = relight::parse_light_model(basis);
        if (model.has_sigma()) model.sigma = relight::best_sigma(gram, field.directions, model);
    }
    if (model.kind == relight::LightModel::Kind::Interpolation) {
        options.interpolation = model.interpolation;
        return model.name() + " interpolation" + why;
    }
    options.light_model = model;
    return patterns::apply_light_model(field, options) + ", blended between them" + why;
}

void add_encode_command(CLI::App& pattern) {
    auto* cmd = pattern.add_subcommand("encode", "Encode a reflectance field into a print-resolution pattern (Designs I and II)");
    struct Options {
        std::string design, field, out, dpi, printer, compression = "rle", preview, basis;
        optics::ModelChoice model = optics::ModelChoice::Auto;
        relight::Interpolation interpolation = relight::Interpolation::Delaunay;
        patterns::ImageFit fit = patterns::ImageFit::Cover;
        double tilt = 0, turn = 0, angle_scale = 0, margin = 0;  // add_option sets the defaults
        std::string tilt_text = "0";
        bool allow_partial = false, json = false, single_float = false;
        WindowOptions window;
    };
    auto opt = std::make_shared<Options>();
    cmd->add_option("DESIGN", opt->design, "Design file (designs/design1.toml, design2.toml)")->required();
    cmd->add_option("FIELD", opt->field, "Reflectance field folder or .lp file")->required();
    cmd->add_option("--out", opt->out, "Pattern file: .exr (linear, half float), .tif (16-bit sRGB) or .png")->required();
    add_model_option(*cmd, opt->model);
    add_choice(*cmd, "--interpolation", opt->interpolation, relight::kInterpolationNames,
               "Between light directions: delaunay, solid-angle or nearest");
    cmd->add_option("--basis", opt->basis,
                    "How the field is predicted between its lights, if not by --interpolation: ptm, hsh2, hsh3, hsh4, "
                    "rbf, bilinear (relight/light_model.hpp; the field sampled by it at 4 times its directions, blended between "
                    "them), an interpolation's name, or auto: the one of least leave-one-out error on the field");
    cmd->add_option("--tilt", opt->tilt_text, std::string(patterns::kTiltAutoHelp) + " (degrees)")->capture_default_str();
    add_option(*cmd, patterns::kTurnOption, opt->turn);
    add_option(*cmd, patterns::kAngleScaleOption, opt->angle_scale);
    add_choice(*cmd, "--fit", opt->fit, patterns::kImageFitNames,
               "Field image on the array: cover (crop), contain (letterbox) or stretch");
    cmd->add_option("--printer", opt->printer,
                    "Printer profile to encode for (a file or a bundled name): its resolution, recorded in the "
                    "pattern so simulate and print sheet use it too");
    cmd->add_option("--dpi", opt->dpi, "Printer resolution XDPIxYDPI (default: --printer's, else the design's [printer])");
    add_option(*cmd, patterns::kMarginOption, opt->margin);
    cmd->add_option("--compression", opt->compression, "EXR compression: rle (fast), zips (smaller), none")
        ->check(CLI::IsMember({"none", "rle", "zips", "zip", "piz"}));
    cmd->add_option("--preview", opt->preview, "Also write a screen preview (PNG, 1600 px), scaled to the white");
    cmd->add_flag("--single-float", opt->single_float, "EXR: 32-bit floats instead of half floats (for values above 65504)");
    add_window_options(*cmd, opt->window);
    cmd->add_flag("--allow-partial", opt->allow_partial, "Encode even where the field does not cover the display's range");
    cmd->add_flag("--json", opt->json, "Machine-readable summary on stdout");
    cmd->callback([opt] {
        const optics::Design design = optics::load_design(opt->design);
        patterns::EncodeOptions options;
        const auto [dpi_x, dpi_y, printer_record] = encoding_resolution(design, opt->printer, opt->dpi);
        const patterns::PatternGeometry geometry = patterns::pattern_geometry(design, Dpi{dpi_x}, Dpi{dpi_y}, opt->margin);
        const optics::ResolvedModel choice =
            optics::resolve(opt->model, optics::DesignOptics(design), {geometry.dot_x, geometry.dot_y});
        options.model = choice.model;
        options.interpolation = opt->interpolation;
        options.fit = opt->fit;
        const std::optional<double> tilt = patterns::parse_tilt(opt->tilt_text, "--tilt");
        if (tilt) {
            opt->tilt = *tilt;
        } else {
            const std::vector<Eigen::Vector3d> directions =
                relight::FieldReader(opt->field, opt->window.window()).directions();
            const patterns::TiltChoice best =
                patterns::best_tilt(optics::DesignOptics(design), directions, {0.0, opt->turn, opt->angle_scale});
            opt->tilt = best.tilt_deg;
            Progress::note(format_text("--tilt auto: %g deg, %d of the field's %d lights inside the display's range%s",
                                       best.tilt_deg, best.lights.inside, best.lights.total,
                                       best.lights.covered ? "" : " (they do not surround it)"));
        }
        options.mapping = {opt->tilt, opt->turn, opt->angle_scale};
        options.allow_partial_coverage = opt->allow_partial;
        options.field_name = opt->field;
        options.window = opt->window.window();

        const auto start = std::chrono::steady_clock::now();
        relight::ReflectanceField field = patterns::load_field_for(design, opt->field, options);
        const std::size_t captured = field.size();
        const std::string predictor = predict_between_lights(opt->basis, field, options);
        const patterns::Encoder encoder(design, field, geometry, options);
        const auto prepared = std::chrono::steady_clock::now();
        patterns::WriteOptions write_options;
        write_options.exr_compression = opt->compression;
        write_options.half_float = !opt->single_float;
        patterns::PatternAttributes attributes = encoder.attributes();
        attributes.insert(printer_record.begin(), printer_record.end());
        patterns::write_pattern(opt->out, encoder, attributes, write_options);
        const auto done = std::chrono::steady_clock::now();
        if (!opt->preview.empty()) patterns::write_preview(opt->out, opt->preview, 1600);
        const double prepare_s = std::chrono::duration<double>(prepared - start).count();
        const double write_s = std::chrono::duration<double>(done - prepared).count();
        const double dots = static_cast<double>(geometry.dot_count());
        const double table_error_deg =
            options.model == optics::Model::Exact ? radians_to_degrees(encoder.exact_table_error(200)) : 0.0;
        if (opt->json) {
            const nlohmann::json summary = {
                {"pattern", opt->out},
                {"design", design.name},
                {"width", geometry.width},
                {"height", geometry.height},
                {"dpi", {geometry.dpi_x, geometry.dpi_y}},
                {"printer", printer_record.empty() ? nlohmann::json(nullptr) : nlohmann::json(printer_record.at("printer"))},
                {"size_mm", {geometry.size_mm().x(), geometry.size_mm().y()}},
                {"lenslets", encoder.lattice().count_x() * encoder.lattice().count_y()},
                {"field_directions_used", captured},
                {"predictor", predictor},
                {"predicted_directions", field.size()},
                {"display_half_angle_deg", radians_to_degrees(encoder.display_range().max_angle_rad)},
                {"model", std::string(optics::to_string(options.model))},
                {"paraxial_error_dots", json_or_null(choice.paraxial_error_dots)},
                {"exact_table_error_deg", table_error_deg},
                {"white", encoder.white()},
                {"prepare_seconds", prepare_s},
                {"render_write_seconds", write_s},
                {"dots_per_second", dots / std::max(write_s, 1e-9)},
            };
            std::printf("%s\n", summary.dump(2).c_str());
            return;
        }
        std::printf("pattern %s: %d x %d dots at %g x %g dpi (%.1f x %.1f mm), %d lenslets\n", opt->out.c_str(),
                    geometry.width, geometry.height, geometry.dpi_x, geometry.dpi_y, geometry.size_mm().x(),
                    geometry.size_mm().y(), encoder.lattice().count_x() * encoder.lattice().count_y());
        std::printf("  display range      up to %.1f deg from the axis; %s model (paraxial error up to %.2f dots)",
                    radians_to_degrees(encoder.display_range().max_angle_rad),
                    std::string(optics::to_string(options.model)).c_str(), choice.paraxial_error_dots.value_or(0.0));
        if (options.model == optics::Model::Exact) std::printf(" (table error %.2g deg)", table_error_deg);
        std::printf("\n  field              %zu light direction(s) used, tilt %g deg, turn %g deg, angle scale %g\n",
                    captured, opt->tilt, opt->turn, opt->angle_scale);
        std::printf("  between lights     %s\n", predictor.c_str());
        std::printf("  white              %.6g (the value printed as full transmittance)\n", encoder.white());
        if (!printer_record.empty())
            std::printf("  printer            %s (recorded: simulate and print sheet use it)\n",
                        printer_record.at("printer").c_str());
        std::printf("  time               %.2f s to prepare, %.2f s to render and write (%.1f Mdots/s)\n", prepare_s,
                    write_s, dots / std::max(write_s, 1e-9) / 1e6);
    });
}

void add_field_command(CLI::App& pattern) {
    auto* cmd = pattern.add_subcommand("field", "Write a procedural test field: letters, bars or diamonds (thesis 8.2.4)");
    struct Options {
        std::string kind, text = "SIG08", out, resolution = "64x64";
        double spread = 10.0;
        int steps = 5;
        bool json = false;
    };
    auto opt = std::make_shared<Options>();
    cmd->add_option("KIND", opt->kind, "letters, bars or diamonds")->required();
    cmd->add_option("--text", opt->text, "letters: one character per light direction, left to right");
    cmd->add_option("--spread", opt->spread, "Largest angle of a picture direction from the zenith, degrees");
    cmd->add_option("--steps", opt->steps, "diamonds: light directions per side of the grid");
    cmd->add_option("--resolution", opt->resolution, "Image size WIDTHxHEIGHT");
    cmd->add_option("--out", opt->out, "Output field folder")->required();
    cmd->add_flag("--json", opt->json, "Machine-readable summary on stdout");
    cmd->callback([opt] {
        patterns::ProceduralOptions options;
        if (opt->kind == "letters") options.kind = patterns::ProceduralKind::Letters;
        else if (opt->kind == "bars") options.kind = patterns::ProceduralKind::Bars;
        else if (opt->kind == "diamonds") options.kind = patterns::ProceduralKind::Diamonds;
        else throw InputError("KIND: expected 'letters', 'bars' or 'diamonds', got '" + opt->kind + "'");
        options.text = opt->text;
        options.spread_deg = opt->spread;
        options.diamond_steps = opt->steps;
        std::tie(options.width, options.height) = parse_resolution(opt->resolution);
        const relight::ReflectanceField field = patterns::procedural_field(options);
        ensure_directory(opt->out);
        relight::write_field(opt->out, field, opt->kind);
        if (opt->json) {
            const nlohmann::json summary = {{"out", opt->out},
                                            {"kind", opt->kind},
                                            {"width", options.width},
                                            {"height", options.height},
                                            {"light_directions", field.size()}};
            std::printf("%s\n", summary.dump(2).c_str());
        } else {
            std::printf("wrote %s field: %zu light directions of %d x %d into %s\n", opt->kind.c_str(), field.size(),
                        options.width, options.height, opt->out.c_str());
        }
    });
}

}  // namespace

void add_pattern_commands(CLI::App& app) {
    CLI::App* pattern = app.add_subcommand("pattern", "Encode reflectance fields into print-resolution patterns (Designs I-IV)")
                            ->require_subcommand(1);
    add_encode_command(*pattern);
    add_field_command(*pattern);
    add_pattern_angular_command(*pattern);
    add_pattern_optimize_command(*pattern);
}

}  // namespace rfd::cli
