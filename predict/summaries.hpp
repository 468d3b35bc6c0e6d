#pragma once
// The files one step writes and a later one reads, as structs: rfd make's steps, the
// verdict and the index page talk through them, and a key renamed on one side breaks the
// build or the round-trip test (tests/test_summaries.cpp), never the verdict silently.
//
//   predict/compare/summary.json    CompareSummary    rfd simulate compare  -> rfd simulate verdict
//   predict/tolerance/summary.json  ToleranceSummary  rfd simulate tolerance -> rfd simulate verdict
//   verdict.json                    VerdictReport     rfd simulate verdict  -> README.txt, index.html
//   calibration/registration.json   RegistrationSummary rfd calibrate registration -> README.txt
//
// One PSNR for a display against its field: 10 log10(field_peak^2 / MSE), field_peak the
// brightest reference value over every compared direction (psnr_against_field_db). A
// direction where the field is dark (a test field lights one letter per direction) then
// reads high when the display is dark there too, instead of -60 dB for a faint residue
// against its own faint peak; `psnr_own_peak_db` keeps that per-direction figure.
//
// Example:
//   write_summary(out / "summary.json", summarise_comparison(results));
//   const CompareSummary compare = read_summary<CompareSummary>(folder / "summary.json");

#include <array>
#include <cstddef>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json_fwd.hpp>

namespace rfd::predict {

struct DirectionComparison;
struct Verdict;

/// PSNR of a display against its field, dB: 10 log10(field_peak^2 / mse), a perfect match
/// (mse 0) and anything above capped at 100 dB so that means stay finite; nullopt when the
/// field is black (field_peak <= 0) or mse is not finite.
std::optional<double> psnr_against_field_db(double mse, double field_peak);
/// That PSNR's peak: the reference's brightest value over the compared directions.
double field_peak_of(const std::vector<DirectionComparison>& results);

/// PSNR figures over a set of directions (those inside the field of view, or the
/// crosstalk-free ones); nullopt where the set is empty.
struct PsnrFigures {
    int count = 0;
    std::optional<double> min_psnr_db, mean_psnr_db;            ///< whole picture (macro-pixel cores for Design II)
    std::optional<double> min_psnr_fitted_db, mean_psnr_fitted_db;  ///< with the fitted gain
    std::optional<double> min_psnr_cell_db;                     ///< over whole cells
};

/// One light direction of `rfd simulate compare`.
struct CompareDirection {
    std::string image;                     ///< its side-by-side PNG in the folder
    double field_theta_deg = 0.0, field_phi_deg = 0.0, display_angle_deg = 0.0;
    bool inside_fov = false, crosstalk_free = false;
    double efficiency = 0.0;
    double peak = 0.0;                     ///< the reference's brightest value in this direction
    double mse = 0.0;                      ///< against the relit field
    std::optional<double> psnr_db;         ///< against the field's brightest (the one PSNR)
    std::optional<double> psnr_own_peak_db;///< against this direction's own brightest
    double fitted_gain = 1.0;
    std::optional<double> psnr_fitted_db;  ///< with the fitted gain, against the field's brightest
    std::optional<double> psnr_cell_db;    ///< over whole cells, against the field's brightest
    long long rays = 0;
};

/// `--chart-accuracy`: one model at one ray count against the converged prediction.
struct AccuracyRecord {
    struct Direction {
        double display_angle_deg = 0.0;
        std::optional<double> psnr_db, fitted_psnr_db;
    };
    std::string model;
    int rays_per_side = 0;
    long long rays = 0;
    double seconds = 0.0;  ///< wall-clock: the one time a file holds, asked for by --chart-accuracy
    double mse = 0.0;
    std::optional<double> psnr_db, worst_psnr_db, fitted_psnr_db;
    std::vector<Direction> per_direction;
};

/// predict/compare/summary.json.
struct CompareSummary {
    std::string design, pattern, field;
    std::string model, model_choice;
    std::optional<double> paraxial_error_dots;
    int rays_per_side = 0;
    std::array<int, 2> lenslets{0, 0};
    double display_range_deg = 0.0;
    double field_peak = 0.0;               ///< the peak of every psnr_db: the brightest over the directions
    double core_fraction = 1.0, core_magnification = 1.0;  ///< MacroPixelCore
    std::vector<CompareDirection> directions;
    PsnrFigures in_fov, crosstalk_free;
    std::size_t accuracy_directions = 0;
    std::vector<AccuracyRecord> accuracy;
};

/// The directions and the figures over them, from `simulate compare`'s results; the
/// caller fills what names the inputs (design, pattern, field, model, ...). `images[k]`
/// names result k's picture.
CompareSummary summarise_comparison(const std::vector<DirectionComparison>& results,
                                    const std::vector<std::string>& images);

/// One kind of mounting error of `rfd simulate tolerance`, in the unit it is shown in.
struct ToleranceCurveRecord {
    struct Point {
        double error = 0.0, psnr_db = 0.0;
        std::optional<double> shift_lenslets;  ///< the sweep's points; not the refinement's
    };
    std::string kind;                 ///< "shift", "rotation", "pitch_error", "spacer"
    std::string unit;
    double max = 0.0;                 ///< the largest error swept
    std::optional<double> tolerance;  ///< nullopt: the whole sweep stayed above the threshold
    std::vector<Point> sweep, refinement;
    std::string chart;                ///< its chart's file name in the folder
};

/// predict/tolerance/summary.json.
struct ToleranceSummary {
    std::string design, model, summary;
    double threshold_db = 0.0;
    std::size_t lights = 0;
    double nominal_peak = 0.0;
    std::vector<ToleranceCurveRecord> curves;
};

/// verdict.json.
struct VerdictReport {
    struct Tolerances {
        std::optional<double> shift_mm, rotation_deg, pitch_error_ppm, spacer_mm;
        std::vector<std::string> at_least;  ///< kinds the sweep only bounded from below
    };
    std::string design, call, reason, line;
    /// The two parts: on this field (whatever the design's warnings), on the design itself.
    std::string field_call, field_line, design_call, design_line;
    std::optional<double> psnr_mean_in_fov_db, psnr_min_in_fov_db, psnr_mean_crosstalk_free_db;
    int directions_in_fov = 0, directions_crosstalk_free = 0;
    std::optional<double> field_of_view_deg, crosstalk_free_cone_deg;
    std::optional<Tolerances> tolerances;
    std::vector<std::string> warnings;
};

/// calibration/registration.json: where the printed pattern sits on the lens array, as
/// photographs of the assembled display measured it, and whether that is inside the design's
/// tolerances.
struct RegistrationSummary {
    std::string design;
    int photographs = 0;
    std::string light;  ///< how the light's spot was taken out: "given", "turned pair", "assumed head-on"
    std::array<double, 2> shift_mm{}, sigma_shift_mm{};  ///< right and up of where it belongs, seen from the front
    double rotation_deg = 0.0, sigma_rotation_deg = 0.0;  ///< counter-clockwise seen from the front
    double scale_error = 0.0, sigma_scale_error = 0.0;    ///< the print's size over the encoded, minus 1
    std::optional<double> tolerance_shift_mm, tolerance_rotation_deg;
    std::optional<bool> inside;  ///< nullopt: no tolerances to judge against
};

/// The report of `verdict`; `at_least` as in VerdictReport::Tolerances.
VerdictReport verdict_report(const Verdict& verdict, const std::vector<std::string>& at_least);

void to_json(nlohmann::json& json, const CompareDirection& value);
void from_json(const nlohmann::json& json, CompareDirection& value);
void to_json(nlohmann::json& json, const AccuracyRecord& value);
void from_json(const nlohmann::json& json, AccuracyRecord& value);
void to_json(nlohmann::json& json, const CompareSummary& value);
void from_json(const nlohmann::json& json, CompareSummary& value);
void to_json(nlohmann::json& json, const ToleranceCurveRecord& value);
void from_json(const nlohmann::json& json, ToleranceCurveRecord& value);
void to_json(nlohmann::json& json, const ToleranceSummary& value);
void from_json(const nlohmann::json& json, ToleranceSummary& value);
void to_json(nlohmann::json& json, const VerdictReport& value);
void from_json(const nlohmann::json& json, VerdictReport& value);
void to_json(nlohmann::json& json, const RegistrationSummary& value);
void from_json(const nlohmann::json& json, RegistrationSummary& value);

/// Writes `value` as indented JSON, atomically.
template <class Summary>
void write_summary(const std::filesystem::path& file, const Summary& value);

/// Reads a file written by write_summary. IoError when it cannot be opened; InputError
/// naming the file and the key when it is not what rfd writes (a key missing, renamed or of
/// another type).
template <class Summary>
Summary read_summary(const std::filesystem::path& file);

/// The same as text: what --json prints.
template <class Summary>
std::string summary_text(const Summary& value);

}  // namespace rfd::predict
