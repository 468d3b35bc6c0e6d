// Calibration spheres seen by a pinhole camera and found by themselves
// (relight/sphere_detection.hpp). Photographs are drawn here with their own ray-sphere
// intersection and mirror law, independent of the code under test: spheres placed in 3D in
// front of a pinhole, a lamp disc reflected in them, a lit checkered table around them.

#include <algorithm>
#include <cmath>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "core/error.hpp"
#include "core/image_io.hpp"
#include "core/sphere.hpp"
#include "core/units.hpp"
#include "relight/sphere_detection.hpp"
#include "tests/support/temp_dir.hpp"

namespace rfd::relight {
namespace {

constexpr int kWidth = 480, kHeight = 320;
constexpr double kFocal = 1500.0;  // pixels: a 18-degree-wide view

// Camera frame = field frame: the camera at the origin looking down -z, y up in the image.
Eigen::Vector3d pixel_ray(double px, double py) {
    return Eigen::Vector3d((px - 0.5 * kWidth) / kFocal, -(py - 0.5 * kHeight) / kFocal, -1.0).normalized();
}

struct Ball {
    Eigen::Vector3d centre;  // camera frame, mm
    double radius = 10.0;    // mm
    bool mirror = true;      // else a diffuse grey ball
};

// The sphere as the code under test describes it: the image of its centre's ray and
// f tan(half-angle of the tangent cone).
MirrorSphere outline_of(const Ball& ball) {
    const Eigen::Vector3d c = ball.centre;
    return {0.5 * kWidth + kFocal * c.x() / -c.z(), 0.5 * kHeight - kFocal * c.y() / -c.z(),
            kFocal * std::tan(std::asin(ball.radius / c.norm()))};
}

// Nearest hit of the ray from the origin along unit e with the ball: distance, or -1.
double hit(const Ball& ball, const Eigen::Vector3d& e) {
    const double b = e.dot(ball.centre);
    const double disc = b * b - (ball.centre.squaredNorm() - ball.radius * ball.radius);
    return disc < 0.0 ? -1.0 : b - std::sqrt(disc);
}

struct Lamp {
    Eigen::Vector3d direction;  // unit, toward the lamp
    double radius = degrees_to_radians(4.0);
};

// One photograph under `lamp`, s x s samples a pixel: mirror balls show the lamp disc (of
// brightness `lamp_value`) on a dark room, diffuse balls and the table are Lambertian (the
// table checkered, of albedo `table`), linear RGB.
// Only the pixels within `only`'s box (and 3 px) are drawn when it is given.
Image photograph(const std::vector<Ball>& balls, const Lamp& lamp, int supersample = 4, double table = 0.5,
                 double lamp_value = 50.0, const MirrorSphere* only = nullptr) {
    Image image(kWidth, kHeight, 3);
    for (int y = 0; y < kHeight; ++y)
        for (int x = 0; x < kWidth; ++x) {
            if (only && (std::abs(x + 0.5 - only->centre_x) > only->radius + 3.0 ||
                         std::abs(y + 0.5 - only->centre_y) > only->radius + 3.0))
                continue;
            double sum = 0.0;
            for (int j = 0; j < supersample; ++j)
                for (int i = 0; i < supersample; ++i) {
                    const Eigen::Vector3d e = pixel_ray(x + (i + 0.5) / supersample, y + (j + 0.5) / supersample);
                    double nearest = 1e300;
                    int which = -1;
                    for (std::size_t b = 0; b < balls.size(); ++b) {
                        const double t = hit(balls[b], e);
                        if (t > 0.0 && t < nearest) {
                            nearest = t;
                            which = static_cast<int>(b);
                        }
                    }
                    double value = 0.0;
                    if (which < 0) {
                        // The table, 1 m away: checkers of 40 px, lit by the lamp's cosine.
                        const int checker = (x / 40 + y / 40) % 2;
                        value = (checker ? 1.0 : 0.6) * table * std::max(0.1, lamp.direction.z());
                    } else {
                        const Ball& ball = balls[static_cast<std::size_t>(which)];
                        const Eigen::Vector3d n = (nearest * e - ball.centre) / ball.radius;
                        if (!ball.mirror) {
                            value = 0.4 * std::max(0.0, n.dot(lamp.direction));
                        } else {
                            const Eigen::Vector3d v = -e;
                            const Eigen::Vector3d l = 2.0 * n.dot(v) * n - v;
                            value = 0.002;
                            if (angle_between(l, lamp.direction) < lamp.radius) value = lamp_value;
                        }
                    }
                    sum += value;
                }
            const float v = static_cast<float>(sum / (supersample * supersample));
            for (int c = 0; c < 3; ++c) image.at(x, y, c) = v;
        }
    return image;
}

CalibrationCamera camera() { return pinhole_camera(kFocal, kWidth, kHeight); }

double error_deg(const Eigen::Vector3d& a, const Eigen::Vector3d& b) { return radians_to_degrees(angle_between(a, b)); }

// Two balls 7 degrees off the axis, as a dome's corners are.
const Ball kLeft{{-105.0, 50.0, -1000.0}, 24.0};
const Ball kRight{{100.0, -45.0, -1000.0}, 24.0};

TEST(SphereView, PinholeMatchesRayTracingAndInverts) {
    const SphereView view(outline_of(kLeft), camera());
    std::mt19937 rng(3);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    const MirrorSphere o = outline_of(kLeft);
    int checked = 0;
    for (int k = 0; k < 2000; ++k) {
        const Eigen::Vector2d p(o.centre_x + 1.05 * o.radius * u(rng), o.centre_y + 1.05 * o.radius * u(rng));
        const Eigen::Vector3d e = pixel_ray(p.x(), p.y());
        const double t = hit(kLeft, e);
        // Right at the outline the two intersections may round differently.
        const double from_outline = e.cross(kLeft.centre.normalized()).norm() - kLeft.radius / kLeft.centre.norm();
        if (std::abs(from_outline) > 1e-9) {
            EXPECT_EQ(view.sees(p), t > 0.0) << p.transpose();
        }
        if (t <= 0.0) continue;
        const Eigen::Vector3d n = (t * e - kLeft.centre) / kLeft.radius;
        const Eigen::Vector3d l = 2.0 * n.dot(-e) * n + e;
        const auto [normal, v] = view.normal_and_view(p);
        EXPECT_LT((normal - n).norm(), 1e-9);
        EXPECT_LT((v + e).norm(), 1e-12);
        EXPECT_LT((view.reflected(p) - l).norm(), 1e-9);
        if (n.dot(-e) > 0.05) {  // away from the rim, where the inverse is well conditioned
            EXPECT_LT((view.highlight_point(l) - p).norm(), 1e-6) << p.transpose();
            ++checked;
        }
    }
    EXPECT_GT(checked, 1000);
    // The centre in sphere radii, as near_light() needs it.
    EXPECT_LT((view.centre() - kLeft.centre / kLeft.radius).norm(), 1e-9);
}

TEST(SphereView, OrthographicIsTheCircleModel) {
    const MirrorSphere sphere{64.3, 63.8, 60.0};
    const SphereView view(sphere, CalibrationCamera{});
    for (const Eigen::Vector2d& p : {Eigen::Vector2d(64.0, 60.0), Eigen::Vector2d(20.0, 90.0), Eigen::Vector2d(110.0, 40.0)}) {
        EXPECT_EQ(view.reflected(p), reflect_view(mirror_normal(sphere, p)));
        EXPECT_LT((view.highlight_point(view.reflected(p)) - p).norm(), 1e-9);
    }
}

TEST(SphereView, HighlightsNeedThePinhole) {
    // A ball 7 degrees off the axis: with the pinhole, the highlight gives the lamp to a
    // tenth of a degree; taken as seen from afar, the view direction is 7 degrees off and
    // so is the light.
    double worst = 0.0, worst_far = 0.0;
    for (const double theta : {10.0, 35.0, 60.0, 80.0})
        for (const double phi : {30.0, 160.0, 290.0}) {
            const Lamp lamp{direction_from_angles(degrees_to_radians(theta), degrees_to_radians(phi))};
            const MirrorSphere outline = outline_of(kLeft);
            const Image image = photograph({kLeft}, lamp, 8, 0.5, 50.0, &outline);
            const Highlight h = find_highlight(image, outline_of(kLeft), camera());
            ASSERT_EQ(h.status, HighlightStatus::Found) << theta << " " << phi;
            worst = std::max(worst, error_deg(h.direction, lamp.direction));
            const Highlight far = find_highlight(image, outline_of(kLeft));
            if (far.status == HighlightStatus::Found) worst_far = std::max(worst_far, error_deg(far.direction, lamp.direction));
        }
    EXPECT_LT(worst, 0.15);
    EXPECT_GT(worst_far, 3.0);
}

TEST(SphereOutline, FitsTheTangentConeToATenthOfAPixel) {
    // The mean of a capture: a dark ball on the lit checkered table, a dark stand touching
    // its lower edge, the rough circle off by 3 px and its radius by 4.
    const Ball ball = kRight;
    const Image mean = photograph({ball}, Lamp{Eigen::Vector3d::UnitZ(), 0.0});
    CaptureBrightness b;
    b.size = {kWidth, kHeight};
    b.mean.assign(b.size.area(), 0.0f);
    b.max.assign(b.size.area(), 0.0f);
    const MirrorSphere truth = outline_of(ball);
    for (int y = 0; y < kHeight; ++y)
        for (int x = 0; x < kWidth; ++x) {
            float v = mean.at(x, y, 0);
            if (std::abs(x + 0.5 - truth.centre_x) < 4.0 && y + 0.5 > truth.centre_y) v = std::min(v, 0.01f);
            b.mean[static_cast<std::size_t>(y) * kWidth + static_cast<std::size_t>(x)] = v;
        }
    const MirrorSphere rough{truth.centre_x + 3.0, truth.centre_y - 2.0, truth.radius + 4.0};
    const auto fit = fit_sphere_outline(b, rough, camera());
    ASSERT_TRUE(fit.has_value());
    EXPECT_NEAR(fit->sphere.centre_x, truth.centre_x, 0.1);
    EXPECT_NEAR(fit->sphere.centre_y, truth.centre_y, 0.1);
    EXPECT_NEAR(fit->sphere.radius, truth.radius, 0.1);
    EXPECT_GT(fit->edges, fit->rays * 8 / 10);
    EXPECT_LT(fit->rms_px, 0.2);
}

TEST(SphereDetection, FindsBothBallsAndTheirLampsInACapture) {
    rfd::testing::TempDir dir;
    // Two mirror balls and a diffuse one (round, but no highlight: not a calibration
    // sphere); 16 lamps over the hemisphere, exposed so that the highlights do not clip,
    // written as 8-bit PNGs. (Clipped, a highlight of 2.5 px is located to whole pixels
    // only: a degree of light on these 36 px balls.)
    const Ball diffuse{{0.0, 0.0, -1000.0}, 20.0, false};
    const std::vector<Ball> balls{kLeft, kRight, diffuse};
    std::vector<Lamp> lamps;
    std::vector<std::filesystem::path> files;
    for (int k = 0; k < 16; ++k) {
        const double theta = 15.0 + 60.0 * (k % 4) / 3.0, phi = 22.5 * k;
        lamps.push_back({direction_from_angles(degrees_to_radians(theta), degrees_to_radians(phi))});
        files.push_back(dir / ("photo_" + std::to_string(k) + ".png"));
        write_image(files.back(), photograph(balls, lamps.back(), 3, 0.5, 0.9));
    }
    const CaptureCalibration found = calibrate_capture(files, {camera(), {}});
    ASSERT_EQ(found.spheres.size(), 2u);
    EXPECT_GE(found.candidates, 2);
    ASSERT_GE(found.primary, 0);
    // Which is which: by position.
    const bool left_first = found.spheres[0].outline.centre_x < found.spheres[1].outline.centre_x;
    const MirrorSphere left = found.spheres[left_first ? 0 : 1].outline, right = found.spheres[left_first ? 1 : 0].outline;
    for (const auto& [got, truth] : {std::pair{left, outline_of(kLeft)}, std::pair{right, outline_of(kRight)}}) {
        EXPECT_NEAR(got.centre_x, truth.centre_x, 0.3);
        EXPECT_NEAR(got.centre_y, truth.centre_y, 0.3);
        EXPECT_NEAR(got.radius, truth.radius, 0.3);
    }
    double worst = 0.0, worst_disagreement = 0.0;
    for (std::size_t k = 0; k < lamps.size(); ++k) {
        const CalibratedImageLight& light = found.lights[k];
        ASSERT_EQ(light.spheres_used, 2) << k;
        worst = std::max(worst, error_deg(light.direction, lamps[k].direction));
        worst_disagreement = std::max(worst_disagreement, light.disagreement_deg);
    }
    // Measured: worst 0.20 degrees, the balls disagreeing by at most 0.32.
    EXPECT_LT(worst, 0.3);
    EXPECT_LT(worst_disagreement, 0.5);
}

TEST(SphereDetection, AFaintSpotIsNotAHighlight) {
    // Photographs of one mirror ball in a dark room; in one the lamp is hidden and the ball
    // shows a reflection a twentieth as bright as its highlights.
    rfd::testing::TempDir dir;
    std::vector<std::filesystem::path> files;
    for (int k = 0; k < 6; ++k) {
        const Lamp lamp{direction_from_angles(degrees_to_radians(20.0 + 10.0 * k), degrees_to_radians(60.0 * k))};
        files.push_back(dir / ("ball_" + std::to_string(k) + ".exr"));
        write_image(files.back(), photograph({kRight}, lamp, 3, 0.0, k == 4 ? 1.0 : 20.0));
    }
    const CaptureCalibration found = calibrate_capture(files, {camera(), {outline_of(kRight)}});
    ASSERT_EQ(found.lights.size(), 6u);
    for (int k = 0; k < 6; ++k)
        EXPECT_EQ(found.lights[static_cast<std::size_t>(k)].highlights[0].status,
                  k == 4 ? HighlightStatus::Faint : HighlightStatus::Found) << k;
    EXPECT_EQ(found.lights[4].spheres_used, 0);
    try {
        calibrate_lights(files, outline_of(kRight), camera());
        ADD_FAILURE() << "a hidden lamp calibrated";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("ball_4.exr: the brightest spot on the sphere is far fainter"),
                  std::string::npos) << e.what();
    }
}

TEST(NearLight, TriangulatesALampFromTwoSpheresAndKnowsADistantOne) {
    const std::vector<SphereView> views{SphereView(outline_of(kLeft), camera()),
                                        SphereView(outline_of(kRight), camera())};
    // Positions are in sphere radii from the camera.
    const Eigen::Vector3d lamp = Eigen::Vector3d(300.0, 200.0, -500.0) / kLeft.radius;
    std::vector<Highlight> seen(2);
    for (std::size_t s = 0; s < 2; ++s) {
        seen[s].status = HighlightStatus::Found;
        seen[s].direction = (lamp - views[s].centre()).normalized();
    }
    const auto near = near_light(views, seen);
    ASSERT_TRUE(near.has_value());
    EXPECT_FALSE(near->distant);
    EXPECT_LT((near->position - lamp).norm(), 1e-6 * lamp.norm());
    EXPECT_LT(near->residual_rms, 1e-9);
    EXPECT_NEAR(near->distance, (lamp - 0.5 * (views[0].centre() + views[1].centre())).norm(), 1e-6);
    // One direction for both: parallel rays, a lamp at infinity.
    seen[1].direction = seen[0].direction;
    const auto far = near_light(views, seen);
    ASSERT_TRUE(far.has_value());
    EXPECT_TRUE(far->distant);
    // One sphere alone places nothing.
    seen[1].status = HighlightStatus::None;
    EXPECT_FALSE(near_light(views, seen).has_value());
}

}  // namespace
}  // namespace rfd::relight
