#pragma once
// The virtual light stage as a capture device, so adaptive sampling (adaptive.hpp) can drive
// it exactly as it drives a real rig.
//
// Narrow images use the scene's own kernel (scenes/*.toml: a spot of a few degrees), wide
// ones the given wide kernel (default LightKernel::wide(), the thesis's frost-filtered
// light). Wide images are rendered by a second LightStage whose scene takes at least the
// shadow samples the wide kernel needs; it is built on the first wide request, since most
// runs never make one. No progress output: callers know how much work a run holds.
//
// Example: StageCaptureDevice device(load_scene("scenes/bottle.toml"));
//          AdaptiveRun run = adaptive_capture(device, initial, delaunay_triangles, options);

#include <memory>
#include <vector>

#include <Eigen/Core>

#include "core/image.hpp"
#include "relight/capture_device.hpp"
#include "relight/light_kernel.hpp"
#include "relight/scene.hpp"
#include "relight/stage.hpp"

namespace rfd::relight {

class StageCaptureDevice : public CaptureDevice {
public:
    /// Traces the camera paths of the scene's first camera (the stage's one-off cost).
    explicit StageCaptureDevice(Scene scene, LightKernel wide = LightKernel::wide());

    std::vector<Image> capture(const std::vector<Eigen::Vector3d>& directions,
                               KernelChoice kernel) override;
    double kernel_radius(KernelChoice kernel) const override;

    const LightKernel& kernel(KernelChoice choice) const;
    /// Images rendered so far, per kernel: the cost of a run in the thesis's currency.
    std::size_t images_taken(KernelChoice choice) const;

private:
    Scene scene_;
    LightKernel wide_;
    LightStage narrow_stage_;
    std::unique_ptr<LightStage> wide_stage_;
    std::size_t narrow_taken_ = 0;
    std::size_t wide_taken_ = 0;
};

}  // namespace rfd::relight
