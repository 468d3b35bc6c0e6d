#pragma once
// The CSV tables of rfd's reports (RFC 4180): a header row, then one row per record; a cell
// holding a comma, a double quote or a line break is quoted, its quotes doubled. Cells are
// text: the caller formats numbers (format_fixed for a set number of decimals,
// format_number for significant digits), so the same figures give the same bytes. Charts'
// data files are gnuplot's own (core/plot.hpp), not these.
//
// Example:
//   CsvTable table({"index", "psnr_db"});
//   table.add_row({std::to_string(k), format_fixed(psnr, 4)});
//   table.write(out / "directions.csv");

#include <cstddef>
#include <filesystem>
#include <string>
#include <vector>

namespace rfd {

class CsvTable {
public:
    explicit CsvTable(std::vector<std::string> columns);

    /// One record: exactly one cell per column (a programmer's error otherwise: RFD_CHECK).
    void add_row(std::vector<std::string> cells);

    std::size_t columns() const { return columns_.size(); }
    std::size_t rows() const { return rows_.size(); }

    /// The table as CSV, "\n" after every row.
    std::string text() const;
    /// Written atomically (core/files.hpp): a reader never sees half a table.
    void write(const std::filesystem::path& file) const;

private:
    std::vector<std::string> columns_;
    std::vector<std::vector<std::string>> rows_;
};

/// "1" or "0": how rfd's tables write a yes or no.
inline std::string csv_flag(bool value) { return value ? "1" : "0"; }

}  // namespace rfd
