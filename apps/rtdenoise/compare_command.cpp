// `rtdenoise compare RESULT_DIR REFERENCE_DIR`: per-frame quality metrics of a denoised sequence
// against its reference (table, CSV, JSON) and contact sheets of chosen frames.
#include <fmt/format.h>

#include <algorithm>
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
#include "rtdenoise/rtdenoise.h"

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
    std::vector<int> frames;
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

struct FramePair {
    Image result;
    Image reference;
};

FramePair readPair(const fs::path& results, const fs::path& references, int index) {
    const fs::path resultFile = framePath(results, "result", index);
    const fs::path referenceFile = framePath(references, "reference", index);
    FramePair pair{readExr(resultFile, kRgb), readExr(referenceFile, kRgb)};
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
    return fmt::format("{:>5}  {:>11}  {:>11}  {:>9.2f}  {:>7.4f}  {:>11}\n", label, sci(m.mse),
                       sci(m.relMse), m.psnr, m.ssim,
                       m.temporalError ? sci(*m.temporalError) : std::string("-"));
}

std::string table(const metrics::SequenceMetrics& s) {
    std::string out = fmt::format("{:>5}  {:>11}  {:>11}  {:>9}  {:>7}  {:>11}\n", "frame", "MSE",
                                  "relMSE", "PSNR (dB)", "SSIM", "temporal");
    for (std::size_t i = 0; i < s.frames.size(); ++i)
        out += tableRow(std::to_string(i), s.frames[i]);
    out += tableRow("mean", s.mean);
    return out;
}

std::string jsonFields(const metrics::FrameMetrics& m) {
    return fmt::format(
        "\"mse\": {}, \"rel_mse\": {}, \"psnr\": {}, \"ssim\": {}, \"temporal_error\": {}",
        jsonNumber(m.mse), jsonNumber(m.relMse), jsonNumber(m.psnr), jsonNumber(m.ssim),
        jsonNumber(m.temporalError));
}

std::string json(const metrics::SequenceMetrics& s) {
    std::string out = "{\n  \"frames\": [\n";
    for (std::size_t i = 0; i < s.frames.size(); ++i)
        out += fmt::format("    {{\"frame\": {}, {}}}{}\n", i, jsonFields(s.frames[i]),
                           i + 1 < s.frames.size() ? "," : "");
    out += fmt::format("  ],\n  \"mean\": {{{}}}\n}}\n", jsonFields(s.mean));
    return out;
}

std::string csvRow(const std::string& label, const metrics::FrameMetrics& m) {
    return fmt::format("{},{},{},{},{},{}\n", label, csvNumber(m.mse), csvNumber(m.relMse),
                       csvNumber(m.psnr), csvNumber(m.ssim), csvNumber(m.temporalError));
}

std::string csv(const metrics::SequenceMetrics& s) {
    std::string out = "frame,mse,rel_mse,psnr,ssim,temporal_error\n";
    for (std::size_t i = 0; i < s.frames.size(); ++i) out += csvRow(std::to_string(i), s.frames[i]);
    out += csvRow("mean", s.mean);
    return out;
}

// ---- the command ----

// Frames with a contact sheet: the chosen ones, else first, middle and last.
std::vector<int> sheetFrames(const std::vector<int>& chosen, int frameCount) {
    std::vector<int> frames = chosen;
    if (frames.empty()) frames = {0, frameCount / 2, frameCount - 1};
    for (int f : frames)
        if (f < 0 || f >= frameCount)
            throw Error(ErrorCode::InvalidArgument,
                        fmt::format("--frames: frame {} is outside 0..{}", f, frameCount - 1));
    std::sort(frames.begin(), frames.end());
    frames.erase(std::unique(frames.begin(), frames.end()), frames.end());
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
        throw Error(ErrorCode::InvalidArgument,
                    fmt::format("--exposure must be finite and > 0, got {}", options.exposure));
    requireFolder(options.results, "RESULT_DIR");
    requireFolder(options.references, "REFERENCE_DIR");
    const int frameCount = countFrames(options.results, "result");
    // Every result needs its reference: checked up front, before minutes of 4K reading.
    std::error_code ec;
    for (int i = 0; i < frameCount; ++i) {
        const fs::path reference = framePath(options.references, "reference", i);
        if (!fs::exists(reference, ec))
            throw Error(ErrorCode::MissingFile,
                        fmt::format("{}: no such file (the reference of {})", reference.string(),
                                    framePath(options.results, "result", i).string()));
    }

    // A bad --json/--csv path fails now, not after the whole sequence was read.
    for (const fs::path& file : {options.json, options.csv}) {
        const fs::path parent = file.parent_path();
        if (!file.empty() && !parent.empty() && !fs::is_directory(parent, ec))
            throw Error(ErrorCode::IoFailure,
                        fmt::format("{}: cannot write, folder '{}' does not exist", file.string(),
                                    parent.string()));
    }

    const bool sheets = !options.images.empty();
    std::vector<int> chosen;
    std::optional<fs::path> input;
    if (sheets) {
        chosen = sheetFrames(options.frames, frameCount);
        input = inputFolder(options, chosen);
        fs::create_directories(options.images, ec);
        if (!fs::is_directory(options.images))
            throw Error(ErrorCode::IoFailure,
                        fmt::format("{}: cannot create the images folder{}",
                                    options.images.string(), ec ? " (" + ec.message() + ")" : ""));
    }

    metrics::SequenceComparer comparer(options.exposure);
    metrics::ContactSheetOptions sheetOptions;
    sheetOptions.exposure = options.exposure;
    std::vector<fs::path> written;
    Progress progress(frameCount, options.quiet);

    // Frame i+1 is read on another thread while frame i is compared.
    const auto readAsync = [&](int i) {
        return std::async(std::launch::async, [&options, i] {
            return readPair(options.results, options.references, i);
        });
    };
    std::future<FramePair> next = readAsync(0);
    std::string firstSize;
    for (int i = 0; i < frameCount; ++i) {
        FramePair pair = next.get();
        if (i + 1 < frameCount) next = readAsync(i + 1);
        // The temporal error compares consecutive frames: the size must stay that of frame 0.
        if (i == 0) {
            firstSize = sizeText(pair.result);
        } else if (sizeText(pair.result) != firstSize) {
            throw Error(
                ErrorCode::InvalidInput,
                fmt::format("{}: {}, but {} is {}",
                            framePath(options.results, "result", i).string(), sizeText(pair.result),
                            framePath(options.results, "result", 0).string(), firstSize));
        }
        comparer.addFrame(pair.result, pair.reference);
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
        progress.update(i + 1);
    }
    progress.finish();

    const metrics::SequenceMetrics result = comparer.metrics();
    if (!options.json.empty()) writeFileAtomically(options.json, json(result));
    if (!options.csv.empty()) writeFileAtomically(options.csv, csv(result));
    if (!options.quiet) {
        fmt::print("{}", table(result));
        fmt::print("MSE, relMSE: linear RGB; PSNR, SSIM, temporal: tone-mapped (exposure {})\n",
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
    return 0;
}

}  // namespace

Command addCompareCommand(CLI::App& app) {
    auto options = std::make_shared<CompareOptions>();
    CLI::App* c = app.add_subcommand(
        "compare",
        "Quality metrics of RESULT_DIR/result_<i>.exr against "
        "REFERENCE_DIR/reference_<i>.exr: MSE, relMSE (linear), PSNR, SSIM, temporal "
        "error (tone-mapped), per frame and mean");
    c->add_option("RESULT_DIR", options->results, "Folder of result_<i>.exr")->required();
    c->add_option("REFERENCE_DIR", options->references, "Folder of reference_<i>.exr")->required();
    c->add_option("--json", options->json,
                  "Also write the metrics as JSON: {\"frames\": [...], \"mean\": {...}}, "
                  "infinite PSNR as null");
    c->add_option("--csv", options->csv, "Also write the metrics as CSV (mean on the last row)");
    CLI::Option* images =
        c->add_option("--images", options->images,
                      "Write contact_<i>.png into this folder (created if missing): input | "
                      "result | reference | relative-error heat map");
    c->add_option("--frames", options->frames,
                  "Frames with a contact sheet, e.g. 0,9,15 (default: first, middle, last)")
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
