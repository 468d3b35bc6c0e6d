// Image-based priors (thesis 6.4.2): the patch basis's algebra, and regularisation that
// must pull corrupted pixels back to a texture the sources show up to an intensity scale,
// never touch pixels outside the uncertain mask, and do nothing when nothing is uncertain.

#include <cmath>
#include <cstdint>
#include <vector>

#include <gtest/gtest.h>

#include "core/error.hpp"
#include "relight/image_priors.hpp"

namespace rfd::relight {
namespace {

constexpr int kPriorSide = 40;

// A colour texture with edges in both directions and a slow gradient: every window of it is
// distinctive enough to be found again.
Image texture(int shift_x = 0) {
    Image out(kPriorSide, kPriorSide, 3);
    for (int y = 0; y < kPriorSide; ++y)
        for (int x = 0; x < kPriorSide; ++x) {
            const int u = x + shift_x;
            const float checker = ((u / 5 + y / 7) % 2 == 0) ? 1.0f : 0.35f;
            const float ramp = 0.5f + 0.5f * static_cast<float>(u + y) / (2.0f * kPriorSide);
            for (int c = 0; c < 3; ++c) out.at(x, y, c) = checker * ramp * (0.6f + 0.2f * static_cast<float>(c));
        }
    return out;
}

Image scaled(const Image& image, float factor) {
    Image out = image;
    for (float& v : out.samples()) v *= factor;
    return out;
}

// Deterministic +-amplitude relative noise on the pixels of `mask`.
Image corrupted(const Image& image, const std::vector<std::uint8_t>& mask, float amplitude) {
    Image out = image;
    unsigned state = 12345u;
    for (int c = 0; c < out.channels(); ++c)
        for (std::size_t p = 0; p < out.pixel_count(); ++p) {
            state = state * 1664525u + 1013904223u;
            if (!mask[p]) continue;
            const float r = static_cast<float>(state >> 8) / static_cast<float>(1u << 24) * 2.0f - 1.0f;
            out.plane(c)[p] *= 1.0f + amplitude * r;
        }
    return out;
}

std::vector<std::uint8_t> square(int x0, int y0, int size) {
    std::vector<std::uint8_t> mask(static_cast<std::size_t>(kPriorSide * kPriorSide), 0);
    for (int y = y0; y < y0 + size; ++y)
        for (int x = x0; x < x0 + size; ++x) mask[static_cast<std::size_t>(y * kPriorSide + x)] = 1;
    return mask;
}

double squared_error(const Image& a, const Image& b, const std::vector<std::uint8_t>& mask) {
    double sum = 0.0;
    for (int c = 0; c < a.channels(); ++c)
        for (std::size_t p = 0; p < a.pixel_count(); ++p)
            if (mask[p]) {
                const double d = static_cast<double>(a.plane(c)[p]) - b.plane(c)[p];
                sum += d * d;
            }
    return sum;
}

TEST(ImagePriors, BasisIsOrthonormalAndIgnoresIntensity) {
    const Image source = texture();
    // The usual window and the largest one, whose unit window fills project's stack buffer.
    for (const int radius : {2, PatchBasis::kMaxRadius}) {
        SCOPED_TRACE(radius);
        const int size = (2 * radius + 1) * (2 * radius + 1);
        const auto n = static_cast<std::size_t>(size);
        const PatchBasis basis = PatchBasis::fit({&source}, radius, 6);
        EXPECT_EQ(basis.radius(), radius);
        EXPECT_EQ(basis.components(), 6);
        // Project the unit vectors: the coordinates are the axes' entries, so the Gram matrix
        // of the projections (components x window size) times its transpose is the identity.
        Eigen::MatrixXf axes(6, size);
        for (int i = 0; i < size; ++i) {
            std::vector<float> unit(n, 0.0f), out(6);
            unit[static_cast<std::size_t>(i)] = 1.0f;
            basis.project(unit.data(), out.data());
            for (int k = 0; k < 6; ++k) axes(k, i) = out[static_cast<std::size_t>(k)];
        }
        EXPECT_TRUE((axes * axes.transpose()).isIdentity(1e-5f)) << axes * axes.transpose();
        std::vector<float> window(n), bright(n), a(6), b(6);
        for (std::size_t i = 0; i < n; ++i) {
            window[i] = 0.1f + 0.03f * static_cast<float>(i % 7);
            bright[i] = 40.0f * window[i];
        }
        basis.project(window.data(), a.data());
        basis.project(bright.data(), b.data());
        for (int k = 0; k < 6; ++k) EXPECT_NEAR(a[static_cast<std::size_t>(k)], b[static_cast<std::size_t>(k)], 1e-5f);
        const std::vector<float> black(n, 0.0f);
        basis.project(black.data(), a.data());
        for (float v : a) EXPECT_EQ(v, 0.0f);
    }
}

TEST(ImagePriors, NoisyPixelsReturnToTheScaledTexture) {
    // The truth is a source at 60 % of its intensity, shifted by two pixels: found again
    // only up to a scale and at another position. Noise of +-30 % on a 12 x 12 square.
    const Image truth = scaled(texture(2), 0.6f);
    const Image source = texture();
    const auto mask = square(14, 12, 12);
    const Image estimate = corrupted(truth, mask, 0.3f);
    const PatchBasis basis = PatchBasis::fit({&source}, 2, 8);
    const Image result = regularise_with_priors(estimate, mask, {&source}, basis, PriorOptions{});
    const double before = squared_error(estimate, truth, mask), after = squared_error(result, truth, mask);
    EXPECT_LT(after, 0.1 * before) << "before " << before << ", after " << after;
    // Outside the mask nothing moves.
    for (int c = 0; c < 3; ++c)
        for (std::size_t p = 0; p < result.pixel_count(); ++p)
            if (!mask[p]) {
                EXPECT_EQ(result.plane(c)[p], estimate.plane(c)[p]);
            }
    // More iterations do not undo the first one.
    PriorOptions one;
    one.iterations = 1;
    EXPECT_LT(after, 1.05 * squared_error(regularise_with_priors(estimate, mask, {&source}, basis, one), truth, mask));
}

TEST(ImagePriors, TheMatchingSourceWinsOverAnUnrelatedOne) {
    // Two sources: a flat grey image and the texture. A smeared (mean-filled) square must
    // take its texture back from the second.
    const Image truth = scaled(texture(), 0.8f);
    Image flat(kPriorSide, kPriorSide, 3);
    for (float& v : flat.samples()) v = 0.4f;
    const Image source = texture();
    const auto mask = square(10, 10, 8);
    Image estimate = truth;
    for (int c = 0; c < 3; ++c) {
        double mean = 0.0;
        for (std::size_t p = 0; p < mask.size(); ++p) mean += mask[p] ? truth.plane(c)[p] : 0.0f;
        mean /= 64.0;
        for (std::size_t p = 0; p < mask.size(); ++p)
            if (mask[p]) estimate.plane(c)[p] = static_cast<float>(mean);
    }
    const PatchBasis basis = PatchBasis::fit({&flat, &source}, 2, 8);
    const Image result = regularise_with_priors(estimate, mask, {&flat, &source}, basis, PriorOptions{});
    EXPECT_LT(squared_error(result, truth, mask), 0.5 * squared_error(estimate, truth, mask));
}

TEST(ImagePriors, NothingUncertainOrNoIterationsChangesNothing) {
    const Image source = texture(), estimate = scaled(texture(3), 0.5f);
    const PatchBasis basis = PatchBasis::fit({&source}, 2, 8);
    const std::vector<std::uint8_t> none(estimate.pixel_count(), 0);
    EXPECT_EQ(regularise_with_priors(estimate, none, {&source}, basis, PriorOptions{}), estimate);
    PriorOptions off;
    off.iterations = 0;
    EXPECT_EQ(regularise_with_priors(estimate, square(5, 5, 5), {&source}, basis, off), estimate);
    // Deterministic.
    const auto mask = square(5, 5, 9);
    EXPECT_EQ(regularise_with_priors(estimate, mask, {&source}, basis, PriorOptions{}),
              regularise_with_priors(estimate, mask, {&source}, basis, PriorOptions{}));
}

TEST(ImagePriors, BadOptionsAreAnInputError) {
    const Image source = texture();
    const PatchBasis basis = PatchBasis::fit({&source}, 2, 8);
    const auto mask = square(5, 5, 5);
    PriorOptions bad;
    bad.proximity = 0.0;
    EXPECT_THROW(regularise_with_priors(source, mask, {&source}, basis, bad), InputError);
    bad = PriorOptions{};
    bad.iterations = -1;
    EXPECT_THROW(check_prior_options(bad), InputError);
}

// Sources and masks come from the upsampler itself: a mismatch is a bug in rfd, not input.
TEST(ImagePriorsDeathTest, MismatchedSourcesAreABug) {
    const Image source = texture();
    const PatchBasis basis = PatchBasis::fit({&source}, 2, 8);
    const auto mask = square(5, 5, 5);
    const Image other(kPriorSide + 1, kPriorSide, 3);
    EXPECT_DEATH(regularise_with_priors(source, mask, {}, basis, PriorOptions{}), "check failed");
    EXPECT_DEATH(regularise_with_priors(source, mask, {&other}, basis, PriorOptions{}), "check failed");
    EXPECT_DEATH(regularise_with_priors(source, {1, 0}, {&source}, basis, PriorOptions{}), "check failed");
    EXPECT_DEATH(PatchBasis::fit({}, 2, 6), "check failed");
    EXPECT_DEATH(PatchBasis::fit({&source}, 0, 1), "check failed");
    EXPECT_DEATH(PatchBasis::fit({&source}, PatchBasis::kMaxRadius + 1, 1), "check failed");
    EXPECT_DEATH(PatchBasis::fit({&source}, 2, 26), "check failed");
}

}  // namespace
}  // namespace rfd::relight
