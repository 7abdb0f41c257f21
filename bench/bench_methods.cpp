// Google Benchmark: ms per frame of each method on the course scene (box, 512x512, beside the
// repository), with each pass's mean time as a counter; a case per kernel (BM_Pass/...); and the
// straightforward JBF as the baseline. Disk I/O is outside the timing. Where a CUDA GPU is
// present, BM_Cuda/<method> and BM_Pass/cuda/<method>/<pass> time the same on it (device time
// from the pass timestamps).
//   build/release/bench/bench_methods --benchmark_min_time=2
#include <benchmark/benchmark.h>

#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "baseline_jbf.h"
#include "core/frame_order.h"
#include "rtdenoise/io.h"
#include "rtdenoise/rtdenoise.hpp"
#include "tuning.h"

namespace {

using namespace rtd;

const std::vector<Frame>& frames() {
    static const std::vector<Frame> loaded = [] {
        std::vector<Frame> result;
        std::filesystem::path box = std::filesystem::path(RTD_SHARED_DIR) / "data" / "box";
        if (std::filesystem::exists(box / "beauty_0.exr")) {
            Sequence sequence(box);
            for (int i = 0; i < std::min(sequence.frameCount(), 6); ++i)
                result.push_back(sequence.readFrame(i));
        }
        return result;
    }();
    return loaded;
}

// A CPU denoiser already run once over the frames, so temporal methods have a full history (the
// steady state of all but a sequence's first frames); next() feeds it the following frame.
struct SteadyState {
    explicit SteadyState(Method method, SpatialFilter filter = SpatialFilter::Atrous,
                         DeviceType device = DeviceType::Cpu,
                         TilePasses tilePasses = TilePasses::Auto)
        : denoiser([&] {
              DenoiserSettings settings;
              settings.method = method;
              settings.device = device;
              settings.temporal.spatialFilter = filter;
              return makeTunedDenoiser(settings, {CpuIsa::Auto, tilePasses});
          }()) {
        for (const Frame& f : frames()) denoiser.processFrame(f, output);
    }
    void next() {
        denoiser.processFrame(frames()[pingPongFrame(index++, frames().size())], output);
    }

    Denoiser denoiser;
    Image output;
    std::size_t index = 0;
};

bool skipWithoutFrames(benchmark::State& state) {
    if (!frames().empty()) return false;
    state.SkipWithError("course data not found beside the repository");
    return true;
}

// The frame's device time is given as the manual time, which the cases registered with
// UseManualTime (the GPU's) report; the others report real time.
void runMethod(benchmark::State& state, Method method, SpatialFilter filter,
               DeviceType device = DeviceType::Cpu) {
    if (skipWithoutFrames(state)) return;
    SteadyState run(method, filter, device);
    std::vector<double> passTotals(run.denoiser.passes().size(), 0.0);
    for (auto _ : state) {
        run.next();
        benchmark::DoNotOptimize(run.output.pixels.data());
        const FrameStats& stats = run.denoiser.lastFrameStats();
        state.SetIterationTime(stats.deviceMilliseconds / 1000.0);
        for (std::size_t p = 0; p < passTotals.size(); ++p)
            passTotals[p] += stats.passMilliseconds[p];
    }
    for (std::size_t p = 0; p < passTotals.size(); ++p)
        state.counters[run.denoiser.passes()[p].name + "_ms"] =
            passTotals[p] / double(state.iterations());
    state.SetItemsProcessed(state.iterations());
    state.SetLabel(run.denoiser.deviceName());
}

void BM_Jbf(benchmark::State& s) {
    runMethod(s, Method::Jbf, SpatialFilter::Jbf);
}
void BM_Atrous(benchmark::State& s) {
    runMethod(s, Method::Atrous, SpatialFilter::Atrous);
}
void BM_TemporalAtrous(benchmark::State& s) {
    runMethod(s, Method::Temporal, SpatialFilter::Atrous);
}
void BM_TemporalJbf(benchmark::State& s) {
    runMethod(s, Method::Temporal, SpatialFilter::Jbf);
}
void BM_Svgf(benchmark::State& s) {
    runMethod(s, Method::Svgf, SpatialFilter::Atrous);
}

// state.range(0): threads (1: the course code as written, 2: both cores of this machine).
void BM_BaselineJbf(benchmark::State& state) {
    if (skipWithoutFrames(state)) return;
    DenoiserSettings settings;
    Image output;
    for (auto _ : state) {
        bench::baselineJbf(frames()[0], settings, output, int(state.range(0)));
        benchmark::DoNotOptimize(output.pixels.data());
    }
}

BENCHMARK(BM_BaselineJbf)
    ->Arg(1)
    ->Arg(2)
    ->ArgName("threads")
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->MinTime(3.0);
BENCHMARK(BM_Jbf)->Unit(benchmark::kMillisecond)->UseRealTime()->MinTime(3.0);
BENCHMARK(BM_Atrous)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_TemporalAtrous)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_Svgf)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_TemporalJbf)->Unit(benchmark::kMillisecond)->UseRealTime()->MinTime(3.0);

// One case per kernel: each pass of the svgf and temporal pipelines (every kernel the
// denoiser has is in one of them, or in jbf/atrous above), timed alone with the device's pass
// timestamps (manual time), the frames run in order as above.
void runPass(benchmark::State& state, Method method, std::size_t pass,
             DeviceType device = DeviceType::Cpu, TilePasses tilePasses = TilePasses::Auto) {
    if (skipWithoutFrames(state)) return;
    SteadyState run(method, SpatialFilter::Atrous, device, tilePasses);
    for (auto _ : state) {
        run.next();
        state.SetIterationTime(run.denoiser.lastFrameStats().passMilliseconds[pass] / 1000.0);
    }
    state.SetLabel(run.denoiser.passes()[pass].name);
}

// The passes a pipeline with these settings has (BM_Pass/<prefix>/<pass name>), and the firefly
// removal in its tile form (BM_Pass/<prefix>/outlier-tile; the device's default is off).
void registerPassesOf(Method method, DeviceType device, const std::string& prefix, int iterations) {
    DenoiserSettings settings;
    settings.method = method;
    settings.device = device;
    std::unique_ptr<Denoiser> probe;
    try {
        probe = std::make_unique<Denoiser>(settings);
    } catch (const Error&) {
        return;  // no such device here
    }
    auto add = [&](const std::string& name, std::size_t p, TilePasses tiles) {
        benchmark::RegisterBenchmark(("BM_Pass/" + prefix + "/" + name).c_str(),
                                     [method, p, device, tiles](benchmark::State& state) {
                                         runPass(state, method, p, device, tiles);
                                     })
            ->Unit(benchmark::kMillisecond)
            ->UseManualTime()
            // A fixed count: a pass is a small part of a frame, and Google Benchmark would
            // otherwise run frames until the pass alone adds up to its minimum time.
            ->Iterations(iterations);
    };
    for (std::size_t p = 0; p < probe->passes().size(); ++p)
        add(probe->passes()[p].name, p, TilePasses::Auto);
    for (std::size_t p = 0; p < probe->passes().size(); ++p)
        if (probe->passes()[p].name == "outlier") add("outlier-tile", p, TilePasses::On);
}

void registerPassBenchmarks() {
    for (Method method : {Method::Temporal, Method::Svgf})
        registerPassesOf(method, DeviceType::Cpu, toString(method), 20);
}

// The GPU's cases, registered only where a CUDA denoiser can be made.
void registerCudaBenchmarks() {
    DenoiserSettings settings;
    settings.method = Method::Svgf;
    settings.device = DeviceType::Cuda;
    std::unique_ptr<Denoiser> svgf;  // made only where there is a GPU
    try {
        svgf = std::make_unique<Denoiser>(settings);
    } catch (const Error&) {
        return;
    }
    for (Method method : {Method::Jbf, Method::Atrous, Method::Temporal, Method::Svgf}) {
        SpatialFilter filter = method == Method::Jbf ? SpatialFilter::Jbf : SpatialFilter::Atrous;
        std::string name = std::string("BM_Cuda/") + toString(method);
        // Manual time: the pipeline on the GPU (FrameStats::deviceMilliseconds).
        benchmark::RegisterBenchmark(name.c_str(),
                                     [method, filter](benchmark::State& state) {
                                         runMethod(state, method, filter, DeviceType::Cuda);
                                     })
            ->Unit(benchmark::kMillisecond)
            ->UseManualTime()
            ->Iterations(200);
    }
    registerPassesOf(Method::Svgf, DeviceType::Cuda, "cuda/svgf", 200);
}

}  // namespace

int main(int argc, char** argv) {
    registerPassBenchmarks();
    registerCudaBenchmarks();
    benchmark::Initialize(&argc, argv);
    if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
    benchmark::RunSpecifiedBenchmarks();
    benchmark::Shutdown();
    return 0;
}
