// rfd simulate for Designs III and IV: what leaves an observer-variant display under given
// lights, seen from chosen viewpoints, predicted from its design and its pattern as printed.
// The `simulate` command's own options (SimulateOptions: DESIGN, PATTERN, --light, --out,
// --model, --printer, --brightness, --sheets, --area-samples, --max-rays, --json) come from
// it; the options below only matter for these designs.

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "cli/arguments.hpp"
#include "cli/commands.hpp"
#include "cli/simulate_options.hpp"
#include "core/error.hpp"
#include "core/number.hpp"
#include "core/image_io.hpp"
#include "core/sphere.hpp"
#include "core/units.hpp"
#include "optics/diffraction.hpp"
#include "optics/display_angular.hpp"
#include "patterns/angular.hpp"
#include "predict/display_lights.hpp"
#include "predict/prediction_report.hpp"
#include "print/printed.hpp"

namespace rfd::cli {

struct ObserverVariantOptions {
    std::vector<std::string> views, eyes, distributions;
    std::string macro_out, distribution_out;
    int lens_rays = 0, distribution_pixels = 64, zoom = 1;  // add_option sets lens_rays' default
    double kernel = 2.0;
};

namespace {

// "A,B[,C]" as numbers, naming the option in the error.
std::vector<double> numbers(const std::string& text, const std::string& option, std::size_t count) {
    std::vector<double> values;
    std::stringstream in(text);
    std::string part;
    while (std::getline(in, part, ',')) {
        const std::optional<double> value = finite_number(part);
        if (!value)
            throw InputError(option + " '" + text + "': expected " + std::to_string(count) + " numbers separated by commas");
        values.push_back(*value);
    }
    if (values.size() != count)
        throw InputError(option + " '" + text + "': expected " + std::to_string(count) + " numbers separated by commas");
    return values;
}

// name.ext -> name_SUFFIX.ext
std::filesystem::path with_suffix(const std::filesystem::path& path, const std::string& suffix) {
    return path.parent_path() / (path.stem().string() + "_" + suffix + path.extension().string());
}

// Nearest-neighbour enlargement, so that a 7 x 7 picture can be looked at.
Image zoomed(const Image& image, int zoom) {
    if (zoom <= 1) return image;
    Image out(image.width() * zoom, image.height() * zoom, image.channels());
    for (int c = 0; c < image.channels(); ++c)
        for (int y = 0; y < out.height(); ++y)
            for (int x = 0; x < out.width(); ++x) out.at(x, y, c) = image.at(x / zoom, y / zoom, c);
    return out;
}

// --light in the field's frame to display lights: the mirror of patterns/angular.hpp's
// field_light_of.
std::vector<optics::DisplayLight> observer_lights(const std::vector<std::string>& texts) {
    std::vector<optics::DisplayLight> lights;
    for (const std::string& text : texts) {
        const relight::Light light = parse_light(text);
        optics::DisplayLight d;
        Eigen::Vector3d toward, colour;
        if (const auto* point = std::get_if<relight::DirectionalLight>(&light)) {
            toward = point->direction;
            colour = point->irradiance;
        } else {
            const auto& disc = std::get<relight::DiskLight>(light);
            toward = disc.direction;
            d.angular_radius_rad = disc.radius;
            colour = disc.irradiance;
        }
        d.direction = patterns::field_light_of(toward);  // its own inverse
        d.colour = {colour.x(), colour.y(), colour.z()};
        lights.push_back(d);
    }
    return lights;
}

// --view and --eye into `options` (one distant view from 0,0 when neither is given); their
// names for the report.
std::vector<std::string> add_viewpoints(const ObserverVariantOptions& opt, optics::AngularSimulationOptions& options) {
    std::vector<std::string> view_names;
    for (const std::string& text : opt.views) {
        const auto v = numbers(text, "--view", 2);
        optics::Viewpoint view;
        view.direction = direction_from_angles(degrees_to_radians(v[0]), degrees_to_radians(v[1]));
        options.views.push_back(view);
        view_names.push_back("view " + text);
    }
    for (const std::string& text : opt.eyes) {
        const auto v = numbers(text, "--eye", 3);
        optics::Viewpoint view;
        view.eye_mm = Eigen::Vector3d(v[0], v[1], v[2]);
        options.views.push_back(view);
        view_names.push_back("eye " + text);
    }
    if (options.views.empty()) {
        options.views.push_back(optics::Viewpoint{});
        view_names.push_back("view 0,0");
    }
    return view_names;
}

// --distribution U,V into `options`; the suffixes of their files ("U_V").
std::vector<std::string> add_distributions(const ObserverVariantOptions& opt, optics::AngularSimulationOptions& options) {
    std::vector<std::string> suffixes;
    for (const std::string& text : opt.distributions) {
        const auto v = numbers(text, "--distribution", 2);
        if (v[0] != std::floor(v[0]) || v[1] != std::floor(v[1]))
            throw InputError("--distribution '" + text + "': expected whole macro-pixel indices U,V");
        options.distributions.push_back({static_cast<int>(v[0]), static_cast<int>(v[1])});
        suffixes.push_back(std::to_string(static_cast<int>(v[0])) + "_" + std::to_string(static_cast<int>(v[1])));
    }
    return suffixes;
}

// The options of Designs I and II's diffuser picture, refused here by name.
void refuse_diffuser_options(const CLI::App& simulate, const SimulateOptions& common) {
    const std::string& design_file = common.design;
    if (simulate.count("--rays") > 0 || simulate.count("--lenslets") > 0 || simulate.count("--pixels-per-lenslet") > 0)
        throw InputError(SourceLocation{design_file, 0, 0, "design.kind"},
                         "--rays-per-side, --lenslets and --pixels-per-lenslet are for Designs I and II; Designs III and IV "
                         "take --lens-rays, --view, --eye, --macro and --distribution");
    if (simulate.count("--frame") > 0 && common.frame != predict::LightFrame::Field)
        throw InputError(SourceLocation{design_file, 0, 0, "design.kind"},
                         "Designs III and IV take --light in the field's frame (--frame field): their patterns "
                         "have no tilt, and the field's directions are the cells' incident bins");
    for (const char* name : {"--front", "--diffuser-transmittance", "--diffuser-reflectance"})
        if (simulate.count(name) > 0)
            throw InputError(SourceLocation{design_file, 0, 0, "design.kind"},
                             std::string(name) + " is for Designs I and II (a diffuser shows the picture)");
}

}  // namespace

std::shared_ptr<ObserverVariantOptions> add_observer_variant_options(CLI::App& simulate) {
    auto opt = std::make_shared<ObserverVariantOptions>();
    const std::string group = "Designs III and IV";
    simulate.add_option("--view", opt->views,
                        "III/IV: a distant observer at THETA,PHI (degrees, field frame: the direction toward the "
                        "observer); repeat for several (one image each, --out gets _view1, _view2, ...); none: one from 0,0")
        ->group(group);
    simulate.add_option("--eye", opt->eyes,
                        "III/IV: an observer's eye at X,Y,Z mm (display frame; Z in front of the last lens surface); "
                        "repeatable, numbered after the --view images")
        ->group(group);
    simulate.add_option("--macro", opt->macro_out,
                        "III/IV: also the picture of each view at the macro-pixel resolution (mean over its "
                        "meso-pixels), as a distant observer sees it; suffixed like --out")
        ->group(group);
    simulate.add_option("--distribution", opt->distributions,
                        "III/IV: the angular distribution of macro-pixel U,V (0,0 bottom left); repeatable")
        ->group(group);
    simulate.add_option("--distribution-out", opt->distribution_out,
                        "III/IV: file for the distributions (.exr/.png), suffixed _U_V")
        ->group(group);
    simulate.add_option("--distribution-pixels", opt->distribution_pixels,
                        "III/IV: pixels per side of a distribution image")
        ->check(CLI::Range(2, 4096))
        ->group(group);
    add_option(simulate, optics::kLensRaysOption, opt->lens_rays)->group(group);
    simulate.add_option("--kernel", opt->kernel,
                        "III/IV: radius of the kernel over output directions, in ray spacings")
        ->check(CLI::Range(0.5, 64.0))
        ->group(group);
    simulate.add_option("--zoom", opt->zoom, "III/IV: enlarge the view images N times (nearest)")
        ->check(CLI::Range(1, 256))
        ->group(group);
    return opt;
}

void simulate_observer_variant(const CLI::App& simulate, const SimulateOptions& common, const ObserverVariantOptions& opt) {
    const auto start = std::chrono::steady_clock::now();
    const std::string& design_file = common.design;
    const std::string& pattern_file = common.pattern;
    const std::string& out = common.out;
    const std::vector<std::string>& light_texts = common.lights;
    refuse_diffuser_options(simulate, common);
    const std::string& envmap = common.envmap;
    if (!opt.distributions.empty() && opt.distribution_out.empty())
        throw InputError("--distribution needs --distribution-out FILE");

    const optics::Design design = optics::load_design(design_file);
    const optics::AngularDisplaySimulator simulator(design);
    const print::PrintedTransparency pattern = printed_pattern(design, pattern_file, common.print);

    std::vector<optics::DisplayLight> lights = observer_lights(light_texts);

    // An environment map: one light per lit pixel, mapped as the lights above. Every
    // direction traces the whole main lens (--lens-rays squared rays), so the map is
    // box-filtered to at most --max-rays / 16 lit directions, which still
    // puts many directions in each of the display's few incident bins.
    predict::EnvironmentSampling sampling;
    if (!envmap.empty()) {
        const std::size_t budget = std::max<std::size_t>(1, common.max_rays / 16);
        const std::vector<optics::DisplayLight> sky = predict::environment_lights(
            read_image(envmap), envmap, [](const Eigen::Vector3d& field) { return patterns::field_light_of(field); },
            0.0, budget, &sampling);
        lights.insert(lights.end(), sky.begin(), sky.end());
    }
    if (lights.empty())
        throw InputError(SourceLocation{envmap.empty() ? design_file : envmap, 0, 0, ""},
                         envmap.empty() ? "Designs III and IV need --light or --envmap"
                                        : "no light reaches the display from behind: the map is black there");

    optics::AngularSimulationOptions options;
    // auto: exact. The rays are traced once for all macro-pixels, so the exact model costs
    // little, and the paraxial one misplaces the bins' edges off axis.
    const optics::DesignOptics design_optics(design);
    const optics::ResolvedModel choice = optics::resolve(common.model, design_optics, design_optics.dot_mm());
    options.model = choice.model;
    options.rays_per_side = opt.lens_rays;
    options.kernel_spacings = opt.kernel;
    options.area_samples_per_side = common.area_samples;
    options.distribution_pixels = opt.distribution_pixels;
    const std::vector<std::string> view_names = add_viewpoints(opt, options);
    const std::vector<std::string> distribution_texts = add_distributions(opt, options);

    const std::unique_ptr<optics::Transparency> through =
        choice.diffraction ? optics::diffracted(pattern, design_optics) : nullptr;
    const optics::AngularDisplayOutput result = simulator.simulate(through ? *through : static_cast<const optics::Transparency&>(pattern), lights, options);
    const bool several = result.views.size() > 1;
    std::vector<std::string> written;
    for (std::size_t w = 0; w < result.views.size(); ++w) {
        const std::string suffix = "view" + std::to_string(w + 1);
        const std::filesystem::path path = several ? with_suffix(out, suffix) : std::filesystem::path(out);
        write_image(path, zoomed(result.views[w], opt.zoom).exposed(common.exposure));
        written.push_back(path.string());
        if (!opt.macro_out.empty()) {
            const std::filesystem::path macro = several ? with_suffix(opt.macro_out, suffix) : std::filesystem::path(opt.macro_out);
            write_image(macro, zoomed(simulator.per_macro_pixel(result.views[w]), opt.zoom).exposed(common.exposure));
            written.push_back(macro.string());
        }
    }
    for (std::size_t q = 0; q < result.distributions.size(); ++q) {
        const std::filesystem::path path = with_suffix(opt.distribution_out, distribution_texts[q]);
        write_image(path, result.distributions[q]);
        written.push_back(path.string());
    }
    const predict::ObserverPredictionReport report{
        written, design.name, std::string(optics::to_string(design.kind)),
        std::string(name_of(optics::kModelChoiceNames, common.model)), choice, light_texts.size(), view_names, envmap,
        sampling, &result, simulator.macro_x(), simulator.macro_y(), simulator.meso().lattice().count_x(),
        simulator.meso().lattice().count_y(),
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count()};
    if (common.json)
        std::printf("%s\n", predict::to_json(report).dump(2).c_str());
    else
        std::fputs(predict::report_text(report).c_str(), stdout);
}

}  // namespace rfd::cli
