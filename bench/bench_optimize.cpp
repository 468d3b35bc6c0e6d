// rfd pattern optimize on the Design I preset (63 x 73 lenslets, 144 million dots at
// 2880 x 1440 dpi), nodes 0.1 mm apart (9.3 million unknowns), 8 rays per side, exact model,
// with the diamonds test field (the bottle needs a rendered field; the cost does not depend
// on the field):
//   - one solver iteration (one forward and one adjoint pass over every optimised direction)
//     against one forward simulation of the same lights (DisplaySimulator::simulate of the
//     direct pattern, every direction a light, its full grid of rays), in the same run;
//   - the whole optimisation as `rfd pattern optimize` runs it (operator, targets, direct
//     start, 40 iterations), with the process's peak memory as a counter.

#include <sys/resource.h>

#include <memory>

#include <benchmark/benchmark.h>

#include "optics/display.hpp"
#include "patterns/encode.hpp"
#include "patterns/procedural.hpp"
#include "predict/optimize.hpp"
#include "print/printer.hpp"

namespace {

using namespace rfd;

struct Setup {
    optics::Design design = optics::load_design(std::string(RFD_SOURCE_DIR) + "/designs/design1.toml");
    optics::DisplaySimulator simulator{design};
    relight::ReflectanceField field;
    std::unique_ptr<patterns::Encoder> encoder;
    print::ToneMap tone;
    std::unique_ptr<predict::NodeGrid> nodes;
    predict::SweepDirections sweep;
    optics::SimulationOptions options;

    Setup() {
        patterns::ProceduralOptions field_options;
        field_options.kind = patterns::ProceduralKind::Diamonds;
        field_options.spread_deg = 20.0;
        field = patterns::procedural_field(field_options);
        const patterns::PatternGeometry g = patterns::pattern_geometry(design, design.printer.dpi_x, design.printer.dpi_y);
        patterns::EncodeOptions encode;
        encode.model = optics::Model::Exact;
        encoder = std::make_unique<patterns::Encoder>(design, field, g, encode);
        tone.printer = print::load_printer("epson_stylus_pro_4800");
        tone.white = encoder->white();
        nodes = std::make_unique<predict::NodeGrid>(encoder->lattice(), g, 0.1);
        sweep = predict::sweep_directions(*encoder, *nodes, false);
        options.model = optics::Model::Exact;
        options.rays_per_side = 8;
    }
};

const Setup& setup() {
    static const Setup instance;
    return instance;
}

double peak_memory_gb() {
    rusage usage{};
    getrusage(RUSAGE_SELF, &usage);
    return static_cast<double>(usage.ru_maxrss) / (1024.0 * 1024.0);  // kB -> GB
}

void BM_OptimizeIteration(benchmark::State& state) {
    const Setup& s = setup();
    static const predict::DisplayOperator op(s.simulator, *s.nodes, s.sweep.display, s.options);
    std::vector<double> u(op.input_size(), 0.5), y(op.output_size()), g(op.input_size());
    for (auto _ : state) {
        op.forward(u, y);
        op.adjoint(y, g);
        benchmark::DoNotOptimize(g.data());
    }
    state.counters["directions"] = static_cast<double>(op.directions());
}
BENCHMARK(BM_OptimizeIteration)->Unit(benchmark::kSecond)->Iterations(2)->UseRealTime();

void BM_ForwardSimulationOfTheSameLights(benchmark::State& state) {
    const Setup& s = setup();
    const predict::NodeTransparency pattern(*s.nodes, predict::direct_nodes(*s.nodes, *s.encoder, s.tone),
                                            s.tone.stack_transmittance(0.0));
    std::vector<optics::DisplayLight> lights;
    for (const Eigen::Vector3d& d : s.sweep.display) lights.push_back({d});
    optics::SimulationOptions options = s.options;
    options.max_rays_per_lenslet = lights.size() * 64;  // every direction its full 8 x 8 grid
    for (auto _ : state) benchmark::DoNotOptimize(s.simulator.simulate(pattern, lights, options).image.samples().data());
    state.counters["directions"] = static_cast<double>(lights.size());
}
BENCHMARK(BM_ForwardSimulationOfTheSameLights)->Unit(benchmark::kSecond)->Iterations(1)->UseRealTime();

void BM_OptimizeDesignOnePreset(benchmark::State& state) {
    const Setup& s = setup();
    for (auto _ : state) {
        const predict::DisplayOperator op(s.simulator, *s.nodes, s.sweep.display, s.options);
        const predict::OptimizationProblem problem(op, predict::optimization_targets(op, op.flat_field(), *s.encoder, s.tone),
                                                   s.sweep.weights);
        predict::SolverOptions solver;
        solver.iterations = 40;
        solver.tolerance = 0.0;
        const predict::OptimizationResult r = predict::solve(problem, predict::direct_nodes(*s.nodes, *s.encoder, s.tone), solver);
        benchmark::DoNotOptimize(r.u.data());
    }
    state.counters["peak_memory_GB"] = peak_memory_gb();
}
BENCHMARK(BM_OptimizeDesignOnePreset)->Unit(benchmark::kSecond)->Iterations(1)->UseRealTime();

}  // namespace
