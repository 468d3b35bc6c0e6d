// The lens array's pitch and rotation from photographs of the moire sheet mounted in the
// display, made without a printer: the sheet's measuring bands under an array of known pitch
// error and turn, lit from behind by the sun through the display's own exact optics
// (calibrate/moire_photo.hpp), then photographed by calibrate/camera.hpp. What is read back
// must be within 0.01 % of the true pitch (ten times finer than the hypothesis bands' 0.1 %
// steps read by eye) and 0.02 deg of the true turn; what cannot be read must be refused.

#include <cmath>
#include <numbers>
#include <string>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "calibrate/camera.hpp"
#include "calibrate/moire_photo.hpp"
#include "calibrate/pitch.hpp"
#include "calibrate/pitch_report.hpp"
#include "core/error.hpp"
#include "core/image_io.hpp"
#include "optics/design.hpp"
#include "print/moire.hpp"
#include "print/printer.hpp"
#include "tests/support/bundled.hpp"
#include "tests/support/cameras.hpp"
#include "tests/support/error_of.hpp"
#include "tests/support/temp_dir.hpp"

namespace rfd::calibrate {
namespace {

using rfd::testing::bundled_design;
using rfd::testing::error_of;
using ::testing::AllOf;
using ::testing::HasSubstr;
using ::testing::Not;

struct MoireFixture {
    optics::Design design = bundled_design(1);
    print::PrinterProfile printer = print::load_printer("epson_stylus_pro_4800");
    print::MoireSheet sheet = print::moire_sheet(design, printer, {print::default_pitch_range(design)});
};

const MoireFixture& moire_fixture() {
    static const MoireFixture f;
    return f;
}

// A 3000 x 2250 camera framing the A4 sheet, frontal.
Camera frontal_camera() { return framing_camera(print::Paper{}, 450.0, 0.9, 3000); }

// Through an 8-bit JPEG at quality 80, as phones store them.
Image stored_jpeg(const Image& photo) {
    const rfd::testing::TempDir dir;
    write_photograph(dir / "photo.jpg", photo, 80);
    return read_image(dir / "photo.jpg");
}

MoireScene mounted(double pitch_error, double rotation_deg) {
    MoireScene s;
    s.mounting.centre = measuring_centre(moire_fixture().sheet);
    s.mounting.pitch_error_x = s.mounting.pitch_error_y = pitch_error;
    s.mounting.rotation_deg = rotation_deg;
    return s;
}

// The measuring bands: lines half a period wide, a period that is not the pitch so that the
// lenslets drift across them (a fifth of a period and more per lenslet, as measuring_period
// says), slanted at most 3 deg, crossing in the array's middle with the crossing left bare.
TEST(MoireSheet, MeasuringBandsCrossUnderTheArray) {
    const MoireFixture& f = moire_fixture();
    const optics::Lattice& lattice = print::moire_lattice(f.design);
    ASSERT_EQ(f.sheet.measuring.size(), 2u);
    const print::MoireBand& x = f.sheet.measuring[0];
    const print::MoireBand& rows = f.sheet.measuring[1];
    EXPECT_TRUE(x.along_x);
    EXPECT_FALSE(rows.along_x);
    for (const print::MoireBand* band : {&x, &rows}) {
        const double spacing = band->along_x ? lattice.pitch_x() : lattice.pitch_y();
        const double lines = spacing / band->period;
        const double drift = lines - std::floor(lines);
        EXPECT_GE(drift, 0.2);
        EXPECT_LE(drift, 0.45);
        EXPECT_NEAR(band->line_fraction, 0.5, 0.0);
        EXPECT_GT(std::abs(band->slant_rad), 0.0);
        EXPECT_LE(std::abs(band->slant_rad), 0.0524);
        EXPECT_EQ(band->page, 0);
    }
    // The x band spans the array's width, the rows band (nearly) its height.
    EXPECT_NEAR(x.width, 2.0 * lattice.half_extent().x(), 1e-9);
    EXPECT_GT(rows.height, 1.9 * lattice.half_extent().y());
    // Crossing: the middle is bare, each band's arms are inked somewhere.
    const Eigen::Vector2d middle = measuring_centre(f.sheet);
    EXPECT_FALSE(x.inside(middle.x(), middle.y()));
    EXPECT_FALSE(rows.inside(middle.x(), middle.y()));
    int inked = 0, checked = 0;
    for (double dx = -70; dx <= 70; dx += 0.05) {
        inked += x.inked(middle.x() + dx, middle.y());
        ++checked;
    }
    EXPECT_EQ(checked, 2801);
    // Half of each arm's length is ink (half-period lines), none in the crossing.
    EXPECT_NEAR(inked * 0.05, 0.5 * (140.0 - x.hole[2]), 2.0);
    // The lines are where inked() says, slanted: one passes through the band's centre, and
    // the next one a period along the normal.
    const Eigen::Vector2d centre(x.left + 0.5 * x.width, x.top + 0.5 * x.height);
    const Eigen::Vector2d n = x.normal();
    EXPECT_NEAR(n.norm(), 1.0, 1e-15);
    const Eigen::Vector2d on_arm = centre + Eigen::Vector2d(40.0, 0.0);
    const double across = n.dot(on_arm - centre) / x.period;
    const Eigen::Vector2d line = on_arm - (across - std::round(across)) * x.period * n;
    EXPECT_TRUE(x.inked(line.x(), line.y()));
    EXPECT_TRUE(x.inked(line.x() + 0.24 * x.period * n.x(), line.y() + 0.24 * x.period * n.y()));
    EXPECT_FALSE(x.inked(line.x() + 0.26 * x.period * n.x(), line.y() + 0.26 * x.period * n.y()));
}

// Frontal and hand-held photographs (tilted 30 deg, blurred, vignetted, noisy, the sun 10 deg
// off the axis), the array 0.1 % too large or 0.23 % too small and turned: the pitch within
// 0.01 % along both axes, the turn within 0.02 deg, each within four of its stated
// uncertainties (and 0.002 %). (Suite PitchAccuracy: label `accuracy`, HACKING.md.)
TEST(PitchAccuracy, RecoversThePitchAndTurnFromPhotographs) {
    const MoireFixture& f = moire_fixture();
    struct Case {
        const char* name;
        double pitch_error, rotation_deg;
        Camera camera;
        Eigen::Vector3d light = Eigen::Vector3d::UnitZ();
    };
    Camera phone = rfd::testing::hand_held(frontal_camera());
    phone.seed = 5;
    const double sun = 10.0 * std::numbers::pi / 180.0;
    const std::vector<Case> cases = {
        {"frontal", 0.001, 0.3, frontal_camera()},
        {"hand-held, sun 10 deg off", -0.0023, -1.2, phone,
         Eigen::Vector3d(std::sin(sun) * 0.766, std::sin(sun) * 0.643, std::cos(sun))},
    };
    for (const Case& c : cases) {
        const MoireScene s = mounted(c.pitch_error, c.rotation_deg);
        MoireScene lit = s;
        lit.light = c.light;
        const Image photo = stored_jpeg(simulated_moire_photo(f.design, f.sheet, f.printer, lit, c.camera));
        const PitchReading reading = read_pitch_photo(photo, c.name, f.design, f.sheet);
        const PitchCalibration calibration = calibrate_pitch(f.design, {reading});
        const double error_x = calibration.scale_x - (1.0 + c.pitch_error);
        const double error_y = calibration.scale_y - (1.0 + c.pitch_error);
        const double error_turn = calibration.rotation_deg[0] - c.rotation_deg;
        std::printf("%s: pitch %+.4f %% (+- %.4f), rows %+.4f %% (+- %.4f), turn %+.4f deg (+- %.4f)\n", c.name,
                    100 * error_x, 100 * calibration.sigma_scale_x, 100 * error_y, 100 * calibration.sigma_scale_y,
                    error_turn, calibration.sigma_rotation_deg[0]);
        EXPECT_LT(std::abs(error_x), 1e-4) << c.name;
        EXPECT_LT(std::abs(error_y), 1e-4) << c.name;
        EXPECT_LT(std::abs(error_turn), 0.02) << c.name;
        EXPECT_LT(std::abs(error_x), 4 * calibration.sigma_scale_x + 2e-5) << c.name;
        EXPECT_LT(std::abs(error_y), 4 * calibration.sigma_scale_y + 2e-5) << c.name;
        EXPECT_GT(reading.x.lenslets, 200) << c.name;
        EXPECT_GT(reading.y.lenslets, 200) << c.name;
        EXPECT_LT(reading.lattice_mismatch, kLatticeMismatchNoise) << c.name;
    }
}

// The sun 28 deg off the display's axis (beyond Design I's 25): the lattice of lenslet images
// the spectrum finds departs from the shape the lines measure, the reading discs drift across
// the images, and the row spacing read 0.03 % off at +-0.002 %. The departure is measured and
// the uncertainty covers the error; the report says so and how to photograph it again.
TEST(PitchAccuracy, SaysWhenTheLensletImagesDriftFromTheLinesLattice) {
    const MoireFixture& f = moire_fixture();
    MoireScene lit = mounted(0.001, 0.3);
    const double sun = 28.0 * std::numbers::pi / 180.0;
    lit.light = Eigen::Vector3d(0.0, std::sin(sun), std::cos(sun));
    const Image photo = stored_jpeg(simulated_moire_photo(f.design, f.sheet, f.printer, lit, frontal_camera()));
    const PitchReading reading = read_pitch_photo(photo, "sun.jpg", f.design, f.sheet);
    const PitchCalibration calibration = calibrate_pitch(f.design, {reading});
    const double error_x = calibration.scale_x - 1.001, error_y = calibration.scale_y - 1.001;
    std::printf("sun 28 deg off: lattice %.4f %% out of shape; pitch %+.4f %% (+- %.4f), rows %+.4f %% (+- %.4f)\n",
                100 * reading.lattice_mismatch, 100 * error_x, 100 * calibration.sigma_scale_x, 100 * error_y,
                100 * calibration.sigma_scale_y);
    EXPECT_GT(reading.lattice_mismatch, kLatticeMismatchNoise);
    EXPECT_LT(std::abs(error_x), 2 * calibration.sigma_scale_x);
    EXPECT_LT(std::abs(error_y), 2 * calibration.sigma_scale_y);
    const std::string text = pitch_text(calibration, {reading});
    EXPECT_THAT(text, HasSubstr("out of the shape the lines measure"));
    EXPECT_THAT(text, HasSubstr("with the sun behind the display"));
}

// Design II's 6 x 5 array is too small for the bands to cross under it: the sheet lays it
// whole on the x band, then on the rows band, each a lenslet larger than the array on every
// side, with graded lines for its reading discs (a quarter period of drift per lenslet).
struct SmallArrayFixture {
    optics::Design design = bundled_design(2);
    print::PrinterProfile printer = print::load_printer("epson_stylus_pro_4800");
    print::MoireSheet sheet = print::moire_sheet(design, printer, {print::default_pitch_range(design)});
};

const SmallArrayFixture& small_array_fixture() {
    static const SmallArrayFixture f;
    return f;
}

// The array, `pitch_error` too large and turned `rotation_deg`, laid `shift` mm from the
// middle of each band in turn and photographed by `camera`: the two readings.
std::vector<PitchReading> small_array_readings(const Camera& camera, const Eigen::Vector2d& shift,
                                               double pitch_error = 0.0015, double rotation_deg = 0.4) {
    const SmallArrayFixture& f = small_array_fixture();
    std::vector<PitchReading> readings;
    for (const MeasuringBands band : {MeasuringBands::X, MeasuringBands::Rows}) {
        MoireScene s;
        s.mounting.centre = measuring_centre(f.sheet, band) + shift;
        s.mounting.pitch_error_x = s.mounting.pitch_error_y = pitch_error;
        s.mounting.rotation_deg = rotation_deg;
        const Image photo = stored_jpeg(simulated_moire_photo(f.design, f.sheet, f.printer, s, camera));
        readings.push_back(read_pitch_photo(photo, band == MeasuringBands::X ? "x.jpg" : "rows.jpg", f.design, f.sheet));
    }
    return readings;
}

TEST(MoireSheet, ASmallArrayIsLaidWholeOnEachBandInTurn) {
    const SmallArrayFixture& f = small_array_fixture();
    const optics::Lattice& lattice = print::moire_lattice(f.design);
    EXPECT_TRUE(f.sheet.whole_array);
    EXPECT_TRUE(print::lays_array_whole(f.design, f.printer.paper));
    EXPECT_FALSE(moire_fixture().sheet.whole_array);
    EXPECT_FALSE(print::lays_array_whole(moire_fixture().design, moire_fixture().printer.paper));
    ASSERT_EQ(f.sheet.measuring.size(), 2u);
    for (const print::MoireBand& band : f.sheet.measuring) {
        EXPECT_EQ(band.hole[2], 0.0);
        EXPECT_NEAR(band.width, 2.0 * (lattice.half_extent().x() + lattice.pitch_x()), 1e-9);
        EXPECT_GE(band.height, 2.0 * (lattice.half_extent().y() + lattice.pitch_y()) - 1e-9);
        // A quarter period of drift from one lenslet to the next; graded lines, slanted.
        const double per_lenslet = band.pitch / band.period;
        EXPECT_NEAR(per_lenslet - std::floor(per_lenslet), 0.25, 1e-9);
        EXPECT_TRUE(band.graded);
        EXPECT_GT(std::abs(band.slant_rad), 0.0);
    }
    EXPECT_GT(f.sheet.measuring[1].top, f.sheet.measuring[0].top + f.sheet.measuring[0].height);
}

// The whole array's bands are graded: as printed (the page's codes), the transmittance across
// the lines is the cosine MoireBand::ink says, through the printer's tone curve, which is what
// the photographs' simulator and the reader assume. Printed as 64 codes a period, so each
// pixel's transmittance is the cosine's within half a sample of phase (and a code) of its own.
TEST(MoireSheet, ASmallArraysLinesAreGradedAsTheReaderModelsThem) {
    const SmallArrayFixture& f = small_array_fixture();
    constexpr double kPixelsPerMm = 10.0;
    const Image codes = print::moire_page_codes(f.sheet, f.design, f.printer, 0, kPixelsPerMm);
    const double ink = f.printer.ink_transmittance();
    int checked = 0;
    double worst = 0.0, darkest = 1.0, lightest = 0.0;
    for (const print::MoireBand& band : f.sheet.measuring) {
        EXPECT_TRUE(band.graded);
        const Eigen::Vector2d centre(band.left + 0.5 * band.width, band.top + 0.5 * band.height);
        for (double t = -3.0 * band.period; t <= 3.0 * band.period; t += 0.02) {
            const Eigen::Vector2d at = centre + t * band.normal();
            const int x = static_cast<int>(std::floor(at.x() * kPixelsPerMm));
            const int y = static_cast<int>(std::floor(at.y() * kPixelsPerMm));
            const double printed = f.printer.transmittance(1.0 - codes.at(x, y, 0));
            const double modelled = 1.0 - band.ink((x + 0.5) / kPixelsPerMm, (y + 0.5) / kPixelsPerMm) * (1.0 - ink);
            worst = std::max(worst, std::abs(printed - modelled));
            darkest = std::min(darkest, printed);
            lightest = std::max(lightest, printed);
            ++checked;
        }
    }
    EXPECT_GT(checked, 300);
    EXPECT_LT(worst, 0.5 * std::numbers::pi / 64.0 * (1.0 - ink) + 0.01);
    // The cosine runs from bare film to full ink.
    EXPECT_LT(darkest, ink + 0.05);
    EXPECT_GT(lightest, 0.95);
}

// Hand-held (tilted 30 deg, blurred, vignetted, noisy): every lenslet read, the pitch along
// both axes within 0.01 % (the target) and within four stated uncertainties, which
// are themselves inside it, the turn within 0.02 deg. The lenslet images lie on the diffuser
// 13.4 mm above the sheet, so they look 3 % larger than the array: the reader takes that from
// the camera's pose.
TEST(PitchCalibration, ReadsASmallArrayLaidWholeOnEachBand) {
    Camera phone = rfd::testing::hand_held(frontal_camera());
    phone.seed = 7;
    const std::vector<PitchReading> readings = small_array_readings(phone, {0.13, 0.0});
    EXPECT_EQ(readings[0].x.lenslets + readings[0].x.outliers, 30);
    EXPECT_EQ(readings[1].y.lenslets + readings[1].y.outliers, 30);
    EXPECT_EQ(readings[0].y.lenslets, 0);
    const PitchCalibration calibration = calibrate_pitch(small_array_fixture().design, readings);
    const double error_x = calibration.scale_x - 1.0015, error_y = calibration.scale_y - 1.0015;
    std::printf("Design II, hand-held: pitch %+.4f %% (+- %.4f), rows %+.4f %% (+- %.4f), turn %+.4f %+.4f deg\n",
                100 * error_x, 100 * calibration.sigma_scale_x, 100 * error_y, 100 * calibration.sigma_scale_y,
                calibration.rotation_deg[0] - 0.4, calibration.rotation_deg[1] - 0.4);
    EXPECT_LT(std::abs(error_x), 1e-4);
    EXPECT_LT(std::abs(error_y), 1e-4);
    EXPECT_LT(std::abs(error_x), 4 * calibration.sigma_scale_x);
    EXPECT_LT(std::abs(error_y), 4 * calibration.sigma_scale_y);
    EXPECT_LT(calibration.sigma_scale_x, 1e-4);
    EXPECT_LT(calibration.sigma_scale_y, 1e-4);
    for (const double turn : calibration.rotation_deg) EXPECT_LT(std::abs(turn - 0.4), 0.02);
    // Each photograph shows one band: the axes' departure from square is not measured there,
    // and the report says which band it read instead of printing a NaN.
    const std::string text = pitch_text(calibration, readings);
    EXPECT_THAT(text, HasSubstr("x.jpg: 0."));
    EXPECT_THAT(text, HasSubstr("the x band only"));
    EXPECT_THAT(text, HasSubstr("the rows band only"));
    EXPECT_THAT(text, Not(HasSubstr("nan")));
}

// Over eight arrays (pitch error, turn, placement up to 2.3 mm off the band's middle, and
// pose each different): each pair read within 0.01 % along both axes (the target)
// and four stated uncertainties. Three of them were refused while the lattice's origin was
// taken from the spectrum's phase (the discs then straddled two images).
TEST(PitchAccuracy, ASmallArrayOverPlacementsAndPoses) {
    struct Case {
        double pitch_error, rotation_deg;
        Eigen::Vector2d shift;
    };
    const std::vector<Case> cases = {{0.0015, 0.3, {0.0, 0.0}},    {0.002, 0.5, {0.31, 0.23}},
                                     {-0.002, 1.0, {-0.21, 0.11}}, {0.0015, 1.0, {0.07, -0.29}},
                                     {0.002, 0.3, {-0.37, -0.05}}, {-0.001, 0.7, {0.45, 0.41}},
                                     {0.0005, -0.8, {1.6, -1.6}},  {0.001, 0.4, {-0.5, 0.3}}};
    int checked = 0;
    for (std::size_t k = 0; k < cases.size(); ++k) {
        const Case& c = cases[k];
        Camera phone = rfd::testing::hand_held(frontal_camera());
        phone.seed = 11 + k;
        phone.pose.tilt_deg = 25.0 + 2.0 * static_cast<double>(k % 4);
        phone.pose.turn_deg = k % 2 ? 20.0 : -15.0;
        const std::vector<PitchReading> readings = small_array_readings(phone, c.shift, c.pitch_error, c.rotation_deg);
        const PitchCalibration r = calibrate_pitch(small_array_fixture().design, readings);
        const double error_x = r.scale_x - (1.0 + c.pitch_error), error_y = r.scale_y - (1.0 + c.pitch_error);
        std::printf("array %zu: pitch %+.4f %% (+- %.4f), rows %+.4f %% (+- %.4f), turn %+.4f %+.4f deg\n", k,
                    100 * error_x, 100 * r.sigma_scale_x, 100 * error_y, 100 * r.sigma_scale_y,
                    r.rotation_deg[0] - c.rotation_deg, r.rotation_deg[1] - c.rotation_deg);
        EXPECT_LT(std::abs(error_x), 1e-4) << k;
        EXPECT_LT(std::abs(error_y), 1e-4) << k;
        EXPECT_LT(std::abs(error_x), 4 * r.sigma_scale_x) << k;
        EXPECT_LT(std::abs(error_y), 4 * r.sigma_scale_y) << k;
        for (const double turn : r.rotation_deg) EXPECT_LT(std::abs(turn - c.rotation_deg), 0.02) << k;
        ++checked;
    }
    EXPECT_EQ(checked, 8);
}

// An array laid off the middle of its band, photographed from the side it lies toward: many
// of the lattice points read around it fall on the holder and read nothing. The bare sheet's
// brightness is then judged from the light alone; judged from all points it fell below the
// brightest lenslets, which counted as bare sheet and pushed the block a lenslet onto the
// holder (the fit then missed the readings by a third of their spread, and both were refused).
TEST(PitchCalibration, FindsASmallArrayBesideItsHoldersDark) {
    Camera phone = framing_camera(small_array_fixture().printer.paper, 520.0, 0.78, 4000);
    phone.pose.tilt_deg = 29.6;
    phone.pose.turn_deg = 50.0;
    phone.pose.roll_deg = -4.0;
    phone.blur = 1.2;
    phone.vignetting = 0.3;
    phone.photons = 2500.0;
    phone.seed = 4;
    const std::vector<PitchReading> readings = small_array_readings(phone, {1.58, -1.6}, -0.0015, -0.38);
    const PitchCalibration r = calibrate_pitch(small_array_fixture().design, readings);
    EXPECT_EQ(readings[0].x.lenslets, 30);
    EXPECT_EQ(readings[1].y.lenslets, 30);
    EXPECT_LT(std::abs(r.scale_x - (1.0 - 0.0015)), 4 * r.sigma_scale_x);
    EXPECT_LT(std::abs(r.scale_y - (1.0 - 0.0015)), 4 * r.sigma_scale_y);
}

// The graded lines spread the lenslet images' light from none to full, and the light falls
// off across the photograph: judged from the 70th percentile of the light, the brightest
// images counted as bare sheet and the block slid a row onto the holder (study turn -0.3 deg
// of docs/results.md, refused).
TEST(PitchCalibration, KeepsTheArraysBrightestImagesInItsBlock) {
    Camera phone = framing_camera(small_array_fixture().printer.paper, 520.0, 0.78, 4000);
    phone.pose.tilt_deg = 28.0;
    phone.pose.turn_deg = -150.0;
    phone.pose.roll_deg = 4.0;
    phone.blur = 1.2;
    phone.vignetting = 0.3;
    phone.photons = 2500.0;
    phone.seed = 3;
    const std::vector<PitchReading> readings = small_array_readings(phone, {0.8, -0.6}, 0.0007, -0.3);
    const PitchCalibration r = calibrate_pitch(small_array_fixture().design, readings);
    EXPECT_LT(std::abs(r.scale_x - 1.0007), 1e-4);
    EXPECT_LT(std::abs(r.scale_y - 1.0007), 1e-4);
    EXPECT_LT(std::abs(r.scale_x - 1.0007), 4 * r.sigma_scale_x);
    EXPECT_LT(std::abs(r.scale_y - 1.0007), 4 * r.sigma_scale_y);
}

// A frontal photograph cannot tell the camera's height, which the small array's reading
// needs: refused, saying to tilt the camera.
TEST(PitchCalibration, RefusesAFrontalPhotographOfASmallArray) {
    EXPECT_THAT(error_of([&] { small_array_readings(frontal_camera(), Eigen::Vector2d::Zero()); }),
                AllOf(HasSubstr("x.jpg"), HasSubstr("frontal"), HasSubstr("20 to 40 deg")));
}

// The measured pitch goes into the design file the rest of rfd reads: a hexagonal array's
// one pitch, the rest of the file as it was.
// A scale read less finely than 0.005 % (a small array at a turn where its lenslets read few
// phases) is still given, and the report says how to read it finer; a fine one says nothing.
TEST(PitchCalibration, SaysHowToReadAnUncertainScaleFiner) {
    PitchCalibration calibration;
    calibration.design_pitch_x = 4.0;
    calibration.design_pitch_y = 4.8;
    calibration.sigma_scale_x = 2e-5;
    calibration.sigma_scale_y = 3e-5;
    calibration.rotation_deg = {0.4};  // one photograph's turn, as calibrate_pitch gives it
    calibration.sigma_rotation_deg = {0.002};
    calibration.shear_deg = {0.0};
    EXPECT_THAT(pitch_text(calibration, {PitchReading{}}), Not(HasSubstr("uncertain")));
    calibration.sigma_scale_x = 9e-5;
    const std::string text = pitch_text(calibration, {PitchReading{}});
    EXPECT_THAT(text, HasSubstr("+- 0.0090 %"));
    EXPECT_THAT(text, HasSubstr("uncertain beyond 0.005 %: turn the array a degree or two"));
}

TEST(PitchCalibration, WritesTheDesignWithTheMeasuredPitch) {
    const MoireFixture& f = moire_fixture();
    PitchCalibration calibration;
    calibration.design_pitch_x = print::moire_lattice(f.design).pitch_x();
    calibration.design_pitch_y = print::moire_lattice(f.design).pitch_y();
    calibration.scale_x = 1.0012;
    calibration.scale_y = 1.0010;
    calibration.sigma_scale_x = calibration.sigma_scale_y = 1e-5;
    const std::string text = calibrated_design_text(f.design, calibration, {PitchReading{}});
    const optics::Design calibrated = optics::parse_design(text, "calibrated.toml");
    EXPECT_NEAR(print::moire_lattice(calibrated).pitch_x(), calibration.design_pitch_x * 1.0011, 1e-6);
    EXPECT_EQ(calibrated.planes.size(), f.design.planes.size());
    EXPECT_THAT(text, HasSubstr("measured by rfd calibrate pitch"));
    EXPECT_EQ(text.find("lenses_per_cm2"), std::string::npos);
}

// Photographs it cannot read are refused with the reason, never a number.
TEST(PitchCalibration, RefusesPhotographsItCannotRead) {
    const MoireFixture& f = moire_fixture();
    // The array laid over the hypotheses, not the measuring bands.
    MoireScene away = mounted(0.001, 0.0);
    away.mounting.centre.y() += 150.0;
    const Image off_bands = stored_jpeg(simulated_moire_photo(f.design, f.sheet, f.printer, away, frontal_camera()));
    EXPECT_THAT(error_of([&] { read_pitch_photo(off_bands, "away.jpg", f.design, f.sheet); }),
                HasSubstr("away.jpg"));
    // Too blurred to see the marks.
    Camera blurred = frontal_camera();
    blurred.blur = 10.0;
    const Image soft = stored_jpeg(simulated_moire_photo(f.design, f.sheet, f.printer, mounted(0.0, 0.0), blurred));
    EXPECT_THAT(error_of([&] { read_pitch_photo(soft, "soft.jpg", f.design, f.sheet); }), HasSubstr("soft.jpg"));
    // Photographs of one band only cannot give the other axis.
    EXPECT_THAT(error_of([&] {
                    PitchReading only_x;
                    only_x.name = "x.jpg";
                    only_x.x.lenslets = 100;
                    calibrate_pitch(f.design, {only_x});
                }),
                HasSubstr("rows measuring band"));
}

}  // namespace
}  // namespace rfd::calibrate
