// EXR reading and writing with OpenEXR: channels found by name, converted to float, the data
// window's origin wherever it lies; every OpenEXR exception becomes an rtd::Error naming the file.
#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfInputFile.h>
#include <ImfOutputFile.h>
#include <ImfStdIO.h>
#include <ImfThreading.h>
#include <ImfTileDescription.h>
#include <ImfVersion.h>

#include <cstddef>
#include <cstdint>
#include <exception>
#include <filesystem>
#include <optional>
#include <string>
#include <system_error>
#include <vector>

#include "io/atomic_file.h"
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

// A header's size is checked before anything is allocated for it: a corrupt or hostile header
// would otherwise end in std::bad_alloc or an allocation of gigabytes.
constexpr std::int64_t kMaxSide = 65536;
constexpr std::int64_t kMaxPixels = std::int64_t(1) << 28;  // 16384 x 16384

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
    std::int64_t chunks = 0;
    if (header.hasTileDescription()) {
        const Imf::TileDescription& tiles = header.tileDescription();
        const std::int64_t tx = std::max<std::int64_t>(tiles.xSize, 1);
        const std::int64_t ty = std::max<std::int64_t>(tiles.ySize, 1);
        chunks = ((width + tx - 1) / tx) * ((height + ty - 1) / ty);  // level 0 alone
    } else {
        const int lines = linesPerChunk(header.compression());
        chunks = (height + lines - 1) / lines;
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

// The size claimed by the file's header, checked (checkedSize) before OpenEXR's InputFile reads
// the block offset table it sizes from it: for a hostile header that read fails with "early end
// of file", or allocates as claimed, either way saying nothing of the size. A file that is not a
// readable EXR header is left for InputFile to report.
void checkClaimedSize(const std::filesystem::path& file) {
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
        header.emplace();
        header->readFrom(stream, version);
    } catch (const std::exception&) {
        return;
    }
    checkedSize(file, *header);
}

// The file channel chosen for each entry of `channelChoices` (first match wins); throws
// InvalidInput naming the file for a missing or subsampled channel.
std::vector<std::string> chooseChannels(
    const std::filesystem::path& file, const Imf::ChannelList& channels,
    const std::vector<std::vector<std::string>>& channelChoices) {
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
                         const std::vector<std::vector<std::string>>& channelChoices) {
    if (channelChoices.empty()) {
        throw Error(ErrorCode::InvalidArgument, file.string() + ": no channels requested");
    }
    std::error_code ec;
    const std::filesystem::file_status status = std::filesystem::status(file, ec);
    if (!std::filesystem::exists(status)) {
        const bool dangling =
            std::filesystem::is_symlink(std::filesystem::symlink_status(file, ec));
        throw Error(ErrorCode::MissingFile,
                    file.string() +
                        (dangling ? ": a link to a file that does not exist" : ": no such file"));
    }
    if (!std::filesystem::is_regular_file(status)) {
        throw Error(ErrorCode::InvalidInput, file.string() + (std::filesystem::is_directory(status)
                                                                  ? ": is a folder, not an EXR file"
                                                                  : ": not a regular file"));
    }
}

}  // namespace

ExrSize readExrSize(const std::filesystem::path& file,
                    const std::vector<std::vector<std::string>>& channelChoices) {
    requireReadableFile(file, channelChoices);
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

void setExrThreads(int count) {
    Imf::setGlobalThreadCount(count < 0 ? 0 : count);
}

Image readExr(const std::filesystem::path& file,
              const std::vector<std::vector<std::string>>& channelChoices) {
    requireReadableFile(file, channelChoices);
    checkClaimedSize(file);
    try {
        Imf::InputFile input(file.c_str(), Imf::globalThreadCount());
        const Imf::Header& header = input.header();

        // Resolve every output channel to a file channel, and check the size, before reading
        // or allocating anything.
        const std::vector<std::string> chosen =
            chooseChannels(file, header.channels(), channelChoices);
        const Imath::Box2i window = header.dataWindow();
        const auto [width, height] = checkedSize(file, header);
        const int channelCount = static_cast<int>(chosen.size());
        Image image(width, height, channelCount);

        // A FrameBuffer holds one slice per name, so an output channel that repeats an earlier
        // one is copied after the read instead.
        const std::size_t xStride = sizeof(float) * channelCount;
        const std::size_t yStride = xStride * width;
        Imf::FrameBuffer frameBuffer;
        std::vector<int> copyOf(chosen.size(), -1);
        for (int c = 0; c < channelCount; ++c) {
            for (int earlier = 0; earlier < c; ++earlier) {
                if (chosen[earlier] == chosen[c]) {
                    copyOf[c] = earlier;
                    break;
                }
            }
            if (copyOf[c] >= 0) continue;
            frameBuffer.insert(chosen[c], Imf::Slice::Make(Imf::FLOAT, image.pixels.data() + c,
                                                           window, xStride, yStride));
        }
        input.setFrameBuffer(frameBuffer);
        input.readPixels(window.min.y, window.max.y);

        for (int c = 0; c < channelCount; ++c) {
            if (copyOf[c] < 0) continue;
            for (std::size_t i = 0; i < image.pixelCount(); ++i) {
                image.pixels[i * channelCount + c] = image.pixels[i * channelCount + copyOf[c]];
            }
        }
        return image;
    } catch (const Error&) {
        throw;
    } catch (const std::exception& e) {
        throw Error(ErrorCode::IoFailure, file.string() + ": " + e.what());
    }
}

void writeExr(const std::filesystem::path& file, const Image& image) {
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
    io_detail::requireParentFolder(file);
    io_detail::TemporaryFile temporary(io_detail::temporaryPathFor(file));
    try {
        static const char* const rgb[] = {"R", "G", "B"};
        static const char* const gray[] = {"Y"};
        const char* const* names = image.channels == 3 ? rgb : gray;

        Imf::Header header(image.width, image.height, 1.0f, Imath::V2f(0, 0), 1.0f,
                           Imf::INCREASING_Y, Imf::ZIP_COMPRESSION);
        for (int c = 0; c < image.channels; ++c) {
            header.channels().insert(names[c], Imf::Channel(Imf::FLOAT));
        }
        const std::size_t xStride = sizeof(float) * image.channels;
        const std::size_t yStride = xStride * image.width;
        Imf::FrameBuffer frameBuffer;
        for (int c = 0; c < image.channels; ++c) {
            // OpenEXR's Slice takes a mutable pointer but only reads from it when writing.
            frameBuffer.insert(names[c], Imf::Slice(Imf::FLOAT,
                                                    const_cast<char*>(reinterpret_cast<const char*>(
                                                        image.pixels.data() + c)),
                                                    xStride, yStride));
        }
        {
            Imf::OutputFile output(temporary.path().c_str(), header, Imf::globalThreadCount());
            output.setFrameBuffer(frameBuffer);
            output.writePixels(image.height);
        }  // the destructor finishes the file before the rename
    } catch (const std::exception& e) {
        throw Error(ErrorCode::IoFailure, file.string() + ": cannot write: " + e.what());
    }
    temporary.commitTo(file);
}

}  // namespace rtd
