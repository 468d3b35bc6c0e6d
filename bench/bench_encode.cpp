// The Design I pattern encoder on a full A4 sheet at the thesis's 2880 x 1440 dpi (about 400
// million dots): rendering alone, and rendering streamed to an EXR file, with the process's
// peak memory. Baseline in the same run: writing the same number of replayed pattern dots.

#include <algorithm>
#include <filesystem>

#include <sys/resource.h>

#include <benchmark/benchmark.h>

#include "core/parallel.hpp"
#include "core/sphere.hpp"
#include "optics/design.hpp"
#include "patterns/encode.hpp"

namespace {

using namespace rfd;

// Design I with an array covering A4 portrait (210 x 297 mm): 88 lenslets by 145 rows.
optics::Design a4_design1() {
    return optics::with_lenslet_count(optics::load_design(std::string(RFD_SOURCE_DIR) + "/designs/design1.toml"), 88, 145);
}

// A bottle-sized field: 1024 directions of 128 x 64 RGB (only those near the display's
// range are sampled per lenslet).
relight::ReflectanceField bench_field() {
    relight::ReflectanceField field;
    field.directions = fibonacci_hemisphere(1024);
    for (const auto& d : field.directions) {
        Image image(128, 64, 3);
        for (int c = 0; c < 3; ++c)
            for (int y = 0; y < 64; ++y)
                for (int x = 0; x < 128; ++x)
                    image.at(x, y, c) = static_cast<float>(std::max(0.0, d.z() + 0.01 * ((x * 7 + y * 3 + c) % 11)));
        field.images.push_back(std::move(image));
    }
    return field;
}

double peak_memory_mb() {
    rusage usage{};
    getrusage(RUSAGE_SELF, &usage);
    return static_cast<double>(usage.ru_maxrss) / 1024.0;
}

struct A4Fixture {
    optics::Design design = a4_design1();
    relight::ReflectanceField field = bench_field();
    patterns::PatternGeometry geometry = patterns::pattern_geometry(design, Dpi{2880}, Dpi{1440});
};

A4Fixture& fixture() {
    static A4Fixture f;
    return f;
}

patterns::EncodeOptions options_for(int model) {
    patterns::EncodeOptions options;
    options.model = model == 0 ? optics::Model::Paraxial : optics::Model::Exact;
    options.mapping.tilt_deg = 45;
    return options;
}

// Rendering only: every row, in strips of 64 rows over both cores, as write_pattern does.
void BM_EncodeA4_Render(benchmark::State& state) {
    A4Fixture& f = fixture();
    const patterns::Encoder encoder(f.design, f.field, f.geometry, options_for(static_cast<int>(state.range(0))));
    const std::size_t row = static_cast<std::size_t>(f.geometry.width) * 3;
    std::vector<float> strip(row * 64);
    for (auto _ : state) {
        for (int y0 = 0; y0 < f.geometry.height; y0 += 64) {
            const int rows = std::min(64, f.geometry.height - y0);
            rfd::parallel_for_chunks(static_cast<std::size_t>(rows), 1, [&](std::size_t b, std::size_t e) {
                for (std::size_t r = b; r < e; ++r)
                    encoder.render_row(y0 + static_cast<int>(r), std::span<float>(strip.data() + r * row, row));
            });
            benchmark::DoNotOptimize(strip.data());
        }
    }
    state.counters["Mdots_per_s"] = benchmark::Counter(static_cast<double>(f.geometry.dot_count()) / 1e6,
                                                       benchmark::Counter::kIsIterationInvariantRate);
    state.counters["dots"] = static_cast<double>(f.geometry.dot_count());
    state.counters["peak_MB"] = peak_memory_mb();
}
BENCHMARK(BM_EncodeA4_Render)->Arg(0)->Arg(1)->ArgName("exact")->Unit(benchmark::kSecond)->UseRealTime()->Iterations(1);

// The writer's share: 64 rows of the real pattern rendered once and replayed for every
// strip, so conversion, compression (on data that compresses like the pattern) and disk
// cost what they do in BM_EncodeA4_ToExr while rendering costs a copy.
class Replay final : public patterns::PatternSource {
public:
    explicit Replay(const patterns::Encoder& encoder)
        : g_(encoder.geometry()), row_(static_cast<std::size_t>(g_.width) * 3), rows_(row_ * kRows) {
        for (int r = 0; r < kRows; ++r)
            encoder.render_row(g_.height / 2 + r, std::span<float>(rows_.data() + static_cast<std::size_t>(r) * row_, row_));
    }
    const patterns::PatternGeometry& geometry() const override { return g_; }
    int channels() const override { return 3; }
    void render_row(int py, std::span<float> out) const override {
        const float* row = rows_.data() + static_cast<std::size_t>(py % kRows) * row_;
        std::copy(row, row + row_, out.begin());
    }

private:
    static constexpr int kRows = 64;
    patterns::PatternGeometry g_;
    std::size_t row_;
    std::vector<float> rows_;
};

const char* kCompressions[] = {"none", "rle", "zips", "piz"};

void BM_WriteA4_Baseline(benchmark::State& state) {
    A4Fixture& f = fixture();
    const patterns::Encoder encoder(f.design, f.field, f.geometry, options_for(0));
    const Replay source(encoder);
    const std::string path = "/tmp/rfd-bench-replay.exr";
    patterns::WriteOptions options;
    options.exr_compression = kCompressions[state.range(0)];
    state.SetLabel(options.exr_compression);
    for (auto _ : state) patterns::write_pattern(path, source, {}, options);
    state.counters["file_MB"] = static_cast<double>(std::filesystem::file_size(path)) / 1e6;
    std::remove(path.c_str());
    state.counters["Mdots_per_s"] = benchmark::Counter(static_cast<double>(f.geometry.dot_count()) / 1e6,
                                                       benchmark::Counter::kIsIterationInvariantRate);
    state.counters["peak_MB"] = peak_memory_mb();
}
BENCHMARK(BM_WriteA4_Baseline)->DenseRange(0, 3)->Unit(benchmark::kSecond)->UseRealTime()->Iterations(1);

void BM_EncodeA4_ToExr(benchmark::State& state) {
    A4Fixture& f = fixture();
    const patterns::Encoder encoder(f.design, f.field, f.geometry, options_for(static_cast<int>(state.range(0))));
    const std::string path = "/tmp/rfd-bench-pattern.exr";
    for (auto _ : state) patterns::write_pattern(path, encoder, encoder.attributes());
    state.counters["file_MB"] = static_cast<double>(std::filesystem::file_size(path)) / 1e6;
    std::remove(path.c_str());
    state.counters["Mdots_per_s"] = benchmark::Counter(static_cast<double>(f.geometry.dot_count()) / 1e6,
                                                       benchmark::Counter::kIsIterationInvariantRate);
    state.counters["peak_MB"] = peak_memory_mb();
}
BENCHMARK(BM_EncodeA4_ToExr)->Arg(0)->Arg(1)->ArgName("exact")->Unit(benchmark::kSecond)->UseRealTime()->Iterations(1);

}  // namespace
