#include "relight/fit_file.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <iterator>
#include <memory>
#include <string>

#include <Eigen/Eigenvalues>
#include <Eigen/QR>
#include <nlohmann/json.hpp>

#include "core/error.hpp"
#include "core/files.hpp"
#include "core/image_file.hpp"
#include "core/image_io.hpp"
#include "core/parallel.hpp"
#include "core/progress.hpp"
#include "relight/field.hpp"
#include "relight/light_model.hpp"

namespace rfd::relight {
namespace {

constexpr const char* kInfo = "info.json";
// Pixels sampled for the planes' ranges and rbf's components: CNR relight samples 2^16.
constexpr int kSampleRows = 256, kSampleColumns = 256;
// The share of a plane's sampled values its range holds (CNR relight's rangeQuantile).
constexpr double kRangeQuantile = 0.995;


// A field sample in the fit's units: display (sRGB-encoded, 0..1) or linear.
float in_units(float linear, bool exact) {
    return exact ? linear : linear_to_srgb(std::clamp(linear, 0.0f, 1.0f));
}

// The 3 n samples of every pixel of `band` (light-major, channel-minor), in the fit's units:
// column k is pixel k (of columns `columns` of each row, or every column when empty).
Eigen::MatrixXd pixel_vectors(const std::vector<Image>& band, const std::vector<int>& columns, bool exact) {
    const Image& shape = band.front();
    const int channels = shape.channels();
    const std::size_t n = band.size();
    const auto width = static_cast<std::size_t>(shape.width());
    const std::size_t per_row = columns.empty() ? width : columns.size();
    const std::size_t pixels = per_row * static_cast<std::size_t>(shape.height());
    Eigen::MatrixXd x(static_cast<Eigen::Index>(3 * n), static_cast<Eigen::Index>(pixels));
    for (std::size_t i = 0; i < n; ++i)
        for (int c = 0; c < 3; ++c) {
            const std::span<const float> plane = band[i].plane(channels == 1 ? 0 : c);
            const auto r = static_cast<Eigen::Index>(3 * i + static_cast<std::size_t>(c));
            for (int y = 0; y < shape.height(); ++y)
                for (std::size_t k = 0; k < per_row; ++k) {
                    const std::size_t column = columns.empty() ? k : static_cast<std::size_t>(columns[k]);
                    x(r, static_cast<Eigen::Index>(static_cast<std::size_t>(y) * per_row + k)) =
                        in_units(plane[static_cast<std::size_t>(y) * width + column], exact);
                }
        }
    return x;
}

// Evenly spread indices in [0, count), at most `most` of them.
std::vector<int> spread(int count, int most) {
    const int taken = std::min(count, most);
    std::vector<int> out;
    for (int i = 0; i < taken; ++i) out.push_back(static_cast<int>((i + 0.5) * count / taken));
    return out;
}

// The affine map from a pixel's 3 n samples x to its planes: matrix x + shift.
struct PlaneMap {
    Eigen::MatrixXd matrix;  // nplanes x 3 n
    Eigen::VectorXd shift;   // nplanes

    Eigen::MatrixXd operator()(const Eigen::MatrixXd& x) const { return (matrix * x).colwise() + shift; }
};

PlaneMap basis_plane_map(const BasisFit& fit, std::size_t n) {
    const int functions = fit.size();
    PlaneMap map{Eigen::MatrixXd::Zero(3 * functions, static_cast<Eigen::Index>(3 * n)),
                 Eigen::VectorXd::Zero(3 * functions)};
    for (int j = 0; j < functions; ++j)
        for (int c = 0; c < 3; ++c)
            for (std::size_t i = 0; i < n; ++i)
                map.matrix(3 * j + c, static_cast<Eigen::Index>(3 * i) + c) = fit.solve()(j, static_cast<Eigen::Index>(i));
    return map;
}

// Pixel vectors at the bilinear grid's nodes from those at the lights: row 3 g + c of the
// result is sum_i M(g, i) x(3 i + c), i.e. (M kron I3) x.
Eigen::MatrixXd node_matrix(const Eigen::MatrixXd& grid) {
    Eigen::MatrixXd k = Eigen::MatrixXd::Zero(3 * grid.rows(), 3 * grid.cols());
    for (Eigen::Index g = 0; g < grid.rows(); ++g)
        for (Eigen::Index i = 0; i < grid.cols(); ++i)
            for (int c = 0; c < 3; ++c) k(3 * g + c, 3 * i + c) = grid(g, i);
    return k;
}

// The principal components of the sampled pixel vectors `x` (3 nodes x P), quantised to
// bytes as the format stores them unless exact; fills the file's mean, components, range
// and basis bytes, and returns the map to the planes (least squares onto the components as
// stored) and the share of variance kept.
PlaneMap principal_components(const Eigen::MatrixXd& x, FitFile& file, std::vector<int>& basis_bytes,
                              double& kept_variance) {
    const Eigen::Index dims = x.rows();
    const auto n = static_cast<std::size_t>(dims / 3);
    Eigen::VectorXd mean = x.rowwise().mean();
    if (!file.exact) mean = mean.cwiseMax(0.0).cwiseMin(1.0);
    const Eigen::MatrixXd centred = x.colwise() - mean;
    const Eigen::MatrixXd covariance = centred * centred.transpose() / static_cast<double>(x.cols());
    const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> solver(covariance);
    const int planes = file.nplanes;
    Eigen::MatrixXd components(dims, planes);
    double kept = 0.0;
    for (int p = 0; p < planes; ++p) {
        const Eigen::Index column = dims - 1 - p;  // eigenvalues ascend
        Eigen::VectorXd e = solver.eigenvectors().col(column);
        Eigen::Index largest = 0;
        e.cwiseAbs().maxCoeff(&largest);
        if (e[largest] < 0.0) e = -e;  // a fixed sign, for identical files
        components.col(p) = e;
        kept += std::max(0.0, solver.eigenvalues()[column]);
    }
    const double total = std::max(solver.eigenvalues().sum(), 1e-300);
    kept_variance = std::min(1.0, kept / total);
    file.range.assign(static_cast<std::size_t>(planes), 1.0);
    basis_bytes.clear();
    if (!file.exact) {
        for (Eigen::Index k = 0; k < dims; ++k) {
            const int byte = static_cast<int>(std::clamp(std::lround(mean[k] * 255.0), 0L, 255L));
            basis_bytes.push_back(byte);
            mean[k] = byte / 255.0;
        }
        for (int p = 0; p < planes; ++p) {
            const double largest = std::max(components.col(p).cwiseAbs().maxCoeff(), 1e-12);
            const double range = 127.0 / largest;
            file.range[static_cast<std::size_t>(p)] = range;
            for (Eigen::Index k = 0; k < dims; ++k) {
                const int byte = static_cast<int>(std::clamp(std::lround(127.0 + range * components(k, p)), 0L, 255L));
                basis_bytes.push_back(byte);
                components(k, p) = (byte - 127) / range;
            }
        }
    }
    file.mean.resize(static_cast<Eigen::Index>(n), 3);
    file.components.assign(static_cast<std::size_t>(planes), Eigen::MatrixXd(static_cast<Eigen::Index>(n), 3));
    for (std::size_t i = 0; i < n; ++i)
        for (int c = 0; c < 3; ++c) {
            const auto k = static_cast<Eigen::Index>(3 * i) + c, row = static_cast<Eigen::Index>(i);
            file.mean(row, c) = mean[k];
            for (int p = 0; p < planes; ++p) file.components[static_cast<std::size_t>(p)](row, c) = components(k, p);
        }
    // Least squares onto the components as stored (orthonormal only before quantisation).
    const Eigen::MatrixXd map = components.colPivHouseholderQr().solve(Eigen::MatrixXd::Identity(dims, dims));
    return {map, -(map * mean)};
}

nlohmann::json info_json(const FitFile& file, const std::vector<int>& basis_bytes) {
    nlohmann::json info = {{"width", file.width},
                           {"height", file.height},
                           {"format", file.exact ? "exr" : "jpg"},
                           {"type", fit_type_name(file.type)},
                           {"colorspace", file.principal() ? "mrgb" : "rgb"},
                           {"nplanes", file.nplanes},
                           {"quality", file.quality}};
    if (file.exact) info["linear"] = true;
    nlohmann::json lights = nlohmann::json::array();
    for (const Eigen::Vector3d& d : file.lights)
        for (int c = 0; c < 3; ++c) lights.push_back(d[c]);
    if (file.principal()) info["sigma"] = file.sigma;  // bilinear: its prior's, for the record
    if (file.type == FitType::Bilinear) info["resolution"] = file.resolution;
    info["lights"] = std::move(lights);
    if (file.principal()) {
        if (file.exact) {
            nlohmann::json basis = nlohmann::json::array();
            const auto add = [&](const Eigen::MatrixXd& m) {
                for (Eigen::Index i = 0; i < m.rows(); ++i)
                    for (int c = 0; c < 3; ++c) basis.push_back(m(i, c));
            };
            add(file.mean);
            for (const Eigen::MatrixXd& e : file.components) add(e);
            info["basis"] = std::move(basis);
        } else {
            info["basis"] = basis_bytes;
        }
    }
    nlohmann::json material = {{"scale", file.scale}, {"bias", file.bias}};
    if (file.principal()) material["range"] = file.range;
    info["materials"] = nlohmann::json::array({material});
    return info;
}

// Plane files of a fit, written a band of rows at a time.
class PlaneWriters {
public:
    PlaneWriters(const std::filesystem::path& folder, const FitFile& file) : exact_(file.exact) {
        for (int j = 0; j < file.jpegs(); ++j) {
            ImageFileSpec spec;
            spec.width = file.width;
            spec.height = file.height;
            spec.channels = 3;
            spec.type = exact_ ? SampleType::Float32 : SampleType::UInt8;
            if (!exact_) {
                spec.compression = "jpeg:" + std::to_string(file.quality);
                spec.jpeg_subsampling = "4:4:4";  // packed planes, not chroma: keep every sample
            }
            writers_.push_back(std::make_unique<ImageFileWriter>(file.plane_file(folder, j), spec, "fit plane"));
        }
    }
    // values: nplanes x (pixels of rows [y0, y1)), quantised already unless exact.
    void write(int y0, int y1, const Eigen::MatrixXd& values) {
        const auto pixels = static_cast<std::size_t>(values.cols());
        for (std::size_t j = 0; j < writers_.size(); ++j) {
            if (exact_) floats_.assign(3 * pixels, 0.0f);
            else bytes_.assign(3 * pixels, 0);
            for (int c = 0; c < 3; ++c) {
                const auto p = static_cast<Eigen::Index>(3 * j) + c;
                if (p >= values.rows()) continue;
                for (std::size_t k = 0; k < pixels; ++k) {
                    const double v = values(p, static_cast<Eigen::Index>(k));
                    if (exact_) floats_[3 * k + static_cast<std::size_t>(c)] = static_cast<float>(v);
                    else bytes_[3 * k + static_cast<std::size_t>(c)] = static_cast<std::uint8_t>(v);
                }
            }
            if (exact_) writers_[j]->write_rows(y0, y1, SampleType::Float32, floats_.data());
            else writers_[j]->write_rows(y0, y1, SampleType::UInt8, bytes_.data());
        }
    }
    void finish() {
        for (auto& writer : writers_) writer->finish();
    }

private:
    bool exact_;
    std::vector<std::unique_ptr<ImageFileWriter>> writers_;
    std::vector<float> floats_;
    std::vector<std::uint8_t> bytes_;
};

// The values of a quantile of `values` (sorted in place).
double quantile(std::vector<double>& values, double q) {
    const auto index = static_cast<std::size_t>(std::min(q * static_cast<double>(values.size()),
                                                         static_cast<double>(values.size() - 1)));
    std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(index), values.end());
    return values[index];
}

double number_at(const nlohmann::json& info, const char* key, const std::string& where) {
    if (!info.contains(key) || !info[key].is_number())
        throw InputError(SourceLocation{where}, std::string("field '") + key + "': expected a number");
    return info[key].get<double>();
}

std::vector<double> numbers_at(const nlohmann::json& object, const char* key, std::size_t count,
                               const std::string& where) {
    if (!object.contains(key) || !object[key].is_array() || object[key].size() != count)
        throw InputError(SourceLocation{where}, std::string("field '") + key + "': expected an array of " +
                                                    std::to_string(count) + " numbers");
    std::vector<double> out;
    for (const auto& v : object[key]) {
        if (!v.is_number())
            throw InputError(SourceLocation{where}, std::string("field '") + key + "': expected numbers only");
        out.push_back(v.get<double>());
    }
    return out;
}

}  // namespace

const char* fit_type_name(FitType type) {
    switch (type) {
    case FitType::Ptm: return "ptm";
    case FitType::Hsh: return "hsh";
    case FitType::Rbf: return "rbf";
    case FitType::Bilinear: return "bilinear";
    }
    return "";
}

std::filesystem::path FitFile::plane_file(const std::filesystem::path& folder, int j) const {
    return folder / ("plane_" + std::to_string(j) + (exact ? ".exr" : ".jpg"));
}

void FitFile::light_weights(const Eigen::Vector3d& d, Eigen::Matrix3Xd& weights, Eigen::Vector3d& offset) const {
    weights = Eigen::Matrix3Xd::Zero(3, nplanes);
    offset.setZero();
    if (!principal()) {
        const Eigen::VectorXd b = basis_values(basis, d.normalized());
        for (Eigen::Index j = 0; j < b.size(); ++j)
            for (int c = 0; c < 3; ++c) weights(c, 3 * j + c) = b[j];
        return;
    }
    // The nodes' weights: radial over the lights, or bilinear between four grid nodes.
    Eigen::VectorXd w;
    if (type == FitType::Rbf) {
        w = rbf_weights(lights, sigma, d.normalized());
    } else {
        w = Eigen::VectorXd::Zero(mean.rows());
        const GridCell cell = octahedral_cell(d.normalized(), resolution);
        for (int k = 0; k < 4; ++k) w[cell.node[k]] += cell.weight[k];
    }
    offset = mean.transpose() * w;
    for (int p = 0; p < nplanes; ++p) weights.col(p) = components[static_cast<std::size_t>(p)].transpose() * w;
}

FitFile read_fit(const std::filesystem::path& folder) {
    const std::filesystem::path path =
        std::filesystem::is_directory(folder) ? folder / kInfo : folder;
    const std::string where = path.string();
    nlohmann::json info;
    try {
        info = nlohmann::json::parse(read_text_file(path));
    } catch (const nlohmann::json::exception& e) {
        throw InputError(SourceLocation{where}, std::string("not valid JSON: ") + e.what());
    }
    if (!info.is_object()) throw InputError(SourceLocation{where}, "expected a JSON object");
    FitFile file;
    file.width = static_cast<int>(number_at(info, "width", where));
    file.height = static_cast<int>(number_at(info, "height", where));
    if (file.width <= 0 || file.height <= 0 || file.width > (1 << 20) || file.height > (1 << 20))
        throw InputError(SourceLocation{where}, "fields 'width', 'height': expected positive sizes");
    const std::string type = info.value("type", ""), colorspace = info.value("colorspace", "");
    file.nplanes = static_cast<int>(number_at(info, "nplanes", where));
    file.exact = info.value("format", "jpg") == "exr";
    file.quality = static_cast<int>(info.value("quality", 95));
    if (info.contains("lights")) {
        if (!info["lights"].is_array() || info["lights"].size() % 3 != 0)
            throw InputError(SourceLocation{where}, "field 'lights': expected x, y, z per light");
        const std::vector<double> xyz = numbers_at(info, "lights", info["lights"].size(), where);
        for (std::size_t i = 0; i < xyz.size(); i += 3) file.lights.emplace_back(xyz[i], xyz[i + 1], xyz[i + 2]);
    }
    if (type == "ptm" || type == "hsh") {
        if (colorspace != "rgb")
            throw InputError(SourceLocation{where}, "field 'colorspace': rfd reads ptm and hsh fits in 'rgb', got '" +
                                                        colorspace + "'");
        file.type = type == "ptm" ? FitType::Ptm : FitType::Hsh;
        const int functions = file.nplanes / 3;
        if (file.nplanes % 3 != 0 || (type == "ptm" && functions != 6) ||
            (type == "hsh" && functions != 4 && functions != 9 && !(file.exact && functions == 16)))
            throw InputError(SourceLocation{where}, "field 'nplanes': " + std::to_string(file.nplanes) +
                                                        " planes do not make a " + type +
                                                        " fit (ptm: 18; hsh: 12 or 27)");
        file.basis = type == "ptm" ? Basis::Ptm : functions == 4 ? Basis::Hsh2 : functions == 9 ? Basis::Hsh3
                                                                                                 : Basis::Hsh4;
    } else if (type == "rbf") {
        if (colorspace != "mrgb")
            throw InputError(SourceLocation{where}, "field 'colorspace': rfd reads rbf fits in 'mrgb', got '" +
                                                        colorspace + "'");
        file.type = FitType::Rbf;
        file.sigma = number_at(info, "sigma", where);
        if (!(file.sigma > 0.0)) throw InputError(SourceLocation{where}, "field 'sigma': expected a positive width");
        if (file.lights.empty()) throw InputError(SourceLocation{where}, "field 'lights': an rbf fit needs its lights");
        if (file.nplanes <= 0) throw InputError(SourceLocation{where}, "field 'nplanes': expected at least 1");
    } else if (type == "bilinear") {
        if (colorspace != "mrgb")
            throw InputError(SourceLocation{where}, "field 'colorspace': rfd reads bilinear fits in 'mrgb', got '" +
                                                        colorspace + "'");
        file.type = FitType::Bilinear;
        file.resolution = static_cast<int>(number_at(info, "resolution", where));
        if (file.resolution < 2 || file.resolution > 256)
            throw InputError(SourceLocation{where}, "field 'resolution': expected a grid side of 2 to 256, got " +
                                                        std::to_string(file.resolution));
        file.sigma = info.value("sigma", 0.0);
        if (file.nplanes <= 0) throw InputError(SourceLocation{where}, "field 'nplanes': expected at least 1");
    } else {
        throw InputError(SourceLocation{where}, "field 'type': expected ptm, hsh, rbf or bilinear, got '" + type + "'");
    }
    const auto planes = static_cast<std::size_t>(file.nplanes);
    if (!info.contains("materials") || !info["materials"].is_array() || info["materials"].empty())
        throw InputError(SourceLocation{where}, "field 'materials': expected one material");
    if (info["materials"].size() > 1)
        throw InputError(SourceLocation{where}, "field 'materials': rfd reads fits of one material (no segments.png)");
    const nlohmann::json& material = info["materials"][0];
    file.scale = numbers_at(material, "scale", planes, where);
    file.bias = numbers_at(material, "bias", planes, where);
    if (file.principal()) {
        const std::size_t n = file.type == FitType::Rbf ? file.lights.size()
                                                         : static_cast<std::size_t>(file.resolution * file.resolution);
        const std::size_t count = (planes + 1) * n * 3;
        const std::vector<double> basis = numbers_at(info, "basis", count, where);
        if (!file.exact) file.range = numbers_at(material, "range", planes, where);
        else file.range.assign(planes, 1.0);
        file.mean.resize(static_cast<Eigen::Index>(n), 3);
        file.components.assign(planes, Eigen::MatrixXd(static_cast<Eigen::Index>(n), 3));
        for (std::size_t p = 0; p <= planes; ++p)
            for (std::size_t i = 0; i < n; ++i)
                for (int c = 0; c < 3; ++c) {
                    const double v = basis[(p * n + i) * 3 + static_cast<std::size_t>(c)];
                    const auto row = static_cast<Eigen::Index>(i);
                    if (p == 0) file.mean(row, c) = file.exact ? v : v / 255.0;
                    else file.components[p - 1](row, c) = file.exact ? v : (v - 127.0) / file.range[p - 1];
                }
    }
    for (std::size_t p = 0; p < planes; ++p)
        if (!std::isfinite(file.scale[p]) || !std::isfinite(file.bias[p]) ||
            (!file.range.empty() && !(std::isfinite(file.range[p]) && file.range[p] != 0.0)))
            throw InputError(SourceLocation{where}, "field 'materials': plane " + std::to_string(p) +
                                                        " has a scale, bias or range that is not a finite number");
    for (const Eigen::Vector3d& d : file.lights)
        if (!d.allFinite() || d.norm() == 0.0)
            throw InputError(SourceLocation{where}, "field 'lights': a light that is not a direction");
    const std::filesystem::path dir = path.parent_path();
    for (int j = 0; j < file.jpegs(); ++j) {
        const std::filesystem::path plane = file.plane_file(dir, j);
        const ImageSize size = read_image_size(plane);
        if (size.width != file.width || size.height != file.height || size.channels != 3)
            throw InputError(SourceLocation{plane.string()},
                             "a plane of " + std::to_string(size.width) + " x " + std::to_string(size.height) + " x " +
                                 std::to_string(size.channels) + "; info.json says " + std::to_string(file.width) +
                                 " x " + std::to_string(file.height) + " x 3");
    }
    return file;
}

FitReport fit_field(FieldReader& field, const FitSpec& spec, const std::filesystem::path& folder) {
    const std::size_t n = field.size();
    if (field.channels() != 1 && field.channels() != 3)
        throw InputError(SourceLocation{field.light_file().string()},
                         "a fit holds colour (3 channels) or grey; the field has " + std::to_string(field.channels()) +
                             " channels");
    FitReport report;
    FitFile& file = report.file;
    file.type = spec.type;
    file.basis = spec.basis;
    file.width = field.width();
    file.height = field.height();
    file.exact = spec.exact;
    file.quality = spec.quality;
    file.lights = field.directions();
    if (spec.quality < 1 || spec.quality > 100) throw InputError("--quality: expected 1 to 100");
    if (spec.type == FitType::Ptm && spec.basis != Basis::Ptm) throw InputError("a ptm fit has the ptm basis");
    if (spec.type == FitType::Hsh && (spec.basis == Basis::Ptm || (spec.basis == Basis::Hsh4 && !spec.exact)))
        throw InputError("hsh4 (16 functions) is beyond what OpenLIME renders (hsh3, 9): fit it with --exact, "
                         "or choose hsh2 or hsh3");

    // The sample: evenly spread rows and columns.
    const std::vector<int> rows = spread(file.height, kSampleRows), columns = spread(file.width, kSampleColumns);
    Eigen::MatrixXd sample(static_cast<Eigen::Index>(3 * n), 0);
    {
        std::vector<Eigen::MatrixXd> parts;
        Progress progress("sampling the field", rows.size());
        for (const int y : rows) {
            parts.push_back(pixel_vectors(field.read_band(y, y + 1), columns, spec.exact));
            progress.advance();
        }
        progress.finish();
        sample.resize(static_cast<Eigen::Index>(3 * n), static_cast<Eigen::Index>(parts.size() * columns.size()));
        for (std::size_t r = 0; r < parts.size(); ++r)
            sample.middleCols(static_cast<Eigen::Index>(r * columns.size()), parts[r].cols()) = parts[r];
    }
    report.sampled_pixels = static_cast<std::size_t>(sample.cols());

    PlaneMap map;
    std::vector<int> basis_bytes;
    if (spec.type == FitType::Rbf || spec.type == FitType::Bilinear) {
        const bool bilinear = spec.type == FitType::Bilinear;
        LightModel model = parse_light_model(fit_type_name(spec.type));
        model.resolution = spec.resolution;
        file.resolution = bilinear ? spec.resolution : 0;
        const std::size_t nodes = bilinear ? static_cast<std::size_t>(spec.resolution * spec.resolution) : n;
        const int most = static_cast<int>(std::min<std::size_t>(3 * nodes, report.sampled_pixels));
        if (spec.planes < 1 || spec.planes > most)
            throw InputError(std::string("--planes: ") + (bilinear ? "a bilinear" : "an rbf") + " fit of " + std::to_string(nodes) +
                             (bilinear ? " grid nodes" : " lights") + " keeps 1 to " + std::to_string(most) +
                             " components, got " + std::to_string(spec.planes));
        file.nplanes = spec.planes;
        file.sigma = spec.sigma;
        if (file.sigma <= 0.0) {
            FieldGram gram;
            gram.gram = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(n), static_cast<Eigen::Index>(n));
            for (int c = 0; c < 3; ++c) {
                Eigen::MatrixXd channel(static_cast<Eigen::Index>(n), sample.cols());
                for (std::size_t i = 0; i < n; ++i)
                    channel.row(static_cast<Eigen::Index>(i)) = sample.row(static_cast<Eigen::Index>(3 * i) + c);
                gram.gram += channel * channel.transpose();
            }
            file.sigma = best_sigma(gram, file.lights, model);
        }
        if (bilinear) {
            // The components of the samples resampled at the grid's nodes, then the map from a
            // pixel's samples at the lights through the nodes to the planes.
            model.sigma = file.sigma;
            const Eigen::MatrixXd to_nodes = node_matrix(LightWeights(model, file.lights).grid());
            map = principal_components(to_nodes * sample, file, basis_bytes, report.kept_variance);
            map.matrix = map.matrix * to_nodes;
        } else {
            map = principal_components(sample, file, basis_bytes, report.kept_variance);
        }
    } else {
        const BasisFit fit(spec.basis, file.lights);
        file.nplanes = 3 * fit.size();
        map = basis_plane_map(fit, n);
    }
    const auto planes = static_cast<std::size_t>(file.nplanes);

    // Ranges from the sample's planes (display fits); the exact variant keeps floats.
    file.scale.assign(planes, 1.0);
    file.bias.assign(planes, 0.0);
    if (!spec.exact) {
        const Eigen::MatrixXd values = map(sample);
        for (std::size_t p = 0; p < planes; ++p) {
            std::vector<double> v(static_cast<std::size_t>(values.cols()));
            for (Eigen::Index k = 0; k < values.cols(); ++k)
                v[static_cast<std::size_t>(k)] = values(static_cast<Eigen::Index>(p), k);
            const double lo = quantile(v, (1.0 - kRangeQuantile) / 2.0);
            const double hi = std::max(quantile(v, (1.0 + kRangeQuantile) / 2.0), lo + 1e-6);
            file.scale[p] = hi - lo;
            file.bias[p] = -lo / (hi - lo);
        }
    }

    // Every pixel, a band of rows at a time.
    ensure_directory(folder);
    std::filesystem::remove(folder / kInfo);
    PlaneWriters writers(folder, file);
    const int band_rows = field.band_rows(n, 3 * n + planes);
    Progress progress("fitting", static_cast<std::size_t>((file.height + band_rows - 1) / band_rows));
    std::size_t clipped = 0;
    for (int y0 = 0; y0 < file.height; y0 += band_rows) {
        const int y1 = std::min(file.height, y0 + band_rows);
        const Eigen::MatrixXd x = pixel_vectors(field.read_band(y0, y1), {}, spec.exact);
        Eigen::MatrixXd values(static_cast<Eigen::Index>(planes), x.cols());
        const std::size_t blocks = (static_cast<std::size_t>(x.cols()) + 1023) / 1024;
        std::vector<std::size_t> block_clipped(blocks, 0);
        parallel_for_chunks(blocks, 1, [&](std::size_t begin, std::size_t end) {
            for (std::size_t b = begin; b < end; ++b) {
                const auto first = static_cast<Eigen::Index>(b * 1024);
                const Eigen::Index count = std::min<Eigen::Index>(1024, x.cols() - first);
                Eigen::MatrixXd v = map(x.middleCols(first, count));
                if (!spec.exact)
                    for (Eigen::Index k = 0; k < count; ++k)
                        for (std::size_t p = 0; p < planes; ++p) {
                            const auto P = static_cast<Eigen::Index>(p);
                            const double code = std::round(255.0 * (v(P, k) / file.scale[p] + file.bias[p]));
                            if (code < 0.0 || code > 255.0) ++block_clipped[b];
                            v(P, k) = std::clamp(code, 0.0, 255.0);
                        }
                values.middleCols(first, count) = v;
            }
        });
        for (const std::size_t c : block_clipped) clipped += c;
        writers.write(y0, y1, values);
        progress.advance();
    }
    writers.finish();
    progress.finish();
    report.clipped = clipped;
    // One key a line, as relight-cli writes it: readable, and short for the long arrays.
    const nlohmann::json info = info_json(file, basis_bytes);
    std::string text = "{\n";
    for (auto it = info.begin(); it != info.end(); ++it)
        text += " \"" + it.key() + "\": " + it.value().dump() + (std::next(it) == info.end() ? "\n" : ",\n");
    write_text_file(folder / kInfo, text + "}\n");
    return report;
}

namespace {

// Planes of a fit read a band of rows at a time, dequantised: nplanes x pixels.
class PlaneReaders {
public:
    PlaneReaders(const std::filesystem::path& folder, const FitFile& file) : file_(file) {
        for (int j = 0; j < file.jpegs(); ++j)
            readers_.push_back(std::make_unique<ImageFileReader>(file.plane_file(folder, j), "fit plane"));
    }
    Eigen::MatrixXd read(int y0, int y1) {
        const auto pixels = static_cast<std::size_t>(file_.width) * static_cast<std::size_t>(y1 - y0);
        Eigen::MatrixXd values(file_.nplanes, static_cast<Eigen::Index>(pixels));
        for (std::size_t j = 0; j < readers_.size(); ++j) {
            if (file_.exact) {
                floats_.resize(3 * pixels);
                readers_[j]->read_rows(y0, y1, std::span<float>(floats_));
            } else {
                bytes_.resize(3 * pixels);
                readers_[j]->read_rows(y0, y1, std::span<std::uint8_t>(bytes_));
            }
            for (int c = 0; c < 3; ++c) {
                const std::size_t p = 3 * j + static_cast<std::size_t>(c);
                if (p >= static_cast<std::size_t>(file_.nplanes)) continue;
                const double scale = file_.scale[p], bias = file_.bias[p];
                for (std::size_t k = 0; k < pixels; ++k) {
                    const double v = file_.exact ? floats_[3 * k + static_cast<std::size_t>(c)]
                                                 : bytes_[3 * k + static_cast<std::size_t>(c)] / 255.0;
                    values(static_cast<Eigen::Index>(p), static_cast<Eigen::Index>(k)) = (v - bias) * scale;
                }
            }
        }
        return values;
    }

private:
    const FitFile& file_;
    std::vector<std::unique_ptr<ImageFileReader>> readers_;
    std::vector<float> floats_;
    std::vector<std::uint8_t> bytes_;
};

// Renders every direction band by band, handing each band of each output to `take`.
template <typename Take>
void render_bands(const std::filesystem::path& folder, const std::vector<Eigen::Vector3d>& directions, Take&& take) {
    const FitFile file = read_fit(folder);
    const std::filesystem::path dir =
        std::filesystem::is_directory(folder) ? folder : folder.parent_path();
    std::vector<Eigen::Matrix3Xd> weights(directions.size());
    std::vector<Eigen::Vector3d> offsets(directions.size());
    for (std::size_t j = 0; j < directions.size(); ++j) {
        if (!directions[j].allFinite() || directions[j].norm() == 0.0)
            throw InputError("a fit is relit toward a direction; got a zero or non-finite vector");
        file.light_weights(directions[j], weights[j], offsets[j]);
    }
    PlaneReaders planes(dir, file);
    const int rows = std::max(1, static_cast<int>((std::size_t{64} << 20) /
                                                  (static_cast<std::size_t>(file.width) * 8 *
                                                   static_cast<std::size_t>(file.nplanes + 3))));
    Progress progress("relighting the fit", static_cast<std::size_t>((file.height + rows - 1) / rows));
    for (int y0 = 0; y0 < file.height; y0 += rows) {
        const int y1 = std::min(file.height, y0 + rows);
        const Eigen::MatrixXd values = planes.read(y0, y1);
        for (std::size_t j = 0; j < directions.size(); ++j) {
            const Eigen::MatrixXd out = (weights[j] * values).colwise() + offsets[j];
            Image band(file.width, y1 - y0, 3);
            for (int c = 0; c < 3; ++c) {
                std::span<float> plane = band.plane(c);
                for (Eigen::Index k = 0; k < out.cols(); ++k) {
                    const double v = out(c, k);
                    plane[static_cast<std::size_t>(k)] =
                        file.exact ? static_cast<float>(v)
                                   : srgb_to_linear(static_cast<float>(std::clamp(v, 0.0, 1.0)));
                }
            }
            take(j, y0, band);
        }
        progress.advance();
    }
    progress.finish();
}

}  // namespace

void render_fit_to_files(const std::filesystem::path& folder, const std::vector<Eigen::Vector3d>& directions,
                         const std::vector<std::filesystem::path>& outs) {
    RFD_CHECK(directions.size() == outs.size());
    const FitFile file = read_fit(folder);
    std::vector<std::unique_ptr<ImageBandWriter>> writers;
    for (const auto& out : outs) writers.push_back(std::make_unique<ImageBandWriter>(out, file.width, file.height, 3));
    render_bands(folder, directions, [&](std::size_t j, int, const Image& band) { writers[j]->write(band); });
    for (auto& writer : writers) writer->finish();
}

std::vector<Image> render_fit(const std::filesystem::path& folder, const std::vector<Eigen::Vector3d>& directions) {
    const FitFile file = read_fit(folder);
    std::vector<Image> out(directions.size(), Image(file.width, file.height, 3));
    render_bands(folder, directions, [&](std::size_t j, int y0, const Image& band) {
        for (int c = 0; c < 3; ++c)
            std::copy(band.plane(c).begin(), band.plane(c).end(),
                      out[j].plane(c).begin() + static_cast<std::ptrdiff_t>(y0) * file.width);
    });
    return out;
}

}  // namespace rfd::relight
