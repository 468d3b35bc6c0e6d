#pragma once
// Registration of the rfd subcommands. Each command is thin: it parses its arguments,
// calls the libraries, and prints. No science lives in cli/.

#include <memory>

#include <CLI/CLI.hpp>

namespace rfd::cli {

void add_optics_commands(CLI::App& app);
void add_chart_command(CLI::App& optics);
void add_design_commands(CLI::App& app);
/// rfd design tune, under `design` (cli/design_tune_commands.cpp).
void add_design_tune_command(CLI::App& design_cmd);
/// rfd design advise, under `design` (cli/design_advise_commands.cpp).
void add_design_advise_command(CLI::App& design_cmd);
void add_capture_commands(CLI::App& capture);
void add_adaptive_command(CLI::App& capture);
void add_study_command(CLI::App& capture);
/// The `relight` group: render, eval.
void add_relight_commands(CLI::App& app);
/// `relight implicit`: train, predict, sweep (thesis chapter 7).
void add_implicit_commands(CLI::App& relight);
/// `relight upsample`: feature-guided upsampling (thesis chapter 6).
void add_upsample_command(CLI::App& relight);
/// `capture implicit`: training and held-out sets for implicit relighting on the virtual stage.
void add_capture_implicit_command(CLI::App& capture);
/// `capture hdr` (exposure brackets) and `capture calibrate` (mirror-sphere light directions).
void add_capture_tool_commands(CLI::App& capture);

/// The `pattern` group: encode (Designs I/II), field (procedural test fields).
void add_pattern_commands(CLI::App& app);
/// The `print` group: sheet (pattern sheets for a printer), moire (pitch calibration).
void add_print_commands(CLI::App& app);
/// rfd calibrate tone (calibrate_commands.cpp).
void add_calibrate_commands(CLI::App& app);
/// `pattern encode-angular` (Designs III/IV), added to the `pattern` group.
void add_pattern_angular_command(CLI::App& pattern);
/// `pattern optimize` (Designs I/II): a pattern chosen through the simulator.
void add_pattern_optimize_command(CLI::App& pattern);

/// `simulate`: the predicted output of a Design I/II display under lights.
void add_simulate_commands(CLI::App& app);
/// `simulate tolerance`: PSNR against assembly errors (shift, rotation, pitch, spacer).
void add_simulate_tolerance_command(CLI::App& simulate);

/// `simulate compare`: predicted output against the software relighting of the same field.
void add_simulate_compare_command(CLI::App& simulate);

/// `simulate verdict`: go / check / no-go from compare's and tolerance's summaries.
void add_simulate_verdict_command(CLI::App& simulate);

/// `simulate preview`: the precomputed pictures of rfd make's preview page.
void add_simulate_preview_command(CLI::App& simulate);

/// `holder`: the lens holder as OpenSCAD, its STLs and their checks; `holder coupon`.
void add_holder_commands(CLI::App& app);

/// `make`: a project file into every output (project/make.hpp).
void add_make_command(CLI::App& app);

/// `options-doc` (hidden): every other command's options as Markdown, docs/options.md.
void add_options_doc_command(CLI::App& app);

}  // namespace rfd::cli
