#include "core/csv.hpp"

#include <utility>

#include "core/error.hpp"
#include "core/files.hpp"

namespace rfd {
namespace {

void append_cell(std::string& out, const std::string& cell) {
    if (cell.find_first_of(",\"\n\r") == std::string::npos) {
        out += cell;
        return;
    }
    out += '"';
    for (char c : cell) {
        if (c == '"') out += '"';
        out += c;
    }
    out += '"';
}

void append_row(std::string& out, const std::vector<std::string>& cells) {
    for (std::size_t k = 0; k < cells.size(); ++k) {
        if (k) out += ',';
        append_cell(out, cells[k]);
    }
    out += '\n';
}

}  // namespace

CsvTable::CsvTable(std::vector<std::string> columns) : columns_(std::move(columns)) {
    RFD_CHECK(!columns_.empty());
}

void CsvTable::add_row(std::vector<std::string> cells) {
    RFD_CHECK(cells.size() == columns_.size());
    rows_.push_back(std::move(cells));
}

std::string CsvTable::text() const {
    std::string out;
    append_row(out, columns_);
    for (const auto& row : rows_) append_row(out, row);
    return out;
}

void CsvTable::write(const std::filesystem::path& file) const { write_text_file(file, text()); }

}  // namespace rfd
