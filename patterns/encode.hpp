#pragma once
// The pattern encoder of thesis 8.4 for the observer-invariant Designs I and II: a
// reflectance field R(theta, phi, x, y) becomes a print-resolution transparency.
//
// For every printer dot (patterns/raster.hpp):
//   1. its lenslet: the lattice cell holding the dot's centre, centres computed from the
//      floating-point lattice (optics/lattice.hpp);
//   2. its offset s from the lenslet's axis on the pattern plane;
//   3. the incident direction d whose chief ray lands at s: the inverse map of
//      optics::DesignOptics, paraxial (closed form, s = B tan) or exact (Newton on the traced
//      map, tabulated once per design on a grid over one cell and interpolated bilinearly;
//      the table's error is measured by exact_table_error());
//   4. value = R(field direction of d, lenslet) / cos(kappa), kappa the angle of d to the
//      array's normal: less light falls into a lenslet under flat angles (the thesis's
//      factor). R between the field's light directions comes from the relighting
//      interpolation (relight/interpolation.hpp), R at a lenslet from the field's images
//      box-filtered over the lenslet's footprint.
// Dots outside every lenslet of the array are 0 (opaque).
//
// Display direction -> field direction. d travels from a light behind the display toward
// the observer (optics frame: x right, y up as the observer sees, z toward the observer).
// The light therefore sits at -d; the scene is lit as if that light stood in front of it
// at the same side and height: v = (-d_x, -d_y, d_z) in the field frame (core/sphere.hpp:
// x right, y up in the image, z toward the camera). A light above the display lights the
// scene from above. Then, as the thesis suggests, the angular range may be re-parameterised
// and the light rotated (it tilted the light by 45 degrees so the display shows the
// interesting highlights of a field lit from above):
//     v' = R_z(turn) R_x(-tilt) S(v),   S scales v's polar angle by angle_scale.
//
// Field image -> array. The field image is fitted to the array's extent ("cover": fills the
// array, cropping the image's longer side; "contain": all of the image, black borders;
// "stretch"), image x to the right and row 0 at the top as the observer sees the display.
//
// Example:
//   Encoder encoder(design, field, EncodeOptions{});
//   write_pattern("pattern.exr", encoder, encoder.attributes());

#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Core>

#include "core/options.hpp"
#include "optics/analysis.hpp"
#include "patterns/raster.hpp"
#include "relight/field.hpp"
#include "relight/interpolation.hpp"
#include "relight/light_model.hpp"

namespace rfd::patterns {

/// From display incident direction to field direction, see the header comment.
/// How a pattern maps display directions to field directions (AngularMapping below).
inline constexpr NumberOption kTiltOption{"--tilt", "tilt_deg", "deg", -90.0, 90.0, 0.0,
                                          "Rotate the display's axis this many degrees toward the field's up (the "
                                          "thesis used 45)"};
inline constexpr NumberOption kTurnOption{"--turn", "turn_deg", "deg", -360.0, 360.0, 0.0,
                                          "Then rotate about the field's axis"};
inline constexpr NumberOption kAngleScaleOption{"--angle-scale", "angle_scale", "", 0.05, 20.0, 1.0,
                                                "Field polar angle per display polar angle (re-parameterise the "
                                                "range)"};

struct AngularMapping {
    double tilt_deg = kTiltOption.fallback;            ///< rotation of the display's axis toward the field's +y
    double turn_deg = kTurnOption.fallback;            ///< then about the field's z axis, counter-clockwise
    double angle_scale = kAngleScaleOption.fallback;   ///< field polar angle = angle_scale * display polar angle

    /// Field direction (unit, toward the light) for a display incident direction (unit,
    /// direction of travel). May point below the field's horizon.
    Eigen::Vector3d field_direction(const Eigen::Vector3d& incident) const;
    /// The same with rotation() computed once, for loops over many directions.
    Eigen::Vector3d field_direction(const Eigen::Vector3d& incident, const Eigen::Matrix3d& rotation) const;
    /// R_z(turn) R_x(-tilt).
    Eigen::Matrix3d rotation() const;
    /// The inverse: the display incident direction a field direction comes from (z <= 0
    /// when no display direction maps there).
    Eigen::Vector3d display_direction(const Eigen::Vector3d& field) const;
};

/// The mapping a pattern was encoded with, from its rfd:tilt_deg, turn_deg and angle_scale
/// attributes (0, 0, 1 when absent). InputError naming `file` and the attribute otherwise.
AngularMapping mapping_of(const PatternFileInfo& info, const std::string& file);

enum class ImageFit { Cover, Contain, Stretch };
/// As the command line and a pattern's rfd:fit attribute spell them.
inline constexpr std::array kImageFitNames{Named{ImageFit::Cover, "cover"}, Named{ImageFit::Contain, "contain"},
                                           Named{ImageFit::Stretch, "stretch"}};

struct EncodeOptions {
    optics::Model model = optics::Model::Paraxial;
    relight::Interpolation interpolation = relight::Interpolation::Delaunay;
    AngularMapping mapping;
    ImageFit fit = ImageFit::Cover;
    /// Nodes per side of the exact model's inverse-map table over one cell.
    int exact_table_nodes = 257;
    /// Encode even where the field does not cover the display's range (the interpolation
    /// then extrapolates toward the horizon); otherwise that is an InputError.
    bool allow_partial_coverage = false;
    std::string field_name = "field";  ///< for messages
    /// The part of each field image used (--region, --scale), applied as it is read.
    relight::ImageWindow window;
    /// A fitted model between the field's lights (relight/light_model.hpp: a basis or rbf)
    /// instead of interpolating the images themselves: the field is replaced by what the model
    /// predicts at its own directions and three times as many more inside their hull (a
    /// Fibonacci spiral), which are then interpolated. None: the images themselves.
    std::optional<relight::LightModel> light_model;
};

/// The encoder's options as a pattern file's rfd: attributes record them, and back: model,
/// field, tilt_deg, turn_deg, angle_scale, interpolation, fit, and region (X,Y,W,H) and
/// scale when the field was read through a window, basis (and rbf_sigma, all its digits)
/// for a fitted light model. Numbers keep 6 significant
/// digits. Reading: absent attributes take the defaults of files written before they were
/// recorded (paraxial, no mapping, delaunay, cover); InputError naming `file` and the
/// attribute for a value it cannot read. The options read back allow partial coverage: a
/// reader needs every direction the pattern could show.
PatternAttributes encode_attributes(const EncodeOptions& options);
EncodeOptions encode_options_of(const PatternFileInfo& info, const std::string& file);

/// The display incident directions a design needs: those whose chief ray lands inside a
/// lenslet cell. `max_angle_rad` bounds them (from the cell's corners and edges).
struct DisplayRange {
    double max_angle_rad = 0.0;   ///< largest angle to the axis of any needed direction
    std::vector<Eigen::Vector3d> probes;  ///< display directions along the cell boundary and inside
};

/// Every field direction whose image the encoder can need for `design` under `options`:
/// indices into `field_directions`. Lets callers load only those images of a large field.
std::vector<std::size_t> needed_field_directions(const optics::Design& design,
                                                 const std::vector<Eigen::Vector3d>& field_directions,
                                                 const EncodeOptions& options);

/// `field` replaced as options.light_model says (see EncodeOptions); unchanged without one.
/// Returns what it did, for reports ("hsh3 fitted to the 48 lights, sampled at 192
/// directions").
std::string apply_light_model(relight::ReflectanceField& field, const EncodeOptions& options);

/// Loads a field from disk keeping only the images the encoder can need (see above), each
/// through options.window as it is read, then through options.light_model.
relight::ReflectanceField load_field_for(const optics::Design& design,
                                         const std::filesystem::path& field,
                                         const EncodeOptions& options);

class Encoder final : public PatternSource {
public:
    /// Prepares the tables: the design's optics, the inverse map (exact: tabulated), the
    /// field's triangulation and its samples at every lenslet. Throws InputError when the
    /// design is not Design I or II, when the field is empty, or when the field does not
    /// cover the display's angular range (unless allowed), naming the missing directions.
    Encoder(const optics::Design& design, const relight::ReflectanceField& field,
            const PatternGeometry& geometry, const EncodeOptions& options);
    ~Encoder() override;

    const PatternGeometry& geometry() const override { return geometry_; }
    int channels() const override { return channels_; }
    void render_row(int py, std::span<float> out) const override;

    /// The pattern value that should print as full transmittance: the 99.5th percentile
    /// of the brightest channel over a deterministic subsample of the dots inside lenslets.
    double white() const { return white_; }
    /// rfd: attributes for the pattern file: design, kind, model, mapping, white, ...
    PatternAttributes attributes() const;

    /// Incident direction (unit, travel) for a dot offset from its lenslet's centre, in
    /// the encoder's model (exact: from the table, clamped to its edge).
    Eigen::Vector3d incident_direction(const Eigen::Vector2d& offset) const;
    /// Largest angle (radians) between the tabulated exact inverse map and a direct Newton
    /// solve, over `samples` deterministic offsets inside the centre cell (0 for paraxial).
    double exact_table_error(int samples) const;
    /// The field's value at lenslet `cell` for field direction `index` (box-filtered).
    float lenslet_sample(optics::CellIndex cell, std::size_t index, int channel) const;
    /// The display directions the encoder covers and their range.
    const DisplayRange& display_range() const { return range_; }
    const optics::Lattice& lattice() const;
    const optics::DesignOptics& optics() const;
    const EncodeOptions& options() const { return options_; }
    const relight::SphericalInterpolator& interpolator() const;

    struct Tables;  // the prepared optics, field and lenslet samples (encode.cpp)

private:
    template <optics::LatticeKind K>
    void render_row_of(int py, std::span<float> out) const;

    std::unique_ptr<Tables> tables_;
    PatternGeometry geometry_;
    EncodeOptions options_;
    int channels_ = 0;
    double white_ = 1.0;
    DisplayRange range_;
};

/// The inverse check: for every lenslet and every field light direction whose chief ray
/// (through the encoder's model's forward map) lands at least `border_dots` inside the
/// lenslet's cell, the pattern value at the landing point (bilinear between dots) times
/// cos(kappa), against the field's own sample of that lenslet and direction.
struct DecodeComparison {
    std::size_t samples = 0;
    double mse = 0.0;
    double peak = 0.0;   ///< largest direct sample
    double psnr_db = 0.0;
};
DecodeComparison decode_and_compare(const Encoder& encoder, const std::vector<float>& pattern_rows,
                                    double border_dots = 1.5);

}  // namespace rfd::patterns
