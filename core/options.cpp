#include "core/options.hpp"

#include "core/text.hpp"

namespace rfd {
namespace {

template <class Option>
std::string with_unit_and_range(const Option& option) {
    std::string text(option.help);
    if (!option.unit.empty()) text += ", " + std::string(option.unit);
    return text;
}

}  // namespace

std::string range_text(const NumberOption& option) {
    return format_number(option.min) + ".." + format_number(option.max);
}

std::string range_text(const IntegerOption& option) {
    return std::to_string(option.min) + ".." + std::to_string(option.max);
}

std::string help_text(const NumberOption& option) { return with_unit_and_range(option); }
std::string help_text(const IntegerOption& option) { return with_unit_and_range(option); }

}  // namespace rfd
