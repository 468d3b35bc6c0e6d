#include "relight/field.hpp"

#include <algorithm>
#include <cmath>
#include <cctype>
#include <cstdio>
#include <exception>
#include <fstream>
#include <sstream>
#include <tuple>
#include <utility>

#include "core/error.hpp"
#include "core/files.hpp"
#include "core/image_io.hpp"
#include "core/number.hpp"
#include "core/parallel.hpp"
#include "core/progress.hpp"
#include "core/text.hpp"
#include "relight/vision.hpp"
#include "core/units.hpp"

namespace rfd::relight {
namespace {

// The file name at the start of a light file's line, and the rest: the name's first word
// and every following word that is not a number (names with spaces, as Windows tools
// write them), kept with their spacing.
std::pair<std::string, std::string> split_name(const std::string& line) {
    std::size_t begin = line.find_first_not_of(" \t");
    std::size_t end = line.find_first_of(" \t", begin);
    while (end != std::string::npos) {
        const std::size_t next = line.find_first_not_of(" \t", end);
        if (next == std::string::npos) break;
        const std::size_t next_end = line.find_first_of(" \t", next);
        if (finite_number(line.substr(next, next_end == std::string::npos ? std::string::npos : next_end - next))) break;
        end = next_end;
    }
    if (end == std::string::npos) return {line.substr(begin), ""};
    return {line.substr(begin, end - begin), line.substr(end)};
}

// RTIBuilder writes the absolute Windows path of each image on the machine that took the
// capture: C:\Users\...\jpeg-exports\Bottle_001.jpg (or \\server\share\...).
bool is_windows_path(const std::string& name) {
    const bool drive = name.size() > 2 && std::isalpha(static_cast<unsigned char>(name[0])) && name[1] == ':' &&
                       (name[2] == '\\' || name[2] == '/');
    return drive || name.find('\\') != std::string::npos;
}

// Where the image a light file names is: relative to the light file's folder; a Windows
// path by its file name, in the light file's jpeg-exports/ folder if it is there, else next
// to the light file (where a reader that needs the image reports it missing). Light files
// are also read for their directions alone, so a missing image is not an error here.
std::filesystem::path image_path(const std::filesystem::path& folder, const std::string& name) {
    if (!is_windows_path(name)) return folder / name;
    const std::string file = name.substr(name.find_last_of("\\/") + 1);
    std::error_code ec;
    if (std::filesystem::is_regular_file(folder / file, ec)) return folder / file;
    if (std::filesystem::is_regular_file(folder / "jpeg-exports" / file, ec)) return folder / "jpeg-exports" / file;
    return folder / file;
}

}  // namespace

std::vector<LightEntry> read_light_file(const std::filesystem::path& lp_path) {
    std::ifstream in(lp_path);
    if (!in) throw IoError(SourceLocation{lp_path.string()}, "cannot open light file");
    std::string line;
    int line_number = 0;
    long declared = -1;
    std::vector<LightEntry> entries;
    int windows_names = 0, extra_lines = 0;
    while (std::getline(in, line)) {
        ++line_number;
        if (!line.empty() && line.back() == '\r') line.pop_back();  // files from Windows tools
        if (is_blank_or_comment(line)) continue;
        std::istringstream fields(line);
        if (declared < 0) {
            std::string extra;
            if (!(fields >> declared) || declared < 0 || (fields >> extra))
                throw InputError(line_in(lp_path, line_number),
                                 "expected the image count (a non-negative integer), got '" +
                                     line + "'");
            continue;
        }
        if (static_cast<long>(entries.size()) == declared) {
            // More lines than the count: readers of the format (RTIBuilder, relight) take the
            // first ones, so a stray last line does not lose the capture.
            ++extra_lines;
            continue;
        }
        LightEntry entry;
        entry.line = line_number;
        std::string rest;
        std::tie(entry.file, rest) = split_name(line);
        fields = std::istringstream(rest);
        double x = 0, y = 0, z = 0;
        if (!(fields >> x >> y >> z))
            throw InputError(line_in(lp_path, line_number),
                             "expected 'filename x y z [kernel_degrees]', got '" + line + "'");
        double kernel_degrees = 0.0;
        if (fields >> kernel_degrees) {
            if (!(kernel_degrees >= 0.0 && kernel_degrees < 180.0))
                throw InputError(line_in(lp_path, line_number),
                                 "kernel radius must be in [0, 180) degrees, got " +
                                     std::to_string(kernel_degrees));
        } else if (!fields.eof()) {
            throw InputError(line_in(lp_path, line_number),
                             "the fifth value (kernel radius in degrees) is not a number");
        }
        std::string extra;
        fields.clear();
        if (fields >> extra)
            throw InputError(line_in(lp_path, line_number), "unexpected extra value '" + extra + "'");
        const Eigen::Vector3d d(x, y, z);
        const double length = d.norm();
        if (!std::isfinite(length) || length < 1e-12)
            throw InputError(line_in(lp_path, line_number),
                             "light direction (" + std::to_string(x) + ", " + std::to_string(y) +
                                 ", " + std::to_string(z) + ") has zero length");
        // Unit directions are kept bit for bit, so a written field reads back identically.
        entry.direction = std::abs(length - 1.0) > 1e-12 ? Eigen::Vector3d(d / length) : d;
        entry.kernel_radius = degrees_to_radians(kernel_degrees);
        entry.path = image_path(lp_path.parent_path(), entry.file);
        windows_names += is_windows_path(entry.file);
        entries.push_back(entry);
    }
    if (windows_names > 0)
        Progress::note(lp_path.string() + ": its image names are Windows paths (as RTIBuilder writes them); read by "
                       "file name from " + (entries.front().path.parent_path().filename() == "jpeg-exports"
                                                ? std::string("its jpeg-exports/ folder")
                                                : std::string("its folder")));
    if (declared < 0) throw InputError(line_in(lp_path, line_number), "light file is empty");
    if (extra_lines > 0)
        Progress::note(lp_path.string() + ": declares " + std::to_string(declared) + " images but lists " +
                       std::to_string(declared + extra_lines) + "; reading the first " + std::to_string(declared) +
                       ", as RTIBuilder and relight do");
    if (static_cast<long>(entries.size()) != declared)
        throw InputError(line_in(lp_path, 1), "declares " + std::to_string(declared) +
                                             " images but lists " +
                                             std::to_string(entries.size()));
    return entries;
}

void write_light_file(const std::filesystem::path& lp_path, const std::vector<std::string>& files,
                      const std::vector<Eigen::Vector3d>& directions,
                      const std::vector<double>& kernel_radii) {
    RFD_CHECK(files.size() == directions.size());
    RFD_CHECK(kernel_radii.empty() || kernel_radii.size() == directions.size());
    std::string text = std::to_string(files.size()) + "\n";
    char buffer[160];
    for (std::size_t i = 0; i < files.size(); ++i) {
        const Eigen::Vector3d& d = directions[i];
        // 17 significant digits: directions survive the round trip bit for bit.
        std::snprintf(buffer, sizeof buffer, " %.17g %.17g %.17g", d.x(), d.y(), d.z());
        text += files[i] + buffer;
        if (!kernel_radii.empty()) {
            std::snprintf(buffer, sizeof buffer, " %.17g", radians_to_degrees(kernel_radii[i]));
            text += buffer;
        }
        text += "\n";
    }
    write_text_file(lp_path, text);
}

void check_field_images(const std::filesystem::path& lp_path, const std::vector<LightEntry>& entries) {
    ImageSize first;
    for (const LightEntry& entry : entries) {
        std::error_code ec;
        if (std::filesystem::exists(entry.path, ec) && !std::filesystem::is_regular_file(entry.path, ec))
            throw InputError(line_in(lp_path, entry.line),
                             "image '" + entry.file + "' (" + entry.path.string() + ") is not a regular file");
        ImageSize size;
        try {
            size = read_image_size(entry.path);
        } catch (const Error& error) {
            rethrow_at(error, line_in(lp_path, entry.line), "image '" + entry.file + "': " + error.what());
        }
        const auto text = [](const ImageSize& s) {
            return std::to_string(s.width) + " x " + std::to_string(s.height) + " pixels, " +
                   std::to_string(s.channels) + (s.channels == 1 ? " channel" : " channels");
        };
        if (&entry == &entries.front()) first = size;
        else if (size.width != first.width || size.height != first.height || size.channels != first.channels)
            throw InputError(line_in(lp_path, entry.line), "image '" + entry.file + "' is " + text(size) +
                                                          ", the field's first image '" + entries.front().file +
                                                          "' is " + text(first));
    }
}

std::filesystem::path light_file_of(const std::filesystem::path& field) {
    namespace fs = std::filesystem;
    std::error_code ec;
    if (!fs::is_directory(field, ec)) {
        if (!fs::exists(field, ec))
            throw IoError(SourceLocation{field.string()}, "no such field (folder or .lp file)");
        if (!fs::is_regular_file(field, ec))
            throw InputError(SourceLocation{field.string()},
                             "not a field: expected a folder or a regular .lp light file, not a device or pipe");
        return field;
    }
    std::vector<fs::path> found;
    for (const auto& entry : fs::directory_iterator(field, ec))
        if (entry.path().extension() == ".lp") found.push_back(entry.path());
    if (found.size() != 1)
        throw InputError(SourceLocation{field.string()},
                         found.empty() ? "folder holds no .lp light file"
                                       : "folder holds " + std::to_string(found.size()) +
                                             " .lp files; name the one to use");
    return found.front();
}

ImageWindow parse_region(const std::string& text, const std::string& option) {
    ImageWindow window;
    char tail = 0;
    if (std::sscanf(text.c_str(), "%d,%d,%d,%d%c", &window.x, &window.y, &window.width, &window.height, &tail) != 4 ||
        window.x < 0 || window.y < 0 || window.width <= 0 || window.height <= 0)
        throw InputError(option + ": expected X,Y,W,H in pixels (X, Y >= 0; W, H > 0), such as 120,40,800,600, got '" +
                         text + "'");
    return window;
}

namespace {

// The pixels of an image of `size` a window takes, and the size it scales them to; the
// errors name `name`, the image the window meets first.
struct WindowGeometry {
    int x = 0, y = 0, width = 0, height = 0;  // the region
    PlaneSize to;                              // after the scale
};

WindowGeometry window_geometry(const ImageWindow& window, int width, int height, const std::string& name) {
    if (!(window.scale > 0.0) || !std::isfinite(window.scale))
        throw InputError("--scale: expected a positive number, got " + std::to_string(window.scale));
    WindowGeometry g{0, 0, width, height, {width, height}};
    if (window.width > 0 || window.height > 0) {
        if (window.x + window.width > width || window.y + window.height > height)
            throw InputError(SourceLocation{name}, "--region " + std::to_string(window.x) + "," + std::to_string(window.y) +
                                                       "," + std::to_string(window.width) + "," +
                                                       std::to_string(window.height) + " reaches outside the " +
                                                       std::to_string(width) + " x " + std::to_string(height) +
                                                       " image");
        g = {window.x, window.y, window.width, window.height, {window.width, window.height}};
    }
    if (window.scale == 1.0) return g;
    g.to = {static_cast<int>(std::lround(g.width * window.scale)), static_cast<int>(std::lround(g.height * window.scale))};
    if (g.to.width < 1 || g.to.height < 1 || g.to.area() > (std::size_t{1} << 28))
        throw InputError(SourceLocation{name}, "--scale " + format_number(window.scale) + " makes the " +
                                                   std::to_string(g.width) + " x " + std::to_string(g.height) +
                                                   " image " + std::to_string(g.to.width) + " x " +
                                                   std::to_string(g.to.height) + " pixels");
    return g;
}

bool identity(const AxisResampling& axis) { return axis.from() == axis.to(); }

// Rows [y0, y1) of `image`, every column.
Image rows_of(const Image& image, int y0, int y1) {
    Image out(image.width(), y1 - y0, image.channels());
    for (int c = 0; c < image.channels(); ++c)
        std::copy_n(image.plane(c).data() + static_cast<std::size_t>(y0) * image.width(),
                    static_cast<std::size_t>(y1 - y0) * image.width(), out.plane(c).data());
    return out;
}

// `top` with `bottom`'s rows below it.
Image stacked(const Image& top, Image&& bottom) {
    if (top.empty()) return std::move(bottom);
    Image out(top.width(), top.height() + bottom.height(), top.channels());
    for (int c = 0; c < top.channels(); ++c) {
        float* to = std::copy(top.plane(c).begin(), top.plane(c).end(), out.plane(c).data());
        std::copy(bottom.plane(c).begin(), bottom.plane(c).end(), to);
    }
    return out;
}

}  // namespace

Image apply_window(const Image& image, const ImageWindow& window, const std::string& name) {
    if (window.whole()) return image;
    const WindowGeometry g = window_geometry(window, image.width(), image.height(), name);
    Image region(g.width, g.height, image.channels());
    for (int c = 0; c < image.channels(); ++c)
        for (int y = 0; y < g.height; ++y)
            for (int x = 0; x < g.width; ++x) region.at(x, y, c) = image.at(g.x + x, g.y + y, c);
    if (window.scale == 1.0) return region;
    return resample_band(region, 0, AxisResampling(g.width, g.to.width), AxisResampling(g.height, g.to.height), 0,
                         g.to.height);
}

// One image of a FieldReader: its file, open from the first band read until the last, and
// the region's rows already decoded that the next band reads again (a shrinking scale's
// bands share a source row; decoding never steps back).
struct FieldReader::Source {
    std::unique_ptr<ImageBandReader> file;
    Image carry;         // region rows [carry_y0, carry_y0 + carry.height()), the region's width
    int carry_y0 = 0;
};

FieldReader::FieldReader(const std::filesystem::path& field, const ImageWindow& window)
    : light_file_(light_file_of(field)), entries_(read_light_file(light_file_)) {
    if (entries_.empty()) throw InputError(line_in(light_file_, 1), "a field needs at least one image");
    check_field_images(light_file_, entries_);
    const LightEntry& front = entries_.front();
    const ImageFileSpec spec = ImageFileReader(front.path).spec();
    const ImageSize size{spec.width, spec.height, spec.channels};
    sample_type_ = spec.type;
    WindowGeometry g;
    try {
        g = window_geometry(window, size.width, size.height, front.path.string());
    } catch (const Error& error) {
        rethrow_at(error, line_in(light_file_, front.line), "image '" + front.file + "': " + error.what());
    }
    channels_ = size.channels;
    region_x_ = g.x;
    region_y_ = g.y;
    columns_ = AxisResampling(g.width, g.to.width);
    rows_ = AxisResampling(g.height, g.to.height);
    sources_.resize(entries_.size());
    // Every image is open while bands are read from it.
    raise_open_file_limit(entries_.size() + 64);
}

FieldReader::~FieldReader() = default;
FieldReader::FieldReader(FieldReader&&) noexcept = default;
FieldReader& FieldReader::operator=(FieldReader&&) noexcept = default;

std::vector<Eigen::Vector3d> FieldReader::directions() const {
    std::vector<Eigen::Vector3d> out;
    for (const LightEntry& entry : entries_) out.push_back(entry.direction);
    return out;
}

std::vector<double> FieldReader::kernel_radii() const {
    std::vector<double> out;
    for (const LightEntry& entry : entries_) out.push_back(entry.kernel_radius);
    if (std::all_of(out.begin(), out.end(), [](double radius) { return radius == 0.0; })) out.clear();
    return out;
}

int FieldReader::band_rows(std::size_t images, std::size_t extra_planes, std::size_t bytes) const {
    // A band's source rows, decoded before scaling, count too: at most one image's per thread,
    // bounded here by every image's.
    const double source_rows_per_row = std::max(1.0, static_cast<double>(rows_.from()) / rows_.to());
    const double per_row = sizeof(float) * (static_cast<double>(images) * channels_ *
                                                (width() + source_rows_per_row * columns_.from() / 4.0) +
                                            static_cast<double>(extra_planes) * width());
    // No one image's band above 16 MB either: blocks the allocator keeps for reuse (cli/main.cpp).
    const double image_rows = (16 << 20) / (sizeof(float) * static_cast<double>(channels_) * width());
    return static_cast<int>(std::clamp(std::min(static_cast<double>(bytes) / std::max(per_row, 1.0), image_rows), 1.0,
                                       static_cast<double>(height())));
}

std::vector<Image> FieldReader::read_band(int y0, int y1, const std::vector<bool>& wanted) {
    RFD_CHECK(0 <= y0 && y0 < y1 && y1 <= height() && (wanted.empty() || wanted.size() == size()));
    // The region's rows the band reads, and the first one the next band will read.
    const int first = rows_.first(y0), end = rows_.end(y1 - 1);
    const int keep_from = y1 < height() ? rows_.first(y1) : end;
    std::vector<Image> band(size());
    std::vector<std::exception_ptr> failures(size());
    parallel_for_chunks(size(), 1, [&](std::size_t begin, std::size_t stop) {
        for (std::size_t i = begin; i < stop; ++i) {
            if (!wanted.empty() && !wanted[i]) continue;
            try {
                if (!sources_[i]) sources_[i] = std::make_unique<Source>();
                Source& source = *sources_[i];
                const int carried_end = source.carry_y0 + source.carry.height();
                if (first < source.carry_y0 || (source.file == nullptr && carried_end < end)) {
                    // Back to the top, or the first band from this image: (re)open it.
                    source.carry = Image();
                    source.file = std::make_unique<ImageBandReader>(entries_[i].path);
                }
                const int carried = source.carry.empty() ? first : std::max(first, carried_end);
                Image rows = source.carry.empty() || carried_end <= first
                                 ? Image()
                                 : rows_of(source.carry, first - source.carry_y0, carried_end - source.carry_y0);
                if (carried < end)
                    rows = stacked(rows, source.file->read(region_y_ + carried, region_y_ + end, region_x_,
                                                           region_x_ + columns_.from()));
                if (keep_from < end) {
                    source.carry = rows_of(rows, keep_from - first, end - first);
                    source.carry_y0 = keep_from;
                } else {
                    source.carry = Image();
                    source.carry_y0 = end;
                }
                if (end == rows_.from()) source.file.reset();  // the image's last row is read
                band[i] = identity(columns_) && identity(rows_) ? std::move(rows)
                                                                : resample_band(rows, first, columns_, rows_, y0, y1);
            } catch (...) {
                failures[i] = std::current_exception();
            }
        }
    });
    for (std::size_t i = 0; i < size(); ++i) {
        if (!failures[i]) continue;
        try {
            std::rethrow_exception(failures[i]);
        } catch (const Error& error) {
            rethrow_at(error, line_in(light_file_, entries_[i].line),
                       "image '" + entries_[i].file + "': " + error.what());
        }
    }
    return band;
}

ReflectanceField read_field(const std::filesystem::path& field_path, const ImageWindow& window) {
    FieldReader reader(field_path, window);
    const LightEntry& front = reader.entries().front();
    try {
        check_whole_image_size(front.path, read_image_size(front.path));
    } catch (const Error& error) {
        rethrow_at(error, line_in(reader.light_file(), front.line), "image '" + front.file + "': " + error.what());
    }
    ReflectanceField field;
    field.directions = reader.directions();
    field.kernel_radii = reader.kernel_radii();
    field.images = reader.read_band(0, reader.height());
    return field;
}

FieldWriter::FieldWriter(std::filesystem::path folder, std::string name, std::string extension)
    : folder_(std::move(folder)), name_(std::move(name)), extension_(std::move(extension)) {
    ensure_directory(folder_);
    const std::filesystem::path lp = folder_ / (name_ + ".lp");
    std::error_code ec;
    std::filesystem::remove(lp, ec);
    if (ec) throw IoError(SourceLocation{lp.string()}, "cannot remove the light file of an earlier field: " + ec.message());
}

std::string FieldWriter::add(const Image& image, const Eigen::Vector3d& direction, double kernel_radius) {
    RFD_CHECK(!finished_);
    char number[32];
    std::snprintf(number, sizeof number, "_%04zu", files_.size());
    const std::string file = name_ + number + extension_;
    write_image(folder_ / file, image);
    files_.push_back(file);
    directions_.push_back(direction);
    kernel_radii_.push_back(kernel_radius);
    return file;
}

std::filesystem::path FieldWriter::finish() {
    RFD_CHECK(!finished_);
    finished_ = true;
    const bool any_kernel =
        std::any_of(kernel_radii_.begin(), kernel_radii_.end(), [](double radius) { return radius > 0.0; });
    const std::filesystem::path lp = folder_ / (name_ + ".lp");
    write_light_file(lp, files_, directions_, any_kernel ? kernel_radii_ : std::vector<double>{});
    return lp;
}

void write_field(const std::filesystem::path& folder, const ReflectanceField& field,
                 const std::string& name, const std::string& extension) {
    RFD_CHECK(field.images.size() == field.directions.size());
    FieldWriter out(folder, name, extension);
    for (std::size_t i = 0; i < field.size(); ++i) out.add(field.images[i], field.directions[i], field.kernel_radius(i));
    out.finish();
}

}  // namespace rfd::relight
