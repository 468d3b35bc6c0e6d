// Feature-guided upsampling (thesis chapter 6): each stage against what it must do on
// synthetic data with closed-form answers (a percentile, a dilated highlight, shadows found
// by region growing, a disk moved half-way by level-set blending, a highlight moved half-way
// by the flow, a small one matched and moved rigidly), then whole fields whose new images are checked against the closed form at
// the new directions: a floating occluder's moving shadow and a dome's moving highlight,
// where upsampling must beat linear blending, and the failure cases of 6.5.1 (no texture,
// shadows that do not overlap, dim caustics), where it must stay no worse than blending.

#include <algorithm>
#include <cmath>
#include <functional>
#include <numeric>
#include <vector>

#include <gtest/gtest.h>

#include "core/error.hpp"
#include "core/sphere.hpp"
#include "core/units.hpp"
#include "relight/interpolation.hpp"
#include "relight/upsample.hpp"
#include "relight/upsample_features.hpp"
#include "relight/upsample_highlights.hpp"

namespace rfd::relight {
namespace {

constexpr int kSide = 48;

// An image whose every pixel is f(x, y), one channel.
Image image_of(int width, int height, const std::function<float(int, int)>& f) {
    Image out(width, height, 1);
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x) out.at(x, y, 0) = f(x, y);
    return out;
}

Image gaussian_blob(double cx, double cy, double sigma, float peak) {
    return image_of(kSide, kSide, [&](int x, int y) {
        const double r2 = (x - cx) * (x - cx) + (y - cy) * (y - cy);
        return static_cast<float>(peak * std::exp(-r2 / (2.0 * sigma * sigma)));
    });
}

// Centroid (x) and total of an image.
std::pair<double, double> centroid_x(const Image& image) {
    double sum = 0.0, sx = 0.0;
    for (int y = 0; y < image.height(); ++y)
        for (int x = 0; x < image.width(); ++x) {
            sum += image.at(x, y, 0);
            sx += x * static_cast<double>(image.at(x, y, 0));
        }
    return {sx / sum, sum};
}

ShadowMap disk_shadow(double cx, double cy, double radius) {
    ShadowMap map(static_cast<std::size_t>(kSide * kSide), 1);
    for (int y = 0; y < kSide; ++y)
        for (int x = 0; x < kSide; ++x)
            if (std::hypot(x - cx, y - cy) <= radius) map[static_cast<std::size_t>(y * kSide + x)] = 0;
    return map;
}

TEST(Upsample, PercentileImageIsTheRankedSamplePerPixel) {
    std::vector<Image> images;
    for (int i = 0; i < 10; ++i)
        images.push_back(image_of(3, 2, [i](int x, int y) { return static_cast<float>(((i * 7 + x * 3 + y) % 10)); }));
    const Image p = percentile_image(images, 0.85);  // rank floor(8.5) = 8: the second largest
    for (int y = 0; y < 2; ++y)
        for (int x = 0; x < 3; ++x) {
            std::vector<float> values;
            for (const Image& im : images) values.push_back(im.at(x, y, 0));
            std::sort(values.begin(), values.end());
            EXPECT_EQ(p.at(x, y, 0), values[8]);
        }
    EXPECT_EQ(percentile_image(images, 1.0).at(0, 0, 0), 9.0f);  // clamped to the largest
    EXPECT_THROW(percentile_image(images, 1.5), InputError);
    EXPECT_THROW(percentile_image({}, 0.5), InputError);
}

TEST(Upsample, HighlightMaskIsDilatedAndIgnoresBlackPixels) {
    Image level = image_of(kSide, kSide, [](int x, int) { return x < 24 ? 0.2f : 0.0f; });
    Image l = level;
    l.at(10, 10, 0) = 0.39f;  // below 2 P
    l.at(30, 30, 0) = 0.39f;  // P = 0 but above the floor: a feature lit by few directions
    l.at(40, 5, 0) = 1e-5f;   // P = 0 and below the floor: a black pixel's noise
    l.at(12, 30, 0) = 0.41f;  // a highlight
    const auto mask = highlight_mask(l, level, 2.0, 5, 1e-3f);
    const auto at = [&](int x, int y) { return mask[static_cast<std::size_t>(y * kSide + x)]; };
    EXPECT_EQ(at(12, 30), 1);
    EXPECT_EQ(at(30, 30), 1);
    EXPECT_EQ(at(10, 10), 0);
    EXPECT_EQ(at(40, 5), 0);
    // The 5x5 box around each highlight, nothing else.
    EXPECT_EQ(std::count(mask.begin(), mask.end(), std::uint8_t{1}), 2 * 25);
    EXPECT_EQ(at(14, 32), 1);
    EXPECT_EQ(at(15, 30), 0);
}

TEST(Upsample, RemovedHighlightLeavesTheSmoothBaseAndANonNegativeLayer) {
    const Image base = image_of(kSide, kSide, [](int x, int y) { return 0.1f + 0.004f * static_cast<float>(x + y); });
    Image r = base;
    const Image blob = gaussian_blob(20, 24, 1.5, 3.0f);
    for (std::size_t s = 0; s < r.samples().size(); ++s) r.samples()[s] += blob.samples()[s];
    std::vector<Image> flat(8, base);
    const Image p = percentile_image(flat, 230.0 / 256.0);
    const auto mask = highlight_mask(r, p, 2.0, 5, 1e-3f);
    const Image d = remove_highlights(r, mask);
    double worst = 0.0;
    for (std::size_t s = 0; s < d.samples().size(); ++s) {
        EXPECT_LE(d.samples()[s], r.samples()[s]);
        worst = std::max(worst, std::abs(static_cast<double>(d.samples()[s] - base.samples()[s])));
    }
    // The base under the highlight is a plane; inpainting from the ring recovers it closely
    // (the highlight peaks 30 times higher).
    EXPECT_LT(worst, 0.02);
}

TEST(Upsample, ShadowsFoundByRegionGrowingOverDirections) {
    // One pixel of a diffuse plane under 120 directions; directions with negative x are
    // blocked by an occluder that leaves 5 % of the light.
    const auto directions = fibonacci_hemisphere(120);
    const SphericalInterpolator interp(directions);
    std::vector<Image> l;
    for (const auto& d : directions)
        l.push_back(Image(1, 1, 1, static_cast<float>(d.z() * (d.x() < 0.0 ? 0.05 : 1.0))));
    const Image p = percentile_image(l, 230.0 / 256.0);
    const auto maps = shadow_maps(l, p, interp.one_rings(), 0.8);
    int seeds = 0;
    for (std::size_t i = 0; i < directions.size(); ++i) {
        seeds += l[i].at(0, 0, 0) >= p.at(0, 0, 0) ? 1 : 0;
        const double theta = std::acos(directions[i].z());
        if (directions[i].x() < 0.0) {
            EXPECT_EQ(maps[i][0], 0) << "blocked direction " << i;
        } else if (theta < degrees_to_radians(55.0)) {
            EXPECT_EQ(maps[i][0], 1) << "open direction " << i;
        }
    }
    EXPECT_LT(seeds, 15);  // growth, not the threshold, found most lit directions
    // f_lit near 0: growing stops at nothing but zero light, so the blocked side is lit too.
    const auto loose = shadow_maps(l, p, interp.one_rings(), 1e-3);
    for (const auto& m : loose) EXPECT_EQ(m[0], 1);
}

TEST(Upsample, LevelSetBlendingMovesAShadowHalfWay) {
    const ShadowMap a = disk_shadow(16, 24, 8), b = disk_shadow(28, 24, 8);
    const ShadowMap k = halfway_shadow_map(a, b, kSide, kSide);
    // The half-way disk, not the union or the intersection of the two.
    int wrong = 0;
    const ShadowMap expected = disk_shadow(22, 24, 8);
    for (std::size_t p = 0; p < k.size(); ++p) wrong += k[p] != expected[p] ? 1 : 0;
    const auto area = std::count(expected.begin(), expected.end(), std::uint8_t{0});
    EXPECT_LT(wrong, area / 10) << "of " << area;
    // Identical maps are a fixed point; a uniform map leaves the other's shape alone.
    EXPECT_EQ(halfway_shadow_map(a, a, kSide, kSide), a);
    const ShadowMap lit(a.size(), 1);
    const ShadowMap with_lit = halfway_shadow_map(a, lit, kSide, kSide);
    EXPECT_EQ(std::count(with_lit.begin(), with_lit.end(), std::uint8_t{0}), 0);
}

TEST(Upsample, ShadowsThatDoNotOverlapGiveAValidSmallerMap) {
    // 6.5.1: shadows too far apart to overlap cannot be morphed. The mean distance keeps
    // no more shadow than either input and never invents shadow away from both.
    const ShadowMap a = disk_shadow(8, 24, 5), b = disk_shadow(40, 24, 5);
    const ShadowMap k = halfway_shadow_map(a, b, kSide, kSide);
    const auto shadowed = std::count(k.begin(), k.end(), std::uint8_t{0});
    EXPECT_LE(shadowed, std::count(a.begin(), a.end(), std::uint8_t{0}));
    for (std::size_t p = 0; p < k.size(); ++p)
        if (k[p] == 0) {
            EXPECT_TRUE(a[p] == 0 || b[p] == 0) << "pixel " << p;
        }
}

TEST(Upsample, FlowMovesAHighlightHalfWay) {
    const Image a = gaussian_blob(18, 24, 2.0, 5.0f), b = gaussian_blob(26, 24, 2.0, 5.0f);
    const double no_blobs = 0.0;
    const Image k = halfway_highlights(a, b, no_blobs);
    const auto [cx, total] = centroid_x(k);
    EXPECT_NEAR(cx, 22.0, 0.5);
    EXPECT_NEAR(total, centroid_x(a).second, 0.1 * centroid_x(a).second);
    // One blob at most of the original height where blending has two at half height.
    const float peak = *std::max_element(k.samples().begin(), k.samples().end());
    EXPECT_GT(peak, 0.7f * 5.0f);
    EXPECT_TRUE(halfway_highlights(Image(), Image(), no_blobs).empty());
    // A highlight that vanishes fades to half: the blend, not a crash.
    const Image half = halfway_highlights(a, Image(), no_blobs);
    EXPECT_NEAR(centroid_x(half).second, 0.5 * centroid_x(a).second, 0.05 * centroid_x(a).second);
}

Image dots(const std::vector<std::pair<int, float>>& at_x) {
    Image out(kSide, kSide, 1);
    for (const auto& [x, value] : at_x) out.at(x, 20, 0) = value;
    return out;
}

// Highlights along row 20 over the spans [x0, x1] of `value`.
Image bars(const std::vector<std::pair<int, int>>& spans, float value) {
    Image out(kSide, kSide, 1);
    for (const auto& [x0, x1] : spans)
        for (int x = x0; x <= x1; ++x) out.at(x, 20, 0) = value;
    return out;
}

TEST(Upsample, MatchedHighlightsMoveRigidlyHalfWay) {
    // One-pixel highlights 5 pixels apart: each carries half its energy 2.5 pixels, split
    // bilinearly between x = 12 and 13. The flow sees almost nothing of such a dot.
    const Image k = halfway_highlights(dots({{10, 4.0f}}), dots({{15, 4.0f}}), 12.0);
    EXPECT_FLOAT_EQ(k.at(12, 20, 0), 2.0f);
    EXPECT_FLOAT_EQ(k.at(13, 20, 0), 2.0f);
    EXPECT_NEAR(centroid_x(k).second, 4.0, 1e-5);
    // Two pairs: each dot goes to its own partner, not across.
    const Image two = halfway_highlights(dots({{6, 1.0f}, {30, 3.0f}}), dots({{10, 1.0f}, {34, 3.0f}}), 12.0);
    EXPECT_FLOAT_EQ(two.at(8, 20, 0), 1.0f);
    EXPECT_FLOAT_EQ(two.at(32, 20, 0), 3.0f);
    EXPECT_NEAR(centroid_x(two).second, 4.0, 1e-5);
    // Beyond the reach, or of too different energy (factor > 4), they are not one highlight
    // moving; with nothing for the flow to lock onto either, each fades to about half.
    for (const auto& [far_x, energy] : {std::pair{40, 4.0f}, std::pair{15, 40.0f}}) {
        const Image apart = halfway_highlights(dots({{10, 4.0f}}), dots({{far_x, energy}}), 12.0);
        EXPECT_NEAR(centroid_x(apart).second, 0.5 * (4.0 + energy), 0.05 * (4.0 + energy));
        EXPECT_LT(apart.at(12, 20, 0) + apart.at(13, 20, 0), 0.5f);
    }
}

TEST(Upsample, OneSidedHighlightsStayInPlaceWithTheirWeight) {
    // Nothing of the other layer within reach: the dot stays where it is, scaled.
    for (const float weight : {0.0f, 0.25f, 1.0f}) {
        const Image k = halfway_highlights(dots({{10, 4.0f}}), dots({{40, 2.0f}}), 12.0, weight);
        EXPECT_FLOAT_EQ(k.at(10, 20, 0), 4.0f * weight);
        EXPECT_FLOAT_EQ(k.at(40, 20, 0), 2.0f * weight);
        EXPECT_NEAR(centroid_x(k).second, 6.0 * weight, 1e-5);
        EXPECT_FLOAT_EQ(halfway_highlights(dots({{10, 4.0f}}), Image(), 12.0, weight).at(10, 20, 0), 4.0f * weight);
    }
}

TEST(Upsample, HighlightThatSplitsIsNotMovedRigidly) {
    // A streak (x = 9..19) that splits into two short ones (x = 5..7 and 21..23): its
    // nearest piece is within reach and within a factor 4 in energy, but moved rigidly onto
    // it, the streak does not land on it. The flow spreads it symmetrically; a rigid move
    // would pull it to one side (centroid 12 instead of 14).
    const Image k = halfway_highlights(bars({{9, 19}}, 1.0f), bars({{5, 7}, {21, 23}}, 1.0f), 12.0, 0.5);
    const auto [cx, total] = centroid_x(k);
    EXPECT_NEAR(cx, 14.0, 0.75);
    EXPECT_GT(total, 0.5 * 11.0);
}

// Light discs in the plane: of the points of a fine grid over the square around the disc
// of `radius` at the origin for which `counted` holds, the share for which `kept` holds too.
using DiscTest = std::function<bool(double x, double y)>;
double disc_grid_share(double radius, const DiscTest& counted, const DiscTest& kept) {
    constexpr int kSteps = 800;
    std::size_t all = 0, share = 0;
    for (int i = 0; i < kSteps; ++i)
        for (int j = 0; j < kSteps; ++j) {
            const double x = radius * (2.0 * (i + 0.5) / kSteps - 1.0), y = radius * (2.0 * (j + 0.5) / kSteps - 1.0);
            if (!counted(x, y)) continue;
            ++all;
            if (kept(x, y)) ++share;
        }
    return static_cast<double>(share) / static_cast<double>(all);
}

TEST(Upsample, OneSidedWeightIsTheOverlapOfTwoLightDiscs) {
    // Against counting the points of a fine grid over one disc that the other disc covers.
    const double radius = degrees_to_radians(2.0);
    const auto inside = [&](double x, double y, double cx) { return (x - cx) * (x - cx) + y * y < radius * radius; };
    for (const double ratio : {0.1, 0.5, 1.0, 1.5, 1.9}) {
        const double distance = ratio * radius;
        const double share = disc_grid_share(
            radius, [&](double x, double y) { return inside(x, y, 0.0); },
            [&](double x, double y) { return inside(x, y, distance); });
        EXPECT_NEAR(one_sided_highlight_weight(distance, radius), share, 2e-3) << "distance " << ratio << " radii";
    }
    EXPECT_DOUBLE_EQ(one_sided_highlight_weight(0.0, radius), 1.0);
    EXPECT_DOUBLE_EQ(one_sided_highlight_weight(2.0 * radius, radius), 0.0);
    EXPECT_DOUBLE_EQ(one_sided_highlight_weight(0.01, 0.0), 0.0);
}

TEST(Upsample, MidpointWeightIsWhatTheMidpointSeesOfOneEndsOwnLight) {
    // Against a fine grid over the first end's disc: of its points outside the second end's
    // disc, the share inside the midpoint's.
    const double radius = degrees_to_radians(2.0);
    const auto inside = [&](double x, double y, double cx) { return (x - cx) * (x - cx) + y * y < radius * radius; };
    for (const double ratio : {0.2, 0.6, 1.0, 1.5, 1.9, 2.5}) {
        const double edge = ratio * radius;
        const double share = disc_grid_share(
            radius, [&](double x, double y) { return inside(x, y, 0.0) && !inside(x, y, edge); },
            [&](double x, double y) { return inside(x, y, 0.5 * edge); });
        EXPECT_NEAR(midpoint_highlight_weight(edge, radius), share, 3e-3) << "edge " << ratio << " radii";
    }
    // Apart, the lights share nothing and it is the one-sided weight at half the edge; as
    // the edge shrinks it tends to blending's half; point lights share nothing.
    EXPECT_DOUBLE_EQ(midpoint_highlight_weight(3.0 * radius, radius), one_sided_highlight_weight(1.5 * radius, radius));
    EXPECT_NEAR(midpoint_highlight_weight(1e-4 * radius, radius), 0.5, 1e-3);
    EXPECT_DOUBLE_EQ(midpoint_highlight_weight(0.0, radius), 0.5);
    EXPECT_DOUBLE_EQ(midpoint_highlight_weight(0.01, 0.0), 0.0);
}

TEST(Upsample, HighlightLitInPlaceUnderOverlappingLightsStaysInPlace) {
    // A glint along a thin mirror (row 20, x = 10..30) whose middle the next light, its
    // disc overlapping the first's, no longer reaches (only x = 10..15 and 25..30 lit).
    // Nothing moved: no flow carries the one onto the other better than they already lie.
    // The pixels both lights reach stay lit, the rest keep the one-sided weight.
    const Image whole = bars({{10, 30}}, 4.0f), ends = bars({{10, 15}, {25, 30}}, 4.0f);
    const float weight = 0.45f;
    const Image k = halfway_highlights(whole, ends, 12.0, weight, true);
    for (int y = 0; y < kSide; ++y)
        for (int x = 0; x < kSide; ++x) {
            const bool on = y == 20 && x >= 10 && x <= 30, both = on && (x <= 15 || x >= 25);
            EXPECT_FLOAT_EQ(k.at(x, y, 0), both ? 4.0f : on ? 4.0f * weight : 0.0f) << x << ", " << y;
        }
    // With lights apart the same layers go to the flow, which warps the glint past the
    // mirror's ends (measured: 0.9 at x = 9 and 31), where neither light lit anything.
    const Image flowed = halfway_highlights(whole, ends, 12.0, weight, false);
    EXPECT_GT(flowed.at(9, 20, 0) + flowed.at(31, 20, 0), 1.0f);
    // A highlight that does move is still carried by the flow when the lights overlap.
    const Image a = gaussian_blob(18, 24, 2.0, 5.0f), b = gaussian_blob(26, 24, 2.0, 5.0f);
    EXPECT_NEAR(centroid_x(halfway_highlights(a, b, 0.0, 0.5, true)).first, 22.0, 0.5);
}

// A von Mises-Fisher lobe of sharpness 40 (about a GGX roughness of 0.12 in light space).
double vmf(const Eigen::Vector3d& axis, const Eigen::Vector3d& light) {
    return 3.0 * std::exp(40.0 * (axis.dot(light) - 1.0));
}

std::vector<Eigen::Vector3d> within(const Eigen::Vector3d& axis, double degrees) {
    std::vector<Eigen::Vector3d> near;
    for (const Eigen::Vector3d& d : fibonacci_hemisphere(400))
        if (std::acos(std::clamp(axis.dot(d), -1.0, 1.0)) < degrees * kPi / 180.0) near.push_back(d);
    return near;
}

TEST(Upsample, LobeFitRecoversAVonMisesFisherLobe) {
    const Eigen::Vector3d axis = Eigen::Vector3d(0.3, -0.2, 1.0).normalized();
    const std::vector<Eigen::Vector3d> directions = within(axis, 20.0);
    ASSERT_GE(directions.size(), 8u);
    std::vector<double> values;
    for (const auto& d : directions) values.push_back(vmf(axis, d));
    const auto lobe = fit_highlight_lobe(directions, values, 8, 30.0 * kPi / 180.0);
    ASSERT_TRUE(lobe.has_value());
    EXPECT_NEAR((lobe->sharpness_axis - 40.0 * axis).norm(), 0.0, 1e-6);
    // Between the samples, at the peak (above every sample) and on the flank.
    for (const Eigen::Vector3d& at : {axis, Eigen::Vector3d(0.35, -0.1, 1.0).normalized(),
                                      Eigen::Vector3d(0.1, -0.3, 1.0).normalized()})
        EXPECT_NEAR((*lobe)(at), vmf(axis, at), 1e-6 * vmf(axis, at));
    // One angular width off the axis a Gaussian keeps exp(-1/2) of its peak; the lobe nearly so.
    const Eigen::Vector3d tilt = axis.cross(Eigen::Vector3d::UnitX()).normalized();
    const Eigen::Vector3d off = Eigen::AngleAxisd(lobe->angular_width(), tilt) * axis;
    EXPECT_NEAR(vmf(axis, off) / vmf(axis, axis), std::exp(-0.5), 0.01);
}

TEST(Upsample, LobeFitRejectsFewSamplesTwoHighlightsAndFlatLight) {
    const Eigen::Vector3d axis = Eigen::Vector3d(0.3, -0.2, 1.0).normalized();
    const std::vector<Eigen::Vector3d> directions = within(axis, 20.0);
    std::vector<double> values;
    for (const auto& d : directions) values.push_back(vmf(axis, d));
    const double spread = 30.0 * kPi / 180.0;
    EXPECT_FALSE(fit_highlight_lobe(directions, values, directions.size() + 1, spread).has_value());
    // Two highlights 60 degrees apart at one pixel are no single lobe.
    const Eigen::Vector3d a = Eigen::Vector3d(std::sin(0.52), 0.0, std::cos(0.52));
    const Eigen::Vector3d b = Eigen::Vector3d(-std::sin(0.52), 0.0, std::cos(0.52));
    std::vector<Eigen::Vector3d> both = within(a, 15.0);
    for (const auto& d : within(b, 15.0)) both.push_back(d);
    std::vector<double> two;
    for (const auto& d : both) two.push_back(vmf(a, d) + vmf(b, d));
    EXPECT_FALSE(fit_highlight_lobe(both, two, 8, spread).has_value());
    // Light that hardly changes with direction is not a highlight lobe.
    EXPECT_FALSE(fit_highlight_lobe(directions, std::vector<double>(directions.size(), 0.5), 8, spread).has_value());
    EXPECT_THROW(fit_highlight_lobe(directions, {1.0}, 8, spread), InputError);
}

// Whole fields with closed-form images: pixel (x, y) sees the point (x - 23.5, 23.5 - y, 0)
// of a plane (field frame: y up), viewed from straight above.
using Shade = std::function<float(int, int, const Eigen::Vector3d&)>;

ReflectanceField render(const std::vector<Eigen::Vector3d>& directions, const Shade& shade) {
    ReflectanceField field;
    for (const auto& d : directions) {
        field.directions.push_back(d);
        field.images.push_back(image_of(kSide, kSide, [&](int x, int y) { return shade(x, y, d); }));
    }
    return field;
}

// A checkered plane under a sphere floating above it (the sphere itself not drawn).
float occluder_scene(int x, int y, const Eigen::Vector3d& l) {
    const Eigen::Vector3d p(x - 23.5, 23.5 - y, 0.0);
    const Eigen::Vector3d to_centre = Eigen::Vector3d(0.0, 0.0, 10.0) - p;
    const double along = to_centre.dot(l);
    const bool shadowed = along > 0.0 && to_centre.squaredNorm() - along * along < 6.0 * 6.0;
    const float albedo = ((x / 6 + y / 6) % 2 == 0) ? 0.8f : 0.3f;
    return shadowed ? 0.02f * albedo : albedo * static_cast<float>(std::max(0.0, l.z()));
}

// A glossy dome of radius 14 in the middle of a plain plane, with a Blinn-Phong highlight
// of the given peak and exponent.
float glossy_dome(int x, int y, const Eigen::Vector3d& l, double peak, double exponent) {
    const double dx = x - 23.5, dy = 23.5 - y, r = 14.0;
    // Seen orthographically, a glossy plane would flash all at once; only the dome is glossy.
    if (dx * dx + dy * dy >= r * r) return static_cast<float>(0.4 * std::max(0.0, l.z()));
    const Eigen::Vector3d n = Eigen::Vector3d(dx, dy, std::sqrt(r * r - dx * dx - dy * dy)) / r;
    const Eigen::Vector3d h = (l + Eigen::Vector3d::UnitZ()).normalized();
    const double diffuse = 0.4 * std::max(0.0, n.dot(l));
    const double specular = n.dot(l) > 0.0 ? peak * std::pow(std::max(0.0, n.dot(h)), exponent) : 0.0;
    return static_cast<float>(diffuse + specular);
}

// A sharp moving highlight.
float dome_scene(int x, int y, const Eigen::Vector3d& l) { return glossy_dome(x, y, l, 6.0, 400.0); }

struct Errors {
    double upsampled = 0.0;  // squared error of the new images
    double blended = 0.0;    // squared error of linear blending from the inputs there
};

// Upsamples `input`, a field of `shade`, and scores the new images against the closed form
// at their directions.
// The model itself, without the guard that blends where it loses (tested on its own below).
UpsampleOptions unguarded() {
    UpsampleOptions options;
    options.guard_tile = 0;
    return options;
}

Errors score(const ReflectanceField& input, const Shade& shade, int levels, UpsampleOptions options = unguarded()) {
    const std::size_t count = input.size();
    const UpsampledField up = upsample_field(input, levels, options);
    EXPECT_EQ(up.field.size(), count + up.statistics.synthesized);
    if (!input.kernel_radii.empty()) {
        EXPECT_EQ(up.field.kernel_radii.size(), up.field.size());
    }
    EXPECT_GT(up.statistics.synthesized, 2 * count);
    const SphericalInterpolator interp(input.directions);
    Errors e;
    for (std::size_t k = count; k < up.field.size(); ++k) {
        const Eigen::Vector3d d = up.field.directions[k];
        const InterpolationWeights w = interp.weights(d);
        for (int y = 0; y < kSide; ++y)
            for (int x = 0; x < kSide; ++x) {
                const double truth = shade(x, y, d);
                const double synthesized = up.field.images[k].at(x, y, 0);
                EXPECT_TRUE(std::isfinite(synthesized));
                double blend = 0.0;
                for (std::size_t j = 0; j < w.count; ++j) blend += w.weight[j] * input.images[w.index[j]].at(x, y, 0);
                e.upsampled += (synthesized - truth) * (synthesized - truth);
                e.blended += (blend - truth) * (blend - truth);
            }
    }
    return e;
}

// The same for `shade` seen from `count` near-uniform directions.
Errors score(const Shade& shade, std::size_t count, int levels, UpsampleOptions options = unguarded()) {
    return score(render(fibonacci_hemisphere(count), shade), shade, levels, options);
}

TEST(Upsample, FieldKeepsInputsAndAddsEdgeMidpoints) {
    const ReflectanceField input = render(fibonacci_hemisphere(40), occluder_scene);
    const UpsampledField up = upsample_field(input, 1, {});
    ASSERT_GE(up.field.size(), 40u);
    for (std::size_t i = 0; i < 40; ++i) {
        EXPECT_EQ(up.field.images[i], input.images[i]);
        EXPECT_EQ(up.field.directions[i], input.directions[i]);
    }
    // Every new direction halves a Delaunay edge of the inputs.
    EXPECT_LE(up.field.size() - 40, 3 * delaunay_triangles(input.directions).size());
    for (std::size_t k = 40; k < up.field.size(); ++k) {
        double best = -2.0;
        for (std::size_t i = 0; i < 40; ++i)
            for (std::size_t j = i + 1; j < 40; ++j)
                best = std::max(best, (input.directions[i] + input.directions[j]).normalized().dot(up.field.directions[k]));
        EXPECT_NEAR(best, 1.0, 1e-12);
    }
    // Deterministic, and level 0 is the identity.
    EXPECT_EQ(upsample_field(input, 1, {}).field.images, up.field.images);
    EXPECT_EQ(upsample_field(input, 0, {}).field.images, input.images);
}

TEST(Upsample, MovingShadowBeatsLinearBlending) {
    const Errors e = score(occluder_scene, 100, 1);
    EXPECT_LT(e.upsampled, 0.8 * e.blended) << "upsampled " << e.upsampled << ", blended " << e.blended;
    // The image priors (6.4.2) pull the checkers back into the extrapolated shadow edges
    // (measured: 677 with, 700 without).
    UpsampleOptions no_priors = unguarded();
    no_priors.priors.iterations = 0;
    const Errors without = score(occluder_scene, 100, 1, no_priors);
    EXPECT_LT(e.upsampled, 0.98 * without.upsampled) << "with priors " << e.upsampled << ", without " << without.upsampled;
}

TEST(Upsample, MovingHighlightBeatsLinearBlending) {
    const Errors e = score(dome_scene, 100, 1);
    EXPECT_LT(e.upsampled, 0.5 * e.blended) << "upsampled " << e.upsampled << ", blended " << e.blended;
}

// A broad glossy highlight on the dome: each pixel shows it over many input directions,
// and the highlight masks catch only the top of so broad a lobe.
float broad_dome_scene(int x, int y, const Eigen::Vector3d& l) { return glossy_dome(x, y, l, 2.0, 25.0); }

// (Suite UpsampleAccuracy: label `accuracy`, HACKING.md.)
TEST(UpsampleAccuracy, BroadHighlightFollowsItsSamples) {
    // The dome's lobe is about 23 degrees wide in light directions, against inputs 9 degrees
    // apart: linear blending is nearly right, and moving the masked top of the lobe is not.
    // Where the fitted lobe is at least as wide as an edge, the edge's mean is taken
    // (measured: lobes 163, without them 372, blending 137; read off the lobe instead: 267).
    // The default spread test turns most of the dome away; at 40 degrees: 93.
    UpsampleOptions no_lobes = unguarded(), wide_spread = unguarded();
    no_lobes.lobe_samples = 0;
    wide_spread.lobe_spread_deg = 40.0;
    const Errors with = score(broad_dome_scene, 256, 1), without = score(broad_dome_scene, 256, 1, no_lobes),
                 wide = score(broad_dome_scene, 256, 1, wide_spread);
    EXPECT_LT(with.upsampled, 0.8 * without.upsampled) << "lobes " << with.upsampled << ", without " << without.upsampled;
    // A regression guard, not a property: with the lobes, upsampling stays a little behind
    // blending here (measured 1.19x); reading off the lobe instead was 1.95x, and the guard
    // fails well before a return to that.
    const double regression_guard = 1.3;
    EXPECT_LT(with.upsampled, regression_guard * with.blended) << "lobes " << with.upsampled << ", blending " << with.blended;
    EXPECT_LT(wide.upsampled, 0.85 * wide.blended) << "spread 40: " << wide.upsampled << ", blending " << wide.blended;
}

TEST(Upsample, SmallReflectionMovesWhereTheFlowCannotFollow) {
    // A mirror-like reflection of a small light: a spot of a few pixels that travels 20
    // pixels per radian of light motion (5 between neighbouring inputs) over a dim diffuse
    // plane, the chrome ball of a light stage. Matching the spot as a blob must beat both
    // blending and the flow alone (measured: blending 55339, flow 4138, matching 1802).
    const Shade spot = [](int x, int y, const Eigen::Vector3d& l) {
        const double cx = 23.5 + 20.0 * l.x(), cy = 23.5 - 20.0 * l.y();
        const double r2 = (x - cx) * (x - cx) + (y - cy) * (y - cy);
        return static_cast<float>(0.2 * std::max(0.0, l.z()) + 8.0 * std::exp(-r2 / 2.0));
    };
    UpsampleOptions flow_only = unguarded();
    flow_only.blob_reach = 0.0;
    const Errors matched = score(spot, 100, 1), flowed = score(spot, 100, 1, flow_only);
    EXPECT_LT(matched.upsampled, 0.1 * matched.blended) << matched.upsampled << " vs blended " << matched.blended;
    EXPECT_LT(matched.upsampled, 0.6 * flowed.upsampled) << matched.upsampled << " vs flow " << flowed.upsampled;
}

TEST(Upsample, GlintsSeenFromOneDirectionDoNotSpreadOverTheEdge) {
    // Every third pixel in x and y mirrors the light toward the camera from its own
    // direction g (256 spread over the hemisphere) while a 2-degree light disc covers g:
    // glints far narrower in light directions than the spacing of 100 inputs (about 14
    // degrees), like those at the edges of the bottle scene's glass. An input sees a few; a
    // midpoint about 7 degrees away sees none of those, so blending's half-bright copies at
    // every neighbouring midpoint are pure error (measured: blending 2188, upsampled 1508;
    // what remains are the glints only the new directions see. Told the kernel is 12
    // degrees wide, the upsampler keeps 62 % of each glint at the midpoints: 2322).
    const double radius = degrees_to_radians(2.0);
    constexpr int kStep = 3;
    const auto mirrors = fibonacci_hemisphere(static_cast<std::size_t>((kSide / kStep) * (kSide / kStep)));
    const Shade glints = [&](int x, int y, const Eigen::Vector3d& l) {
        bool lit = false;
        if (x % kStep == 1 && y % kStep == 1) {
            const Eigen::Vector3d& g = mirrors[static_cast<std::size_t>((y / kStep) * (kSide / kStep) + x / kStep)];
            lit = std::acos(std::clamp(g.dot(l), -1.0, 1.0)) < radius;
        }
        return static_cast<float>(0.2 * std::max(0.0, l.z()) + (lit ? 6.0 : 0.0));
    };
    ReflectanceField input = render(fibonacci_hemisphere(100), glints);
    input.kernel_radii.assign(input.size(), radius);
    const Errors e = score(input, glints, 1);
    EXPECT_LT(e.upsampled, 0.75 * e.blended) << "upsampled " << e.upsampled << ", blended " << e.blended;
}

TEST(Upsample, GlintsOnThinMirrorsUnderWideLights) {
    // Every fourth row is a thin mirror whose reflection direction sweeps an 118-degree arc
    // along x (rows tilted from -40 to 40 degrees): under a light disc of 15 degrees, wider
    // than half the inputs' spacing (100 inputs, about 14 degrees), each lights a segment
    // that slides along its row and shrinks as the light leaves the arc. Neighbouring lights
    // overlap, so much of a segment stays lit at their midpoint; warping it half-way by the
    // flow smeared it (measured: 132342 against blending's 49767). What the flow does not
    // explain better than standing still now stays in place (75094). What remains are the
    // segments the matching moves rigidly though they only shrank: still 1.5 times
    // blending's error; a field captured this way is better blended.
    const double radius = degrees_to_radians(15.0);
    const Shade wires = [&](int x, int y, const Eigen::Vector3d& l) {
        const float diffuse = static_cast<float>(0.3 * std::max(0.0, l.z()));
        if (y % 4 != 1) return diffuse;
        const double tilt = degrees_to_radians(-40.0 + 80.0 * y / 47.0), along = degrees_to_radians(-60.0 + 2.5 * x);
        const Eigen::Vector3d mirrored(std::sin(along), std::cos(along) * std::sin(tilt), std::cos(along) * std::cos(tilt));
        return diffuse + (std::acos(std::clamp(mirrored.dot(l), -1.0, 1.0)) < radius ? 5.0f : 0.0f);
    };
    ReflectanceField input = render(fibonacci_hemisphere(100), wires);
    input.kernel_radii.assign(input.size(), radius);
    const Errors e = score(input, wires, 1);
    // A regression guard, not a property: upsampling stays behind blending here (measured
    // 1.51x); the guard fails well before a return to the smeared warping (2.66x).
    const double regression_guard = 1.8;
    EXPECT_LT(e.upsampled, regression_guard * e.blended) << "upsampled " << e.upsampled << ", blended " << e.blended;
}

TEST(Upsample, NoTextureIsLinearBlending) {
    // A plain diffuse plane: no highlight, no shadow, every new pixel a barycentric blend.
    const Shade plain = [](int, int, const Eigen::Vector3d& l) { return static_cast<float>(0.6 * std::max(0.0, l.z())); };
    const ReflectanceField input = render(fibonacci_hemisphere(60), plain);
    const UpsampledField up = upsample_field(input, 1, {});
    EXPECT_EQ(up.statistics.highlight_fraction, 0.0);
    EXPECT_EQ(up.statistics.fallback_fraction, 0.0);
    const Errors e = score(plain, 60, 1);
    EXPECT_LE(e.upsampled, 1.0001 * e.blended + 1e-9);
    // A black field: nothing to separate, nothing to extrapolate, black out.
    const Shade black = [](int, int, const Eigen::Vector3d&) { return 0.0f; };
    const UpsampledField dark = upsample_field(render(fibonacci_hemisphere(30), black), 1, {});
    for (const Image& image : dark.field.images)
        for (float v : image.samples()) EXPECT_EQ(v, 0.0f);
}

TEST(Upsample, DimCausticStaysNoWorseThanBlending) {
    // 6.5.1: a caustic too dim to be a highlight is not flowed; it must still blend.
    const Shade caustic = [](int x, int y, const Eigen::Vector3d& l) {
        const double cx = 23.5 + 30.0 * l.x(), cy = 23.5 - 30.0 * l.y();
        const double spot = 0.25 * std::exp(-((x - cx) * (x - cx) + (y - cy) * (y - cy)) / 4.0);
        return static_cast<float>((0.5 + spot) * std::max(0.0, l.z()));
    };
    const Errors e = score(caustic, 100, 1);
    EXPECT_LE(e.upsampled, 1.1 * e.blended);
}

TEST(UpsampleGuard, PixelWeightsBlendTheTilesBetweenTheirCentres) {
    UpsampleGuard guard;
    guard.tile = 4;
    guard.columns = 2;
    guard.rows = 1;
    guard.upsampled = {1.0, 0.0};
    const Image w = guard.pixel_weights(8, 4);
    for (int y = 0; y < 4; ++y) {
        EXPECT_FLOAT_EQ(w.at(1, y, 0), 1.0f);    // before tile 0's centre (pixel 1.5 < 2)
        EXPECT_FLOAT_EQ(w.at(3, y, 0), 0.625f);  // 3.5: 3/8 of the way to tile 1's centre at 6
        EXPECT_FLOAT_EQ(w.at(7, y, 0), 0.0f);
    }
}

TEST(UpsampleGuard, KeepsTheGainWhereTheModelWins) {
    // At the new directions, against the truth there: a moving highlight.
    const Errors moving = score(dome_scene, 100, 1, UpsampleOptions{});
    EXPECT_LT(moving.upsampled, 0.9 * moving.blended) << moving.upsampled << " vs blended " << moving.blended;
}

TEST(UpsampleAccuracy, GuardBlendsWhereTheModelLoses) {
    // The broad highlight of BroadHighlightFollowsItsSamples: the model stays behind blending
    // (1.19x); guarded, the field is the blend within a few per cent.
    const Errors raw = score(broad_dome_scene, 256, 1), guarded = score(broad_dome_scene, 256, 1, UpsampleOptions{});
    EXPECT_GT(raw.upsampled, raw.blended);
    EXPECT_LT(guarded.upsampled, 1.03 * guarded.blended) << guarded.upsampled << " vs blended " << guarded.blended;
}

TEST(Upsample, BadOptionsAreInputErrors) {
    const ReflectanceField input = render(fibonacci_hemisphere(12), occluder_scene);
    UpsampleOptions o;
    o.f_highlight = 1.0;
    EXPECT_THROW(upsample_field(input, 1, o), InputError);
    o = {};
    o.f_lit = 1.5;
    EXPECT_THROW(upsample_field(input, 1, o), InputError);
    o = {};
    o.highlight_dilation = 4;
    EXPECT_THROW(upsample_field(input, 1, o), InputError);
    o = {};
    o.blob_reach = -1.0;
    EXPECT_THROW(upsample_field(input, 1, o), InputError);
    o = {};
    o.lobe_samples = 3;
    EXPECT_THROW(upsample_field(input, 1, o), InputError);
    o = {};
    o.lobe_spread_deg = 0.0;
    EXPECT_THROW(upsample_field(input, 1, o), InputError);
    EXPECT_THROW(upsample_field(input, 5, {}), InputError);
    EXPECT_THROW(upsample_field(render(fibonacci_hemisphere(3), occluder_scene), 1, {}), InputError);
}

}  // namespace
}  // namespace rfd::relight
