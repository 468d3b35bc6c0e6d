// The files steps hand to one another (predict/summaries.hpp, project/manifest.hpp): each
// written and read back gives what was written, every key; a key missing is an error that
// names it; and the one PSNR of a display against its field has its closed form.

#include <cmath>
#include <fstream>
#include <string>

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "core/error.hpp"
#include "predict/summaries.hpp"
#include "predict/verdict.hpp"
#include "project/manifest.hpp"
#include "tests/support/error_of.hpp"
#include "tests/support/temp_dir.hpp"

namespace rfd::predict {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;
using testing::error_of;
using testing::TempDir;

TEST(PsnrAgainstField, ClosedForm) {
    EXPECT_NEAR(*psnr_against_field_db(1e-3, 1.0), 30.0, 1e-12);
    EXPECT_NEAR(*psnr_against_field_db(4e-6, 2.0), 10.0 * std::log10(4.0 / 4e-6), 1e-12);
    EXPECT_EQ(*psnr_against_field_db(0.0, 1.0), 100.0);     // a perfect match: the cap
    EXPECT_EQ(*psnr_against_field_db(1e-30, 1.0), 100.0);   // anything above it too
    EXPECT_FALSE(psnr_against_field_db(1e-3, 0.0));         // a black field: nothing to compare with
    EXPECT_FALSE(psnr_against_field_db(std::nan(""), 1.0));
}

// Every field set to a value that differs from its default, optional ones both present and
// absent across the records, so a key from_json forgot shows as a changed text.
CompareSummary full_compare_summary() {
    CompareSummary s;
    s.design = "Design II";
    s.pattern = "pattern.exr";
    s.field = "/data/field";
    s.model = "exact";
    s.model_choice = "auto";
    s.paraxial_error_dots = 1.25;
    s.rays_per_side = 32;
    s.lenslets = {6, 5};
    s.display_range_deg = 16.5;
    s.field_peak = 0.875;
    s.core_fraction = 0.84;
    s.core_magnification = 1.157;
    s.directions.push_back({"light_00.png", 1.5, -90.0, 0.25, true, true, 0.43, 0.875, 1e-4, 38.8, 39.1, 1.02, 40.5,
                            35.25, 11776});
    s.directions.push_back({"light_01.png", 30.0, 45.0, 25.5, false, false, 0.12, 1e-4, 1e-6, 58.8, std::nullopt,
                            0.5, std::nullopt, 57.0, 512});
    s.in_fov = {1, 38.8, 38.8, 40.5, 40.5, 35.25};
    s.crosstalk_free = {1, 38.75, 38.5, std::nullopt, 40.25, 35.0};
    s.accuracy_directions = 3;
    s.accuracy.push_back({"auto (exact)", 4, 4096, 0.125, 2e-5, 47.0, 41.0, std::nullopt, {{0.0, 48.0, 49.0}, {5.0, std::nullopt, 45.0}}});
    return s;
}

TEST(Summaries, CompareSummaryRoundTripsEveryKey) {
    TempDir dir;
    const CompareSummary written = full_compare_summary();
    write_summary(dir / "summary.json", written);
    const CompareSummary read = read_summary<CompareSummary>(dir / "summary.json");
    EXPECT_EQ(summary_text(read), summary_text(written));
    ASSERT_EQ(read.directions.size(), 2u);
    EXPECT_FALSE(read.directions[1].psnr_own_peak_db);
    EXPECT_EQ(read.directions[1].rays, 512);
    EXPECT_EQ(read.accuracy.at(0).per_direction.at(1).fitted_psnr_db, 45.0);
}

TEST(Summaries, ToleranceSummaryRoundTripsEveryKey) {
    TempDir dir;
    ToleranceSummary s;
    s.design = "Design I";
    s.model = "paraxial";
    s.summary = "Shift 0.19 mm and rotation 0.43 deg";
    s.threshold_db = 30.0;
    s.lights = 3;
    s.nominal_peak = 0.71;
    s.curves.push_back({"shift", "mm", 1.0, 0.19, {{0.0, 100.0, 0.0}, {0.5, 21.0, 0.25}}, {{0.19, 30.5, std::nullopt}}, "shift.svg"});
    s.curves.push_back({"spacer", "mm", 0.75, std::nullopt, {{0.0, 100.0, 0.0}}, {}, "spacer.svg"});
    write_summary(dir / "summary.json", s);
    const ToleranceSummary read = read_summary<ToleranceSummary>(dir / "summary.json");
    EXPECT_EQ(summary_text(read), summary_text(s));
    EXPECT_FALSE(read.curves.at(1).tolerance);
    EXPECT_EQ(read.curves.at(0).sweep.at(1).shift_lenslets, 0.25);
}

TEST(Summaries, RegistrationSummaryRoundTripsEveryKey) {
    TempDir dir;
    RegistrationSummary s;
    s.design = "Design I";
    s.photographs = 2;
    s.light = "turned pair";
    s.shift_mm = {0.081, -0.049};
    s.sigma_shift_mm = {0.002, 0.003};
    s.rotation_deg = 0.11;
    s.sigma_rotation_deg = 0.004;
    s.scale_error = -2e-4;
    s.sigma_scale_error = 5e-5;
    s.tolerance_shift_mm = 0.19;
    s.inside = true;
    write_summary(dir / "registration.json", s);
    const RegistrationSummary read = read_summary<RegistrationSummary>(dir / "registration.json");
    EXPECT_EQ(summary_text(read), summary_text(s));
    EXPECT_EQ(read.shift_mm[1], -0.049);
    EXPECT_FALSE(read.tolerance_rotation_deg);
    EXPECT_EQ(read.inside, std::optional<bool>(true));
    s.inside.reset();
    write_summary(dir / "registration.json", s);
    EXPECT_FALSE(read_summary<RegistrationSummary>(dir / "registration.json").inside);
}

TEST(Summaries, VerdictReportRoundTripsEveryKeyAndComesFromTheVerdict) {
    TempDir dir;
    VerdictInputs inputs;
    inputs.design = "Design II";
    inputs.field_of_view_deg = 24.1;
    inputs.crosstalk_free_cone_deg = 18.9;
    inputs.directions = {{0.0, true, true, 1e-4, 1.0}, {3.0, true, false, 1e-6, 1e-4}};
    inputs.tolerances = AssemblyTolerances{0.19, 0.43, 9017.0, 1.37};
    inputs.warnings = {"macro-pixels overlap"};
    const VerdictReport report = verdict_report(judge(inputs), {"spacer"});
    EXPECT_EQ(report.directions_in_fov, 2);
    EXPECT_NEAR(*report.psnr_mean_in_fov_db, 50.0, 1e-9);  // 40 dB and 60 dB against the field's peak of 1
    ASSERT_TRUE(report.tolerances);
    EXPECT_EQ(report.tolerances->pitch_error_ppm, 9017.0);
    write_summary(dir / "verdict.json", report);
    const VerdictReport read = read_summary<VerdictReport>(dir / "verdict.json");
    EXPECT_EQ(summary_text(read), summary_text(report));
    EXPECT_EQ(read.line, report.line);
    EXPECT_EQ(read.tolerances->at_least, std::vector<std::string>{"spacer"});

    VerdictReport bare = report;  // no tolerance sweep
    bare.tolerances.reset();
    write_summary(dir / "bare.json", bare);
    EXPECT_FALSE(read_summary<VerdictReport>(dir / "bare.json").tolerances);
}

TEST(Summaries, AKeyMissingOrOfAnotherTypeIsAnErrorNamingIt) {
    TempDir dir;
    nlohmann::json json = full_compare_summary();
    json["directions"][1].erase("mse");
    std::ofstream(dir / "missing.json") << json.dump();
    EXPECT_THAT(error_of([&] { read_summary<CompareSummary>(dir / "missing.json"); }),
                AllOf(HasSubstr("missing.json"), HasSubstr("'mse'"), HasSubstr("not what rfd writes")));
    json = full_compare_summary();
    json["field_peak"] = "bright";
    std::ofstream(dir / "type.json") << json.dump();
    EXPECT_THAT(error_of([&] { read_summary<CompareSummary>(dir / "type.json"); }), HasSubstr("type.json"));
    std::ofstream(dir / "broken.json") << "{\"curves\": 3}";
    EXPECT_THAT(error_of([&] { read_summary<ToleranceSummary>(dir / "broken.json"); }), HasSubstr("broken.json"));
    EXPECT_THAT(error_of([&] { read_summary<VerdictReport>(dir / "nowhere.json"); }), HasSubstr("cannot open"));
}

TEST(Summaries, TheManifestRoundTripsItsSteps) {
    TempDir dir;
    {
        project::Manifest manifest = project::Manifest::read(dir.path());
        manifest.record("pattern", {"key-1", {{"pattern.exr", "aa"}, {"pattern.png", "bb"}}});
        manifest.record("compare", {"key-2", {{"predict/compare", "cc"}}});
        manifest.write();
    }
    const project::Manifest read = project::Manifest::read(dir.path());
    ASSERT_EQ(read.steps().size(), 2u);
    EXPECT_EQ(read.steps().at("pattern").key, "key-1");
    EXPECT_EQ(read.steps().at("pattern").outputs.at("pattern.png"), "bb");
    EXPECT_EQ(read.steps().at("compare").outputs.at("predict/compare"), "cc");
}

}  // namespace
}  // namespace rfd::predict
