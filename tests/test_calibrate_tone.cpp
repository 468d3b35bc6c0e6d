// The tone curve from photographs of the printed step wedge, made without a printer: the wedge
// page as the printer receives it, "printed" through a true tone curve that is not the
// profile's (dot gain, a lower black), then photographed by calibrate/camera.hpp under a
// scanner's and a hand-held phone's conditions. The curve read back must be within 1 % RMS of
// the true one; photographs it cannot read must be refused with the reason.

#include <cmath>
#include <numbers>
#include <string>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "calibrate/camera.hpp"
#include "calibrate/sheet_finder.hpp"
#include "calibrate/tone.hpp"
#include "print/marks.hpp"
#include "core/image_io.hpp"
#include "print/printer.hpp"
#include "print/wedge.hpp"
#include "tests/support/cameras.hpp"
#include "tests/support/error_of.hpp"
#include "tests/support/temp_dir.hpp"

namespace rfd::calibrate {
namespace {

using rfd::testing::error_of;
using ::testing::AnyOf;
using ::testing::HasSubstr;

constexpr double kMinTilt = 10.0;  // deg

// A printer whose true curve is not a power law: 15 % dot gain in the mid-tones and full ink at
// density 1.7, as a measured table of 256 codes.
print::PrinterProfile true_printer(const print::PrinterProfile& nominal) {
    print::PrinterProfile printer = nominal;
    printer.max_density = 1.7;
    const double ink = std::pow(10.0, -printer.max_density);
    for (int code = 255; code >= 0; --code) {
        const double v = 1.0 - code / 255.0;
        const double coverage = v + 0.15 * std::sin(std::numbers::pi * v);
        printer.tone_ink.push_back(v);
        printer.tone_transmittance.push_back(ink + (1.0 - ink) * std::pow(1.0 - coverage, 1.8));
    }
    printer.tone_transmittance.back() = ink;
    return printer;
}

// A portrait camera framing an A4 sheet, frontal.
Camera scanner() { return framing_camera(print::Paper{}, 450.0); }

Camera phone() {
    Camera camera = rfd::testing::hand_held(scanner());
    camera.light_gradient = 0.15;
    camera.read_noise = 0.002;
    camera.seed = 7;
    return camera;
}

double curve_rms(const print::PrinterProfile& a, const print::PrinterProfile& b) {
    double sum = 0.0;
    constexpr int kSteps = 1000;
    for (int k = 0; k <= kSteps; ++k) {
        const double v = static_cast<double>(k) / kSteps;
        sum += std::pow(a.transmittance(v) - b.transmittance(v), 2);
    }
    return std::sqrt(sum / (kSteps + 1));
}

struct Fixture {
    print::PrinterProfile nominal = print::load_printer("epson_stylus_pro_4800");
    print::PrinterProfile truth = true_printer(nominal);
    print::WedgeSheet sheet = print::wedge_sheet(nominal, 21);
};

const Fixture& fixture() {
    static const Fixture f;
    return f;
}

// Through an 8-bit file, as cameras and scanners store them.
Image stored(const Image& photo, const std::string& name, int quality = 80) {
    const rfd::testing::TempDir dir;
    write_photograph(dir / name, photo, quality);
    return read_image(dir / name);
}

TEST(Camera, HomographyIsThePinholeProjection) {
    Camera camera = phone();
    const Eigen::Matrix3d h = page_to_pixels(camera);
    // The same pose built another way: rotations about the page's normal and an axis in it.
    const double tilt = camera.pose.tilt_deg * std::numbers::pi / 180,
                 turn = camera.pose.turn_deg * std::numbers::pi / 180;
    const Eigen::Vector3d aim(camera.pose.aim.x(), camera.pose.aim.y(), 0.0);
    const Eigen::Vector3d centre =
        aim + camera.pose.distance *
                  Eigen::Vector3d(std::sin(tilt) * std::cos(turn), std::sin(tilt) * std::sin(turn), -std::cos(tilt));
    const Eigen::Vector3d forward = (aim - centre).normalized();
    int checked = 0;
    for (double x = 0; x <= 210; x += 35)
        for (double y = 0; y <= 297; y += 33) {
            const Eigen::Vector3d p(x, y, 0.0);
            const Eigen::Vector3d d = p - centre;
            const double depth = d.dot(forward);
            // The image point's distance from the image centre, f tan(angle off the axis).
            const Eigen::Vector2d pixel = apply(h, {x, y});
            const Eigen::Vector2d off = pixel - Eigen::Vector2d(0.5 * (camera.width - 1), 0.5 * (camera.height - 1));
            const double angle = std::acos(std::clamp(d.normalized().dot(forward), -1.0, 1.0));
            EXPECT_NEAR(off.norm(), camera.focal * std::tan(angle), 1e-6) << x << ", " << y;
            EXPECT_GT(depth, 0.0);
            ++checked;
        }
    EXPECT_EQ(checked, 70);
    // The aim point at the image centre; frontal, 10 mm along x is f 10 / d pixels to the
    // right.
    EXPECT_LT((apply(h, camera.pose.aim) - Eigen::Vector2d(599.5, 799.5)).norm(), 1e-9);
    const Camera front = scanner();
    const Eigen::Vector2d step = apply(page_to_pixels(front), front.pose.aim + Eigen::Vector2d(10, 0)) -
                                 apply(page_to_pixels(front), front.pose.aim);
    EXPECT_NEAR(step.x(), front.focal * 10 / front.pose.distance, 1e-9);
    EXPECT_NEAR(step.y(), 0.0, 1e-9);
}

// The pose back from the homography alone, exact for exact homographies at any tilt beyond the
// frontal band, and refused within it; with the sheet's four marks found 0.3 pixel off (as
// find_sheet does on a sharp photo), the camera's height within 1 % (0.9 % at 8 deg of tilt, 10 %
// at 2 deg: the frontal band is refused).
TEST(Camera, ThePoseFollowsFromATiltedPhotographsHomography) {
    const print::Paper paper = print::load_printer("epson_stylus_pro_4800").paper;
    const print::SheetMarks marks = print::sheet_marks(paper);
    int checked = 0;
    for (const double tilt : {0.0, 2.0, 5.0, 8.0, 12.0, 15.0, 30.0, 45.0, 60.0})
        for (const double turn : {0.0, 20.0, 135.0})
            for (const double roll : {0.0, 7.0, 90.0})
                for (const double distance : {300.0, 520.0}) {
                    Camera camera = framing_camera(paper, distance, 0.9, 4000);
                    camera.pose.tilt_deg = tilt, camera.pose.turn_deg = turn, camera.pose.roll_deg = roll;
                    const Eigen::Matrix3d h = page_to_pixels(camera);
                    const Eigen::Vector3d truth = camera_centre(camera.pose);
                    const std::optional<EstimatedPose> exact = estimate_pose(h, camera.width, camera.height, kMinTilt);
                    ASSERT_EQ(exact.has_value(), tilt >= kMinTilt) << tilt;
                    if (exact) {
                        EXPECT_LT((exact->centre - truth).norm(), 1e-6 * distance) << tilt << " " << turn << " " << roll;
                        EXPECT_NEAR(exact->focal, camera.focal, 1e-6 * camera.focal);
                        EXPECT_NEAR(exact->tilt_deg, tilt, 1e-6);
                    }
                    // The marks found 0.3 pixel off, in a pattern that changes with the pose.
                    std::array<Eigen::Vector2d, 4> pixels;
                    for (std::size_t k = 0; k < 4; ++k) {
                        const double angle = 2.1 * static_cast<double>(k) + 0.01 * (tilt + turn + roll + distance);
                        pixels[k] = apply(h, marks.corners[k]) + 0.3 * Eigen::Vector2d(std::cos(angle), std::sin(angle));
                    }
                    const Eigen::Matrix3d noisy = homography_from_points(marks.corners, pixels);
                    const std::optional<EstimatedPose> found = estimate_pose(noisy, camera.width, camera.height, kMinTilt);
                    if (tilt >= kMinTilt) {
                        ASSERT_TRUE(found.has_value()) << tilt;
                        EXPECT_NEAR(found->centre.z() / truth.z(), 1.0, 0.01) << tilt << " " << turn << " " << roll;
                        ++checked;
                    }
                }
    EXPECT_EQ(checked, 90);
}

TEST(Camera, LightFallsOffAsConfigured) {
    Image white(420, 594, 1, 1.0f);  // an A4 page of bare film at 2 px/mm
    Camera camera = scanner();
    camera.focal = 2700.0;  // the page fills the whole frame
    camera.vignetting = 0.3;
    const Image photo = photograph(white, 2.0, camera);
    EXPECT_NEAR(photo.at(600, 800, 0), camera.exposure, 1e-3);
    EXPECT_NEAR(photo.at(0, 0, 0), camera.exposure * 0.7, 2e-3);
    EXPECT_NEAR(photo.at(1199, 1599, 0), camera.exposure * 0.7, 2e-3);
}

TEST(SheetFinder, FindsTheMarksFromAnySideAndFromTheBack) {
    const Fixture& f = fixture();
    int checked = 0;
    for (const auto& [roll, back] :
         {std::pair{0.0, false}, std::pair{90.0, true}, std::pair{200.0, false}, std::pair{270.0, true}}) {
        Camera camera = phone();
        camera.pose.roll_deg = roll;
        camera.pose.from_back = back;
        camera.pose.distance = 720.0;  // the whole sheet in view however it is turned
        const Image photo = simulated_wedge_photo(f.sheet, f.nominal, f.truth, camera, ScanLight::Back);
        const SheetLocation where = find_sheet(photo, f.sheet.marks, "photo");
        EXPECT_EQ(where.mirrored, back) << roll;
        Eigen::Matrix3d truth = page_to_pixels(camera);
        if (back) truth = truth * (Eigen::Matrix3d() << -1, 0, 210, 0, 1, 0, 0, 0, 1).finished();
        for (const Eigen::Vector2d& corner :
             {Eigen::Vector2d(0, 0), Eigen::Vector2d(210, 0), Eigen::Vector2d(210, 297), Eigen::Vector2d(0, 297)})
            EXPECT_LT((apply(where.page_to_photo, corner) - apply(truth, corner)).norm(), 0.5)
                << "roll " << roll << (back ? " from the back" : "");
        ++checked;
    }
    EXPECT_EQ(checked, 4);
}

TEST(ToneCalibration, RecoversTheTrueCurveFromScansAndPhotographs) {
    const Fixture& f = fixture();
    const double before = curve_rms(f.nominal, f.truth);
    EXPECT_GT(before,
              0.03);  // the profile is far from this printer: a test that can fail
    struct Case {
        std::string name;
        Camera camera;
        ScanLight light;
    };
    Camera reflected = scanner();
    std::vector<Case> cases = {{"scan", scanner(), ScanLight::Back},
                               {"phone", phone(), ScanLight::Back},
                               {"reflected", reflected, ScanLight::Reflected}};
    for (const Case& c : cases) {
        const Image photo =
            stored(simulated_wedge_photo(f.sheet, f.nominal, f.truth, c.camera, c.light), c.name + ".jpg");
        const WedgeReading reading = measure_wedge(photo, c.name, f.sheet, f.nominal, c.light);
        const ToneCalibration fit = calibrate_tone(f.nominal, {reading});
        const double rms = curve_rms(fit.profile, f.truth);
        EXPECT_LT(rms, 0.01) << c.name;
        EXPECT_NEAR(fit.profile.max_density, 1.7, 0.1) << c.name;
        // The profile as written reads back to the same curve.
        const print::PrinterProfile again = print::parse_printer(print::printer_toml(fit.profile), "calibrated.toml");
        EXPECT_EQ(print::printer_toml(again), print::printer_toml(fit.profile));
        std::printf("%s: curve RMS %.4f (profile before %.4f), max density %.3f\n", c.name.c_str(), rms, before,
                    fit.profile.max_density);
    }
}

// What the calibration is for: the sheet printed through the true curve transmits what the
// tone mapping meant. With the nominal profile it cannot (its ink is darker and its curve
// another); with the measured one it does, for one sheet and for two back to back.
TEST(ToneCalibration, TheMeasuredProfilePrintsWhatTheToneMappingMeans) {
    const Fixture& f = fixture();
    const Image photo = stored(simulated_wedge_photo(f.sheet, f.nominal, f.truth, phone(), ScanLight::Back), "w.jpg");
    const print::PrinterProfile measured =
        calibrate_tone(f.nominal, {measure_wedge(photo, "w.jpg", f.sheet, f.nominal, ScanLight::Back)}).profile;
    // PSNR (peak 1) of the stack the true printer makes against the one the tone map asks for.
    const auto psnr = [&](const print::PrinterProfile& profile, int sheets) {
        const print::ToneMap tone{profile, 1.0, 1.0, sheets};
        double sum = 0.0;
        constexpr int kValues = 256;
        for (int k = 0; k < kValues; ++k) {
            const double value = k / (kValues - 1.0);
            const double sheet = f.truth.transmittance(tone.printer_value(value));
            sum += std::pow(std::pow(sheet, sheets) - tone.stack_transmittance(value), 2);
        }
        return 10.0 * std::log10(kValues / sum);
    };
    for (const int sheets : {1, 2}) {
        const double before = psnr(f.nominal, sheets), after = psnr(measured, sheets);
        EXPECT_LT(before, 30.0) << sheets;
        EXPECT_GT(after, 45.0) << sheets;
        std::printf("%d sheet(s): printed against meant, PSNR %.1f dB with the nominal profile, %.1f dB measured\n",
                    sheets, before, after);
    }
}

TEST(ToneCalibration, RefusesPhotographsItCannotRead) {
    const Fixture& f = fixture();
    const auto error_for = [&](Camera camera) {
        // Half the pixels, the same framing: what is refused does not need more.
        camera.width /= 2;
        camera.height /= 2;
        camera.focal /= 2;
        return error_of([&] {
            const Image photo = simulated_wedge_photo(f.sheet, f.nominal, f.truth, camera, ScanLight::Back);
            measure_wedge(stored(photo, "p.png"), "p.png", f.sheet, f.nominal, ScanLight::Back);
        });
    };
    Camera dark = scanner();
    dark.exposure = 0.01;
    EXPECT_THAT(error_for(dark), HasSubstr("too dark"));
    Camera bright = scanner();
    bright.exposure = 1.4;
    EXPECT_THAT(error_for(bright), HasSubstr("overexposed"));
    Camera cut = scanner();
    cut.pose.aim = {150.0, 150.0};  // the left column of discs out of the frame
    EXPECT_THAT(error_for(cut), HasSubstr("cannot find the sheet"));
    Camera far = scanner();
    far.focal = 180.0;  // the sheet about 60 pixels tall
    EXPECT_THAT(error_for(far), AnyOf(HasSubstr("pixels across"), HasSubstr("cannot find the sheet")));
}

}  // namespace
}  // namespace rfd::calibrate
