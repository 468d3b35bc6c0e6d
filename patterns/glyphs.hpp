#pragma once
// Text as coverage masks, for procedural test fields (the thesis's "SIG08" letters, digits
// projected by Design III) and for labels. Drawn with Cairo in DejaVu Sans Bold
// (fonts-dejavu-core), antialiased, on a black background; deterministic for a given
// Cairo and font version.
//
// Example: Image mask = text_mask("S", 64, 48);  // one channel, 0 background, 1 ink

#include <string>

#include "core/image.hpp"

namespace rfd::patterns {

/// A one-channel width x height mask of `text`, centred and scaled so that its ink box
/// fills `fill` of the smaller side. Coverage in [0, 1]. Throws InputError when width or
/// height is not positive or `text` is empty.
Image text_mask(const std::string& text, int width, int height, double fill = 0.8);

}  // namespace rfd::patterns
