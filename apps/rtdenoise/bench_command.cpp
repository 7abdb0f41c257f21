// `rtdenoise bench`: ms per frame and per pass of each method on each device and size, inputs
// rendered by the project's renderer (G-buffers and 1-spp beauty, no reference) or read from a
// sequence folder. Reading frames from disk and host<->device copies are reported apart from
// the denoising itself. Output: a table, and JSON with --json.
#include <fmt/format.h>

#include <algorithm>
#include <charconv>
#include <chrono>
#include <fstream>
#include <map>
#include <thread>

#include "commands.h"
#include "core/frame_order.h"
#include "render/render_sequence.h"
#include "rtdenoise/io.h"
#include "rtdenoise/rtdenoise.hpp"

namespace fs = std::filesystem;

namespace rtd::cli {
namespace {

struct BenchOptions {
    std::vector<std::string> methods{"jbf", "atrous", "temporal", "svgf"};
    std::vector<std::string> devices{"cpu"};
    std::vector<std::string> sizes{"512x512", "1280x720", "1920x1080", "3840x2160"};
    int frames = 20;      // timed frames per case, after a warm-up over the distinct inputs
    int inputFrames = 4;  // distinct frames rendered (cycled)
    std::string scene = "moving-objects";
    fs::path input;  // a sequence folder instead of rendered frames
    fs::path json;
    fs::path cache;  // where rendered inputs are kept (default: a temporary folder)
    TilePasses tilePasses = TilePasses::Auto;
};

struct Timing {
    std::vector<double> frame, device, upload, download;
    std::vector<std::vector<double>> passes;
};

double median(std::vector<double> v) {
    if (v.empty()) return 0.0;
    std::sort(v.begin(), v.end());
    std::size_t m = v.size() / 2;
    return v.size() % 2 ? v[m] : 0.5 * (v[m - 1] + v[m]);
}

double minimum(const std::vector<double>& v) {
    return v.empty() ? 0.0 : *std::min_element(v.begin(), v.end());
}

std::string cpuModel() {
    std::ifstream in("/proc/cpuinfo");
    std::string line;
    while (std::getline(in, line))
        if (line.rfind("model name", 0) == 0) return line.substr(line.find(':') + 2);
    return "unknown CPU";
}

// The renderer's limit on a side (render::validate).
constexpr long long kMaxSide = 16384;

// "1920x1080" -> {1920, 1080}; digits parsed with range checks (sscanf's %d wraps).
std::pair<int, int> parseSize(const std::string& text) {
    const auto fail = [&text](const std::string& problem) {
        return Error(ErrorCode::InvalidArgument, fmt::format("--size {}: {}", text, problem));
    };
    const std::size_t x = text.find('x');
    if (x == std::string::npos) throw fail("expected WIDTHxHEIGHT, e.g. 1920x1080");
    const auto side = [&](std::string_view digits, const char* name) {
        long long value = 0;
        const auto [end, ec] = std::from_chars(digits.data(), digits.data() + digits.size(), value);
        if (digits.empty() || end != digits.data() + digits.size() ||
            (ec != std::errc() && ec != std::errc::result_out_of_range))
            throw fail("expected WIDTHxHEIGHT, e.g. 1920x1080");
        if (ec == std::errc::result_out_of_range || value < 1 || value > kMaxSide)
            throw fail(fmt::format("the {} {} is out of range 1..{}", name, digits, kMaxSide));
        return int(value);
    };
    const std::string_view all(text);
    return {side(all.substr(0, x), "width"), side(all.substr(x + 1), "height")};
}

const std::map<std::string, Method> kBenchMethods{
    {"jbf", Method::Jbf},   {"atrous", Method::Atrous}, {"temporal", Method::Temporal},
    {"svgf", Method::Svgf}, {"detail", Method::Detail}, {"learned", Method::Learned}};
struct BenchDevice {
    DeviceType type;
    CpuIsa isa;
};
// cpu-<set>: the CPU kernels built for one instruction set, to compare them in one run.
const std::map<std::string, BenchDevice> kBenchDevices{
    {"cpu", {DeviceType::Cpu, CpuIsa::Auto}},
    {"cpu-scalar", {DeviceType::Cpu, CpuIsa::Scalar}},
    {"cpu-sse2", {DeviceType::Cpu, CpuIsa::Sse2}},
    {"cpu-avx2", {DeviceType::Cpu, CpuIsa::Avx2}},
    {"cpu-avx512", {DeviceType::Cpu, CpuIsa::Avx512}},
    {"cuda", {DeviceType::Cuda, CpuIsa::Auto}},
    {"auto", {DeviceType::Auto, CpuIsa::Auto}}};

std::vector<std::string> benchDeviceNames() {
    std::vector<std::string> names;
    for (const auto& [name, device] : kBenchDevices) names.push_back(name);
    return names;
}

int runBench(const BenchOptions& o) {
    // Bad arguments fail now, not after minutes of rendering and timing.
    if (o.input.empty())
        for (const std::string& size : o.sizes) parseSize(size);
    if (!o.json.empty()) checkOutputFile(o.json);
    std::string gpu = gpuName();
    fmt::print("machine: {}, {} hardware threads (CPU kernels: {}); GPU: {}\n", cpuModel(),
               std::thread::hardware_concurrency(), toString(bestCpuInstructionSet()),
               gpu.empty() ? "none" : gpu);
    fs::path cache = o.cache.empty() ? fs::temp_directory_path() / "rtdenoise-bench" : o.cache;
    std::string json = "{\"cases\": [";
    bool firstCase = true;
    std::vector<std::string> sizes = o.input.empty() ? o.sizes : std::vector<std::string>{"input"};
    for (const std::string& sizeText : sizes) {
        // Inputs: read once (timed apart), then reused for every method and device.
        fs::path folder = o.input;
        if (folder.empty()) {
            auto [w, h] = parseSize(sizeText);
            folder = cache / fmt::format("{}-{}x{}-{}", o.scene, w, h, o.inputFrames);
            if (!fs::exists(folder / fmt::format("matrix_{}.mat", o.inputFrames - 1))) {
                render::RenderSettings r;
                r.width = w;
                r.height = h;
                r.frames = o.inputFrames;
                r.gbufferOnly = true;
                fmt::print("rendering {} frames of {} at {} into {}\n", o.inputFrames, o.scene,
                           sizeText, folder.string());
                render::renderSequence(o.scene, r, folder);
            }
        }
        const std::unique_ptr<FrameSource> sequence = openFrameSource(folder);
        std::vector<Frame> frames;
        auto readStart = std::chrono::steady_clock::now();
        int count = o.input.empty() ? o.inputFrames : std::min(sequence->frameCount(), 8);
        for (int i = 0; i < count; ++i) frames.push_back(sequence->readFrame(i));
        double readMs =
            std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - readStart)
                .count() /
            count;
        int width = frames[0].width(), height = frames[0].height();
        double megapixels = double(width) * height / 1e6;
        fmt::print("\n{}x{}: reading a frame from disk {:.1f} ms (not in the figures below)\n",
                   width, height, readMs);
        // median ms: the frame as the host sees it (launches and waits included, the copies in
        // and out not); device ms: the passes back to back on the device.
        fmt::print("{:<9} {:<10} {:>10} {:>10} {:>10} {:>9} {:>9} {:>10} {:>8} {:>9}\n", "method",
                   "dev", "median ms", "min ms", "device ms", "upload", "download", "Mpix/s",
                   "B/pixel", "x scalar");
        for (const std::string& methodName : o.methods) {
            double scalarMs = 0.0;  // cpu-scalar's median, once timed: the speed-up baseline
            for (const std::string& deviceName : o.devices) {
                DenoiserSettings settings;
                settings.method = kBenchMethods.at(methodName);
                settings.device = kBenchDevices.at(deviceName).type;
                DeviceTuning tuning{kBenchDevices.at(deviceName).isa, o.tilePasses};
                std::unique_ptr<Denoiser> created;
                try {
                    created = std::make_unique<Denoiser>(makeTunedDenoiser(settings, tuning));
                } catch (const Error& e) {
                    // A device or instruction set this machine lacks: say so, time the rest.
                    if (e.code() != ErrorCode::DeviceFailure) throw;
                    fmt::print("{:<9} {:<10} skipped: {}\n", methodName, deviceName, e.what());
                    continue;
                }
                Denoiser& denoiser = *created;
                Image output;
                for (const Frame& f : frames) denoiser.processFrame(f, output);  // warm-up
                Timing t;
                t.passes.resize(denoiser.passes().size());
                for (int i = 0; i < o.frames; ++i) {
                    auto start = std::chrono::steady_clock::now();
                    denoiser.processFrame(frames[pingPongFrame(std::size_t(i), frames.size())],
                                          output);
                    double total = std::chrono::duration<double, std::milli>(
                                       std::chrono::steady_clock::now() - start)
                                       .count();
                    const FrameStats& s = denoiser.lastFrameStats();
                    t.upload.push_back(s.uploadMilliseconds);
                    t.download.push_back(s.downloadMilliseconds);
                    t.device.push_back(s.deviceMilliseconds);
                    // The denoising itself: everything but the copies in and out.
                    t.frame.push_back(total - s.uploadMilliseconds - s.downloadMilliseconds);
                    for (std::size_t p = 0; p < t.passes.size(); ++p)
                        t.passes[p].push_back(s.passMilliseconds[p]);
                }
                double med = median(t.frame);
                if (deviceName == "cpu-scalar") scalarMs = med;
                std::string speedUp = scalarMs > 0.0 ? fmt::format("{:.1f}", scalarMs / med) : "";
                // Device memory held per pixel: history, G-buffer copies, intermediates.
                double bytesPerPixel = double(denoiser.deviceMemoryBytes()) / (megapixels * 1e6);
                fmt::print(
                    "{:<9} {:<10} {:>10.2f} {:>10.2f} {:>10.3f} {:>9.2f} {:>9.2f} {:>10.1f} "
                    "{:>8.0f} "
                    "{:>9}\n",
                    methodName, deviceName, med, minimum(t.frame), median(t.device),
                    median(t.upload), median(t.download), megapixels / (med / 1000.0),
                    bytesPerPixel, speedUp);
                std::string passes;
                for (std::size_t p = 0; p < t.passes.size(); ++p) {
                    fmt::print("    {:<16} {:8.3f} ms\n", denoiser.passes()[p].name,
                               median(t.passes[p]));
                    passes += fmt::format("{}\"{}\": {:.4f}", p ? ", " : "",
                                          denoiser.passes()[p].name, median(t.passes[p]));
                }
                json += fmt::format(
                    "{}\n  {{\"method\": \"{}\", \"device\": \"{}\", \"device_name\": \"{}\", "
                    "\"width\": {}, \"height\": {}, \"frames\": {}, \"median_ms\": {:.4f}, "
                    "\"min_ms\": {:.4f}, \"device_ms\": {:.4f}, \"upload_ms\": {:.4f}, "
                    "\"download_ms\": {:.4f}, "
                    "\"read_ms\": {:.4f}, \"mpix_per_s\": {:.2f}, \"device_bytes\": {}, "
                    "\"passes_ms\": {{{}}}}}",
                    firstCase ? "" : ",", methodName, deviceName, denoiser.deviceName(), width,
                    height, o.frames, med, minimum(t.frame), median(t.device), median(t.upload),
                    median(t.download), readMs, megapixels / (med / 1000.0),
                    denoiser.deviceMemoryBytes(), passes);
                firstCase = false;
            }
        }
    }
    json += fmt::format(
        "\n], \"tile_passes\": \"{}\", \"machine\": {{\"cpu\": \"{}\", \"threads\": {}, "
        "\"cpu_kernels\": \"{}\", "
        "\"gpu\": {}}}}}\n",
        toString(o.tilePasses), cpuModel(), std::thread::hardware_concurrency(),
        toString(bestCpuInstructionSet()), gpu.empty() ? std::string("null") : "\"" + gpu + "\"");
    if (!o.json.empty()) writeFileAtomically(o.json, json);
    return 0;
}

}  // namespace

Command addBenchCommand(CLI::App& app) {
    auto o = std::make_shared<BenchOptions>();
    CLI::App* c = app.add_subcommand(
        "bench", "Median and min ms per frame and per pass of each method, device and size");
    c->add_option("--method", o->methods, "Methods to time")
        ->check(CLI::IsMember({"jbf", "atrous", "temporal", "svgf", "detail", "learned"}))
        ->capture_default_str();
    c->add_option("--device", o->devices,
                  "Devices to time; cpu-scalar|sse2|avx2|avx512: the CPU kernels built for one "
                  "instruction set (with cpu-scalar first, speed-ups against it are printed)")
        ->check(CLI::IsMember(benchDeviceNames()))
        ->capture_default_str();
    c->add_option("--size", o->sizes, "Frame sizes WxH (inputs rendered once, then cached)")
        ->capture_default_str();
    c->add_option("--frames", o->frames, "Timed frames per case (after a warm-up)")
        ->check(CLI::Range(1, 100000))
        ->capture_default_str();
    c->add_option("--input-frames", o->inputFrames, "Distinct rendered frames, cycled")
        ->check(CLI::Range(2, 64))
        ->capture_default_str();
    c->add_option("--scene", o->scene, "Scene rendered for the inputs")->capture_default_str();
    c->add_option("--input", o->input,
                  "A sequence (a course folder, Blender multilayer EXRs or their pattern) to use "
                  "instead of rendered frames");
    c->add_option("--cache", o->cache, "Folder for rendered inputs (default: the temp folder)");
    c->add_option("--json", o->json, "Also write the results as JSON");
    addTilePassesOption(*c, o->tilePasses,
                        "Firefly removal as one tile pass (on) or separate passes (off) in every "
                        "case (auto: each device's choice)");
    return {c, [o] { return runBench(*o); }};
}

}  // namespace rtd::cli
