#pragma once
// Angular reflectance fields, as the Design III/IV encoder (patterns/angular.hpp) consumes
// them: R(light; u, v; view) with
//   - light: unit direction toward the light in the field frame (core/sphere.hpp);
//   - view: unit direction toward the observer in the same frame (x right, y up as the
//     observer sees the display, z out of its front);
//   - (u, v): the macro-pixel of Design IV, u to the right, v up, (0, 0) bottom left; a
//     Design III display is one macro-pixel (1 x 1).
// Values are linear radiance per channel.
//
// The encoder asks for a field's value averaged over an incident bin (the few light
// directions that sample one meso cell: what the display physically integrates), so a
// field is first bound to the bins and the macro grid: bind() checks coverage and builds
// tables; the lookup it returns is immutable and thread-safe.
//
// Fields provided:
//   - ViewSetField: a captured or rendered view set (relight/view_set.hpp), interpolated
//     over the lights of each view and over the views (SphericalInterpolator, delaunay);
//     each view image is reduced to the macro grid with a box filter (for Design III, 1 x 1:
//     the mean over the image, or over its centre `region`).
//   - LetterField: figure 8.13's letters, one character per light direction (the nearest
//     light decides), each drawn over a box of output directions.
//   - DiamondField: figure 8.15's diamonds over the macro grid, larger as the light moves
//     down, hollow when it comes from the sides, tinted by the viewing angle (magenta from
//     the right, white from the centre, green from the left).
//   - FunctionField: any function of (light, view, u, v), for tests and quick experiments.
//
// Example: LetterField letters(bin_centres, "0123456789ABCDEFGHIJKLMNOPQRST", {0.17, 0.17});
//          auto lookup = letters.bind(bins, 1, 1);

#include <array>
#include <functional>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/image.hpp"
#include "relight/interpolation.hpp"
#include "relight/view_set.hpp"

namespace rfd::patterns {

/// Light directions (field frame) whose mean value stands for one incident bin.
using LightBin = std::vector<Eigen::Vector3d>;

class AngularLookup {
public:
    virtual ~AngularLookup() = default;
    /// R averaged over bin `bin`'s lights, toward `view` (unit, field frame), at macro-pixel
    /// (u, v); writes channels() values to `out`. Thread-safe.
    virtual void value(std::size_t bin, const Eigen::Vector3d& view, int u, int v,
                       std::span<float> out) const = 0;
};

class AngularField {
public:
    virtual ~AngularField() = default;
    virtual int channels() const = 0;
    /// Prepares lookups for these bins on a macro_x x macro_y grid. Throws InputError when
    /// the field cannot serve them (e.g. light directions it does not cover).
    virtual std::unique_ptr<AngularLookup> bind(const std::vector<LightBin>& bins, int macro_x,
                                                int macro_y) const = 0;
};

/// A view set as an angular field. Needs one view (constant over view directions) or three
/// and more (interpolated); two views are an InputError (the interpolator needs three).
class ViewSetField : public AngularField {
public:
    /// `region`: fraction (0, 1] of the image width and height, about its centre, that the
    /// macro grid covers (1: the whole image).
    explicit ViewSetField(relight::ViewSet views, double region = 1.0);
    int channels() const override;
    /// Throws InputError naming the view file, the view and the bins' light directions
    /// (theta, phi in degrees) that lie outside the triangulation of a view's lights.
    std::unique_ptr<AngularLookup> bind(const std::vector<LightBin>& bins, int macro_x,
                                        int macro_y) const override;
    const relight::ViewSet& views() const { return views_; }

private:
    relight::ViewSet views_;
    double region_;
};

/// One character per light direction, drawn (patterns/glyphs.hpp, 1 channel, coverage in
/// [0, 1]) over the output directions with |tan_x| <= half_tan[0], |tan_y| <= half_tan[1]
/// (view direction slopes view.x/view.z, view.y/view.z), readable with x right and y up;
/// 0 outside the box. A light's letter is that of the nearest of `lights`.
class LetterField : public AngularField {
public:
    LetterField(std::vector<Eigen::Vector3d> lights, const std::string& characters,
                std::array<double, 2> half_tan, int mask_size = 96);
    int channels() const override { return 1; }
    std::unique_ptr<AngularLookup> bind(const std::vector<LightBin>& bins, int macro_x,
                                        int macro_y) const override;
    /// The mask of character k (mask_size x mask_size, row 0 at +tan_y).
    const Image& mask(std::size_t k) const { return masks_[k]; }
    /// Coverage of letter k toward `view` (bilinear in the mask).
    float sample(std::size_t k, const Eigen::Vector3d& view) const;
    /// Index of the letter of `light`.
    std::size_t letter_of(const Eigen::Vector3d& light) const;
    const std::string& characters() const { return characters_; }

private:
    std::vector<Eigen::Vector3d> lights_;
    std::string characters_;
    std::array<double, 2> half_tan_;
    std::vector<Image> masks_;
};

/// Figure 8.15's 6D test field, RGB. With t = (light.x, light.y) / light.z / light_half_tan
/// (clamped to [-1, 1]) and normalised macro coordinates x, y in (-1, 1): a diamond
/// |x| + |y| <= s with s = 0.35 + 0.45 (1 - t_y) / 2 (grows as the light moves down), hollow
/// inside |x| + |y| < 0.75 s |t_x| (empty as the light moves sideways); box-filtered over each
/// macro-pixel (4 x 4 samples). Colour with a = view.x / view.z / view_half_tan in [-1, 1]:
/// (1, 1 - a, 1) for a > 0 (magenta seen from the right), (1 + a, 1, 1 + a) for a < 0 (green
/// from the left), white head-on.
class DiamondField : public AngularField {
public:
    DiamondField(double light_half_tan, double view_half_tan);
    int channels() const override { return 3; }
    std::unique_ptr<AngularLookup> bind(const std::vector<LightBin>& bins, int macro_x,
                                        int macro_y) const override;
    /// Diamond coverage of macro-pixel (u, v) of a macro_x x macro_y grid under `light`.
    double coverage(const Eigen::Vector3d& light, int u, int v, int macro_x, int macro_y) const;
    /// RGB tint toward `view`.
    std::array<float, 3> colour(const Eigen::Vector3d& view) const;

private:
    double light_half_tan_, view_half_tan_;
};

/// R given as a function; bins are averaged sample by sample on every lookup.
class FunctionField : public AngularField {
public:
    using Function = std::function<void(const Eigen::Vector3d& light, const Eigen::Vector3d& view,
                                        int u, int v, std::span<float> out)>;
    FunctionField(int channels, Function function);
    int channels() const override { return channels_; }
    std::unique_ptr<AngularLookup> bind(const std::vector<LightBin>& bins, int macro_x,
                                        int macro_y) const override;

private:
    int channels_;
    Function function_;
};

}  // namespace rfd::patterns
