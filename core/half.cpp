#include "core/half.hpp"

#include <cstddef>

#include <Imath/half.h>

// Clang 14's __builtin_cpu_supports knows no "f16c": the clang build (the fuzz preset)
// takes the portable path, which rounds the same way.
#if (defined(__x86_64__) || defined(__i386__)) && !defined(__clang__)
#include <immintrin.h>
#define RFD_HAVE_F16C_PATH 1
#endif

#include "core/error.hpp"

namespace rfd {
namespace {

void convert_portable(const float* in, std::uint16_t* out, std::size_t n) {
    for (std::size_t i = 0; i < n; ++i) out[i] = imath_float_to_half(in[i]);
}

#ifdef RFD_HAVE_F16C_PATH
// Compiled for F16C regardless of the build's target; only called when the CPU has it.
__attribute__((target("avx,f16c"))) void convert_f16c(const float* in, std::uint16_t* out, std::size_t n) {
    std::size_t i = 0;
    for (; i + 8 <= n; i += 8) {
        const __m128i bits = _mm256_cvtps_ph(_mm256_loadu_ps(in + i), _MM_FROUND_TO_NEAREST_INT | _MM_FROUND_NO_EXC);
        _mm_storeu_si128(reinterpret_cast<__m128i*>(out + i), bits);
    }
    // Explicitly: GCC drops its own vzeroupper before the tail call below, and the dirty
    // upper halves then slowed the caller's SSE code (the pattern renderer) 2.7 times.
    _mm256_zeroupper();
    convert_portable(in + i, out + i, n - i);
}

bool cpu_has_f16c() {
    static const bool has = __builtin_cpu_supports("f16c") && __builtin_cpu_supports("avx");
    return has;
}
#endif

}  // namespace

void floats_to_half(std::span<const float> in, std::span<std::uint16_t> out, HalfConversion conversion) {
    RFD_CHECK(in.size() == out.size());
#ifdef RFD_HAVE_F16C_PATH
    if (conversion == HalfConversion::Fastest && cpu_has_f16c()) {
        convert_f16c(in.data(), out.data(), in.size());
        return;
    }
#else
    (void)conversion;
#endif
    convert_portable(in.data(), out.data(), in.size());
}

}  // namespace rfd
