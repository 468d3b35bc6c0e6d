// The project file and rfd make's pipeline: what a project file may say (and the errors
// for what it may not), the plan of steps, and the manifest's skip and re-run, with a
// stand-in runner whose outputs depend on exactly the files a step names.

#include <fstream>
#include <map>
#include <set>
#include <string>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "core/files.hpp"
#include "core/image.hpp"
#include "project/make.hpp"
#include "project/manifest.hpp"
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

// Stands in for rfd: writes every path after an output option, its content the command
// line and the content of every existing file or folder the command names, so outputs
// change exactly when what a step reads changes. Folders (no extension) get one file, the
// preview's folder the three files rfd make checks for.
struct FakeRfd {
    std::vector<std::string> calls;  // the first two words of each command
    std::string fail_on;             // a command ("print sheet") that exits 2
    StepResult operator()(const std::vector<std::string>& arguments) {
        const std::string command = arguments.at(0) + " " + arguments.at(1);
        calls.push_back(command);
        if (command == fail_on) return {2, "rfd: error: the printer is out of ink\n"};
        std::string content;
        for (const std::string& argument : arguments) {
            content += argument + "\n";
            if (fs::exists(argument) && argument.find("field") != std::string::npos)
                content += content_hash(argument) + "\n";
        }
        for (std::size_t k = 0; k + 1 < arguments.size(); ++k) {
            if (arguments[k] != "--out" && arguments[k] != "--preview" && arguments[k] != "--stl") continue;
            fs::path target = arguments[k + 1];
            if (command == "simulate preview") {
                for (const char* file : {"data.js", "predicted.png", "relit.png"}) write(target / file, content);
                continue;
            }
            if (target.extension().empty()) target /= "made.txt";
            if (arguments[k] == "--stl") target.replace_filename("holder_base.stl");
            write(target, content);
        }
        return {0, "made\n"};
    }
};

struct MadeSteps {
    std::set<std::string> ran;
};
MadeSteps run_make(const Project& project, const fs::path& out, FakeRfd& rfd, bool force = false) {
    MakeOptions options;
    options.rfd_identity = "rfd test";
    options.force = force;
    MadeSteps made;
    for (const StepOutcome& step : make(project, out, std::ref(rfd), options))
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

TEST(ProjectPlan, EveryStepReadsOnlyWhatEarlierStepsOrTheUserMade) {
    TempDir dir;
    write_small_field(dir / "field", 0.5f);
    write(dir / "p.toml", kProject);
    const std::vector<Step> steps = plan(load_project(dir / "p.toml"), dir / "out");
    std::vector<std::string> names;
    std::set<fs::path> made;
    for (const Step& step : steps) {
        names.push_back(step.name);
        for (const fs::path& input : step.inputs) {
            if (input.string().starts_with((dir / "out").string())) {
                EXPECT_TRUE(made.count(fs::relative(input, dir / "out"))) << step.name << " reads " << input;
            }
        }
        for (const fs::path& output : step.outputs) made.insert(output);
    }
    // inkjet_720 prints one sheet: no back sheet.
    EXPECT_THAT(names, ::testing::ElementsAre("pattern", "sheet_front_pdf", "moire", "wedge", "holder", "compare", "tolerance", "preview", "verdict"));
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
    for (const Step& step : plan(project, dir / "out")) lines[step.name] = command_line(step);
    ASSERT_TRUE(lines.count("optimize"));
    EXPECT_THAT(lines["optimize"], AllOf(HasSubstr("pattern optimize"), HasSubstr("--from " + (dir / "out").string() + "/pattern.exr"),
                                         HasSubstr("--iterations 12"), HasSubstr("--core-weight 30")));
    for (const char* step : {"sheet_front_pdf", "compare", "tolerance", "preview"})
        EXPECT_THAT(lines[step], HasSubstr("pattern_optimized.exr")) << step;
    EXPECT_THAT(lines["preview"], HasSubstr("--direct " + (dir / "out").string() + "/pattern.exr"));
    write(dir / "p.toml", kProject + "\n[optimize]\nspacing_mm = 0\n");
    EXPECT_THAT(error_of([&] { load_project(dir / "p.toml"); }), HasSubstr("optimize.spacing_mm"));
}

TEST(Make, ASecondRunSkipsEveryStepAndAChangedFieldRemakesOnlyWhatDependsOnIt) {
    TempDir dir;
    write_small_field(dir / "field", 0.5f);
    write(dir / "p.toml", kProject);
    const Project project = load_project(dir / "p.toml");
    FakeRfd rfd;
    EXPECT_EQ(run_make(project, dir / "out", rfd).ran.size(), 9u);
    EXPECT_TRUE(fs::exists(dir / "out/README.txt"));
    EXPECT_TRUE(fs::exists(dir / "out/index.html"));
    EXPECT_TRUE(run_make(project, dir / "out", rfd).ran.empty());

    fs::remove_all(dir / "field");
    write_small_field(dir / "field", 0.75f);
    EXPECT_THAT(run_make(project, dir / "out", rfd).ran,
                UnorderedElementsAre("pattern", "sheet_front_pdf", "compare", "tolerance", "preview", "verdict"));

    // An output removed by hand is made again; what reads it is not, as it comes out the same.
    fs::remove(dir / "out/print/moire.pdf");
    EXPECT_THAT(run_make(project, dir / "out", rfd).ran, UnorderedElementsAre("moire"));
    fs::remove(dir / "out/pattern.png");
    EXPECT_THAT(run_make(project, dir / "out", rfd).ran, UnorderedElementsAre("pattern"));
    EXPECT_EQ(run_make(project, dir / "out", rfd, true).ran.size(), 9u);
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
    EXPECT_EQ(run_make(project, dir / "out", rfd).ran.size(), 9u);
    EXPECT_TRUE(run_make(project, dir / "out", rfd).ran.empty());
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
