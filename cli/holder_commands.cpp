// rfd holder: the 3D-printable lens holder of a design as parametric OpenSCAD, its STLs
// built with openscad, and the checks of those STLs (mesh, volume, seats, beam clearance);
// rfd holder coupon: the fit-test coupon that calibrates the clearance for a printer.

#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>

#include <nlohmann/json.hpp>

#include "cli/arguments.hpp"
#include "cli/commands.hpp"
#include "core/error.hpp"
#include "core/files.hpp"
#include "core/progress.hpp"
#include "core/text.hpp"
#include "holders/checks.hpp"
#include "holders/coupon.hpp"
#include "holders/generate.hpp"
#include "holders/openscad.hpp"
#include "holders/profile.hpp"
#include "optics/design.hpp"
#include "patterns/raster.hpp"
#include "print/printed.hpp"

namespace rfd::cli {
namespace {

namespace fs = std::filesystem;

holders::HolderProfile read_profile(const std::string& file) {
    return file.empty() ? holders::HolderProfile{} : holders::load_profile(file);
}

// STEM.stl -> STEM_PART.stl
fs::path part_stl(const fs::path& stl, const std::string& part) {
    fs::path out = stl;
    out.replace_filename(stl.stem().string() + "_" + part + ".stl");
    return out;
}

// What the generator made, before any STL: the report of `--json` without `--stl`, and the
// start of the one with it. Keys are those of check_json's entries for the same things.
nlohmann::json holder_json(const holders::Holder& holder, const std::string& scad) {
    nlohmann::json parts = nlohmann::json::array();
    for (const auto& p : holder.parts)
        parts.push_back({{"name", p.name},
                         {"copies", p.copies},
                         {"print", p.print_note},
                         {"expected_volume_mm3", holder.part_volume(p)}});
    nlohmann::json seats = nlohmann::json::array();
    for (const auto& s : holder.seats) seats.push_back({{"plane", s.plane}, {"face", s.what}, {"expected_z_mm", s.z}});
    return {{"scad", scad},
            {"title", holder.title},
            {"notes", holder.notes},
            {"field_of_view_half_deg", holder.fov_half_deg},
            {"parts", parts},
            {"seats", seats}};
}

nlohmann::json check_json(const holders::HolderCheck& check, const holders::Holder& holder) {
    nlohmann::json parts = nlohmann::json::array();
    for (const auto& p : check.parts)
        parts.push_back({{"name", p.name},
                         {"stl", p.stl.string()},
                         {"volume_mm3", p.mesh.volume_mm3},
                         {"expected_volume_mm3", p.expected_volume},
                         {"volume_error", p.volume_error},
                         {"box_error_mm", p.box_error},
                         {"closed", p.mesh.closed},
                         {"bounds_volume", p.mesh.bounds_volume},
                         {"outward", p.mesh.outward},
                         {"self_intersecting", p.mesh.self_intersecting},
                         {"components", p.mesh.components}});
    nlohmann::json seats = nlohmann::json::array();
    for (const auto& s : check.seats)
        seats.push_back({{"plane", s.plane},
                         {"face", s.what},
                         {"part", s.part},
                         {"expected_z_mm", s.expected_z},
                         {"measured_z_mm", json_or_null(s.measured_z)}});
    return {{"parts", parts},
            {"seats", seats},
            {"beam_clearance",
             {{"field_of_view_half_deg", holder.fov_half_deg},
              {"rays", check.clearance.rays},
              {"segments", check.clearance.segments},
              {"blocked", check.clearance.blocked},
              {"min_clearance_mm", check.clearance.min_clearance}}},
            {"problems", check.problems()}};
}

void print_check(const holders::HolderCheck& check, const holders::Holder& holder) {
    for (const auto& p : check.parts)
        std::printf("part %-7s %s: %s, %zu piece%s, volume %.1f mm^3 (closed form %.1f, %+.3f %%), box within %.3f mm\n",
                    p.name.c_str(), p.stl.string().c_str(), p.mesh.problems().empty() ? "closed solid" : "NOT A SOLID",
                    p.mesh.components, p.mesh.components == 1 ? "" : "s", p.mesh.volume_mm3, p.expected_volume,
                    100 * p.volume_error, p.box_error);
    for (const auto& s : check.seats)
        std::printf("seat %s (%s, part %s): z = %s mm, design %.3f mm\n", s.plane.c_str(), s.what.c_str(),
                    s.part.c_str(), s.measured_z ? (std::to_string(*s.measured_z).substr(0, 8) + " (" +
                                                    std::to_string(s.error() * 1000).substr(0, 6) + " um)").c_str()
                                                 : "none",
                    s.expected_z);
    std::printf("beam clearance: %zu rays of the field of view (half-angle %.1f deg) through the clear apertures, "
                "%zu touch the holder; closest approach %.3f mm (part %s)\n",
                check.clearance.rays, holder.fov_half_deg, check.clearance.blocked, check.clearance.min_clearance,
                check.clearance.closest_part.c_str());
}

void add_coupon_command(CLI::App& holder_cmd) {
    struct Options {
        std::string out, stl, profile;
        double diameter = 25.0;
        double square = 24.0;
        bool json = false;
    };
    auto opt = std::make_shared<Options>();
    auto* cmd = holder_cmd.add_subcommand(
        "coupon", "Fit-test coupon: seat rings (round and square) stepping the clearance, to calibrate a printer");
    cmd->add_option("--out", opt->out, "OpenSCAD file to write")->required();
    cmd->add_option("--stl", opt->stl, "Also build the STL here with openscad, and check it");
    cmd->add_option("--3d-printer,--printer-profile", opt->profile, "3D printer profile TOML (holders/profiles/)");
    cmd->add_option("--diameter", opt->diameter, "Diameter of the round part to fit, mm")->check(CLI::Range(2.0, 200.0));
    cmd->add_option("--square", opt->square, "Side of the square part (lenslet array) to fit, mm")->check(CLI::Range(2.0, 200.0));
    cmd->add_flag("--json", opt->json, "Machine-readable report on stdout");
    cmd->callback([opt] {
        const holders::HolderProfile profile = read_profile(opt->profile);
        const holders::Coupon coupon = holders::make_coupon(opt->diameter, opt->square, profile);
        write_text_file(opt->out, coupon.scad);
        nlohmann::json report = {{"scad", opt->out},
                                 {"diameter_mm", opt->diameter},
                                 {"square_mm", opt->square},
                                 {"clearances_mm", coupon.clearances},
                                 {"expected_volume_mm3", coupon.volume}};
        if (!opt->json)
            std::printf("wrote %s: %zu seat rings for a %.2f mm round part and a %.2f mm square part, clearance %.2f to %.2f mm\n",
                        opt->out.c_str(), coupon.clearances.size(), opt->diameter, opt->square, coupon.clearances.front(),
                        coupon.clearances.back());
        if (opt->stl.empty()) {
            if (opt->json) std::printf("%s\n", report.dump(2).c_str());
            return;
        }
        if (Progress::enabled()) std::fprintf(stderr, "building %s with openscad...\n", opt->stl.c_str());
        const holders::StlBuild build = holders::build_stl(opt->out, "coupon", opt->stl);
        const holders::MeshCheck mesh = holders::check_stl(opt->stl);
        auto problems = mesh.problems();
        if (std::abs(mesh.volume_mm3 / coupon.volume - 1) > 0.005) problems.push_back("volume off the closed form");
        if (opt->json) {
            report["stl"] = opt->stl;
            report["seconds"] = build.seconds;
            report["volume_mm3"] = mesh.volume_mm3;
            report["problems"] = problems;
            std::printf("%s\n", report.dump(2).c_str());
        } else {
            std::printf("wrote %s in %.1f s: volume %.1f mm^3 (closed form %.1f)\n", opt->stl.c_str(), build.seconds,
                        mesh.volume_mm3, coupon.volume);
        }
        if (!problems.empty()) {
            std::string message = opt->stl + ": the coupon failed its checks:";
            for (const auto& p : problems) message += "\n  " + p;
            throw Error(message);
        }
    });
}

}  // namespace

void add_holder_commands(CLI::App& app) {
    struct Options {
        std::string design, out, stl, profile, printer, pattern;
        double time_limit = 300.0;
        bool json = false;
    };
    auto opt = std::make_shared<Options>();
    auto* cmd = app.add_subcommand("holder", "3D-printable lens holder for a design: OpenSCAD, STLs and their checks");
    cmd->add_option("DESIGN", opt->design, "Design TOML file");
    cmd->add_option("--out", opt->out, "OpenSCAD file to write");
    cmd->add_option("--stl", opt->stl,
                    "Build the STLs with openscad: STEM.stl gives STEM_base.stl and STEM_lid.stl "
                    "(Design IV: STEM_bottom, STEM_middle, STEM_top); then check them");
    cmd->add_option("--3d-printer,--printer-profile", opt->profile, "3D printer profile TOML (holders/profiles/)");
    cmd->add_option("--printer", opt->printer,
                    "The film printer's profile (printers/, or a bundled name): its film thickness and sheets size the "
                    "pattern's pocket. Default: the pattern's (--pattern), else the design's default printer");
    cmd->add_option("--pattern", opt->pattern, "The pattern the holder is for: the printer it records");
    cmd->add_option("--time-limit", opt->time_limit, "Seconds openscad may take per part")->check(CLI::Range(1.0, 36000.0));
    cmd->add_flag("--json", opt->json, "Machine-readable report on stdout");
    add_coupon_command(*cmd);
    cmd->callback([opt, cmd] {
        if (!cmd->get_subcommands().empty()) return;  // the coupon ran
        if (opt->design.empty() || opt->out.empty())
            throw InputError("rfd holder: give a design file and --out FILE.scad (or use `rfd holder coupon`)");
        const optics::Design design = optics::load_design(opt->design);
        const holders::HolderProfile profile = read_profile(opt->profile);
        const print::PrinterProfile printer =
            opt->pattern.empty()
                ? printer_for(design, opt->printer)
                : print::printer_for_pattern(design, opt->pattern, opt->printer);
        const holders::Holder holder = holders::make_holder(design, profile, {printer.film, printer.sheets});
        write_text_file(opt->out, holders::to_scad(holder));
        if (!opt->json) {
            std::printf("wrote %s: %s\n", opt->out.c_str(), holder.title.c_str());
            std::printf("  pattern film: %d sheet(s) of %s mm, from printer '%s'\n", printer.sheets,
                        format_number(printer.film).c_str(), printer.name.c_str());
            for (const auto& note : holder.notes) std::printf("  %s\n", note.c_str());
        }
        if (opt->stl.empty()) {
            if (opt->json) std::printf("%s\n", holder_json(holder, opt->out).dump(2).c_str());
            return;
        }
        std::vector<std::pair<holders::PrintedPart, fs::path>> stls;
        nlohmann::json builds = nlohmann::json::array();
        for (const auto& part : holder.parts) {
            const fs::path stl = part_stl(opt->stl, part.name);
            if (Progress::enabled()) std::fprintf(stderr, "building %s with openscad...\n", stl.string().c_str());
            const holders::StlBuild build = holders::build_stl(opt->out, part.name, stl, opt->time_limit);
            builds.push_back({{"part", part.name}, {"stl", stl.string()}, {"seconds", build.seconds},
                              {"slivers_removed", build.slivers}, {"copies", part.copies}});
            if (!opt->json)
                std::printf("built %s in %.1f s (%zu sliver triangles of the tessellation removed)\n",
                            stl.string().c_str(), build.seconds, build.slivers);
            stls.emplace_back(part, stl);
        }
        const holders::HolderCheck check = holders::check_holder(holder, design, stls);
        if (opt->json) {
            nlohmann::json out = check_json(check, holder);
            out["scad"] = opt->out;
            out["title"] = holder.title;
            out["notes"] = holder.notes;
            out["builds"] = builds;
            std::printf("%s\n", out.dump(2).c_str());
        } else {
            print_check(check, holder);
        }
        const auto problems = check.problems();
        if (!problems.empty()) {
            std::string message = "the holder failed its checks:";
            for (const auto& p : problems) message += "\n  " + p;
            throw Error(message);
        }
    });
}

}  // namespace rfd::cli
