// A real rig through a user's command: placeholders, quoting, and each failure's message.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "core/error.hpp"
#include "core/image_io.hpp"
#include "core/sphere.hpp"
#include "core/units.hpp"
#include "relight/capture_device.hpp"
#include "tests/support/error_of.hpp"
#include "tests/support/temp_dir.hpp"

namespace rfd::relight {
namespace {

using ::testing::HasSubstr;
using rfd::testing::TempDir;

using rfd::testing::error_of;

TEST(CommandCaptureDevice, FillsEveryPlaceholder) {
    TempDir dir;
    const CommandCaptureDevice device("shoot {theta} {phi} {x} {y} {z} {kernel} {out}", dir / "scratch");
    const std::string command = device.command_for(direction_from_angles(degrees_to_radians(30), degrees_to_radians(-90)),
                                                   KernelChoice::Wide, "/tmp/it's.exr");
    EXPECT_THAT(command, HasSubstr("shoot 30 -90 "));
    EXPECT_THAT(command, HasSubstr(" wide '/tmp/it'\\''s.exr'"));
}

// The "rig" copies a prepared image to {out}: what the device returns must be that image.
TEST(CommandCaptureDevice, ReturnsTheImageTheCommandWrote) {
    TempDir dir;
    Image image(4, 3, 3);
    for (std::size_t k = 0; k < image.samples().size(); ++k) image.samples()[k] = 0.1f * static_cast<float>(k);
    write_image(dir / "prepared.exr", image);
    CommandCaptureDevice device("cp " + (dir / "prepared.exr").string() + " {out}", dir / "scratch");
    const auto images = device.capture({Eigen::Vector3d::UnitZ(), Eigen::Vector3d(1, 0, 1).normalized()}, KernelChoice::Narrow);
    ASSERT_EQ(images.size(), 2u);
    EXPECT_EQ(images[0], image);
    EXPECT_EQ(images[1], image);
}

// A rig's photographs hold more than the object: the device reads each through its window.
TEST(CommandCaptureDevice, ReadsEachPhotographThroughItsWindow) {
    TempDir dir;
    Image image(4, 3, 1);
    for (std::size_t k = 0; k < image.samples().size(); ++k) image.samples()[k] = static_cast<float>(k);
    write_image(dir / "prepared.exr", image);
    ImageWindow window;
    window.x = 1;
    window.y = 1;
    window.width = 2;
    window.height = 2;
    CommandCaptureDevice device("cp " + (dir / "prepared.exr").string() + " {out}", dir / "scratch", 0.0, 0.0, window);
    const auto images = device.capture({Eigen::Vector3d::UnitZ()}, KernelChoice::Narrow);
    ASSERT_EQ(images.size(), 1u);
    ASSERT_EQ(images[0].width(), 2);
    ASSERT_EQ(images[0].height(), 2);
    EXPECT_EQ(images[0].at(0, 0, 0), image.at(1, 1, 0));
    EXPECT_EQ(images[0].at(1, 1, 0), image.at(2, 2, 0));
    window.width = 9;
    CommandCaptureDevice outside("cp " + (dir / "prepared.exr").string() + " {out}", dir / "scratch2", 0.0, 0.0, window);
    EXPECT_THAT(error_of([&] { outside.capture({Eigen::Vector3d::UnitZ()}, KernelChoice::Narrow); }), HasSubstr("region"));
}

TEST(CommandCaptureDevice, FailuresAreNamed) {
    TempDir dir;
    EXPECT_THAT(error_of([&] { CommandCaptureDevice("shoot", dir / "s"); }), HasSubstr("must contain {out}"));
    CommandCaptureDevice failing("exit 3 # {out}", dir / "s");
    EXPECT_THAT(error_of([&] { failing.capture({Eigen::Vector3d::UnitZ()}, KernelChoice::Narrow); }),
                HasSubstr("capture command failed (exit status 3)"));
    CommandCaptureDevice silent("true {out}", dir / "s");
    EXPECT_THAT(error_of([&] { silent.capture({Eigen::Vector3d::UnitZ()}, KernelChoice::Narrow); }),
                HasSubstr("wrote no image"));
}

}  // namespace
}  // namespace rfd::relight
