// Holder printer profiles (holders/profiles/*.toml): parse_profile.
#include "fuzz/fuzz.hpp"
#include "holders/profile.hpp"

using namespace rfd;

RFD_FUZZ_TARGET(holder_profile) { holders::parse_profile(fuzz::text(data, size), "fuzz.toml"); }
