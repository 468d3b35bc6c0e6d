#include "project/make.hpp"

#include <chrono>
#include <fstream>
#include <iterator>
#include <sstream>
#include <system_error>

#include "core/command.hpp"
#include "core/error.hpp"
#include "core/files.hpp"
#include "core/text.hpp"
#include "print/printer.hpp"
#include "project/index.hpp"
#include "project/manifest.hpp"
#include "relight/field.hpp"

namespace rfd::project {
namespace {

namespace fs = std::filesystem;

std::string read_text(const fs::path& file) {
    std::ifstream in(file, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// A scene and the files beside it that it names (meshes): what rendering it reads.
std::vector<fs::path> scene_files(const fs::path& scene) {
    std::vector<fs::path> files{scene};
    const std::string text = read_text(scene);
    std::error_code ec;
    for (const auto& entry : fs::directory_iterator(scene.parent_path().empty() ? "." : scene.parent_path(), ec))
        if (entry.is_regular_file(ec) && entry.path() != scene &&
            text.find(entry.path().filename().string()) != std::string::npos)
            files.push_back(entry.path());
    std::sort(files.begin() + 1, files.end());
    return files;
}

// A captured field: its light file and the images it names, wherever they were found.
std::vector<fs::path> field_files(const fs::path& field) {
    const fs::path lp = relight::light_file_of(field);
    std::vector<fs::path> files{lp};
    for (const relight::LightEntry& entry : relight::read_light_file(lp)) files.push_back(entry.path);
    return files;
}

fs::path printer_file(const std::string& printer) {
    return printer.find('/') == std::string::npos && !fs::exists(printer)
               ? print::bundled_printer_folder() / (printer + ".toml")
               : fs::path(printer);
}

std::string last_lines(const std::string& text, int count) {
    std::size_t start = text.size();
    while (start > 0 && (text[start - 1] == '\n')) --start;
    const std::size_t end = start;
    for (int n = 0; n < count && start > 0; ++n) {
        start = text.rfind('\n', start - 1);
        if (start == std::string::npos) {
            start = 0;
            break;
        }
    }
    return text.substr(start == 0 ? 0 : start + 1, end - (start == 0 ? 0 : start + 1));
}

}  // namespace

std::vector<Step> plan(const Project& p, const fs::path& out) {
    const std::string design = p.design.string();
    const std::string o = out.string() + "/";
    const fs::path printer = printer_file(p.printer);
    std::vector<Step> steps;

    fs::path field;
    std::vector<fs::path> field_inputs;
    if (p.source.scene) {
        Step render{"field", "the reflectance field, rendered from the scene on the virtual light stage",
                    {"capture", "render", p.source.scene->string(), "--lights", std::to_string(p.source.lights),
                     "--out", o + "field"},
                    scene_files(*p.source.scene),
                    {"field"}};
        steps.push_back(std::move(render));
    } else if (p.source.procedural) {
        steps.push_back({"field", "the test field of " + *p.source.procedural,
                         {"pattern", "field", *p.source.procedural, "--out", o + "field"},
                         {},
                         {"field"}});
        if (*p.source.procedural == "letters")
            steps.back().arguments.insert(steps.back().arguments.end(), {"--text", p.source.text});
    }
    if (!p.source.field) {
        if (p.source.resolution)
            steps.back().arguments.insert(steps.back().arguments.end(),
                                          {"--resolution", std::to_string((*p.source.resolution)[0]) + "x" +
                                                               std::to_string((*p.source.resolution)[1])});
        field = out / "field";
        field_inputs = {field};
    } else {
        field = *p.source.field;
        field_inputs = field_files(field);
    }

    const Encoding& e = p.encoding;
    Step encode{"pattern", "the pattern at the printer's resolution (pattern.exr; pattern.png to look at)",
                {"pattern", "encode", design, field.string(), "--printer", p.printer, "--tilt",
                 format_number(e.tilt_deg, 17), "--turn", format_number(e.turn_deg, 17), "--angle-scale",
                 format_number(e.angle_scale, 17), "--model", e.model, "--interpolation", e.interpolation, "--fit",
                 e.fit, "--margin", format_number(e.margin_mm, 17), "--out", o + "pattern.exr", "--preview",
                 o + "pattern.png"},
                field_inputs,
                {"pattern.exr", "pattern.png"}};
    encode.inputs.insert(encode.inputs.begin(), {p.design, printer});
    if (const auto& r = p.source.region)
        encode.arguments.insert(encode.arguments.end(), {"--region", std::to_string((*r)[0]) + "," +
                                                                         std::to_string((*r)[1]) + "," +
                                                                         std::to_string((*r)[2]) + "," +
                                                                         std::to_string((*r)[3])});
    if (p.source.scale) encode.arguments.insert(encode.arguments.end(), {"--scale", format_number(*p.source.scale, 17)});
    steps.push_back(std::move(encode));

    // What is printed and predicted: the direct encoding, or the pattern optimised from it.
    std::string pattern = o + "pattern.exr";
    fs::path pattern_file = out / "pattern.exr";
    if (const auto& opt = p.optimization) {
        Step optimize{"optimize",
                      "the pattern chosen through the simulator (pattern_optimized.exr), from the direct encoding; "
                      "its report in predict/optimize",
                      {"pattern", "optimize", design, field.string(), "--from", o + "pattern.exr", "--out",
                       o + "pattern_optimized.exr", "--iterations", std::to_string(opt->iterations), "--spacing",
                       format_number(opt->spacing_mm), "--core-weight", format_number(opt->core_weight),
                       "--report", o + "predict/optimize", "--judge-sweep", std::to_string(p.outputs.compare_sweep)},
                      {p.design, out / "pattern.exr"},
                      {"pattern_optimized.exr", "predict/optimize"}};
        optimize.inputs.insert(optimize.inputs.end(), field_inputs.begin(), field_inputs.end());
        steps.push_back(std::move(optimize));
        pattern = o + "pattern_optimized.exr";
        pattern_file = out / "pattern_optimized.exr";
    }
    const int sheets = print::load_printer(p.printer).sheets;
    for (const std::string& format : p.outputs.sheet_formats)
        for (int side = 0; side < sheets; ++side) {
            const std::string name = std::string(side == 0 ? "front" : "back") + "." + format;
            Step sheet{"sheet_" + std::string(side == 0 ? "front_" : "back_") + format,
                       side == 0 ? "the front sheet to print (" + name + ")"
                                 : "the mirrored back sheet to print (" + name + "), laid behind the front one",
                       {"print", "sheet", design, pattern, "--copies", std::to_string(p.outputs.copies), "--out",
                        o + "print/" + name},
                       {p.design, pattern_file},
                       {"print/" + name}};
            if (side == 1) sheet.arguments.push_back("--mirror");
            if (format == p.outputs.sheet_formats.front()) {  // one picture per side, whatever the formats
                const std::string preview = std::string("print/") + (side == 0 ? "front" : "back") + ".png";
                sheet.arguments.insert(sheet.arguments.end(), {"--preview", o + preview});
                sheet.outputs.push_back(preview);
            }
            steps.push_back(std::move(sheet));
        }
    if (p.outputs.moire)
        steps.push_back({"moire", "the pitch calibration sheet (moire.pdf)",
                         {"print", "moire", design, "--printer", p.printer, "--out", o + "print/moire.pdf",
                          "--preview", o + "print/moire.png"},
                         {p.design, printer},
                         {"print/moire.pdf", "print/moire.png"}});
    if (p.outputs.wedge)
        steps.push_back({"wedge", "the step wedge that measures the printer's tone curve (wedge.pdf)",
                         {"print", "wedge", "--printer", p.printer, "--out", o + "print/wedge.pdf", "--preview",
                          o + "print/wedge.png"},
                         {printer},
                         {"print/wedge.pdf", "print/wedge.png"}});
    if (p.outputs.holder)
        steps.push_back({"holder", "the lens holder: OpenSCAD source, STLs to 3D-print, and their checks",
                         {"holder", design, "--3d-printer", p.printer_3d.string(), "--printer", p.printer, "--out",
                          o + "holder/holder.scad", "--stl", o + "holder/holder.stl"},
                         {p.design, p.printer_3d, printer},
                         {"holder"}});
    if (p.outputs.compare_sweep > 0)
        steps.push_back({"compare",
                         "the predicted display beside the field relit in software, over a sweep of light directions",
                         {"simulate", "compare", design, pattern, field.string(), "--sweep",
                          std::to_string(p.outputs.compare_sweep), "--out", o + "predict/compare"},
                         {p.design, pattern_file},
                         {"predict/compare"}});
    if (p.outputs.compare_sweep > 0)
        steps.back().inputs.insert(steps.back().inputs.end(), field_inputs.begin(), field_inputs.end());
    if (p.outputs.tolerance)
        steps.push_back({"tolerance", "how precisely to assemble: the shift, rotation, pitch and spacer errors it tolerates",
                         {"simulate", "tolerance", design, pattern, "--out", o + "predict/tolerance"},
                         {p.design, pattern_file},
                         {"predict/tolerance"}});
    if (p.outputs.preview_lights > 0) {
        steps.push_back({"preview", "the preview page's pictures: predicted and relit over the field of view",
                         {"simulate", "preview", design, pattern, field.string(), "--count",
                          std::to_string(p.outputs.preview_lights), "--out", o + "preview"},
                         {p.design, pattern_file},
                         {"preview/data.js", "preview/predicted.png", "preview/relit.png"}});
        steps.back().inputs.insert(steps.back().inputs.end(), field_inputs.begin(), field_inputs.end());
        if (p.optimization) {  // the page switches between the optimised pattern and the direct one
            steps.back().arguments.insert(steps.back().arguments.end(), {"--direct", o + "pattern.exr"});
            steps.back().inputs.push_back(out / "pattern.exr");
            steps.back().outputs.push_back("preview/direct.png");
        }
    }
    if (p.outputs.compare_sweep > 0) {
        Step verdict{"verdict", "the verdict: go, check or no-go, and the figures it rests on (verdict.json)",
                     {"simulate", "verdict", design, "--compare", o + "predict/compare", "--out", o + "verdict.json"},
                     {p.design, out / "predict/compare"},
                     {"verdict.json"}};
        if (p.outputs.tolerance) {
            verdict.arguments.insert(verdict.arguments.end(), {"--tolerance", o + "predict/tolerance"});
            verdict.inputs.push_back(out / "predict/tolerance");
        }
        steps.push_back(std::move(verdict));
    }
    return steps;
}

std::string command_line(const Step& step) {
    std::string line = "rfd";
    for (const std::string& argument : step.arguments) {
        const bool plain = !argument.empty() && argument.find_first_not_of(
                                                    "abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789"
                                                    "-_./,:+=") == std::string::npos;
        line += " " + (plain ? argument : shell_quoted(argument));
    }
    return line;
}

std::vector<StepOutcome> make(const Project& project, const fs::path& out, const StepRunner& run,
                              const MakeOptions& options, const MakeListener& listener) {
    ensure_directory(out / "logs");
    const std::vector<Step> steps = plan(project, out);
    Manifest manifest = Manifest::read(out);
    std::vector<StepOutcome> outcomes;
    for (std::size_t k = 0; k < steps.size(); ++k) {
        const Step& step = steps[k];
        std::vector<std::string> key_parts{options.rfd_identity};
        key_parts.insert(key_parts.end(), step.arguments.begin(), step.arguments.end());
        for (const fs::path& input : step.inputs) {
            key_parts.push_back(input.string());
            key_parts.push_back(content_hash(input));
        }
        const std::string key = hash_strings(key_parts);
        if (listener.starting) listener.starting(step, static_cast<int>(k), static_cast<int>(steps.size()));
        StepOutcome outcome{step.name, step.title, false, 0.0};
        if (options.force || !manifest.up_to_date(step.name, key)) {
            manifest.forget(step.name);
            manifest.write();
            // The folders of whatever the step writes into the output folder: rfd's commands
            // write into folders that exist, they do not create them.
            const std::string prefix = (out / "").string();
            for (const std::string& argument : step.arguments)
                if (argument.starts_with(prefix)) ensure_directory(fs::path(argument).parent_path());
            const auto start = std::chrono::steady_clock::now();
            const StepResult result = run(step.arguments);
            outcome.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
            const fs::path log = out / "logs" / (step.name + ".txt");
            write_text_file(log, "$ " + command_line(step) + "\n" + result.output);
            if (result.exit_code != 0)
                throw ToolError("step '" + step.name + "' (" + step.title + ") failed with exit code " +
                                std::to_string(result.exit_code) + ":\n" + last_lines(result.output, 6) +
                                "\nThe steps before it are made and kept; its command and output are in " +
                                log.string());
            StepRecord record{key, {}};
            for (const fs::path& output : step.outputs) {
                std::error_code ec;
                if (!fs::exists(out / output, ec))
                    throw ToolError("step '" + step.name + "' succeeded but did not write " + (out / output).string());
                record.outputs[output.generic_string()] = content_hash(out / output);
            }
            const fs::path log_name = fs::path("logs") / (step.name + ".txt");
            record.outputs[log_name.generic_string()] = content_hash(log);
            manifest.record(step.name, std::move(record));
            manifest.write();
            outcome.ran = true;
        }
        outcomes.push_back(outcome);
        if (listener.finished) listener.finished(outcome);
    }
    write_index(project, out, steps);
    return outcomes;
}

}  // namespace rfd::project
