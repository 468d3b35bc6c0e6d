// Design files (designs/*.toml): parse_design, then the optical system every command builds
// from the design.
#include "fuzz/fuzz.hpp"
#include "optics/design.hpp"

using namespace rfd;

RFD_FUZZ_TARGET(design) {
    const optics::Design design = optics::parse_design(fuzz::text(data, size), "fuzz.toml");
    optics::build_system(design);
}
