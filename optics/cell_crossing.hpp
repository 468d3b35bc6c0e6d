#pragma once
// How the display's tracers (display.cpp, display_angular.cpp) follow a ray that leaves its
// lenslet: it is restarted at the surface where it left, now in the lenslet it crossed into;
// each restart is one more cell boundary crossed.

namespace rfd::optics {

/// Restarts a ray may take; past them it is lost.
inline constexpr int kMaxCrossings = 4;
/// How far before a surface a restarted exact ray begins, mm: clear of its own surface.
inline constexpr double kRestartBackoff = 1e-7;

}  // namespace rfd::optics
