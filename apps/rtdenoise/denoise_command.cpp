// `rtdenoise denoise INPUT -o OUT_DIR`: reads the sequence (a course folder or Blender's
// multilayer EXRs; the next frame is read while the current one is filtered), denoises it,
// writes result_<i>.exr (+ PNG, debug images, MP4).
#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <future>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <variant>
#include <vector>

#include "commands.h"
#include "progress.h"
#include "rtdenoise/io.h"
#include "rtdenoise/rtdenoise.hpp"

namespace fs = std::filesystem;

namespace rtd::cli {
namespace {

struct DenoiseOptions {
    fs::path input;
    std::string viewLayer;
    fs::path output;
    bool png = false;
    bool debug = false;
    fs::path video;
    fs::path config;
    int fps = 24;
    float exposure = 1.0f;
    // --frames: N (the first N frames; 0: all) or A:B, A:, A..B (a chunk of the input's frame
    // numbers, run after `warmup` frames that only build its history; parseFrameSelection).
    std::string frames;
    int warmup = kDefaultChunkWarmup;  // [>=0] frames denoised before A and not written
    bool warmupGiven = false;
    bool dryRun = false;  // check everything, print what would be denoised, create nothing
    bool quiet = false;
    ExrWriteOptions exr;  // result_<i>.exr's compression and channel type
};

const std::map<std::string, Method> kMethods{
    {"jbf", Method::Jbf},   {"atrous", Method::Atrous}, {"temporal", Method::Temporal},
    {"svgf", Method::Svgf}, {"detail", Method::Detail}, {"learned", Method::Learned}};
// The learned method's training inputs (DebugView::LearnedInputs), as docs/learned_spec.md names
// them.
constexpr const char* kLearnedInputsFolder = "learned-inputs";
const std::vector<std::string> kLearnedInputNames = [] {
    std::vector<std::string> names;
    for (int k = 0; k < 6; ++k)
        for (const char* c : {"R", "G", "B", "V"}) names.push_back(fmt::format("L{}.{}", k, c));
    for (const char* name : {"history", "albedo.R", "albedo.G", "albedo.B", "foreground"})
        names.push_back(name);
    return names;
}();
const std::map<std::string, SpatialFilter> kFilters{{"jbf", SpatialFilter::Jbf},
                                                    {"atrous", SpatialFilter::Atrous}};
const std::map<std::string, DeviceType> kDevices{
    {"cpu", DeviceType::Cpu}, {"cuda", DeviceType::Cuda}, {"auto", DeviceType::Auto}};
const std::map<std::string, ExrCompression> kCompressions = [] {
    std::map<std::string, ExrCompression> names;
    for (ExrCompression compression : exrCompressions()) names[toString(compression)] = compression;
    return names;
}();
const std::map<std::string, TilePasses> kTilePasses{
    {"auto", TilePasses::Auto}, {"on", TilePasses::On}, {"off", TilePasses::Off}};

// An option taking one of `choices` by name (any case). A wrong name fails with the names
// allowed ("--method: magic not in {atrous, jbf, svgf, temporal}"), not the enum values.
template <class Enum>
void addChoice(CLI::App& c, const std::string& name, Enum& target,
               const std::map<std::string, Enum>& choices, const std::string& help,
               const std::string& names) {
    std::vector<std::string> keys;
    for (const auto& entry : choices) keys.push_back(entry.first);
    c.add_option_function<std::string>(
         name,
         [&target, &choices](std::string value) {
             for (char& ch : value) ch = char(std::tolower(static_cast<unsigned char>(ch)));
             target = choices.at(value);
         },
         help)
        ->check(CLI::IsMember(keys, CLI::ignore_case))
        ->option_text(fmt::format("{} (default {})", names, toString(target)));
}

// What --frames selects: the first `count` frames (0: all), or a chunk of the input's frame
// numbers first..end-1 (end absent: to the last frame).
struct FrameSelection {
    int count = 0;
    bool chunk = false;
    int first = 0;
    std::optional<int> end;
};

// A whole number in 0..1000000000, or an explanation of why `text` is not one.
std::variant<int, std::string> frameNumberOf(std::string_view text, std::string_view what) {
    long long value = 0;
    const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
    if (text.empty() || ec != std::errc() || end != text.data() + text.size())
        return fmt::format("'{}' is not a whole number ({})", text, what);
    if (value < 0) return fmt::format("{} is negative ({})", text, what);
    if (value > 1000000000) return fmt::format("{} is out of range: at most 1000000000", text);
    return int(value);
}

// --frames N, A:B (A..B-1; A: to the end) or A..B (A..B inclusive: Blender's and the farm
// managers' notation), or an explanation of the mistake.
std::variant<FrameSelection, std::string> parseFrameSelection(const std::string& text) {
    FrameSelection selection;
    const std::size_t dots = text.find("..");
    const std::size_t colon = text.find(':');
    if (colon == std::string::npos && dots == std::string::npos) {
        auto count = frameNumberOf(text, "a frame count, 0 for all frames, A:B or A..B");
        if (auto* error = std::get_if<std::string>(&count)) return *error;
        selection.count = std::get<int>(count);
        return selection;
    }
    const bool inclusive = colon == std::string::npos;
    const std::size_t split = inclusive ? dots : colon;
    const std::size_t endStart = split + (inclusive ? 2 : 1);
    selection.chunk = true;
    auto first = frameNumberOf(std::string_view(text).substr(0, split), "the chunk's first frame");
    if (auto* error = std::get_if<std::string>(&first)) return *error;
    selection.first = std::get<int>(first);
    if (endStart < text.size() || inclusive) {
        auto end = frameNumberOf(
            std::string_view(text).substr(endStart),
            inclusive ? "B of A..B: the last frame" : "B of A:B: the frame after the last");
        if (auto* error = std::get_if<std::string>(&end)) return *error;
        selection.end = std::get<int>(end) + (inclusive ? 1 : 0);
        if (*selection.end <= selection.first)
            return fmt::format("{}: the chunk is empty (A:B is frames A..B-1, A..B frames A to B)",
                               text);
    }
    return selection;
}

// --frames: N, A:B, A: or A..B (checked when the option is read, before anything else).
CLI::Validator frameSelectionValidator() {
    return CLI::Validator(
        [](std::string& text) -> std::string {
            auto parsed = parseFrameSelection(text);
            if (auto* error = std::get_if<std::string>(&parsed)) return *error;
            return {};
        },
        "N|A:B|A..B");
}

double median(std::vector<double> v) {
    if (v.empty()) return 0.0;
    std::sort(v.begin(), v.end());
    std::size_t m = v.size() / 2;
    return v.size() % 2 ? v[m] : 0.5 * (v[m - 1] + v[m]);
}

// "dir/out/" and "dir/./out" -> "/abs/dir/out": to tell whether two paths name one folder.
fs::path normalFolder(const fs::path& folder) {
    fs::path p = fs::absolute(folder).lexically_normal();
    return p.filename().empty() ? p.parent_path() : p;
}

// --video's file: a video in the output folder is checked with that folder, which may not exist
// yet; anywhere else its folder must exist.
void checkVideoPath(const DenoiseOptions& options) {
    std::error_code ec;
    if (fs::is_directory(options.video, ec))
        throw Error(ErrorCode::IoFailure, fmt::format("--video {}: cannot write, it is a folder",
                                                      options.video.string()));
    if (normalFolder(options.video.parent_path().empty() ? "." : options.video.parent_path()) !=
        normalFolder(options.output))
        checkOutputFile(options.video);
    if (!VideoWriter::ffmpegAvailable())
        throw Error(
            ErrorCode::MissingTool,
            "ffmpeg not found on PATH: install it (apt-get install ffmpeg) or drop --video");
}

// A folder holds one run: this program's outputs that this run does not rewrite are removed, so
// a shorter or different run leaves nothing of an earlier one for `compare` to score with it.
// A chunk's run (--frames A:B) owns only its frames' numbers: the kinds of file it does not
// write are removed there, and the other chunks' files are left alone.
void removeEarlierOutputs(const DenoiseOptions& options, const DenoiserSettings& settings,
                          int frames, std::optional<std::pair<int, int>> chunkNumbers) {
    const bool history = usesHistory(settings.method);
    const bool svgfViews = settings.method == Method::Svgf || settings.method == Method::Detail;
    const bool learnedInputs = settings.method == Method::Learned;
    const auto remove = [&](std::string_view stem, std::string_view extension, bool written) {
        if (chunkNumbers) {
            if (!written)
                removeNumberedFiles(options.output, stem, extension, chunkNumbers->first,
                                    chunkNumbers->second);
        } else {
            removeNumberedFiles(options.output, stem, extension, written ? frames : 0);
        }
    };
    remove("result", ".exr", true);
    remove("result", ".png", options.png);
    remove("reprojection", ".png", options.debug && history);
    remove("variance", ".png", options.debug && svgfViews);
    remove("history", ".png", options.debug && svgfViews);
    if (chunkNumbers) {
        if (!(options.debug && learnedInputs))
            removeNumberedFiles(options.output / kLearnedInputsFolder, "learned-inputs", ".exr",
                                chunkNumbers->first, chunkNumbers->second);
    } else {
        removeNumberedFiles(options.output / kLearnedInputsFolder, "learned-inputs", ".exr",
                            options.debug && learnedInputs ? frames : 0);
    }
}

// What the ingest repaired, per frame: (frame, count) where the count is not 0.
using FrameCounts = std::vector<std::pair<int, long long>>;

// "frame 3: 12 <what>" (what: "NaN/Inf radiance values replaced by 0"), or the total and the
// frames.
std::string inputWarning(const FrameCounts& perFrame, const std::string& what) {
    if (perFrame.size() == 1)
        return fmt::format("frame {}: {} {}", perFrame[0].first, perFrame[0].second, what);
    long long total = 0;
    std::string frames;
    constexpr std::size_t kListed = 10;
    for (std::size_t i = 0; i < perFrame.size(); ++i) {
        total += perFrame[i].second;
        if (i < kListed)
            frames +=
                fmt::format("{}frame {}: {}", i ? ", " : "", perFrame[i].first, perFrame[i].second);
    }
    if (perFrame.size() > kListed) frames += ", ...";
    return fmt::format("{} {} in {} frames ({})", total, what, perFrame.size(), frames);
}

// The passes a frame's warning (rtd::inputWarning) points at: where most of it lost its geometry,
// which of the frame's passes did it.
std::string brokenPasses(const Frame& frame, const FrameStats& stats) {
    if (stats.nonFiniteGeometry * 2 > stats.pixels) {
        long long depth = 0, position = 0;
        for (std::size_t i = 0; i < frame.objectId.size(); ++i) {
            if (frame.objectId[i] < 0) continue;
            depth += std::isfinite(frame.depth.pixels[i]) ? 0 : 1;
            const float* p = &frame.position.pixels[3 * i];
            position += std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2]) ? 0 : 1;
        }
        return depth && position ? "the depth and position passes"
               : depth           ? "the depth pass"
                                 : "the position pass";
    }
    if (stats.missingNormals * 2 > stats.pixels) return "the normal pass";
    return "the object ID pass";
}

// Frames left mostly undenoised by a broken pass: each named at the frame, up to this many,
// then counted (a whole shot of them must not bury the run's output).
constexpr int kFrameWarningsShown = 10;

std::string sizeText(const ExrSize& size) {
    return fmt::format("{}x{}", size.width, size.height);
}

// "4 frames of 64x48", or with frames of several sizes "4 frames (3 of 64x48, 1 of 32x24)", the
// sizes in the order they first appear.
std::string framesAndSizes(const std::vector<ExrSize>& sizes) {
    std::vector<std::pair<std::string, int>> counts;
    for (const ExrSize& size : sizes) {
        const std::string text = sizeText(size);
        const auto entry = std::find_if(counts.begin(), counts.end(),
                                        [&](const auto& count) { return count.first == text; });
        if (entry == counts.end())
            counts.emplace_back(text, 1);
        else
            ++entry->second;
    }
    if (counts.size() == 1) return fmt::format("{} frames of {}", sizes.size(), counts[0].first);
    std::string listed;
    for (const auto& [text, count] : counts)
        listed += fmt::format("{}{} of {}", listed.empty() ? "" : ", ", count, text);
    return fmt::format("{} frames ({})", sizes.size(), listed);
}

int runDenoise(const DenoiseOptions& options, const DenoiserSettings& settings) {
    // Everything that can be checked is checked before anything is created (not even the output
    // folder): options, output paths, every frame's files up to their EXR headers. Only a bad
    // object ID (a pixel value) shows when its frame is read.
    if (!std::isfinite(options.exposure) || options.exposure <= 0.0f)
        throw Error(
            ErrorCode::InvalidArgument,
            fmt::format("--exposure must be a finite number > 0, got {}", options.exposure));
    if (!options.video.empty()) checkVideoPath(options);
    const std::unique_ptr<FrameSource> source =
        openFrameSource(options.input, FrameSourceOptions{options.viewLayer});
    const bool history = usesHistory(settings.method);
    if (history && !source->backProjectionProblem().empty())
        throw Error(ErrorCode::InvalidInput,
                    fmt::format("{} (--method {} reprojects the previous frame)",
                                source->backProjectionProblem(), toString(settings.method)));
    // The frames read: [chunk.warmupIndex, chunk.endIndex), of which those from
    // chunk.firstIndex are written, as result_<n> with n the input's number for a chunk.
    const FrameSelection selection = std::get<FrameSelection>(
        parseFrameSelection(options.frames.empty() ? "0" : options.frames));
    if (options.warmupGiven && !selection.chunk)
        throw Error(ErrorCode::InvalidArgument,
                    "--warmup is for a chunk of the shot: give --frames A:B with it");
    FrameChunk chunk{0, 0, source->frameCount()};
    if (selection.chunk) {
        try {
            chunk =
                chunkOf(*source, selection.first,
                        selection.end.value_or(source->firstFrameNumber() + source->frameCount()),
                        options.warmup);
        } catch (const Error& e) {
            throw Error(e.code(), fmt::format("--frames {}: {}", options.frames, e.what()));
        }
    } else if (selection.count > 0) {
        chunk.endIndex = std::min(chunk.endIndex, selection.count);
    }
    const int frames = chunk.endIndex - chunk.firstIndex;  // written
    const int framesRead = chunk.endIndex - chunk.warmupIndex;
    const auto numberOf = [&](int index) {
        return selection.chunk ? source->firstFrameNumber() + index : index;
    };
    // sizes[k]: frame chunk.warmupIndex + k.
    const std::vector<ExrSize> sizes = source->checkFrames(framesRead, chunk.warmupIndex);
    const int firstWritten = chunk.firstIndex - chunk.warmupIndex;
    for (int k = firstWritten + 1; k < framesRead && !options.video.empty(); ++k) {
        const ExrSize& size = sizes[std::size_t(k)];
        const ExrSize& firstSize = sizes[std::size_t(firstWritten)];
        if (size.width != firstSize.width || size.height != firstSize.height)
            throw Error(ErrorCode::InvalidInput,
                        fmt::format("{}: {}x{}, but {} is {}x{}: a --video needs frames of one "
                                    "size",
                                    source->frameFile(chunk.warmupIndex + k).string(), size.width,
                                    size.height, source->frameFile(chunk.firstIndex).string(),
                                    firstSize.width, firstSize.height));
    }
    checkOutputFolder(options.output);
    Denoiser denoiser(settings);  // a device that is not there fails here, before any output
    if (options.dryRun) {
        // What a farm submission checks before it queues a task per chunk.
        fmt::print(
            "would denoise frames {}..{} ({} frames{}) of {} into {}, method {}, device {}\n",
            numberOf(chunk.firstIndex), numberOf(chunk.endIndex) - 1, frames,
            chunk.firstIndex > chunk.warmupIndex
                ? fmt::format(", after {} warm-up frames", chunk.firstIndex - chunk.warmupIndex)
                : "",
            source->describe(), options.output.string(), toString(settings.method),
            denoiser.deviceName());
        return 0;
    }

    prepareOutputFolder(options.output);
    removeEarlierOutputs(options, settings, frames,
                         selection.chunk ? std::optional(std::pair(numberOf(chunk.firstIndex),
                                                                   numberOf(chunk.endIndex)))
                                         : std::nullopt);
    for (const std::string& warning : source->warnings())  // once per run, not per frame
        fmt::print(stderr, "rtdenoise: warning: {}\n", warning);
    // A frame of another size starts afresh (the denoiser's buffers are remade, by design): said
    // at that frame, so that a stray render of another size is not taken for a filter's fault.
    for (int k = 1; k < framesRead; ++k)
        if (sizes[k].width != sizes[k - 1].width || sizes[k].height != sizes[k - 1].height)
            fmt::print(
                stderr, "rtdenoise: warning: {}: {}, but the frame before it is {}: {}\n",
                source->frameFile(chunk.warmupIndex + k).string(), sizeText(sizes[k]),
                sizeText(sizes[k - 1]),
                history ? "the history restarts at this frame" : "its result is of another size");
    if (!options.quiet) {
        if (selection.chunk)
            fmt::print(stderr,
                       "rtdenoise: frames {}..{} ({} frames, after {} warm-up frames not "
                       "written) from {}, method {}, device {}\n",
                       numberOf(chunk.firstIndex), numberOf(chunk.endIndex) - 1, frames,
                       chunk.firstIndex - chunk.warmupIndex, source->describe(),
                       toString(settings.method), denoiser.deviceName());
        else
            fmt::print(stderr, "rtdenoise: {} frames from {}, method {}, device {}\n", frames,
                       source->describe(), toString(settings.method), denoiser.deviceName());
    }
    std::optional<VideoWriter> video;
    Progress progress(framesRead, options.quiet);

    using Clock = std::chrono::steady_clock;
    std::vector<std::vector<double>> passTimes(denoiser.passes().size());
    std::vector<double> frameTimes, readWaitTimes, writeTimes;
    FrameCounts nonFinite, clamped, missingNormals;
    int framesWithoutGeometry = 0;
    auto start = Clock::now();

    // Frame i+1 is read on another thread while frame i is denoised.
    auto readAsync = [&](int i) {
        return std::async(std::launch::async, [&source, i] { return source->readFrame(i); });
    };
    std::future<Frame> next = readAsync(chunk.warmupIndex);
    // Frame i's files are written on another thread while frame i+1 is denoised; two result
    // images alternate so the one being written is never the one being filled.
    Image results[2];
    std::future<double> writing;  // milliseconds the last write took
    auto writeAsync = [&](int i, const Image& result,
                          std::vector<std::pair<std::string, Image>> debug) {
        return std::async(std::launch::async, [&, i, debug = std::move(debug)] {
            auto writeStart = Clock::now();
            writeExr(options.output / fmt::format("result_{}.exr", i), result, options.exr);
            if (options.png || !options.video.empty()) {
                Image display = toneMap(result, options.exposure);
                if (options.png)
                    writePng(options.output / fmt::format("result_{}.png", i), display);
                if (!options.video.empty()) {
                    if (!video)
                        video.emplace(options.video, display.width, display.height, options.fps);
                    video->addFrame(display);
                }
            }
            for (const auto& [prefix, image] : debug) {
                if (std::size_t(image.channels) == kLearnedInputNames.size()) {
                    // A folder of their own: `compare` then finds the results alone.
                    const fs::path folder = options.output / kLearnedInputsFolder;
                    fs::create_directories(folder);
                    writeExrChannels(folder / fmt::format("{}_{}.exr", prefix, i),
                                     {{&image, kLearnedInputNames, false}});
                } else
                    writePng(options.output / fmt::format("{}_{}.png", prefix, i), image);
            }
            return std::chrono::duration<double, std::milli>(Clock::now() - writeStart).count();
        });
    };
    for (int i = chunk.warmupIndex; i < chunk.endIndex; ++i) {
        auto waitStart = Clock::now();
        Frame frame = next.get();
        readWaitTimes.push_back(
            std::chrono::duration<double, std::milli>(Clock::now() - waitStart).count());
        if (i + 1 < chunk.endIndex) next = readAsync(i + 1);

        Image& result = results[i % 2];
        auto frameStart = Clock::now();
        denoiser.processFrame(frame, result);
        frameTimes.push_back(
            std::chrono::duration<double, std::milli>(Clock::now() - frameStart).count());
        const FrameStats& stats = denoiser.lastFrameStats();
        for (std::size_t p = 0; p < passTimes.size(); ++p)
            passTimes[p].push_back(stats.passMilliseconds[p]);
        const int number = numberOf(i);
        if (stats.nonFiniteReplaced > 0) nonFinite.emplace_back(number, stats.nonFiniteReplaced);
        if (stats.radianceClamped > 0) clamped.emplace_back(number, stats.radianceClamped);
        if (stats.missingNormals > 0) missingNormals.emplace_back(number, stats.missingNormals);
        if (const std::string broken = rtd::inputWarning(stats); !broken.empty()) {
            if (++framesWithoutGeometry <= kFrameWarningsShown)
                progress.warn(fmt::format("{}: {} (frame {}; is {} broken?)",
                                          source->frameFile(i).string(), broken, number,
                                          brokenPasses(frame, stats)));
        }
        if (i < chunk.firstIndex) {  // a warm-up frame: its history is all this run needs of it
            progress.update(i + 1 - chunk.warmupIndex);
            continue;
        }

        std::vector<std::pair<std::string, Image>> debug;
        if (options.debug && (usesHistory(settings.method))) {
            debug.emplace_back("reprojection", denoiser.debugImage(DebugView::Reprojection));
            if (settings.method == Method::Svgf || settings.method == Method::Detail) {
                debug.emplace_back("variance", denoiser.debugImage(DebugView::Variance));
                debug.emplace_back("history", denoiser.debugImage(DebugView::HistoryLength));
            }
            if (settings.method == Method::Learned)
                debug.emplace_back("learned-inputs", denoiser.debugImage(DebugView::LearnedInputs));
        }
        if (writing.valid()) writeTimes.push_back(writing.get());  // in order, one at a time
        writing = writeAsync(numberOf(i), result, std::move(debug));
        progress.update(i + 1 - chunk.warmupIndex);
    }
    if (writing.valid()) writeTimes.push_back(writing.get());
    if (video) video->finish();
    progress.finish();
    double total = std::chrono::duration<double>(Clock::now() - start).count();

    if (framesWithoutGeometry > kFrameWarningsShown)
        fmt::print(stderr,
                   "rtdenoise: warning: {} frames in all were mostly without usable geometry "
                   "(the first {} named above)\n",
                   framesWithoutGeometry, kFrameWarningsShown);
    if (!nonFinite.empty())
        fmt::print(stderr, "rtdenoise: warning: {}\n",
                   inputWarning(nonFinite, "NaN/Inf radiance values replaced by 0"));
    if (!clamped.empty())
        fmt::print(stderr, "rtdenoise: warning: {}\n",
                   inputWarning(clamped, fmt::format("radiance values beyond +-{:g} clamped to it",
                                                     kMaxRadiance)));
    if (!missingNormals.empty())
        fmt::print(stderr, "rtdenoise: warning: {}\n",
                   inputWarning(missingNormals,
                                "object pixels with a zero or NaN/Inf normal (filtered among "
                                "themselves, without a normal term)"));
    if (!options.quiet) {
        const std::vector<ExrSize> written(sizes.begin() + firstWritten, sizes.end());
        fmt::print("{}{} in {:.2f} s ({:.1f} fps overall, I/O included)\n", framesAndSizes(written),
                   firstWritten ? fmt::format(" after {} warm-up frames", firstWritten) : "", total,
                   framesRead / total);
        fmt::print("denoise  median {:8.2f} ms/frame  (device {})\n", median(frameTimes),
                   denoiser.deviceName());
        for (std::size_t p = 0; p < passTimes.size(); ++p)
            fmt::print("  {:<14} median {:8.2f} ms\n", denoiser.passes()[p].name,
                       median(passTimes[p]));
        fmt::print("read wait median {:8.2f} ms/frame (reading overlaps denoising)\n",
                   median(readWaitTimes));
        fmt::print("write     median {:8.2f} ms/frame (overlaps the next frame's denoising)\n",
                   median(writeTimes));
        fmt::print("output: {}\n", options.output.string());
        if (!options.video.empty()) fmt::print("video: {}\n", options.video.string());
    }
    return 0;
}

}  // namespace

void applyConfigFile(CLI::App& command, const fs::path& file) {
    std::error_code ec;
    if (fs::is_directory(file, ec))
        throw Error(ErrorCode::InvalidInput,
                    file.string() +
                        ": is a folder, not a config file (--config names a TOML/INI "
                        "file)");
    std::ifstream in(file);
    if (!in) throw Error(ErrorCode::MissingFile, file.string() + ": cannot open the config file");
    std::vector<CLI::ConfigItem> items;
    try {
        items = CLI::ConfigTOML().from_config(in);
    } catch (const CLI::Error& e) {
        throw Error(ErrorCode::InvalidInput, file.string() + ": " + e.what());
    }
    for (const CLI::ConfigItem& item : items) {
        if (item.name == "++" || item.name == "--") continue;  // section markers
        std::string key = item.name;
        std::replace(key.begin(), key.end(), '_', '-');
        CLI::Option* option = command.get_option_no_throw("--" + key);
        if (!option || key == "config")
            throw Error(ErrorCode::InvalidInput,
                        fmt::format("{}: unknown setting '{}' (see rtdenoise {} --help)",
                                    file.string(), item.name, command.get_name()));
        if (option->count() > 0) continue;  // given on the command line
        try {
            option->add_result(item.inputs);
            option->run_callback();
        } catch (const CLI::Error& e) {
            throw Error(ErrorCode::InvalidInput,
                        fmt::format("{}: {} = {}: {}", file.string(), item.name,
                                    fmt::join(item.inputs, " "), e.what()));
        }
    }
}

void addTilePassesOption(CLI::App& command, TilePasses& target, const std::string& help) {
    addChoice(command, "--tile-passes", target, kTilePasses, help, "auto|on|off");
}

void addDenoiserOptions(CLI::App& c, DenoiserSettings& s) {
    // Named choices: the help shows the names and the default by name, not the enum values.
    addChoice(c, "--method", s.method, kMethods, "Denoising method",
              "jbf|atrous|temporal|svgf|detail|learned");
    addChoice(c, "--spatial-filter", s.temporal.spatialFilter, kFilters,
              "Spatial filter of the temporal method", "jbf|atrous");
    addChoice(c, "--device", s.device, kDevices,
              "Compute device (auto picks a GPU when there is one)", "cpu|cuda|auto");
    c.add_option("--sigma-color", s.edges.sigmaColor, "[>=1e-6] colour edge-stopping sigma")
        ->capture_default_str();
    c.add_option("--sigma-normal", s.edges.sigmaNormal,
                 "[>=1e-6] normal-angle edge-stopping sigma (radians)")
        ->capture_default_str();
    c.add_option("--sigma-plane", s.edges.sigmaPlane, "[>=1e-6] plane-distance edge-stopping sigma")
        ->capture_default_str();
    c.add_flag("--separate-objects,!--no-separate-objects", s.edges.separateObjects,
               "Pixels of another object ID never contribute to a filtered pixel (on by default)");
    c.add_option("--sigma-coord", s.jbf.sigmaCoord, "[>=1e-6] JBF spatial sigma (pixels)")
        ->capture_default_str();
    c.add_option("--radius", s.jbf.radius, "[0,64] JBF kernel half width")->capture_default_str();
    c.add_option("--atrous-passes", s.atrous.passes, "[1,10] A-Trous levels (stride 2^i)")
        ->capture_default_str();
    c.add_option("--alpha", s.temporal.alpha, "[0,1] weight of the current frame")
        ->capture_default_str();
    c.add_option("--clamp-k", s.temporal.clampK, "[>0] history clamp: mu +- k sigma")
        ->capture_default_str();
    c.add_option("--clamp-radius", s.temporal.clampRadius,
                 "[1,15] history clamp window half width (3: 7x7)")
        ->capture_default_str();
    c.add_flag("--geometry-tests,!--no-geometry-tests", s.history.geometryTests,
               "temporal/svgf: history must also agree in depth and normal (on by default)");
    c.add_option("--depth-tolerance", s.history.depthTolerance,
                 "[>0] reject history if |dz| > t * (fwidth(z) + 0.01)")
        ->capture_default_str();
    c.add_option("--normal-tolerance", s.history.normalTolerance,
                 "[>0] reject history if |dn| > t * (fwidth(n) + 0.01)")
        ->capture_default_str();
    c.add_option_function<std::vector<float>>(
         "--motion-scale",
         [&s](const std::vector<float>& v) {
             s.motion.scaleX = v[0];
             s.motion.scaleY = v[1];
         },
         "X,Y: motion vectors times these (default 1,1: pixels, y down; W,-H: UV units, y up)")
        ->delimiter(',')
        ->expected(2);
    c.add_flag("--motion-current-minus-previous", s.motion.currentMinusPrevious,
               "motion vectors point from the previous frame to this one (sign flipped)");
    c.add_option("--svgf-alpha", s.svgf.alpha, "[0,1] svgf colour: current-frame weight floor")
        ->capture_default_str();
    c.add_option("--svgf-moments-alpha", s.svgf.momentsAlpha,
                 "[0,1] svgf luminance moments: current-frame weight floor")
        ->capture_default_str();
    c.add_option("--svgf-sigma-depth", s.svgf.sigmaDepth, "[>=1e-6] svgf depth tolerance (sigma_z)")
        ->capture_default_str();
    c.add_option("--svgf-sigma-normal", s.svgf.sigmaNormal,
                 "[>=1e-6] svgf normal exponent (sigma_n)")
        ->capture_default_str();
    c.add_option("--svgf-sigma-luminance", s.svgf.sigmaLuminance,
                 "[>=1e-6] svgf luminance tolerance in standard deviations (sigma_l)")
        ->capture_default_str();
    c.add_option("--svgf-iterations", s.svgf.iterations, "[1,10] svgf A-Trous iterations")
        ->capture_default_str();
    c.add_option("--svgf-feedback", s.svgf.feedbackIteration,
                 "[0,iterations-1] svgf iteration whose output is the next colour history")
        ->capture_default_str();
    c.add_option("--svgf-max-history", s.svgf.maxHistory, "[1,1000] svgf history length cap")
        ->capture_default_str();
    c.add_option("--svgf-clamp-k", s.svgf.historyClampK,
                 "[>=0] svgf anti-lag: clamp the colour history to mu +- k sigma of the current "
                 "7x7 neighbourhood and shorten it where lighting changed (0: off, the paper)")
        ->capture_default_str();
    c.add_option("--detail-sigma-depth", s.detail.sigmaDepth,
                 "[>=1e-6] detail depth tolerance (sigma_z)")
        ->capture_default_str();
    c.add_option("--detail-sigma-normal", s.detail.sigmaNormal,
                 "[>=1e-6] detail normal exponent (sigma_n)")
        ->capture_default_str();
    c.add_option("--detail-sigma-luminance", s.detail.sigmaLuminance,
                 "[>=1e-6] detail luminance tolerance in standard deviations of the accumulated "
                 "mean")
        ->capture_default_str();
    c.add_option("--detail-iterations", s.detail.iterations, "[1,10] detail A-Trous iterations")
        ->capture_default_str();
    c.add_option("--detail-specular-iterations", s.detail.specularIterations,
                 "[1,10] detail A-Trous iterations of the specular signal (with a specular input)")
        ->capture_default_str();
    c.add_option("--detail-max-history", s.detail.maxHistory,
                 "[1,1000] detail slow history length cap")
        ->capture_default_str();
    c.add_option("--detail-fast-history", s.detail.fastHistory,
                 "[1,max-history] detail fast history length cap (the clamp's guide)")
        ->capture_default_str();
    c.add_option("--detail-clamp-sigma", s.detail.clampSigma,
                 "[>=0] detail: slow history clamped to the fast one's 5x5 mean +- this many "
                 "sigma (0: off)")
        ->capture_default_str();
    c.add_option("--detail-moments-alpha", s.detail.momentsAlpha,
                 "[0,1] detail luminance moments: current-frame weight floor")
        ->capture_default_str();
    c.add_flag("--detail-anti-lag,!--no-detail-anti-lag", s.detail.antiLag,
               "detail: follow the current frame where its 5x5 mean leaves the fast history's "
               "(lighting changed; on by default)");
    c.add_flag("--albedo,!--no-albedo", s.albedo.demodulate,
               "Where albedo_<i>.exr exists, filter colour / albedo and multiply it back (on by "
               "default)");
    c.add_option("--albedo-epsilon", s.albedo.epsilon,
                 "[>0] illumination = colour / max(albedo, epsilon)")
        ->capture_default_str();
    c.add_flag("--outlier,!--no-outlier", s.outlier.enabled,
               "Firefly removal before filtering (on by default)");
    c.add_option("--outlier-radius", s.outlier.radius, "[1,15] firefly window half width")
        ->capture_default_str();
    c.add_option("--outlier-k", s.outlier.k, "[>0] luminance clamp: mean + k stddev")
        ->capture_default_str();
    c.add_flag("--energy,!--no-energy", s.energy.keep,
               "Give back the light the robust steps discard, per 16x16 tile, from the noisy "
               "input's mean (on by default)");
    c.add_option("--energy-cap", s.energy.cap,
                 "[>=1] input samples above cap x the local mean count as that much")
        ->capture_default_str();
    c.add_option("--energy-frame-share", s.energy.frameShare,
                 "[0, 1] the light above that cap is given back over the whole frame, one "
                 "sample lifting it by at most this share (0: not given back)")
        ->capture_default_str();
    c.add_option("--weights", s.learned.weights,
                 "The learned method's weights file (training/train.py writes one; default: the "
                 "built-in weights)");
}

Command addDenoiseCommand(CLI::App& app) {
    auto options = std::make_shared<DenoiseOptions>();
    auto settings = std::make_shared<DenoiserSettings>();
    CLI::App* c =
        app.add_subcommand("denoise",
                           "Denoise a sequence (a folder of beauty_i.exr, normal_i.exr, "
                           "position_i.exr, depth_i.exr, ID_i.exr, matrix_i.mat, or Blender's "
                           "multilayer EXRs) into OUT_DIR/result_<i>.exr");
    c->add_option(
        "--config", options->config,
        "Read options from a TOML/INI file: one `key = value` per line, keys are the long "
        "option names (e.g. method = \"jbf\", sigma-color = 0.8); flags given on the "
        "command line win");
    c->add_option("INPUT", options->input,
                  "The input sequence: a course-layout folder, a folder of Blender multilayer "
                  "EXRs (0001.exr, ...; result_0 is the first), or a pattern naming them "
                  "(renders/frame_####.exr, renders/frame_%04d.exr)")
        ->required();
    c->add_option("--view-layer", options->viewLayer,
                  "Blender input: the view layer to read (default: the first with a colour pass "
                  "and Depth)");
    c->add_option("-o,--output", options->output, "Output folder (created if missing)")->required();
    addDenoiserOptions(*c, *settings);
    c->add_flag("--png", options->png, "Also write result_<i>.png (ACES, sRGB)");
    addChoice(*c, "--compression", options->exr.compression, kCompressions,
              "Compression of result_<i>.exr. Lossless: none, rle, zips, zip, piz; b44, b44a "
              "for float (they store float as is). Lossy: pxr24 for float, b44, b44a for half, "
              "dwaa, dwab",
              "none|rle|zips|zip|piz|pxr24|b44|b44a|dwaa|dwab");
    c->add_flag("--half", options->exr.half,
                "Write result_<i>.exr with HALF channels (rounded to the nearest half) instead "
                "of FLOAT");
    c->add_option("--exposure", options->exposure, "Exposure multiplier before tone mapping")
        ->capture_default_str();
    c->add_option("--video", options->video, "Also write an H.264 MP4 (needs ffmpeg)");
    c->add_option("--fps", options->fps, "Frames per second of the video")
        ->check(CLI::Range(1, 240))
        ->capture_default_str();
    c->add_flag("--debug", options->debug,
                "Write reprojection_<i>.png (history valid green, outside the screen red, other "
                "object or depth/normal mismatch yellow, background blue, no history black); "
                "svgf also variance_<i>.png (luminance stddev) and history_<i>.png (length / cap); "
                "learned: learned-inputs/learned-inputs_<i>.exr, its network's inputs (training/)");
    c->add_option("--frames", options->frames,
                  "N: only the first N frames (0: all). A:B: a chunk of the shot, the input's "
                  "frame numbers A..B-1 (A: to the end; A..B: A to B inclusive, as Blender "
                  "writes ranges), written as result_<number>; the --warmup frames before A "
                  "are denoised first for their history, not written")
        ->check(frameSelectionValidator());
    c->add_option_function<int>(
         "--warmup",
         [options](int frames) {
             options->warmup = frames;
             options->warmupGiven = true;
         },
         fmt::format("[0,1000000] with --frames A:B: frames before A denoised to build the "
                     "history, not written (default {}: the chunk's results then match a run "
                     "over the whole shot, docs/farm.md)",
                     kDefaultChunkWarmup))
        ->check(CLI::Range(0, 1000000));
    c->add_flag("--dry-run", options->dryRun,
                "Check the input's files (headers), the options and the output folder, print "
                "what would be denoised and exit; creates nothing");
    c->add_flag("-q,--quiet", options->quiet, "No progress or summary");
    return {c, [c, options, settings] {
                // The reading and writing threads share the cores with the denoiser's: OpenMP
                // threads that sleep when they wait, instead of spinning, leave them the time
                // (docs/performance-cpu.md, 2026-12-02). Set before OpenMP starts; the caller's
                // OMP_WAIT_POLICY wins.
                ::setenv("OMP_WAIT_POLICY", "passive", 0);
                if (!options->config.empty()) applyConfigFile(*c, options->config);
                validate(*settings);
                return runDenoise(*options, *settings);
            }};
}

}  // namespace rtd::cli
