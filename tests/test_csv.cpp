// The one CSV writer of rfd's reports: what it writes reads back, cell for cell, through an
// independent RFC 4180 reader, whatever the cells hold; and format_text, their lines' printf.

#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "core/csv.hpp"
#include "core/text.hpp"

namespace rfd {
namespace {

// RFC 4180, section 2, read as written there: records end in a line break, a quoted field
// may hold commas, line breaks and doubled quotes.
std::vector<std::vector<std::string>> read_csv(const std::string& text) {
    std::vector<std::vector<std::string>> records(1, std::vector<std::string>(1));
    bool quoted = false;
    for (std::size_t i = 0; i < text.size(); ++i) {
        const char c = text[i];
        std::string& field = records.back().back();
        if (quoted) {
            if (c == '"' && i + 1 < text.size() && text[i + 1] == '"') field += '"', ++i;
            else if (c == '"') quoted = false;
            else field += c;
        } else if (c == '"') {
            quoted = true;
        } else if (c == ',') {
            records.back().emplace_back();
        } else if (c == '\n') {
            records.emplace_back(1);
        } else {
            field += c;
        }
    }
    EXPECT_FALSE(quoted) << "unterminated quote";
    EXPECT_EQ(records.back(), std::vector<std::string>(1)) << "the last record has no line break";
    records.pop_back();
    return records;
}

TEST(CsvTable, ReadsBackCellForCellWhateverTheCellsHold) {
    const std::vector<std::string> columns{"light", "psnr_db", "note"};
    const std::vector<std::vector<std::string>> rows{
        {"10,20", format_fixed(31.25, 4), "plain"},
        {"say \"hi\"", format_number(1e-7), "two\nlines"},
        {"", "nan", "\"\""},
        {",", "\r", "a,\"b\",c"},
    };
    CsvTable table(columns);
    for (const auto& row : rows) table.add_row(row);
    EXPECT_EQ(table.rows(), rows.size());
    EXPECT_EQ(table.columns(), columns.size());

    const auto read = read_csv(table.text());
    ASSERT_EQ(read.size(), rows.size() + 1);
    EXPECT_EQ(read[0], columns);
    for (std::size_t r = 0; r < rows.size(); ++r) EXPECT_EQ(read[r + 1], rows[r]) << "row " << r;
}

TEST(CsvTable, QuotesOnlyWhatNeedsIt) {
    CsvTable table({"index", "value"});
    table.add_row({"0", "1.5000"});
    // Plain cells stay as written: tables that never needed quotes read the same as before.
    EXPECT_EQ(table.text(), "index,value\n0,1.5000\n");
    EXPECT_EQ(csv_flag(true) + csv_flag(false), "10");
}

// format_text, the reports' printf into a string: any length, and the same digits as
// format_fixed and format_number write.
TEST(FormatText, AnyLengthAndTheSameDigitsAsTheNumberFormatters) {
    const std::string long_word(3000, 'x');
    const std::string text = format_text("%s|%.4f|%g", long_word.c_str(), 31.25, 1e-7);
    EXPECT_EQ(text, long_word + "|" + format_fixed(31.25, 4) + "|" + format_number(1e-7));
    EXPECT_EQ(format_text("%s", ""), "");
}

}  // namespace
}  // namespace rfd
