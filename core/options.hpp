#pragma once
// Options declared once. A value that several commands, or a command and the project file,
// share is declared as one option in the library that owns it: its command-line name (and
// the older spelling users may have), its project-file key, unit, range, default and help.
// The command line (cli/arguments.hpp), the project-file reader (ConfigTable::value) and the
// generated docs/options.md all read that declaration, so none of these is typed twice
// (Mitsuba's parameter table atop each plugin; pbrt-v4 parses each parameter in one place).
//
// Example (patterns/encode.hpp):
//   inline constexpr NumberOption kTiltOption{"--tilt", "tilt_deg", "deg", -90, 90, 0,
//       "Rotate the display's axis this many degrees toward the field's up"};
//   struct AngularMapping { double tilt_deg = kTiltOption.fallback; ... };

#include <string>
#include <string_view>

namespace rfd {

/// A number option. Both ends of the range are accepted.
struct NumberOption {
    std::string_view flag;   ///< on the command line: "--tilt"
    std::string_view key;    ///< in a project file: "tilt_deg"; empty where only commands have it
    std::string_view unit;   ///< "deg", "mm", "print dots"; empty for a plain number
    double min = 0.0;
    double max = 0.0;
    double fallback = 0.0;   ///< the default
    std::string_view help;   ///< what it sets; the unit, range and default are added where shown
    std::string_view alias = {};  ///< an older command-line spelling still accepted
};

/// A whole-number option (counts: rays, iterations, lights).
struct IntegerOption {
    std::string_view flag;
    std::string_view key;
    std::string_view unit;
    long long min = 0;
    long long max = 0;
    long long fallback = 0;
    std::string_view help;
    std::string_view alias = {};
};

/// "0.05..20", "1..256": the range as the docs and messages write it.
std::string range_text(const NumberOption& option);
std::string range_text(const IntegerOption& option);

/// The help a user reads: the option's help, then its unit ("Rotate ..., deg"). The range
/// and default are shown beside it by whoever shows it (CLI11's help, docs/options.md).
std::string help_text(const NumberOption& option);
std::string help_text(const IntegerOption& option);

}  // namespace rfd
