// A folder in the course layout (shared/data/README.md): frame discovery and per-frame reading
// with the checks that make a bad file fail here, naming it, instead of deep in the denoiser.
#include <fmt/format.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>
#include <system_error>
#include <utility>
#include <vector>

#include "io/numbering.h"
#include "rtdenoise/error.h"
#include "rtdenoise/io.h"

namespace rtd {
namespace {

const std::vector<std::vector<std::string>> kRgb = {{"R"}, {"G"}, {"B"}};
// Scalar buffers: the course data uses Y; other producers write Z, R or a layer prefix.
const std::vector<std::vector<std::string>> kDepth = {{"Y", "Z", "R", "depth.Y", "depth.Z"}};
const std::vector<std::vector<std::string>> kId = {{"Y", "R", "ID.Y", "id.Y"}};
// History confidence: 1 channel; of an RGB file its R (a grey image holds it in every channel).
const std::vector<std::vector<std::string>> kConfidence = {
    {"Y", "R", "confidence.Y", "confidence.R", "A"}};
// The split signal's scalars (specular itself is RGB): 1 channel, Y or an RGB file's R.
const std::vector<std::vector<std::string>> kRoughness = {{"Y", "R", "roughness.Y", "roughness.R"}};
const std::vector<std::vector<std::string>> kHitDistance = {
    {"Y", "R", "hit_distance.Y", "hit_distance.R"}};

// IDs are stored as floats; anything further than this from an integer is a broken file.
constexpr float kIdTolerance = 1e-3f;

std::string sizeText(const Image& image) {
    return std::to_string(image.width) + "x" + std::to_string(image.height);
}

void requireSameSize(const std::filesystem::path& file, const Image& image,
                     const std::filesystem::path& beautyFile, const Image& beauty) {
    if (image.width != beauty.width || image.height != beauty.height) {
        throw Error(ErrorCode::InvalidInput, file.string() + ": " + sizeText(image) + ", but " +
                                                 beautyFile.string() + " is " + sizeText(beauty));
    }
}

// Whether anything has this name (a dangling link too): the optional albedo is then read, and
// a broken one is an error rather than silently skipped.
bool hasEntry(const std::filesystem::path& file) {
    std::error_code ec;
    return std::filesystem::exists(std::filesystem::symlink_status(file, ec));
}

}  // namespace

void io_detail::requireFrameFile(const std::filesystem::directory_entry& entry) {
    std::error_code ec;
    const std::filesystem::file_status status = entry.status(ec);
    if (std::filesystem::is_regular_file(status)) return;
    const std::string name = entry.path().string();
    if (!std::filesystem::exists(status))
        throw Error(ErrorCode::MissingFile, name + ": a link to a file that does not exist");
    throw Error(ErrorCode::InvalidInput,
                name + (std::filesystem::is_directory(status) ? ": is a folder, not a frame file"
                                                              : ": not a regular file"));
}

std::string io_detail::describeRanges(const std::vector<int>& sorted) {
    std::vector<std::string> ranges;
    for (std::size_t i = 0; i < sorted.size();) {
        std::size_t j = i;
        while (j + 1 < sorted.size() && sorted[j + 1] == sorted[j] + 1) ++j;
        ranges.push_back(i == j ? std::to_string(sorted[i])
                                : std::to_string(sorted[i]) + ".." + std::to_string(sorted[j]));
        i = j + 1;
    }
    constexpr std::size_t kShown = 8;
    std::string out;
    for (std::size_t i = 0; i < ranges.size() && i < kShown; ++i) {
        if (i > 0) out += (i + 1 == ranges.size()) ? " and " : ", ";
        out += ranges[i];
    }
    if (ranges.size() > kShown) out += ", ...";
    return out;
}

int frameIndexOf(const std::string& name, std::string_view stem, std::string_view extension) {
    if (name.size() <= stem.size() + 1 + extension.size() || !name.starts_with(stem) ||
        name[stem.size()] != '_' || !name.ends_with(extension))
        return -1;
    const std::string_view digits(name.data() + stem.size() + 1,
                                  name.size() - stem.size() - 1 - extension.size());
    if (digits.size() > 1 && digits[0] == '0') return -1;
    if (!std::all_of(digits.begin(), digits.end(), [](char c) { return c >= '0' && c <= '9'; }))
        return -1;
    int index = -1;
    const auto [end, ec] = std::from_chars(digits.data(), digits.data() + digits.size(), index);
    if (ec != std::errc() || end != digits.data() + digits.size()) return -1;
    return index;
}

int countFrames(const std::filesystem::path& folder, std::string_view stem,
                std::string_view extension) {
    std::error_code ec;
    const auto status = std::filesystem::status(folder, ec);
    if (!std::filesystem::exists(status))
        throw Error(ErrorCode::MissingFile, folder.string() + ": no such folder");
    if (!std::filesystem::is_directory(status))
        throw Error(ErrorCode::MissingFile, folder.string() + ": not a folder");

    std::vector<int> indices;
    std::filesystem::directory_iterator it(folder, ec);
    for (; !ec && it != std::filesystem::directory_iterator(); it.increment(ec)) {
        const int index = frameIndexOf(it->path().filename().string(), stem, extension);
        if (index < 0) continue;
        io_detail::requireFrameFile(*it);
        indices.push_back(index);
    }
    if (ec) throw Error(ErrorCode::IoFailure, folder.string() + ": cannot list: " + ec.message());
    if (indices.empty())
        throw Error(ErrorCode::MissingFile,
                    fmt::format("{}: no frames (no {}_<i>{} files, i = 0, 1, ...)", folder.string(),
                                stem, extension));
    std::sort(indices.begin(), indices.end());

    // Names are unique, so the indices are 0..N-1 exactly when the last one is N-1.
    const int count = static_cast<int>(indices.size());
    if (indices.back() != count - 1) {
        int missing = 0;
        while (missing < count && indices[missing] == missing) ++missing;
        throw Error(
            ErrorCode::InvalidInput,
            fmt::format("{} is missing: frames {} exist",
                        (folder / fmt::format("{}_{}{}", stem, missing, extension)).string(),
                        io_detail::describeRanges(indices)));
    }
    return count;
}

void removeNumberedFiles(const std::filesystem::path& folder, std::string_view stem,
                         std::string_view extension, int firstRemoved, int endRemoved) {
    std::error_code ec;
    std::vector<std::filesystem::path> stale;
    for (std::filesystem::directory_iterator it(folder, ec);
         !ec && it != std::filesystem::directory_iterator(); it.increment(ec)) {
        const int index = frameIndexOf(it->path().filename().string(), stem, extension);
        std::error_code typeError;
        if (index >= firstRemoved && index < endRemoved && it->is_regular_file(typeError))
            stale.push_back(it->path());
    }
    for (const std::filesystem::path& file : stale) {
        std::filesystem::remove(file, ec);
        if (ec)
            throw Error(
                ErrorCode::IoFailure,
                file.string() + ": cannot remove this output of an earlier run: " + ec.message());
    }
}

FrameChunk chunkOf(const FrameSource& source, int firstNumber, int endNumber, int warmup) {
    const int first = source.firstFrameNumber();
    const int end = first + source.frameCount();
    if (endNumber <= firstNumber)
        throw Error(ErrorCode::InvalidArgument,
                    fmt::format("frames {}:{} is empty: the end ({}) is the first frame after "
                                "the chunk, and must be greater than its start ({})",
                                firstNumber, endNumber, endNumber, firstNumber));
    if (firstNumber < first || endNumber > end)
        throw Error(ErrorCode::InvalidArgument,
                    fmt::format("frames {}..{} reach outside {}", firstNumber, endNumber - 1,
                                source.describe()));
    if (warmup < 0)
        throw Error(ErrorCode::InvalidArgument,
                    fmt::format("a warm-up of {} frames: it must be 0 or more", warmup));
    FrameChunk chunk;
    chunk.firstIndex = firstNumber - first;
    chunk.endIndex = endNumber - first;
    chunk.warmupIndex = std::max(0, chunk.firstIndex - warmup);
    return chunk;
}

Sequence::Sequence(std::filesystem::path folder)
    : folder_(std::move(folder)), frameCount_(countFrames(folder_, "beauty")) {}

Frame Sequence::readFrame(int index) const {
    if (index < 0 || index >= frameCount_) {
        throw Error(ErrorCode::InvalidArgument, folder_.string() + ": frame " +
                                                    std::to_string(index) + " is outside 0.." +
                                                    std::to_string(frameCount_ - 1));
    }
    std::string suffix = "_";
    suffix += std::to_string(index);
    const auto path = [&](const char* stem, const char* extension) {
        return folder_ / (stem + suffix + extension);
    };

    Frame frame;
    const std::filesystem::path matrixFile = path("matrix", ".mat");
    MatrixFile matrices = readMatrixFile(matrixFile);
    frame.objectToWorld = std::move(matrices.objectToWorld);
    frame.worldToCamera = matrices.worldToCamera;
    frame.worldToScreen = matrices.worldToScreen;

    const std::filesystem::path beautyFile = path("beauty", ".exr");
    frame.beauty = readExr(beautyFile, kRgb);
    const auto readChecked = [&](const std::filesystem::path& file,
                                 const std::vector<std::vector<std::string>>& channels) {
        Image image = readExr(file, channels);
        requireSameSize(file, image, beautyFile, frame.beauty);
        return image;
    };
    frame.normal = readChecked(path("normal", ".exr"), kRgb);
    frame.position = readChecked(path("position", ".exr"), kRgb);
    frame.depth = readChecked(path("depth", ".exr"), kDepth);

    const std::filesystem::path idFile = path("ID", ".exr");
    const Image ids = readChecked(idFile, kId);
    const auto objectCount = static_cast<std::int64_t>(frame.objectToWorld.size());
    frame.objectId.resize(ids.pixelCount());
    for (std::size_t i = 0; i < ids.pixelCount(); ++i) {
        const float value = ids.pixels[i];
        const float rounded = std::round(value);
        const bool integral = std::isfinite(value) && std::abs(value - rounded) <= kIdTolerance;
        const auto id = integral ? static_cast<std::int64_t>(rounded) : std::int64_t(-2);
        if (id != -1 && (id < 0 || id >= objectCount)) {
            const std::string expected =
                objectCount > 0 ? "-1 or an integer in 0.." + std::to_string(objectCount - 1)
                                : std::string("-1");
            throw Error(ErrorCode::InvalidInput,
                        fmt::format("{}: pixel ({}, {}) holds object ID {}, expected {} (K = {} "
                                    "in {})",
                                    idFile.string(), i % ids.width, i / ids.width, value, expected,
                                    objectCount, matrixFile.filename().string()));
        }
        frame.objectId[i] = static_cast<std::int32_t>(id);
    }

    const std::filesystem::path albedoFile = path("albedo", ".exr");
    if (hasEntry(albedoFile)) frame.albedo = readChecked(albedoFile, kRgb);
    const std::filesystem::path confidenceFile = path("confidence", ".exr");
    if (hasEntry(confidenceFile)) frame.confidence = readChecked(confidenceFile, kConfidence);
    // The split signal (the Denoiser checks that roughness and hit distance come with specular).
    const std::filesystem::path specularFile = path("specular", ".exr");
    if (hasEntry(specularFile)) frame.specular = readChecked(specularFile, kRgb);
    const std::filesystem::path roughnessFile = path("roughness", ".exr");
    if (hasEntry(roughnessFile)) frame.roughness = readChecked(roughnessFile, kRoughness);
    const std::filesystem::path hitDistanceFile = path("hit_distance", ".exr");
    if (hasEntry(hitDistanceFile)) frame.hitDistance = readChecked(hitDistanceFile, kHitDistance);
    return frame;
}

std::string Sequence::describe() const {
    return fmt::format("{} (course layout, frames 0..{})", folder_.string(), frameCount_ - 1);
}

std::filesystem::path Sequence::frameFile(int index) const {
    return folder_ / fmt::format("beauty_{}.exr", index);
}

std::vector<ExrSize> Sequence::checkFrames(int count, int firstIndex) const {
    if (count < 0 || firstIndex < 0 || firstIndex + count > frameCount_) {
        throw Error(ErrorCode::InvalidArgument,
                    fmt::format("{}: cannot check {} frames from frame {}, it has {}",
                                folder_.string(), count, firstIndex, frameCount_));
    }
    std::vector<ExrSize> sizes;
    for (int index = firstIndex; index < firstIndex + count; ++index) {
        const std::string suffix = "_" + std::to_string(index);
        const auto path = [&](const char* stem, const char* extension) {
            return folder_ / (stem + suffix + extension);
        };
        readMatrixFile(path("matrix", ".mat"));  // tiny: read and validated in full
        const std::filesystem::path beautyFile = path("beauty", ".exr");
        const ExrSize beauty = readExrSize(beautyFile, kRgb);
        const auto checkSize = [&](const std::filesystem::path& file,
                                   const std::vector<std::vector<std::string>>& channels) {
            const ExrSize size = readExrSize(file, channels);
            if (size.width != beauty.width || size.height != beauty.height) {
                throw Error(
                    ErrorCode::InvalidInput,
                    fmt::format("{}: {}x{}, but {} is {}x{}", file.string(), size.width,
                                size.height, beautyFile.string(), beauty.width, beauty.height));
            }
        };
        checkSize(path("normal", ".exr"), kRgb);
        checkSize(path("position", ".exr"), kRgb);
        checkSize(path("depth", ".exr"), kDepth);
        checkSize(path("ID", ".exr"), kId);
        if (hasEntry(path("albedo", ".exr"))) checkSize(path("albedo", ".exr"), kRgb);
        if (hasEntry(path("confidence", ".exr")))
            checkSize(path("confidence", ".exr"), kConfidence);
        if (hasEntry(path("specular", ".exr"))) checkSize(path("specular", ".exr"), kRgb);
        if (hasEntry(path("roughness", ".exr"))) checkSize(path("roughness", ".exr"), kRoughness);
        if (hasEntry(path("hit_distance", ".exr")))
            checkSize(path("hit_distance", ".exr"), kHitDistance);
        sizes.push_back(beauty);
    }
    return sizes;
}

void writeFrame(const std::filesystem::path& folder, int index, const Frame& frame) {
    std::error_code ec;
    std::filesystem::create_directories(folder, ec);  // a failure shows at the first write
    const auto path = [&](const char* stem, const char* extension) {
        return folder / fmt::format("{}_{}{}", stem, index, extension);
    };
    writeExr(path("beauty", ".exr"), frame.beauty);
    writeExr(path("normal", ".exr"), frame.normal);
    writeExr(path("position", ".exr"), frame.position);
    writeExr(path("depth", ".exr"), frame.depth);
    Image ids(frame.width(), frame.height(), 1);
    for (std::size_t i = 0; i < ids.pixels.size() && i < frame.objectId.size(); ++i)
        ids.pixels[i] = float(frame.objectId[i]);
    writeExr(path("ID", ".exr"), ids);
    if (frame.albedo) writeExr(path("albedo", ".exr"), *frame.albedo);
    if (frame.confidence) writeExr(path("confidence", ".exr"), *frame.confidence);
    if (frame.specular) writeExr(path("specular", ".exr"), *frame.specular);
    if (frame.roughness) writeExr(path("roughness", ".exr"), *frame.roughness);
    if (frame.hitDistance) writeExr(path("hit_distance", ".exr"), *frame.hitDistance);
    writeMatrixFile(path("matrix", ".mat"),
                    MatrixFile{frame.objectToWorld, frame.worldToCamera, frame.worldToScreen});
}

}  // namespace rtd
