// The direct reader of plain scan-line EXR files (exr_blocks.h). Debian's OpenEXR 3.1 inflates
// with zlib and converts every value of a block with a byte loop; on the course data that is most
// of a frame's reading time, which on two cores competes with the denoiser.
#include "io/exr_blocks.h"

#include <IlmThreadPool.h>
#include <ImfChannelList.h>
#include <ImfHeader.h>
#include <ImfIO.h>
#include <ImfPartType.h>
#include <ImfStdIO.h>
#include <ImfThreading.h>
#include <ImfVersion.h>
#include <ImfXdr.h>
#include <half.h>

#if RTD_HAS_LIBDEFLATE
#include <libdeflate.h>
#else
#include <zlib.h>
#endif
#if defined(__SSSE3__)
#include <tmmintrin.h>
#elif defined(__SSE2__)
#include <emmintrin.h>
#endif

#include <algorithm>
#include <atomic>
#include <bit>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <memory>
#include <stdexcept>
#include <system_error>

namespace rtd::io_detail {
namespace {

// Larger files are left to OpenEXR, which reads them a block at a time.
constexpr std::uintmax_t kMaxFileBytes = std::uintmax_t(1) << 32;

// A file read into memory, for OpenEXR's header parser.
class MemoryStream final : public Imf::IStream {
  public:
    MemoryStream(const std::filesystem::path& file, const std::vector<char>& bytes)
        : Imf::IStream(file.c_str()), bytes_(bytes) {}
    bool read(char c[], int n) override {
        if (n < 0 || std::size_t(n) > bytes_.size() - position_)
            throw std::runtime_error("early end of file");
        std::memcpy(c, bytes_.data() + position_, std::size_t(n));
        position_ += std::size_t(n);
        return position_ < bytes_.size();
    }
    std::uint64_t tellg() override { return position_; }
    void seekg(std::uint64_t position) override {
        position_ = std::size_t(std::min<std::uint64_t>(position, bytes_.size()));
    }

  private:
    const std::vector<char>& bytes_;
    std::size_t position_ = 0;
};

std::uint32_t loadLe32(const char* p) {
    std::uint32_t value;
    std::memcpy(&value, p, sizeof value);
    return value;  // little-endian hosts only (checked in readExrBlocks)
}

std::uint64_t loadLe64(const char* p) {
    std::uint64_t value;
    std::memcpy(&value, p, sizeof value);
    return value;
}

struct FileChannel {
    Imf::PixelType type;
    std::size_t offset;  // of its values in a line of a block
};

struct Block {
    const char* data;
    std::size_t bytes;  // as stored
    int firstLine;      // from the data window's top
    int lines;
};

// Decodes a run of blocks into the image; a failure (corrupt deflate data) is only flagged, the
// whole file then read again by OpenEXR.
class DecodeTask final : public IlmThread::Task {
  public:
    DecodeTask(IlmThread::TaskGroup* group, const std::vector<Block>& blocks, std::size_t begin,
               std::size_t end, std::size_t lineBytes, const std::vector<FileChannel>& channels,
               const std::vector<int>& chosen, Image& image, std::atomic<bool>& failed)
        : IlmThread::Task(group),
          blocks_(blocks),
          begin_(begin),
          end_(end),
          lineBytes_(lineBytes),
          channels_(channels),
          chosen_(chosen),
          image_(image),
          failed_(failed) {}

    void execute() override {
        try {
            for (std::size_t b = begin_; b < end_ && !failed_.load(std::memory_order_relaxed); ++b)
                if (!decode(blocks_[b])) failed_.store(true);
        } catch (...) {
            failed_.store(true);  // an allocation failure: OpenEXR's path reports it
        }
    }

  private:
    bool decode(const Block& block) {
        const std::size_t expected = std::size_t(block.lines) * lineBytes_;
        const unsigned char* values = reinterpret_cast<const unsigned char*>(block.data);
        if (block.bytes < expected) {  // compressed (a block that would not shrink is stored)
            inflated_.resize(expected);
            reordered_.resize(expected);
            if (!inflate(block, expected)) return false;
            undoZipPredictor(inflated_.data(), expected);
            interleaveHalves(inflated_.data(), expected, reordered_.data());
            values = reordered_.data();
        }
        const int outChannels = image_.channels;
        const std::size_t width = std::size_t(image_.width);
        for (int line = 0; line < block.lines; ++line) {
            const unsigned char* lineValues = values + std::size_t(line) * lineBytes_;
            float* row = image_.pixels.data() +
                         std::size_t(block.firstLine + line) * width * std::size_t(outChannels);
            for (int o = 0; o < outChannels; ++o) {
                const FileChannel& channel = channels_[std::size_t(chosen_[std::size_t(o)])];
                convert(channel.type, lineValues + channel.offset, width, row + o,
                        std::size_t(outChannels));
            }
        }
        return true;
    }

    bool inflate(const Block& block, std::size_t expected) {
#if RTD_HAS_LIBDEFLATE
        if (!decompressor_) decompressor_.reset(libdeflate_alloc_decompressor());
        if (!decompressor_) return false;
        // Without a size to return, it fails unless the stream holds exactly `expected` bytes.
        return libdeflate_zlib_decompress(decompressor_.get(), block.data, block.bytes,
                                          inflated_.data(), expected,
                                          nullptr) == LIBDEFLATE_SUCCESS;
#else
        uLongf length = uLongf(expected);
        return ::uncompress(inflated_.data(), &length, reinterpret_cast<const Bytef*>(block.data),
                            uLong(block.bytes)) == Z_OK &&
               length == expected;
#endif
    }

    // `count` little-endian values of `type` to floats `stride` apart, as OpenEXR converts them.
    static void convert(Imf::PixelType type, const unsigned char* in, std::size_t count, float* out,
                        std::size_t stride) {
        if (type == Imf::FLOAT) {
            for (std::size_t x = 0; x < count; ++x) std::memcpy(out + x * stride, in + 4 * x, 4);
        } else if (type == Imf::HALF) {
            for (std::size_t x = 0; x < count; ++x) {
                std::uint16_t bits;
                std::memcpy(&bits, in + 2 * x, 2);
                half value;
                value.setBits(bits);
                out[x * stride] = float(value);
            }
        } else {  // UINT
            for (std::size_t x = 0; x < count; ++x) {
                std::uint32_t value;
                std::memcpy(&value, in + 4 * x, 4);
                out[x * stride] = float(value);
            }
        }
    }

#if RTD_HAS_LIBDEFLATE
    struct FreeDecompressor {
        void operator()(libdeflate_decompressor* d) const { libdeflate_free_decompressor(d); }
    };
    std::unique_ptr<libdeflate_decompressor, FreeDecompressor> decompressor_;
#endif
    const std::vector<Block>& blocks_;
    std::size_t begin_, end_, lineBytes_;
    const std::vector<FileChannel>& channels_;
    const std::vector<int>& chosen_;
    Image& image_;
    std::atomic<bool>& failed_;
    std::vector<unsigned char> inflated_, reordered_;
};

}  // namespace

std::string uncompressedExrBytes(const Imf::Header& header, const Image& image,
                                 const std::vector<std::string>& channelNames) {
    static_assert(std::endian::native == std::endian::little, "EXR values are little-endian");
    // Each line holds the header's channels in its order (by name), each channel's values in turn.
    struct Column {
        int imageChannel;
        bool isHalf;
    };
    std::vector<Column> columns;
    std::size_t lineBytes = 0;
    for (auto it = header.channels().begin(); it != header.channels().end(); ++it) {
        const auto named = std::find(channelNames.begin(), channelNames.end(), it.name());
        const bool isHalf = it.channel().type == Imf::HALF;
        columns.push_back({int(named - channelNames.begin()), isHalf});
        lineBytes += std::size_t(image.width) * (isHalf ? 2 : 4);
    }
    // The start OpenEXR writes: magic number, version (scan lines, names of up to 31
    // characters), the header's attributes and its end.
    Imf::StdOSStream start;
    Imf::Xdr::write<Imf::StreamIO>(start, Imf::MAGIC);
    Imf::Xdr::write<Imf::StreamIO>(start, Imf::EXR_VERSION);
    header.writeTo(start, false);
    const std::string headerBytes = start.str();

    const std::size_t lines = std::size_t(image.height);
    const std::size_t chunkBytes = 8 + lineBytes;  // line number, byte count, values
    std::string bytes(headerBytes.size() + 8 * lines + chunkBytes * lines, '\0');
    std::memcpy(bytes.data(), headerBytes.data(), headerBytes.size());
    char* table = bytes.data() + headerBytes.size();
    char* chunk = table + 8 * lines;
    const int firstLine = header.dataWindow().min.y;
    const std::size_t width = std::size_t(image.width);
    const std::size_t stride = std::size_t(image.channels);
    for (std::size_t y = 0; y < lines; ++y, chunk += chunkBytes) {
        const std::uint64_t offset = std::uint64_t(chunk - bytes.data());
        const std::int32_t lineNumber = std::int32_t(firstLine + std::int64_t(y));
        const std::int32_t byteCount = std::int32_t(lineBytes);
        std::memcpy(table + 8 * y, &offset, 8);
        std::memcpy(chunk, &lineNumber, 4);
        std::memcpy(chunk + 4, &byteCount, 4);
        char* out = chunk + 8;
        for (const Column& column : columns) {
            const float* in = image.pixels.data() + y * width * stride + column.imageChannel;
            if (column.isHalf) {
                for (std::size_t x = 0; x < width; ++x, out += 2) {
                    const std::uint16_t bits = half(in[x * stride]).bits();
                    std::memcpy(out, &bits, 2);
                }
            } else {
                for (std::size_t x = 0; x < width; ++x, out += 4)
                    std::memcpy(out, in + x * stride, 4);
            }
        }
    }
    return bytes;
}

void undoZipPredictor(unsigned char* bytes, std::size_t count) {
    std::size_t i = 1;
#if defined(__SSE2__)
    // A running sum of (t[i] - 128) mod 256 over 16 bytes: four shifted adds, then the carry-in,
    // the previous 16's last byte, kept in a register (through memory, the store-to-load latency
    // set the pace).
    const __m128i bias = _mm_set1_epi8(char(-128));
    __m128i carry = _mm_set1_epi8(char(count > 0 ? bytes[0] : 0));
    for (; count >= 16 && i <= count - 16; i += 16) {
        __m128i x =
            _mm_add_epi8(_mm_loadu_si128(reinterpret_cast<const __m128i*>(bytes + i)), bias);
        x = _mm_add_epi8(x, _mm_slli_si128(x, 1));
        x = _mm_add_epi8(x, _mm_slli_si128(x, 2));
        x = _mm_add_epi8(x, _mm_slli_si128(x, 4));
        x = _mm_add_epi8(x, _mm_slli_si128(x, 8));
        x = _mm_add_epi8(x, carry);
        _mm_storeu_si128(reinterpret_cast<__m128i*>(bytes + i), x);
#if defined(__SSSE3__)
        carry = _mm_shuffle_epi8(x, _mm_set1_epi8(15));
#else
        const __m128i high = _mm_shufflehi_epi16(_mm_unpackhi_epi8(x, x), 0xff);
        carry = _mm_unpackhi_epi64(high, high);
#endif
    }
#endif
    for (; i < count; ++i) bytes[i] = static_cast<unsigned char>(bytes[i - 1] + bytes[i] - 128);
}

void interleaveHalves(const unsigned char* bytes, std::size_t count, unsigned char* out) {
    const unsigned char* first = bytes;
    const unsigned char* second = bytes + (count + 1) / 2;
    const std::size_t pairs = count / 2;
    std::size_t i = 0;
#if defined(__SSE2__)
    for (; pairs >= 16 && i <= pairs - 16; i += 16) {
        const __m128i a = _mm_loadu_si128(reinterpret_cast<const __m128i*>(first + i));
        const __m128i b = _mm_loadu_si128(reinterpret_cast<const __m128i*>(second + i));
        _mm_storeu_si128(reinterpret_cast<__m128i*>(out + 2 * i), _mm_unpacklo_epi8(a, b));
        _mm_storeu_si128(reinterpret_cast<__m128i*>(out + 2 * i + 16), _mm_unpackhi_epi8(a, b));
    }
#endif
    for (; i < pairs; ++i) {
        out[2 * i] = first[i];
        out[2 * i + 1] = second[i];
    }
    if (count % 2) out[count - 1] = first[pairs];
}

std::optional<Image> readExrBlocks(const std::filesystem::path& file,
                                   const std::vector<std::vector<std::string>>& channelChoices) {
    if constexpr (std::endian::native != std::endian::little) return std::nullopt;
    std::error_code ec;
    const std::uintmax_t fileBytes = std::filesystem::file_size(file, ec);
    if (ec || fileBytes < 8 || fileBytes > kMaxFileBytes) return std::nullopt;
    std::vector<char> bytes(static_cast<std::size_t>(fileBytes));
    {
        std::ifstream in(file, std::ios::binary);
        if (!in.read(bytes.data(), std::streamsize(bytes.size()))) return std::nullopt;
    }
    int version = int(loadLe32(bytes.data() + 4));
    if (int(loadLe32(bytes.data())) != Imf::MAGIC || Imf::getVersion(version) != Imf::EXR_VERSION ||
        !Imf::supportsFlags(Imf::getFlags(version)) || Imf::isTiled(version) ||
        Imf::isMultiPart(version) || Imf::isNonImage(version))
        return std::nullopt;

    MemoryStream stream(file, bytes);
    Imf::Header header;
    try {
        stream.seekg(8);
        header.readFrom(stream, version);
        header.sanityCheck(false);  // what OpenEXR's InputFile (and so readExrSize) refuses
    } catch (const std::exception&) {
        return std::nullopt;
    }
    const Imf::Compression compression = header.compression();
    if (header.hasTileDescription() || (header.hasType() && header.type() != Imf::SCANLINEIMAGE) ||
        (compression != Imf::NO_COMPRESSION && compression != Imf::ZIPS_COMPRESSION &&
         compression != Imf::ZIP_COMPRESSION))
        return std::nullopt;

    const Imath::Box2i window = header.dataWindow();
    const std::int64_t width = std::int64_t(window.max.x) - window.min.x + 1;
    const std::int64_t height = std::int64_t(window.max.y) - window.min.y + 1;
    if (width <= 0 || height <= 0 || width > kMaxSide || height > kMaxSide ||
        width * height > kMaxPixels)
        return std::nullopt;

    // Channels in the file's order (by name): each line of a block holds every channel's
    // values in turn.
    std::vector<FileChannel> channels;
    std::vector<std::string> names;
    std::uint64_t lineBytes = 0;
    for (auto it = header.channels().begin(); it != header.channels().end(); ++it) {
        const Imf::Channel& channel = it.channel();
        if (channel.xSampling != 1 || channel.ySampling != 1) return std::nullopt;
        if (channel.type != Imf::HALF && channel.type != Imf::FLOAT && channel.type != Imf::UINT)
            return std::nullopt;
        channels.push_back({channel.type, std::size_t(lineBytes)});
        names.emplace_back(it.name());
        lineBytes += std::uint64_t(width) * (channel.type == Imf::HALF ? 2 : 4);
        if (lineBytes > std::uint64_t(kMaxBlockBytes)) return std::nullopt;
    }
    std::vector<int> chosen;
    for (const auto& choices : channelChoices) {
        int found = -1;
        for (const std::string& name : choices) {
            const auto at = std::find(names.begin(), names.end(), name);
            if (at != names.end()) {
                found = int(at - names.begin());
                break;
            }
        }
        if (found < 0) return std::nullopt;  // OpenEXR's path names what is missing
        chosen.push_back(found);
    }
    if (chosen.empty()) return std::nullopt;

    const int linesPerBlock = compression == Imf::ZIP_COMPRESSION ? 16 : 1;
    if (lineBytes * std::uint64_t(linesPerBlock) > std::uint64_t(kMaxBlockBytes))
        return std::nullopt;
    const std::size_t blockCount = std::size_t((height + linesPerBlock - 1) / linesPerBlock);
    const std::uint64_t tableStart = stream.tellg();
    const std::uint64_t tableEnd = tableStart + 8 * std::uint64_t(blockCount);
    if (tableEnd > fileBytes) return std::nullopt;
    std::vector<Block> blocks(blockCount);
    for (std::size_t b = 0; b < blockCount; ++b) {
        const std::uint64_t offset = loadLe64(bytes.data() + tableStart + 8 * b);
        if (offset < tableEnd || offset > fileBytes - 8) return std::nullopt;
        const std::int64_t firstLine = std::int64_t(b) * linesPerBlock;
        const auto y = std::int32_t(loadLe32(bytes.data() + offset));
        const auto stored = std::int32_t(loadLe32(bytes.data() + offset + 4));
        const int lines = int(std::min<std::int64_t>(linesPerBlock, height - firstLine));
        const std::uint64_t expected = std::uint64_t(lines) * lineBytes;
        if (y != window.min.y + firstLine || stored <= 0 ||
            std::uint64_t(stored) > fileBytes - offset - 8 || std::uint64_t(stored) > expected ||
            (compression == Imf::NO_COMPRESSION && std::uint64_t(stored) != expected))
            return std::nullopt;
        blocks[b] = {bytes.data() + offset + 8, std::size_t(stored), int(firstLine), lines};
    }

    Image image(int(width), int(height), int(chosen.size()));
    std::atomic<bool> failed{false};
    {
        // A few runs of blocks per thread, each with its own buffers; with no threads the one
        // run is decoded here, as OpenEXR does.
        const std::size_t runs =
            std::min(blockCount, std::size_t(std::max(1, 4 * Imf::globalThreadCount())));
        IlmThread::TaskGroup group;  // its destructor waits for the tasks
        for (std::size_t r = 0; r < runs; ++r)
            IlmThread::ThreadPool::addGlobalTask(
                new DecodeTask(&group, blocks, r * blockCount / runs, (r + 1) * blockCount / runs,
                               std::size_t(lineBytes), channels, chosen, image, failed));
    }
    if (failed.load()) return std::nullopt;
    return image;
}

}  // namespace rtd::io_detail
