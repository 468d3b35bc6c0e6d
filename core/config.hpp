#pragma once
// Checked reading of TOML input files (designs, lens systems, scenes).
//
// Every value is read through a ConfigTable, which remembers which keys were asked for.
// finish() then rejects every key nobody read, so a typo or a key in the wrong unit
// ("pitch_cm" where "pitch_mm" is expected) is an error naming file, line and key instead
// of being silently ignored (pbrt-v4's ParameterDictionary::ReportUnused).
//
// Units live in key suffixes: _mm (millimetres), _deg (degrees), _dpi (dots per inch).
// Example:
//   auto doc = ConfigTable::parse_file("designs/design1.toml");
//   double pitch = doc.table("lattice").positive("pitch_mm");
//   doc.finish();

#include <array>
#include <filesystem>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <string_view>
#include <vector>

#include "core/error.hpp"
#include "core/options.hpp"

namespace toml {
inline namespace v3 {
class table;
class node;
}  // namespace v3
}  // namespace toml

namespace rfd {

class ConfigTable {
public:
    /// Parses a TOML file; syntax errors become InputError with file, line and column.
    static ConfigTable parse_file(const std::filesystem::path& path);
    /// Parses TOML text; `name` stands for the file in messages.
    static ConfigTable parse_string(std::string_view text, const std::string& name);

    ConfigTable(const ConfigTable&) = delete;
    ConfigTable& operator=(const ConfigTable&) = delete;
    ConfigTable(ConfigTable&&) noexcept;
    ConfigTable& operator=(ConfigTable&&) noexcept;
    ~ConfigTable();

    bool has(const std::string& key) const;
    /// The key is there and holds a string (for values that are a number or a word).
    bool is_string(const std::string& key) const;
    /// Keys of this table in file order (by line); reading them is the caller's business.
    std::vector<std::string> keys() const;

    /// Required number (integers accepted) within [min, max].
    double number(const std::string& key, double min, double max);
    /// Required number > 0.
    double positive(const std::string& key);
    /// Required number >= 0.
    double non_negative(const std::string& key);
    /// Optional number within [min, max]; nullopt when absent.
    std::optional<double> optional_number(const std::string& key, double min, double max);
    /// Required integer within [min, max].
    long long integer(const std::string& key, long long min, long long max);
    std::optional<long long> optional_integer(const std::string& key, long long min,
                                              long long max);
    /// An option declared once (core/options.hpp) under its key: its default when absent,
    /// checked against its range otherwise.
    double value(const NumberOption& option);
    long long value(const IntegerOption& option);
    bool boolean(const std::string& key);
    std::optional<bool> optional_boolean(const std::string& key);
    std::string string(const std::string& key);
    std::optional<std::string> optional_string(const std::string& key);
    /// Required string that must be one of `choices`.
    std::string choice(const std::string& key, const std::vector<std::string>& choices);
    /// Required array of exactly two numbers, each > 0.
    std::array<double, 2> positive_pair(const std::string& key);
    /// Required array of exactly two integers within [min, max].
    std::array<long long, 2> integer_pair(const std::string& key, long long min,
                                          long long max);

    /// Required array of exactly `count` numbers, each within [min, max] (points, directions,
    /// colours: `center_mm = [0, 0, 20]`).
    std::vector<double> numbers(const std::string& key, std::size_t count, double min,
                                double max);

    /// Required array of `min_count` to `max_count` numbers, each within [min, max]
    /// (measured curves: `transmittance = [1, 0.82, 0.61]`).
    std::vector<double> number_list(const std::string& key, std::size_t min_count, std::size_t max_count,
                                    double min, double max);

    /// Required array of strings, possibly empty (`formats = ["pdf", "tif"]`).
    std::vector<std::string> strings(const std::string& key);

    /// Required sub-table.
    ConfigTable table(const std::string& key);
    std::optional<ConfigTable> optional_table(const std::string& key);
    /// Required array of tables (`[[key]]`), at least one entry.
    std::vector<ConfigTable> table_array(const std::string& key);

    /// Throws InputError for the first key of this table that was never read.
    /// Sub-tables obtained from this table check their own keys in their own finish().
    void finish() const;

    /// Location of `key` in this table (or of the table itself when the key is absent).
    SourceLocation location(const std::string& key) const;
    /// Location of this table.
    SourceLocation location() const;
    /// Dotted path of this table, "" for the document root.
    const std::string& path() const { return path_; }
    const std::string& file() const { return file_; }

    /// An InputError at `key` with `message`.
    [[noreturn]] void fail(const std::string& key, const std::string& message) const;

private:
    ConfigTable(std::shared_ptr<const toml::table> root, const toml::table* table,
                std::string file, std::string path);
    const toml::node* find(const std::string& key) const;
    const toml::node& require(const std::string& key);
    std::string full_key(const std::string& key) const;
    [[noreturn]] void fail_missing(const std::string& key) const;

    std::shared_ptr<const toml::table> root_;  // keeps the parsed document alive
    const toml::table* table_ = nullptr;
    std::string file_;
    std::string path_;
    mutable std::set<std::string> read_;
};

/// `text` as a TOML basic string, quoted and escaped: for files that rfd writes and reads back.
std::string toml_string(const std::string& text);

}  // namespace rfd
