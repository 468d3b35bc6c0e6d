#pragma once
// A number of a generated OpenSCAD model held twice: as the OpenSCAD expression that
// computes it from the model's named parameters, and as its value. Building the holder
// from Exprs keeps the .scad parametric (edit `clearance` at its top and every pocket
// follows) while the checks in C++ use exactly the numbers the .scad computes.
//
// Example: Expr d = ScadParameters::atom("A_diameter", 25) + 2 * clearance;
//          d.text == "A_diameter + 2 * clearance", d.value == 25.4

#include <string>
#include <vector>

namespace rfd::holders {

/// OpenSCAD literal for a number: fixed point, at most 6 decimals, no trailing zeros.
std::string scad_number(double value);

struct Expr {
    enum Precedence { Sum = 1, Product = 2, Atom = 3 };
    std::string text;
    double value = 0.0;
    Precedence precedence = Atom;

    Expr() = default;
    Expr(double number) : text(scad_number(number)), value(number) {}  // NOLINT: literals mix in freely
    Expr(std::string text_, double value_, Precedence p = Atom)
        : text(std::move(text_)), value(value_), precedence(p) {}
};

Expr operator+(const Expr& a, const Expr& b);
Expr operator-(const Expr& a, const Expr& b);
Expr operator*(const Expr& a, const Expr& b);
Expr operator/(const Expr& a, const Expr& b);
Expr operator-(const Expr& a);
/// OpenSCAD's max(a, b) and min(a, b).
Expr max(const Expr& a, const Expr& b);
Expr min(const Expr& a, const Expr& b);
/// OpenSCAD's cos() of an angle in degrees.
Expr cos_deg(const Expr& degrees);

/// The named parameters at the top of a .scad file, in order of definition. Each is
/// either a plain number or an expression over earlier parameters.
class ScadParameters {
public:
    struct Entry {
        std::string name;
        Expr definition;
        std::string comment;
        std::string group;   ///< heading the parameter is listed under
    };

    /// Declares `name = value;` (or `name = <expression>;`) and returns it as an atom.
    Expr define(const std::string& name, const Expr& definition, const std::string& comment = "");
    /// Starts a new group heading for the following definitions.
    void group(const std::string& heading) { group_ = heading; }
    const std::vector<Entry>& entries() const { return entries_; }
    /// The definitions as OpenSCAD text, grouped under comment headings.
    std::string text() const;

private:
    std::vector<Entry> entries_;
    std::string group_;
};

}  // namespace rfd::holders
