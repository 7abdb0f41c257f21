// Google Benchmark: ms per frame through the C API (librtdenoise_c) on the course scene (box,
// 512x512, beside the repository), the default method in its steady state, as an engine drives
// it: plainly; setting a parameter to the value it has before every frame (the history must be
// kept, and nothing rebuilt); with motion vectors and the scene's object count, and with 4
// million object IDs allowed (the cost must not grow with the count). Only the C API is used, so the file builds against any version.
//   build/release/bench/bench_c_api --benchmark_repetitions=5 --benchmark_report_aggregates_only
#include <benchmark/benchmark.h>

#include <filesystem>
#include <vector>

#include "rtdenoise/io.h"
#include "rtdenoise/rtdenoise.h"

namespace {

const std::vector<rtd::Frame>& frames() {
    static const std::vector<rtd::Frame> loaded = [] {
        std::vector<rtd::Frame> result;
        const std::filesystem::path box = std::filesystem::path(RTD_SHARED_DIR) / "data" / "box";
        if (std::filesystem::exists(box / "beauty_0.exr")) {
            rtd::Sequence sequence(box);
            for (int i = 0; i < std::min(sequence.frameCount(), 6); ++i)
                result.push_back(sequence.readFrame(i));
        }
        return result;
    }();
    return loaded;
}

std::vector<float> flat(const rtd::Matrix4& m) {
    std::vector<float> values;
    for (const auto& row : m.m) values.insert(values.end(), row.begin(), row.end());
    return values;
}

enum class Drive { Plain, SettingEveryFrame, Motion, MotionManyObjects };

void runCApi(benchmark::State& state, Drive drive) {
    if (frames().empty()) {
        state.SkipWithError("course data not found beside the repository");
        return;
    }
    RTDDevice device = rtdNewDevice(RTD_DEVICE_CPU);
    RTDDenoiser d = rtdNewDenoiser(device, "detail");
    const std::size_t w = std::size_t(frames()[0].width()), h = std::size_t(frames()[0].height());
    std::vector<float> output(3 * w * h), motion(2 * w * h, 0.0f);  // zero motion: a still shot
    std::size_t index = 0;
    auto next = [&] {
        const rtd::Frame& f = frames()[index++ % frames().size()];
        rtdSetImage(d, "color", f.beauty.pixels.data(), RTD_FORMAT_FLOAT3, w, h, 0, 0);
        rtdSetImage(d, "normal", f.normal.pixels.data(), RTD_FORMAT_FLOAT3, w, h, 0, 0);
        rtdSetImage(d, "position", f.position.pixels.data(), RTD_FORMAT_FLOAT3, w, h, 0, 0);
        rtdSetImage(d, "depth", f.depth.pixels.data(), RTD_FORMAT_FLOAT, w, h, 0, 0);
        rtdSetImage(d, "ids", f.objectId.data(), RTD_FORMAT_INT, w, h, 0, 0);
        rtdSetImage(d, "output", output.data(), RTD_FORMAT_FLOAT3, w, h, 0, 0);
        if (drive == Drive::Motion || drive == Drive::MotionManyObjects) {
            rtdSetImage(d, "motion", motion.data(), RTD_FORMAT_FLOAT2, w, h, 0, 0);
            rtdSetObjectCount(d, drive == Drive::Motion ? int(f.objectToWorld.size()) : 4000000);
        } else {
            std::vector<float> objects;
            for (const rtd::Matrix4& m : f.objectToWorld) {
                const std::vector<float> one = flat(m);
                objects.insert(objects.end(), one.begin(), one.end());
            }
            const std::vector<float> camera = flat(f.worldToCamera), screen = flat(f.worldToScreen);
            rtdSetMatrices(d, objects.data(), int(f.objectToWorld.size()), camera.data(),
                           screen.data());
        }
        if (drive == Drive::SettingEveryFrame) rtdSetFloat(d, "sigma-color", 0.6f);
        if (rtdExecute(d) != RTD_ERROR_NONE) state.SkipWithError("rtdExecute failed");
    };
    for (std::size_t i = 0; i < frames().size(); ++i) next();  // the steady state
    for (auto _ : state) {
        next();
        benchmark::DoNotOptimize(output.data());
    }
    state.SetLabel(rtdGetDeviceName(device));
    rtdReleaseDenoiser(d);
    rtdReleaseDevice(device);
}

void BM_CApiDetail(benchmark::State& s) {
    runCApi(s, Drive::Plain);
}
void BM_CApiDetailSettingEveryFrame(benchmark::State& s) {
    runCApi(s, Drive::SettingEveryFrame);
}
void BM_CApiDetailMotion(benchmark::State& s) {
    runCApi(s, Drive::Motion);
}
void BM_CApiDetailMotionManyObjects(benchmark::State& s) {
    runCApi(s, Drive::MotionManyObjects);
}

BENCHMARK(BM_CApiDetail)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_CApiDetailSettingEveryFrame)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_CApiDetailMotion)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_CApiDetailMotionManyObjects)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
