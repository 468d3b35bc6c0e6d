// Checked TOML reading: every mistake a user can make in a file is named with its line.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "core/config.hpp"
#include "core/error.hpp"
#include "optics/lens_file.hpp"

namespace rfd {
namespace {

using ::testing::HasSubstr;

std::string message_of(const std::function<void()>& action) {
    try {
        action();
    } catch (const InputError& error) {
        return error.what();
    }
    return "";
}

TEST(Config, SyntaxErrorNamesTheLine) {
    const std::string message = message_of([] { ConfigTable::parse_string("a = 1\nb = = 2\n", "f.toml"); });
    EXPECT_THAT(message, HasSubstr("f.toml:2:"));
    EXPECT_THAT(message, HasSubstr("TOML syntax error"));
}

TEST(Config, KeysOfTensOfThousandsOfPartsAreRefusedBeforeTheParserRecurses) {
    // toml++ recurses once per dotted part: 40 000 of them overflowed the stack (SIGSEGV).
    const auto parts = [](int n, const std::string& separator) {
        std::string key = "a";
        for (int k = 1; k < n; ++k) key += separator + "a";
        return key;
    };
    EXPECT_THAT(message_of([&] { ConfigTable::parse_string("x = 1\n[" + parts(40000, ".") + "]\n", "deep.toml"); }),
                HasSubstr("deep.toml:2: TOML key of more than 64 dotted parts"));
    EXPECT_THAT(message_of([&] { ConfigTable::parse_string(parts(40000, ".") + " = 1\n", "deep.toml"); }),
                HasSubstr("deep.toml:1: TOML key of more than 64 dotted parts"));
    // 64 parts parse; dots in values, quoted keys, comments and multi-line strings are no parts.
    const std::string dots(500, '.');
    const std::string fine = "[" + parts(64, ".") + "]\n\"" + dots + "\" = \"" + dots + "\"\n" +
                             "b = 1.5 # " + dots + "\nc = \"\"\"\n" + dots + "\n\"\"\"\nd = \'\'\'" + dots + "\'\'\'\n";
    EXPECT_EQ(message_of([&] { ConfigTable::parse_string(fine, "fine.toml"); }), "");
}

TEST(Config, RangesTypesAndUnits) {
    auto table = ConfigTable::parse_string("n = 5\nname = 3\npitch_cm = 0.2\nlist = [1, 2, 3]\n", "f.toml");
    EXPECT_THAT(message_of([&] { table.number("n", 0.0, 1.0); }), HasSubstr("outside the allowed range [0, 1]"));
    EXPECT_THAT(message_of([&] { table.string("name"); }), HasSubstr("f.toml:2:8: name: expected a string, found an integer"));
    EXPECT_THAT(message_of([&] { table.positive("pitch_mm"); }),
                HasSubstr("wrong unit: expected 'pitch_mm' in millimetres, found 'pitch_cm' (centimetres)"));
    EXPECT_THAT(message_of([&] { table.positive_pair("list"); }), HasSubstr("expected an array of two numbers"));
    EXPECT_THAT(message_of([&] { table.positive("absent"); }), HasSubstr("missing required key 'absent'"));
}

TEST(Config, FinishRejectsKeysNobodyRead) {
    auto table = ConfigTable::parse_string("used = 1\n[sub]\nx = 1\ntypo = 2\n", "f.toml");
    table.integer("used", 0, 10);
    auto sub = table.table("sub");
    sub.integer("x", 0, 10);
    EXPECT_NO_THROW(table.finish());
    EXPECT_THAT(message_of([&] { sub.finish(); }), HasSubstr("f.toml:4:8: sub.typo: unknown key"));
}

TEST(Config, IoErrorForAMissingFile) {
    EXPECT_THROW(ConfigTable::parse_file("/nonexistent/design.toml"), IoError);
}

// Lens files: each malformed case with its own message.
std::string lens_error(const std::string& surfaces) {
    return message_of([&] { optics::parse_lens_system("name = \"x\"\n" + surfaces, "lens.toml"); });
}

const std::string kSecond = "[[surface]]\nradius = \"flat\"\nmaterial = \"air\"\nsemi_diameter_mm = 5\n";

TEST(LensFile, MalformedSurfacesAreNamed) {
    EXPECT_THAT(lens_error("[[surface]]\nradius_mm = 0\nthickness_mm = 2\nindex = 1.5\nsemi_diameter_mm = 5\n" + kSecond),
                HasSubstr("radius of 0 is not a surface"));
    EXPECT_THAT(lens_error("[[surface]]\nradius_mm = 20\nthickness_mm = 2\nindex = 1.5\nmaterial = \"N-BK7\"\nsemi_diameter_mm = 5\n" + kSecond),
                HasSubstr("give exactly one of material"));
    EXPECT_THAT(lens_error("[[surface]]\nradius_mm = 20\nthickness_mm = 2\nmaterial = \"glass\"\nsemi_diameter_mm = 5\n" + kSecond),
                HasSubstr("unknown material 'glass'; known: air, N-BK7"));
    EXPECT_THAT(lens_error("[[surface]]\nradius_mm = 4\nthickness_mm = 2\nindex = 1.5\nsemi_diameter_mm = 5\n" + kSecond),
                HasSubstr("does not extend to this semi-diameter"));
    // A biconvex lens too thin for its sags: the surfaces cross inside the aperture.
    EXPECT_THAT(lens_error("[[surface]]\nradius_mm = 10\nthickness_mm = 1\nindex = 1.5\nsemi_diameter_mm = 5\n"
                           "[[surface]]\nradius_mm = -10\nmaterial = \"air\"\nsemi_diameter_mm = 5\n"),
                HasSubstr("intersect inside the aperture"));
    EXPECT_THAT(lens_error("[[surface]]\nradius_mm = 20\nindex = 1.5\nsemi_diameter_mm = 5\n" + kSecond),
                HasSubstr("missing required key 'surface[0].thickness_mm'"));
    EXPECT_THAT(lens_error(kSecond), HasSubstr("at least two surfaces"));
}

}  // namespace
}  // namespace rfd

namespace rfd {
namespace {

using ::testing::Not;

// The message of an exception of the given type, or a text no assertion expects.
template <typename Exception>
std::string message_if(const std::function<void()>& action) {
    try {
        action();
    } catch (const Exception& error) {
        return error.what();
    }
    return "no exception of the expected type";
}

TEST(Config, UnknownKeyNamesFileLineAndDottedKey) {
    auto doc = ConfigTable::parse_string(
        "name = \"d\"\n[lattice]\npitch_mm = 2.358\ncount = [40, 40]\nshape = \"hex\"\n", "design.toml");
    doc.string("name");
    auto lattice = doc.table("lattice");
    lattice.positive("pitch_mm");
    lattice.integer_pair("count", 1, 1000);
    doc.finish();  // the root read everything it has
    const std::string message = message_if<InputError>([&] { lattice.finish(); });
    EXPECT_THAT(message, HasSubstr("design.toml:5:"));
    EXPECT_THAT(message, HasSubstr("lattice.shape: unknown key"));
    // An unknown table at the root is an unknown key of the root.
    auto other = ConfigTable::parse_string("a = 1\n\n[extra]\nb = 2\n", "x.toml");
    other.integer("a", 0, 9);
    EXPECT_THAT(message_if<InputError>([&] { other.finish(); }), HasSubstr("x.toml:3:"));
    EXPECT_THAT(message_if<InputError>([&] { other.finish(); }), HasSubstr("extra: unknown key"));
}

TEST(Config, MissingKeyNamesTheTable) {
    auto doc = ConfigTable::parse_string("[printer]\nname = \"p\"\n", "design.toml");
    auto printer = doc.table("printer");
    const std::string message = message_if<InputError>([&] { printer.number("dpi_x", 1, 1e5); });
    EXPECT_THAT(message, HasSubstr("design.toml:1:"));
    EXPECT_THAT(message, HasSubstr("printer: missing required key 'printer.dpi_x'"));
    auto nested = ConfigTable::parse_string("[[part]]\nx = 1\n", "n.toml");
    auto parts = nested.table_array("part");
    EXPECT_THAT(message_if<InputError>([&] { parts[0].table("optics"); }),
                HasSubstr("missing required key 'part[0].optics'"));
    EXPECT_THAT(message_if<InputError>([&] { nested.table("absent"); }),
                HasSubstr("missing required key 'absent'"));
}

TEST(Config, ASiblingKeyIsNotCalledATypo) {
    // dpi_y is a key of its own, read after dpi_x: a missing dpi_x must not be reported as
    // "dpi_y: unknown key (did you mean 'dpi_x'?)".
    auto doc = ConfigTable::parse_string("[printer]\ndpi_y = 1440\n", "design.toml");
    auto printer = doc.table("printer");
    const std::string message = message_if<InputError>([&] { printer.number("dpi_x", 1, 1e5); });
    EXPECT_THAT(message, HasSubstr("missing required key 'printer.dpi_x'"));
    EXPECT_THAT(message, Not(HasSubstr("unknown key")));
    // A real misspelling one letter away is still pointed at, on its own line.
    auto typo = ConfigTable::parse_string("[printer]\ndpi_x = 2880\ndpy_y = 1440\n", "design.toml");
    auto p = typo.table("printer");
    p.number("dpi_x", 1, 1e5);
    EXPECT_THAT(message_if<InputError>([&] { p.number("dpi_y", 1, 1e5); }),
                HasSubstr("design.toml:3:9: printer.dpy_y: unknown key (did you mean 'dpi_y'?)"));
}

TEST(Config, WrongUnitForRequiredAndOptionalKeys) {
    auto doc = ConfigTable::parse_string("pitch_cm = 0.2358\nthickness_in = 0.1\n", "d.toml");
    // Required: reported when the key is asked for.
    const std::string required = message_if<InputError>([&] { doc.positive("pitch_mm"); });
    EXPECT_THAT(required, HasSubstr("d.toml:1:12: pitch_cm: wrong unit: expected 'pitch_mm' in millimetres, "
                                    "found 'pitch_cm' (centimetres)"));
    // Optional: absent as asked, so finish() reports the key that stood in for it.
    EXPECT_FALSE(doc.optional_number("thickness_mm", 0, 100).has_value());
    const std::string optional = message_if<InputError>([&] { doc.finish(); });
    EXPECT_THAT(optional, HasSubstr("d.toml:2:"));
    EXPECT_THAT(optional, HasSubstr("wrong unit: expected 'thickness_mm' in millimetres, found "
                                    "'thickness_in' (inches)"));
    // A key without a unit where one is expected.
    auto bare = ConfigTable::parse_string("focal_length = 50\n", "d.toml");
    EXPECT_THAT(message_if<InputError>([&] { bare.positive("focal_length_mm"); }),
                HasSubstr("found 'focal_length' (no unit)"));
    // And a misspelt optional key gets its hint from finish().
    auto misspelt = ConfigTable::parse_string("conci = -1\n", "d.toml");
    EXPECT_FALSE(misspelt.optional_number("conic", -1e6, 1e6).has_value());
    EXPECT_THAT(message_if<InputError>([&] { misspelt.finish(); }),
                HasSubstr("d.toml:1:9: conci: unknown key (did you mean 'conic'?)"));
}

TEST(Config, NumbersOutOfRangeOrOfTheWrongKind) {
    auto doc = ConfigTable::parse_string(
        "n = 1.5\nbig = 7\nneg = -2\nzero = 0\nnan = nan\ninf = inf\ncount = [3, 0]\nmode = \"fast\"\n"
        "flag = 1\npair = [1.0, -2.0]\n",
        "r.toml");
    EXPECT_THAT(message_if<InputError>([&] { doc.integer("n", 0, 9); }),
                HasSubstr("r.toml:1:5: n: expected an integer, found a number"));
    EXPECT_THAT(message_if<InputError>([&] { doc.integer("big", 0, 5); }),
                HasSubstr("r.toml:2:7: big: value 7 is outside the allowed range [0, 5]"));
    EXPECT_THAT(message_if<InputError>([&] { doc.number("neg", 0.0, 1.0); }),
                HasSubstr("value -2 is outside the allowed range [0, 1]"));
    EXPECT_THAT(message_if<InputError>([&] { doc.positive("zero"); }), HasSubstr("expected a positive number, found 0"));
    EXPECT_THAT(message_if<InputError>([&] { doc.non_negative("neg"); }), HasSubstr("expected a number >= 0, found -2"));
    EXPECT_THAT(message_if<InputError>([&] { doc.number("nan", -1e9, 1e9); }), HasSubstr("nan: expected a finite number"));
    EXPECT_THAT(message_if<InputError>([&] { doc.positive("inf"); }), HasSubstr("inf: expected a finite number"));
    EXPECT_THAT(message_if<InputError>([&] { doc.integer_pair("count", 1, 10); }),
                HasSubstr("count: value 0 is outside the allowed range [1, 10]"));
    EXPECT_THAT(message_if<InputError>([&] { doc.choice("mode", {"exact", "paraxial"}); }),
                HasSubstr("mode: 'fast' is not one of 'exact', 'paraxial'"));
    EXPECT_THAT(message_if<InputError>([&] { doc.boolean("flag"); }), HasSubstr("expected true or false, found an integer"));
    EXPECT_THAT(message_if<InputError>([&] { doc.positive_pair("pair"); }), HasSubstr("expected two positive numbers"));
    EXPECT_THAT(message_if<InputError>([&] { doc.table("n"); }), HasSubstr("expected a table, found a number"));
}

TEST(Config, ErrorTypesAndExitCodes) {
    // Bad content is an InputError (exit code 2), a missing file an IoError (3); both are
    // rfd::Error, which the CLI's main catches once.
    EXPECT_THROW(ConfigTable::parse_string("x = [", "s.toml"), InputError);
    try {
        ConfigTable::parse_string("a = 1\nb = 2\nc = \"unterminated\n", "s.toml");
        ADD_FAILURE() << "no syntax error";
    } catch (const Error& error) {
        EXPECT_EQ(error.exit_code(), 2);
        EXPECT_THAT(error.what(), HasSubstr("s.toml:3:"));
        EXPECT_THAT(error.what(), HasSubstr("TOML syntax error"));
    }
    try {
        ConfigTable::parse_file("/nonexistent/lens.toml");
        ADD_FAILURE() << "no I/O error";
    } catch (const Error& error) {
        EXPECT_EQ(error.exit_code(), 3);
        EXPECT_THAT(error.what(), HasSubstr("/nonexistent/lens.toml: cannot open"));
    }
    // A duplicate key is a syntax error too, on the line of the second one.
    EXPECT_THAT(message_if<InputError>([] { ConfigTable::parse_string("k = 1\n\nk = 2\n", "s.toml"); }),
                HasSubstr("s.toml:3:"));
}

}  // namespace
}  // namespace rfd
