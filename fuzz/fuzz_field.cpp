// Field folders (rfd capture render's output): read_field over a folder of tiny images
// (a.exr, b.exr and c.png of 4 x 3 RGB, odd.exr of 5 x 3) whose light file is the input.
#include <filesystem>

#include "core/image.hpp"
#include "core/image_io.hpp"
#include "fuzz/fuzz.hpp"
#include "relight/field.hpp"

using namespace rfd;

namespace {

const std::filesystem::path& field_folder() {
    static const std::filesystem::path folder = [] {
        const auto path = fuzz::scratch_folder() / "field";
        std::filesystem::create_directories(path);
        const Image image(4, 3, 3, 0.25f);
        write_image(path / "a.exr", image);
        write_image(path / "b.exr", image);
        write_image(path / "c.png", image);
        write_image(path / "odd.exr", Image(5, 3, 3, 0.5f));
        return path;
    }();
    return folder;
}

}  // namespace

RFD_FUZZ_TARGET(field) {
    const auto& folder = field_folder();
    fuzz::write_bytes(folder / "field.lp", data, size);
    relight::read_field(folder);
}
