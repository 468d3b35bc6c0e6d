#include "patterns/glyphs.hpp"

#include <algorithm>
#include <memory>

#include <cairo.h>

#include "core/error.hpp"

namespace rfd::patterns {

Image text_mask(const std::string& text, int width, int height, double fill) {
    if (width <= 0 || height <= 0)
        throw InputError("text mask size must be positive, got " + std::to_string(width) + " x " +
                         std::to_string(height));
    if (text.empty()) throw InputError("text mask: empty text");
    RFD_CHECK(fill > 0.0 && fill <= 1.0);
    std::unique_ptr<cairo_surface_t, decltype(&cairo_surface_destroy)> surface(
        cairo_image_surface_create(CAIRO_FORMAT_A8, width, height), &cairo_surface_destroy);
    std::unique_ptr<cairo_t, decltype(&cairo_destroy)> cr(cairo_create(surface.get()), &cairo_destroy);
    RFD_CHECK(cairo_status(cr.get()) == CAIRO_STATUS_SUCCESS);
    cairo_select_font_face(cr.get(), "DejaVu Sans", CAIRO_FONT_SLANT_NORMAL, CAIRO_FONT_WEIGHT_BOLD);
    // Measure at a reference size, then scale so the ink box fills the mask.
    constexpr double kReference = 100.0;
    cairo_set_font_size(cr.get(), kReference);
    cairo_text_extents_t ink;
    cairo_text_extents(cr.get(), text.c_str(), &ink);
    if (ink.width <= 0 || ink.height <= 0) throw InputError("text mask: '" + text + "' has no ink");
    const double scale = fill * std::min(width / ink.width, height / ink.height);
    cairo_set_font_size(cr.get(), kReference * scale);
    cairo_text_extents(cr.get(), text.c_str(), &ink);
    cairo_move_to(cr.get(), 0.5 * width - (ink.x_bearing + 0.5 * ink.width),
                  0.5 * height - (ink.y_bearing + 0.5 * ink.height));
    cairo_set_source_rgba(cr.get(), 0, 0, 0, 1);
    cairo_show_text(cr.get(), text.c_str());
    cairo_surface_flush(surface.get());
    const unsigned char* data = cairo_image_surface_get_data(surface.get());
    const int stride = cairo_image_surface_get_stride(surface.get());
    Image mask(width, height, 1);
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x) mask.at(x, y, 0) = data[y * stride + x] / 255.0f;
    return mask;
}

}  // namespace rfd::patterns
