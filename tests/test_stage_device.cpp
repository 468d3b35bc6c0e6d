// The virtual light stage as a capture device: the images it hands to adaptive sampling are
// the stage's own renders under the requested kernel.

#include <gtest/gtest.h>

#include <Eigen/Core>

#include "core/sphere.hpp"
#include "core/units.hpp"
#include "relight/scene.hpp"
#include "relight/stage.hpp"
#include "relight/stage_device.hpp"

namespace rfd::relight {
namespace {

// A glossy sphere on a card: a highlight and a cast shadow, so kernels make a difference.
Scene small_scene() {
    return parse_scene(R"(
[[camera]]
position_mm = [0, 0, 800]
look_at_mm = [0, 0, 0]
up = [0, 1, 0]
fov_deg = 8
resolution = [24, 16]
samples_per_pixel = 1
[kernel]
profile = "constant"
radius_deg = 2
[materials.card]
type = "diffuse"
albedo = [0.8, 0.8, 0.8]
[materials.plastic]
type = "glossy"
albedo = [0.5, 0.1, 0.1]
specular = [0.05, 0.05, 0.05]
roughness = 0.1
[[object]]
type = "card"
material = "card"
center_mm = [0, 0, 0]
normal = [0, 0, 1]
up = [0, 1, 0]
size_mm = [200, 200]
[[object]]
type = "sphere"
material = "plastic"
center_mm = [0, 0, 20]
radius_mm = 20
)", "small.toml", ".");
}

TEST(StageDevice, NarrowImagesAreTheStagesRendersUnderTheScenesKernel) {
    const Scene scene = small_scene();
    StageCaptureDevice device(scene);
    const LightStage stage(scene);
    const std::vector<Eigen::Vector3d> directions = {
        Eigen::Vector3d::UnitZ(), direction_from_angles(degrees_to_radians(50), degrees_to_radians(30))};
    const auto images = device.capture(directions, KernelChoice::Narrow);
    ASSERT_EQ(images.size(), 2u);
    for (std::size_t i = 0; i < 2; ++i) EXPECT_EQ(images[i], stage.render(directions[i]));
    EXPECT_NE(images[0], images[1]);
    EXPECT_DOUBLE_EQ(device.kernel_radius(KernelChoice::Narrow), degrees_to_radians(2));
    EXPECT_EQ(device.images_taken(KernelChoice::Narrow), 2u);
    EXPECT_EQ(device.images_taken(KernelChoice::Wide), 0u);
}

TEST(StageDevice, WideImagesUseTheWideKernelWithEnoughShadowSamples) {
    const Scene scene = small_scene();
    StageCaptureDevice device(scene);
    const Eigen::Vector3d d = direction_from_angles(degrees_to_radians(40), degrees_to_radians(-60));
    const Image wide = device.capture({d}, KernelChoice::Wide).front();
    Scene wide_scene = scene;
    wide_scene.kernel = LightKernel::wide();
    wide_scene.shadow_samples = default_shadow_samples(LightKernel::wide());
    ASSERT_GT(wide_scene.shadow_samples, scene.shadow_samples);
    EXPECT_EQ(wide, LightStage(wide_scene).render(d));
    EXPECT_NE(wide, device.capture({d}, KernelChoice::Narrow).front());
    EXPECT_DOUBLE_EQ(device.kernel_radius(KernelChoice::Wide), LightKernel::wide().radius);
    EXPECT_EQ(device.images_taken(KernelChoice::Wide), 1u);
}

}  // namespace
}  // namespace rfd::relight
