// rfd capture hdr / calibrate: the tools that turn light-stage photographs into field inputs,
// HDR images from exposure brackets and light directions from a mirror sphere.

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "cli/commands.hpp"
#include "core/error.hpp"
#include "core/image_io.hpp"
#include "core/sphere.hpp"
#include "core/units.hpp"
#include "relight/calibration.hpp"
#include "relight/field.hpp"
#include "relight/hdr.hpp"

namespace rfd::cli {
namespace {

namespace fs = std::filesystem;

double parse_number(const std::string& text) {
    double value = 0.0;
    const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
    if (ec != std::errc() || end != text.data() + text.size()) throw std::invalid_argument(text);
    return value;
}

// Seconds as cameras print them: "0.25", "1/60" or "2".
double parse_exposure(const std::string& text) {
    try {
        const auto slash = text.find('/');
        if (slash == std::string::npos) return parse_number(text);
        return parse_number(text.substr(0, slash)) / parse_number(text.substr(slash + 1));
    } catch (const std::invalid_argument&) {
        throw InputError("--exposures: expected times in seconds such as 0.25 or 1/60, got '" + text + "'");
    }
}

relight::MirrorSphere parse_sphere(const std::string& text) {
    std::vector<double> values;
    std::size_t start = 0;
    try {
        for (std::size_t comma = 0; comma != std::string::npos; start = comma + 1) {
            comma = text.find(',', start);
            values.push_back(parse_number(text.substr(start, comma == std::string::npos ? comma : comma - start)));
        }
    } catch (const std::invalid_argument&) {
        values.clear();
    }
    if (values.size() != 3 || !(values[2] > 0.0))
        throw InputError("--sphere: expected CX,CY,R in pixels with R > 0, such as 320.5,240,180, got '" + text + "'");
    return {values[0], values[1], values[2]};
}

// A file name as the light file should list it: relative to the light file's folder, the
// way read_light_file() resolves it.
std::string name_in_light_file(const fs::path& image, const fs::path& light_file) {
    const fs::path base = fs::absolute(light_file).parent_path().lexically_normal();
    fs::path name = fs::absolute(image).lexically_normal().lexically_relative(base);
    if (name.empty()) name = fs::absolute(image).lexically_normal();
    const std::string text = name.generic_string();
    if (std::any_of(text.begin(), text.end(), [](unsigned char c) { return std::isspace(c); }))
        throw InputError(SourceLocation{image.string()},
                         "a light file cannot list a file name with white space in it");
    return text;
}

void add_hdr_command(CLI::App& capture) {
    auto* cmd = capture.add_subcommand(
        "hdr", "Assemble a linear HDR image from an exposure bracket of 8-bit photographs (Robertson 2003)");
    struct Options {
        std::vector<std::string> images;
        std::vector<std::string> exposures;
        bool exif = false;
        std::string out;
        std::string response;
        std::string save_response;
        bool json = false;
    };
    auto opt = std::make_shared<Options>();
    cmd->add_option("IMAGES", opt->images, "8-bit photographs of one bracket (PNG, TIFF, JPEG)")->required();
    auto* exposures = cmd->add_option("--exposures", opt->exposures,
                                      "Exposure times in seconds, one per image, comma-separated (0.25 or 1/60)")
                          ->delimiter(',');
    auto* exif = cmd->add_flag("--exif", opt->exif, "Read each image's exposure time from its EXIF ExposureTime");
    exposures->excludes(exif);
    cmd->add_option("--out", opt->out, "Output image (.exr, or .hdr), linear")->required();
    auto* response_option = cmd->add_option("--response", opt->response,
                                      "Merge with this camera response CSV instead of calibrating one "
                                      "(docs/formats.md)");
    cmd->add_option("--save-response", opt->save_response,
                    "Write the response calibrated from this bracket as CSV, for the rest of a capture")
        ->excludes(response_option);
    cmd->add_flag("--json", opt->json, "Machine-readable summary on stdout");
    cmd->callback([opt] {
        if (opt->exposures.empty() && !opt->exif)
            throw InputError("give the exposure times with --exposures T1,T2,... or read them with --exif");
        if (!is_linear_format(opt->out))
            throw InputError("--out: expected a linear image file (.exr or .hdr), got '" + opt->out + "'");
        std::vector<double> times;
        for (const std::string& text : opt->exposures) times.push_back(parse_exposure(text));
        const std::vector<fs::path> files(opt->images.begin(), opt->images.end());
        const relight::Bracket bracket = relight::read_bracket(files, times);

        const bool calibrating = opt->response.empty();
        const bool ambiguous = calibrating && relight::regular_exposure_ratios(bracket.exposure_seconds);
        if (ambiguous)
            std::fprintf(stderr, "rfd: warning: the exposure times are all one ratio apart; the calibrated "
                                 "response is ambiguous up to a periodic ripple (docs/formats.md): calibrate "
                                 "from a bracket with uneven steps and pass it with --response\n");
        const relight::CameraResponse response =
            calibrating ? relight::calibrate_response(bracket) : relight::read_response(opt->response);
        if (!opt->save_response.empty()) relight::write_response(opt->save_response, response);
        const relight::MergedImage merged = relight::merge_bracket(bracket, response);
        write_image(opt->out, merged.radiance);

        float low = 0.0f, high = 0.0f;  // smallest positive and largest value
        for (const float v : merged.radiance.samples()) {
            if (v > 0.0f && (low == 0.0f || v < low)) low = v;
            high = std::max(high, v);
        }
        const double samples = static_cast<double>(merged.radiance.samples().size());
        if (opt->json) {
            const nlohmann::json summary = {
                {"images", opt->images},
                {"exposure_seconds", bracket.exposure_seconds},
                {"out", opt->out},
                {"width", merged.radiance.width()},
                {"height", merged.radiance.height()},
                {"channels", merged.radiance.channels()},
                {"response", calibrating ? std::string("calibrated") : opt->response},
                {"response_saved", opt->save_response},
                {"regular_exposure_ratios", relight::regular_exposure_ratios(bracket.exposure_seconds)},
                {"saturated_samples", merged.saturated_samples},
                {"black_samples", merged.black_samples},
                {"min_positive", low},
                {"max", high}};
            std::printf("%s\n", summary.dump(2).c_str());
        } else {
            std::printf("merged %zu exposures into %s\n", bracket.images.size(), opt->out.c_str());
            std::printf("  image              %d x %d, %d channel(s)\n", merged.radiance.width(),
                        merged.radiance.height(), merged.radiance.channels());
            std::printf("  exposures          ");
            for (const double t : bracket.exposure_seconds) std::printf("%g s  ", t);
            const std::string source = !calibrating ? opt->response
                                       : opt->save_response.empty() ? std::string("calibrated from this bracket")
                                                                    : "calibrated, saved to " + opt->save_response;
            std::printf("\n  response           %s\n", source.c_str());
            std::printf("  range              %.4g .. %.4g (%.1f stops)\n", static_cast<double>(low),
                        static_cast<double>(high), low > 0.0f ? std::log2(high / low) : 0.0);
            std::printf("  clipped            %zu saturated (%.2f%%), %zu black (%.2f%%) in every exposure\n",
                        merged.saturated_samples, 100.0 * static_cast<double>(merged.saturated_samples) / samples,
                        merged.black_samples, 100.0 * static_cast<double>(merged.black_samples) / samples);
        }
    });
}

void add_calibrate_command(CLI::App& capture) {
    auto* cmd = capture.add_subcommand(
        "calibrate", "Light directions from the highlight on a mirror sphere, one photograph per light, into a .lp file");
    struct Options {
        std::string sphere;
        std::vector<std::string> mirror_images;
        std::vector<std::string> field_images;
        std::string out;
        bool json = false;
    };
    auto opt = std::make_shared<Options>();
    cmd->add_option("MIRROR_IMAGES", opt->mirror_images, "Photographs of the mirror sphere, one per light")->required();
    cmd->add_option("--sphere", opt->sphere,
                    "Outline of the sphere in the images, CX,CY,R: centre and radius in pixels from the "
                    "top-left corner (pixel centres at .5)")
        ->required();
    cmd->add_option("--out", opt->out, "Light file to write (.lp)")->required();
    cmd->add_option("--images", opt->field_images,
                    "Field images to list in the light file, in the same order (default: the mirror images)");
    cmd->add_flag("--json", opt->json, "Machine-readable summary on stdout");
    cmd->callback([opt] {
        if (!opt->field_images.empty() && opt->field_images.size() != opt->mirror_images.size())
            throw InputError("--images: got " + std::to_string(opt->field_images.size()) + " field images for " +
                             std::to_string(opt->mirror_images.size()) + " mirror-sphere images; expected one each");
        const relight::MirrorSphere sphere = parse_sphere(opt->sphere);
        const std::vector<fs::path> mirrors(opt->mirror_images.begin(), opt->mirror_images.end());
        const std::vector<std::string>& listed = opt->field_images.empty() ? opt->mirror_images : opt->field_images;
        std::vector<std::string> names;
        for (const std::string& image : listed) names.push_back(name_in_light_file(image, opt->out));

        const std::vector<relight::CalibratedLight> lights = relight::calibrate_lights(mirrors, sphere);
        std::vector<Eigen::Vector3d> directions;
        for (const auto& light : lights) directions.push_back(light.highlight.direction);
        relight::write_light_file(opt->out, names, directions);

        nlohmann::json entries = nlohmann::json::array();
        if (!opt->json)
            std::printf("calibrated %zu light(s) into %s\n  %-28s %9s %9s %8s %8s\n", lights.size(), opt->out.c_str(),
                        "mirror image", "theta deg", "phi deg", "x px", "y px");
        for (std::size_t i = 0; i < lights.size(); ++i) {
            const relight::Highlight& h = lights[i].highlight;
            const SphericalAngles angles = angles_of(h.direction);
            const double theta = radians_to_degrees(angles.theta), phi = radians_to_degrees(angles.phi);
            if (h.touches_rim)
                std::fprintf(stderr, "rfd: warning: %s: the highlight reaches the rim of the sphere; the light is "
                                     "nearly behind it and its direction less certain\n",
                             opt->mirror_images[i].c_str());
            if (opt->json) {
                entries.push_back({{"mirror_image", opt->mirror_images[i]},
                                   {"listed_as", names[i]},
                                   {"direction", {h.direction.x(), h.direction.y(), h.direction.z()}},
                                   {"theta_deg", theta},
                                   {"phi_deg", phi},
                                   {"centroid_px", {h.centroid.x(), h.centroid.y()}},
                                   {"highlight_pixels", h.pixels},
                                   {"touches_rim", h.touches_rim}});
            } else {
                std::printf("  %-28s %9.3f %9.3f %8.2f %8.2f%s\n", fs::path(opt->mirror_images[i]).filename().c_str(),
                            theta, phi, h.centroid.x(), h.centroid.y(), h.direction.z() <= 0.0 ? "  (below the horizon)" : "");
            }
        }
        if (opt->json) {
            const nlohmann::json summary = {{"out", opt->out},
                                            {"sphere", {{"centre_x", sphere.centre_x},
                                                        {"centre_y", sphere.centre_y},
                                                        {"radius", sphere.radius}}},
                                            {"lights", entries}};
            std::printf("%s\n", summary.dump(2).c_str());
        }
    });
}

}  // namespace

void add_capture_tool_commands(CLI::App& capture) {
    add_hdr_command(capture);
    add_calibrate_command(capture);
}

}  // namespace rfd::cli
