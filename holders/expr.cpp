#include "holders/expr.hpp"

#include <cmath>
#include <cstdio>
#include <numbers>

#include "core/error.hpp"

namespace rfd::holders {

std::string scad_number(double value) {
    RFD_CHECK(std::isfinite(value));
    char buffer[64];
    std::snprintf(buffer, sizeof buffer, "%.6f", value);
    std::string text = buffer;
    while (!text.empty() && text.back() == '0') text.pop_back();
    if (!text.empty() && text.back() == '.') text.pop_back();
    if (text == "-0") text = "0";
    return text;
}

namespace {

std::string wrapped(const Expr& e, Expr::Precedence at_least) {
    return e.precedence < at_least ? "(" + e.text + ")" : e.text;
}

}  // namespace

Expr operator+(const Expr& a, const Expr& b) {
    return {a.text + " + " + wrapped(b, Expr::Sum), a.value + b.value, Expr::Sum};
}
Expr operator-(const Expr& a, const Expr& b) {
    // a - (b + c) needs the brackets; a - b * c does not.
    return {a.text + " - " + wrapped(b, Expr::Product), a.value - b.value, Expr::Sum};
}
Expr operator*(const Expr& a, const Expr& b) {
    return {wrapped(a, Expr::Product) + " * " + wrapped(b, Expr::Product), a.value * b.value,
            Expr::Product};
}
Expr operator/(const Expr& a, const Expr& b) {
    RFD_CHECK(b.value != 0.0);
    return {wrapped(a, Expr::Product) + " / " + wrapped(b, Expr::Atom), a.value / b.value,
            Expr::Product};
}
Expr operator-(const Expr& a) { return {"-" + wrapped(a, Expr::Atom), -a.value, Expr::Atom}; }
Expr max(const Expr& a, const Expr& b) {
    return {"max(" + a.text + ", " + b.text + ")", std::max(a.value, b.value)};
}
Expr min(const Expr& a, const Expr& b) {
    return {"min(" + a.text + ", " + b.text + ")", std::min(a.value, b.value)};
}
Expr cos_deg(const Expr& degrees) {
    return {"cos(" + degrees.text + ")", std::cos(degrees.value * std::numbers::pi / 180.0)};
}

Expr ScadParameters::define(const std::string& name, const Expr& definition,
                            const std::string& comment) {
    for (const Entry& e : entries_) RFD_CHECK(e.name != name);
    entries_.push_back({name, definition, comment, group_});
    return {name, definition.value};
}

std::string ScadParameters::text() const {
    std::string out;
    std::string group = "\x01";
    for (const Entry& e : entries_) {
        if (e.group != group) {
            group = e.group;
            if (!group.empty()) out += (out.empty() ? "" : "\n") + std::string("// ") + group + "\n";
        }
        std::string line = e.name + " = " + e.definition.text + ";";
        if (!e.comment.empty()) {
            if (line.size() < 44) line.resize(44, ' ');
            else line += "  ";
            line += "// " + e.comment;
        }
        out += line + "\n";
    }
    return out;
}

}  // namespace rfd::holders
