// Printed sheets: streaming a full A4 TIFF sheet at a printer's resolution.
//  - BM_SheetTiff/DPI_X/DPI_Y: Design I's pattern (the thesis's 150 mm array, RGB) on an A4
//    page, tone-mapped for two sheets, markers, marks and label composed, written as 8-bit
//    zip TIFF; counters: page dots per second and pattern dots per second;
//  - BM_PlainTiff/DPI_X/DPI_Y: the baseline measured in the same run, patterns/raster's
//    write_pattern streaming a uniform raster of the same page size to TIFF (16-bit, no
//    tone mapping, no marks): the sheet's time over this one is the cost of composing.
// Both report the process's peak resident memory (getrusage; run one benchmark per process
// with --benchmark_filter for a clean figure). The pattern file is written once, before
// timing, to the temporary directory. Rates are per wall-clock second (UseRealTime).
//   ./build/bin/rfd_bench --benchmark_filter='SheetTiff/2880/1440'

#include <sys/resource.h>

#include <filesystem>

#include <benchmark/benchmark.h>

#include "core/progress.hpp"
#include "optics/design.hpp"
#include "patterns/raster.hpp"
#include "print/sheet.hpp"

namespace rfd::print {
namespace {

const std::filesystem::path kSource = RFD_SOURCE_DIR;

double peak_resident_mib() {
    rusage usage{};
    getrusage(RUSAGE_SELF, &usage);
    return static_cast<double>(usage.ru_maxrss) / 1024.0;  // kilobytes on Linux
}

// A smooth RGB pattern: compresses like a real one, costs nothing to render.
class Gradient final : public patterns::PatternSource {
public:
    explicit Gradient(patterns::PatternGeometry g) : g_(g) {}
    const patterns::PatternGeometry& geometry() const override { return g_; }
    int channels() const override { return 3; }
    void render_row(int py, std::span<float> out) const override {
        for (int x = 0; x < g_.width; ++x)
            for (int c = 0; c < 3; ++c)
                out[static_cast<std::size_t>(3 * x + c)] =
                    static_cast<float>((x + 2 * py + 97 * c) % 1024) / 1024.0f;
    }

private:
    patterns::PatternGeometry g_;
};

class Uniform final : public patterns::PatternSource {
public:
    explicit Uniform(patterns::PatternGeometry g) : g_(g) {}
    const patterns::PatternGeometry& geometry() const override { return g_; }
    int channels() const override { return 3; }
    void render_row(int, std::span<float> out) const override { std::fill(out.begin(), out.end(), 0.5f); }

private:
    patterns::PatternGeometry g_;
};

PrinterProfile a4_printer(double dpi_x, double dpi_y) {
    PrinterProfile printer = load_printer("epson_stylus_pro_4800");
    printer.dpi_x = Dpi(dpi_x);
    printer.dpi_y = Dpi(dpi_y);
    return printer;
}

void BM_SheetTiff(benchmark::State& state) {
    Progress::set_quiet(true);
    const optics::Design design = optics::load_design(kSource / "designs" / "design1.toml");
    const PrinterProfile printer = a4_printer(static_cast<double>(state.range(0)), static_cast<double>(state.range(1)));
    const auto dir = std::filesystem::temp_directory_path() / "rfd-bench-print";
    std::filesystem::create_directories(dir);
    const auto pattern = dir / "pattern.exr";
    const auto g = patterns::pattern_geometry(design, printer.dpi_x, printer.dpi_y);
    patterns::write_pattern(pattern, Gradient(g), {});
    SheetReport report;
    for (auto _ : state) report = write_sheet(dir / "sheet.tif", design, printer, pattern, {});
    const double page = static_cast<double>(report.layout.page_width) * report.layout.page_height;
    state.counters["page_dots/s"] = benchmark::Counter(page * static_cast<double>(state.iterations()),
                                                       benchmark::Counter::kIsRate);
    state.counters["pattern_dots/s"] = benchmark::Counter(
        static_cast<double>(g.dot_count()) * static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
    state.counters["page_Mdots"] = page / 1e6;
    state.counters["peak_MiB"] = peak_resident_mib();
    state.counters["file_MiB"] = static_cast<double>(std::filesystem::file_size(dir / "sheet.tif")) / (1 << 20);
    std::filesystem::remove_all(dir);
}

void BM_PlainTiff(benchmark::State& state) {
    Progress::set_quiet(true);
    const PrinterProfile printer = a4_printer(static_cast<double>(state.range(0)), static_cast<double>(state.range(1)));
    patterns::PatternGeometry g;
    g.dpi_x = printer.dpi_x.value;
    g.dpi_y = printer.dpi_y.value;
    g.dot_x = printer.dpi_x.dot_mm();
    g.dot_y = printer.dpi_y.dot_mm();
    g.width = static_cast<int>(printer.paper.width / g.dot_x);
    g.height = static_cast<int>(printer.paper.height / g.dot_y);
    const auto dir = std::filesystem::temp_directory_path() / "rfd-bench-print-plain";
    std::filesystem::create_directories(dir);
    for (auto _ : state) patterns::write_pattern(dir / "plain.tif", Uniform(g), {});
    state.counters["page_dots/s"] = benchmark::Counter(
        static_cast<double>(g.dot_count()) * static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
    state.counters["peak_MiB"] = peak_resident_mib();
    std::filesystem::remove_all(dir);
}

BENCHMARK(BM_SheetTiff)->Args({720, 720})->Args({2880, 1440})->Unit(benchmark::kSecond)->Iterations(1)->UseRealTime();
BENCHMARK(BM_PlainTiff)->Args({720, 720})->Args({2880, 1440})->Unit(benchmark::kSecond)->Iterations(1)->UseRealTime();

}  // namespace
}  // namespace rfd::print
