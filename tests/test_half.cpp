// Float to half conversion (core/half.hpp): the F16C path and Imath's portable path give the
// same bits everywhere, and both round as IEEE 754 says on the cases that decide it.

#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <vector>

#include <gtest/gtest.h>

#include "core/half.hpp"

namespace rfd {
namespace {

std::uint16_t half_bits(float v, HalfConversion conversion) {
    std::uint16_t out = 0;
    floats_to_half(std::span<const float>(&v, 1), std::span<std::uint16_t>(&out, 1), conversion);
    return out;
}

TEST(Half, RoundsToNearestEvenAndOverflowsToInfinity) {
    for (HalfConversion conversion : {HalfConversion::Fastest, HalfConversion::Portable}) {
        EXPECT_EQ(half_bits(1.0f, conversion), 0x3c00);
        EXPECT_EQ(half_bits(-2.0f, conversion), 0xc000);
        EXPECT_EQ(half_bits(65504.0f, conversion), 0x7bff);       // the largest half
        EXPECT_EQ(half_bits(65520.0f, conversion), 0x7c00);       // halfway to 2^16: ties to even, inf
        EXPECT_EQ(half_bits(65519.0f, conversion), 0x7bff);
        EXPECT_EQ(half_bits(std::ldexp(1.0f, -24), conversion), 0x0001);  // the smallest subnormal
        EXPECT_EQ(half_bits(std::ldexp(1.0f, -25), conversion), 0x0000);  // half of it: ties to even
        EXPECT_EQ(half_bits(std::ldexp(3.0f, -25), conversion), 0x0002);
        EXPECT_EQ(half_bits(1.0f + std::ldexp(1.0f, -11), conversion), 0x3c00);       // tie, even below
        EXPECT_EQ(half_bits(1.0f + std::ldexp(3.0f, -11), conversion), 0x3c02);       // tie, even above
        EXPECT_EQ(half_bits(std::numeric_limits<float>::infinity(), conversion), 0x7c00);
    }
}

TEST(Half, FastAndPortablePathsAgreeOnEveryFloatClass) {
    // A stride through all 2^32 bit patterns (odd, so every exponent and mantissa low bits
    // are hit), NaNs excluded: their payloads may differ.
    std::vector<float> values;
    for (std::uint64_t bits = 0; bits < (1ull << 32); bits += 1021) {
        float v;
        const std::uint32_t b = static_cast<std::uint32_t>(bits);
        std::memcpy(&v, &b, sizeof v);
        if (!std::isnan(v)) values.push_back(v);
    }
    // Lengths that are not multiples of the 8-wide vector path.
    values.resize(values.size() - values.size() % 8 + 5);
    std::vector<std::uint16_t> fast(values.size()), portable(values.size());
    floats_to_half(values, fast, HalfConversion::Fastest);
    floats_to_half(values, portable, HalfConversion::Portable);
    std::size_t differ = 0;
    for (std::size_t i = 0; i < values.size(); ++i) differ += fast[i] != portable[i];
    EXPECT_EQ(differ, 0u);
    EXPECT_GT(values.size(), 4000000u);
}

}  // namespace
}  // namespace rfd
