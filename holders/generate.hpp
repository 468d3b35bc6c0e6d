#pragma once
// Lens holders for Designs I-IV (thesis 8.2.4 and 8.3.2): a printed block that holds every
// part of a design at its plane, in register, and lets the design's full field of view
// through. See holder.hpp for the frame and the construction.
//
// How a part is held: it lies in a pocket larger than it by the profile's clearance
// (radially and on one side along z), and rests against one face of the pocket, its seat,
// which is where the design wants that face of the part:
//   - a lens or lenslet array curved toward the light rests its flat back on the seat;
//   - one curved toward the observer rests its flat front on the seat;
//   - a back-to-back pair (pattern between the flats) rests the front array's outer lenslets
//     on the seat, at the depth where their curved faces reach it;
//   - a stack of sheets (Design I: the pattern sheets, spacer, diffuser) rests its front.
// Between pockets, channels as large as the light of the field of view needs (its traced
// envelope plus a margin, and never smaller than a lens's dome) and no larger, so the rims
// of the parts keep a seat. Design II adds baffles between its lenslets from the primary
// array toward the pattern, stepped down to follow the converging light; Design III a
// conical bore with light-trap grooves between the main and the field lens; Design IV
// repeats the Design III cell at every macro-pixel.

#include "holders/holder.hpp"
#include "holders/profile.hpp"
#include "optics/design.hpp"

namespace rfd::holders {

/// Builds the holder. Throws InputError naming the design's file and plane when the design
/// cannot be held: parts whose pockets overlap or leave less than the printable minimum
/// between them, a part whose pocket and walls do not fit its macro-pixel, light that needs
/// the room of a seat.
/// `film`: the pattern's printed transparencies, which the pocket of the pattern's plane
/// keeps room for.
Holder make_holder(const optics::Design& design, const HolderProfile& profile, const PatternFilm& film);

}  // namespace rfd::holders
