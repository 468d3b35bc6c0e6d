#pragma once
// The image processing relight/ takes from OpenCV, on planes of samples viewed in place.
//
// OpenCV lives in the module librfd_opencv.so (relight/opencv_module.cpp; core/module.hpp
// says why), loaded by the first call of vision(). Each operation is one OpenCV function
// with the options rfd uses, so results are OpenCV's to the bit. A plane is `size.width`
// by `size.height` samples, row-major, row 0 at the top, as one channel of an rfd::Image;
// every span must hold size.area() samples (flow fields two per pixel, dx then dy).
//
// Example: vision().dilate({w, h}, mask, 3);

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

namespace rfd::relight {

struct PlaneSize {
    int width = 0;
    int height = 0;
    std::size_t area() const { return static_cast<std::size_t>(width) * static_cast<std::size_t>(height); }
};

/// What lies beyond a plane's edge for filters and warps.
enum class Border {
    Zero,       ///< zeros (OpenCV's BORDER_CONSTANT)
    Replicate,  ///< the edge sample repeated
    Reflect     ///< mirrored about the edge sample (OpenCV's default, BORDER_REFLECT_101)
};

/// Farneback's optical flow options (OpenCV's calcOpticalFlowFarneback).
struct FlowOptions {
    double pyramid_scale = 0.5;  ///< each pyramid level this much the size of the one below
    int levels = 1;              ///< pyramid levels, the full image included
    int window = 21;             ///< averaging window, pixels
    int iterations = 3;          ///< per level
    int polynomial_size = 7;     ///< neighbourhood of the polynomial expansion, pixels
    double polynomial_sigma = 1.5;
};

/// A camera response as OpenCV's Robertson code keeps it: 256 codes x (blue, green, red).
using BgrResponse = std::array<std::array<float, 3>, 256>;

class Vision {
public:
    virtual ~Vision() = default;

    /// Gaussian blur; `kernel` 0 sizes the kernel from the sigmas. `in` and `out` may be one.
    virtual void gaussian_blur(PlaneSize size, std::span<const float> in, std::span<float> out, int kernel,
                               double sigma_x, double sigma_y, Border border) const = 0;
    virtual void gaussian_blur(PlaneSize size, std::span<const std::uint8_t> in, std::span<std::uint8_t> out,
                               double sigma) const = 0;
    /// Mean over a `kernel` x `kernel` box, in place, zeros beyond the edge.
    virtual void box_blur(PlaneSize size, std::span<float> plane, int kernel) const = 0;
    /// Greatest value over a `kernel` x `kernel` square, in place.
    virtual void dilate(PlaneSize size, std::span<std::uint8_t> mask, int kernel) const = 0;
    /// 8-connected components of the non-zero samples into `labels` (0 for the rest);
    /// returns the number of labels, 0 included.
    virtual int connected_components(PlaneSize size, std::span<const std::uint8_t> mask,
                                     std::span<int> labels) const = 0;
    /// The exact Euclidean distance of every non-zero sample to the nearest zero one.
    virtual void distance_transform(PlaneSize size, std::span<const std::uint8_t> mask,
                                    std::span<float> distance) const = 0;
    /// Farneback's dense optical flow: from(x) ~ to(x + flow(x)).
    virtual void optical_flow(PlaneSize size, std::span<const std::uint8_t> from, std::span<const std::uint8_t> to,
                              const FlowOptions& options, std::span<float> flow) const = 0;
    /// `in` resampled to `out_size`: the mean over each output pixel's footprint when
    /// shrinking (OpenCV's INTER_AREA), bilinear when growing.
    virtual void resize(PlaneSize in_size, std::span<const float> in, PlaneSize out_size, std::span<float> out) const = 0;
    /// out(x, y) = in(map_x(x, y), map_y(x, y)), bilinear.
    virtual void remap(PlaneSize size, std::span<const float> in, std::span<const float> map_x,
                       std::span<const float> map_y, std::span<float> out, Border border) const = 0;
    /// Navier-Stokes inpainting (Bertalmio et al. 2001) of the non-zero samples of `mask`.
    virtual void inpaint(PlaneSize size, std::span<const float> in, std::span<const std::uint8_t> mask, double radius,
                         std::span<float> out) const = 0;
    /// out(p) = in(A p), bilinear, for the 2 x 3 matrix A (row-major) from output to input
    /// pixel centres.
    virtual void warp_affine(PlaneSize in_size, std::span<const float> in, const std::array<double, 6>& to_source,
                             PlaneSize out_size, std::span<float> out, Border border) const = 0;
    /// round(v * scale + offset) clamped to 0..255, rounding half to even (OpenCV's convertTo).
    virtual void scale_to_bytes(std::span<const float> in, double scale, double offset,
                                std::span<std::uint8_t> out) const = 0;
    /// Circles in an 8-bit image by OpenCV's HoughCircles (HOUGH_GRADIENT_ALT): centres
    /// (x, y in pixel coordinates, pixel centres at .5) and radii, strongest first.
    /// `canny_threshold` is the edge detector's upper threshold, `perfectness` (0-1) how
    /// closed a circle's edge must be, `min_distance` between centres, radii in pixels.
    virtual std::vector<std::array<float, 3>> hough_circles(PlaneSize size, std::span<const std::uint8_t> image,
                                                            double min_distance, double canny_threshold,
                                                            double perfectness, int min_radius,
                                                            int max_radius) const = 0;
    /// Robertson et al.'s response calibration from 8-bit BGR images (3 samples a pixel).
    virtual BgrResponse robertson_calibrate(PlaneSize size, const std::vector<std::span<const std::uint8_t>>& images,
                                            const std::vector<float>& seconds, int iterations,
                                            float tolerance) const = 0;
    /// Robertson et al.'s merge into BGR radiance (3 samples a pixel).
    virtual void robertson_merge(PlaneSize size, const std::vector<std::span<const std::uint8_t>>& images,
                                 const std::vector<float>& seconds, const BgrResponse& response,
                                 std::span<float> radiance) const = 0;
};

/// OpenCV's operations, from the module loaded on first use. Throws ToolError when the
/// module cannot be loaded.
const Vision& vision();

}  // namespace rfd::relight
