// The project file and rfd make's pipeline: what a project file may say (and the errors
// for what it may not), the plan of steps, and the manifest's skip and re-run, with a
// stand-in runner whose outputs depend on exactly the files a step names.

#include <algorithm>
#include <array>
#include <cmath>
#include <deque>
#include <fstream>
#include <iterator>
#include <map>
#include <optional>
#include <set>
#include <sstream>
#include <type_traits>
#include <variant>
#include <string>

#include <gmock/gmock.h>
#include <nlohmann/json.hpp>
#include <gtest/gtest.h>

#include "core/error.hpp"
#include "core/files.hpp"
#include "core/image.hpp"
#include "project/make.hpp"
#include "project/manifest.hpp"
#include "project/preview.hpp"
#include "project/project.hpp"
#include "relight/field.hpp"
#include "tests/support/error_of.hpp"
#include "tests/support/temp_dir.hpp"

namespace rfd::project {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;
using ::testing::UnorderedElementsAre;
using testing::error_of;
using testing::TempDir;

const fs::path kSource = RFD_SOURCE_DIR;

void write(const fs::path& file, const std::string& text) {
    fs::create_directories(file.parent_path());
    std::ofstream(file) << text;
}

// A field of three lights of 4 x 3 pixels, `level` everywhere.
void write_small_field(const fs::path& folder, float level) {
    relight::FieldWriter writer(folder);
    for (const Eigen::Vector3d& d : {Eigen::Vector3d(0, 0, 1), Eigen::Vector3d(0.5, 0, 0.866), Eigen::Vector3d(0, 0.5, 0.866)}) {
        writer.add(Image(4, 3, 1, level), d.normalized());
    }
    writer.finish();
}

const std::string kProject = R"(
[project]
name = "test"
design = "design2"
printer = "inkjet_720"

[source]
field = "field"

[make]
sheets = ["pdf"]
)";

// Stands in for rfd: writes every path after an output option (relative to the output
// folder, where a step runs), its content the command line and the content of every
// existing field the command names, so outputs change exactly when what a step reads
// changes. Folders (no extension) get one file, the preview's folder the files rfd make
// checks for. Steps end in the order `last_first` says: as started, or the latest
// first, as steps running side by side may.
struct FakeRfd : StepRunner {
    std::vector<std::string> calls;  // the first two words of each command
    std::string fail_on;             // a command ("print sheet") that exits 2
    bool last_first = false;
    std::deque<Ended> ending;
    long handles = 0;

    long start(const Step& step, const fs::path& out, const fs::path& log) override {
        const std::vector<std::string>& arguments = step.arguments;
        const std::string command = arguments.at(0) + " " + arguments.at(1);
        calls.push_back(command);
        ++handles;
        if (command == fail_on) {
            std::ofstream(log, std::ios::app) << "rfd: error: the printer is out of ink\n";
            ending.push_back({handles, 2});
            return handles;
        }
        std::string content;
        for (const std::string& argument : arguments) {
            content += argument + "\n";
            if (fs::exists(out / argument) && argument.find("field") != std::string::npos)
                content += content_hash(out / argument) + "\n";
        }
        for (std::size_t k = 0; k + 1 < arguments.size(); ++k) {
            if (arguments[k] != "--out" && arguments[k] != "--preview" && arguments[k] != "--stl" &&
                arguments[k] != "--report")
                continue;
            fs::path target = out / arguments[k + 1];
            if (command == "simulate preview") {
                for (const char* file : {"data.js", "predicted.png", "relit.png"}) write(target / file, content);
                if (std::find(arguments.begin(), arguments.end(), "--direct") != arguments.end())
                    write(target / "direct.png", content);
                continue;
            }
            if (target.extension().empty()) target /= "made.txt";
            if (arguments[k] == "--stl") target.replace_filename("holder_base.stl");
            write(target, content);
        }
        std::ofstream(log, std::ios::app) << "made\n";
        ending.push_back({handles, 0});
        return handles;
    }
    Ended wait() override {
        const Ended ended = last_first ? ending.back() : ending.front();
        if (last_first) ending.pop_back();
        else ending.pop_front();
        return ended;
    }
};

struct MadeSteps {
    std::set<std::string> ran;
};
MadeSteps run_make(const Project& project, const fs::path& out, FakeRfd& rfd, bool force = false, int jobs = 1,
                   std::vector<std::string> only = {}) {
    MakeOptions options;
    options.rfd_identity = "rfd test";
    options.force = force;
    options.jobs = jobs;
    options.only = std::move(only);
    MadeSteps made;
    for (const StepOutcome& step : make(project, out, rfd, options))
        if (step.ran) made.ran.insert(step.name);
    return made;
}

TEST(ProjectFile, BundledExamplesLoadWithBundledNamesResolved) {
    const Project bottle = load_project(kSource / "examples/bottle_design1.toml");
    EXPECT_EQ(bottle.design, kSource / "designs/design1.toml");
    EXPECT_EQ(bottle.printer, "epson_stylus_pro_4800");
    EXPECT_EQ(bottle.printer_3d, kSource / "holders/profiles/fdm_0.4mm.toml");
    ASSERT_TRUE(bottle.source.scene);
    EXPECT_EQ(*bottle.source.scene, kSource / "scenes/bottle.toml");
    EXPECT_EQ(bottle.encoding.tilt_deg, 45.0);
    const Project sig08 = load_project(kSource / "examples/sig08_design2.toml");
    EXPECT_EQ(sig08.source.procedural, "letters");
    EXPECT_EQ(sig08.encoding.interpolation, "nearest");
}

TEST(ProjectFile, MistakesNameTheFileLineAndKey) {
    TempDir dir;
    write_small_field(dir / "field", 0.5f);
    const auto error_for = [&](const std::string& text) {
        write(dir / "p.toml", text);
        return error_of([&] { load_project(dir / "p.toml"); });
    };
    EXPECT_EQ(error_for(kProject), "");
    EXPECT_THAT(error_for(kProject + "\n[encode]\ntilt = 45\n"),
                AllOf(HasSubstr("p.toml:14:8: encode.tilt"), HasSubstr("expected 'tilt_deg'")));
    EXPECT_THAT(error_for("[project]\ndesign = \"design2\"\n[source]\nfield = \"field\"\nscene = \"field\"\n"),
                HasSubstr("expected exactly one of field"));
    EXPECT_THAT(error_for(R"([project]
design = "design9"
[source]
field = "field"
)"),
                AllOf(HasSubstr("p.toml:2"), HasSubstr("cannot open design 'design9'")));
    EXPECT_THAT(error_for("[project]\ndesign = \"design3\"\n[source]\nfield = \"field\"\n"),
                HasSubstr("rfd make builds Designs I and II"));
    EXPECT_THAT(error_for("[project]\ndesign = \"design2\"\nprinter = \"epson\"\n[source]\nfield = \"field\"\n"),
                HasSubstr("cannot open printer profile 'epson'"));
    EXPECT_THAT(error_for("[project]\ndesign = \"design2\"\n[source]\nfield = \"nowhere\"\n"),
                HasSubstr("cannot open"));
    EXPECT_THAT(error_for(kProject + "[encode]\nmodel = \"fast\"\n"), HasSubstr("encode.model"));
    EXPECT_THAT(error_for("[project]\ndesign = \"design2\"\n[source]\nfield = \"field\"\n[make]\nsheets = [\"png\"]\n"),
                HasSubstr("expected formats \"pdf\" and/or \"tif\""));
    EXPECT_THAT(error_for("[project]\ndesign = \"design2\"\n[source]\nfield = \"field\"\n[make]\nsheets = [\"pdf\", \"pdf\"]\n"),
                HasSubstr("\"pdf\" is named twice"));
    EXPECT_THAT(error_for("[project]\ndesign = \"design2\"\n[source]\nfield = \"field\"\nregion = [0, 0, 0, 3]\n"),
                HasSubstr("source.region"));
    EXPECT_THAT(error_for("[project]\ndesign = \"design2\"\n"), HasSubstr("source"));
}

// Every key declared as an option (project::declared_keys) is read through that
// declaration: its ends are accepted, a value past either end is refused naming the key.
TEST(ProjectFile, TiltIsDegreesOrAuto) {
    TempDir dir;
    write_small_field(dir / "field", 0.5f);
    write(dir / "p.toml", kProject + "\n[encode]\ntilt_deg = \"auto\"\n");
    EXPECT_FALSE(load_project(dir / "p.toml").encoding.tilt_deg);
    write(dir / "p.toml", kProject + "\n[encode]\ntilt_deg = 30\n");
    EXPECT_EQ(load_project(dir / "p.toml").encoding.tilt_deg, 30.0);
    write(dir / "p.toml", kProject + "\n[encode]\ntilt_deg = \"up\"\n");
    EXPECT_THAT(error_of([&] { load_project(dir / "p.toml"); }), ::testing::HasSubstr("encode.tilt_deg: expected degrees"));
}

TEST(ProjectFile, DeclaredKeysTakeTheirOptionsRange) {
    TempDir dir;
    write_small_field(dir / "field", 0.5f);
    const auto error_for = [&](std::string_view table, std::string_view key, const std::string& value) {
        std::string text = "[project]\ndesign = \"design2\"\n[source]\nfield = \"field\"\n";
        if (table != "source") text += "[" + std::string(table) + "]\n";
        write(dir / "p.toml", text + std::string(key) + " = " + value + "\n");
        return error_of([&] { load_project(dir / "p.toml"); });
    };
    int checked = 0;
    for (const DeclaredKey& declared : declared_keys()) {
        std::visit(
            [&](const auto& option) {
                const std::string name = std::string(declared.table) + "." + std::string(option.key);
                const auto text = [](auto v) {
                    std::ostringstream out;
                    out.precision(17);
                    out << v;
                    return out.str();
                };
                const double step = std::max<double>(1e-3, std::abs(static_cast<double>(option.min)) * 0.5);
                EXPECT_EQ(error_for(declared.table, option.key, text(option.min)), "") << name;
                EXPECT_EQ(error_for(declared.table, option.key, text(option.max)), "") << name;
                if constexpr (std::is_same_v<std::decay_t<decltype(option)>, IntegerOption>) {
                    EXPECT_THAT(error_for(declared.table, option.key, text(option.min - 1)),
                                AllOf(HasSubstr(name), HasSubstr("outside the allowed range")));
                    EXPECT_THAT(error_for(declared.table, option.key, text(option.max + 1)),
                                AllOf(HasSubstr(name), HasSubstr("outside the allowed range")));
                } else {
                    EXPECT_THAT(error_for(declared.table, option.key, text(option.min - step)),
                                AllOf(HasSubstr(name), HasSubstr("outside the allowed range")));
                    EXPECT_THAT(error_for(declared.table, option.key, text(option.max + std::max(1.0, option.max))),
                                AllOf(HasSubstr(name), HasSubstr("outside the allowed range")));
                }
                ++checked;
            },
            declared.option);
    }
    EXPECT_GE(checked, 10);
    // Below the preview's own range, 0 still turns its light control off.
    EXPECT_EQ(error_for("make", "preview_lights", "0"), "");
    EXPECT_EQ(load_project(dir / "p.toml").outputs.preview_lights, 0);
}

// data.js is a contract with the page: what write_preview_data writes reads back as the
// same struct, with the set's directions, triangles and rims, and a file that is not one is
// refused naming it.
TEST(PreviewData, RoundTripsThroughDataJs) {
    TempDir dir;
    predict::PreviewSet set;
    set.directions = {Eigen::Vector3d(0, 0, 1), Eigen::Vector3d(0.1, 0, 0.995).normalized(),
                      Eigen::Vector3d(0, 0.1, 0.995).normalized()};
    for (std::size_t k = 0; k < set.directions.size(); ++k) {
        set.predicted.push_back(Image(2, 3, 3, 0.25f * static_cast<float>(k)));
        set.relit.push_back(Image(2, 3, 3, 0.5f));
    }
    set.scale = 1.5;
    set.max_angle_deg = 8.0;
    set.triangles = {{0, 1, 2}};
    set.edge_planes = {{Eigen::Vector3d(1, 0, 0), Eigen::Vector3d(0, 1, 0), Eigen::Vector3d(0, 0, 1)}};
    set.rims = {{0.0, 12.5, std::nullopt}, {15.0, std::nullopt, 9.25}};
    for (const bool direct : {false, true}) {
        if (direct) set.predicted_direct = set.predicted;
        const PreviewData written = write_preview_data(set, "a design", dir / "preview");
        const PreviewData read = read_preview_data(dir / "preview" / "data.js");
        EXPECT_EQ(nlohmann::json(read), nlohmann::json(written));
        EXPECT_EQ(read.design, "a design");
        ASSERT_EQ(read.directions.size(), set.directions.size());
        for (std::size_t k = 0; k < set.directions.size(); ++k)
            for (int i = 0; i < 3; ++i) EXPECT_EQ(read.directions[k][i], set.directions[k][i]);
        EXPECT_EQ(read.triangles, set.triangles);
        EXPECT_EQ(read.tile, (std::array<int, 2>{2, 3}));
        EXPECT_EQ(read.columns, 2);  // ceil(sqrt(3))
        ASSERT_EQ(read.rims.size(), 2u);
        EXPECT_EQ(read.rims[0].wrap_over_deg, std::optional<double>(12.5));
        EXPECT_FALSE(read.rims[0].crosstalk_deg);
        EXPECT_EQ(read.rims[1].crosstalk_deg, std::optional<double>(9.25));
        EXPECT_TRUE(read.predicted.starts_with("data:image/png;base64,"));
        EXPECT_EQ(read.predicted_direct.has_value(), direct);
    }
    write(dir / "other.js", "window.SOMETHING = {};\n");
    EXPECT_THAT(error_of([&] { read_preview_data(dir / "other.js"); }),
                AllOf(HasSubstr("other.js"), HasSubstr("not a preview's data.js")));
}

TEST(ProjectPlan, EveryStepReadsOnlyWhatEarlierStepsOrTheUserMade) {
    TempDir dir;
    write_small_field(dir / "field", 0.5f);
    write(dir / "p.toml", kProject);
    const std::vector<Step> steps = plan(load_project(dir / "p.toml"));
    std::vector<std::string> names;
    std::set<fs::path> made;
    int made_inputs = 0;
    for (const Step& step : steps) {
        names.push_back(step.name);
        for (const fs::path& input : step.inputs) {
            // What a step made is named relative to the output folder, the user's files absolutely.
            if (input.is_relative()) {
                EXPECT_TRUE(made.count(input)) << step.name << " reads " << input;
                ++made_inputs;
            } else {
                EXPECT_TRUE(fs::exists(input)) << step.name << " reads " << input;
            }
        }
        for (const std::string& argument : step.arguments)
            EXPECT_EQ(argument.find((dir / "out").string()), std::string::npos) << step.name << ": " << argument;
        for (const fs::path& output : step.outputs) made.insert(output);
    }
    // The direct pattern by the optimiser and the preview; the optimised one by the sheet,
    // compare, tolerance and preview; compare's and tolerance's by the verdict.
    EXPECT_EQ(made_inputs, 8);
    // inkjet_720 prints one sheet: no back sheet.
    EXPECT_THAT(names, ::testing::ElementsAre("advice", "pattern", "optimize", "sheet_front_pdf", "moire", "wedge",
                                              "holder", "compare", "tolerance", "preview", "verdict"));
}

// With [optimize], the optimised pattern is printed and predicted, and the preview page
// gets the direct encoding's pictures beside it.
TEST(ProjectPlan, AnOptimisedPatternIsWhatIsPrintedAndPredicted) {
    TempDir dir;
    write_small_field(dir / "field", 0.5f);
    write(dir / "p.toml", kProject + "\n[optimize]\niterations = 12\ncore_weight = 30\n");
    const Project project = load_project(dir / "p.toml");
    ASSERT_TRUE(project.optimization);
    EXPECT_EQ(project.optimization->iterations, 12);
    EXPECT_EQ(project.optimization->spacing_mm, 0.1);
    std::map<std::string, std::string> lines;
    for (const Step& step : plan(project)) lines[step.name] = command_line(step);
    ASSERT_TRUE(lines.count("optimize"));
    EXPECT_THAT(lines["optimize"], AllOf(HasSubstr("pattern optimize"), HasSubstr("--from pattern.exr"),
                                         HasSubstr("--iterations 12"), HasSubstr("--core-weight 30")));
    for (const char* step : {"sheet_front_pdf", "compare", "tolerance", "preview"})
        EXPECT_THAT(lines[step], HasSubstr("pattern_optimized.exr")) << step;
    EXPECT_THAT(lines["preview"], HasSubstr("--direct pattern.exr"));
    write(dir / "p.toml", kProject + "\n[optimize]\nspacing_mm = 0\n");
    EXPECT_THAT(error_of([&] { load_project(dir / "p.toml"); }), HasSubstr("optimize.spacing_mm"));
}

// Photographs of the printed wedge: the printer's curve is measured first, and the pattern,
// the sheets and the holder use the measured profile; the wedge keeps the profile named.
TEST(ProjectPlan, WedgePhotographsCalibrateThePrinterFirst) {
    TempDir dir;
    write_small_field(dir / "field", 0.5f);
    write(dir / "wedge 1.jpg", "a photograph");
    write(dir / "p.toml", kProject + "\n[calibration]\nwedge_photos = [\"wedge 1.jpg\"]\nlight = \"reflected\"\n");
    const Project project = load_project(dir / "p.toml");
    ASSERT_EQ(project.calibration.wedge_photos.size(), 1u);
    const std::vector<Step> steps = plan(project);
    ASSERT_FALSE(steps.empty());
    EXPECT_EQ(steps.front().name, "calibrate_tone");
    EXPECT_THAT(command_line(steps.front()),
                AllOf(HasSubstr("calibrate tone inkjet_720 "), HasSubstr("wedge 1.jpg"), HasSubstr("--light reflected"),
                      HasSubstr("--out calibration/printer.toml")));
    std::map<std::string, std::string> lines;
    for (const Step& step : steps) lines[step.name] = command_line(step);
    for (const char* step : {"pattern", "moire", "holder"})
        EXPECT_THAT(lines[step], HasSubstr("--printer calibration/printer.toml")) << step;
    EXPECT_THAT(lines["wedge"], HasSubstr("--printer inkjet_720"));
    // What the project names must be there, and be photographs.
    const auto error_for = [&](const std::string& table) {
        write(dir / "p.toml", kProject + "\n[calibration]\n" + table);
        return error_of([&] { load_project(dir / "p.toml"); });
    };
    EXPECT_THAT(error_for("wedge_photos = [\"missing.jpg\"]\n"),
                AllOf(HasSubstr("calibration.wedge_photos"), HasSubstr("missing.jpg")));
    EXPECT_THAT(error_for("wedge_photos = [\"field\"]\n"), HasSubstr("regular file"));
    EXPECT_THAT(error_for("wedge_photos = []\n"), HasSubstr("at least one photograph"));
    EXPECT_THAT(error_for("wedge_photos = [\"wedge 1.jpg\"]\nlight = \"side\"\n"), HasSubstr("calibration.light"));
}

// Photographs of the moire sheet: the pitch is measured before the pattern, which is built
// for the measured design; the sheet and the holder stay the named design's (printed before
// the photographs). Photographs of the display: its registration, judged against the
// tolerances predicted for it.
TEST(ProjectPlan, MoireAndDisplayPhotographsMeasureThePitchAndTheRegistration) {
    TempDir dir;
    write_small_field(dir / "field", 0.5f);
    for (const char* photo : {"moire.jpg", "up.jpg", "turned.jpg"}) write(dir / photo, "a photograph");
    const std::string photos = "\n[calibration]\nmoire_photos = [\"moire.jpg\"]\nmoire_page = 2\n"
                               "display_photos = [\"up.jpg\"]\nturned_photos = [\"turned.jpg\"]\n";
    // Design I: Design II's 6 x 5 array is too small for either (below).
    std::string project_text = kProject;
    project_text.replace(project_text.find("design2"), 7, "design1");
    write(dir / "p.toml", project_text + photos);
    const std::vector<Step> steps = plan(load_project(dir / "p.toml"));
    std::vector<std::string> order;
    std::map<std::string, std::string> lines;
    for (const Step& step : steps) {
        order.push_back(step.name);
        lines[step.name] = command_line(step) + " ";
    }
    const auto at = [&](const char* name) { return std::find(order.begin(), order.end(), name) - order.begin(); };
    ASSERT_LT(at("calibrate_pitch"), at("pattern"));
    ASSERT_LT(at("tolerance"), at("calibrate_registration"));
    ASSERT_LT(at("calibrate_registration"), static_cast<long>(order.size()));
    EXPECT_THAT(lines["calibrate_pitch"],
                AllOf(HasSubstr("calibrate pitch /"), HasSubstr("design1.toml"), HasSubstr("moire.jpg"),
                      HasSubstr("--page 2"), HasSubstr("--out calibration/design.toml")));
    for (const char* step : {"pattern", "optimize", "sheet_front_pdf", "compare", "tolerance", "preview", "verdict",
                             "calibrate_registration"})
        EXPECT_THAT(lines[step], HasSubstr(" calibration/design.toml ")) << step;
    for (const char* step : {"moire", "holder"}) {
        EXPECT_THAT(lines[step], HasSubstr("design1.toml")) << step;
        EXPECT_THAT(lines[step], Not(HasSubstr("calibration/design.toml"))) << step;
    }
    EXPECT_THAT(lines["calibrate_registration"],
                AllOf(HasSubstr("calibrate registration calibration/design.toml pattern_optimized.exr /"),
                      HasSubstr("up.jpg --turned /"), HasSubstr("turned.jpg --tolerance predict/tolerance"),
                      HasSubstr("--out calibration/registration.json"), Not(HasSubstr("--light-tilt"))));
    write(dir / "p.toml", project_text + photos + "display_light_tilt_deg = 5\ndisplay_light_turn_deg = 90\n");
    for (const Step& step : plan(load_project(dir / "p.toml"))) {
        if (step.name == "calibrate_registration") {
            EXPECT_THAT(command_line(step), HasSubstr("--light-tilt 5 --light-turn 90"));
        }
    }

    const auto error_for = [&](const std::string& table) {
        write(dir / "p.toml", project_text + "\n[calibration]\n" + table);
        return error_of([&] { load_project(dir / "p.toml"); });
    };
    // Design II's array: its pitch measured (laid whole on each band) and its registration
    // (26 macro-pixels away from the markers).
    write(dir / "p.toml", kProject + "\n[calibration]\nmoire_photos = [\"moire.jpg\"]\ndisplay_photos = [\"up.jpg\"]\n");
    int pitch_steps = 0, registration_steps = 0;
    for (const Step& step : plan(load_project(dir / "p.toml"))) {
        pitch_steps += step.name == "calibrate_pitch";
        registration_steps += step.name == "calibrate_registration";
    }
    EXPECT_EQ(pitch_steps, 1);
    EXPECT_EQ(registration_steps, 1);
    EXPECT_THAT(error_for("light = \"back\"\n"), HasSubstr("names no photographs"));
    EXPECT_THAT(error_for("moire_photos = [\"moire.jpg\"]\nmoire_page = 0\n"), HasSubstr("calibration.moire_page"));
    EXPECT_THAT(error_for("moire_photos = [\"moire.jpg\"]\nturned_photos = [\"turned.jpg\"]\n"),
                AllOf(HasSubstr("calibration.turned_photos"), HasSubstr("display_photos")));
    EXPECT_THAT(error_for("moire_photos = [\"moire.jpg\"]\ndisplay_light_tilt_deg = 3\n"),
                HasSubstr("calibration.display_light_tilt_deg"));
    EXPECT_THAT(error_for("display_photos = [\"up.jpg\"]\ndisplay_light_tilt_deg = 70\n"),
                HasSubstr("calibration.display_light_tilt_deg"));
    EXPECT_THAT(error_for("display_photos = [\"nowhere.jpg\"]\n"),
                AllOf(HasSubstr("calibration.display_photos"), HasSubstr("nowhere.jpg")));
}

// Optimisation is the default; `enabled = false` prints the direct encoding.
TEST(ProjectPlan, PatternsAreOptimisedUnlessTheProjectSaysNot) {
    TempDir dir;
    write_small_field(dir / "field", 0.5f);
    const auto steps_of = [&](const std::string& text) {
        write(dir / "p.toml", text);
        std::map<std::string, std::string> lines;
        for (const Step& step : plan(load_project(dir / "p.toml"))) lines[step.name] = command_line(step);
        return lines;
    };
    auto lines = steps_of(kProject);
    ASSERT_TRUE(lines.count("optimize"));
    EXPECT_THAT(lines["optimize"], AllOf(HasSubstr("--iterations 40"), HasSubstr("--core-weight 0")));
    EXPECT_THAT(lines["sheet_front_pdf"], HasSubstr("pattern_optimized.exr"));
    lines = steps_of(kProject + "\n[optimize]\nenabled = false\n");
    EXPECT_FALSE(lines.count("optimize"));
    EXPECT_THAT(lines["sheet_front_pdf"], AllOf(HasSubstr(" pattern.exr"), ::testing::Not(HasSubstr("optimized"))));
    EXPECT_FALSE(lines["preview"].find("--direct") != std::string::npos);
}

TEST(Make, ASecondRunSkipsEveryStepAndAChangedFieldRemakesOnlyWhatDependsOnIt) {
    TempDir dir;
    write_small_field(dir / "field", 0.5f);
    write(dir / "p.toml", kProject);
    const Project project = load_project(dir / "p.toml");
    FakeRfd rfd;
    EXPECT_EQ(run_make(project, dir / "out", rfd).ran.size(), 11u);
    EXPECT_TRUE(fs::exists(dir / "out/README.txt"));
    EXPECT_TRUE(fs::exists(dir / "out/index.html"));
    EXPECT_TRUE(run_make(project, dir / "out", rfd).ran.empty());

    fs::remove_all(dir / "field");
    write_small_field(dir / "field", 0.75f);
    EXPECT_THAT(run_make(project, dir / "out", rfd).ran,
                UnorderedElementsAre("advice", "pattern", "optimize", "sheet_front_pdf", "compare", "tolerance",
                                     "preview", "verdict"));

    // An output removed by hand is made again; what reads it is not, as it comes out the same.
    fs::remove(dir / "out/print/moire.pdf");
    EXPECT_THAT(run_make(project, dir / "out", rfd).ran, UnorderedElementsAre("moire"));
    fs::remove(dir / "out/pattern.png");
    EXPECT_THAT(run_make(project, dir / "out", rfd).ran, UnorderedElementsAre("pattern"));
    EXPECT_EQ(run_make(project, dir / "out", rfd, true).ran.size(), 11u);
}

TEST(Make, AFailingStepSaysWhichAndKeepsTheStepsBeforeIt) {
    TempDir dir;
    write_small_field(dir / "field", 0.5f);
    write(dir / "p.toml", kProject);
    const Project project = load_project(dir / "p.toml");
    FakeRfd rfd;
    rfd.fail_on = "print sheet";
    const std::string message = error_of([&] { run_make(project, dir / "out", rfd); });
    EXPECT_THAT(message, HasSubstr("step 'sheet_front_pdf'"));
    EXPECT_THAT(message, HasSubstr("exit code 2"));
    EXPECT_THAT(message, HasSubstr("the printer is out of ink"));
    EXPECT_THAT(message, HasSubstr((dir / "out/logs/sheet_front_pdf.txt").string()));
    EXPECT_TRUE(fs::exists(dir / "out/pattern.exr"));
    rfd.fail_on.clear();
    rfd.calls.clear();
    EXPECT_THAT(run_make(project, dir / "out", rfd).ran,
                UnorderedElementsAre("sheet_front_pdf", "moire", "wedge", "holder", "compare", "tolerance", "preview", "verdict"));
}

TEST(Make, ADamagedManifestRemakesEverythingAfterANote) {
    TempDir dir;
    write_small_field(dir / "field", 0.5f);
    write(dir / "p.toml", kProject);
    const Project project = load_project(dir / "p.toml");
    FakeRfd rfd;
    run_make(project, dir / "out", rfd);
    write(dir / "out/manifest.json", "{\"steps\": 3");
    EXPECT_EQ(run_make(project, dir / "out", rfd).ran.size(), 11u);
    EXPECT_TRUE(run_make(project, dir / "out", rfd).ran.empty());
}

// Steps side by side, ending in any order, start only once what they read is made, and
// leave the same files as one at a time.
TEST(Make, StepsSideBySideWaitForWhatTheyReadAndMakeTheSameFiles) {
    TempDir dir;
    write_small_field(dir / "field", 0.5f);
    write(dir / "p.toml", kProject);
    const Project project = load_project(dir / "p.toml");
    const std::vector<Step> steps = plan(project);
    const std::vector<std::vector<std::size_t>> needs = dependencies(steps);
    int edges = 0;
    for (const auto& step_needs : needs) edges += static_cast<int>(step_needs.size());
    EXPECT_EQ(edges, 8);  // as made_inputs in ProjectPlan.EveryStepReadsOnlyWhatEarlierStepsOrTheUserMade

    // A runner that records when each step started and ended, ending the latest first.
    struct Recording : FakeRfd {
        std::vector<std::string> events;
        std::map<long, std::string> names;
        long start(const Step& step, const fs::path& out, const fs::path& log) override {
            events.push_back("start " + step.name);
            const long handle = FakeRfd::start(step, out, log);
            names[handle] = step.name;
            return handle;
        }
        Ended wait() override {
            const Ended ended = FakeRfd::wait();
            events.push_back("end " + names[ended.handle]);
            return ended;
        }
    };
    Recording parallel;
    parallel.last_first = true;
    EXPECT_EQ(run_make(project, dir / "parallel", parallel, false, 3).ran.size(), 11u);
    const auto at = [&](const std::string& event) {
        return std::find(parallel.events.begin(), parallel.events.end(), event) - parallel.events.begin();
    };
    int side_by_side = 0, running = 0, checked = 0;
    for (const std::string& event : parallel.events) {
        running += event.starts_with("start") ? 1 : -1;
        side_by_side = std::max(side_by_side, running);
    }
    for (std::size_t k = 0; k < steps.size(); ++k)
        for (const std::size_t j : needs[k]) {
            EXPECT_LT(at("end " + steps[j].name), at("start " + steps[k].name)) << steps[k].name << " after " << steps[j].name;
            ++checked;
        }
    EXPECT_EQ(checked, edges);
    EXPECT_EQ(side_by_side, 3);

    FakeRfd serial;
    run_make(project, dir / "serial", serial);
    std::vector<std::string> files;
    for (const auto& entry : fs::recursive_directory_iterator(dir / "serial"))
        if (entry.is_regular_file()) files.push_back(fs::relative(entry.path(), dir / "serial").generic_string());
    EXPECT_GE(files.size(), 15u);
    for (const std::string& file : files)
        EXPECT_EQ(content_hash(dir / "serial" / file), content_hash(dir / "parallel" / file)) << file;
}

TEST(Make, OnlyMakesTheNamedStepsAndWhatTheyRead) {
    TempDir dir;
    write_small_field(dir / "field", 0.5f);
    write(dir / "p.toml", kProject);
    const Project project = load_project(dir / "p.toml");
    FakeRfd rfd;
    EXPECT_THAT(run_make(project, dir / "out", rfd, false, 1, {"sheet_front_pdf"}).ran,
                UnorderedElementsAre("pattern", "optimize", "sheet_front_pdf"));
    EXPECT_FALSE(fs::exists(dir / "out/README.txt"));  // written by a whole make only
    EXPECT_THAT(run_make(project, dir / "out", rfd, false, 1, {"verdict", "wedge"}).ran,
                UnorderedElementsAre("compare", "tolerance", "verdict", "wedge"));
    EXPECT_THAT(error_of([&] { run_make(project, dir / "out", rfd, false, 1, {"sheets"}); }),
                AllOf(HasSubstr("no step 'sheets'"), HasSubstr("sheet_front_pdf")));
}

// Turning an output off removes what an earlier make made of it, from the folder, the
// manifest and README.txt.
TEST(Make, WhatThePlanNoLongerMakesIsRemovedAndNotListed) {
    TempDir dir;
    write_small_field(dir / "field", 0.5f);
    write(dir / "p.toml", kProject);
    FakeRfd rfd;
    run_make(load_project(dir / "p.toml"), dir / "out", rfd);
    ASSERT_TRUE(fs::exists(dir / "out/print/moire.pdf"));
    write(dir / "p.toml", kProject + "moire = false\n");
    EXPECT_TRUE(run_make(load_project(dir / "p.toml"), dir / "out", rfd).ran.empty());
    EXPECT_FALSE(fs::exists(dir / "out/print/moire.pdf"));
    EXPECT_FALSE(fs::exists(dir / "out/print/moire.png"));
    EXPECT_FALSE(fs::exists(dir / "out/logs/moire.txt"));
    EXPECT_TRUE(fs::exists(dir / "out/print/wedge.pdf"));
    EXPECT_FALSE(Manifest::read(dir / "out").steps().count("moire"));
    std::ifstream readme(dir / "out/README.txt");
    const std::string text{std::istreambuf_iterator<char>(readme), std::istreambuf_iterator<char>()};
    EXPECT_THAT(text, HasSubstr("wedge.pdf"));
    EXPECT_EQ(text.find("moire"), std::string::npos);
}

TEST(Make, ASecondMakeIntoTheSameFolderIsRefusedWhileTheFirstRuns) {
    TempDir dir;
    write_small_field(dir / "field", 0.5f);
    write(dir / "p.toml", kProject);
    FakeRfd rfd;
    fs::create_directories(dir / "out");
    {
        const ExclusiveLock first(dir / "out/.rfd-make.lock", "busy");
        EXPECT_THAT(error_of([&] { run_make(load_project(dir / "p.toml"), dir / "out", rfd); }),
                    AllOf(HasSubstr("another rfd make is making into"), HasSubstr("out")));
        EXPECT_TRUE(rfd.calls.empty());
    }
    EXPECT_EQ(run_make(load_project(dir / "p.toml"), dir / "out", rfd).ran.size(), 11u);
}

// A signal while steps run: the running steps' outputs and logs are removed, what ended
// before stays made, and the next make makes the rest.
TEST(Make, AStopSignalRemovesWhatTheRunningStepsWroteAndKeepsTheRest) {
    TempDir dir;
    write_small_field(dir / "field", 0.5f);
    write(dir / "p.toml", kProject);
    const Project project = load_project(dir / "p.toml");
    struct Stopped : FakeRfd {
        int started = 0;
        long start(const Step& step, const fs::path& out, const fs::path& log) override {
            ++started;
            return FakeRfd::start(step, out, log);
        }
        int stop_signal() const override { return started >= 4 ? 15 : 0; }  // during the fourth step
    };
    Stopped rfd;
    MakeOptions options;
    options.rfd_identity = "rfd test";
    try {
        make(project, dir / "out", rfd, options);
        ADD_FAILURE() << "make went on after the signal";
    } catch (const Interrupted& stop) {
        EXPECT_EQ(stop.exit_code(), 128 + 15);
    }
    EXPECT_EQ(rfd.started, 4);
    EXPECT_TRUE(fs::exists(dir / "out/advice.json"));
    EXPECT_TRUE(fs::exists(dir / "out/pattern.exr"));
    EXPECT_TRUE(fs::exists(dir / "out/pattern_optimized.exr"));
    EXPECT_FALSE(fs::exists(dir / "out/print/front.pdf"));  // the fourth step, stopped
    for (const auto& entry : fs::recursive_directory_iterator(dir / "out"))
        EXPECT_FALSE(entry.path().filename().string().starts_with(".running")) << entry.path();
    EXPECT_EQ(Manifest::read(dir / "out").steps().size(), 3u);
    FakeRfd again;
    EXPECT_EQ(run_make(project, dir / "out", again).ran.size(), 8u);
}

TEST(Make, TheSameProjectMadeIntoTwoFoldersGivesTheSameFiles) {
    TempDir dir;
    write_small_field(dir / "field", 0.5f);
    write(dir / "p.toml", kProject);
    const Project project = load_project(dir / "p.toml");
    FakeRfd rfd;
    run_make(project, dir / "one", rfd);
    run_make(project, dir / "deeper/two", rfd);
    int compared = 0;
    for (const auto& entry : fs::recursive_directory_iterator(dir / "one")) {
        if (!entry.is_regular_file()) continue;
        const fs::path file = fs::relative(entry.path(), dir / "one");
        EXPECT_EQ(content_hash(entry.path()), content_hash(dir / "deeper/two" / file)) << file;
        ++compared;
    }
    EXPECT_GE(compared, 15);
}

TEST(ProjectFile, SourcesMustBeRegularFilesOrFolders) {
    TempDir dir;
    write_small_field(dir / "field", 0.5f);
    const auto error_for = [&](const std::string& source) {
        write(dir / "p.toml", "[project]\ndesign = \"design2\"\n[source]\n" + source + "\n");
        return error_of([&] { load_project(dir / "p.toml"); });
    };
    EXPECT_THAT(error_for("field = \"/dev/zero\""), AllOf(HasSubstr("source.field"), HasSubstr("not a regular file")));
    EXPECT_THAT(error_for("scene = \"field\""), AllOf(HasSubstr("source.scene"), HasSubstr("is a folder")));
    EXPECT_THAT(error_for("scene = \"\""), AllOf(HasSubstr("source.scene"), HasSubstr("empty name")));
    EXPECT_EQ(error_for("field = \"field\""), "");
}

TEST(ContentHash, FoldersHashNamesAndContents) {
    TempDir dir;
    write(dir / "a/x.txt", "one");
    write(dir / "a/sub/y.txt", "two");
    write(dir / "b/x.txt", "one");
    write(dir / "b/sub/y.txt", "two");
    EXPECT_EQ(content_hash(dir / "a"), content_hash(dir / "b"));
    write(dir / "b/sub/y.txt", "tw0");
    EXPECT_NE(content_hash(dir / "a"), content_hash(dir / "b"));
    write(dir / "b/sub/y.txt", "two");
    fs::rename(dir / "b/sub/y.txt", dir / "b/sub/z.txt");
    EXPECT_NE(content_hash(dir / "a"), content_hash(dir / "b"));
    EXPECT_EQ(content_hash(dir / "a/x.txt"), content_hash(dir / "b/x.txt"));
    EXPECT_NE(hash_strings({"ab", "c"}), hash_strings({"a", "bc"}));
    EXPECT_THAT(error_of([&] { content_hash(dir / "missing"); }), HasSubstr("cannot read"));
}

}  // namespace
}  // namespace rfd::project
