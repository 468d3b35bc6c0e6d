#include "project/project.hpp"

#include <algorithm>
#include <functional>
#include <system_error>

#include "calibrate/pitch.hpp"
#include "calibrate/registration.hpp"
#include "core/config.hpp"
#include "core/error.hpp"
#include "core/names.hpp"
#include "optics/design.hpp"
#include "optics/model.hpp"
#include "patterns/encode.hpp"
#include "print/printer.hpp"
#include "relight/field.hpp"
#include "relight/interpolation.hpp"
#include "relight/light_model.hpp"

namespace rfd::project {
namespace {

namespace fs = std::filesystem;

bool is_file(const fs::path& path) {
    std::error_code ec;
    return fs::is_regular_file(path, ec);
}

// A bundled name ("design1") or a path relative to the project file; the key's location
// and what is bundled in the message when neither exists.
fs::path resolve(ConfigTable& table, const std::string& key, const fs::path& project_folder,
                 const fs::path& bundled_folder, const std::string& what) {
    const std::string value = table.string(key);
    if (value.empty()) table.fail(key, "expected " + what + ", got an empty name");
    const fs::path relative = project_folder / value;
    if (is_file(relative)) return relative.lexically_normal();
    const fs::path bundled = bundled_folder / (value + ".toml");
    if (value.find('/') == std::string::npos && is_file(bundled)) return bundled;
    table.fail(key, "cannot open " + what + " '" + value + "': no such file (relative to the project file) or "
                    "bundled name in " + bundled_folder.string());
}

// A source the project names: a regular file, or a folder where `folder_too`. Checked
// before anything reads it: a device or a pipe would be read forever.
fs::path existing(ConfigTable& table, const std::string& key, const fs::path& project_folder, bool folder_too) {
    const std::string value = table.string(key);
    const std::string expected = folder_too ? "a folder or a regular file" : "a regular file";
    if (value.empty()) table.fail(key, "expected " + expected + ", got an empty name");
    const fs::path path = (project_folder / value).lexically_normal();
    std::error_code ec;
    if (!fs::exists(path, ec)) table.fail(key, "cannot open '" + path.string() + "': no such file or folder");
    if (fs::is_directory(path, ec) ? !folder_too : !fs::is_regular_file(path, ec))
        table.fail(key, "'" + path.string() + "' is " +
                            (fs::is_directory(path, ec) ? "a folder" : "not a regular file (a device or a pipe?)") +
                            "; expected " + expected);
    return path;
}

template <class Enum, std::size_t N>
std::string choice(ConfigTable& table, const std::string& key, const std::string& fallback,
                   const std::array<Named<Enum>, N>& names) {
    if (!table.has(key)) return fallback;
    return table.choice(key, names_of(names));
}

Source read_source(ConfigTable& table, const fs::path& folder) {
    Source source;
    const int kinds = int(table.has("field")) + int(table.has("scene")) + int(table.has("procedural"));
    if (kinds != 1)
        table.fail(table.has("scene") ? "scene" : "field",
                   "expected exactly one of field (a field folder or .lp file), scene (a scene to render) and "
                   "procedural (a test field)");
    if (table.has("field")) source.field = existing(table, "field", folder, true);
    if (table.has("scene")) {
        source.scene = existing(table, "scene", folder, false);
        source.lights = static_cast<int>(table.optional_integer("lights", 3, 100000).value_or(source.lights));
    }
    if (table.has("procedural")) {
        source.procedural = table.choice("procedural", {"letters", "bars", "diamonds"});
        source.text = table.optional_string("text").value_or(source.text);
        if (source.text.empty()) table.fail("text", "expected at least one letter");
    }
    if (table.has("resolution")) {
        if (source.field) table.fail("resolution", "a field has its own resolution (scale it with scale)");
        const auto size = table.integer_pair("resolution", 1, 16384);
        source.resolution = std::array<int, 2>{static_cast<int>(size[0]), static_cast<int>(size[1])};
    }
    if (table.has("region")) {
        const auto r = table.numbers("region", 4, 0, 1e6);
        for (double v : r)
            if (v != static_cast<int>(v)) table.fail("region", "expected whole pixels [x, y, width, height]");
        if (r[2] < 1 || r[3] < 1) table.fail("region", "expected a width and height of at least one pixel");
        source.region = std::array<int, 4>{static_cast<int>(r[0]), static_cast<int>(r[1]), static_cast<int>(r[2]),
                                           static_cast<int>(r[3])};
    }
    if (table.has("scale")) source.scale = table.value(relight::kFieldScaleOption);
    return source;
}

Encoding read_encoding(ConfigTable& table) {
    Encoding e;
    if (table.is_string("tilt_deg")) {
        if (table.string("tilt_deg") != "auto")
            table.fail("tilt_deg", "expected degrees from " + format_number(patterns::kTiltOption.min) + " to " +
                                       format_number(patterns::kTiltOption.max) + ", or \"auto\"");
        e.tilt_deg = std::nullopt;
    } else {
        e.tilt_deg = table.value(patterns::kTiltOption);
    }
    e.turn_deg = table.value(patterns::kTurnOption);
    e.angle_scale = table.value(patterns::kAngleScaleOption);
    e.margin_mm = table.value(patterns::kMarginOption);
    e.model = choice(table, "model", e.model, optics::kModelChoiceNames);
    e.interpolation = choice(table, "interpolation", e.interpolation, relight::kInterpolationNames);
    e.fit = choice(table, "fit", e.fit, patterns::kImageFitNames);
    if (table.has("basis")) {
        std::vector<std::string> names = relight::light_model_names();
        names.emplace_back("auto");
        e.basis = table.choice("basis", names);
    }
    return e;
}

Outputs read_outputs(ConfigTable& table) {
    Outputs o;
    if (table.has("sheets")) {
        o.sheet_formats = table.strings("sheets");
        for (std::size_t k = 0; k < o.sheet_formats.size(); ++k) {
            const std::string& format = o.sheet_formats[k];
            if (format != "pdf" && format != "tif")
                table.fail("sheets", "expected formats \"pdf\" and/or \"tif\", got \"" + format + "\"");
            if (std::find(o.sheet_formats.begin(), o.sheet_formats.begin() + static_cast<std::ptrdiff_t>(k), format) !=
                o.sheet_formats.begin() + static_cast<std::ptrdiff_t>(k))
                table.fail("sheets", "\"" + format + "\" is named twice");
        }
    }
    o.copies = static_cast<int>(table.optional_integer("copies", 0, 1000).value_or(o.copies));
    o.moire = table.optional_boolean("moire").value_or(o.moire);
    o.wedge = table.optional_boolean("wedge").value_or(o.wedge);
    o.holder = table.optional_boolean("holder").value_or(o.holder);
    o.compare_sweep = static_cast<int>(table.value(predict::kSweepOption));
    o.tolerance = table.optional_boolean("tolerance").value_or(o.tolerance);
    // 0 turns the light control off; any other count is the preview's own (kPreviewLightsOption).
    const auto& lights = predict::kPreviewLightsOption;
    if (table.has("preview_lights") && table.integer("preview_lights", 0, lights.max) == 0)
        o.preview_lights = 0;
    else
        o.preview_lights = static_cast<int>(table.value(lights));
    return o;
}

// Photographs named under `key`, each a regular file, before anything reads them.
std::vector<fs::path> photographs(ConfigTable& table, const std::string& key, const fs::path& folder) {
    std::vector<fs::path> photos;
    if (!table.has(key)) return photos;
    for (const std::string& photo : table.strings(key)) {
        const fs::path path = (folder / photo).lexically_normal();
        std::error_code ec;
        if (photo.empty() || !fs::is_regular_file(path, ec))
            table.fail(key, "cannot open '" + path.string() + "': expected a photograph (a regular file)");
        photos.push_back(path);
    }
    if (photos.empty()) table.fail(key, "expected at least one photograph (or leave the key out)");
    return photos;
}

// What a calibrate:: precondition on the design says when it refuses; empty when it holds.
std::string refusal(const std::function<void()>& check) {
    try {
        check();
        return "";
    } catch (const InputError& error) {
        return error.what();
    }
}

Calibration read_calibration(ConfigTable& table, const fs::path& folder, const Project& project) {
    Calibration c;
    c.wedge_photos = photographs(table, "wedge_photos", folder);
    if (table.has("light")) c.light = table.choice("light", {"back", "reflected"});
    c.moire_photos = photographs(table, "moire_photos", folder);
    if (table.has("moire_page")) c.moire_page = static_cast<int>(table.integer("moire_page", 1, 100));
    c.display_photos = photographs(table, "display_photos", folder);
    c.turned_photos = photographs(table, "turned_photos", folder);
    c.display_light_tilt_deg = table.optional_number("display_light_tilt_deg", 0.0, 60.0);
    if (table.has("display_light_turn_deg"))
        c.display_light_turn_deg = table.number("display_light_turn_deg", -360.0, 360.0);
    if (c.wedge_photos.empty() && c.moire_photos.empty() && c.display_photos.empty())
        table.fail("wedge_photos", "the table names no photographs: expected wedge_photos, moire_photos or "
                                   "display_photos");
    if (!c.moire_photos.empty() && !project.pitch_refusal.empty()) table.fail("moire_photos", project.pitch_refusal);
    if (!c.display_photos.empty() && !project.registration_refusal.empty())
        table.fail("display_photos", project.registration_refusal);
    if (!c.turned_photos.empty() && c.display_photos.empty())
        table.fail("turned_photos", "expected display_photos too: the turned photographs pair with upright ones");
    if (c.display_photos.empty() && (table.has("display_light_tilt_deg") || table.has("display_light_turn_deg")))
        table.fail(table.has("display_light_tilt_deg") ? "display_light_tilt_deg" : "display_light_turn_deg",
                   "expected display_photos: the light is the one they were taken in");
    return c;
}

}  // namespace

const std::vector<DeclaredKey>& declared_keys() {
    static const std::vector<DeclaredKey> keys{
        {"source", relight::kFieldScaleOption},     {"encode", patterns::kTiltOption},
        {"encode", patterns::kTurnOption},          {"encode", patterns::kAngleScaleOption},
        {"encode", patterns::kMarginOption},        {"make", predict::kSweepOption},
        {"make", predict::kPreviewLightsOption},    {"optimize", predict::kIterationsOption},
        {"optimize", predict::kNodeSpacingOption},  {"optimize", predict::kCoreWeightOption},
    };
    return keys;
}

fs::path bundled_design_folder() { return RFD_DESIGNS_DIR; }
fs::path bundled_holder_profile_folder() { return RFD_HOLDER_PROFILES_DIR; }

Project load_project(const fs::path& file) {
    ConfigTable root = ConfigTable::parse_file(file);
    const fs::path folder = file.parent_path().empty() ? fs::path(".") : file.parent_path();
    Project project;
    project.file = file;

    ConfigTable head = root.table("project");
    project.name = head.optional_string("name").value_or(file.stem().string());
    project.design = resolve(head, "design", folder, bundled_design_folder(), "design");
    const optics::Design design = optics::load_design(project.design);
    if (design.kind != optics::DesignKind::I && design.kind != optics::DesignKind::II)
        head.fail("design", "rfd make builds Designs I and II; " + design.name +
                                " is Design " + std::string(optics::to_string(design.kind)) +
                                " (use rfd pattern encode-angular and rfd simulate for it)");
    project.pitch_refusal = refusal([&] { calibrate::check_pitch_readable(design); });
    project.registration_refusal = refusal([&] { calibrate::check_registration_readable(design); });
    // A bundled printer is passed on by name, so the pattern records the name users know.
    const std::string printer = head.optional_string("printer").value_or("epson_stylus_pro_4800");
    if (is_file(folder / printer)) project.printer = (folder / printer).lexically_normal().string();
    else if (fs::path(printer).has_parent_path())
        head.fail("printer", "cannot open printer profile '" + printer + "': no such file (relative to the project file)");
    else {
        try {
            print::printer_file(printer);
        } catch (const Error&) {
            head.fail("printer", "cannot open printer profile '" + printer + "': no such file (relative to the project "
                                 "file) or bundled name in " + print::bundled_printer_folder().string());
        }
        project.printer = printer;
    }
    project.printer_3d = head.has("printer_3d")
                             ? resolve(head, "printer_3d", folder, bundled_holder_profile_folder(), "3D printer profile")
                             : bundled_holder_profile_folder() / "fdm_0.4mm.toml";
    head.finish();

    ConfigTable source = root.table("source");
    project.source = read_source(source, folder);
    source.finish();
    if (auto encode = root.optional_table("encode")) {
        project.encoding = read_encoding(*encode);
        encode->finish();
    }
    // The best rfd makes is the default: the pattern chosen through the simulator (Designs I
    // and II, the ones rfd make builds); `enabled = false` prints the direct encoding.
    project.optimization = Optimization{};
    if (auto optimize = root.optional_table("optimize")) {
        Optimization& o = *project.optimization;
        o.iterations = static_cast<int>(optimize->value(predict::kIterationsOption));
        o.spacing_mm = optimize->value(predict::kNodeSpacingOption);
        o.core_weight = optimize->value(predict::kCoreWeightOption);
        if (!optimize->optional_boolean("enabled").value_or(true)) project.optimization.reset();
        optimize->finish();
    }
    if (auto make = root.optional_table("make")) {
        project.outputs = read_outputs(*make);
        make->finish();
    }
    if (auto calibration = root.optional_table("calibration")) {
        project.calibration = read_calibration(*calibration, folder, project);
        calibration->finish();
    }
    root.finish();
    return project;
}

}  // namespace rfd::project
