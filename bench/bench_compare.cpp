// rfd simulate compare's unit of work (predict/compare.hpp): one light direction on
// Design II with the diamonds test field, 32 x 32 rays per lenslet, paraxial and exact in
// the same run so the exact model's cost reads as a ratio. The pattern is encoded and tone
// mapped in memory, so the figure is the comparison's (two simulations, the clear print's
// and the pattern's, and the reference), not a pattern file's.

#include <memory>

#include <benchmark/benchmark.h>

#include "core/units.hpp"
#include "optics/display.hpp"
#include "predict/compare.hpp"
#include "print/printer.hpp"
#include "patterns/encode.hpp"
#include "patterns/procedural.hpp"

namespace {

using namespace rfd;

struct Setup {
    optics::Design design = optics::load_design(std::string(RFD_SOURCE_DIR) + "/designs/design2.toml");
    optics::DisplaySimulator simulator{design};
    std::unique_ptr<patterns::Encoder> encoder;
    std::unique_ptr<optics::RasterTransparency> transparency;
    std::unique_ptr<predict::DisplayComparison> comparison;

    Setup() {
        patterns::ProceduralOptions field_options;
        field_options.kind = patterns::ProceduralKind::Diamonds;
        field_options.spread_deg = 14.0;
        const relight::ReflectanceField field = patterns::procedural_field(field_options);
        const patterns::PatternGeometry g = patterns::pattern_geometry(design, design.printer.dpi_x, design.printer.dpi_y);
        patterns::EncodeOptions options;
        options.model = optics::resolve(optics::ModelChoice::Auto, optics::DesignOptics(design), {g.dot_x, g.dot_y}).model;
        encoder = std::make_unique<patterns::Encoder>(design, field, g, options);
        print::ToneMap tone;
        tone.printer = print::load_printer("epson_stylus_pro_4800");
        tone.white = encoder->white();
        tone.sheets = 1;
        const std::size_t channels = static_cast<std::size_t>(encoder->channels());
        std::vector<float> values(g.dot_count() * channels);
        for (int py = 0; py < g.height; ++py) {
            const std::span<float> row(values.data() + static_cast<std::size_t>(py) * static_cast<std::size_t>(g.width) * channels,
                                       static_cast<std::size_t>(g.width) * channels);
            encoder->render_row(py, row);
            for (float& v : row) v = static_cast<float>(tone.stack_transmittance(v));
        }
        transparency = std::make_unique<optics::RasterTransparency>(g.width, g.height, static_cast<int>(channels), g.dot_x,
                                                                    g.dot_y, std::move(values));
        comparison = std::make_unique<predict::DisplayComparison>(simulator, *transparency, *encoder, tone);
    }
};

void BM_CompareDirection(benchmark::State& state) {
    static const Setup setup;
    optics::SimulationOptions options;
    options.rays_per_side = 32;
    options.pixels_per_pitch = 16.0;
    options.model = state.range(0) == 0 ? optics::Model::Paraxial : optics::Model::Exact;
    // 8 degrees off the display's axis, inside its crosstalk-free cone.
    const Eigen::Vector3d light =
        setup.encoder->options().mapping.field_direction(optics::incident_direction(degrees_to_radians(8.0), 0.5));
    for (auto _ : state) {
        const predict::DirectionComparison r = setup.comparison->compare(light, options);
        benchmark::DoNotOptimize(r.comparison.mse);
    }
    state.SetLabel(std::string(optics::to_string(options.model)) + ", PSNR " +
                   std::to_string(setup.comparison->compare(light, options).comparison.psnr_db) + " dB");
}
BENCHMARK(BM_CompareDirection)->Arg(0)->Arg(1)->ArgName("exact")->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
