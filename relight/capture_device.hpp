#pragma once
// Capture devices: whatever takes an image of the scene under one distant light. Adaptive
// sampling (adaptive.hpp) asks a device for the images of the directions it chooses, so
// the virtual light stage and a real rig serve alike.
//
// CommandCaptureDevice drives a real rig through a user's program: for every direction it
// runs a shell command built from a template whose placeholders are replaced:
//   {x} {y} {z}     the unit direction toward the light, field frame (core/sphere.hpp)
//   {theta} {phi}   the same in degrees
//   {kernel}        "narrow" or "wide" (two-level fields ask for wide images)
//   {out}           the image file the command must write (EXR or any format rfd reads)
// Example: CommandCaptureDevice rig("shoot --theta {theta} --phi {phi} -o {out}", dir);

#include <filesystem>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/image.hpp"
#include "relight/field.hpp"

namespace rfd::relight {

/// Which of the device's two lights an image is taken with (two-level fields, 5.4).
enum class KernelChoice { Narrow, Wide };

class CaptureDevice {
public:
    virtual ~CaptureDevice() = default;
    /// One linear image per direction, in order, under the narrow or the wide light.
    virtual std::vector<Image> capture(const std::vector<Eigen::Vector3d>& directions,
                                       KernelChoice kernel) = 0;
    /// Angular radius (radians) of the light each kernel gives, as recorded in the field.
    virtual double kernel_radius(KernelChoice kernel) const = 0;
};

class CommandCaptureDevice : public CaptureDevice {
public:
    /// `scratch` is a directory for the command's output files (created if needed). Each
    /// photograph is read through `window` (the object's part of the frame, then scaled).
    CommandCaptureDevice(std::string command_template, std::filesystem::path scratch,
                         double narrow_radius = 0.0, double wide_radius = 0.0, ImageWindow window = {});
    std::vector<Image> capture(const std::vector<Eigen::Vector3d>& directions,
                               KernelChoice kernel) override;
    double kernel_radius(KernelChoice kernel) const override {
        return kernel == KernelChoice::Narrow ? narrow_radius_ : wide_radius_;
    }
    /// The command line for one direction (exposed for tests and --dry-run reports).
    std::string command_for(const Eigen::Vector3d& direction, KernelChoice kernel,
                            const std::filesystem::path& out) const;

private:
    std::string template_;
    std::filesystem::path scratch_;
    double narrow_radius_;
    double wide_radius_;
    ImageWindow window_;
    std::size_t counter_ = 0;
};

}  // namespace rfd::relight
