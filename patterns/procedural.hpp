#pragma once
// Procedural reflectance fields for the display demonstrations of thesis 8.2.4 (Design II):
// a picture per light direction, as a ReflectanceField the encoder takes like a captured one.
//
//  - letters: one letter of `text` per light direction, the directions spread along the
//    horizontal arc from the left (first letter) to the right (last), each letter in its own
//    colour ("SIG08" under white light from five directions);
//  - bars: two horizontal bars when lit from the left, one vertical bar from the right;
//  - diamonds: a diamond that grows as the light moves down and is hollowed out as the light
//    moves to either side (the shapes of figure 8.15, without its view-dependent colour).
//
// Directions are field directions (core/sphere.hpp: toward the light, x right, y up), within
// `spread_deg` of the zenith; the encoder's AngularMapping then decides which display
// directions show them. So that a field covers a display's whole range, black "guard"
// directions fill the hemisphere away from the pictures (a Fibonacci set, each guard at
// least one picture spacing from every picture direction): between a picture direction and
// its guards the picture fades to black, as the interpolation between captured lights does.
//
// Example: ReflectanceField f = procedural_field({.kind = ProceduralKind::Letters, .text = "SIG08"});

#include <string>

#include "relight/field.hpp"

namespace rfd::patterns {

enum class ProceduralKind { Letters, Bars, Diamonds };

struct ProceduralOptions {
    ProceduralKind kind = ProceduralKind::Letters;
    std::string text = "SIG08";  ///< letters: one character per light direction
    double spread_deg = 10.0;    ///< largest angle of a picture direction from the zenith
    int width = 64, height = 64;
    int diamond_steps = 5;       ///< diamonds: directions per side of the grid
    int guards = 96;             ///< Fibonacci guard directions over the hemisphere
};

/// The field; throws InputError for an empty text, a non-positive size or spread outside
/// (0, 80] degrees, naming the option.
relight::ReflectanceField procedural_field(const ProceduralOptions& options);

}  // namespace rfd::patterns
