// Light files (.lp): read_light_file, from a file as the program reads it.
#include "fuzz/fuzz.hpp"
#include "relight/field.hpp"

using namespace rfd;

RFD_FUZZ_TARGET(light_file) {
    const auto path = fuzz::scratch_folder() / "fuzz.lp";
    fuzz::write_bytes(path, data, size);
    relight::read_light_file(path);
}
