// EXR reading and writing with OpenEXR: channels found by name, converted to float, the data
// window's origin wherever it lies; every OpenEXR exception becomes an rtd::Error naming the file.
// Over 450 lines for the header checks that refuse hostile files before OpenEXR allocates (each
// found by the fuzzer, docs/robustness.md); they belong with the reader they guard.
#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfInputFile.h>
#include <ImfOutputFile.h>
#include <ImfStdIO.h>
#include <ImfThreading.h>
#include <ImfTileDescription.h>
#include <ImfVersion.h>
#include <half.h>

#include <algorithm>
#include <cctype>
#include <cstddef>
#include <cstdint>
#include <exception>
#include <filesystem>
#include <fstream>
#include <optional>
#include <string>
#include <string_view>
#include <system_error>
#include <utility>
#include <vector>

#include "io/atomic_file.h"
#include "io/exr_blocks.h"
#include "rtdenoise/error.h"
#include "rtdenoise/io.h"

namespace rtd {
namespace {

std::string quotedList(const std::vector<std::string>& names, const char* lastSeparator) {
    std::string out;
    for (std::size_t i = 0; i < names.size(); ++i) {
        if (i > 0) out += (i + 1 == names.size()) ? lastSeparator : ", ";
        out += "'" + names[i] + "'";
    }
    return out;
}

std::string channelNames(const Imf::ChannelList& channels) {
    std::string out;
    int count = 0;
    for (auto it = channels.begin(); it != channels.end(); ++it, ++count) {
        if (count == 24) return out + ", ...";  // keep messages readable for layered files
        if (count > 0) out += ", ";
        out += it.name();
    }
    return count == 0 ? std::string("no channels") : out;
}

using io_detail::kMaxBlockBytes;  // the size limits, shared with the direct reader
using io_detail::kMaxPixels;
using io_detail::kMaxSide;

// Scanlines per stored block of each compression (OpenEXR's own table is not public).
int linesPerChunk(Imf::Compression compression) {
    switch (compression) {
        case Imf::NO_COMPRESSION:
        case Imf::RLE_COMPRESSION:
        case Imf::ZIPS_COMPRESSION:
            return 1;
        case Imf::ZIP_COMPRESSION:
        case Imf::PXR24_COMPRESSION:
            return 16;
        case Imf::PIZ_COMPRESSION:
        case Imf::B44_COMPRESSION:
        case Imf::B44A_COMPRESSION:
        case Imf::DWAA_COMPRESSION:
            return 32;
        default:
            return 256;  // DWAB and any newer one: the fewest blocks, the weakest bound
    }
}

// The data window's size, after checking it against a sane maximum and against the file's
// length: each stored block costs at least 16 bytes (its offset-table entry and its header).
ExrSize checkedSize(const std::filesystem::path& file, const Imf::Header& header) {
    const Imath::Box2i window = header.dataWindow();
    const std::int64_t width = std::int64_t(window.max.x) - window.min.x + 1;
    const std::int64_t height = std::int64_t(window.max.y) - window.min.y + 1;
    if (width <= 0 || height <= 0) {
        throw Error(ErrorCode::InvalidInput, file.string() + ": empty data window");
    }
    const std::string claimed = std::to_string(width) + "x" + std::to_string(height);
    if (width > kMaxSide || height > kMaxSide || width * height > kMaxPixels) {
        throw Error(ErrorCode::InvalidInput,
                    file.string() + ": the header claims a " + claimed +
                        " image, larger than this reader accepts (at most " +
                        std::to_string(kMaxSide) + " pixels a side and " +
                        std::to_string(kMaxPixels) + " pixels)");
    }
    std::int64_t bytesPerPixel = 0;
    for (auto it = header.channels().begin(); it != header.channels().end(); ++it)
        bytesPerPixel += it.channel().type == Imf::HALF ? 2 : 4;
    std::int64_t chunks = 0, blockPixels = 0;
    if (header.hasTileDescription()) {
        const Imf::TileDescription& tiles = header.tileDescription();
        const std::int64_t tx = std::max<std::int64_t>(tiles.xSize, 1);
        const std::int64_t ty = std::max<std::int64_t>(tiles.ySize, 1);
        chunks = ((width + tx - 1) / tx) * ((height + ty - 1) / ty);  // level 0 alone
        // Each side checked first: two claimed sides of near 2^32 overflow their product.
        if (tx > kMaxSide || ty > kMaxSide) {
            throw Error(ErrorCode::InvalidInput,
                        file.string() + ": the header claims tiles of " + std::to_string(tx) + "x" +
                            std::to_string(ty) +
                            " pixels, larger than this reader accepts (at most " +
                            std::to_string(kMaxSide) + " a side)");
        }
        blockPixels = tx * ty;
    } else {
        const int lines = linesPerChunk(header.compression());
        chunks = (height + lines - 1) / lines;
        blockPixels = width * lines;
    }
    if (blockPixels * bytesPerPixel > kMaxBlockBytes) {
        throw Error(ErrorCode::InvalidInput,
                    file.string() + ": the header claims blocks of " + std::to_string(blockPixels) +
                        " pixels of " + std::to_string(bytesPerPixel) +
                        " bytes (every channel), more than this reader accepts (" +
                        std::to_string(kMaxBlockBytes) + " bytes a block)");
    }
    std::error_code ec;
    const std::uintmax_t bytes = std::filesystem::file_size(file, ec);
    if (!ec && std::int64_t(bytes) < 16 * chunks) {
        throw Error(ErrorCode::InvalidInput,
                    file.string() + ": the header claims a " + claimed + " image (" +
                        std::to_string(chunks) + " blocks of at least 16 bytes), but the file " +
                        "has only " + std::to_string(bytes) + " bytes: truncated or corrupt");
    }
    return {int(width), int(height)};
}

// OpenEXR's header parse trusts the file: it allocates an attribute's value at the size the file
// claims (fuzz_exr: a 600-byte file with an attribute of 2 GB), a preview at its claimed width
// times height and a string vector's strings at their claimed lengths, and reads a value of a
// known type by that type's layout whatever size the file gives it, so that a wrong size makes it
// read the rest of the header from the wrong offset, where anything can be taken for a size.
// So the header is walked here first, attribute by attribute as OpenEXR 3.1 reads it, and any
// size that is not what OpenEXR will read, or more than the file holds, is refused. A header
// that ends early (or a file that is not an EXR) is left for OpenEXR to report.
std::uint32_t loadLe32(const char* p) {
    return std::uint32_t(std::uint8_t(p[0])) | std::uint32_t(std::uint8_t(p[1])) << 8 |
           std::uint32_t(std::uint8_t(p[2])) << 16 | std::uint32_t(std::uint8_t(p[3])) << 24;
}

// What is wrong with a value of `type` stored in `value` ("" if nothing): its size against the
// bytes OpenEXR reads for the type.
std::string attributeValueProblem(const std::string& type, const std::string& value,
                                  std::size_t maxNameLength) {
    static const std::pair<const char*, std::size_t> fixed[] = {
        {"box2i", 16},      {"box2f", 16},
        {"compression", 1}, {"envmap", 1},
        {"lineOrder", 1},   {"deepImageState", 1},
        {"int", 4},         {"float", 4},
        {"double", 8},      {"v2i", 8},
        {"v2f", 8},         {"v2d", 16},
        {"v3i", 12},        {"v3f", 12},
        {"v3d", 24},        {"m33f", 36},
        {"m33d", 72},       {"m44f", 64},
        {"m44d", 128},      {"chromaticities", 32},
        {"keycode", 28},    {"rational", 8},
        {"timecode", 8},    {"tiledesc", 9}};
    const std::size_t size = value.size();
    for (const auto& [name, bytes] : fixed)
        if (type == name)
            return size == bytes ? std::string()
                                 : std::to_string(size) + " bytes, where a " + type + " is " +
                                       std::to_string(bytes);
    if (type == "chlist") {  // (name, type, pLinear, 3 reserved, xSampling, ySampling)..., ""
        std::size_t at = 0;
        for (;;) {
            const std::size_t end = value.find('\0', at);
            if (end == std::string::npos) return "a channel list without its end";
            if (end == at) break;
            if (end - at > maxNameLength) return "a channel name longer than the format allows";
            at = end + 1 + 16;
            if (at > size) return "a channel list cut short";
        }
        return at + 1 == size ? std::string() : "bytes after the channel list";
    }
    if (type == "preview") {  // width, height, width * height RGBA bytes
        if (size < 8) return "a preview without its size";
        const std::uint64_t pixels =
            std::uint64_t(loadLe32(value.data())) * loadLe32(value.data() + 4);
        return 8 + 4 * pixels == size ? std::string() : "a preview of another size than it claims";
    }
    if (type == "stringvector") {  // (int32 length, bytes)...
        std::size_t at = 0;
        while (at < size) {
            if (size - at < 4) return "a string vector cut short";
            const auto length = std::int32_t(loadLe32(value.data() + at));
            at += 4;
            if (length < 0 || std::size_t(length) > size - at)
                return "a string longer than its string vector";
            at += std::size_t(length);
        }
        return {};
    }
    if (type == "floatvector") return size % 4 == 0 ? std::string() : "a partial float";
    // Debian's OpenEXR 3.1 reads an ID manifest past the size its attribute gives (fuzz_exr: the
    // rest of the header then read from the wrong offset, 1.4 GB allocated); nothing here
    // needs one.
    if (type == "idmanifest") return "an ID manifest, which this reader does not accept";
    return {};  // a string, or a type OpenEXR stores opaquely: the size is what it reads
}

void checkHeaderAttributes(const std::filesystem::path& file) {
    std::error_code ec;
    const std::uintmax_t fileBytes = std::filesystem::file_size(file, ec);
    std::ifstream in(file, std::ios::binary);
    if (ec || !in) return;
    char start[8];
    if (!in.read(start, sizeof start) || std::int32_t(loadLe32(start)) != Imf::MAGIC) return;
    const int version = std::int32_t(loadLe32(start + 4));
    constexpr std::size_t kMaxName = 255;  // OpenEXR 3's Name::MAX_LENGTH, for every name
    std::uintmax_t offset = sizeof start;
    const auto fail = [&file](const std::string& problem) {
        throw Error(ErrorCode::InvalidInput, file.string() + ": corrupt header: " + problem);
    };
    // false: the file ends first.
    const auto readName = [&](std::string& text, std::size_t maxLength, const char* what) {
        text.clear();
        for (char c; in.get(c);) {
            ++offset;
            if (c == 0) return true;
            if (text.size() == maxLength)
                fail(std::string("an attribute ") + what + " longer than " +
                     std::to_string(maxLength) + " characters");
            text.push_back(c);
        }
        return false;
    };
    for (;;) {  // the headers: one, or a multi-part file's list ended by an empty one
        std::string name, type, value;
        bool empty = true;
        for (;;) {
            if (!readName(name, kMaxName, "name")) return;
            if (name.empty()) break;  // the end of this header
            empty = false;
            char size[4];
            if (!readName(type, kMaxName, "type") || !in.read(size, sizeof size)) return;
            offset += sizeof size;
            const auto claimed = std::int32_t(loadLe32(size));
            if (claimed < 0 || std::uintmax_t(claimed) > fileBytes - offset)
                fail("attribute '" + name + "' (" + type + ") claims " + std::to_string(claimed) +
                     " bytes, but " + std::to_string(fileBytes - offset) + " follow it");
            value.resize(std::size_t(claimed));
            if (!in.read(value.data(), claimed)) return;
            offset += std::uintmax_t(claimed);
            const std::string problem = attributeValueProblem(type, value, kMaxName);
            if (!problem.empty()) fail("attribute '" + name + "' (" + type + "): " + problem);
        }
        if (!Imf::isMultiPart(version) || empty) return;
    }
}

// The size claimed by the file's header, checked (checkedSize) before OpenEXR's InputFile reads
// the block offset table it sizes from it: for a hostile header that read fails with "early end
// of file", or allocates as claimed, either way saying nothing of the size. A file that is not a
// readable EXR header is left for InputFile to report.
void checkClaimedSize(const std::filesystem::path& file) {
    checkHeaderAttributes(file);
    std::optional<Imf::Header> header;
    try {
        Imf::StdIFStream stream(file.c_str());
        char start[8];
        stream.read(start, sizeof start);
        const auto le32 = [&start](int at) {
            return std::int32_t(std::uint32_t(std::uint8_t(start[at])) |
                                std::uint32_t(std::uint8_t(start[at + 1])) << 8 |
                                std::uint32_t(std::uint8_t(start[at + 2])) << 16 |
                                std::uint32_t(std::uint8_t(start[at + 3])) << 24);
        };
        if (le32(0) != Imf::MAGIC) return;
        int version = le32(4);
        // A version InputFile refuses before it parses the header (unknown flags): left for it
        // to report. Parsed here, such a header is read by other rules than checkHeaderAttributes
        // walked it by (fuzz_exr: a 100-byte file, 1.4 GB allocated).
        if (Imf::getVersion(version) != Imf::EXR_VERSION ||
            !Imf::supportsFlags(Imf::getFlags(version)))
            return;
        header.emplace();
        header->readFrom(stream, version);
    } catch (const std::exception&) {
        return;
    }
    checkedSize(file, *header);
}

// The file channel chosen for each entry of `channelChoices` (first match wins); throws
// InvalidInput naming the file for a missing or subsampled channel.
std::vector<std::string> chooseChannels(const std::filesystem::path& file,
                                        const Imf::ChannelList& channels,
                                        const ChannelChoices& channelChoices) {
    std::vector<std::string> chosen;
    for (const auto& choices : channelChoices) {
        const std::string* found = nullptr;
        for (const auto& name : choices) {
            if (channels.findChannel(name)) {
                found = &name;
                break;
            }
        }
        if (!found) {
            throw Error(ErrorCode::InvalidInput, file.string() + ": missing channel " +
                                                     quotedList(choices, " or ") +
                                                     " (has: " + channelNames(channels) + ")");
        }
        const Imf::Channel* channel = channels.findChannel(*found);
        if (channel->xSampling != 1 || channel->ySampling != 1) {
            throw Error(ErrorCode::InvalidInput, file.string() + ": channel '" + *found +
                                                     "' is subsampled, which is not supported");
        }
        chosen.push_back(*found);
    }
    return chosen;
}

// The checks before opening: channels asked for, the file there and a regular file.
void requireReadableFile(const std::filesystem::path& file,
                         const std::vector<ChannelChoices>& images) {
    for (const ChannelChoices& choices : images)
        if (choices.empty())
            throw Error(ErrorCode::InvalidArgument, file.string() + ": no channels requested");
    if (images.empty())
        throw Error(ErrorCode::InvalidArgument, file.string() + ": no channels requested");
    io_detail::requireRegularFile(file, "an EXR file");
}

}  // namespace

ExrSize readExrSize(const std::filesystem::path& file, const ChannelChoices& channelChoices) {
    requireReadableFile(file, {channelChoices});
    checkClaimedSize(file);
    try {
        Imf::InputFile input(file.c_str(), 0);
        chooseChannels(file, input.header().channels(), channelChoices);
        return checkedSize(file, input.header());
    } catch (const Error&) {
        throw;
    } catch (const std::exception& e) {
        throw Error(ErrorCode::IoFailure, file.string() + ": " + e.what());
    }
}

ExrContents readExrContents(const std::filesystem::path& file) {
    io_detail::requireRegularFile(file, "an EXR file");
    checkClaimedSize(file);
    try {
        Imf::InputFile input(file.c_str(), 0);
        ExrContents contents{checkedSize(file, input.header()), {}};
        const Imf::ChannelList& channels = input.header().channels();
        for (auto it = channels.begin(); it != channels.end(); ++it)
            contents.channels.emplace_back(it.name());
        return contents;
    } catch (const Error&) {
        throw;
    } catch (const std::exception& e) {
        throw Error(ErrorCode::IoFailure, file.string() + ": " + e.what());
    }
}

void setExrThreads(int count) {
    Imf::setGlobalThreadCount(count < 0 ? 0 : count);
}

namespace {
std::vector<Image> readImagesWithOpenExr(const std::filesystem::path& file,
                                         const std::vector<ChannelChoices>& images);
}  // namespace

Image io_detail::readExrWithOpenExr(const std::filesystem::path& file,
                                    const ChannelChoices& channelChoices) {
    return std::move(readExrImages(file, {channelChoices}).front());
}

// The files this project's own commands read most (scan-line none/zips/zip) by the direct
// reader, anything else by OpenEXR.
Image readExr(const std::filesystem::path& file, const ChannelChoices& channelChoices) {
    requireReadableFile(file, {channelChoices});
    checkClaimedSize(file);
    if (std::optional<Image> image = io_detail::readExrBlocks(file, channelChoices))
        return std::move(*image);
    return std::move(readImagesWithOpenExr(file, {channelChoices}).front());
}

std::vector<Image> readExrImages(const std::filesystem::path& file,
                                 const std::vector<ChannelChoices>& images) {
    requireReadableFile(file, images);
    checkClaimedSize(file);
    return readImagesWithOpenExr(file, images);
}

namespace {

// readExrImages' reading, after its checks (readExr's fallback has made them already).
std::vector<Image> readImagesWithOpenExr(const std::filesystem::path& file,
                                         const std::vector<ChannelChoices>& images) {
    try {
        Imf::InputFile input(file.c_str(), Imf::globalThreadCount());
        const Imf::Header& header = input.header();

        // Resolve every output channel to a file channel, and check the size, before reading
        // or allocating anything.
        std::vector<std::vector<std::string>> chosen;
        for (const ChannelChoices& choices : images)
            chosen.push_back(chooseChannels(file, header.channels(), choices));
        const Imath::Box2i window = header.dataWindow();
        const auto [width, height] = checkedSize(file, header);
        std::vector<Image> result;
        for (const auto& channels : chosen)
            result.emplace_back(width, height, static_cast<int>(channels.size()));

        // A FrameBuffer holds one slice per name, so an output channel that repeats an earlier
        // one (in any image) is copied after the read instead.
        struct Target {
            std::size_t image;
            int channel;
        };
        std::vector<std::pair<Target, Target>> copies;  // (to, from)
        std::vector<std::pair<std::string, Target>> read;
        Imf::FrameBuffer frameBuffer;
        for (std::size_t k = 0; k < chosen.size(); ++k) {
            const int channelCount = result[k].channels;
            const std::size_t xStride = sizeof(float) * channelCount;
            const std::size_t yStride = xStride * width;
            for (int c = 0; c < channelCount; ++c) {
                const Target target{k, c};
                const auto earlier = std::find_if(read.begin(), read.end(), [&](const auto& entry) {
                    return entry.first == chosen[k][c];
                });
                if (earlier != read.end()) {
                    copies.emplace_back(target, earlier->second);
                    continue;
                }
                read.emplace_back(chosen[k][c], target);
                frameBuffer.insert(chosen[k][c],
                                   Imf::Slice::Make(Imf::FLOAT, result[k].pixels.data() + c, window,
                                                    xStride, yStride));
            }
        }
        input.setFrameBuffer(frameBuffer);
        input.readPixels(window.min.y, window.max.y);

        for (const auto& [to, from] : copies) {
            Image& target = result[to.image];
            const Image& source = result[from.image];
            for (std::size_t i = 0; i < target.pixelCount(); ++i)
                target.pixels[i * target.channels + to.channel] =
                    source.pixels[i * source.channels + from.channel];
        }
        return result;
    } catch (const Error&) {
        throw;
    } catch (const std::exception& e) {
        throw Error(ErrorCode::IoFailure, file.string() + ": " + e.what());
    }
}

struct CompressionName {
    ExrCompression compression;
    const char* name;
    Imf::Compression imf;
};
constexpr CompressionName kCompressionNames[] = {
    {ExrCompression::None, "none", Imf::NO_COMPRESSION},
    {ExrCompression::Rle, "rle", Imf::RLE_COMPRESSION},
    {ExrCompression::Zips, "zips", Imf::ZIPS_COMPRESSION},
    {ExrCompression::Zip, "zip", Imf::ZIP_COMPRESSION},
    {ExrCompression::Piz, "piz", Imf::PIZ_COMPRESSION},
    {ExrCompression::Pxr24, "pxr24", Imf::PXR24_COMPRESSION},
    {ExrCompression::B44, "b44", Imf::B44_COMPRESSION},
    {ExrCompression::B44a, "b44a", Imf::B44A_COMPRESSION},
    {ExrCompression::Dwaa, "dwaa", Imf::DWAA_COMPRESSION},
    {ExrCompression::Dwab, "dwab", Imf::DWAB_COMPRESSION},
};

const CompressionName& entryOf(ExrCompression compression) {
    for (const CompressionName& entry : kCompressionNames)
        if (entry.compression == compression) return entry;
    throw Error(ErrorCode::InvalidArgument,
                "unknown EXR compression " + std::to_string(int(compression)));
}

}  // namespace

const char* toString(ExrCompression compression) {
    return entryOf(compression).name;
}

const std::vector<ExrCompression>& exrCompressions() {
    static const std::vector<ExrCompression> all = [] {
        std::vector<ExrCompression> out;
        for (const CompressionName& entry : kCompressionNames) out.push_back(entry.compression);
        return out;
    }();
    return all;
}

ExrCompression exrCompressionNamed(std::string_view name) {
    std::string lower(name);
    for (char& c : lower) c = char(std::tolower(static_cast<unsigned char>(c)));
    std::vector<std::string> names;
    for (const CompressionName& entry : kCompressionNames) {
        if (lower == entry.name) return entry.compression;
        names.emplace_back(entry.name);
    }
    throw Error(ErrorCode::InvalidArgument, "compression '" + std::string(name) +
                                                "' is not one of " + quotedList(names, " or "));
}

bool isLossless(ExrCompression compression, bool half) {
    switch (compression) {
        case ExrCompression::Pxr24:
            return half;
        case ExrCompression::B44:
        case ExrCompression::B44a:
            return !half;
        case ExrCompression::Dwaa:
        case ExrCompression::Dwab:
            return false;
        default:
            return true;
    }
}

void writeExr(const std::filesystem::path& file, const Image& image) {
    writeExr(file, image, ExrWriteOptions{});
}

void writeExr(const std::filesystem::path& file, const Image& image,
              const ExrWriteOptions& options) {
    // 3 channels are written as R,G,B; 1 channel as Y (the layout's depth and ID files).
    if (image.channels != 3 && image.channels != 1) {
        throw Error(ErrorCode::InvalidArgument,
                    file.string() + ": writeExr needs a 1- or 3-channel image, got " +
                        std::to_string(image.channels) + " channels");
    }
    if (image.width <= 0 || image.height <= 0 ||
        image.pixels.size() != image.pixelCount() * image.channels) {
        throw Error(ErrorCode::InvalidArgument,
                    file.string() + ": writeExr got an empty or inconsistent image (" +
                        std::to_string(image.width) + "x" + std::to_string(image.height) + ")");
    }
    const Imf::Compression compression = entryOf(options.compression).imf;
    static const char* const rgb[] = {"R", "G", "B"};
    static const char* const gray[] = {"Y"};
    const char* const* names = image.channels == 3 ? rgb : gray;
    Imf::Header header(image.width, image.height, 1.0f, Imath::V2f(0, 0), 1.0f, Imf::INCREASING_Y,
                       compression);
    const Imf::PixelType fileType = options.half ? Imf::HALF : Imf::FLOAT;
    for (int c = 0; c < image.channels; ++c) {
        header.channels().insert(names[c], Imf::Channel(fileType));
    }
    if (compression == Imf::NO_COMPRESSION) {
        writeFileAtomically(
            file, io_detail::uncompressedExrBytes(header, image, {names, names + image.channels}));
        return;
    }
    io_detail::requireParentFolder(file);
    io_detail::TemporaryFile temporary(io_detail::temporaryPathFor(file));
    try {
        // OpenEXR's writer does not convert FLOAT to HALF: the halves (rounded to nearest even)
        // are made here.
        std::vector<half> halves;
        if (options.half) halves.assign(image.pixels.begin(), image.pixels.end());
        const char* base = options.half ? reinterpret_cast<const char*>(halves.data())
                                        : reinterpret_cast<const char*>(image.pixels.data());
        const std::size_t valueBytes = options.half ? sizeof(half) : sizeof(float);
        const std::size_t xStride = valueBytes * image.channels;
        const std::size_t yStride = xStride * image.width;
        Imf::FrameBuffer frameBuffer;
        for (int c = 0; c < image.channels; ++c) {
            // OpenEXR's Slice takes a mutable pointer but only reads from it when writing.
            frameBuffer.insert(
                names[c],
                Imf::Slice(fileType, const_cast<char*>(base + c * valueBytes), xStride, yStride));
        }
        {
            io_detail::FileCreation creation(file);
            Imf::OutputFile output(temporary.path().c_str(), header, Imf::globalThreadCount());
            creation.finish();
            output.setFrameBuffer(frameBuffer);
            output.writePixels(image.height);
        }  // the destructor finishes the file before the rename
    } catch (const std::exception& e) {
        throw Error(ErrorCode::IoFailure, file.string() + ": cannot write: " + e.what());
    }
    temporary.commitTo(file);
}

void writeExrChannels(const std::filesystem::path& file,
                      const std::vector<ExrChannelGroup>& groups) {
    if (groups.empty() || !groups.front().image)
        throw Error(ErrorCode::InvalidArgument, file.string() + ": no channels to write");
    const int width = groups.front().image->width, height = groups.front().image->height;
    for (const ExrChannelGroup& group : groups) {
        const Image* image = group.image;
        if (!image || image->width <= 0 || image->height <= 0 || image->channels <= 0 ||
            image->pixels.size() != image->pixelCount() * image->channels ||
            image->width != width || image->height != height ||
            group.names.size() != std::size_t(image->channels)) {
            throw Error(
                ErrorCode::InvalidArgument,
                file.string() + ": an empty or inconsistent image to write (" +
                    (image ? std::to_string(image->width) + "x" + std::to_string(image->height)
                           : std::string("none")) +
                    ")");
        }
    }
    io_detail::requireParentFolder(file);
    io_detail::TemporaryFile temporary(io_detail::temporaryPathFor(file));
    try {
        Imf::Header header(width, height, 1.0f, Imath::V2f(0, 0), 1.0f, Imf::INCREASING_Y,
                           Imf::ZIP_COMPRESSION);
        // The slices stay FLOAT: OpenEXR converts them to a HALF file channel itself.
        Imf::FrameBuffer frameBuffer;
        for (const ExrChannelGroup& group : groups) {
            const Image& image = *group.image;
            const std::size_t xStride = sizeof(float) * image.channels;
            const std::size_t yStride = xStride * image.width;
            for (int c = 0; c < image.channels; ++c) {
                header.channels().insert(group.names[c],
                                         Imf::Channel(group.half ? Imf::HALF : Imf::FLOAT));
                // OpenEXR's Slice takes a mutable pointer but only reads from it when writing.
                frameBuffer.insert(
                    group.names[c],
                    Imf::Slice(
                        Imf::FLOAT,
                        const_cast<char*>(reinterpret_cast<const char*>(image.pixels.data() + c)),
                        xStride, yStride));
            }
        }
        {
            io_detail::FileCreation creation(file);
            Imf::OutputFile output(temporary.path().c_str(), header, Imf::globalThreadCount());
            creation.finish();
            output.setFrameBuffer(frameBuffer);
            output.writePixels(height);
        }  // the destructor finishes the file before the rename
    } catch (const std::exception& e) {
        throw Error(ErrorCode::IoFailure, file.string() + ": cannot write: " + e.what());
    }
    temporary.commitTo(file);
}

}  // namespace rtd
