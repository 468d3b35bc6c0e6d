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
