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
#include "core/config.hpp"
#include "core/error.hpp"
#include "core/files.hpp"
#include "core/image_io.hpp"
#include "core/sphere.hpp"
#include "core/text.hpp"
#include "core/units.hpp"
#include "relight/calibration.hpp"
#include "relight/sphere_detection.hpp"
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

// The camera the photographs were taken with: a focal length in pixels given, or one in 35 mm
// film terms (given, or the first photograph's EXIF) scaled by the image diagonal; else
// orthographic, as RTIBuilder and CNR relight assume.
struct CameraChoice {
    relight::CalibrationCamera camera;
    std::string source;
};

CameraChoice choose_camera(double focal_px, double focal_35mm, const fs::path& first_image) {
    const ImageBandReader first(first_image);
    const int width = first.width(), height = first.height();
    constexpr double kFilmDiagonalMm = 43.266615305567875;  // 36 x 24 mm
    const double diagonal = std::hypot(static_cast<double>(width), static_cast<double>(height));
    if (focal_px > 0.0) return {relight::pinhole_camera(focal_px, width, height), "--focal-length-px"};
    if (focal_35mm > 0.0)
        return {relight::pinhole_camera(focal_35mm * diagonal / kFilmDiagonalMm, width, height),
                "--focal-length-35mm " + format_number(focal_35mm) + " mm"};
    if (first.spec().focal_length_35mm)
        return {relight::pinhole_camera(*first.spec().focal_length_35mm * diagonal / kFilmDiagonalMm, width, height),
                "the EXIF 35 mm focal length of " + first_image.filename().string() + ", " +
                    format_number(*first.spec().focal_length_35mm) + " mm"};
    return {relight::CalibrationCamera{}, "orthographic: no focal length given or in the EXIF"};
}

// The user's corrections: spheres' outlines, photographs to leave out, the focal length.
struct Overrides {
    std::vector<relight::MirrorSphere> spheres;
    std::vector<std::string> drop;
    double focal_length_px = 0.0;
};

Overrides read_overrides(const fs::path& file) {
    ConfigTable doc = ConfigTable::parse_file(file);
    Overrides o;
    if (const auto f = doc.optional_number("focal_length_px", 1.0, 1e7)) o.focal_length_px = *f;
    if (doc.has("sphere"))
        for (ConfigTable& sphere : doc.table_array("sphere")) {
            const std::vector<double> circle = sphere.numbers("circle_px", 3, -1e7, 1e7);
            if (!(circle[2] > 0.0)) sphere.fail("circle_px", "expected [CX, CY, R] with a radius R > 0 pixels");
            o.spheres.push_back({circle[0], circle[1], circle[2]});
            sphere.finish();
        }
    if (doc.has("drop")) o.drop = doc.strings("drop");
    doc.finish();
    return o;
}

// The spheres go primary first: given spheres, the first gives the directions.
std::string overrides_text(const std::vector<relight::CalibrationSphere>& spheres, int primary, double focal_length_px,
                           const std::vector<std::string>& drop) {
    std::string text = "# rfd capture calibrate --overrides: edit a sphere's circle, list photographs to drop.\n";
    if (focal_length_px > 0.0) text += "focal_length_px = " + format_number(focal_length_px, 17) + "\n";
    text += "drop = [";
    for (std::size_t i = 0; i < drop.size(); ++i) text += (i ? ", " : "") + toml_string(drop[i]);
    text += "]\n";
    std::vector<std::size_t> order;
    if (primary >= 0) order.push_back(static_cast<std::size_t>(primary));
    for (std::size_t s = 0; s < spheres.size(); ++s)
        if (static_cast<int>(s) != primary) order.push_back(s);
    for (const std::size_t s : order) {
        const relight::MirrorSphere& o = spheres[s].outline;
        text += "\n[[sphere]]" + std::string(s == order.front() ? "  # gives the directions" : "") +
                "\ncircle_px = [" + format_number(o.centre_x, 17) + ", " + format_number(o.centre_y, 17) + ", " +
                format_number(o.radius, 17) + "]\n";
    }
    return text;
}

// The photographs named by --drop: file names (or paths) as given, or 1-based numbers.
std::vector<bool> dropped_images(const std::vector<std::string>& images, const std::vector<std::string>& drop,
                                 const std::string& what) {
    std::vector<bool> dropped(images.size(), false);
    for (const std::string& name : drop) {
        bool matched = false;
        for (std::size_t i = 0; i < images.size(); ++i)
            if (images[i] == name || fs::path(images[i]).filename() == name) dropped[i] = matched = true;
        if (!matched && !name.empty() && std::all_of(name.begin(), name.end(), [](unsigned char c) { return std::isdigit(c); })) {
            const std::size_t number = std::stoul(name);
            if (number >= 1 && number <= images.size()) dropped[number - 1] = matched = true;
        }
        if (!matched)
            throw InputError(what + ": '" + name + "' is none of the photographs (a file name, or a number from 1 to " +
                             std::to_string(images.size()) + ")");
    }
    return dropped;
}

void add_calibrate_command(CLI::App& capture) {
    auto* cmd = capture.add_subcommand(
        "calibrate", "Light directions from the highlights on calibration spheres (chrome or black glossy), found in "
                     "the photographs by themselves, into a .lp file");
    struct Options {
        std::vector<std::string> spheres;
        std::vector<std::string> images;
        std::vector<std::string> field_images;
        std::vector<std::string> drop;
        std::string overrides;
        std::string save_overrides;
        std::string compare;
        std::string out;
        double focal_px = 0.0;
        double focal_35mm = 0.0;
        double sphere_diameter_mm = 0.0;
        bool near_lamps = false;
        bool json = false;
    };
    auto opt = std::make_shared<Options>();
    cmd->add_option("IMAGES", opt->images,
                    "Photographs, one per light: the capture with its spheres in view, or photographs of a mirror "
                    "sphere")
        ->required();
    cmd->add_option("--sphere", opt->spheres,
                    "A sphere's outline CX,CY,R in pixels from the top-left corner (pixel centres at .5), repeat for "
                    "several (the first gives the directions, the others check them); default: found in the "
                    "photographs")
        ->allow_extra_args(false)
        ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);
    cmd->add_option("--overrides", opt->overrides,
                    "TOML file of corrections: [[sphere]] circle_px = [CX, CY, R], drop = [names], focal_length_px "
                    "(write one with --save-overrides)");
    cmd->add_option("--save-overrides", opt->save_overrides,
                    "Write the spheres used, the focal length and the photographs dropped as an --overrides file");
    cmd->add_option("--drop", opt->drop, "Leave a photograph out of the light file (a file name or a number from 1); repeat for several")
        ->allow_extra_args(false)
        ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);
    auto* focal_px = cmd->add_option("--focal-length-px", opt->focal_px,
                                     "The camera's focal length in pixels (default: from --focal-length-35mm or "
                                     "the EXIF; else the camera is taken as distant)")
                         ->check(CLI::PositiveNumber);
    cmd->add_option("--focal-length-35mm", opt->focal_35mm,
                       "The lens's 35 mm-equivalent focal length in mm (default: the first photograph's EXIF)")
        ->check(CLI::PositiveNumber)
        ->excludes(focal_px);
    cmd->add_option("--sphere-diameter-mm", opt->sphere_diameter_mm,
                    "The spheres' diameter, to give near lights' positions in mm (default: in sphere radii)")
        ->check(CLI::PositiveNumber);
    cmd->add_flag("--near-lamps", opt->near_lamps,
                  "The lamps are near (a dome, a hand-held lamp): write each light's direction from the object "
                  "(under the image centre, on the spheres' table) to its lamp, placed from two spheres or more");
    cmd->add_option("--compare", opt->compare,
                    "A light file of the true directions (the dome's own), one line per photograph: print the "
                    "angular error of each light");
    cmd->add_option("--out", opt->out, "Light file to write (.lp)")->required();
    cmd->add_option("--images", opt->field_images,
                    "Field images to list in the light file, in the same order (default: the photographs)");
    cmd->add_flag("--json", opt->json, "Machine-readable summary on stdout");
    cmd->callback([opt] {
        if (!opt->field_images.empty() && opt->field_images.size() != opt->images.size())
            throw InputError("--images: got " + std::to_string(opt->field_images.size()) + " field images for " +
                             std::to_string(opt->images.size()) + " mirror-sphere images; expected one each");
        Overrides overrides;
        if (!opt->overrides.empty()) overrides = read_overrides(opt->overrides);
        std::vector<relight::MirrorSphere> given = overrides.spheres;
        if (!opt->spheres.empty()) {
            given.clear();
            for (const std::string& text : opt->spheres) given.push_back(parse_sphere(text));
        }
        std::vector<std::string> drop = overrides.drop;
        drop.insert(drop.end(), opt->drop.begin(), opt->drop.end());
        const std::vector<bool> dropped = dropped_images(opt->images, drop, opt->overrides.empty() ? "--drop" : "--drop/--overrides");
        std::vector<relight::LightEntry> truth;
        if (!opt->compare.empty()) {
            truth = relight::read_light_file(opt->compare);
            if (truth.size() != opt->images.size())
                throw InputError(SourceLocation{opt->compare}, "lists " + std::to_string(truth.size()) + " lights for " +
                                                                   std::to_string(opt->images.size()) +
                                                                   " photographs; expected one per photograph");
        }
        const std::vector<std::string>& listed = opt->field_images.empty() ? opt->images : opt->field_images;
        std::vector<std::string> names;
        for (const std::string& image : listed) names.push_back(name_in_light_file(image, opt->out));

        const std::vector<fs::path> photos(opt->images.begin(), opt->images.end());
        const CameraChoice camera =
            choose_camera(opt->focal_px > 0.0 ? opt->focal_px : overrides.focal_length_px, opt->focal_35mm, photos.front());
        const relight::CaptureCalibration calibration =
            relight::calibrate_capture(photos, {camera.camera, given, opt->near_lamps});
        if (opt->near_lamps && calibration.spheres.size() < 2)
            throw InputError("--near-lamps: lamps are placed from two spheres or more; " +
                             std::to_string(calibration.spheres.size()) + " found (give them with --sphere)");

        // Every photograph kept needs a light.
        for (std::size_t i = 0; i < photos.size(); ++i) {
            const relight::CalibratedImageLight& light = calibration.lights[i];
            if (dropped[i] || light.spheres_used > 0) continue;
            std::string why;
            for (std::size_t s = 0; s < light.highlights.size(); ++s)
                why += (s ? "; " : "") + (light.highlights.size() > 1 ? "sphere " + std::to_string(s + 1) + ": " : "") +
                       relight::highlight_problem(light.highlights[s]);
            throw InputError(SourceLocation{opt->images[i]},
                             why + (dropped.size() > 1 ? " (leave it out with --drop " + fs::path(opt->images[i]).filename().string() + ")" : ""));
        }
        std::vector<std::string> kept_names;
        std::vector<Eigen::Vector3d> directions;
        for (std::size_t i = 0; i < photos.size(); ++i)
            if (!dropped[i]) {
                kept_names.push_back(names[i]);
                directions.push_back(calibration.lights[i].direction);
            }
        if (directions.empty()) throw InputError("--drop: every photograph was dropped; nothing to calibrate");
        relight::write_light_file(opt->out, kept_names, directions);
        if (!opt->save_overrides.empty()) {
            std::vector<std::string> dropped_names;
            for (std::size_t i = 0; i < photos.size(); ++i)
                if (dropped[i]) dropped_names.push_back(fs::path(opt->images[i]).filename().string());
            write_text_file(opt->save_overrides,
                            overrides_text(calibration.spheres, calibration.primary, camera.camera.focal_length_px,
                                           dropped_names));
        }

        // Positions are in sphere radii; a diameter in mm makes them millimetres.
        const double unit = opt->sphere_diameter_mm > 0.0 ? 0.5 * opt->sphere_diameter_mm : 1.0;
        const std::string unit_name = opt->sphere_diameter_mm > 0.0 ? "mm" : "sphere radii";

        nlohmann::json spheres_json = nlohmann::json::array(), lights_json = nlohmann::json::array();
        for (std::size_t s = 0; s < calibration.spheres.size(); ++s) {
            const auto& sphere = calibration.spheres[s];
            nlohmann::json entry = {{"circle_px", {sphere.outline.centre_x, sphere.outline.centre_y, sphere.outline.radius}},
                                    {"highlights", sphere.highlights},
                                    {"detected", sphere.fit.has_value()}};
            if (sphere.aligned_rms_px) entry["aligned_rms_px"] = *sphere.aligned_rms_px;
            entry["primary"] = static_cast<int>(s) == calibration.primary;
            if (sphere.fit) {
                entry["edges"] = sphere.fit->edges;
                entry["rays"] = sphere.fit->rays;
                entry["edge_rms_px"] = sphere.fit->rms_px;
            }
            spheres_json.push_back(entry);
        }
        double sum_error = 0.0, worst_error = 0.0, sum_disagreement = 0.0, worst_disagreement = 0.0;
        std::size_t compared = 0, worst_error_at = 0, worst_disagreement_at = 0, disagreements = 0;
        std::string table;
        for (std::size_t i = 0; i < photos.size(); ++i) {
            const relight::CalibratedImageLight& light = calibration.lights[i];
            const SphericalAngles angles = angles_of(light.direction);
            const double theta = radians_to_degrees(angles.theta), phi = radians_to_degrees(angles.phi);
            nlohmann::json per_sphere = nlohmann::json::array();
            std::string points;
            for (const relight::Highlight& h : light.highlights) {
                if (h.status == relight::HighlightStatus::Found) {
                    per_sphere.push_back({{"direction", {h.direction.x(), h.direction.y(), h.direction.z()}},
                                          {"centroid_px", {h.centroid.x(), h.centroid.y()}},
                                          {"highlight_pixels", h.pixels},
                                          {"touches_rim", h.touches_rim}});
                    char cell[48];
                    std::snprintf(cell, sizeof cell, " %8.2f %8.2f", h.centroid.x(), h.centroid.y());
                    points += cell;
                } else {
                    per_sphere.push_back({{"problem", relight::highlight_problem(h)}});
                    points += "        -        -";
                }
                if (h.status == relight::HighlightStatus::Found && h.touches_rim && !dropped[i])
                    std::fprintf(stderr, "rfd: warning: %s: the highlight reaches the rim of the sphere; the light is "
                                         "nearly behind it and its direction less certain\n",
                                 opt->images[i].c_str());
            }
            nlohmann::json entry = {{"image", opt->images[i]},
                                    {"listed_as", names[i]},
                                    {"dropped", dropped[i]},
                                    {"spheres", per_sphere},
                                    {"spheres_used", light.spheres_used}};
            char row[160];
            std::snprintf(row, sizeof row, "  %-24s", fs::path(opt->images[i]).filename().c_str());
            std::string line = row;
            if (light.spheres_used > 0) {
                entry["direction"] = {light.direction.x(), light.direction.y(), light.direction.z()};
                entry["theta_deg"] = theta;
                entry["phi_deg"] = phi;
                std::snprintf(row, sizeof row, " %9.3f %9.3f", theta, phi);
                line += row;
            } else {
                line += "         -         -";
            }
            line += points;
            if (light.spheres_used > 1) {
                entry["disagreement_deg"] = light.disagreement_deg;
                std::snprintf(row, sizeof row, " %8.3f", light.disagreement_deg);
                line += row;
                if (!dropped[i]) {
                    sum_disagreement += light.disagreement_deg;
                    ++disagreements;
                    if (light.disagreement_deg >= worst_disagreement) {
                        worst_disagreement = light.disagreement_deg;
                        worst_disagreement_at = i;
                    }
                }
                if (const auto& lamp = light.lamp; lamp && !lamp->distant) {
                    entry["near_light"] = {{"position", {unit * lamp->position.x(), unit * lamp->position.y(),
                                                         unit * lamp->position.z()}},
                                           {"distance", unit * lamp->distance},
                                           {"residual_rms", unit * lamp->residual_rms},
                                           {"unit", unit_name}};
                    std::snprintf(row, sizeof row, " %10.1f", unit * lamp->distance);
                    line += row;
                } else {
                    entry["near_light"] = {{"distant", true}};
                    line += "    distant";
                }
            }
            if (!truth.empty() && light.spheres_used > 0) {
                const double error = radians_to_degrees(angle_between(light.direction, truth[i].direction));
                entry["error_deg"] = error;
                std::snprintf(row, sizeof row, " %8.3f", error);
                line += row;
                if (!dropped[i]) {
                    sum_error += error;
                    ++compared;
                    if (error >= worst_error) {
                        worst_error = error;
                        worst_error_at = i;
                    }
                }
            }
            if (dropped[i]) line += "  (dropped)";
            table += line + "\n";
            lights_json.push_back(entry);
        }
        // Worth a look: a light the spheres read far less alike than the others.
        constexpr double kDisagreementWarnDeg = 2.0;
        if (disagreements > 0 && calibration.spheres.size() > 1 &&
            worst_disagreement > std::max(kDisagreementWarnDeg, 3.0 * sum_disagreement / static_cast<double>(disagreements)))
            std::fprintf(stderr,
                         "rfd: warning: %s: the spheres' directions differ by %.2f degrees (a near lamp, or a "
                         "highlight that is not one: check it, or --drop it)\n",
                         opt->images[worst_disagreement_at].c_str(), worst_disagreement);

        if (opt->json) {
            nlohmann::json summary = {{"out", opt->out},
                                      {"camera", {{"focal_length_px", camera.camera.focal_length_px},
                                                  {"source", camera.source}}},
                                      {"candidates", calibration.candidates},
                                      {"spheres", spheres_json},
                                      {"lights", lights_json}};
            if (disagreements > 0)
                summary["disagreement_deg"] = {{"mean", sum_disagreement / static_cast<double>(disagreements)},
                                               {"worst", worst_disagreement}};
            if (compared > 0)
                summary["error_deg"] = {{"mean", sum_error / static_cast<double>(compared)}, {"worst", worst_error}};
            std::printf("%s\n", summary.dump(2).c_str());
            return;
        }
        std::printf("camera: %s\n", camera.camera.orthographic()
                                        ? "distant (orthographic): no focal length given or in the EXIF"
                                        : ("pinhole, f = " + format_number(camera.camera.focal_length_px, 6) +
                                           " px, from " + camera.source)
                                              .c_str());
        std::printf("%zu sphere(s)%s:\n", calibration.spheres.size(),
                    calibration.candidates > 0
                        ? (" found among " + std::to_string(calibration.candidates) + " specular circles").c_str()
                        : " given");
        for (std::size_t s = 0; s < calibration.spheres.size(); ++s) {
            const auto& sphere = calibration.spheres[s];
            std::printf("  sphere %zu  centre %.2f, %.2f  radius %.2f px  highlights in %d of %zu photographs",
                        s + 1, sphere.outline.centre_x, sphere.outline.centre_y, sphere.outline.radius,
                        sphere.highlights, photos.size());
            if (sphere.fit)
                std::printf("\n            outline fits %d of %d edges, rms %.2f px", sphere.fit->edges, sphere.fit->rays,
                            sphere.fit->rms_px);
            if (static_cast<int>(s) == calibration.primary) std::printf("; the lights' directions");
            if (sphere.aligned_rms_px)
                std::printf("; aligned to sphere %d's lights (distant lamps), highlights within %.2f px rms",
                            calibration.primary + 1, *sphere.aligned_rms_px);
            std::printf("\n");
        }
        std::printf("calibrated %zu light(s) into %s\n  %-24s %9s %9s", directions.size(), opt->out.c_str(),
                    "photograph", "theta deg", "phi deg");
        for (std::size_t s = 0; s < calibration.spheres.size(); ++s) std::printf("   x%zu px   y%zu px", s + 1, s + 1);
        if (calibration.spheres.size() > 1) std::printf(" %8s %10s", "differ", "lamp dist");
        if (!truth.empty()) std::printf(" %8s", "error");
        std::printf("\n%s", table.c_str());
        if (disagreements > 0)
            std::printf("spheres differ by %.3f deg on average, at most %.3f (%s)\n",
                        sum_disagreement / static_cast<double>(disagreements), worst_disagreement,
                        fs::path(opt->images[worst_disagreement_at]).filename().c_str());
        // Spheres that see a lamp from directions this far apart on average are seeing a
        // near lamp from two places, not misreading a distant one.
        constexpr double kNearHintDeg = 3.0;
        if (!opt->near_lamps && disagreements > 0 &&
            sum_disagreement / static_cast<double>(disagreements) > kNearHintDeg)
            std::printf("the spheres differ by %.1f deg on average: the lamps may be near (see 'lamp dist'); "
                        "--near-lamps writes directions from the object\n",
                        sum_disagreement / static_cast<double>(disagreements));
        if (compared > 0)
            std::printf("against %s: mean error %.3f deg, worst %.3f (%s)\n", opt->compare.c_str(),
                        sum_error / static_cast<double>(compared), worst_error,
                        fs::path(opt->images[worst_error_at]).filename().c_str());
    });
}

}  // namespace

void add_capture_tool_commands(CLI::App& capture) {
    add_hdr_command(capture);
    add_calibrate_command(capture);
}

}  // namespace rfd::cli
