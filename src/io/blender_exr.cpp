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

// In a folder without a pattern: the one name ("", "frame_") its numbered files share, padded as
// the shortest number is ("0001": 4 digits).
Pattern patternOfFolder(const fs::path& folder, std::string_view extension) {
    std::map<std::string, int> shortestDigits;  // prefix -> digits of its shortest number
    std::error_code ec;
    for (fs::directory_iterator it(folder, ec); !ec && it != fs::directory_iterator();
         it.increment(ec)) {
        const std::string name = it->path().filename().string();
        if (!name.ends_with(extension) || name.size() == extension.size()) continue;
        const std::string stem = name.substr(0, name.size() - extension.size());
        std::size_t digitsStart = stem.size();
        while (digitsStart > 0 && isDigit(stem[digitsStart - 1])) --digitsStart;
        if (digitsStart == stem.size()) continue;
        const std::string prefix = stem.substr(0, digitsStart);
        const int digits = int(stem.size() - digitsStart);
        auto [entry, added] = shortestDigits.emplace(prefix, digits);
        if (!added) entry->second = std::min(entry->second, digits);
    }
    if (ec) throw Error(ErrorCode::IoFailure, folder.string() + ": cannot list: " + ec.message());
    if (shortestDigits.empty())
        throw Error(ErrorCode::MissingFile,
                    fmt::format("{}: no frames (no numbered {} files such as 0001{})",
                                folder.string(), extension, extension));
    if (shortestDigits.size() > 1) {
        std::string names;
        for (const auto& [prefix, digits] : shortestDigits)
            names += fmt::format("{}{}{}{}", names.empty() ? "" : ", ", prefix,
                                 std::string(std::size_t(digits), '#'), extension);
        throw Error(
            ErrorCode::InvalidInput,
            fmt::format("{}: numbered files of several names ({}): name one with a "
                        "pattern, e.g. {}",
                        folder.string(), names,
                        (folder / (shortestDigits.begin()->first + "####" + std::string(extension)))
                            .string()));
    }
    Pattern pattern;
    pattern.prefix = shortestDigits.begin()->first;
    pattern.digits = shortestDigits.begin()->second;
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

    bool has(const std::string& pass, std::string_view components) const {
        for (const auto& entry : passes)
            if (entry.first == pass) {
                const std::string& present = entry.second;
                return std::all_of(components.begin(), components.end(), [&present](char c) {
                    return present.find(c) != std::string::npos;
                });
            }
        return false;
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

Error missingPass(const fs::path& file, const ViewLayer& layer, const PassInfo& pass) {
    return Error(ErrorCode::InvalidInput,
                 fmt::format("{}: no {} pass in view layer '{}' (no channel '{}.{}.{}'; it has: "
                             "{}): enable {}",
                             file.string(), pass.name, layer.name, layer.name, pass.name,
                             pass.components[0], layer.passList(), pass.howToEnable));
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
    const auto hasColour = [](const ViewLayer& l) {
        return l.has(kNoisyImage.name, kNoisyImage.components) ||
               l.has(kCombined.name, kCombined.components);
    };
    if (layer_.empty()) {
        // The first layer that can make a frame; else the first one, for its error message.
        const auto usable = std::find_if(layers.begin(), layers.end(), [&](const ViewLayer& l) {
            return hasColour(l) && l.has(kDepth.name, kDepth.components);
        });
        layer_ = usable != layers.end() ? usable->name : layers.front().name;
    }
    const ViewLayer& layer = findLayer(first, layers, layer_);
    if (layer.has(kNoisyImage.name, kNoisyImage.components))
        colourPass_ = kNoisyImage.name;
    else if (layer.has(kCombined.name, kCombined.components))
        colourPass_ = kCombined.name;
    else
        throw missingPass(first, layer, kCombined);
    for (const PassInfo* pass : {&kDepth, &kNormal, &kPosition})
        if (!layer.has(pass->name, pass->components)) throw missingPass(first, layer, *pass);
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
    // An optional pass the first frame has is read from every frame: one frame without it would
    // change what the denoiser gets in the middle of the sequence.
    const std::pair<bool, const PassInfo*> optional[] = {
        {hasObjectIndex_, &kObjectIndex}, {hasAlbedo_, &kAlbedo}, {hasMotion_, &kVector}};
    for (const auto& [read, pass] : optional)
        if (read && !layer.has(pass->name, pass->components))
            throw Error(ErrorCode::InvalidInput,
                        fmt::format("{}: no {} pass in view layer '{}', which {} has: every "
                                    "frame needs the passes of the first",
                                    file.string(), pass->name, layer_, files_.file(0).string()));
}

std::vector<ExrSize> BlenderSequence::checkFrames(int count) const {
    if (count < 0 || count > files_.count)
        throw Error(ErrorCode::InvalidArgument, fmt::format("{}: cannot check {} frames, it has {}",
                                                            files_.pattern(), count, files_.count));
    std::vector<ExrSize> sizes;
    for (int index = 0; index < count; ++index) {
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
        if (!(depth < kBackgroundDepth)) {  // Cycles' miss value, or not a number
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
