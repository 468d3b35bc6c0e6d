#pragma once
// Advice on a user's own field before the long steps: how many picture elements a design
// shows against the field's pixels, how many of the field's lights fall inside the
// display's range at a tilt, the tilt that puts the most inside (`--tilt auto`), and which
// bundled design shows the field best and why.
//
// "Inside the display's range": a light whose direction, mapped into the display's frame
// (AngularMapping::display_direction), lands paraxially inside the centre lenslet's cell:
// its own photograph is shown at some dot. The range is covered when the field's lights
// surround every direction the pattern holds (the encoder's condition: otherwise it
// extrapolates toward the horizon).
//
// Example: const TiltChoice tilt = best_tilt(DesignOptics(design), directions, mapping);
//          // tilt.tilt_deg, tilt.lights.inside of tilt.lights.total

#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "optics/design_optics.hpp"
#include "patterns/encode.hpp"

namespace rfd::patterns {

/// How a field's lights fall on a design's range under one mapping.
struct LightsInRange {
    int inside = 0;       ///< lights shown at some dot
    int total = 0;
    bool covered = false; ///< the lights surround every direction the pattern holds
};
LightsInRange lights_in_range(const optics::DesignOptics& optics, const std::vector<Eigen::Vector3d>& field_directions,
                              const AngularMapping& mapping);

/// The tilt (whole degrees, -90 to 90; turn and angle scale as given) that covers the range
/// with the most lights inside it; of equals, the smallest tilt. When no tilt covers the
/// range, the one with the most lights inside (covered false).
struct TiltChoice {
    double tilt_deg = 0.0;
    LightsInRange lights;
};
TiltChoice best_tilt(const optics::DesignOptics& optics, const std::vector<Eigen::Vector3d>& field_directions,
                     AngularMapping mapping);

/// `--tilt` and tilt_deg as a user writes them: degrees within kTiltOption's range, or
/// "auto" (nullopt). InputError naming `option` otherwise.
std::optional<double> parse_tilt(const std::string& text, const std::string& option);
/// The help text of a tilt that may be "auto".
inline constexpr const char* kTiltAutoHelp =
    "Rotate the display's axis this many degrees toward the field's up (the thesis used 45), or auto: the tilt "
    "that puts the most of the field's lights inside the display's range";

/// What one design makes of the field.
struct DesignFit {
    std::string name;            ///< the design's name
    std::string file;
    std::string kind;            ///< "I" ... "IV"
    int elements_x = 0, elements_y = 0;  ///< picture elements: lenslets (I/II), macro-pixels (IV), 1 (III)
    bool encodes_pictures = true;  ///< Designs I/II (pattern encode); III/IV take angular fields
    TiltChoice at_given;         ///< at the tilt asked for (the file's or the project's)
    TiltChoice at_best;          ///< at best_tilt
    /// Picture elements the field fills: min(elements, the field's pixels) per axis, when the
    /// range is covered at the best tilt with at least 3 lights inside; 0 otherwise.
    long long shown_elements = 0;
};
DesignFit fit_design(const optics::Design& design, const std::string& file, int field_width, int field_height,
                     const std::vector<Eigen::Vector3d>& field_directions, const AngularMapping& mapping);

struct Advice {
    std::string field;
    int field_width = 0, field_height = 0, lights = 0;
    DesignFit chosen;                 ///< the design the project names
    std::vector<DesignFit> bundled;   ///< each bundled design
    int best = -1;                    ///< index into bundled of the one that shows the field best; -1: none can
    std::vector<std::string> lines;   ///< the advice, one sentence per line
};
/// `chosen` and every design of `bundled` (files) judged on the field; the lines say how
/// many picture elements the chosen design shows against the field's pixels, how many
/// lights fall inside its range at the given tilt and at the best, and which bundled
/// design shows the field best and why.
Advice advise(const optics::Design& chosen, const std::string& chosen_file,
              const std::vector<std::string>& bundled, const std::string& field_name, int field_width,
              int field_height, const std::vector<Eigen::Vector3d>& field_directions, const AngularMapping& mapping);

}  // namespace rfd::patterns
