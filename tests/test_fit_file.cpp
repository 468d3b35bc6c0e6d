// Light models and fitted fields (relight/light_model.hpp, relight/fit_file.hpp): the Gram
// matrix's leave-one-out against the streamed one, OpenLIME's radial basis weights, planes
// written by hand to the format's documented rules read and relit as those rules say, and
// fields made of a basis fitted and relit back.

#include <cmath>
#include <cstdint>
#include <random>
#include <utility>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "core/error.hpp"
#include "core/files.hpp"
#include "core/image_file.hpp"
#include "core/image_io.hpp"
#include "core/sphere.hpp"
#include "core/units.hpp"
#include "relight/basis.hpp"
#include "relight/evaluate.hpp"
#include "relight/field.hpp"
#include "relight/fit_file.hpp"
#include "relight/light_model.hpp"
#include "tests/support/error_of.hpp"
#include "tests/support/scattered_lights.hpp"
#include "tests/support/temp_dir.hpp"

namespace rfd::relight {
namespace {

using ::testing::HasSubstr;
using rfd::testing::error_of;
using rfd::testing::scattered_lights;
using rfd::testing::TempDir;

// A field of smooth random shading plus a narrow highlight per pixel (no basis holds it
// exactly), 16 x 12 x 3, as EXR.
std::filesystem::path shiny_field(const TempDir& dir, const std::vector<Eigen::Vector3d>& lights) {
    std::mt19937 random(4);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    FieldWriter out(dir / "field");
    std::vector<Eigen::Vector3d> normals;
    std::vector<double> albedo;
    for (int k = 0; k < 16 * 12; ++k) {
        normals.push_back(direction_from_angles(0.5 * unit(random), 2.0 * kPi * unit(random)));
        albedo.push_back(0.2 + 0.6 * unit(random));
    }
    for (const Eigen::Vector3d& d : lights) {
        Image image(16, 12, 3);
        for (int k = 0; k < 16 * 12; ++k) {
            const Eigen::Vector3d n = normals[static_cast<std::size_t>(k)];
            const Eigen::Vector3d h = (d + Eigen::Vector3d::UnitZ()).normalized();
            const double diffuse = albedo[static_cast<std::size_t>(k)] * std::max(0.0, n.dot(d));
            const double specular = 0.8 * std::pow(std::max(0.0, n.dot(h)), 40.0);
            for (int c = 0; c < 3; ++c)
                image.at(k % 16, k / 16, c) = static_cast<float>((0.7 + 0.15 * c) * diffuse + specular);
        }
        out.add(image, d);
    }
    out.finish();
    return dir / "field";
}

TEST(LightModel, GramLeaveOneOutIsTheStreamedOne) {
    TempDir dir;
    const auto lights = scattered_lights(30, 2);
    FieldReader field(shiny_field(dir, lights));
    const FieldGram gram = field_gram(field);
    std::size_t checked = 0;
    for (const std::string name : {"delaunay", "nearest", "ptm", "hsh3", "rbf", "bilinear"}) {
        LightModel model = parse_light_model(name);
        if (model.has_sigma()) model.sigma = 0.3;
        const LightWeights weights(model, lights);
        std::vector<bool> predictable;
        const Eigen::VectorXd closed = leave_one_out_errors(gram, weights.leave_one_out(predictable));
        const LeaveOneOut streamed = leave_one_out(field, {&weights}).front();
        for (std::size_t j = 0; j < lights.size(); ++j) {
            ASSERT_TRUE(predictable[j]);
            EXPECT_NEAR(closed[static_cast<Eigen::Index>(j)], streamed.squared_error[j], 1e-4 * streamed.squared_error[j])
                << name << " light " << j;
            ++checked;
        }
    }
    EXPECT_EQ(checked, 6u * 30u);
}

TEST(LightModel, TheBilinearGridIsOpenLimesOctahedralMap) {
    // OpenLIME's BLN: s = |x|+|y|+|z|, u = ((x+y)/s + 1)/2, v = ((y-x)/s + 1)/2, the
    // cell's corner floor(u), floor(v) (at most R-2), weights bilinear in the fractions.
    const int r = 8;
    std::size_t checked = 0;
    for (const Eigen::Vector3d& d : scattered_lights(50, 3)) {
        const double s = std::abs(d.x()) + std::abs(d.y()) + std::abs(d.z());
        const double u = ((d.x() + d.y()) / s + 1.0) / 2.0 * (r - 1), v = ((d.y() - d.x()) / s + 1.0) / 2.0 * (r - 1);
        const int x = std::min(r - 2, static_cast<int>(u)), y = std::min(r - 2, static_cast<int>(v));
        const GridCell cell = octahedral_cell(d, r);
        EXPECT_EQ(cell.node[0], x + y * r);
        EXPECT_EQ(cell.node[3], x + 1 + (y + 1) * r);
        EXPECT_NEAR(cell.weight[0], (1 - (u - x)) * (1 - (v - y)), 1e-12);
        EXPECT_NEAR(cell.weight[3], (u - x) * (v - y), 1e-12);
        ++checked;
    }
    // Each node's direction falls on the node itself.
    for (int y = 0; y < r; ++y)
        for (int x = 0; x < r; ++x) {
            const GridCell cell = octahedral_cell(octahedral_node(x, y, r), r);
            double on_node = 0.0;
            for (int k = 0; k < 4; ++k)
                if (cell.node[k] == x + y * r) on_node += cell.weight[k];
            EXPECT_NEAR(on_node, 1.0, 1e-9) << x << "," << y;
            EXPECT_GE(octahedral_node(x, y, r).z(), 0.0);
            ++checked;
        }
    EXPECT_EQ(checked, 50u + 64u);
}

TEST(LightModel, TheBilinearGridIsTheLeastSquaresGridNearestItsPrior) {
    // M y minimises |A g - y|^2 + k |g - B y|^2: its gradient A^T (A g - y) + k (g - B y) is 0,
    // with A and B built here from the cells and the rbf weights at the nodes.
    const auto lights = scattered_lights(30, 5);
    LightModel model = parse_light_model("bilinear");
    model.sigma = 0.3;
    model.resolution = 5;
    const Eigen::MatrixXd m = bilinear_grid(lights, model);
    const int nodes = 25;
    Eigen::MatrixXd a = Eigen::MatrixXd::Zero(30, nodes), b(nodes, 30);
    for (Eigen::Index i = 0; i < 30; ++i) {
        const GridCell cell = octahedral_cell(lights[static_cast<std::size_t>(i)], 5);
        for (int k = 0; k < 4; ++k) a(i, cell.node[k]) += cell.weight[k];
    }
    for (int g = 0; g < nodes; ++g) b.row(g) = rbf_weights(lights, 0.3, octahedral_node(g % 5, g / 5, 5)).transpose();
    std::mt19937 random(8);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    Eigen::VectorXd y(30);
    for (double& v : y) v = unit(random);
    const Eigen::VectorXd g = m * y;
    const Eigen::VectorXd gradient = a.transpose() * (a * g - y) + model.regularization * (g - b * y);
    EXPECT_LT(gradient.cwiseAbs().maxCoeff(), 1e-10);
    // The weights at a direction are the bilinear blend of the grid there.
    const Eigen::Vector3d d = direction_from_angles(0.6, 2.2);
    const GridCell cell = octahedral_cell(d, 5);
    Eigen::VectorXd blend = Eigen::VectorXd::Zero(30);
    for (int k = 0; k < 4; ++k) blend += cell.weight[k] * m.row(cell.node[k]).transpose();
    EXPECT_LT((LightWeights(model, lights).at(d) - blend).cwiseAbs().maxCoeff(), 1e-12);
}

TEST(LightModel, LeaveOneOutRefitsWithoutTheLight) {
    // Row j of W: the model built from the other lights alone, at light j.
    const auto lights = scattered_lights(16, 7);
    std::size_t checked = 0;
    for (const std::string name : {"rbf", "bilinear"}) {
        LightModel model = parse_light_model(name);
        model.sigma = 0.4;
        std::vector<bool> predictable;
        const Eigen::MatrixXd w = LightWeights(model, lights).leave_one_out(predictable);
        for (std::size_t j = 0; j < lights.size(); ++j) {
            std::vector<Eigen::Vector3d> others = lights;
            others.erase(others.begin() + static_cast<std::ptrdiff_t>(j));
            const Eigen::VectorXd alone = LightWeights(model, others).at(lights[j]);
            EXPECT_EQ(w(static_cast<Eigen::Index>(j), static_cast<Eigen::Index>(j)), 0.0);
            for (std::size_t i = 0, o = 0; i < lights.size(); ++i) {
                if (i == j) continue;
                EXPECT_NEAR(w(static_cast<Eigen::Index>(j), static_cast<Eigen::Index>(i)),
                            alone[static_cast<Eigen::Index>(o++)], 1e-9)
                    << name << " " << j << " " << i;
            }
            ++checked;
        }
    }
    EXPECT_EQ(checked, 2u * 16u);
}

TEST(LightModel, SeveralModelsInOnePassScoreAsEachAlone) {
    TempDir dir;
    const auto lights = scattered_lights(24, 8);
    FieldReader field(shiny_field(dir, lights));
    const LightWeights delaunay(parse_light_model("delaunay"), lights), ptm(parse_light_model("ptm"), lights);
    const std::vector<LeaveOneOut> both = leave_one_out(field, {&delaunay, &ptm});
    const LeaveOneOut interpolated = leave_one_out(field, Interpolation::Delaunay);
    const LeaveOneOut fitted = leave_one_out(field, BasisFit(Basis::Ptm, lights));
    for (std::size_t j = 0; j < lights.size(); ++j) {
        EXPECT_NEAR(both[0].squared_error[j], interpolated.squared_error[j], 1e-6 * interpolated.squared_error[j]);
        EXPECT_NEAR(both[1].squared_error[j], fitted.squared_error[j], 1e-5 * fitted.squared_error[j]);
    }
}

TEST(LightModel, RadialWeightsAreOpenLimes) {
    const auto lights = scattered_lights(40, 3);
    const double sigma = 0.2;
    const Eigen::Vector3d d = direction_from_angles(0.4, 0.7);
    // OpenLIME's RBF.rbf, written out: exp(-|l - d|^2 / sigma^2), normalised, those above
    // 0.001 kept and normalised again.
    std::vector<double> w(lights.size());
    double total = 0.0;
    for (std::size_t i = 0; i < lights.size(); ++i) total += w[i] = std::exp(-(lights[i] - d).squaredNorm() / (sigma * sigma));
    double kept = 0.0;
    for (double& v : w) {
        v /= total;
        v = v > 0.001 ? v : 0.0;
        kept += v;
    }
    const Eigen::VectorXd ours = rbf_weights(lights, sigma, d);
    int nonzero = 0;
    for (std::size_t i = 0; i < lights.size(); ++i) {
        EXPECT_NEAR(ours[static_cast<Eigen::Index>(i)], w[i] / kept, 1e-12);
        nonzero += w[i] > 0.0;
    }
    EXPECT_GT(nonzero, 1);
    EXPECT_LT(nonzero, 40);
    // Far narrower than the lights' spacing, OpenLIME's weights underflow to 0 / 0; rfd's
    // are the nearest light's.
    const Eigen::VectorXd narrow = rbf_weights(lights, 1e-4, d);
    EXPECT_NEAR(narrow.sum(), 1.0, 1e-12);
    EXPECT_EQ((narrow.array() > 0.0).count(), 1);
}

TEST(LightModel, TheChosenSigmaIsALeastLeaveOneOutError) {
    TempDir dir;
    const auto lights = scattered_lights(40, 6);
    FieldReader field(shiny_field(dir, lights));
    const FieldGram gram = field_gram(field);
    const double sigma = best_sigma(gram, lights, parse_light_model("rbf"));
    const auto error_at = [&](double s) {
        LightModel model = parse_light_model("rbf");
        model.sigma = s;
        std::vector<bool> predictable;
        return leave_one_out_errors(gram, LightWeights(model, lights).leave_one_out(predictable)).sum();
    };
    EXPECT_GT(sigma, 0.02);
    EXPECT_LT(sigma, 1.5);
    for (const double factor : {0.5, 0.8, 0.95, 1.05, 1.25, 2.0})
        EXPECT_LE(error_at(sigma), error_at(sigma * factor) * (1.0 + 1e-9)) << factor;
}

// Writes planes of random codes and an info.json by the format's rules (the header of
// relight/fit_file.hpp), and returns the codes: codes[p][pixel].
std::vector<std::vector<std::uint8_t>> write_planes(const std::filesystem::path& folder, int width, int height,
                                                    int nplanes, unsigned seed) {
    std::mt19937 random(seed);
    std::uniform_int_distribution<int> code(0, 255);
    const int jpegs = (nplanes + 2) / 3;
    std::vector<std::vector<std::uint8_t>> codes(static_cast<std::size_t>(nplanes));
    std::filesystem::create_directories(folder);
    for (int j = 0; j < jpegs; ++j) {
        // Blocks of 8 x 8 of one colour: JPEG at quality 100 keeps them.
        std::vector<std::uint8_t> rows(static_cast<std::size_t>(width * height * 3), 0);
        std::vector<std::array<int, 3>> block_colour(static_cast<std::size_t>((width / 8) * (height / 8)));
        for (auto& colour : block_colour) colour = {code(random), code(random), code(random)};
        for (int y = 0; y < height; ++y)
            for (int x = 0; x < width; ++x)
                for (int c = 0; c < 3; ++c)
                    rows[static_cast<std::size_t>((y * width + x) * 3 + c)] = static_cast<std::uint8_t>(
                        block_colour[static_cast<std::size_t>((y / 8) * (width / 8) + x / 8)][static_cast<std::size_t>(c)]);
        ImageFileSpec spec;
        spec.width = width;
        spec.height = height;
        spec.channels = 3;
        spec.type = SampleType::UInt8;
        spec.compression = "jpeg:100";
        spec.jpeg_subsampling = "4:4:4";
        const auto path = folder / ("plane_" + std::to_string(j) + ".jpg");
        ImageFileWriter writer(path, spec);
        writer.write_rows(0, height, SampleType::UInt8, rows.data());
        writer.finish();
        // The codes as a decoder gives them back (JPEG may still move a code by one).
        ImageFileReader reader(path);
        reader.read_rows(0, height, std::span<std::uint8_t>(rows));
        for (int c = 0; c < 3 && 3 * j + c < nplanes; ++c)
            for (int k = 0; k < width * height; ++k)
                codes[static_cast<std::size_t>(3 * j + c)].push_back(rows[static_cast<std::size_t>(k * 3 + c)]);
    }
    return codes;
}

// An mrgb material of random values by the format's rules: basis bytes for (nplanes + 1)
// blocks of `nodes` x 3 values, then per plane a scale, bias and range.
struct MrgbMaterial {
    std::vector<int> basis;
    std::vector<double> scale, bias, range;
};
MrgbMaterial random_mrgb_material(int nplanes, int nodes, unsigned seed) {
    std::mt19937 random(seed);
    std::uniform_int_distribution<int> byte(0, 255);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    MrgbMaterial m;
    for (int k = 0; k < (nplanes + 1) * nodes * 3; ++k) m.basis.push_back(byte(random));
    for (int p = 0; p < nplanes; ++p) {
        m.scale.push_back(0.1 + unit(random));
        m.bias.push_back(unit(random));
        m.range.push_back(100.0 + 400.0 * unit(random));
    }
    return m;
}

// Expects `relit` (8 x 8) to be OpenLIME's MRGB render of `codes` under the nodes' weights
// (node, weight): base[p][c] = sum over the nodes of weight x basis[(p nodes + node) 3 + c],
// decoded; rgb = base[0] + sum_p v_p base[p + 1]. Returns the samples checked.
std::size_t expect_mrgb_render(const Image& relit, const std::vector<std::vector<std::uint8_t>>& codes,
                               const MrgbMaterial& m, int nodes, const std::vector<std::pair<int, double>>& weights) {
    const int width = relit.width(), nplanes = static_cast<int>(m.scale.size());
    std::size_t checked = 0;
    for (int k = 0; k < width * relit.height(); ++k)
        for (int c = 0; c < 3; ++c) {
            double display = 0.0;
            for (int p = 0; p <= nplanes; ++p) {
                double base = 0.0;
                for (const auto& [node, weight] : weights) {
                    const int b = m.basis[static_cast<std::size_t>((p * nodes + node) * 3 + c)];
                    base += weight * (p == 0 ? b / 255.0 : (b - 127.0) / m.range[static_cast<std::size_t>(p - 1)]);
                }
                const double value = p == 0 ? 1.0
                                            : (codes[static_cast<std::size_t>(p - 1)][static_cast<std::size_t>(k)] / 255.0 -
                                               m.bias[static_cast<std::size_t>(p - 1)]) *
                                                  m.scale[static_cast<std::size_t>(p - 1)];
                display += base * value;
            }
            EXPECT_NEAR(relit.at(k % width, k / width, c),
                        srgb_to_linear(static_cast<float>(std::clamp(display, 0.0, 1.0))), 1e-5);
            ++checked;
        }
    return checked;
}

TEST(FitFile, PtmPlanesWrittenByTheRulesRelightAsTheRulesSay) {
    TempDir dir;
    const int width = 16, height = 8, nplanes = 18;
    const auto codes = write_planes(dir / "ptm", width, height, nplanes, 5);
    std::mt19937 random(9);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    std::vector<double> scale, bias;
    for (int p = 0; p < nplanes; ++p) {
        scale.push_back(p < 3 ? 1.0 : 0.2 + unit(random));
        bias.push_back(p < 3 ? 0.0 : unit(random));
    }
    const nlohmann::json info = {{"width", width},  {"height", height},         {"format", "jpg"},
                                 {"type", "ptm"},   {"colorspace", "rgb"},      {"nplanes", nplanes},
                                 {"quality", 100},  {"materials", {{{"scale", scale}, {"bias", bias}}}}};
    write_text_file(dir / "ptm" / "info.json", info.dump());
    const std::vector<Eigen::Vector3d> directions{direction_from_angles(0.3, 1.0), direction_from_angles(1.1, -2.0)};
    const std::vector<Image> relit = render_fit(dir / "ptm", directions);
    ASSERT_EQ(relit.size(), 2u);
    std::size_t checked = 0;
    for (std::size_t l = 0; l < directions.size(); ++l) {
        const Eigen::Vector3d& d = directions[l];
        const double b[6] = {1.0, d.x(), d.y(), d.x() * d.x(), d.x() * d.y(), d.y() * d.y()};
        for (int k = 0; k < width * height; ++k)
            for (int c = 0; c < 3; ++c) {
                double display = 0.0;
                for (int j = 0; j < 6; ++j) {
                    const auto p = static_cast<std::size_t>(3 * j + c);
                    display += b[j] * (codes[p][static_cast<std::size_t>(k)] / 255.0 - bias[p]) * scale[p];
                }
                const double expected = srgb_to_linear(static_cast<float>(std::clamp(display, 0.0, 1.0)));
                EXPECT_NEAR(relit[l].at(k % width, k / width, c), expected, 1e-5);
                ++checked;
            }
    }
    EXPECT_EQ(checked, 2u * width * height * 3);
}

TEST(FitFile, RbfPlanesWrittenByTheRulesRelightAsTheRulesSay) {
    TempDir dir;
    const int width = 8, height = 8, nplanes = 4;
    const auto codes = write_planes(dir / "rbf", width, height, nplanes, 6);
    const auto lights = scattered_lights(7, 1);
    const MrgbMaterial m = random_mrgb_material(nplanes, 7, 2);
    std::vector<double> xyz;
    for (const Eigen::Vector3d& l : lights) xyz.insert(xyz.end(), {l.x(), l.y(), l.z()});
    const double sigma = 0.35;
    const nlohmann::json info = {{"width", width},   {"height", height},      {"format", "jpg"},  {"type", "rbf"},
                                 {"colorspace", "mrgb"}, {"nplanes", nplanes}, {"sigma", sigma},   {"lights", xyz},
                                 {"basis", m.basis},
                                 {"materials", {{{"scale", m.scale}, {"bias", m.bias}, {"range", m.range}}}}};
    write_text_file(dir / "rbf" / "info.json", info.dump());
    const Eigen::Vector3d d = direction_from_angles(0.5, 0.2);
    const Image relit = render_fit(dir / "rbf", {d}).front();
    // OpenLIME's RBF.lightWeights: Gaussian weights normalised, those <= 0.001 dropped, the
    // rest normalised again.
    std::vector<double> w(7);
    double total = 0.0;
    for (std::size_t l = 0; l < 7; ++l) total += w[l] = std::exp(-(lights[l] - d).squaredNorm() / (sigma * sigma));
    double kept = 0.0;
    for (double& v : w) {
        v /= total;
        v = v > 0.001 ? v : 0.0;
        kept += v;
    }
    std::vector<std::pair<int, double>> weights;
    for (std::size_t l = 0; l < 7; ++l) weights.emplace_back(static_cast<int>(l), w[l] / kept);
    EXPECT_EQ(expect_mrgb_render(relit, codes, m, 7, weights), std::size_t{8 * 8 * 3});
}

TEST(FitFile, BilinearPlanesWrittenByTheRulesRelightAsTheRulesSay) {
    TempDir dir;
    const int width = 8, height = 8, nplanes = 4, r = 4;
    const auto codes = write_planes(dir / "bln", width, height, nplanes, 7);
    const MrgbMaterial m = random_mrgb_material(nplanes, r * r, 5);
    // As relight-cli writes it: type "bilinear", the grid's side, no sigma needed.
    const nlohmann::json info = {{"width", width},      {"height", height},   {"format", "jpg"},
                                 {"type", "bilinear"},  {"resolution", r},    {"colorspace", "mrgb"},
                                 {"nplanes", nplanes},  {"basis", m.basis},
                                 {"materials", {{{"scale", m.scale}, {"bias", m.bias}, {"range", m.range}}}}};
    write_text_file(dir / "bln" / "info.json", info.dump());
    const Eigen::Vector3d d = direction_from_angles(0.7, -1.2);
    const Image relit = render_fit(dir / "bln", {d}).front();
    // OpenLIME's BLN.lightWeights: the four grid nodes around d, blended bilinearly.
    const double s = std::abs(d.x()) + std::abs(d.y()) + std::abs(d.z());
    const double u = ((d.x() + d.y()) / s + 1.0) / 2.0 * (r - 1), v = ((d.y() - d.x()) / s + 1.0) / 2.0 * (r - 1);
    const int sx = std::min(r - 2, static_cast<int>(u)), sy = std::min(r - 2, static_cast<int>(v));
    const double dx = u - sx, dy = v - sy;
    const std::vector<std::pair<int, double>> weights{{sx + sy * r, (1 - dx) * (1 - dy)},
                                                      {sx + 1 + sy * r, dx * (1 - dy)},
                                                      {sx + (sy + 1) * r, (1 - dx) * dy},
                                                      {sx + 1 + (sy + 1) * r, dx * dy}};
    EXPECT_EQ(expect_mrgb_render(relit, codes, m, r * r, weights), std::size_t{8 * 8 * 3});
}

// A field whose every pixel and channel is a ptm polynomial of the light, as EXR; display
// values (sRGB-encoded) when `display`, else linear.
std::filesystem::path polynomial_field(const TempDir& dir, const std::vector<Eigen::Vector3d>& lights,
                                       bool display) {
    std::mt19937 random(12);
    std::uniform_real_distribution<double> unit(-1.0, 1.0);
    std::vector<Eigen::VectorXd> coefficients;
    for (int k = 0; k < 16 * 16 * 3; ++k) {
        Eigen::VectorXd c(6);
        c << 0.5 + 0.1 * unit(random), 0.15 * unit(random), 0.15 * unit(random), 0.05 * unit(random),
            0.05 * unit(random), 0.05 * unit(random);
        coefficients.push_back(c);
    }
    FieldWriter out(dir / "poly");
    for (const Eigen::Vector3d& d : lights) {
        const Eigen::VectorXd b = basis_values(Basis::Ptm, d);
        Image image(16, 16, 3);
        for (std::size_t k = 0; k < coefficients.size(); ++k) {
            const auto v = static_cast<float>(coefficients[k].dot(b));
            image.samples()[k] = display ? srgb_to_linear(v) : v;
        }
        out.add(image, d);
    }
    out.finish();
    return dir / "poly";
}

TEST(FitFile, AFieldOfTheBasisIsFittedAndRelitBack) {
    const auto lights = scattered_lights(25, 4);
    const std::vector<Eigen::Vector3d> novel{direction_from_angles(0.2, 0.3), direction_from_angles(0.9, 2.5)};
    for (const bool exact : {true, false}) {
        TempDir dir;
        FieldReader field(polynomial_field(dir, lights, !exact));
        FitSpec spec;
        spec.exact = exact;
        spec.quality = 100;
        const FitReport report = fit_field(field, spec, dir / "fit");
        EXPECT_EQ(report.file.nplanes, 18);
        EXPECT_EQ(read_fit(dir / "fit").nplanes, 18);
        const std::vector<Image> relit = render_fit(dir / "fit", novel);
        // The truth at the novel lights: the field's own polynomial, from a field made there.
        TempDir truth_dir;
        const ReflectanceField truth = read_field(polynomial_field(truth_dir, novel, !exact));
        for (std::size_t l = 0; l < novel.size(); ++l) {
            double worst = 0.0;
            for (std::size_t k = 0; k < relit[l].samples().size(); ++k) {
                const double a = exact ? relit[l].samples()[k] : linear_to_srgb(relit[l].samples()[k]);
                const double b = exact ? truth.images[l].samples()[k] : linear_to_srgb(truth.images[l].samples()[k]);
                worst = std::max(worst, std::abs(a - b));
            }
            // Exact: float planes. Display: 18 planes of 8 bits, each within half a code of
            // its range (a few tenths of the value's range), and JPEG at quality 100.
            EXPECT_LT(worst, exact ? 1e-5 : 3.0 / 255.0) << (exact ? "exact" : "jpg") << " light " << l;
        }
    }
}

TEST(FitFile, AnRbfFitKeepsWhatItsComponentsHold) {
    // Every pixel a mix of two light responses: two principal components hold it all.
    TempDir dir;
    const auto lights = scattered_lights(20, 9);
    FieldWriter out(dir / "two");
    std::mt19937 random(3);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    std::vector<std::array<double, 2>> mix(8 * 8);
    for (auto& m : mix) m = {unit(random), unit(random)};
    for (const Eigen::Vector3d& d : lights) {
        Image image(8, 8, 3);
        for (int k = 0; k < 64; ++k)
            for (int c = 0; c < 3; ++c)
                image.at(k % 8, k / 8, c) = static_cast<float>(mix[static_cast<std::size_t>(k)][0] * d.z() * (0.5 + 0.2 * c) +
                                                                mix[static_cast<std::size_t>(k)][1] * d.x() * d.x());
        out.add(image, d);
    }
    out.finish();
    FieldReader field(dir / "two");
    FitSpec spec;
    spec.type = FitType::Rbf;
    spec.planes = 2;
    spec.exact = true;
    spec.sigma = 0.25;
    const FitReport report = fit_field(field, spec, dir / "fit");
    EXPECT_GT(report.kept_variance, 1.0 - 1e-9);
    // At a capture's own light the fit is the RBF blend of the captured images.
    const ReflectanceField whole = read_field(dir / "two");
    const Eigen::VectorXd w = rbf_weights(lights, 0.25, lights[3]);
    const Image relit = render_fit(dir / "fit", {lights[3]}).front();
    double worst = 0.0;
    for (std::size_t k = 0; k < relit.samples().size(); ++k) {
        double blend = 0.0;
        for (std::size_t i = 0; i < lights.size(); ++i) blend += w[static_cast<Eigen::Index>(i)] * whole.images[i].samples()[k];
        worst = std::max(worst, std::abs(relit.samples()[k] - blend));
    }
    EXPECT_LT(worst, 1e-5);
}

TEST(FitFile, ABilinearFitWithEveryComponentIsItsLightModel) {
    // 3 R^2 components hold the grid's samples whole: the fit relights as the bilinear light
    // model blends the captured images, at the lights and between them.
    TempDir dir;
    const auto lights = scattered_lights(20, 9);
    FieldReader field(shiny_field(dir, lights));
    FitSpec spec;
    spec.type = FitType::Bilinear;
    spec.resolution = 4;
    spec.planes = 48;
    spec.exact = true;
    spec.sigma = 0.3;
    const FitReport report = fit_field(field, spec, dir / "fit");
    EXPECT_GT(report.kept_variance, 1.0 - 1e-9);
    const FitFile file = read_fit(dir / "fit");
    EXPECT_EQ(file.type, FitType::Bilinear);
    EXPECT_EQ(file.resolution, 4);
    LightModel model = parse_light_model("bilinear");
    model.sigma = 0.3;
    model.resolution = 4;
    const LightWeights weights(model, lights);
    const ReflectanceField whole = read_field(dir / "field");
    const std::vector<Eigen::Vector3d> directions{lights[2], direction_from_angles(0.4, 1.0),
                                                  direction_from_angles(1.0, -2.0)};
    const std::vector<Image> relit = render_fit(dir / "fit", directions);
    for (std::size_t l = 0; l < directions.size(); ++l) {
        const Eigen::VectorXd w = weights.at(directions[l]);
        double worst = 0.0;
        for (std::size_t k = 0; k < relit[l].samples().size(); ++k) {
            double blend = 0.0;
            for (std::size_t i = 0; i < lights.size(); ++i)
                blend += w[static_cast<Eigen::Index>(i)] * whole.images[i].samples()[k];
            worst = std::max(worst, std::abs(relit[l].samples()[k] - blend));
        }
        EXPECT_LT(worst, 1e-5) << "direction " << l;
    }
}

TEST(FitFile, WhatTheFormatCannotHoldIsRefused) {
    TempDir dir;
    const auto lights = scattered_lights(25, 4);
    FieldReader field(polynomial_field(dir, lights, false));
    FitSpec spec;
    spec.type = FitType::Hsh;
    spec.basis = Basis::Hsh4;
    EXPECT_THAT(error_of([&] { fit_field(field, spec, dir / "fit"); }), HasSubstr("beyond what OpenLIME renders"));
    spec.type = FitType::Rbf;
    spec.planes = 100;
    EXPECT_THAT(error_of([&] { fit_field(field, spec, dir / "fit"); }), HasSubstr("keeps 1 to 75 components"));
    // A broken info.json: named, with its field.
    spec.type = FitType::Ptm;
    spec.basis = Basis::Ptm;
    fit_field(field, spec, dir / "fit");
    nlohmann::json info = nlohmann::json::parse(read_text_file(dir / "fit" / "info.json"));
    info["nplanes"] = 15;
    write_text_file(dir / "fit" / "info.json", info.dump());
    EXPECT_THAT(error_of([&] { read_fit(dir / "fit"); }), HasSubstr("info.json: field 'nplanes': 15 planes"));
    info["nplanes"] = 18;
    info["type"] = "neural";
    write_text_file(dir / "fit" / "info.json", info.dump());
    EXPECT_THAT(error_of([&] { read_fit(dir / "fit"); }), HasSubstr("field 'type': expected ptm, hsh, rbf or bilinear"));
    write_text_file(dir / "fit" / "info.json", "{\"width\": ");
    EXPECT_THAT(error_of([&] { read_fit(dir / "fit"); }), HasSubstr("not valid JSON"));
}

}  // namespace
}  // namespace rfd::relight

namespace rfd::relight {
namespace {

// The block SSIM of two 8-bit pictures, written out per block from its definition.
double ssim_of(const std::vector<int>& a, const std::vector<int>& b, int width, int height) {
    double sum = 0.0;
    int blocks = 0;
    for (int by = 0; by < height; by += 8)
        for (int bx = 0; bx < width; bx += 8) {
            std::vector<double> va, vb;
            for (int y = by; y < std::min(height, by + 8); ++y)
                for (int x = bx; x < std::min(width, bx + 8); ++x) {
                    va.push_back(a[static_cast<std::size_t>(y * width + x)]);
                    vb.push_back(b[static_cast<std::size_t>(y * width + x)]);
                }
            const double n = static_cast<double>(va.size());
            double ma = 0, mb = 0;
            for (std::size_t k = 0; k < va.size(); ++k) {
                ma += va[k] / n;
                mb += vb[k] / n;
            }
            double sa = 0, sb = 0, sab = 0;
            for (std::size_t k = 0; k < va.size(); ++k) {
                sa += (va[k] - ma) * (va[k] - ma) / n;
                sb += (vb[k] - mb) * (vb[k] - mb) / n;
                sab += (va[k] - ma) * (vb[k] - mb) / n;
            }
            const double c1 = 6.5025, c2 = 58.5225;
            sum += (2 * ma * mb + c1) * (2 * sab + c2) / ((ma * ma + mb * mb + c1) * (sa + sb + c2));
            ++blocks;
        }
    return sum / blocks;
}

TEST(LeaveOneOut, SsimIsTheBlockSsimOfTheEightBitPictures) {
    TempDir dir;
    const auto lights = scattered_lights(12, 5);
    // 20 x 13: blocks cut short at the right and bottom; one channel.
    std::mt19937 random(1);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    FieldWriter out(dir / "f");
    std::vector<Image> images;
    for (const Eigen::Vector3d& d : lights) {
        Image image(20, 13, 1);
        for (float& v : image.samples()) v = static_cast<float>(0.05 + 0.9 * unit(random) * d.z());
        out.add(image, d);
        images.push_back(image);
    }
    out.finish();
    FieldReader field(dir / "f");
    const LightWeights nearest(parse_light_model("nearest"), lights);
    // Bands of 8 rows (a small band_bytes) and of the whole picture give the same score.
    const LeaveOneOut whole = leave_one_out(field, {&nearest}).front();
    const LeaveOneOut banded = leave_one_out(field, {&nearest}, 1).front();
    std::vector<bool> predictable;
    const Eigen::MatrixXd w = nearest.leave_one_out(predictable);
    for (std::size_t j = 0; j < lights.size(); ++j) {
        std::vector<int> predicted, truth;
        for (std::size_t k = 0; k < images[j].samples().size(); ++k) {
            double v = 0.0;
            for (std::size_t i = 0; i < lights.size(); ++i)
                v += w(static_cast<Eigen::Index>(j), static_cast<Eigen::Index>(i)) * images[i].samples()[k];
            predicted.push_back(encode_srgb8(static_cast<float>(v)));
            truth.push_back(encode_srgb8(images[j].samples()[k]));
        }
        const double expected = ssim_of(predicted, truth, 20, 13);
        EXPECT_NEAR(whole.ssim[j], expected, 1e-9) << j;
        EXPECT_NEAR(banded.ssim[j], expected, 1e-9) << j;
        EXPECT_LT(expected, 0.99);
    }
}

}  // namespace
}  // namespace rfd::relight
