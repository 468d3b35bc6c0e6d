#pragma once
// What `rfd simulate` says of a prediction, as --json and as text: the Designs I/II
// diffuser picture (optics/display.hpp) and the Designs III/IV views
// (optics/display_angular.hpp), with the lights' checks and the environment map's sampling
// (predict/display_lights.hpp).
//
// Example:
//   const DiffuserPredictionReport report{...};
//   std::printf("%s\n", to_json(report).dump(2).c_str());   // or report_text(report)

#include <cstddef>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "optics/display.hpp"
#include "optics/display_angular.hpp"
#include "optics/model.hpp"
#include "predict/display_lights.hpp"

namespace rfd::predict {

/// A Design I/II prediction: what was asked, what the simulator did, the picture's contrast.
struct DiffuserPredictionReport {
    std::string out;                  ///< the predicted picture's file
    std::string design;               ///< the design's name
    std::string model_choice;         ///< as asked: "auto", "paraxial", "exact"
    optics::ResolvedModel choice;
    double tolerance_dots = 0.0;
    std::vector<std::string> lights;  ///< as the user wrote them
    LightFrame frame = kDefaultLightFrame;
    std::vector<LightCheck> checks;   ///< one per light
    std::string envmap;               ///< "" when none
    EnvironmentSampling sampling;
    const optics::DiffuserImage* result = nullptr;
    optics::PictureContrast contrast;
    optics::DiffuserScatter diffuser;
    double exposure_stops = 0.0;
    double seconds = 0.0;
};
nlohmann::json to_json(const DiffuserPredictionReport& report);
std::string report_text(const DiffuserPredictionReport& report);

/// A Design III/IV prediction: the views written and the simulator's figures.
struct ObserverPredictionReport {
    std::vector<std::string> written;  ///< the images written, views first
    std::string design, design_kind;
    std::string model_choice;
    optics::ResolvedModel choice;
    std::size_t lights = 0;
    std::vector<std::string> views;    ///< "view 0,0", "eye 0,0,1000"
    std::string envmap;
    EnvironmentSampling sampling;
    const optics::AngularDisplayOutput* result = nullptr;
    int macro_x = 0, macro_y = 0;      ///< meso-pixels per macro-pixel
    int lattice_x = 0, lattice_y = 0;  ///< macro-pixels
    double seconds = 0.0;
};
nlohmann::json to_json(const ObserverPredictionReport& report);
std::string report_text(const ObserverPredictionReport& report);

/// How an environment map was sampled, as both reports give it.
nlohmann::json environment_json(const std::string& file, const EnvironmentSampling& sampling);
std::string environment_line(const std::string& file, const EnvironmentSampling& sampling);

}  // namespace rfd::predict
