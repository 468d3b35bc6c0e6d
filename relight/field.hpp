#pragma once
// A reflectance field (thesis 2.4, 4.1): one linear image of a fixed-viewpoint scene per
// light direction, R_i(x, y) = R(x, y, theta_i, phi_i).
//
// Directions are unit vectors toward the light in the field frame of core/sphere.hpp (x
// right, y up in the image, z toward the camera). A two-level field (5.4) also records, per
// image, the angular radius of the light kernel it was taken with; 0 means a narrow light.
//
// On disk a field is a folder with an RTI-style light file `<name>.lp` and the images:
//     3
//     img_0000.exr 0.0 0.0 1.0
//     img_0001.exr 0.5 0.0 0.8660254
//     img_0002.exr 0.0 0.5 0.8660254 4.0
// First line the image count, then per image: file name (relative to the .lp's folder),
// the direction toward the light (normalised on reading) and optionally the kernel radius
// in degrees. Lines starting with '#' are comments.
//
// Light files of the field's other tools read as they are: CRLF line ends; file names
// with spaces (the last three numbers on a line are the direction); and RTIBuilder's
// absolute Windows paths (C:\Users\...\jpeg-exports\Bottle_001.jpg), which name a
// file on the machine that took the capture: rfd looks for that file name next to the
// .lp, then in its jpeg-exports/ folder, and says so once.
//
// Example: ReflectanceField field = read_field("out/bottle"); field.size();

#include <cstddef>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/image.hpp"
#include "core/image_file.hpp"
#include "core/options.hpp"
#include "core/resample.hpp"

namespace rfd::relight {

struct ReflectanceField {
    std::vector<Eigen::Vector3d> directions;  ///< unit, toward the light
    std::vector<Image> images;                ///< linear, all the same shape
    std::vector<double> kernel_radii;         ///< radians per image, or empty (all narrow)

    std::size_t size() const { return directions.size(); }
    int width() const { return images.empty() ? 0 : images.front().width(); }
    int height() const { return images.empty() ? 0 : images.front().height(); }
    int channels() const { return images.empty() ? 0 : images.front().channels(); }
    double kernel_radius(std::size_t i) const { return kernel_radii.empty() ? 0.0 : kernel_radii[i]; }
};

/// The part of a capture's images a field is made of, applied as each image is read: a
/// region of pixels (leaving out the calibration spheres and the frame a capture holds),
/// then a scale (0.5 halves each side, averaging; sizes round to whole pixels).
/// --scale of a command that reads a field, `scale` of a project's [source].
inline constexpr NumberOption kFieldScaleOption{"--scale", "scale", "", 0.01, 16.0, 1.0,
                                                "Scale every image of the field by this, after the region (0.5 "
                                                "halves; OpenCV INTER_AREA)"};

struct ImageWindow {
    int x = 0, y = 0;             ///< the region's top-left pixel
    int width = 0, height = 0;    ///< 0 x 0: the whole image
    double scale = kFieldScaleOption.fallback;  ///< > 0

    bool whole() const { return width == 0 && height == 0 && scale == 1.0; }
};
/// --region X,Y,W,H and --scale S as the command line and project files spell them;
/// InputError naming `option` otherwise.
ImageWindow parse_region(const std::string& text, const std::string& option);
/// `image` (named `name` in messages) through the window: InputError when the region
/// reaches outside it or the scale leaves no pixel.
Image apply_window(const Image& image, const ImageWindow& window, const std::string& name);

/// One line of a light file.
struct LightEntry {
    std::string file;                   ///< as written in the .lp
    std::filesystem::path path;         ///< the image it names (see the header)
    Eigen::Vector3d direction;          ///< normalised
    double kernel_radius = 0.0;         ///< radians
    int line = 0;                       ///< 1-based line in the .lp
};

/// Parses a light file. Throws InputError naming file and line for a bad count, a missing
/// field, an unparsable number or a zero-length direction; IoError if it cannot be read.
std::vector<LightEntry> read_light_file(const std::filesystem::path& lp_path);

/// Checks, from the files' headers alone, that every image `entries` names is a regular file
/// (not a folder, a device or a pipe) of the first image's size. InputError at the light
/// file's line naming the image and both sizes; IoError when one cannot be read.
void check_field_images(const std::filesystem::path& lp_path, const std::vector<LightEntry>& entries);

/// Writes directions (and kernel radii when `kernel_radii` is non-empty) as a light file.
void write_light_file(const std::filesystem::path& lp_path, const std::vector<std::string>& files,
                      const std::vector<Eigen::Vector3d>& directions,
                      const std::vector<double>& kernel_radii = {});

/// The light file of a field given as a folder (which must hold exactly one .lp) or as the
/// .lp itself.
std::filesystem::path light_file_of(const std::filesystem::path& field);

/// Reads a whole field (a FieldReader's one band of every row). Throws for any malformed
/// light file, a missing or unreadable image, images of different sizes, and non-finite
/// samples, naming the file and the .lp line. Each image goes through `window` as it is read.
ReflectanceField read_field(const std::filesystem::path& field, const ImageWindow& window = {});

/// A field read a band of rows at a time, for fields larger than memory: the images stay on
/// disk, each open while bands are read from it, and a band of rows is decoded from every
/// image it is asked of in parallel, through the window (region, then scale, as
/// apply_window(): the same samples as reading whole images). Bands read in ascending order
/// decode each image once.
//
// Example: FieldReader field("captures/coin", window);
//          for (int y = 0; y < field.height(); y += rows)
//              use(field.read_band(y, std::min(y + rows, field.height())));
class FieldReader {
public:
    /// Reads the light file and the images' headers; throws as read_field() does for a bad
    /// light file, a missing image, images of different sizes or a window outside them.
    explicit FieldReader(const std::filesystem::path& field, const ImageWindow& window = {});
    ~FieldReader();
    FieldReader(FieldReader&&) noexcept;
    FieldReader& operator=(FieldReader&&) noexcept;

    const std::filesystem::path& light_file() const { return light_file_; }
    const std::vector<LightEntry>& entries() const { return entries_; }
    std::size_t size() const { return entries_.size(); }
    std::vector<Eigen::Vector3d> directions() const;
    /// Radians per image, or empty when every light is narrow (ReflectanceField::kernel_radii).
    std::vector<double> kernel_radii() const;
    /// The field's images, through the window.
    int width() const { return columns_.to(); }
    int height() const { return rows_.to(); }
    int channels() const { return channels_; }
    /// How the first image stores its samples (UInt8: an 8-bit capture, JPEG or PNG).
    SampleType sample_type() const { return sample_type_; }

    /// Rows [y0, y1) of the images whose `wanted` entry is true (all when `wanted` is empty),
    /// linear; the others are left empty. Throws, naming the image and its line in the light
    /// file (the first in the file when several fail), for an unreadable image or a sample
    /// that is not finite.
    std::vector<Image> read_band(int y0, int y1, const std::vector<bool>& wanted = {});
    /// Rows a band may have so that `images` images of it, and `extra_planes` more planes of
    /// the field's width (outputs being made), take at most `bytes`; at least 1.
    int band_rows(std::size_t images, std::size_t extra_planes = 0, std::size_t bytes = kBandBytes) const;
    static constexpr std::size_t kBandBytes = std::size_t{256} << 20;

private:
    struct Source;
    std::filesystem::path light_file_;
    std::vector<LightEntry> entries_;
    int channels_ = 0;
    SampleType sample_type_ = SampleType::Float32;
    int region_x_ = 0, region_y_ = 0;
    AxisResampling columns_{1, 1}, rows_{1, 1};
    std::vector<std::unique_ptr<Source>> sources_;  // per image, open while bands are read
};

/// Writes a field into `folder` one image at a time, for fields too large to hold: open
/// (creates the folder and removes `<name>.lp` if an earlier run left one, since it would
/// list images being replaced), add each image as `<name>_NNNN<ext>`, finish (writes the
/// light file, last). Until finish() the folder holds no readable field, so an interrupted
/// write, or one that throws, never leaves a field mixing old and new images.
//
// Example: FieldWriter out("out/field");
//          for (...) out.add(image, direction);
//          out.finish();
class FieldWriter {
public:
    explicit FieldWriter(std::filesystem::path folder, std::string name = "field", std::string extension = ".exr");
    /// Writes `image` (the light toward unit `direction`, a kernel of `kernel_radius`
    /// radians, 0 for a narrow light) and returns its file name.
    std::string add(const Image& image, const Eigen::Vector3d& direction, double kernel_radius = 0.0);
    /// Writes the light file (with kernel radii when any is non-zero) and returns its path.
    std::filesystem::path finish();
    std::size_t size() const { return files_.size(); }

private:
    std::filesystem::path folder_;
    std::string name_, extension_;
    std::vector<std::string> files_;
    std::vector<Eigen::Vector3d> directions_;
    std::vector<double> kernel_radii_;
    bool finished_ = false;
};

/// Writes `field` to `folder` with a FieldWriter: `<name>.lp` plus `<name>_NNNN<ext>` images.
void write_field(const std::filesystem::path& folder, const ReflectanceField& field,
                 const std::string& name = "field", const std::string& extension = ".exr");

}  // namespace rfd::relight
