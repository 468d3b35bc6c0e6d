// Lens prescriptions (designs/lenses/*.toml): parse_lens_system.
#include "fuzz/fuzz.hpp"
#include "optics/lens_file.hpp"

using namespace rfd;

RFD_FUZZ_TARGET(lens) { optics::parse_lens_system(fuzz::text(data, size), "fuzz.toml"); }
