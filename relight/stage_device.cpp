#include "relight/stage_device.hpp"

#include <algorithm>
#include <utility>

namespace rfd::relight {

StageCaptureDevice::StageCaptureDevice(Scene scene, LightKernel wide)
    : scene_(std::move(scene)), wide_(wide), narrow_stage_(scene_) {}

const LightKernel& StageCaptureDevice::kernel(KernelChoice choice) const {
    return choice == KernelChoice::Narrow ? scene_.kernel : wide_;
}

double StageCaptureDevice::kernel_radius(KernelChoice choice) const { return kernel(choice).radius; }

std::size_t StageCaptureDevice::images_taken(KernelChoice choice) const {
    return choice == KernelChoice::Narrow ? narrow_taken_ : wide_taken_;
}

std::vector<Image> StageCaptureDevice::capture(const std::vector<Eigen::Vector3d>& directions,
                                               KernelChoice choice) {
    const LightStage* stage = &narrow_stage_;
    if (choice == KernelChoice::Wide) {
        if (!wide_stage_) {
            Scene wide_scene = scene_;
            wide_scene.kernel = wide_;
            wide_scene.shadow_samples = std::max(scene_.shadow_samples, default_shadow_samples(wide_));
            wide_stage_ = std::make_unique<LightStage>(std::move(wide_scene));
        }
        stage = wide_stage_.get();
    }
    std::vector<Image> images;
    images.reserve(directions.size());
    for (const Eigen::Vector3d& d : directions) images.push_back(stage->render(d, kernel(choice)));
    (choice == KernelChoice::Narrow ? narrow_taken_ : wide_taken_) += directions.size();
    return images;
}

}  // namespace rfd::relight
