#include "relight/capture_device.hpp"

#include <cstdio>
#include <cstdlib>
#include <sys/wait.h>

#include "core/command.hpp"
#include "core/error.hpp"
#include "core/files.hpp"
#include "core/image_io.hpp"
#include "core/sphere.hpp"
#include "core/units.hpp"
#include "core/text.hpp"

namespace rfd::relight {
namespace {

void replace_all(std::string& text, const std::string& key, const std::string& value) {
    for (std::size_t at = text.find(key); at != std::string::npos; at = text.find(key, at + value.size()))
        text.replace(at, key.size(), value);
}

}  // namespace

CommandCaptureDevice::CommandCaptureDevice(std::string command_template,
                                           std::filesystem::path scratch, double narrow_radius,
                                           double wide_radius, ImageWindow window)
    : template_(std::move(command_template)),
      scratch_(std::move(scratch)),
      narrow_radius_(narrow_radius),
      wide_radius_(wide_radius),
      window_(window) {
    if (template_.find("{out}") == std::string::npos)
        throw InputError(SourceLocation{"", 0, 0, "--device"},
                         "the capture command must contain {out}, the image file it writes");
    ensure_directory(scratch_);
}

std::string CommandCaptureDevice::command_for(const Eigen::Vector3d& direction, KernelChoice kernel,
                                              const std::filesystem::path& out) const {
    const SphericalAngles angles = angles_of(direction);
    std::string command = template_;
    replace_all(command, "{x}", format_number(direction.x(), 9));
    replace_all(command, "{y}", format_number(direction.y(), 9));
    replace_all(command, "{z}", format_number(direction.z(), 9));
    replace_all(command, "{theta}", format_number(radians_to_degrees(angles.theta), 9));
    replace_all(command, "{phi}", format_number(radians_to_degrees(angles.phi), 9));
    replace_all(command, "{kernel}", kernel == KernelChoice::Narrow ? "narrow" : "wide");
    replace_all(command, "{out}", shell_quoted(out.string()));
    return command;
}

std::vector<Image> CommandCaptureDevice::capture(const std::vector<Eigen::Vector3d>& directions,
                                                 KernelChoice kernel) {
    std::vector<Image> images;
    for (const Eigen::Vector3d& direction : directions) {
        char name[32];
        std::snprintf(name, sizeof name, "capture_%06zu.exr", counter_++);
        const std::filesystem::path out = scratch_ / name;
        std::error_code ec;
        std::filesystem::remove(out, ec);
        const std::string command = command_for(direction, kernel, out);
        const int status = std::system(command.c_str());
        if (status == -1 || !WIFEXITED(status) || WEXITSTATUS(status) != 0)
            throw ToolError("capture command failed (" +
                            (status == -1 || !WIFEXITED(status)
                                 ? std::string("did not run to completion")
                                 : "exit status " + std::to_string(WEXITSTATUS(status))) +
                            "): " + command);
        if (!std::filesystem::exists(out))
            throw ToolError("capture command succeeded but wrote no image at " + out.string() +
                            ": " + command);
        images.push_back(apply_window(read_image(out), window_, out.string()));
        if (!images.front().same_shape(images.back()))
            throw ToolError("capture command returned images of different sizes: " + command);
        std::filesystem::remove(out, ec);
    }
    return images;
}

}  // namespace rfd::relight
