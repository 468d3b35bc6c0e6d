#include "core/config.hpp"

#include "core/files.hpp"
#include "core/text.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <fstream>
#include <sstream>

#include <toml++/toml.h>

namespace rfd {
namespace {

// The unit suffixes a key may carry, with what they mean, for "wrong unit" messages.
struct UnitSuffix {
    std::string_view suffix;
    std::string_view meaning;
};
constexpr UnitSuffix kKnownSuffixes[] = {
    {"_mm", "millimetres"}, {"_cm", "centimetres"}, {"_m", "metres"},
    {"_um", "micrometres"}, {"_in", "inches"},      {"_deg", "degrees"},
    {"_rad", "radians"},    {"_dpi", "dots per inch"}, {"_dpcm", "dots per centimetre"},
};

std::string_view stem_of(std::string_view key) {
    for (const auto& unit : kKnownSuffixes) {
        if (key.size() > unit.suffix.size() && key.ends_with(unit.suffix))
            return key.substr(0, key.size() - unit.suffix.size());
    }
    return key;
}

std::string_view unit_meaning(std::string_view key) {
    for (const auto& unit : kKnownSuffixes)
        if (key.size() > unit.suffix.size() && key.ends_with(unit.suffix)) return unit.meaning;
    return "no unit";
}

// Levenshtein distance, for "did you mean" hints on short keys.
std::size_t edit_distance(std::string_view a, std::string_view b) {
    std::vector<std::size_t> previous(b.size() + 1), current(b.size() + 1);
    for (std::size_t j = 0; j <= b.size(); ++j) previous[j] = j;
    for (std::size_t i = 1; i <= a.size(); ++i) {
        current[0] = i;
        for (std::size_t j = 1; j <= b.size(); ++j)
            current[j] = std::min({previous[j] + 1, current[j - 1] + 1,
                                   previous[j - 1] + (a[i - 1] == b[j - 1] ? 0 : 1)});
        std::swap(previous, current);
    }
    return previous[b.size()];
}

// Keys that differ in one whole word, such as dpi_x and dpi_y, are siblings rather than
// typos of each other, however short the words.
bool differ_by_a_whole_word(std::string_view a, std::string_view b) {
    while (!a.empty() && !b.empty()) {
        const std::string_view word_a = a.substr(0, a.find('_'));
        const std::string_view word_b = b.substr(0, b.find('_'));
        if (word_a != word_b &&
            edit_distance(word_a, word_b) == std::max(word_a.size(), word_b.size()))
            return true;
        a.remove_prefix(std::min(a.size(), word_a.size() + 1));
        b.remove_prefix(std::min(b.size(), word_b.size() + 1));
    }
    return false;
}

// `found` is a misspelling of `wanted`: a letter or two away, and not a sibling key.
bool is_typo_of(std::string_view found, std::string_view wanted) {
    return edit_distance(found, wanted) <= 2 && !differ_by_a_whole_word(found, wanted);
}

// `found` stands where `wanted` was expected, in another unit (or none).
bool is_unit_mistake(std::string_view found, std::string_view wanted) {
    return found != wanted && stem_of(wanted) != wanted && stem_of(found) == stem_of(wanted);
}

std::string wrong_unit_message(std::string_view wanted, std::string_view found) {
    return "wrong unit: expected '" + std::string(wanted) + "' in " +
           std::string(unit_meaning(wanted)) + ", found '" + std::string(found) + "' (" +
           std::string(unit_meaning(found)) + ")";
}

std::string type_name(const toml::node& node) {
    switch (node.type()) {
        case toml::node_type::table: return "a table";
        case toml::node_type::array: return "an array";
        case toml::node_type::string: return "a string";
        case toml::node_type::integer: return "an integer";
        case toml::node_type::floating_point: return "a number";
        case toml::node_type::boolean: return "a boolean";
        default: return "a date or time";
    }
}

std::optional<double> as_number(const toml::node& node) {
    if (auto v = node.value_exact<double>()) return *v;
    if (auto v = node.value_exact<int64_t>()) return static_cast<double>(*v);
    return std::nullopt;
}

// toml++ parses a dotted key recursively, a level per part, so a key of tens of thousands
// of parts overflows the stack (SIGSEGV) before any error can be given. rfd's keys have a
// few parts: refuse a key of more than kMaxKeyParts before parsing. A key is what precedes
// '=' on a line, or a [table] header; quoted parts, values, comments and the lines of
// multi-line strings are skipped.
constexpr int kMaxKeyParts = 64;

void check_key_depth(std::string_view text, const std::string& name) {
    bool in_multiline = false;
    std::string_view multiline_quote;
    int line_number = 0;
    std::size_t start = 0;
    while (start <= text.size()) {
        std::size_t end = text.find('\n', start);
        if (end == std::string_view::npos) end = text.size();
        const std::string_view line = text.substr(start, end - start);
        start = end + 1;
        ++line_number;
        std::size_t i = 0;
        if (in_multiline) {
            const std::size_t close = line.find(multiline_quote);
            if (close == std::string_view::npos) continue;
            in_multiline = false;
            i = close + 3;
        }
        int parts = 1;
        bool in_key = true;
        for (; i < line.size(); ++i) {
            const char c = line[i];
            if (c == '#') break;
            if (c == '"' || c == '\'') {
                const std::string_view triple = c == '"' ? "\"\"\"" : "'''";
                if (line.substr(i, 3) == triple) {
                    const std::size_t close = line.find(triple, i + 3);
                    if (close == std::string_view::npos) {
                        in_multiline = true;
                        multiline_quote = triple;
                        break;
                    }
                    i = close + 2;
                    continue;
                }
                // A one-line string: skip to its closing quote (a basic string's \" is no end).
                for (++i; i < line.size() && line[i] != c; ++i)
                    if (c == '"' && line[i] == '\\') ++i;
                continue;
            }
            if (c == '=') in_key = false;
            if (c == '.' && in_key && ++parts > kMaxKeyParts)
                throw InputError(SourceLocation{name, line_number},
                                 "TOML key of more than " + std::to_string(kMaxKeyParts) + " dotted parts");
        }
    }
}

}  // namespace

ConfigTable::ConfigTable(std::shared_ptr<const toml::table> root, const toml::table* table,
                         std::string file, std::string path)
    : root_(std::move(root)), table_(table), file_(std::move(file)), path_(std::move(path)) {}

ConfigTable::ConfigTable(ConfigTable&&) noexcept = default;
ConfigTable& ConfigTable::operator=(ConfigTable&&) noexcept = default;
ConfigTable::~ConfigTable() = default;

ConfigTable ConfigTable::parse_file(const std::filesystem::path& path) {
    return parse_string(read_text_file(path), path.string());
}

ConfigTable ConfigTable::parse_string(std::string_view text, const std::string& name) {
    check_key_depth(text, name);
    try {
        auto root = std::make_shared<const toml::table>(toml::parse(text, name));
        return ConfigTable(root, root.get(), name, "");
    } catch (const toml::parse_error& error) {
        const auto& begin = error.source().begin;
        throw InputError(SourceLocation{name, static_cast<int>(begin.line),
                                        static_cast<int>(begin.column), ""},
                         std::string("TOML syntax error: ") + std::string(error.description()));
    }
}

bool ConfigTable::has(const std::string& key) const { return find(key) != nullptr; }

bool ConfigTable::is_string(const std::string& key) const {
    const toml::node* node = find(key);
    return node != nullptr && node->is_string();
}

std::vector<std::string> ConfigTable::keys() const {
    std::vector<std::pair<int, std::string>> ordered;
    for (const auto& [key, node] : *table_)
        ordered.emplace_back(static_cast<int>(node.source().begin.line), std::string(key.str()));
    std::stable_sort(ordered.begin(), ordered.end());
    std::vector<std::string> names;
    for (auto& entry : ordered) names.push_back(std::move(entry.second));
    return names;
}

const toml::node* ConfigTable::find(const std::string& key) const {
    return table_->get(key);
}

std::string ConfigTable::full_key(const std::string& key) const {
    return path_.empty() ? key : path_ + "." + key;
}

SourceLocation ConfigTable::location(const std::string& key) const {
    const toml::node* node = find(key);
    const auto& source = node ? node->source() : table_->source();
    return SourceLocation{file_, static_cast<int>(source.begin.line),
                          static_cast<int>(source.begin.column), full_key(key)};
}

SourceLocation ConfigTable::location() const {
    const auto& source = table_->source();
    return SourceLocation{file_, static_cast<int>(source.begin.line),
                          static_cast<int>(source.begin.column), path_};
}

void ConfigTable::fail(const std::string& key, const std::string& message) const {
    throw InputError(location(key), message);
}

void ConfigTable::fail_missing(const std::string& key) const {
    // A key with the same stem but another unit suffix is almost certainly a unit mistake.
    for (const auto& [other, node] : *table_) {
        const std::string other_key(other.str());
        if (is_unit_mistake(other_key, key)) {
            read_.insert(other_key);
            throw InputError(location(other_key), wrong_unit_message(key, other_key));
        }
    }
    // An unread key a letter or two away is a typo of this one: point at the typo.
    for (const auto& [other, node] : *table_) {
        const std::string other_key(other.str());
        if (read_.count(other_key) || !is_typo_of(other_key, key)) continue;
        throw InputError(location(other_key), "unknown key (did you mean '" + key + "'?)");
    }
    throw InputError(location(), "missing required key '" + full_key(key) + "'");
}

const toml::node& ConfigTable::require(const std::string& key) {
    read_.insert(key);
    const toml::node* node = find(key);
    if (!node) fail_missing(key);
    return *node;
}

double ConfigTable::number(const std::string& key, double min, double max) {
    const toml::node& node = require(key);
    const auto value = as_number(node);
    if (!value) fail(key, "expected a number, found " + type_name(node));
    if (!std::isfinite(*value)) fail(key, "expected a finite number");
    if (*value < min || *value > max)
        fail(key, "value " + format_number(*value) + " is outside the allowed range [" +
                      format_number(min) + ", " + format_number(max) + "]");
    return *value;
}

double ConfigTable::positive(const std::string& key) {
    const double value = number(key, -HUGE_VAL, HUGE_VAL);
    if (!(value > 0.0)) fail(key, "expected a positive number, found " + format_number(value));
    return value;
}

double ConfigTable::non_negative(const std::string& key) {
    const double value = number(key, -HUGE_VAL, HUGE_VAL);
    if (value < 0.0) fail(key, "expected a number >= 0, found " + format_number(value));
    return value;
}

std::optional<double> ConfigTable::optional_number(const std::string& key, double min,
                                                   double max) {
    if (!has(key)) {
        read_.insert(key);
        return std::nullopt;
    }
    return number(key, min, max);
}

double ConfigTable::value(const NumberOption& option) {
    return optional_number(std::string(option.key), option.min, option.max).value_or(option.fallback);
}

long long ConfigTable::value(const IntegerOption& option) {
    return optional_integer(std::string(option.key), option.min, option.max).value_or(option.fallback);
}

long long ConfigTable::integer(const std::string& key, long long min, long long max) {
    const toml::node& node = require(key);
    const auto value = node.value_exact<int64_t>();
    if (!value) fail(key, "expected an integer, found " + type_name(node));
    if (*value < min || *value > max)
        fail(key, "value " + std::to_string(*value) + " is outside the allowed range [" +
                      std::to_string(min) + ", " + std::to_string(max) + "]");
    return *value;
}

std::optional<long long> ConfigTable::optional_integer(const std::string& key, long long min,
                                                       long long max) {
    if (!has(key)) {
        read_.insert(key);
        return std::nullopt;
    }
    return integer(key, min, max);
}

bool ConfigTable::boolean(const std::string& key) {
    const toml::node& node = require(key);
    const auto value = node.value_exact<bool>();
    if (!value) fail(key, "expected true or false, found " + type_name(node));
    return *value;
}

std::optional<bool> ConfigTable::optional_boolean(const std::string& key) {
    if (!has(key)) {
        read_.insert(key);
        return std::nullopt;
    }
    return boolean(key);
}

std::string ConfigTable::string(const std::string& key) {
    const toml::node& node = require(key);
    const auto value = node.value_exact<std::string>();
    if (!value) fail(key, "expected a string, found " + type_name(node));
    return *value;
}

std::optional<std::string> ConfigTable::optional_string(const std::string& key) {
    if (!has(key)) {
        read_.insert(key);
        return std::nullopt;
    }
    return string(key);
}

std::string ConfigTable::choice(const std::string& key, const std::vector<std::string>& choices) {
    std::string value = string(key);
    if (std::find(choices.begin(), choices.end(), value) != choices.end()) return value;
    std::string list;
    for (const auto& c : choices) list += (list.empty() ? "'" : ", '") + c + "'";
    fail(key, "'" + value + "' is not one of " + list);
}

std::array<double, 2> ConfigTable::positive_pair(const std::string& key) {
    const toml::node& node = require(key);
    const toml::array* array = node.as_array();
    if (!array || array->size() != 2)
        fail(key, "expected an array of two numbers, e.g. [24.0, 24.0]");
    std::array<double, 2> result{};
    for (std::size_t i = 0; i < 2; ++i) {
        const auto value = as_number(*array->get(i));
        if (!value || !(*value > 0.0) || !std::isfinite(*value))
            fail(key, "expected two positive numbers");
        result[i] = *value;
    }
    return result;
}

std::array<long long, 2> ConfigTable::integer_pair(const std::string& key, long long min,
                                                   long long max) {
    const toml::node& node = require(key);
    const toml::array* array = node.as_array();
    if (!array || array->size() != 2) fail(key, "expected an array of two integers, e.g. [6, 5]");
    std::array<long long, 2> result{};
    for (std::size_t i = 0; i < 2; ++i) {
        const auto value = array->get(i)->value_exact<int64_t>();
        if (!value) fail(key, "expected two integers");
        if (*value < min || *value > max)
            fail(key, "value " + std::to_string(*value) + " is outside the allowed range [" +
                          std::to_string(min) + ", " + std::to_string(max) + "]");
        result[i] = *value;
    }
    return result;
}

std::vector<double> ConfigTable::numbers(const std::string& key, std::size_t count, double min,
                                         double max) {
    const toml::node& node = require(key);
    const toml::array* array = node.as_array();
    if (!array || array->size() != count)
        fail(key, "expected an array of " + std::to_string(count) + " numbers");
    std::vector<double> result(count);
    for (std::size_t i = 0; i < count; ++i) {
        const auto value = as_number(*array->get(i));
        if (!value || !std::isfinite(*value))
            fail(key, "expected " + std::to_string(count) + " finite numbers");
        if (*value < min || *value > max)
            fail(key, "value " + format_number(*value) + " is outside the allowed range [" +
                          format_number(min) + ", " + format_number(max) + "]");
        result[i] = *value;
    }
    return result;
}

std::vector<double> ConfigTable::number_list(const std::string& key, std::size_t min_count, std::size_t max_count,
                                              double min, double max) {
    const toml::array* array = require(key).as_array();
    const std::string expected = "expected an array of " + std::to_string(min_count) + " to " +
                                 std::to_string(max_count) + " numbers from " + format_number(min) + " to " +
                                 format_number(max);
    if (!array || array->size() < min_count || array->size() > max_count) fail(key, expected);
    std::vector<double> result;
    for (const toml::node& element : *array) {
        const auto value = as_number(element);
        if (!value || !std::isfinite(*value) || *value < min || *value > max)
            fail(key, expected + ", found " + (value ? format_number(*value) : type_name(element)));
        result.push_back(*value);
    }
    return result;
}

std::vector<std::string> ConfigTable::strings(const std::string& key) {
    const toml::array* array = require(key).as_array();
    if (!array) fail(key, "expected an array of strings");
    std::vector<std::string> result;
    for (const toml::node& element : *array) {
        const auto* text = element.as_string();
        if (!text) fail(key, "expected an array of strings, found " + type_name(element) + " in it");
        result.push_back(text->get());
    }
    return result;
}

ConfigTable ConfigTable::table(const std::string& key) {
    const toml::node& node = require(key);
    const toml::table* sub = node.as_table();
    if (!sub) fail(key, "expected a table, found " + type_name(node));
    return ConfigTable(root_, sub, file_, full_key(key));
}

std::optional<ConfigTable> ConfigTable::optional_table(const std::string& key) {
    if (!has(key)) {
        read_.insert(key);
        return std::nullopt;
    }
    return table(key);
}

std::vector<ConfigTable> ConfigTable::table_array(const std::string& key) {
    const toml::node& node = require(key);
    const toml::array* array = node.as_array();
    if (!array || !array->is_array_of_tables() || array->empty())
        fail(key, "expected one or more [[" + full_key(key) + "]] tables");
    std::vector<ConfigTable> tables;
    for (std::size_t i = 0; i < array->size(); ++i)
        tables.push_back(ConfigTable(root_, array->get(i)->as_table(), file_,
                                     full_key(key) + "[" + std::to_string(i) + "]"));
    return tables;
}

void ConfigTable::finish() const {
    for (const auto& key : keys()) {
        if (read_.count(key)) continue;
        // A key that was asked for and is absent (an optional one) explains most unknown
        // keys: the same quantity in another unit, or a typo.
        for (const auto& wanted : read_)
            if (!find(wanted) && is_unit_mistake(key, wanted))
                throw InputError(location(key), wrong_unit_message(wanted, key));
        for (const auto& wanted : read_)
            if (!find(wanted) && is_typo_of(key, wanted))
                throw InputError(location(key), "unknown key (did you mean '" + wanted + "'?)");
        throw InputError(location(key), "unknown key");
    }
}

std::string toml_string(const std::string& text) {
    std::ostringstream out;
    out << toml::value<std::string>(text);
    return out.str();
}

}  // namespace rfd
