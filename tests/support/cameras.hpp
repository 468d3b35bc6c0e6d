#pragma once
// The hand-held phone the calibration tests photograph their sheets with: tilted 30 deg,
// turned 20, rolled 7, from 520 mm, blur 1.5 px, 35 % vignetting, 2000 photons at full scale.

#include "calibrate/camera.hpp"

namespace rfd::testing {

inline calibrate::Camera hand_held(calibrate::Camera camera) {
    camera.pose.tilt_deg = 30.0;
    camera.pose.turn_deg = 20.0;
    camera.pose.roll_deg = 7.0;
    camera.pose.distance = 520.0;
    camera.blur = 1.5;
    camera.vignetting = 0.35;
    camera.photons = 2000.0;
    return camera;
}

}  // namespace rfd::testing
