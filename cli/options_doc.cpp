// rfd options-doc (hidden): every command's options as Markdown, from the options as the
// commands declare them. docs/options.md is this output (`make docs`); the ctest
// `doc_options` fails when the two differ, so the page cannot drift from the program.

#include <cstdio>
#include <string>
#include <type_traits>
#include <variant>

#include "cli/commands.hpp"
#include "core/text.hpp"
#include "project/project.hpp"

namespace rfd::cli {
namespace {

// A table cell: no line breaks, and a '|' that would end the cell escaped.
std::string cell(std::string text) {
    std::string out;
    for (char c : text) {
        if (c == '|') out += "\\|";
        else if (c == '\n') out += ' ';
        else out += c;
    }
    return out;
}

// `text` with every `from` replaced by `to`.
std::string replaced(std::string text, const std::string& from, const std::string& to) {
    for (std::size_t at = text.find(from); at != std::string::npos; at = text.find(from, at + to.size()))
        text.replace(at, from.size(), to);
    return text;
}

// CLI11's type and checks ("FLOAT:FLOAT in [-20 - 20]", "TEXT:{auto,exact}") as a reader
// writes them ("number, -20..20", "auto, exact").
std::string value_text(const CLI::Option& option) {
    const std::string type = option.get_type_name();
    std::string base = type.substr(0, type.find(':'));
    if (base == "FLOAT") base = "number";
    else if (base == "INT" || base == "UINT") base = "integer";
    else if (base == "TEXT") base = "text";
    if (option.get_expected_max() > 1) base += " ...";
    // Plain searches, not std::regex: GCC 12 warns inside <regex> in the sanitizer build.
    if (const auto open = type.find('{'), close = type.find('}'); open != std::string::npos && close > open)
        return replaced(type.substr(open + 1, close - open - 1), ",", ", ");
    if (const auto start = type.find("in ["); start != std::string::npos) {
        const auto dash = type.find(" - ", start), end = type.find(']', start);
        if (dash != std::string::npos && end != std::string::npos && dash < end)
            return base + ", " + type.substr(start + 4, dash - start - 4) + ".." + type.substr(dash + 3, end - dash - 3);
    }
    if (type.find("NONNEGATIVE") != std::string::npos) return base + ", >= 0";
    if (type.find("POSITIVE") != std::string::npos) return base + ", > 0";
    return base;
}

void write_command(std::string& out, const CLI::App& command, const std::string& path) {
    std::string rows;
    for (const CLI::Option* option : command.get_options()) {
        if (option->check_lname("help") || option->check_lname("quiet") || option->get_group().empty()) continue;
        const bool flag = option->get_type_name().empty();
        std::string names = option->get_positional() ? option->get_name(true) : option->get_name(false, true);
        names = replaced(names, ",", "`, `");
        std::string what = option->get_description();
        if (option->get_required()) what = "Required. " + what;
        rows += "| `" + names + "` | " + (flag ? "flag" : cell(value_text(*option))) + " | " +
                cell(option->get_default_str()) + " | " + cell(what) + " |\n";
    }
    if (!rows.empty()) {
        out += "## `" + path + "`\n\n" + cell(command.get_description()) + "\n\n";
        out += "| option | value | default | what it sets |\n|---|---|---|---|\n" + rows + "\n";
    }
    for (const CLI::App* sub : command.get_subcommands([](const CLI::App* app) { return !app->get_group().empty(); }))
        write_command(out, *sub, path + " " + sub->get_name());
}

// The project file's declared keys (project::declared_keys), in the same columns.
std::string project_keys_table() {
    std::string out = "## Project files (`rfd make`)\n\nThe keys of a project file that commands share "
                      "(the whole file: [formats](formats.md#project-files-rfd-make-projecttoml---out-dir-examplestoml)).\n\n"
                      "| key | value | default | what it sets |\n|---|---|---|---|\n";
    for (const project::DeclaredKey& key : project::declared_keys())
        std::visit(
            [&](const auto& option) {
                const bool integer = std::is_same_v<std::decay_t<decltype(option)>, IntegerOption>;
                std::string fallback;
                if constexpr (integer) fallback = std::to_string(option.fallback);
                else fallback = format_number(option.fallback);
                out += "| `[" + std::string(key.table) + "] " + std::string(option.key) + "` | " +
                       (integer ? "integer, " : "number, ") + range_text(option) + " | " + fallback + " | " +
                       cell(help_text(option)) + " (as `" + std::string(option.flag) + "`) |\n";
            },
            key.option);
    return out + "\n";
}

}  // namespace

void add_options_doc_command(CLI::App& app) {
    auto* cmd = app.add_subcommand("options-doc", "Every command's options as Markdown (docs/options.md)");
    cmd->group("");  // hidden: for `make docs` and the ctest doc_options
    cmd->callback([&app] {
        std::string out =
            "# Every command's options\n\n"
            "Generated from the program by `rfd options-doc` (`make docs`); the ctest `doc_options` checks\n"
            "that this page matches it. Ranges include both ends. Every command also takes `--quiet`\n"
            "(`-q`: no progress on stderr) and `--help`. Options that several commands share, or a command\n"
            "and the project file, are declared once in the library that owns them (`core/options.hpp`);\n"
            "the project-file keys among them are in the last table.\n\n";
        for (const CLI::App* sub : app.get_subcommands([](const CLI::App* a) { return !a->get_group().empty(); }))
            write_command(out, *sub, "rfd " + sub->get_name());
        out += project_keys_table();
        std::fputs(out.c_str(), stdout);
    });
}

}  // namespace rfd::cli
