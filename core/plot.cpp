#include "core/plot.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <functional>
#include <sstream>

#include <sys/wait.h>

#include "core/command.hpp"
#include "core/error.hpp"
#include "core/files.hpp"
#include "core/units.hpp"

namespace rfd {
namespace {

std::string quoted(const std::string& text) {
    std::string out = "\"";
    for (char c : text) {
        if (c == '\n') {
            out += "\\n";  // gnuplot reads \n in a double-quoted string as a line break
            continue;
        }
        if (c == '"' || c == '\\') out += '\\';
        out += c;
    }
    return out + "\"";
}

// Whether a file gnuplot wrote ends as a whole SVG or PNG does: gnuplot does not report a
// failed write (a full disk), it leaves the file cut short.
bool ends_whole(const std::filesystem::path& file) {
    std::ifstream in(file, std::ios::binary | std::ios::ate);
    if (!in) return false;
    const std::streamoff size = in.tellg();
    const std::streamoff tail_size = std::min<std::streamoff>(size, 64);
    std::string tail(static_cast<std::size_t>(tail_size), '\0');
    in.seekg(size - tail_size);
    in.read(tail.data(), tail_size);
    if (file.extension() == ".png") return tail.size() >= 8 && tail.compare(tail.size() - 8, 8, "IEND\xAE\x42\x60\x82") == 0;
    return tail.find("</svg>") != std::string::npos;
}

// Runs gnuplot on `plot_commands` for an SVG and a PNG, each rendered to a temporary file
// and moved into place. Throws ToolError when gnuplot is missing or fails.
void render_with_gnuplot(const std::function<void(std::ostream&)>& plot_commands,
                         const std::filesystem::path& svg, const std::filesystem::path& png,
                         const std::string& size = "900,560") {
    namespace fs = std::filesystem;
    const auto gnuplot = find_gnuplot();
    if (!gnuplot)
        throw ToolError(SourceLocation{svg.string()},
                        "gnuplot is not installed (scripts/install-deps.sh installs it); "
                        "the CSV and the gnuplot script are written");
    // Render into temporary files, then move them into place.
    for (const auto& [target, terminal] :
         {std::pair{svg, "svg size " + size + " dynamic font 'sans,12'"},
          std::pair{png, "pngcairo size " + size + " font 'sans,10'"}}) {
        TemporaryFile temporary(temporary_sibling(target));
        std::ostringstream commands;
        commands << "set terminal " << terminal << "\nset output " << quoted(temporary.path().filename().string())
                 << "\n";
        plot_commands(commands);
        const TemporaryFile commands_file(temporary_sibling(fs::path(target).concat(".gp")));
        write_text_file(commands_file.path(), commands.str());
        const CommandResult run = run_command("cd " + shell_quoted(fs::absolute(target).parent_path().string()) +
                                              " && " + shell_quoted(gnuplot->string()) + " " +
                                              shell_quoted(commands_file.path().filename().string()));
        if (run.exit_code != 0 || !fs::exists(temporary.path()))
            throw ToolError(SourceLocation{target.string()}, "gnuplot failed: " + run.output);
        if (!ends_whole(temporary.path()))
            throw IoError(SourceLocation{target.string()}, "gnuplot wrote it cut short (disk full?)");
        move_into_place(temporary.path(), target);
        temporary.release();
    }
}

}  // namespace

std::optional<std::filesystem::path> find_gnuplot() {
#ifdef RFD_GNUPLOT_PATH
    const std::string configured = RFD_GNUPLOT_PATH;
#else
    const std::string configured;
#endif
    return find_program(configured, {"/usr/bin/gnuplot", "/usr/local/bin/gnuplot"});
}

void write_line_chart(const LineChart& chart, const std::filesystem::path& stem) {
    namespace fs = std::filesystem;
    const fs::path csv = fs::path(stem).replace_extension(".csv");
    const fs::path script = fs::path(stem).replace_extension(".gp");
    const fs::path svg = fs::path(stem).replace_extension(".svg");
    const fs::path png = fs::path(stem).replace_extension(".png");

    std::size_t rows = 0;
    for (const auto& s : chart.series) rows = std::max(rows, s.x.size());
    write_file_atomically(csv, [&](std::ostream& out) {
        out.precision(10);
        for (std::size_t k = 0; k < chart.series.size(); ++k)
            out << (k ? "," : "") << quoted(chart.series[k].title + " x") << ","
                << quoted(chart.series[k].title);
        out << "\n";
        for (std::size_t r = 0; r < rows; ++r) {
            for (std::size_t k = 0; k < chart.series.size(); ++k) {
                const auto& s = chart.series[k];
                out << (k ? "," : "");
                if (r < s.x.size()) {
                    out << s.x[r] << ",";
                    if (std::isfinite(s.y[r])) out << s.y[r];
                    else out << "NaN";
                } else {
                    out << ",";
                }
            }
            out << "\n";
        }
    });

    auto plot_commands = [&](std::ostream& out) {
        out << "set datafile separator ','\nset datafile missing 'NaN'\n";
        out << "set key " << chart.key_position << " box opaque\nset grid\n";
        out << "set title " << quoted(chart.title) << "\n";
        out << "set xlabel " << quoted(chart.x_label) << "\n";
        out << "set ylabel " << quoted(chart.y_label) << "\n";
        if (!chart.y2_label.empty())
            out << "set y2label " << quoted(chart.y2_label) << "\nset y2tics\nset ytics nomirror\n";
        if (chart.log_x) out << "set logscale x\nset format x '10^{%L}'\n";
        if (chart.log_y) out << "set logscale y\n";
        int arrow = 1;
        for (const auto& [x, label] : chart.vertical_markers) {
            out << "set arrow " << arrow << " from first " << x << ", graph 0 to first " << x
                << ", graph 1 nohead dashtype 2 linecolor rgb '#c0392b'\n";
            out << "set label " << arrow << " " << quoted(label) << " at first " << x
                << ", graph 0.95 left offset 0.5,0 textcolor rgb '#c0392b'\n";
            ++arrow;
        }
        out << "plot ";
        for (std::size_t k = 0; k < chart.series.size(); ++k) {
            out << (k ? ", \\\n     " : "") << quoted(csv.filename().string()) << " using "
                << 2 * k + 1 << ":" << 2 * k + 2 << " skip 1 with linespoints pointsize 0.5"
                << (chart.series[k].right_axis ? " axes x1y2" : "") << " title "
                << quoted(chart.series[k].title);
        }
        out << "\n";
    };
    write_file_atomically(script, [&](std::ostream& out) {
        out << "# Re-render with: gnuplot -e \"set terminal svg\" " << script.filename().string()
            << " > chart.svg\n";
        plot_commands(out);
    });

    render_with_gnuplot(plot_commands, svg, png);
}

void write_polar_map(const PolarMap& map, const std::filesystem::path& stem) {
    namespace fs = std::filesystem;
    RFD_CHECK(map.directions.size() == map.values.size());
    const fs::path csv = fs::path(stem).replace_extension(".csv");
    const fs::path script = fs::path(stem).replace_extension(".gp");
    const fs::path svg = fs::path(stem).replace_extension(".svg");
    const fs::path png = fs::path(stem).replace_extension(".png");
    write_file_atomically(csv, [&](std::ostream& out) {
        out.precision(10);
        out << "theta_deg,phi_deg,x,y," << quoted(map.colour_label) << "\n";
        for (std::size_t i = 0; i < map.directions.size(); ++i) {
            const Eigen::Vector3d& d = map.directions[i];
            const double theta = std::acos(std::clamp(d.z() / d.norm(), -1.0, 1.0)) * 180.0 / kPi;
            const double phi = std::atan2(d.y(), d.x());
            out << theta << "," << phi * 180.0 / kPi << "," << theta * std::cos(phi) << ","
                << theta * std::sin(phi) << ",";
            if (std::isfinite(map.values[i])) out << map.values[i];
            else out << "NaN";
            out << "\n";
        }
    });
    auto plot_commands = [&](std::ostream& out) {
        out << "set datafile separator ','\nset datafile missing 'NaN'\n";
        out << "set title " << quoted(map.title) << "\n";
        out << "set size ratio -1\nunset key\nunset border\nunset xtics\nunset ytics\n";
        out << "set xrange [-100:100]\nset yrange [-100:100]\n";
        out << "set cblabel " << quoted(map.colour_label) << "\n";
        out << "set palette defined (0 '#000004', 1 '#51127c', 2 '#b73779', 3 '#fc8961', 4 '#fcfdbf')\n";
        if (map.log_colour) out << "set logscale cb\n";
        // Rings every 30 degrees of theta and spokes every 45 degrees of phi.
        int object = 1;
        for (const int ring : {30, 60, 90})
            out << "set object " << object++ << " circle at 0,0 size " << ring
                << " fillstyle empty border linecolor rgb '#999999' dashtype 2 back\n";
        for (const int ring : {30, 60, 90})
            out << "set label " << object++ << " '" << ring << "°' at " << ring * 0.707 + 1 << ","
                << ring * 0.707 + 1 << " textcolor rgb '#666666'\n";
        for (int spoke = 0; spoke < 360; spoke += 45) {
            const double a = spoke * kPi / 180.0;
            out << "set arrow from 0,0 to " << 90 * std::cos(a) << "," << 90 * std::sin(a)
                << " nohead linecolor rgb '#cccccc' back\n";
            out << "set label " << object++ << " 'phi " << spoke << "°' at " << 97 * std::cos(a) << ","
                << 97 * std::sin(a) << " center textcolor rgb '#666666'\n";
        }
        out << "plot " << quoted(csv.filename().string())
            << " using 3:4:5 skip 1 with points pointtype 7 pointsize 1.2 linecolor palette\n";
    };
    write_file_atomically(script, [&](std::ostream& out) {
        out << "# Re-render with: gnuplot -e \"set terminal svg\" " << script.filename().string()
            << " > map.svg\n";
        plot_commands(out);
    });
    render_with_gnuplot(plot_commands, svg, png, "760,680");
}

}  // namespace rfd
