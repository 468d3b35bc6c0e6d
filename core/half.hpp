#pragma once
// Float to IEEE 754 half-precision conversion for large buffers (print patterns are
// written as half-float EXR: ~1.2 billion samples per A4 sheet).
//
// Rounding is to nearest, ties to even, overflow to infinity: Imath::half's conversion, so
// a buffer converted here reads back exactly as one converted by Imath or OpenImageIO. On
// CPUs with the F16C instructions eight values convert per instruction; elsewhere Imath's
// portable conversion runs one value at a time. NaN payloads may differ between the two
// (callers here never write NaN).
//
// Example: std::vector<std::uint16_t> bits(values.size()); floats_to_half(values, bits);

#include <cstdint>
#include <span>

namespace rfd {

enum class HalfConversion { Fastest, Portable };

/// out[i] = the half-precision bits of in[i]. Precondition: in.size() == out.size().
void floats_to_half(std::span<const float> in, std::span<std::uint16_t> out,
                    HalfConversion conversion = HalfConversion::Fastest);

}  // namespace rfd
