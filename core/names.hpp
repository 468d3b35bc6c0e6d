#pragma once
// Names of enumerators as files and the command line spell them: one table per enum, kept
// beside the enum, read both ways through these helpers, so a choice is parsed and printed
// by one codec wherever it appears.
//
// Example:
//   enum class ImageFit { Cover, Contain, Stretch };
//   inline constexpr std::array kImageFitNames{Named{ImageFit::Cover, "cover"}, ...};
//   name_of(kImageFitNames, ImageFit::Cover)          // "cover"
//   value_of(kImageFitNames, "contain", where)       // ImageFit::Contain
//   value_of(kImageFitNames, "fill", where)          // InputError "expected 'cover', ... got 'fill'"

#include <array>
#include <cstddef>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "core/error.hpp"

namespace rfd {

template <class Enum>
struct Named {
    Enum value;
    std::string_view name;
};
// Spelled out for compilers without C++20's deduction for aggregates (clang before 17).
template <class Enum>
Named(Enum, const char*) -> Named<Enum>;

/// The name of `value`; every enumerator has one (RFD_CHECK'ed).
template <class Enum, std::size_t N>
std::string_view name_of(const std::array<Named<Enum>, N>& names, Enum value) {
    for (const Named<Enum>& entry : names)
        if (entry.value == value) return entry.name;
    RFD_CHECK_MSG(false, "an enumerator without a name");
    return {};
}

/// The enumerator named `text`, or nullopt.
template <class Enum, std::size_t N>
std::optional<Enum> find_value(const std::array<Named<Enum>, N>& names, std::string_view text) {
    for (const Named<Enum>& entry : names)
        if (entry.name == text) return entry.value;
    return std::nullopt;
}

/// "'a', 'b' or 'c'": the names for a message.
template <class Enum, std::size_t N>
std::string quoted_names(const std::array<Named<Enum>, N>& names) {
    std::string out;
    for (std::size_t k = 0; k < N; ++k) {
        if (k > 0) out += k + 1 == N ? " or " : ", ";
        out += "'" + std::string(names[k].name) + "'";
    }
    return out;
}

/// The names in order, e.g. for a command-line option's list of choices.
template <class Enum, std::size_t N>
std::vector<std::string> names_of(const std::array<Named<Enum>, N>& names) {
    std::vector<std::string> out;
    for (const Named<Enum>& entry : names) out.emplace_back(entry.name);
    return out;
}

/// The enumerator named `text`; InputError at `where` listing the names otherwise.
template <class Enum, std::size_t N>
Enum value_of(const std::array<Named<Enum>, N>& names, std::string_view text, const SourceLocation& where) {
    if (const std::optional<Enum> value = find_value(names, text)) return *value;
    throw InputError(where, "expected " + quoted_names(names) + ", got '" + std::string(text) + "'");
}

}  // namespace rfd
