// Lens holders: the STL build time per design (every printed part, openscad, target <= 60 s
// per design on a 2-core machine), against the time to generate the .scad (tracing the
// field of view) and to check the built STLs, measured in the same run.

#include <filesystem>
#include <fstream>
#include <string>

#include <benchmark/benchmark.h>

#include "holders/checks.hpp"
#include "holders/generate.hpp"
#include "holders/openscad.hpp"
#include "optics/design.hpp"

namespace rfd::holders {
namespace {

namespace fs = std::filesystem;

optics::Design preset(int n) {
    return optics::load_design(std::string(RFD_SOURCE_DIR) + "/designs/design" + std::to_string(n) + ".toml");
}

fs::path scratch(int n) {
    const fs::path dir = fs::temp_directory_path() / ("rfd-bench-holder-" + std::to_string(n));
    fs::create_directories(dir);
    return dir;
}

void BM_HolderGenerate(benchmark::State& state) {
    const optics::Design design = preset(static_cast<int>(state.range(0)));
    for (auto _ : state) benchmark::DoNotOptimize(to_scad(make_holder(design, HolderProfile{}, PatternFilm{0.1, 2})));
}

std::vector<std::pair<PrintedPart, fs::path>> build_all(const Holder& holder, const fs::path& dir) {
    const fs::path scad = dir / "holder.scad";
    std::ofstream(scad) << to_scad(holder);
    std::vector<std::pair<PrintedPart, fs::path>> stls;
    for (const PrintedPart& part : holder.parts) {
        const fs::path stl = dir / (part.name + ".stl");
        build_stl(scad, part.name, stl, 600);
        stls.emplace_back(part, stl);
    }
    return stls;
}

void BM_HolderBuildStl(benchmark::State& state) {
    if (!find_openscad()) {
        state.SkipWithError("openscad is not installed");
        return;
    }
    const int n = static_cast<int>(state.range(0));
    const Holder holder = make_holder(preset(n), HolderProfile{}, PatternFilm{0.1, 2});
    const fs::path dir = scratch(n);
    for (auto _ : state) benchmark::DoNotOptimize(build_all(holder, dir));
    state.counters["parts"] = static_cast<double>(holder.parts.size());
}

void BM_HolderCheck(benchmark::State& state) {
    if (!find_openscad()) {
        state.SkipWithError("openscad is not installed");
        return;
    }
    const int n = static_cast<int>(state.range(0));
    const optics::Design design = preset(n);
    const Holder holder = make_holder(design, HolderProfile{}, PatternFilm{0.1, 2});
    const auto stls = build_all(holder, scratch(n));
    std::size_t rays = 0;
    for (auto _ : state) rays = check_holder(holder, design, stls).clearance.rays;
    state.counters["rays"] = static_cast<double>(rays);
}

BENCHMARK(BM_HolderGenerate)->DenseRange(1, 4)->Unit(benchmark::kMillisecond)->Iterations(1);
BENCHMARK(BM_HolderBuildStl)->DenseRange(1, 4)->Unit(benchmark::kSecond)->Iterations(1)->UseRealTime();
BENCHMARK(BM_HolderCheck)->DenseRange(1, 4)->Unit(benchmark::kSecond)->Iterations(1)->UseRealTime();

}  // namespace
}  // namespace rfd::holders
