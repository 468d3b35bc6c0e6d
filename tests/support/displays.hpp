#pragma once
// Designs and picture statistics shared by the display tests (test_compare, test_optimize).

#include <cmath>
#include <filesystem>
#include <numeric>

#include "core/image.hpp"
#include "optics/design.hpp"
#include "tests/support/bundled.hpp"

namespace rfd::testing {

inline optics::Design design2() { return optics::load_design(kBundledDesigns / "design2.toml"); }

/// Design I with fewer lenslets (same lenslets, pitch, planes and printer): the preset's
/// 63 x 73 lenslets make a 150 mm pattern, too large for a unit test.
inline optics::Design small_design1(int count_x, int count_y) {
    return optics::with_lenslet_count(optics::load_design(kBundledDesigns / "design1.toml"), count_x, count_y);
}

/// Pearson's correlation of two pictures' samples (same shape).
inline double pearson(const Image& a, const Image& b) {
    const auto x = a.samples(), y = b.samples();
    const double n = static_cast<double>(x.size());
    const double mx = std::accumulate(x.begin(), x.end(), 0.0) / n, my = std::accumulate(y.begin(), y.end(), 0.0) / n;
    double sxy = 0, sxx = 0, syy = 0;
    for (std::size_t k = 0; k < x.size(); ++k) {
        sxy += (x[k] - mx) * (y[k] - my);
        sxx += (x[k] - mx) * (x[k] - mx);
        syy += (y[k] - my) * (y[k] - my);
    }
    return sxy / std::sqrt(sxx * syy);
}

}  // namespace rfd::testing
