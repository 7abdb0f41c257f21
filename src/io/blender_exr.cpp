// Blender's multilayer EXRs: numbered frame files (a folder, %04d or #### patterns), the view
// layer's passes found by channel name, and the conversion of Cycles' conventions (miss depth,
// IndexOB, Vector) into a Frame; the writer that produces the same files from a Frame.
// The conventions, measured on Blender 3.4's own renders: docs/inputs.md.
#include <fmt/format.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <system_error>
#include <utility>
#include <vector>

#include "io/numbering.h"
#include "rtdenoise/error.h"
#include "rtdenoise/io.h"

namespace fs = std::filesystem;

namespace rtd {
namespace {

// Depth at or beyond this is background: Cycles writes kCyclesMissDepth there, and a decade of
// margin also catches it stored as half (infinity) or rounded by other tools.
constexpr float kBackgroundDepth = kCyclesMissDepth * 0.1f;
// Blender's Object.pass_index range.
constexpr int kMaxPassIndex = 32767;
// IndexOB holds integers as floats; anything further than this from one is a broken file.
constexpr float kIdTolerance = 1e-3f;

// ---- numbered files ----

bool isDigit(char c) {
    return c >= '0' && c <= '9';
}

// The number in `digits` written zero-padded to `width` (the canonical form for that width),
// or nullopt.
std::optional<int> numberOf(std::string_view digits, int width) {
    if (digits.empty() || !std::all_of(digits.begin(), digits.end(), isDigit)) return std::nullopt;
    if (digits.size() < std::size_t(width)) return std::nullopt;
    if (digits.size() > std::size_t(width) && digits[0] == '0') return std::nullopt;
    int number = 0;
    const auto [end, ec] = std::from_chars(digits.data(), digits.data() + digits.size(), number);
    if (ec != std::errc() || end != digits.data() + digits.size()) return std::nullopt;
    return number;
}

// A file-name pattern split at its placeholder: prefix, zero-padding width, suffix.
struct Pattern {
    std::string prefix, suffix;
    int digits = 1;
};

// %d, %0Nd or a run of N '#' (exactly one); nullopt for a name without any.
std::optional<Pattern> parsePattern(const std::string& name, const fs::path& input) {
    const std::size_t hash = name.find('#');
    const std::size_t percent = name.find('%');
    if (hash == std::string::npos && percent == std::string::npos) return std::nullopt;
    const auto bad = [&](const std::string& why) {
        return Error(ErrorCode::InvalidArgument,
                     fmt::format("{}: {} (a frame pattern holds one %d, %0Nd or run of '#', "
                                 "e.g. frame_%04d.exr or frame_####.exr)",
                                 input.string(), why));
    };
    Pattern pattern;
    std::size_t end = 0;
    if (hash != std::string::npos && (percent == std::string::npos || hash < percent)) {
        end = hash;
        while (end < name.size() && name[end] == '#') ++end;
        pattern.prefix = name.substr(0, hash);
        pattern.digits = int(end - hash);
    } else {
        end = percent + 1;
        std::size_t widthStart = end;
        if (end < name.size() && name[end] == '0') widthStart = ++end;
        while (end < name.size() && isDigit(name[end])) ++end;
        if (end >= name.size() || name[end] != 'd') throw bad("an unsupported % conversion");
        const std::string width = name.substr(widthStart, end - widthStart);
        if (!width.empty() && widthStart == percent + 1)
            throw bad("%" + width + "d pads with spaces; use %0" + width + "d");
        pattern.digits = width.empty() ? 1 : std::max(1, std::stoi(width));
        if (pattern.digits > 9) throw bad("a number width over 9 digits");
        pattern.prefix = name.substr(0, percent);
        ++end;
    }
    pattern.suffix = name.substr(end);
    if (pattern.suffix.find('#') != std::string::npos ||
        pattern.suffix.find('%') != std::string::npos)
        throw bad("more than one frame-number placeholder");
    return pattern;
}

// The folder's entries "<prefix><number><suffix>" with their numbers; entries that match but are
// not regular files are errors.
std::vector<int> numbersIn(const fs::path& folder, const Pattern& pattern) {
    std::vector<int> numbers;
    std::error_code ec;
    for (fs::directory_iterator it(folder, ec); !ec && it != fs::directory_iterator();
         it.increment(ec)) {
        const std::string name = it->path().filename().string();
        if (name.size() <= pattern.prefix.size() + pattern.suffix.size() ||
            !name.starts_with(pattern.prefix) || !name.ends_with(pattern.suffix))
            continue;
        const std::optional<int> number = numberOf(
            std::string_view(name).substr(
                pattern.prefix.size(), name.size() - pattern.prefix.size() - pattern.suffix.size()),
            pattern.digits);
        if (!number) continue;
        io_detail::requireFrameFile(*it);
        numbers.push_back(*number);
    }
    if (ec) throw Error(ErrorCode::IoFailure, folder.string() + ": cannot list: " + ec.message());
    return numbers;
}

void requireFolder(const fs::path& folder, const fs::path& input) {
    std::error_code ec;
    const auto status = fs::status(folder.empty() ? fs::path(".") : folder, ec);
    if (!fs::exists(status))
        throw Error(ErrorCode::MissingFile, folder == input
                                                ? folder.string() + ": no such folder"
                                                : fmt::format("{}: no such folder (in {})",
                                                              folder.string(), input.string()));
    if (!fs::is_directory(status))
        throw Error(ErrorCode::MissingFile, folder.string() + ": not a folder");
}

// The padding widths a file's number fits, as numberOf reads it: zero-padded "0001" only 4,
// unpadded "12" 1 or 2.
struct Widths {
    int narrowest = 1;
    int widest = 1;
};
Widths widthsOf(std::string_view digits) {
    const int size = int(digits.size());
    return {digits.size() > 1 && digits[0] == '0' ? size : 1, size};
}

// "0001.exr" (one file), "0001.exr, 0002.exr", or "4 files, 0001.exr to 0004.exr".
std::string describeFiles(std::vector<std::string> names) {
    std::sort(names.begin(), names.end(), [](const std::string& a, const std::string& b) {
        return a.size() != b.size() ? a.size() < b.size() : a < b;  // numeric order
    });
    if (names.size() <= 2) {
        std::string out;
        for (const std::string& name : names) out += (out.empty() ? "" : ", ") + name;
        return out;
    }
    return fmt::format("{} files, {} to {}", names.size(), names.front(), names.back());
}

// The numbers of one name ("", "frame_") as its files write them ("0001", "5").
using NumbersByPrefix = std::map<std::string, std::vector<std::string>>;

// A folder whose files of one name fit no single padding (0001..0004.exr and 5.exr): each
// numbering with its files, in an error asking for a pattern. Reading either one would silently
// skip the other's files.
Error severalNumberings(const fs::path& folder, const std::string& prefix,
                        std::vector<std::string> numbers, std::string_view extension) {
    std::vector<std::pair<std::string, std::vector<std::string>>> numberings;  // pattern, files
    while (!numbers.empty()) {
        int width = 1;
        for (const std::string& digits : numbers)
            width = std::max(width, widthsOf(digits).narrowest);
        std::vector<std::string> files;
        std::erase_if(numbers, [&](const std::string& digits) {
            if (widthsOf(digits).widest < width) return false;
            files.push_back(prefix + digits + std::string(extension));
            return true;
        });
        numberings.emplace_back(
            prefix + std::string(std::size_t(width), '#') + std::string(extension),
            std::move(files));
    }
    std::string listed;
    for (const auto& [pattern, files] : numberings)
        listed +=
            fmt::format("{}{}: {}", listed.empty() ? "" : "; ", pattern, describeFiles(files));
    const auto largest = std::max_element(
        numberings.begin(), numberings.end(),
        [](const auto& a, const auto& b) { return a.second.size() < b.second.size(); });
    return Error(ErrorCode::InvalidInput,
                 fmt::format("{}: numbered files of several numberings ({}): name one with a "
                             "pattern, e.g. {}, or move the other files away",
                             folder.string(), listed, (folder / largest->first).string()));
}

// In a folder without a pattern: the one name ("", "frame_") its numbered files share, padded as
// the shortest number is ("0001": 4 digits). Every file of that name must fit that padding.
Pattern patternOfFolder(const fs::path& folder, std::string_view extension) {
    NumbersByPrefix numbersByPrefix;
    std::error_code ec;
    for (fs::directory_iterator it(folder, ec); !ec && it != fs::directory_iterator();
         it.increment(ec)) {
        const std::string name = it->path().filename().string();
        if (!name.ends_with(extension) || name.size() == extension.size()) continue;
        const std::string stem = name.substr(0, name.size() - extension.size());
        std::size_t digitsStart = stem.size();
        while (digitsStart > 0 && isDigit(stem[digitsStart - 1])) --digitsStart;
        if (digitsStart == stem.size()) continue;
        numbersByPrefix[stem.substr(0, digitsStart)].push_back(stem.substr(digitsStart));
    }
    if (ec) throw Error(ErrorCode::IoFailure, folder.string() + ": cannot list: " + ec.message());
    if (numbersByPrefix.empty())
        throw Error(ErrorCode::MissingFile,
                    fmt::format("{}: no frames (no numbered {} files such as 0001{})",
                                folder.string(), extension, extension));
    const auto shortest = [](const std::vector<std::string>& numbers) {
        std::size_t digits = numbers.front().size();
        for (const std::string& number : numbers) digits = std::min(digits, number.size());
        return digits;
    };
    if (numbersByPrefix.size() > 1) {
        std::string names;
        for (const auto& [prefix, numbers] : numbersByPrefix)
            names += fmt::format("{}{}{}{}", names.empty() ? "" : ", ", prefix,
                                 std::string(shortest(numbers), '#'), extension);
        throw Error(ErrorCode::InvalidInput,
                    fmt::format("{}: numbered files of several names ({}): name one with a "
                                "pattern, e.g. {}",
                                folder.string(), names,
                                (folder /
                                 (numbersByPrefix.begin()->first + "####" + std::string(extension)))
                                    .string()));
    }
    const auto& [prefix, numbers] = *numbersByPrefix.begin();
    // The widths every number fits: from the widest zero-padded one to the shortest one.
    Widths fit{1, int(shortest(numbers))};
    for (const std::string& digits : numbers)
        fit.narrowest = std::max(fit.narrowest, widthsOf(digits).narrowest);
    if (fit.narrowest > fit.widest) throw severalNumberings(folder, prefix, numbers, extension);
    Pattern pattern;
    pattern.prefix = prefix;
    pattern.digits = fit.widest;
    pattern.suffix = std::string(extension);
    return pattern;
}

// ---- channels and passes ----

struct ChannelName {
    std::string layer, pass, component;
};

// "ViewLayer.Denoising Albedo.R" -> (ViewLayer, Denoising Albedo, R). Split from the right: pass
// names hold no '.', a view layer's name may.
std::optional<ChannelName> splitChannel(const std::string& name) {
    const std::size_t last = name.rfind('.');
    if (last == std::string::npos || last == 0 || last + 1 == name.size()) return std::nullopt;
    const std::size_t middle = name.rfind('.', last - 1);
    if (middle == std::string::npos || middle == 0 || middle + 1 == last) return std::nullopt;
    return ChannelName{name.substr(0, middle), name.substr(middle + 1, last - middle - 1),
                       name.substr(last + 1)};
}

// A view layer's passes and each one's components, in the order the file lists them.
struct ViewLayer {
    std::string name;
    std::vector<std::pair<std::string, std::string>> passes;  // (pass, components)

    // The components of the pass present in the file; nullopt when it has no channel of it.
    std::optional<std::string> componentsOf(const std::string& pass) const {
        for (const auto& entry : passes)
            if (entry.first == pass) return entry.second;
        return std::nullopt;
    }
    // Those of `components` the pass lacks ("" when it has them all, or has no channel of it).
    std::string missingOf(const std::string& pass, std::string_view components) const {
        const std::optional<std::string> present = componentsOf(pass);
        std::string missing;
        if (present)
            for (char c : components)
                if (present->find(c) == std::string::npos) missing += c;
        return missing;
    }
    bool has(const std::string& pass, std::string_view components) const {
        return componentsOf(pass) && missingOf(pass, components).empty();
    }
    // Some channels of the pass but not all: a damaged file, never a pass that was not enabled.
    bool hasPartly(const std::string& pass, std::string_view components) const {
        return componentsOf(pass) && !missingOf(pass, components).empty();
    }
    std::string passList() const {
        std::string out;
        for (const auto& entry : passes) out += (out.empty() ? "" : ", ") + entry.first;
        return out;
    }
};

std::vector<ViewLayer> viewLayersOf(const std::vector<std::string>& channels) {
    std::vector<ViewLayer> layers;
    for (const std::string& channel : channels) {
        const std::optional<ChannelName> name = splitChannel(channel);
        if (!name || name->component.size() != 1) continue;
        auto layer = std::find_if(layers.begin(), layers.end(),
                                  [&](const ViewLayer& l) { return l.name == name->layer; });
        if (layer == layers.end()) layer = layers.insert(layers.end(), {name->layer, {}});
        auto pass = std::find_if(layer->passes.begin(), layer->passes.end(),
                                 [&](const auto& p) { return p.first == name->pass; });
        if (pass == layer->passes.end())
            pass = layer->passes.insert(layer->passes.end(), {name->pass, {}});
        pass->second += name->component;
    }
    return layers;
}

std::string layerList(const std::vector<ViewLayer>& layers) {
    std::string out;
    for (const ViewLayer& layer : layers) out += (out.empty() ? "'" : ", '") + layer.name + "'";
    return out;
}

// What rtdenoise reads of a pass, and where Blender's UI and Python enable it.
struct PassInfo {
    const char* name;
    const char* components;
    const char* howToEnable;
};
const PassInfo kNoisyImage{"Noisy Image", "RGB",
                           "View Layer Properties > Passes > Data > Denoising Data with "
                           "denoising on"};
const PassInfo kCombined{"Combined", "RGB",
                         "View Layer Properties > Passes > Data > Combined "
                         "(view_layer.use_pass_combined = True)"};
const PassInfo kDepth{"Depth", "Z",
                      "View Layer Properties > Passes > Data > Z (view_layer.use_pass_z = True)"};
const PassInfo kNormal{"Normal", "XYZ",
                       "View Layer Properties > Passes > Data > Normal "
                       "(view_layer.use_pass_normal = True)"};
const PassInfo kPosition{"Position", "XYZ",
                         "View Layer Properties > Passes > Data > Position "
                         "(view_layer.use_pass_position = True)"};
const PassInfo kObjectIndex{"IndexOB", "X",
                            "View Layer Properties > Passes > Data > Indexes > Object Index "
                            "(view_layer.use_pass_object_index = True) and give objects a "
                            "pass_index"};
const PassInfo kAlbedo{"Denoising Albedo", "RGB",
                       "View Layer Properties > Passes > Data > Denoising Data "
                       "(view_layer.cycles.denoising_store_passes = True)"};
const PassInfo kVector{"Vector", "XY",
                       "View Layer Properties > Passes > Data > Vector "
                       "(view_layer.use_pass_vector = True) with motion blur off "
                       "(scene.render.use_motion_blur = False: with it on Cycles writes zeros)"};

ChannelChoices channelsOf(const std::string& layer, const PassInfo& pass) {
    ChannelChoices choices;
    for (const char* c = pass.components; *c; ++c)
        choices.push_back({layer + "." + pass.name + "." + *c});
    return choices;
}

// A pass of which the layer has some channels but not all: the channels missing, named.
Error incompletePass(const fs::path& file, const ViewLayer& layer, const PassInfo& pass) {
    const std::string missing = layer.missingOf(pass.name, pass.components);
    std::string names;
    for (std::size_t i = 0; i < missing.size(); ++i)
        names += fmt::format("{}'{}.{}.{}'",
                             i == 0                    ? ""
                             : i + 1 == missing.size() ? " and "
                                                       : ", ",
                             layer.name, pass.name, missing[i]);
    std::string present;
    for (char c : layer.componentsOf(pass.name).value_or(""))
        present += fmt::format("{}{}", present.empty() ? "" : ", ", c);
    return Error(ErrorCode::InvalidInput,
                 fmt::format("{}: no channel{} {} (the {} pass of view layer '{}' has only {}): "
                             "Blender writes every channel of a pass, so the file was edited or "
                             "damaged; render or save this frame again",
                             file.string(), missing.size() > 1 ? "s" : "", names, pass.name,
                             layer.name, present));
}

Error missingPass(const fs::path& file, const ViewLayer& layer, const PassInfo& pass) {
    if (layer.hasPartly(pass.name, pass.components)) return incompletePass(file, layer, pass);
    return Error(ErrorCode::InvalidInput,
                 fmt::format("{}: no {} pass in view layer '{}' (no channel '{}.{}.{}'; it has: "
                             "{}): enable {}",
                             file.string(), pass.name, layer.name, layer.name, pass.name,
                             pass.components[0], layer.passList(), pass.howToEnable));
}

// The colour pass a layer is read with: Noisy Image when it has any of it (Combined may be
// denoised), else Combined.
const PassInfo& colourPassOf(const ViewLayer& layer) {
    return layer.componentsOf(kNoisyImage.name) ? kNoisyImage : kCombined;
}

// The required passes (or, of a pass present in part, the channels) a layer lacks, e.g.
// {"Depth", "Normal.Z"}; empty for a layer that can make frames.
std::vector<std::string> requiredPassesLacking(const ViewLayer& layer) {
    std::vector<std::string> lacking;
    for (const PassInfo* pass : {&colourPassOf(layer), &kDepth, &kNormal, &kPosition}) {
        if (!layer.componentsOf(pass->name))
            lacking.push_back(pass == &kCombined ? "Combined (or Noisy Image)" : pass->name);
        for (char c : layer.missingOf(pass->name, pass->components))
            lacking.push_back(fmt::format("{}.{}", pass->name, c));
    }
    return lacking;
}

std::vector<ViewLayer> requireLayers(const fs::path& file, const ExrContents& contents) {
    std::vector<ViewLayer> layers = viewLayersOf(contents.channels);
    if (layers.empty()) {
        std::string names;
        for (const std::string& c : contents.channels) names += (names.empty() ? "" : ", ") + c;
        throw Error(ErrorCode::InvalidInput,
                    fmt::format("{}: not a Blender multilayer EXR (channels {}; a multilayer "
                                "file names them <view layer>.<pass>.<component>, e.g. "
                                "ViewLayer.Combined.R): save renders as OpenEXR MultiLayer",
                                file.string(), names.empty() ? "none" : names));
    }
    return layers;
}

const ViewLayer& findLayer(const fs::path& file, const std::vector<ViewLayer>& layers,
                           const std::string& name) {
    for (const ViewLayer& layer : layers)
        if (layer.name == name) return layer;
    throw Error(ErrorCode::InvalidInput, fmt::format("{}: no view layer '{}' (it has {})",
                                                     file.string(), name, layerList(layers)));
}

}  // namespace

// ---- numbered files ----

fs::path NumberedFiles::file(int index) const {
    return folder / fmt::format("{}{:0{}d}{}", prefix, first + index, digits, suffix);
}

std::string NumberedFiles::pattern() const {
    return (folder / (prefix + std::string(std::size_t(digits), '#') + suffix)).string();
}

bool isFramePattern(const fs::path& path) {
    const std::string name = path.filename().string();
    return name.find('#') != std::string::npos || name.find('%') != std::string::npos;
}

NumberedFiles findNumberedFiles(const fs::path& input, std::string_view extension) {
    NumberedFiles files;
    std::optional<Pattern> pattern = parsePattern(input.filename().string(), input);
    if (pattern) {
        files.folder = input.parent_path();
        requireFolder(files.folder, input);
    } else {
        files.folder = input;
        requireFolder(files.folder, input);
        pattern = patternOfFolder(files.folder, extension);
    }
    std::vector<int> numbers = numbersIn(files.folder.empty() ? "." : files.folder, *pattern);
    files.prefix = pattern->prefix;
    files.suffix = pattern->suffix;
    files.digits = pattern->digits;
    if (numbers.empty())
        throw Error(ErrorCode::MissingFile, fmt::format("{}: no frames (no file matches {})",
                                                        input.string(), files.pattern()));
    std::sort(numbers.begin(), numbers.end());
    files.first = numbers.front();
    files.count = int(numbers.size());
    // Numbers are distinct (one canonical name each), so they are contiguous exactly when the
    // last is first + count - 1.
    if (numbers.back() - numbers.front() + 1 != files.count) {
        int missing = 0;
        while (numbers[std::size_t(missing)] == files.first + missing) ++missing;
        throw Error(ErrorCode::InvalidInput,
                    fmt::format("{} is missing: frames {} exist (frame numbers must be "
                                "contiguous)",
                                files.file(missing).string(), io_detail::describeRanges(numbers)));
    }
    return files;
}

// ---- BlenderSequence ----

BlenderSequence::BlenderSequence(const fs::path& input, std::string viewLayer)
    : files_(findNumberedFiles(input)), layer_(std::move(viewLayer)) {
    const fs::path first = files_.file(0);
    const ExrContents contents = readExrContents(first);
    const std::vector<ViewLayer> layers = requireLayers(first, contents);
    if (layer_.empty()) {
        // The first layer that can make frames. When several layers are there and none can, what
        // each one lacks: the user enables it in the layer meant, or names that layer.
        const auto complete = std::find_if(layers.begin(), layers.end(), [](const ViewLayer& l) {
            return requiredPassesLacking(l).empty();
        });
        if (complete == layers.end() && layers.size() > 1) {
            std::string lacking;
            for (const ViewLayer& l : layers) {
                lacking += fmt::format("{}'{}' lacks ", lacking.empty() ? "" : "; ", l.name);
                const std::vector<std::string> passes = requiredPassesLacking(l);
                for (std::size_t i = 0; i < passes.size(); ++i)
                    lacking += (i == 0 ? "" : ", ") + passes[i];
            }
            throw Error(ErrorCode::InvalidInput,
                        fmt::format("{}: no view layer has every pass rtdenoise needs (Noisy "
                                    "Image or Combined, Depth, Normal, Position): {}; enable them "
                                    "in the layer to read (docs/inputs.md) and name it with "
                                    "--view-layer NAME unless it is the first",
                                    first.string(), lacking));
        }
        layer_ = complete != layers.end() ? complete->name : layers.front().name;
    }
    const ViewLayer& layer = findLayer(first, layers, layer_);
    const PassInfo& colour = colourPassOf(layer);
    for (const PassInfo* pass : {&colour, &kDepth, &kNormal, &kPosition})
        if (!layer.has(pass->name, pass->components)) throw missingPass(first, layer, *pass);
    colourPass_ = colour.name;
    // An optional pass present in part is a damaged file, refused as a required one is (read
    // without it, its missing channel would pass for a pass that was never enabled).
    for (const PassInfo* pass : {&kObjectIndex, &kAlbedo, &kVector})
        if (layer.hasPartly(pass->name, pass->components))
            throw incompletePass(first, layer, *pass);
    hasObjectIndex_ = layer.has(kObjectIndex.name, kObjectIndex.components);
    hasAlbedo_ = layer.has(kAlbedo.name, kAlbedo.components);
    hasMotion_ = layer.has(kVector.name, kVector.components);
    if (!hasObjectIndex_)
        warnings_.push_back(fmt::format(
            "{}: no IndexOB pass: every object pixel gets ID 0, so objects are kept apart by "
            "depth and normal alone (enable {})",
            first.string(), kObjectIndex.howToEnable));
    if (!hasAlbedo_)
        warnings_.push_back(fmt::format(
            "{}: no Denoising Albedo pass: colour is filtered without albedo demodulation, "
            "textures blur (enable {})",
            first.string(), kAlbedo.howToEnable));
    // With motion blur on Cycles still writes the Vector pass, all zeros. The second frame is
    // looked at: the first one's vectors point before the animation, often legitimately zero.
    if (hasMotion_ && files_.count > 1) {
        const fs::path second = files_.file(1);
        const std::vector<ViewLayer> secondLayers = viewLayersOf(readExrContents(second).channels);
        // A second frame without the pass is checkFrames' error to report, not this one's.
        if (std::any_of(secondLayers.begin(), secondLayers.end(), [this](const ViewLayer& l) {
                return l.name == layer_ && l.has(kVector.name, kVector.components);
            })) {
            const Image vectors = readExr(second, channelsOf(layer_, kVector));
            if (std::all_of(vectors.pixels.begin(), vectors.pixels.end(),
                            [](float v) { return v == 0.0f; }))
                warnings_.push_back(fmt::format(
                    "{}: the Vector pass is zero at every pixel, as Cycles writes it with motion "
                    "blur on: history then ignores all motion (render with "
                    "scene.render.use_motion_blur = False; a shot where nothing moves is fine)",
                    second.string()));
        }
    }
}

std::string BlenderSequence::backProjectionProblem() const {
    if (hasMotion_) return {};
    return fmt::format(
        "{}: no Vector pass in view layer '{}': without motion vectors (and Blender files have "
        "no matrices) frames cannot be projected into the previous one; enable {}, or use a "
        "spatial method (--method jbf or atrous)",
        files_.file(0).string(), layer_, kVector.howToEnable);
}

std::string BlenderSequence::describe() const {
    return fmt::format("{} (Blender multilayer EXR, frames {}..{}, view layer '{}', {} pass)",
                       files_.pattern(), files_.first, files_.first + files_.count - 1, layer_,
                       colourPass_);
}

std::vector<ChannelChoices> BlenderSequence::channelsRead() const {
    std::vector<ChannelChoices> channels{
        channelsOf(layer_, colourPass_ == kNoisyImage.name ? kNoisyImage : kCombined),
        channelsOf(layer_, kDepth), channelsOf(layer_, kNormal), channelsOf(layer_, kPosition)};
    if (hasObjectIndex_) channels.push_back(channelsOf(layer_, kObjectIndex));
    if (hasAlbedo_) channels.push_back(channelsOf(layer_, kAlbedo));
    if (hasMotion_) channels.push_back(channelsOf(layer_, kVector));
    return channels;
}

void BlenderSequence::requirePasses(const fs::path& file, const ExrContents& contents) const {
    const std::vector<ViewLayer> layers = requireLayers(file, contents);
    const ViewLayer& layer = findLayer(file, layers, layer_);
    const PassInfo& colour = colourPass_ == kNoisyImage.name ? kNoisyImage : kCombined;
    for (const PassInfo* pass : {&colour, &kDepth, &kNormal, &kPosition})
        if (!layer.has(pass->name, pass->components)) throw missingPass(file, layer, *pass);
    // Every frame is read with the passes of the first: a pass one frame lacks and another has,
    // first frame included, would change what the denoiser gets in the middle of the sequence
    // (or, dropped from every frame, degrade all of them).
    const fs::path first = files_.file(0);
    const auto firstLacks = [&](const PassInfo& pass) {
        return Error(ErrorCode::InvalidInput,
                     fmt::format("{}: no {} pass in view layer '{}', which {} has: every frame "
                                 "needs the same passes (render every frame with it)",
                                 first.string(), pass.name, layer_, file.string()));
    };
    if (&colour == &kCombined && layer.componentsOf(kNoisyImage.name))
        throw firstLacks(kNoisyImage);
    const std::pair<bool, const PassInfo*> optional[] = {
        {hasObjectIndex_, &kObjectIndex}, {hasAlbedo_, &kAlbedo}, {hasMotion_, &kVector}};
    for (const auto& [read, pass] : optional) {
        if (layer.hasPartly(pass->name, pass->components)) throw incompletePass(file, layer, *pass);
        const bool present = layer.has(pass->name, pass->components);
        if (read && !present)
            throw Error(ErrorCode::InvalidInput,
                        fmt::format("{}: no {} pass in view layer '{}', which {} has: every "
                                    "frame needs the same passes",
                                    file.string(), pass->name, layer_, first.string()));
        if (!read && present) throw firstLacks(*pass);
    }
}

std::vector<ExrSize> BlenderSequence::checkFrames(int count, int firstIndex) const {
    if (count < 0 || firstIndex < 0 || firstIndex + count > files_.count)
        throw Error(ErrorCode::InvalidArgument,
                    fmt::format("{}: cannot check {} frames from frame {}, it has {}",
                                files_.pattern(), count, firstIndex, files_.count));
    std::vector<ExrSize> sizes;
    for (int index = firstIndex; index < firstIndex + count; ++index) {
        const fs::path file = files_.file(index);
        const ExrContents contents = readExrContents(file);
        requirePasses(file, contents);
        sizes.push_back(contents.size);
    }
    return sizes;
}

Frame BlenderSequence::readFrame(int index) const {
    if (index < 0 || index >= files_.count)
        throw Error(ErrorCode::InvalidArgument,
                    fmt::format("{}: frame {} is outside 0..{}", files_.pattern(), index,
                                files_.count - 1));
    const fs::path file = files_.file(index);
    requirePasses(file, readExrContents(file));  // a pass-level message, not a channel's
    std::vector<Image> images = readExrImages(file, channelsRead());
    Frame frame;
    std::size_t next = 0;
    frame.beauty = std::move(images[next++]);
    frame.depth = std::move(images[next++]);
    frame.normal = std::move(images[next++]);
    frame.position = std::move(images[next++]);
    std::optional<Image> objectIndex;
    if (hasObjectIndex_) objectIndex = std::move(images[next++]);
    if (hasAlbedo_) frame.albedo = std::move(images[next++]);
    if (hasMotion_) frame.motion = std::move(images[next++]);
    frame.depthKind = DepthKind::ViewZ;

    const int width = frame.beauty.width;
    frame.objectId.assign(frame.beauty.pixelCount(), -1);
    int largestId = -1;
    for (std::size_t i = 0; i < frame.beauty.pixelCount(); ++i) {
        float& depth = frame.depth.pixels[i];
        // Cycles' miss value. A NaN is no miss but a broken pass: it goes to the denoiser, which
        // reads the pixel as background too, and counts and reports it (FrameStats).
        if (depth >= kBackgroundDepth) {
            depth = 0.0f;
            for (int c = 0; c < 3; ++c) {
                frame.normal.pixels[i * 3 + c] = 0.0f;
                frame.position.pixels[i * 3 + c] = 0.0f;
            }
            continue;
        }
        int id = 0;
        if (objectIndex) {
            const float value = objectIndex->pixels[i];
            const float rounded = std::round(value);
            if (!std::isfinite(value) || std::abs(value - rounded) > kIdTolerance ||
                rounded < 0.0f || rounded > float(kMaxPassIndex))
                throw Error(ErrorCode::InvalidInput,
                            fmt::format("{}: pixel ({}, {}) holds IndexOB {}, expected an "
                                        "object pass index, an integer in 0..{}",
                                        file.string(), i % std::size_t(width),
                                        i / std::size_t(width), value, kMaxPassIndex));
            id = int(rounded);
        }
        frame.objectId[i] = id;
        largestId = std::max(largestId, id);
    }
    frame.objectCount = largestId + 1;
    if (frame.motion) {
        // Blender's raster y points up; the Frame's rows run top to bottom.
        for (std::size_t i = 0; i < frame.motion->pixelCount(); ++i)
            frame.motion->pixels[i * 2 + 1] = -frame.motion->pixels[i * 2 + 1];
    }
    return frame;
}

// ---- opening any layout ----

std::unique_ptr<FrameSource> openFrameSource(const fs::path& input,
                                             const FrameSourceOptions& options) {
    if (isFramePattern(input)) return std::make_unique<BlenderSequence>(input, options.viewLayer);
    std::error_code ec;
    if (fs::is_directory(input, ec)) {
        bool course = false, numbered = false;
        for (fs::directory_iterator it(input, ec); !ec && it != fs::directory_iterator();
             it.increment(ec)) {
            const std::string name = it->path().filename().string();
            course = course || frameIndexOf(name, "beauty") >= 0;
            numbered = numbered || (name.ends_with(".exr") && name.size() > 4 &&
                                    isDigit(name[name.size() - 5]));
        }
        if (!course && numbered) return std::make_unique<BlenderSequence>(input, options.viewLayer);
        if (!course && !ec)
            throw Error(ErrorCode::MissingFile,
                        fmt::format("{}: no frames: neither the course layout (beauty_<i>.exr, "
                                    "...) nor numbered multilayer EXRs (0001.exr, ... as "
                                    "Blender writes them)",
                                    input.string()));
    } else if (fs::is_regular_file(input, ec)) {
        throw Error(ErrorCode::InvalidArgument,
                    fmt::format("{}: is a file; name its folder or a pattern such as {}",
                                input.string(), (input.parent_path() / "####.exr").string()));
    }
    if (!options.viewLayer.empty())
        throw Error(ErrorCode::InvalidArgument,
                    fmt::format("{}: a view layer ('{}') is for Blender multilayer EXRs; this is "
                                "a course-layout folder",
                                input.string(), options.viewLayer));
    return std::make_unique<Sequence>(input);
}

ChannelChoices colourChannelsOf(const fs::path& file, const std::string& viewLayer) {
    const ExrContents contents = readExrContents(file);
    const auto has = [&](const std::string& name) {
        return std::find(contents.channels.begin(), contents.channels.end(), name) !=
               contents.channels.end();
    };
    if (viewLayer.empty() && has("R") && has("G") && has("B")) return {{"R"}, {"G"}, {"B"}};
    const std::vector<ViewLayer> layers = viewLayersOf(contents.channels);
    for (const ViewLayer& layer : layers)
        if ((viewLayer.empty() || layer.name == viewLayer) &&
            layer.has(kCombined.name, kCombined.components))
            return channelsOf(layer.name, kCombined);
    std::string names;
    for (const std::string& c : contents.channels) names += (names.empty() ? "" : ", ") + c;
    throw Error(
        ErrorCode::InvalidInput,
        fmt::format("{}: no colour: neither R, G, B nor a{} Combined pass (has: {})", file.string(),
                    viewLayer.empty() ? "" : " view layer '" + viewLayer + "' with a",
                    names.empty() ? "no channels" : names));
}

// ---- writing ----

void writeBlenderExr(const fs::path& file, const Frame& frame, const Image* motionToNext,
                     const std::string& viewLayer) {
    const int width = frame.width(), height = frame.height();
    const std::size_t pixels = frame.beauty.pixelCount();
    const auto sameSize = [&](const Image& image, int channels) {
        return image.width == width && image.height == height && image.channels == channels &&
               image.pixels.size() == pixels * std::size_t(channels);
    };
    if (frame.depthKind != DepthKind::ViewZ)
        throw Error(ErrorCode::InvalidArgument,
                    file.string() +
                        ": Cycles' Depth is view depth; this frame holds ray "
                        "distances");
    if (width <= 0 || height <= 0 || !sameSize(frame.beauty, 3) || !sameSize(frame.normal, 3) ||
        !sameSize(frame.position, 3) || !sameSize(frame.depth, 1) ||
        frame.objectId.size() != pixels || (frame.albedo && !sameSize(*frame.albedo, 3)) ||
        (frame.motion && frame.motion->channels < 2) ||
        (frame.motion && !sameSize(*frame.motion, frame.motion->channels)) ||
        (motionToNext &&
         (motionToNext->channels < 2 || !sameSize(*motionToNext, motionToNext->channels))))
        throw Error(ErrorCode::InvalidArgument,
                    file.string() + ": an empty frame, or buffers of different sizes");

    Image combined(width, height, 4, 1.0f);
    Image depth = frame.depth, normal = frame.normal, position = frame.position;
    Image objectIndex(width, height, 1);
    Image vector(width, height, 4);
    for (std::size_t i = 0; i < pixels; ++i) {
        for (int c = 0; c < 3; ++c) combined.pixels[i * 4 + c] = frame.beauty.pixels[i * 3 + c];
        if (frame.objectId[i] < 0) {  // Cycles' background: the miss depth, zero data passes
            depth.pixels[i] = kCyclesMissDepth;
            for (int c = 0; c < 3; ++c) normal.pixels[i * 3 + c] = position.pixels[i * 3 + c] = 0;
            continue;
        }
        objectIndex.pixels[i] = float(frame.objectId[i]);
        // Blender's raster y points up; both of its vectors point back in time.
        if (frame.motion) {
            const int c = frame.motion->channels;
            vector.pixels[i * 4 + 0] = frame.motion->pixels[i * c + 0];
            vector.pixels[i * 4 + 1] = -frame.motion->pixels[i * c + 1];
        }
        if (motionToNext) {
            const int c = motionToNext->channels;
            vector.pixels[i * 4 + 2] = -motionToNext->pixels[i * c + 0];
            vector.pixels[i * 4 + 3] = motionToNext->pixels[i * c + 1];
        }
    }
    const auto names = [&viewLayer](const char* pass, std::string_view components) {
        std::vector<std::string> out;
        for (char c : components) out.push_back(viewLayer + "." + pass + "." + c);
        return out;
    };
    std::vector<ExrChannelGroup> groups{{&combined, names("Combined", "RGBA"), false},
                                        {&depth, names("Depth", "Z"), false},
                                        {&normal, names("Normal", "XYZ"), false},
                                        {&position, names("Position", "XYZ"), false},
                                        {&objectIndex, names("IndexOB", "X"), false}};
    if (frame.albedo) groups.push_back({&*frame.albedo, names("Denoising Albedo", "RGB"), false});
    if (frame.motion) groups.push_back({&vector, names("Vector", "XYZW"), false});
    writeExrChannels(file, groups);
}

}  // namespace rtd
