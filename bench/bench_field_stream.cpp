// A field at camera resolution relit a band of rows at a time: 60 JPEGs of 6000 x 4000
// (24 Mpx), made once and kept in the temporary folder (about 0.4 GB).
//  - the floor: decoding every image once, in bands, both cores, nothing else done;
//  - `rfd relight render FIELD --lights L --out DIR` run as a child process under 8 lights,
//    written as JPEGs (as PNGs, zlib takes about 9 s of one core per 24 Mpx image):
//    point lights (the images next to each are read), and wide discs (every image weighted),
//    its wall time as a ratio to the floor measured in the same run, and its peak memory
//    (the child's maximum resident set).
// Targets (issue 41): at most 1.5 times the floor, at most 2 GB.

#include <spawn.h>
#include <sys/resource.h>
#include <sys/wait.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <benchmark/benchmark.h>

#include "core/error.hpp"
#include "core/image_file.hpp"
#include "core/image_io.hpp"
#include "core/parallel.hpp"
#include "core/sphere.hpp"
#include "core/units.hpp"
#include "relight/field.hpp"

extern char** environ;

namespace rfd::relight {
namespace {

constexpr int kImages = 60, kWidth = 6000, kHeight = 4000;

// A scene's worth of detail for the JPEG coder: shading that moves with the light, a texture
// and a little noise, so the files have a photograph's size rather than a gradient's.
Image synthetic_photograph(int index) {
    Image image(kWidth, kHeight, 3);
    const double phase = 0.37 * index;
    parallel_for_chunks(static_cast<std::size_t>(kHeight), 16, [&](std::size_t begin, std::size_t end) {
        for (std::size_t row = begin; row < end; ++row)
            for (int x = 0; x < kWidth; ++x) {
                const int y = static_cast<int>(row);
                const std::uint32_t hash = (static_cast<std::uint32_t>(x) * 73856093u) ^
                                           (static_cast<std::uint32_t>(y) * 19349663u) ^
                                           (static_cast<std::uint32_t>(index) * 83492791u);
                const double noise = ((hash >> 8) % 1000) / 1000.0 - 0.5;
                const double shade = 0.45 + 0.3 * std::sin(x * 0.004 + phase) * std::cos(y * 0.005 - phase) +
                                     0.1 * std::sin(x * 0.11) * std::sin(y * 0.13) + 0.03 * noise;
                for (int c = 0; c < 3; ++c)
                    image.at(x, y, c) = static_cast<float>(std::clamp(shade * (0.8 + 0.1 * c), 0.0, 1.0));
            }
    });
    return image;
}

// The field, written on the first call and reused while its light file is there.
const std::filesystem::path& big_field() {
    static const std::filesystem::path folder = [] {
        const auto path = std::filesystem::temp_directory_path() / "rfd_bench_field_60x24mpx";
        if (std::filesystem::exists(path / "field.lp")) return path;
        std::fprintf(stderr, "writing the benchmark's field of %d JPEGs of %d x %d into %s (once)\n", kImages, kWidth,
                     kHeight, path.string().c_str());
        FieldWriter out(path, "field", ".jpg");
        const auto directions = fibonacci_hemisphere(kImages);
        for (int i = 0; i < kImages; ++i) out.add(synthetic_photograph(i), directions[static_cast<std::size_t>(i)]);
        out.finish();
        return path;
    }();
    return folder;
}

// A light file of 8 lights (RADIUS_DEG 0: points), for `rfd relight render --lights`.
std::filesystem::path light_file(double radius_deg) {
    const auto path = std::filesystem::temp_directory_path() /
                      ("rfd_bench_lights_" + std::to_string(static_cast<int>(radius_deg)) + ".lp");
    std::ofstream out(path);
    out << "8\n";
    for (int j = 0; j < 8; ++j) {
        const Eigen::Vector3d d = direction_from_angles(degrees_to_radians(15.0 + 7.0 * j), 0.8 * j);
        out << "light_" << j << ".jpg " << d.x() << " " << d.y() << " " << d.z();
        if (radius_deg > 0.0) out << " " << radius_deg;
        out << "\n";
    }
    return path;
}

double floor_seconds = 0.0;  // the decode floor of this run

void BM_FieldDecodeOnce(benchmark::State& state) {
    const auto entries = read_light_file(light_file_of(big_field()));
    for (auto _ : state) {
        const auto start = std::chrono::steady_clock::now();
        parallel_for_chunks(entries.size(), 1, [&](std::size_t begin, std::size_t end) {
            std::vector<std::uint8_t> rows;
            for (std::size_t i = begin; i < end; ++i) {
                ImageFileReader file(entries[i].path);
                const int height = file.spec().height, band = 256;
                rows.resize(static_cast<std::size_t>(band) * file.spec().width * file.spec().channels);
                for (int y = 0; y < height; y += band)
                    file.read_rows(y, std::min(height, y + band), SampleType::UInt8, rows.data());
                benchmark::DoNotOptimize(rows.data());
            }
        });
        floor_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        state.SetIterationTime(floor_seconds);
    }
    state.counters["Mpx/s"] = kImages * (kWidth * 1e-6 * kHeight) / floor_seconds;
}
BENCHMARK(BM_FieldDecodeOnce)->Iterations(1)->UseManualTime()->Unit(benchmark::kSecond);

// Runs rfd with `arguments`; its wall time and peak resident memory.
struct ChildRun {
    double seconds = 0.0;
    double peak_bytes = 0.0;
};

ChildRun run_rfd(std::vector<std::string> arguments) {
    arguments.insert(arguments.begin(), RFD_BINARY);
    std::vector<char*> argv;
    for (auto& a : arguments) argv.push_back(a.data());
    argv.push_back(nullptr);
    const auto start = std::chrono::steady_clock::now();
    pid_t pid = 0;
    if (posix_spawn(&pid, RFD_BINARY, nullptr, nullptr, argv.data(), environ) != 0)
        throw IoError("cannot start " + std::string(RFD_BINARY));
    int status = 0;
    rusage usage{};
    wait4(pid, &status, 0, &usage);
    if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) throw Error("rfd relight render failed");
    return {std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(),
            static_cast<double>(usage.ru_maxrss) * 1024.0};
}

void relight_benchmark(benchmark::State& state, double radius_deg) {
    const auto lights = light_file(radius_deg);
    const auto out = std::filesystem::temp_directory_path() / "rfd_bench_relit";
    ChildRun run;
    for (auto _ : state) {
        run = run_rfd({"--quiet", "relight", "render", big_field().string(), "--lights", lights.string(), "--out",
                       out.string()});
        state.SetIterationTime(run.seconds);
    }
    state.counters["peak_GB"] = run.peak_bytes / 1e9;
    if (floor_seconds > 0.0) state.counters["x_floor"] = run.seconds / floor_seconds;
}

void BM_RelightEightPointLights(benchmark::State& state) { relight_benchmark(state, 0.0); }
void BM_RelightEightWideLights(benchmark::State& state) { relight_benchmark(state, 50.0); }
BENCHMARK(BM_RelightEightPointLights)->Iterations(1)->UseManualTime()->Unit(benchmark::kSecond);
BENCHMARK(BM_RelightEightWideLights)->Iterations(1)->UseManualTime()->Unit(benchmark::kSecond);

}  // namespace
}  // namespace rfd::relight
