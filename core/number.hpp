#pragma once
// Reading a number a user typed (an option, a file attribute): the whole text must be one
// finite number, as std::stod reads it (leading blanks and a sign allowed); anything else
// is no number, and the caller says what it expected.
//
// Example: if (auto v = finite_number("2.5")) use(*v);

#include <cmath>
#include <optional>
#include <string>

namespace rfd {

inline std::optional<double> finite_number(const std::string& text) {
    std::size_t used = 0;
    double value = 0.0;
    try {
        value = std::stod(text, &used);
    } catch (const std::exception&) {  // not a number, or out of range
        return std::nullopt;
    }
    if (used == 0 || used != text.size() || !std::isfinite(value)) return std::nullopt;
    return value;
}

}  // namespace rfd
