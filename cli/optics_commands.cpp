// rfd optics system | trace: single lens systems (the lens-system file format).

#include <cmath>
#include <cstdio>
#include <memory>
#include <optional>
#include <string>

#include <nlohmann/json.hpp>

#include "cli/arguments.hpp"
#include "cli/commands.hpp"
#include "optics/exact.hpp"
#include "optics/lens_file.hpp"
#include "optics/paraxial.hpp"
#include "optics/spot.hpp"

namespace rfd::cli {
namespace {

nlohmann::json to_json(const optics::CardinalPoints& p) {
    return {{"n_in", p.n_in},
            {"n_out", p.n_out},
            {"afocal", p.afocal},
            {"efl_mm", p.efl},
            {"bfl_mm", p.bfl},
            {"ffl_mm", p.ffl},
            {"front_focal_z_mm", p.front_focal_z},
            {"rear_focal_z_mm", p.rear_focal_z},
            {"front_principal_z_mm", p.front_principal_z},
            {"rear_principal_z_mm", p.rear_principal_z},
            {"abcd", {{p.matrix.a, p.matrix.b}, {p.matrix.c, p.matrix.d}}}};
}

std::optional<double> image_plane_z(const optics::SequentialSystem& system) {
    if (optics::last_lens_surface(system) + 1 == system.surfaces.size()) return std::nullopt;
    return system.surfaces.back().z;
}

void print_system(const optics::SequentialSystem& system, const optics::CardinalPoints& p) {
    std::printf("%s\n", system.name.c_str());
    std::printf("  surfaces                 %zu (first vertex z = %.4f mm, last z = %.4f mm)\n",
                optics::last_lens_surface(system) + 1, p.first_vertex_z, p.last_vertex_z);
    if (const auto image = image_plane_z(system))
        std::printf("  image plane              z = %.4f mm\n", *image);
    if (p.afocal) {
        std::printf("  afocal system: no finite focal length\n");
    } else {
        std::printf("  effective focal length   %.4f mm\n", p.efl);
        std::printf("  back focal length        %.4f mm (from the last vertex)\n", p.bfl);
        std::printf("  front focal length       %.4f mm (to the first vertex)\n", p.ffl);
        std::printf("  front principal plane    z = %.4f mm (%+.4f mm from the first vertex)\n",
                    p.front_principal_z, p.front_principal_z - p.first_vertex_z);
        std::printf("  rear principal plane     z = %.4f mm (%+.4f mm from the last vertex)\n",
                    p.rear_principal_z, p.rear_principal_z - p.last_vertex_z);
    }
    std::printf("  ABCD (vertex to vertex, y in mm, u = tan)\n");
    std::printf("    [ %12.8f  %12.8f ]\n    [ %12.8f  %12.8f ]\n", p.matrix.a, p.matrix.b,
                p.matrix.c, p.matrix.d);
}

}  // namespace

void add_optics_commands(CLI::App& app) {
    auto* optics_cmd = app.add_subcommand("optics", "Analyse lens systems and design optics");
    optics_cmd->require_subcommand(1);
    add_chart_command(*optics_cmd);

    {
        auto* cmd = optics_cmd->add_subcommand(
            "system", "Paraxial properties of a lens system: focal lengths, principal planes, ABCD");
        struct Options {
            std::string file;
            bool json = false;
        };
        auto opt = std::make_shared<Options>();
        cmd->add_option("LENS", opt->file, "Lens-system TOML file")->required();
        cmd->add_flag("--json", opt->json, "Machine-readable output");
        cmd->callback([opt] {
            const auto system = optics::load_lens_system(opt->file);
            const auto points = optics::cardinal_points(system, 0, optics::last_lens_surface(system));
            if (opt->json) {
                nlohmann::json out = to_json(points);
                out["name"] = system.name;
                out["image_plane_z_mm"] = json_or_null(image_plane_z(system));
                std::printf("%s\n", out.dump(2).c_str());
            } else {
                print_system(system, points);
            }
        });
    }
    {
        auto* cmd = optics_cmd->add_subcommand(
            "trace", "Exact trace of a lens system at a field angle, against the paraxial model");
        struct Options {
            std::string file;
            double angle_deg = 0.0;
            double pupil_mm = -1.0;
            int rays = 0;  // add_option sets the default
            bool json = false;
        };
        auto opt = std::make_shared<Options>();
        cmd->add_option("LENS", opt->file, "Lens-system TOML file")->required();
        cmd->add_option("--angle", opt->angle_deg, "Field angle in degrees (in the y-z plane)")
            ->check(CLI::Range(-89.9, 89.9));
        cmd->add_option("--pupil", opt->pupil_mm,
                        "Entrance pupil semi-diameter in mm (default: first surface's)")
            ->check(positive_number());
        add_option(*cmd, optics::kPupilRaysOption, opt->rays);
        cmd->add_flag("--json", opt->json, "Machine-readable output");
        cmd->callback([opt] {
            const auto system = optics::load_lens_system(opt->file);
            const auto report = optics::spot_report(system, opt->angle_deg, opt->pupil_mm, opt->rays);
            const double angle_deg = opt->angle_deg;
            if (opt->json) {
                nlohmann::json out = {
                    {"field_angle_deg", report.field_angle_deg},
                    {"pupil_semi_diameter_mm", report.pupil_semi_diameter},
                    {"rays_traced", report.rays_traced},
                    {"focal_plane_z_mm", report.focal_plane_z},
                    {"chief_height_exact_mm", json_or_null(report.chief_height_exact)},
                    {"chief_height_paraxial_mm", report.chief_height_paraxial},
                    {"chief_status", optics::to_string(report.chief_status)},
                    {"rms_spot_radius_mm", json_or_null(report.rms_spot_radius)}};
                for (int s = 0; s < optics::kRayStatusCount; ++s)
                    out["status_counts"][std::string(optics::to_string(static_cast<optics::RayStatus>(s)))] =
                        report.status_counts[static_cast<std::size_t>(s)];
                out["name"] = system.name;
                std::printf("%s\n", out.dump(2).c_str());
                return;
            }
            std::printf("%s at %.3f deg, pupil semi-diameter %.4f mm, %zu rays\n",
                        system.name.c_str(), angle_deg, report.pupil_semi_diameter,
                        report.rays_traced);
            std::printf("  paraxial focal plane       z = %.6f mm\n", report.focal_plane_z);
            if (report.chief_height_exact)
                std::printf("  chief ray height, exact    %.6f mm\n", *report.chief_height_exact);
            else if (report.chief_status != optics::RayStatus::Ok)
                std::printf("  chief ray height, exact    none: the chief ray is %s\n",
                            std::string(optics::to_string(report.chief_status)).c_str());
            else
                std::printf("  chief ray height, exact    none: the chief ray leaves parallel to the focal plane\n");
            std::printf("  chief ray height, paraxial %.6f mm\n", report.chief_height_paraxial);
            if (report.chief_height_exact)
                std::printf("  difference                 %.3f um\n",
                            1000.0 * (*report.chief_height_exact - report.chief_height_paraxial));
            if (report.rms_spot_radius)
                std::printf("  RMS spot radius            %.3f um (about the centroid)\n",
                            1000.0 * *report.rms_spot_radius);
            else
                std::printf("  RMS spot radius            none: no ray reached the focal plane\n");
            std::printf("  rays by status:\n");
            for (int s = 0; s < optics::kRayStatusCount; ++s)
                std::printf("    %-36s %zu\n",
                            std::string(optics::to_string(static_cast<optics::RayStatus>(s))).c_str(),
                            report.status_counts[static_cast<std::size_t>(s)]);
        });
    }
}

}  // namespace rfd::cli
