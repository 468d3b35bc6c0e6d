#pragma once
// Numbers in rfd's JSON outputs: JSON has no NaN, no infinity and no "none", so each
// becomes null. One place, for every report that writes JSON.
//
// Example: summary["psnr_db"] = finite_or_null(psnr);  // null for a perfect match (inf)

#include <cmath>
#include <optional>

#include <nlohmann/json.hpp>

namespace rfd {

/// A value, or null when there is none.
inline nlohmann::json json_or_null(const std::optional<double>& value) {
    return value ? nlohmann::json(*value) : nlohmann::json();
}

/// A figure, or null when it is not finite (a PSNR of a perfect match, a NaN).
inline nlohmann::json finite_or_null(double value) {
    return std::isfinite(value) ? nlohmann::json(value) : nlohmann::json();
}

}  // namespace rfd
