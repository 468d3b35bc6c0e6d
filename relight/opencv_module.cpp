// librfd_opencv.so: relight/'s image processing (relight/vision.hpp) on OpenCV. Adaptor code
// only; it links OpenCV and nothing of rfd.

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/photo.hpp>
#include <opencv2/video/tracking.hpp>

#include <stdexcept>

#include "relight/vision.hpp"

namespace rfd::relight {
namespace {

// Matrices viewing rfd's planes in place (no copy).
cv::Mat view(PlaneSize size, std::span<const float> plane, int channels = 1) {
    return {size.height, size.width, CV_32FC(channels), const_cast<float*>(plane.data())};
}
cv::Mat view(PlaneSize size, std::span<float> plane, int channels = 1) {
    return {size.height, size.width, CV_32FC(channels), plane.data()};
}
cv::Mat view(PlaneSize size, std::span<const std::uint8_t> plane, int channels = 1) {
    return {size.height, size.width, CV_8UC(channels), const_cast<std::uint8_t*>(plane.data())};
}
cv::Mat view(PlaneSize size, std::span<std::uint8_t> plane, int channels = 1) {
    return {size.height, size.width, CV_8UC(channels), plane.data()};
}

int border_of(Border border) {
    switch (border) {
        case Border::Zero: return cv::BORDER_CONSTANT;
        case Border::Replicate: return cv::BORDER_REPLICATE;
        case Border::Reflect: return cv::BORDER_REFLECT_101;
    }
    return cv::BORDER_REFLECT_101;
}

std::vector<cv::Mat> bgr_views(PlaneSize size, const std::vector<std::span<const std::uint8_t>>& images) {
    std::vector<cv::Mat> mats;
    for (const auto& image : images) mats.push_back(view(size, image, 3));
    return mats;
}

cv::Mat response_view(const BgrResponse& response) {
    return {static_cast<int>(response.size()), 1, CV_32FC3, const_cast<float*>(response.front().data())};
}

class OpenCv final : public Vision {
public:
    void gaussian_blur(PlaneSize size, std::span<const float> in, std::span<float> out, int kernel, double sigma_x,
                       double sigma_y, Border border) const override {
        cv::Mat target = view(size, out);
        cv::GaussianBlur(view(size, in), target, cv::Size(kernel, kernel), sigma_x, sigma_y, border_of(border));
    }
    void gaussian_blur(PlaneSize size, std::span<const std::uint8_t> in, std::span<std::uint8_t> out,
                       double sigma) const override {
        cv::Mat target = view(size, out);
        cv::GaussianBlur(view(size, in), target, cv::Size(0, 0), sigma);
    }
    void box_blur(PlaneSize size, std::span<float> plane, int kernel) const override {
        cv::Mat m = view(size, plane);
        cv::blur(m, m, cv::Size(kernel, kernel), cv::Point(-1, -1), cv::BORDER_CONSTANT);
    }
    void dilate(PlaneSize size, std::span<std::uint8_t> mask, int kernel) const override {
        cv::Mat m = view(size, mask);
        cv::dilate(m, m, cv::Mat::ones(kernel, kernel, CV_8U));
    }
    int connected_components(PlaneSize size, std::span<const std::uint8_t> mask,
                             std::span<int> labels) const override {
        cv::Mat out(size.height, size.width, CV_32S, labels.data());
        return cv::connectedComponents(view(size, mask), out, 8, CV_32S);
    }
    void distance_transform(PlaneSize size, std::span<const std::uint8_t> mask,
                            std::span<float> distance) const override {
        cv::Mat out = view(size, distance);
        cv::distanceTransform(view(size, mask), out, cv::DIST_L2, cv::DIST_MASK_PRECISE);
    }
    void optical_flow(PlaneSize size, std::span<const std::uint8_t> from, std::span<const std::uint8_t> to,
                      const FlowOptions& o, std::span<float> flow) const override {
        cv::Mat out = view(size, flow, 2);
        cv::calcOpticalFlowFarneback(view(size, from), view(size, to), out, o.pyramid_scale, o.levels, o.window,
                                     o.iterations, o.polynomial_size, o.polynomial_sigma, 0);
    }
    void remap(PlaneSize size, std::span<const float> in, std::span<const float> map_x, std::span<const float> map_y,
               std::span<float> out, Border border) const override {
        cv::Mat target = view(size, out);
        cv::remap(view(size, in), target, view(size, map_x), view(size, map_y), cv::INTER_LINEAR, border_of(border),
                  0.0);
    }
    void resize(PlaneSize in_size, std::span<const float> in, PlaneSize out_size, std::span<float> out) const override {
        cv::Mat target = view(out_size, out);
        const bool shrinking = out_size.width <= in_size.width && out_size.height <= in_size.height;
        cv::resize(view(in_size, in), target, target.size(), 0.0, 0.0, shrinking ? cv::INTER_AREA : cv::INTER_LINEAR);
    }
    void inpaint(PlaneSize size, std::span<const float> in, std::span<const std::uint8_t> mask, double radius,
                 std::span<float> out) const override {
        cv::Mat target = view(size, out);
        cv::inpaint(view(size, in), view(size, mask), target, radius, cv::INPAINT_NS);
    }
    void warp_affine(PlaneSize in_size, std::span<const float> in, const std::array<double, 6>& a, PlaneSize out_size,
                     std::span<float> out, Border border) const override {
        const cv::Matx23d to_source(a[0], a[1], a[2], a[3], a[4], a[5]);
        cv::Mat target = view(out_size, out);
        cv::warpAffine(view(in_size, in), target, to_source, target.size(), cv::INTER_LINEAR | cv::WARP_INVERSE_MAP,
                       border_of(border));
    }
    void scale_to_bytes(std::span<const float> in, double scale, double offset,
                        std::span<std::uint8_t> out) const override {
        const PlaneSize row{static_cast<int>(in.size()), 1};
        cv::Mat target = view(row, out);
        view(row, in).convertTo(target, CV_8U, scale, offset);
    }
    std::vector<std::array<float, 3>> hough_circles(PlaneSize size, std::span<const std::uint8_t> image,
                                                    double min_distance, double canny_threshold, double perfectness,
                                                    int min_radius, int max_radius) const override {
        std::vector<cv::Vec3f> found;
        cv::HoughCircles(view(size, image), found, cv::HOUGH_GRADIENT_ALT, 1.5, min_distance, canny_threshold,
                         perfectness, min_radius, max_radius);
        std::vector<std::array<float, 3>> circles;
        // OpenCV's centres count from the corner of pixel (0, 0)'s centre.
        for (const cv::Vec3f& c : found) circles.push_back({c[0] + 0.5f, c[1] + 0.5f, c[2]});
        return circles;
    }
    BgrResponse robertson_calibrate(PlaneSize size, const std::vector<std::span<const std::uint8_t>>& images,
                                    const std::vector<float>& seconds, int iterations,
                                    float tolerance) const override {
        cv::Mat bgr;
        cv::createCalibrateRobertson(iterations, tolerance)->process(bgr_views(size, images), bgr, seconds);
        BgrResponse response{};
        if (bgr.rows != static_cast<int>(response.size()) || bgr.type() != CV_32FC3)
            throw std::logic_error("OpenCV's Robertson calibration did not return 256 BGR codes");
        for (int z = 0; z < bgr.rows; ++z)
            for (int c = 0; c < 3; ++c) response[static_cast<std::size_t>(z)][static_cast<std::size_t>(c)] = bgr.at<cv::Vec3f>(z)[c];
        return response;
    }
    void robertson_merge(PlaneSize size, const std::vector<std::span<const std::uint8_t>>& images,
                         const std::vector<float>& seconds, const BgrResponse& response,
                         std::span<float> radiance) const override {
        cv::Mat out = view(size, radiance, 3);
        cv::createMergeRobertson()->process(bgr_views(size, images), out, seconds, response_view(response));
    }
};

}  // namespace
}  // namespace rfd::relight

extern "C" __attribute__((visibility("default"))) const rfd::relight::Vision* rfd_opencv_vision() {
    static const rfd::relight::OpenCv vision;
    return &vision;
}
