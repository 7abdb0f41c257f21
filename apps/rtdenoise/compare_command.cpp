// `rtdenoise compare RESULT_DIR REFERENCE_DIR`: per-frame quality metrics of a denoised sequence
// against its reference (table, CSV, JSON) and contact sheets of chosen frames.
#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <filesystem>
#include <future>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "commands.h"
#include "metrics/metrics.h"
#include "progress.h"
#include "rtdenoise/io.h"
#include "rtdenoise/rtdenoise.hpp"

namespace fs = std::filesystem;

namespace rtd::cli {
namespace {

struct CompareOptions {
    fs::path results;
    fs::path references;
    fs::path json;
    fs::path csv;
    fs::path images;
    fs::path input;
    std::vector<std::string> frames;  // compared: "3" or "0..9" items
    std::vector<std::string> sheets;  // with a contact sheet
    float exposure = 1.0f;
    bool quiet = false;
};

const std::vector<std::vector<std::string>> kRgb = {{"R"}, {"G"}, {"B"}};

fs::path framePath(const fs::path& folder, std::string_view stem, int index) {
    return folder / fmt::format("{}_{}.exr", stem, index);
}

void requireFolder(const fs::path& folder, std::string_view role) {
    std::error_code ec;
    const auto status = fs::status(folder, ec);
    if (!fs::exists(status))
        throw Error(ErrorCode::MissingFile,
                    fmt::format("{}: no such folder ({})", folder.string(), role));
    if (!fs::is_directory(status))
        throw Error(ErrorCode::MissingFile,
                    fmt::format("{}: not a folder ({})", folder.string(), role));
}

// "dir/reference/" -> "dir": the renderer writes DIR/beauty_i.exr beside DIR/reference/.
fs::path parentFolder(const fs::path& folder) {
    fs::path p = fs::absolute(folder).lexically_normal();
    if (p.filename().empty()) p = p.parent_path();  // a trailing separator
    return p.parent_path();
}

std::string sizeText(const Image& image) {
    return fmt::format("{}x{}", image.width, image.height);
}

void requireSameSize(const fs::path& file, const Image& image, const fs::path& resultFile,
                     const Image& result) {
    if (image.width != result.width || image.height != result.height)
        throw Error(ErrorCode::InvalidInput,
                    fmt::format("{}: {}, but {} is {}", file.string(), sizeText(image),
                                resultFile.string(), sizeText(result)));
}

// REFERENCE_DIR's frames: reference_<i>.exr, or numbered EXRs as Blender writes them (0001.exr,
// ...: frame i is the i-th number), their colour R, G, B or a multilayer file's Combined pass.
struct References {
    fs::path folder;
    std::optional<NumberedFiles> numbered;
    ChannelChoices channels = kRgb;
    int count = 0;

    fs::path file(int index) const {
        return numbered ? numbered->file(index) : framePath(folder, "reference", index);
    }
};

References findReferences(const fs::path& folder) {
    References references{folder, std::nullopt, kRgb, 0};
    std::error_code ec;
    bool course = false, numbered = false;
    for (fs::directory_iterator it(folder, ec); !ec && it != fs::directory_iterator();
         it.increment(ec)) {
        const std::string name = it->path().filename().string();
        course = course || frameIndexOf(name, "reference") >= 0;
        numbered = numbered || (name.ends_with(".exr") && name.size() > 4 &&
                                std::isdigit(static_cast<unsigned char>(name[name.size() - 5])));
    }
    if (course || !numbered) {
        references.count = countFrames(folder, "reference");
        return references;
    }
    references.numbered = findNumberedFiles(folder);
    references.count = references.numbered->count;
    references.channels = colourChannelsOf(references.numbered->file(0));
    return references;
}

struct FramePair {
    Image result;
    Image reference;
};

FramePair readPair(const fs::path& results, const References& references, int index) {
    const fs::path resultFile = framePath(results, "result", index);
    const fs::path referenceFile = references.file(index);
    FramePair pair{readExr(resultFile, kRgb), readExr(referenceFile, references.channels)};
    requireSameSize(referenceFile, pair.reference, resultFile, pair.result);
    return pair;
}

// ---- output ----

// Scientific for the error measures: they span decades between methods.
std::string sci(double v) {
    return std::isfinite(v) ? fmt::format("{:.4e}", v) : fmt::format("{}", v);
}

// JSON has no infinity or NaN: both become null (PSNR of identical images).
std::string jsonNumber(double v) {
    return std::isfinite(v) ? fmt::format("{}", v) : "null";
}
std::string jsonNumber(const std::optional<double>& v) {
    return v ? jsonNumber(*v) : "null";
}
std::string csvNumber(double v) {
    return fmt::format("{}", v);
}  // inf / nan as such
std::string csvNumber(const std::optional<double>& v) {
    return v ? csvNumber(*v) : "";
}

std::string tableRow(const std::string& label, const metrics::FrameMetrics& m) {
    return fmt::format("{:>5}  {:>11}  {:>11}  {:>9.2f}  {:>7.4f}  {:>11}  {:>7.4f}\n", label,
                       sci(m.mse), sci(m.relMse), m.psnr, m.ssim,
                       m.temporalError ? sci(*m.temporalError) : std::string("-"),
                       metrics::energyRatio(m));
}

// Row i of `s` is frame indices[i] of the sequence.
std::string table(const metrics::SequenceMetrics& s, const std::vector<int>& indices) {
    std::string out = fmt::format("{:>5}  {:>11}  {:>11}  {:>9}  {:>7}  {:>11}  {:>7}\n", "frame",
                                  "MSE", "relMSE", "PSNR (dB)", "SSIM", "temporal", "energy");
    for (std::size_t i = 0; i < s.frames.size(); ++i)
        out += tableRow(std::to_string(indices[i]), s.frames[i]);
    out += tableRow("mean", s.mean);
    return out;
}

std::string jsonFields(const metrics::FrameMetrics& m) {
    return fmt::format(
        "\"mse\": {}, \"rel_mse\": {}, \"psnr\": {}, \"ssim\": {}, \"temporal_error\": {}, "
        "\"energy_ratio\": {}",
        jsonNumber(m.mse), jsonNumber(m.relMse), jsonNumber(m.psnr), jsonNumber(m.ssim),
        jsonNumber(m.temporalError), jsonNumber(metrics::energyRatio(m)));
}

std::string json(const metrics::SequenceMetrics& s, const std::vector<int>& indices) {
    std::string out = "{\n  \"frames\": [\n";
    for (std::size_t i = 0; i < s.frames.size(); ++i)
        out += fmt::format("    {{\"frame\": {}, {}}}{}\n", indices[i], jsonFields(s.frames[i]),
                           i + 1 < s.frames.size() ? "," : "");
    out += fmt::format("  ],\n  \"mean\": {{{}}},\n  \"excluded_reference_pixels\": {}\n}}\n",
                       jsonFields(s.mean), s.mean.excludedPixels);
    return out;
}

std::string csvRow(const std::string& label, const metrics::FrameMetrics& m) {
    return fmt::format("{},{},{},{},{},{},{}\n", label, csvNumber(m.mse), csvNumber(m.relMse),
                       csvNumber(m.psnr), csvNumber(m.ssim), csvNumber(m.temporalError),
                       csvNumber(metrics::energyRatio(m)));
}

std::string csv(const metrics::SequenceMetrics& s, const std::vector<int>& indices) {
    std::string out = "frame,mse,rel_mse,psnr,ssim,temporal_error,energy_ratio\n";
    for (std::size_t i = 0; i < s.frames.size(); ++i)
        out += csvRow(std::to_string(indices[i]), s.frames[i]);
    out += csvRow("mean", s.mean);
    return out;
}

// Files with their counts of pixels holding NaN/Inf.
using PixelCounts = std::vector<std::pair<fs::path, std::size_t>>;

// "DIR/reference_1.exr: 2 pixels with NaN/Inf", or for several files the total and the files.
std::string nonFiniteText(const PixelCounts& files) {
    const auto pixels = [](std::size_t n) {
        return fmt::format("{} pixel{}", n, n == 1 ? "" : "s");
    };
    if (files.size() == 1)
        return fmt::format("{}: {} with NaN/Inf", files[0].first.string(), pixels(files[0].second));
    std::size_t total = 0;
    std::string listed;
    constexpr std::size_t kListed = 10;
    for (std::size_t i = 0; i < files.size(); ++i) {
        total += files[i].second;
        if (i < kListed)
            listed +=
                fmt::format("{}{}: {}", i ? ", " : "", files[i].first.string(), files[i].second);
    }
    if (files.size() > kListed) listed += ", ...";
    return fmt::format("{} with NaN/Inf in {} files ({})", pixels(total), files.size(), listed);
}

// ---- the command ----

// "0,5..7" -> {0, 5, 6, 7}: sorted, each frame once; throws naming `option` for a bad item.
std::vector<int> parseFrameList(const std::vector<std::string>& items, std::string_view option) {
    const auto number = [&](std::string_view text, const std::string& item) {
        int value = -1;
        const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
        if (text.empty() || ec != std::errc() || end != text.data() + text.size() || value < 0)
            throw Error(ErrorCode::InvalidArgument,
                        fmt::format("{}: '{}' is not a frame (a number >= 0) or a range A..B",
                                    option, item));
        return value;
    };
    constexpr long long kMaxListed = 1000000;
    std::vector<int> frames;
    for (const std::string& item : items) {
        const std::size_t dots = item.find("..");
        if (dots == std::string::npos) {
            frames.push_back(number(item, item));
            continue;
        }
        const int first = number(std::string_view(item).substr(0, dots), item);
        const int last = number(std::string_view(item).substr(dots + 2), item);
        if (last < first || last - first >= kMaxListed)
            throw Error(ErrorCode::InvalidArgument,
                        fmt::format("{}: '{}' is not a range A..B with A <= B", option, item));
        for (int f = first; f <= last; ++f) frames.push_back(f);
    }
    std::sort(frames.begin(), frames.end());
    frames.erase(std::unique(frames.begin(), frames.end()), frames.end());
    return frames;
}

// The frames compared: --frames, else all of them, which needs result and reference sets of one
// length (scoring a longer set's extra frames, or missing some, would be a wrong mean).
std::vector<int> comparedFrames(const CompareOptions& options, int resultCount,
                                int referenceCount) {
    if (options.frames.empty()) {
        if (resultCount != referenceCount)
            throw Error(
                ErrorCode::InvalidInput,
                fmt::format("{} holds {} results but {} holds {} references: the sets "
                            "differ in length (choose the frames to compare with "
                            "--frames, e.g. --frames 0..{})",
                            options.results.string(), resultCount, options.references.string(),
                            referenceCount, std::min(resultCount, referenceCount) - 1));
        std::vector<int> all(std::size_t(resultCount), 0);
        for (int i = 0; i < resultCount; ++i) all[std::size_t(i)] = i;
        return all;
    }
    std::vector<int> frames = parseFrameList(options.frames, "--frames");
    const int available = std::min(resultCount, referenceCount);
    for (int f : frames)
        if (f >= available)
            throw Error(ErrorCode::InvalidArgument,
                        fmt::format("--frames: frame {} is outside 0..{} ({} holds {} results, "
                                    "{} holds {} references)",
                                    f, available - 1, options.results.string(), resultCount,
                                    options.references.string(), referenceCount));
    return frames;
}

// Frames with a contact sheet: --sheets (each one compared), else the first, middle and last of
// the compared frames.
std::vector<int> sheetFrames(const CompareOptions& options, const std::vector<int>& compared) {
    if (options.sheets.empty()) {
        std::vector<int> frames{compared.front(), compared[compared.size() / 2], compared.back()};
        frames.erase(std::unique(frames.begin(), frames.end()), frames.end());  // sorted already
        return frames;
    }
    std::vector<int> frames = parseFrameList(options.sheets, "--sheets");
    for (int f : frames)
        if (!std::binary_search(compared.begin(), compared.end(), f))
            throw Error(ErrorCode::InvalidArgument,
                        fmt::format("--sheets: frame {} is not among the frames compared", f));
    return frames;
}

// The folder of the input panel's beauty_<i>.exr: --input (every chosen frame must be there), or
// REFERENCE_DIR's parent when it holds them all; none: the sheets have three panels.
std::optional<fs::path> inputFolder(const CompareOptions& options, const std::vector<int>& frames) {
    std::error_code ec;
    if (!options.input.empty()) {
        requireFolder(options.input, "--input");
        for (int f : frames)
            if (!fs::exists(framePath(options.input, "beauty", f), ec))
                throw Error(ErrorCode::MissingFile,
                            fmt::format("{}: no such file (--input)",
                                        framePath(options.input, "beauty", f).string()));
        return options.input;
    }
    const fs::path parent = parentFolder(options.references);
    for (int f : frames)
        if (!fs::exists(framePath(parent, "beauty", f), ec)) return std::nullopt;
    return parent;
}

int runCompare(const CompareOptions& options) {
    if (!std::isfinite(options.exposure) || options.exposure <= 0.0f)
        throw Error(
            ErrorCode::InvalidArgument,
            fmt::format("--exposure must be a finite number > 0, got {}", options.exposure));
    // A bad --json/--csv path fails now, not after the whole sequence was read.
    for (const fs::path& file : {options.json, options.csv})
        if (!file.empty()) checkOutputFile(file);
    requireFolder(options.results, "RESULT_DIR");
    requireFolder(options.references, "REFERENCE_DIR");
    // Both sets counted (each numbered 0..N-1) and matched up front, before minutes of 4K reading.
    const int resultCount = countFrames(options.results, "result");
    const References references = findReferences(options.references);
    const std::vector<int> compared = comparedFrames(options, resultCount, references.count);
    const int frameCount = static_cast<int>(compared.size());
    std::error_code ec;

    const bool sheets = !options.images.empty();
    std::vector<int> chosen;
    std::optional<fs::path> input;
    if (sheets) {
        chosen = sheetFrames(options, compared);
        if (!references.numbered || !options.input.empty()) input = inputFolder(options, chosen);
        fs::create_directories(options.images, ec);
        if (!fs::is_directory(options.images))
            throw Error(ErrorCode::IoFailure,
                        fmt::format("{}: cannot create the images folder{}",
                                    options.images.string(), ec ? " (" + ec.message() + ")" : ""));
    }

    // The temporal error compares consecutive frames: a gap in the compared frames starts a new
    // comparer, so the frame after it has none.
    std::optional<metrics::SequenceComparer> comparer;
    std::vector<metrics::FrameMetrics> frameMetrics;
    metrics::ContactSheetOptions sheetOptions;
    sheetOptions.exposure = options.exposure;
    std::vector<fs::path> written;
    Progress progress(frameCount, options.quiet);

    // Frame i+1 is read on another thread while frame i is compared.
    const auto readAsync = [&](int i) {
        return std::async(std::launch::async, [&options, &references, i] {
            return readPair(options.results, references, i);
        });
    };
    std::future<FramePair> next = readAsync(compared[0]);
    std::string firstSize;
    PixelCounts excluded, brokenResults;
    for (int n = 0; n < frameCount; ++n) {
        const int i = compared[std::size_t(n)];
        FramePair pair = next.get();
        if (n + 1 < frameCount) next = readAsync(compared[std::size_t(n) + 1]);
        // The temporal error compares consecutive frames: the size must stay that of the first.
        if (n == 0) {
            firstSize = sizeText(pair.result);
        } else if (sizeText(pair.result) != firstSize) {
            throw Error(
                ErrorCode::InvalidInput,
                fmt::format("{}: {}, but {} is {}",
                            framePath(options.results, "result", i).string(), sizeText(pair.result),
                            framePath(options.results, "result", compared[0]).string(), firstSize));
        }
        // A reference pixel with NaN/Inf has no right answer: left out of every metric, and
        // counted; a reference of nothing else leaves nothing to score.
        const fs::path referenceFile = references.file(i);
        const metrics::PixelMask scored = metrics::finitePixels(pair.reference);
        if (!scored.empty() && metrics::excludedPixels(scored) == scored.size())
            throw Error(ErrorCode::InvalidInput,
                        fmt::format("{}: every pixel holds NaN/Inf: nothing to score {} against",
                                    referenceFile.string(),
                                    framePath(options.results, "result", i).string()));
        if (n == 0 || compared[std::size_t(n) - 1] != i - 1) comparer.emplace(options.exposure);
        frameMetrics.push_back(comparer->addFrame(pair.result, pair.reference));
        if (frameMetrics.back().excludedPixels > 0)
            excluded.emplace_back(referenceFile, frameMetrics.back().excludedPixels);
        if (const std::size_t broken = metrics::excludedPixels(metrics::finitePixels(pair.result)))
            brokenResults.emplace_back(framePath(options.results, "result", i), broken);
        if (sheets && std::binary_search(chosen.begin(), chosen.end(), i)) {
            std::optional<Image> beauty;
            if (input) {
                const fs::path file = framePath(*input, "beauty", i);
                beauty = readExr(file, kRgb);
                requireSameSize(file, *beauty, framePath(options.results, "result", i),
                                pair.result);
            }
            const fs::path png = options.images / fmt::format("contact_{}.png", i);
            writePng(png, metrics::contactSheet(beauty ? &*beauty : nullptr, pair.result,
                                                pair.reference, sheetOptions));
            written.push_back(png);
        }
        progress.update(n + 1);
    }
    progress.finish();

    const metrics::SequenceMetrics result{frameMetrics, metrics::meanOf(frameMetrics)};
    if (!options.json.empty()) writeFileAtomically(options.json, json(result, compared));
    if (!options.csv.empty()) writeFileAtomically(options.csv, csv(result, compared));
    if (!options.quiet) {
        fmt::print("{}", table(result, compared));
        fmt::print(
            "MSE, relMSE, energy (result mean / reference mean): linear RGB; PSNR, SSIM, "
            "temporal: tone-mapped (exposure {})\n",
            options.exposure);
        if (sheets) {
            fmt::print(
                "contact sheets ({}result | reference | relative error, viridis, log scale "
                "{:g}% to {:g}%): {}\n",
                input ? "input | " : "", sheetOptions.scale.minError * 100.0,
                sheetOptions.scale.maxError * 100.0, options.images.string());
            for (const fs::path& png : written) fmt::print("  {}\n", png.filename().string());
        }
        if (!options.json.empty()) fmt::print("json: {}\n", options.json.string());
        if (!options.csv.empty()) fmt::print("csv: {}\n", options.csv.string());
    }
    if (!excluded.empty())
        fmt::print(stderr, "rtdenoise: warning: {} left out of every metric\n",
                   nonFiniteText(excluded));
    // A result with NaN/Inf is broken: its MSE and relMSE say so as NaN, and the exit status too.
    if (!brokenResults.empty()) {
        fmt::print(stderr,
                   "rtdenoise: error: {}: a broken result, so MSE and relMSE are NaN/Inf (PSNR, "
                   "SSIM and the temporal error take those pixels as black)\n",
                   nonFiniteText(brokenResults));
        return 1;
    }
    return 0;
}

}  // namespace

Command addCompareCommand(CLI::App& app) {
    auto options = std::make_shared<CompareOptions>();
    CLI::App* c = app.add_subcommand(
        "compare",
        "Quality metrics of RESULT_DIR/result_<i>.exr against "
        "REFERENCE_DIR/reference_<i>.exr (or its numbered EXRs 0001.exr, ... as Blender writes "
        "them: result_0 against the first): MSE, relMSE (linear), PSNR, SSIM, temporal "
        "error (tone-mapped), per frame and mean");
    c->add_option("RESULT_DIR", options->results, "Folder of result_<i>.exr")->required();
    c->add_option("REFERENCE_DIR", options->references,
                  "Folder of reference_<i>.exr, or of numbered EXRs (0001.exr, ...: R, G, B or a "
                  "multilayer file's Combined pass)")
        ->required();
    c->add_option("--json", options->json,
                  "Also write the metrics as JSON: {\"frames\": [...], \"mean\": {...}}, "
                  "infinite PSNR as null");
    c->add_option("--csv", options->csv, "Also write the metrics as CSV (mean on the last row)");
    CLI::Option* images =
        c->add_option("--images", options->images,
                      "Write contact_<i>.png into this folder (created if missing): input | "
                      "result | reference | relative-error heat map");
    c->add_option("--frames", options->frames,
                  "Frames to compare, e.g. 0,9,15 or 0..9 (default: all; then RESULT_DIR and "
                  "REFERENCE_DIR must hold as many frames, else this is an error); the temporal "
                  "error needs the frame before in the list")
        ->delimiter(',');
    c->add_option("--sheets", options->sheets,
                  "Frames with a contact sheet, among those compared, e.g. 0,9 (default: the "
                  "first, middle and last compared)")
        ->delimiter(',')
        ->needs(images);
    c->add_option("--input", options->input,
                  "Folder of beauty_<i>.exr for the sheets' input panel (default: REFERENCE_DIR's "
                  "parent when it has them; else the sheets have 3 panels)")
        ->needs(images);
    c->add_option("--exposure", options->exposure, "Exposure multiplier before tone mapping")
        ->capture_default_str();
    c->add_flag("-q,--quiet", options->quiet, "Print nothing (use with --json or --csv)");
    return {c, [options] { return runCompare(*options); }};
}

}  // namespace rtd::cli
