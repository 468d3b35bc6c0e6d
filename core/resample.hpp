#pragma once
// Resampling an image to another size one axis at a time, from a table of weights per output
// pixel, so that a band of rows comes out exactly as the same rows of the whole image do.
// Fields at camera resolution are scaled while they are read, a band of rows at a time
// (relight/field.hpp); OpenCV's resize takes whole images only, and resizing bands apart
// would shift every band by the fraction of a pixel where it starts.
//
// The weights are those OpenCV's resize used for rfd before (relight/vision.hpp). Shrinking
// an axis (INTER_AREA), each output pixel is the mean of the source pixels it covers, each
// weighted by the part of it covered. Enlarging (INTER_LINEAR), output pixel o blends the two
// source pixels nearest its centre, (o + 0.5) * from / to - 0.5, clamped at the borders.
//
// Example: AxisResampling columns(4000, 1000), rows(3000, 750);
//          Image band = resample_band(source_rows, first_source_row, columns, rows, 0, 64);

#include <vector>

#include "core/image.hpp"

namespace rfd {

/// The weights that take an axis of `from` pixels to `to` pixels (both > 0).
class AxisResampling {
public:
    AxisResampling(int from, int to);

    int from() const { return from_; }
    int to() const { return to_; }
    /// The first and one past the last source pixel output pixel `o` reads.
    int first(int o) const { return first_[static_cast<std::size_t>(o)]; }
    int end(int o) const { return first(o) + static_cast<int>(offset_[static_cast<std::size_t>(o) + 1] -
                                                              offset_[static_cast<std::size_t>(o)]); }
    /// Its weights, one per source pixel from first(o), summing to 1.
    const float* weights(int o) const { return weights_.data() + offset_[static_cast<std::size_t>(o)]; }

private:
    int from_, to_;
    std::vector<int> first_;
    std::vector<std::size_t> offset_;  // into weights_, to_ + 1 entries
    std::vector<float> weights_;
};

/// Output rows [y0, y1) of an image resampled by `columns` and `rows`, from `source`: its
/// rows from `source_y0` on, whole source rows (columns.from() wide), at least those the
/// output rows read (rows.first(y0) to rows.end(y1 - 1)).
Image resample_band(const Image& source, int source_y0, const AxisResampling& columns, const AxisResampling& rows,
                    int y0, int y1);

}  // namespace rfd
