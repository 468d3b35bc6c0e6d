#include "project/make.hpp"

#include <algorithm>
#include <chrono>
#include <map>
#include <set>
#include <fstream>
#include <iterator>
#include <sstream>
#include <system_error>

#include "core/command.hpp"
#include "core/error.hpp"
#include "core/files.hpp"
#include "core/process.hpp"
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

// A file the user named, as every step reads it from the output folder.
fs::path outside(const fs::path& path) { return fs::absolute(path).lexically_normal(); }

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

std::vector<Step> plan(const Project& p) {
    // The user's files by absolute path, what steps make by their place in the output folder.
    // `design` is the one built: the named design, or the one with the measured pitch.
    const fs::path named_design_file = outside(p.design);
    const std::string named_design = named_design_file.string();
    fs::path design_file = named_design_file;
    std::string design = named_design;
    const fs::path printer = outside(print::printer_file(p.printer));
    // A bundled printer is passed on by name, so the pattern records the name users know.
    const std::string printer_name = fs::path(p.printer).has_parent_path() ? printer.string() : p.printer;
    std::vector<Step> steps;

    // With photographs of the printed wedge, the printer's tone curve is measured first and
    // everything after is printed and predicted with the measured profile; the wedge itself is
    // the profile's own (its codes do not depend on it).
    fs::path film_printer = printer;
    std::string film_printer_name = printer_name;
    const Calibration& c = p.calibration;
    if (!c.wedge_photos.empty()) {
        Step tone{"calibrate_tone",
                  "the printer's tone curve measured from the photographs of its wedge (calibration/printer.toml; the "
                  "patches and curves in calibration/tone)",
                  {"calibrate", "tone", printer_name},
                  {printer},
                  {"calibration/printer.toml", "calibration/tone"}};
        for (const fs::path& photo : c.wedge_photos) {
            tone.arguments.push_back(outside(photo).string());
            tone.inputs.push_back(outside(photo));
        }
        tone.arguments.insert(tone.arguments.end(), {"--light", c.light, "--out", "calibration/printer.toml",
                                                     "--report", "calibration/tone"});
        steps.push_back(std::move(tone));
        film_printer = "calibration/printer.toml";
        film_printer_name = film_printer.string();
    }
    // With photographs of the moire sheet under the array, the array's pitch is measured next
    // and the pattern is encoded, printed and predicted for the measured design. The moire
    // sheet and the holder stay the named design's: they were printed before the photographs
    // (the sheet's bands are what was photographed; the holder held the array for them).
    if (!c.moire_photos.empty()) {
        Step pitch{"calibrate_pitch",
                   "the lens array's pitch measured from the photographs of the moire sheet (calibration/design.toml; "
                   "every lenslet's reading and the fitted profiles in calibration/pitch)",
                   {"calibrate", "pitch", named_design},
                   {named_design_file, film_printer},
                   {"calibration/design.toml", "calibration/pitch"}};
        for (const fs::path& photo : c.moire_photos) {
            pitch.arguments.push_back(outside(photo).string());
            pitch.inputs.push_back(outside(photo));
        }
        pitch.arguments.insert(pitch.arguments.end(),
                               {"--printer", film_printer_name, "--page", std::to_string(c.moire_page), "--out",
                                "calibration/design.toml", "--report", "calibration/pitch"});
        steps.push_back(std::move(pitch));
        design_file = "calibration/design.toml";
        design = design_file.string();
    }

    fs::path field;
    std::vector<fs::path> field_inputs;
    if (p.source.scene) {
        Step render{"field", "the reflectance field, rendered from the scene on the virtual light stage",
                    {"capture", "render", outside(*p.source.scene).string(), "--lights", std::to_string(p.source.lights),
                     "--out", "field"},
                    scene_files(outside(*p.source.scene)),
                    {"field"}};
        steps.push_back(std::move(render));
    } else if (p.source.procedural) {
        steps.push_back({"field", "the test field of " + *p.source.procedural,
                         {"pattern", "field", *p.source.procedural, "--out", "field"},
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
        field = "field";
        field_inputs = {field};
    } else {
        field = outside(*p.source.field);
        field_inputs = field_files(field);
    }

    const Encoding& e = p.encoding;
    const std::string tilt = e.tilt_deg ? format_number(*e.tilt_deg, 17) : std::string("auto");
    // The part of the photographs the steps that read the field use.
    const auto add_window = [&](Step& step) {
        if (const auto& r = p.source.region)
            step.arguments.insert(step.arguments.end(),
                                  {"--region", std::to_string((*r)[0]) + "," + std::to_string((*r)[1]) + "," +
                                                   std::to_string((*r)[2]) + "," + std::to_string((*r)[3])});
        if (p.source.scale) step.arguments.insert(step.arguments.end(), {"--scale", format_number(*p.source.scale, 17)});
    };
    // Before the long steps: what the design makes of this field, and what would suit it better.
    Step advice{"advice",
                "advice on this field before the long steps: the display's picture elements against the field's "
                "pixels, its lights inside the display's range, the bundled design that shows it best (advice.json)",
                {"design", "advise", design, field.string(), "--tilt", tilt, "--turn", format_number(e.turn_deg, 17),
                 "--angle-scale", format_number(e.angle_scale, 17), "--out", "advice.json"},
                field_inputs,
                {"advice.json"}};
    advice.inputs.insert(advice.inputs.begin(), design_file);
    add_window(advice);
    steps.push_back(std::move(advice));
    Step encode{"pattern", "the pattern at the printer's resolution (pattern.exr; pattern.png to look at)",
                {"pattern", "encode", design, field.string(), "--printer", film_printer_name, "--tilt",
                 tilt, "--turn", format_number(e.turn_deg, 17), "--angle-scale",
                 format_number(e.angle_scale, 17), "--model", e.model, "--interpolation", e.interpolation, "--fit",
                 e.fit, "--margin", format_number(e.margin_mm, 17), "--out", "pattern.exr", "--preview",
                 "pattern.png"},
                field_inputs,
                {"pattern.exr", "pattern.png"}};
    encode.inputs.insert(encode.inputs.begin(), {design_file, film_printer});
    add_window(encode);
    // A captured field is predicted between its lights by what leave-one-out finds best on it.
    const std::optional<std::string> basis = e.basis ? e.basis : p.source.field ? std::optional<std::string>("auto")
                                                                                : std::nullopt;
    if (basis) encode.arguments.insert(encode.arguments.end(), {"--basis", *basis});
    steps.push_back(std::move(encode));

    // What is printed and predicted: the direct encoding, or the pattern optimised from it.
    std::string pattern = "pattern.exr";
    fs::path pattern_file = "pattern.exr";
    if (const auto& opt = p.optimization) {
        Step optimize{"optimize",
                      "the pattern chosen through the simulator (pattern_optimized.exr), from the direct encoding; "
                      "its report in predict/optimize",
                      {"pattern", "optimize", design, field.string(), "--from", "pattern.exr", "--out",
                       "pattern_optimized.exr", "--iterations", std::to_string(opt->iterations), "--spacing",
                       format_number(opt->spacing_mm), "--core-weight", format_number(opt->core_weight),
                       "--report", "predict/optimize", "--judge-sweep", std::to_string(p.outputs.compare_sweep)},
                      {design_file, "pattern.exr"},
                      {"pattern_optimized.exr", "predict/optimize"}};
        optimize.inputs.insert(optimize.inputs.end(), field_inputs.begin(), field_inputs.end());
        steps.push_back(std::move(optimize));
        pattern = "pattern_optimized.exr";
        pattern_file = "pattern_optimized.exr";
    }
    const int sheets = print::load_printer(printer.string()).sheets;
    for (const std::string& format : p.outputs.sheet_formats)
        for (int side = 0; side < sheets; ++side) {
            const std::string name = std::string(side == 0 ? "front" : "back") + "." + format;
            Step sheet{"sheet_" + std::string(side == 0 ? "front_" : "back_") + format,
                       side == 0 ? "the front sheet to print (" + name + ")"
                                 : "the mirrored back sheet to print (" + name + "), laid behind the front one",
                       {"print", "sheet", design, pattern, "--copies", std::to_string(p.outputs.copies), "--out",
                        "print/" + name},
                       {design_file, pattern_file},
                       {"print/" + name}};
            if (side == 1) sheet.arguments.push_back("--mirror");
            if (format == p.outputs.sheet_formats.front()) {  // one picture per side, whatever the formats
                const std::string preview = std::string("print/") + (side == 0 ? "front" : "back") + ".png";
                sheet.arguments.insert(sheet.arguments.end(), {"--preview", preview});
                sheet.outputs.push_back(preview);
            }
            steps.push_back(std::move(sheet));
        }
    if (p.outputs.moire)
        steps.push_back({"moire", "the pitch calibration sheet (moire.pdf)",
                         {"print", "moire", named_design, "--printer", film_printer_name, "--out", "print/moire.pdf",
                          "--preview", "print/moire.png"},
                         {named_design_file, film_printer},
                         {"print/moire.pdf", "print/moire.png"}});
    if (p.outputs.wedge)
        steps.push_back({"wedge", "the step wedge that measures the printer's tone curve (wedge.pdf)",
                         {"print", "wedge", "--printer", printer_name, "--out", "print/wedge.pdf", "--preview",
                          "print/wedge.png"},
                         {printer},
                         {"print/wedge.pdf", "print/wedge.png"}});
    if (p.outputs.holder)
        steps.push_back({"holder", "the lens holder: OpenSCAD source, STLs to 3D-print, and their checks",
                         {"holder", named_design, "--3d-printer", outside(p.printer_3d).string(), "--printer",
                          film_printer_name, "--out", "holder/holder.scad", "--stl", "holder/holder.stl"},
                         {named_design_file, outside(p.printer_3d), film_printer},
                         {"holder"}});
    if (p.outputs.compare_sweep > 0)
        steps.push_back({"compare",
                         "the predicted display beside the field relit in software, over a sweep of light directions",
                         {"simulate", "compare", design, pattern, field.string(), "--sweep",
                          std::to_string(p.outputs.compare_sweep), "--out", "predict/compare"},
                         {design_file, pattern_file},
                         {"predict/compare"}});
    if (p.outputs.compare_sweep > 0)
        steps.back().inputs.insert(steps.back().inputs.end(), field_inputs.begin(), field_inputs.end());
    if (p.outputs.tolerance)
        steps.push_back({"tolerance", "how precisely to assemble: the shift, rotation, pitch and spacer errors it tolerates",
                         {"simulate", "tolerance", design, pattern, "--out", "predict/tolerance"},
                         {design_file, pattern_file},
                         {"predict/tolerance"}});
    // Photographs of the assembled display: where its pattern sits, judged against the
    // tolerances just predicted.
    if (!c.display_photos.empty()) {
        Step registration{"calibrate_registration",
                          "where the printed pattern sits on the lens array, measured from the photographs of the "
                          "assembled display (calibration/registration.json; the report in "
                          "logs/calibrate_registration.txt)",
                          {"calibrate", "registration", design, pattern},
                          {design_file, pattern_file},
                          {"calibration/registration.json"}};
        for (const fs::path& photo : c.display_photos) {
            registration.arguments.push_back(outside(photo).string());
            registration.inputs.push_back(outside(photo));
        }
        for (const fs::path& photo : c.turned_photos) {
            registration.arguments.insert(registration.arguments.end(), {"--turned", outside(photo).string()});
            registration.inputs.push_back(outside(photo));
        }
        if (c.display_light_tilt_deg)
            registration.arguments.insert(registration.arguments.end(),
                                          {"--light-tilt", format_number(*c.display_light_tilt_deg, 17), "--light-turn",
                                           format_number(c.display_light_turn_deg, 17)});
        if (p.outputs.tolerance) {
            registration.arguments.insert(registration.arguments.end(), {"--tolerance", "predict/tolerance"});
            registration.inputs.push_back("predict/tolerance");
        }
        registration.arguments.insert(registration.arguments.end(), {"--out", "calibration/registration.json"});
        steps.push_back(std::move(registration));
    }
    if (p.outputs.preview_lights > 0) {
        steps.push_back({"preview", "the preview page's pictures: predicted and relit over the field of view",
                         {"simulate", "preview", design, pattern, field.string(), "--count",
                          std::to_string(p.outputs.preview_lights), "--out", "preview"},
                         {design_file, pattern_file},
                         {"preview/data.js", "preview/predicted.png", "preview/relit.png"}});
        steps.back().inputs.insert(steps.back().inputs.end(), field_inputs.begin(), field_inputs.end());
        if (p.optimization) {  // the page switches between the optimised pattern and the direct one
            steps.back().arguments.insert(steps.back().arguments.end(), {"--direct", "pattern.exr"});
            steps.back().inputs.push_back("pattern.exr");
            steps.back().outputs.push_back("preview/direct.png");
        }
    }
    if (p.outputs.compare_sweep > 0) {
        Step verdict{"verdict", "the verdict: go, check or no-go, and the figures it rests on (verdict.json)",
                     {"simulate", "verdict", design, "--compare", "predict/compare", "--out", "verdict.json"},
                     {design_file, "predict/compare"},
                     {"verdict.json"}};
        if (p.outputs.tolerance) {
            verdict.arguments.insert(verdict.arguments.end(), {"--tolerance", "predict/tolerance"});
            verdict.inputs.push_back("predict/tolerance");
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

namespace {

// A path of a step (relative to the output folder: made by a step) is `inner` or inside it.
bool within(const fs::path& path, const fs::path& inner) {
    if (path.is_absolute() || inner.is_absolute()) return false;
    auto p = path.begin(), q = inner.begin();
    for (; q != inner.end(); ++p, ++q)
        if (p == path.end() || *p != *q) return false;
    return true;
}

// The steps to run: all of them, or those named and every step they read from.
std::vector<bool> selected(const std::vector<Step>& steps, const std::vector<std::vector<std::size_t>>& needs,
                           const std::vector<std::string>& only) {
    std::vector<bool> chosen(steps.size(), only.empty());
    std::vector<std::size_t> todo;
    for (const std::string& name : only) {
        const auto it = std::find_if(steps.begin(), steps.end(), [&](const Step& s) { return s.name == name; });
        if (it == steps.end()) {
            std::string names;
            for (const Step& step : steps) names += (names.empty() ? "" : ", ") + step.name;
            throw InputError("--only: this project has no step '" + name + "' (its steps: " + names + ")");
        }
        todo.push_back(static_cast<std::size_t>(it - steps.begin()));
    }
    while (!todo.empty()) {
        const std::size_t k = todo.back();
        todo.pop_back();
        if (chosen[k]) continue;
        chosen[k] = true;
        todo.insert(todo.end(), needs[k].begin(), needs[k].end());
    }
    return chosen;
}

// What an earlier plan made and this one does not: removed from the folder and the
// manifest, so that nothing lists or tells the maker to print it.
void remove_stale_outputs(const std::vector<Step>& steps, const fs::path& out, Manifest& manifest) {
    std::map<std::string, std::set<std::string>> planned;
    for (const Step& step : steps)
        for (const fs::path& output : step.outputs) planned[step.name].insert(output.generic_string());
    for (const auto& [name, record] : std::map<std::string, StepRecord>(manifest.steps())) {
        StepRecord kept = record;
        for (const auto& [output, hash] : record.outputs) {
            const auto step = planned.find(name);
            if (step != planned.end() && step->second.count(output)) continue;
            const fs::path file = fs::path(output).lexically_normal();
            // A manifest is only ever written by make(); a path outside the folder in it is damage.
            if (!file.is_relative() || file.empty() || *file.begin() == "..") continue;
            std::error_code ec;
            fs::remove_all(out / file, ec);
            kept.outputs.erase(output);
        }
        if (!planned.count(name)) {
            std::error_code ec;
            fs::remove(out / "logs" / (name + ".txt"), ec);
            manifest.forget(name);
        } else if (kept.outputs.size() != record.outputs.size()) {
            manifest.record(name, std::move(kept));
        }
    }
    manifest.write();
}

std::string read_text_after_first_line(const fs::path& file) {
    const std::string text = read_text(file);
    const std::size_t end = text.find('\n');
    return end == std::string::npos ? std::string() : text.substr(end + 1);
}

}  // namespace

std::vector<std::vector<std::size_t>> dependencies(const std::vector<Step>& steps) {
    std::vector<std::vector<std::size_t>> needs(steps.size());
    for (std::size_t k = 0; k < steps.size(); ++k)
        for (std::size_t j = 0; j < k; ++j) {
            bool reads = false;
            for (const fs::path& input : steps[k].inputs)
                for (const fs::path& output : steps[j].outputs)
                    reads = reads || within(input, output) || within(output, input);
            if (reads) needs[k].push_back(j);
        }
    return needs;
}

ProcessStepRunner::ProcessStepRunner(fs::path program) : program_(std::move(program)) {
    forward_signals_to_children();
}

long ProcessStepRunner::start(const Step& step, const fs::path& out, const fs::path& log) {
    std::vector<std::string> arguments{"--quiet"};
    arguments.insert(arguments.end(), step.arguments.begin(), step.arguments.end());
    return spawn_process(program_, arguments, {out, log});
}

StepRunner::Ended ProcessStepRunner::wait() {
    const ChildExit exit = wait_for_child();
    return {exit.pid, exit.exit_code};
}

int ProcessStepRunner::stop_signal() const { return received_signal(); }

std::vector<StepOutcome> make(const Project& project, const fs::path& out, StepRunner& runner,
                              const MakeOptions& options, const MakeListener& listener) {
    ensure_directory(out / "logs");
    const ExclusiveLock lock(out / ".rfd-make.lock",
                             "another rfd make is making into " + out.string() +
                                 " now; wait for it to end, or make into another folder");
    const std::vector<Step> steps = plan(project);
    const std::vector<std::vector<std::size_t>> needs = dependencies(steps);
    const std::vector<bool> chosen = selected(steps, needs, options.only);
    Manifest manifest = Manifest::read(out);
    remove_stale_outputs(steps, out, manifest);

    enum class State { waiting, running, done, failed };
    std::vector<State> state(steps.size(), State::waiting);
    std::vector<StepOutcome> outcomes(steps.size());
    std::vector<std::string> keys(steps.size());
    std::map<long, std::size_t> running;  // handle -> step
    std::vector<std::chrono::steady_clock::time_point> started(steps.size());
    const int count = static_cast<int>(std::count(chosen.begin(), chosen.end(), true));
    int done = 0;
    std::string failure;
    const auto log_of = [&](std::size_t k) { return out / "logs" / (steps[k].name + ".txt"); };
    const auto partial_log_of = [&](std::size_t k) { return out / "logs" / (".running-" + steps[k].name + ".txt"); };
    const auto finish = [&](std::size_t k, bool ran, double seconds) {
        state[k] = State::done;
        outcomes[k] = {steps[k].name, steps[k].title, ran, seconds};
        ++done;
        if (listener.finished) listener.finished(outcomes[k], done, count);
    };
    const auto ready = [&](std::size_t k) {
        if (!chosen[k] || state[k] != State::waiting) return false;
        for (const std::size_t j : needs[k])
            if (state[j] != State::done) return false;
        return true;
    };
    // Starts the next step that can run, or finds it up to date; false when none can.
    const auto start_next = [&] {
        for (std::size_t k = 0; k < steps.size(); ++k) {
            if (!ready(k)) continue;
            const Step& step = steps[k];
            std::vector<std::string> key_parts{options.rfd_identity};
            key_parts.insert(key_parts.end(), step.arguments.begin(), step.arguments.end());
            for (const fs::path& input : step.inputs) {
                key_parts.push_back(input.generic_string());
                key_parts.push_back(content_hash(out / input));
            }
            keys[k] = hash_strings(key_parts);
            if (!options.force && manifest.up_to_date(step.name, keys[k])) {
                finish(k, false, 0.0);
                return true;
            }
            manifest.forget(step.name);
            manifest.write();
            // The folders of whatever the step writes: rfd's commands write into folders
            // that exist, they do not create them.
            for (const std::string& argument : step.arguments)
                for (const fs::path& output : step.outputs)
                    if (within(argument, output)) ensure_directory((out / argument).parent_path());
            write_text_file(partial_log_of(k), "$ " + command_line(step) + "\n");
            started[k] = std::chrono::steady_clock::now();
            running[runner.start(step, out, partial_log_of(k))] = k;
            state[k] = State::running;
            return true;
        }
        return false;
    };

    while (true) {
        const bool stopping = !failure.empty() || runner.stop_signal() != 0;
        if (!stopping && static_cast<int>(running.size()) < std::max(options.jobs, 1) && start_next()) continue;
        if (running.empty()) break;
        const StepRunner::Ended ended = runner.wait();
        const auto it = running.find(ended.handle);
        if (it == running.end()) continue;  // not a step's process
        const std::size_t k = it->second;
        running.erase(it);
        const Step& step = steps[k];
        const double seconds =
            std::chrono::duration<double>(std::chrono::steady_clock::now() - started[k]).count();
        if (runner.stop_signal() != 0) {  // stopped, or ended while the others are stopped: its outputs go
            std::error_code ec;
            for (const fs::path& output : step.outputs) fs::remove_all(out / output, ec);
            fs::remove(partial_log_of(k), ec);
            state[k] = State::failed;
            continue;
        }
        fs::rename(partial_log_of(k), log_of(k));
        if (ended.exit_code != 0) {
            state[k] = State::failed;
            if (failure.empty())
                failure = "step '" + step.name + "' (" + step.title + ") failed with exit code " +
                          std::to_string(ended.exit_code) + ":\n" +
                          last_lines(read_text_after_first_line(log_of(k)), 6) +
                          "\nThe steps that ended well are made and kept; its command and output are in " +
                          log_of(k).string();
            continue;
        }
        StepRecord record{keys[k], {}};
        for (const fs::path& output : step.outputs) {
            std::error_code ec;
            if (fs::exists(out / output, ec)) record.outputs[output.generic_string()] = content_hash(out / output);
            else if (failure.empty()) failure = "step '" + step.name + "' succeeded but did not write " + (out / output).string();
        }
        if (record.outputs.size() != step.outputs.size()) {
            state[k] = State::failed;
            continue;
        }
        manifest.record(step.name, std::move(record));
        manifest.write();
        finish(k, true, seconds);
    }
    if (const int signal = runner.stop_signal())
        throw Interrupted(signal, "stopped by signal " + std::to_string(signal) +
                                      "; the steps that were running are stopped and what they wrote removed, "
                                      "the steps that ended are made and kept");
    if (!failure.empty()) throw ToolError(failure);
    if (options.only.empty()) write_index(project, out, steps);
    std::vector<StepOutcome> result;
    for (std::size_t k = 0; k < steps.size(); ++k)
        if (chosen[k]) result.push_back(outcomes[k]);
    return result;
}

}  // namespace rfd::project
