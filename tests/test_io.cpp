// Known-answer tests of the I/O layer: EXR, .mat, sequence discovery and validation, tone
// mapping, PNG, video. Each error test checks the error code and that the message names the file.
#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfInputFile.h>
#include <ImfOutputFile.h>
#include <gtest/gtest.h>
#include <png.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <limits>
#include <string>
#include <thread>
#include <vector>

#include "io/atomic_file.h"
#include "io/exr_blocks.h"
#include "rtdenoise/error.h"
#include "rtdenoise/image.h"
#include "rtdenoise/io.h"

namespace fs = std::filesystem;
using rtd::Error;
using rtd::ErrorCode;
using rtd::Image;
using rtd::Matrix4;

namespace {

const std::vector<std::vector<std::string>> kRgb = {{"R"}, {"G"}, {"B"}};

// A fresh folder per test, removed afterwards.
class TempDir {
  public:
    TempDir() {
        static std::atomic<int> counter{0};
        path_ = fs::temp_directory_path() /
                ("rtd_test_io_" + std::to_string(::getpid()) + "_" + std::to_string(counter++));
        fs::remove_all(path_);
        fs::create_directories(path_);
    }
    ~TempDir() {
        std::error_code ec;
        fs::permissions(path_, fs::perms::owner_all, fs::perm_options::add, ec);
        fs::remove_all(path_, ec);
    }
    const fs::path& path() const { return path_; }
    fs::path operator/(const std::string& name) const { return path_ / name; }
    // Names in the folder, to check that no temporary file was left behind.
    std::vector<std::string> names() const {
        std::vector<std::string> out;
        for (const auto& entry : fs::directory_iterator(path_)) {
            out.push_back(entry.path().filename().string());
        }
        std::sort(out.begin(), out.end());
        return out;
    }

  private:
    fs::path path_;
};

// Runs `body`, expects an rtd::Error with `code` whose message contains every `parts` entry.
void expectError(const std::function<void()>& body, ErrorCode code,
                 const std::vector<std::string>& parts) {
    try {
        body();
        ADD_FAILURE() << "no exception";
    } catch (const Error& e) {
        EXPECT_EQ(static_cast<int>(e.code()), static_cast<int>(code)) << e.what();
        for (const auto& part : parts) {
            EXPECT_NE(std::string(e.what()).find(part), std::string::npos)
                << "message '" << e.what() << "' lacks '" << part << "'";
        }
    }
}

Image patternImage(int width, int height, int channels, float seed) {
    Image image(width, height, channels);
    for (std::size_t i = 0; i < image.pixels.size(); ++i) {
        // Multiples of 1/64: exact in float, so no rounding (or contraction) can differ.
        image.pixels[i] = seed + float(i % 97) / 64.0f - float(i % 13);
    }
    return image;
}

std::string readBytes(const fs::path& file) {
    std::ifstream in(file, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

void writeBytes(const fs::path& file, const std::string& bytes) {
    std::ofstream out(file, std::ios::binary);
    out.write(bytes.data(), std::streamsize(bytes.size()));
}

void appendLe32(std::string& out, std::uint32_t value) {
    for (int i = 0; i < 4; ++i) out += char((value >> (8 * i)) & 0xff);
}

// The .mat layout, written independently of the reader.
std::string matBytes(std::int32_t count, const std::vector<Matrix4>& matrices) {
    std::string out;
    appendLe32(out, std::uint32_t(count));
    for (const auto& matrix : matrices) {
        for (const auto& row : matrix.m) {
            for (float v : row) {
                std::uint32_t bits;
                std::memcpy(&bits, &v, 4);
                appendLe32(out, bits);
            }
        }
    }
    return out;
}

Matrix4 numbered(float base) {
    Matrix4 m;
    for (int r = 0; r < 4; ++r) {
        for (int c = 0; c < 4; ++c) m.m[r][c] = base + float(4 * r + c);
    }
    return m;
}

// K object matrices numbered from 100, then world-to-camera (200) and world-to-screen (300).
void writeMat(const fs::path& file, int objectCount) {
    std::vector<Matrix4> matrices;
    for (int k = 0; k < objectCount; ++k) matrices.push_back(numbered(100.0f + 16.0f * float(k)));
    matrices.push_back(numbered(200.0f));
    matrices.push_back(numbered(300.0f));
    writeBytes(file, matBytes(objectCount, matrices));
}

// A course-layout folder of `frames` frames of width x height with K objects; ID(x, y) is
// (x + y) % K, except pixel (0, 0), which is background (-1).
void writeSequence(const fs::path& folder, int frames, int width, int height, int objectCount) {
    for (int i = 0; i < frames; ++i) {
        const std::string n = std::to_string(i);
        rtd::writeExr(folder / ("beauty_" + n + ".exr"), patternImage(width, height, 3, float(i)));
        rtd::writeExr(folder / ("normal_" + n + ".exr"), patternImage(width, height, 3, 2.0f));
        rtd::writeExr(folder / ("position_" + n + ".exr"), patternImage(width, height, 3, 3.0f));
        rtd::writeExr(folder / ("depth_" + n + ".exr"), patternImage(width, height, 1, 4.0f));
        Image ids(width, height, 1);
        for (int y = 0; y < height; ++y) {
            for (int x = 0; x < width; ++x) ids.at(x, y) = float((x + y) % objectCount);
        }
        ids.at(0, 0) = -1.0f;
        rtd::writeExr(folder / ("ID_" + n + ".exr"), ids);
        writeMat(folder / ("matrix_" + n + ".mat"), objectCount);
    }
}

// Writes an EXR with OpenEXR directly: channels of the given names and types, data window at
// (originX, originY); channel c of pixel i holds value(c, i).
void writeCustomExr(const fs::path& file,
                    const std::vector<std::pair<std::string, Imf::PixelType>>& channels, int width,
                    int height, int originX, int originY, Imf::Compression compression,
                    const std::function<float(int, int)>& value) {
    Imath::Box2i window(Imath::V2i(originX, originY),
                        Imath::V2i(originX + width - 1, originY + height - 1));
    Imf::Header header(Imath::Box2i(Imath::V2i(0, 0), Imath::V2i(63, 63)), window);
    header.compression() = compression;
    const std::size_t count = std::size_t(width) * height;
    std::vector<std::vector<half>> halves(channels.size(), std::vector<half>(count));
    std::vector<std::vector<float>> floats(channels.size(), std::vector<float>(count));
    std::vector<std::vector<unsigned>> uints(channels.size(), std::vector<unsigned>(count));
    Imf::FrameBuffer frameBuffer;
    for (std::size_t c = 0; c < channels.size(); ++c) {
        const auto& [name, type] = channels[c];
        header.channels().insert(name, Imf::Channel(type));
        for (std::size_t i = 0; i < count; ++i) {
            const float v = value(int(c), int(i));
            halves[c][i] = half(v);
            floats[c][i] = v;
            if (type == Imf::UINT) uints[c][i] = unsigned(v);  // (negative: undefined)
        }
        void* base = type == Imf::HALF    ? static_cast<void*>(halves[c].data())
                     : type == Imf::FLOAT ? static_cast<void*>(floats[c].data())
                                          : static_cast<void*>(uints[c].data());
        const std::size_t size = type == Imf::HALF ? 2 : 4;
        frameBuffer.insert(name, Imf::Slice::Make(type, base, window, size, size * width));
    }
    Imf::OutputFile out(file.c_str(), header);
    out.setFrameBuffer(frameBuffer);
    out.writePixels(height);
}

std::array<float, 4> transform(const Matrix4& m, float x, float y, float z) {
    std::array<float, 4> out{};
    for (int r = 0; r < 4; ++r) out[r] = m.m[r][0] * x + m.m[r][1] * y + m.m[r][2] * z + m.m[r][3];
    return out;
}

}  // namespace

// ---- EXR ----

TEST(Exr, RoundTripIsExact) {
    TempDir dir;
    Image rgb = patternImage(7, 5, 3, -2.5f);
    rgb.pixels[4] = 1e-30f;  // tiny and huge floats survive FLOAT + ZIP unchanged
    rgb.pixels[5] = 3.4e38f;
    rtd::writeExr(dir / "rgb.exr", rgb);
    const Image back = rtd::readExr(dir / "rgb.exr", kRgb);
    EXPECT_EQ(back.width, 7);
    EXPECT_EQ(back.height, 5);
    EXPECT_EQ(back.channels, 3);
    EXPECT_EQ(back.pixels, rgb.pixels);

    const Image gray = patternImage(3, 4, 1, 0.25f);
    rtd::writeExr(dir / "gray.exr", gray);
    EXPECT_EQ(rtd::readExr(dir / "gray.exr", {{"Y"}}).pixels, gray.pixels);
    // Only the finished files: the temporary names were renamed away.
    EXPECT_EQ(dir.names(), (std::vector<std::string>{"gray.exr", "rgb.exr"}));
}

TEST(Exr, ThreadedCompressionGivesTheSameFile) {
    // Many ZIP blocks (16 rows each), so OpenEXR's threads really share the work.
    TempDir dir;
    Image rgb = patternImage(64, 100, 3, -1.0f);
    const rtd::ExrWriteOptions zip{rtd::ExrCompression::Zip};
    rtd::writeExr(dir / "serial.exr", rgb, zip);
    rtd::setExrThreads(3);
    rtd::writeExr(dir / "threaded.exr", rgb, zip);
    const Image back = rtd::readExr(dir / "threaded.exr", kRgb);
    rtd::setExrThreads(0);
    EXPECT_EQ(back.pixels, rgb.pixels);
    auto bytes = [](const std::filesystem::path& f) {
        std::ifstream in(f, std::ios::binary);
        return std::string(std::istreambuf_iterator<char>(in), {});
    };
    EXPECT_EQ(bytes(dir / "threaded.exr"), bytes(dir / "serial.exr"));
}

// What each compression gives back: lossless ones the values written (bit-exact; with --half the
// half-rounded values), lossy ones within the stated tolerance; the direct block reader and
// OpenEXR's own agree on every file.
TEST(Exr, EveryCompressionRoundTrips) {
    TempDir dir;
    // Odd sizes (a last ZIP block of 5 lines, lines of odd byte counts in HALF) and a smooth
    // image with values of every magnitude in [0.01, 2], as a denoised frame.
    Image image(61, 37, 3);
    for (int y = 0; y < image.height; ++y)
        for (int x = 0; x < image.width; ++x)
            for (int c = 0; c < 3; ++c)
                image.pixels[(std::size_t(y) * image.width + x) * 3 + c] =
                    0.01f +
                    (1.0f + std::sin(0.11f * float(x) + float(c)) * std::cos(0.07f * float(y))) *
                        (0.4f + 0.3f * float(c));
    ASSERT_EQ(rtd::exrCompressions().size(), 10u);
    for (rtd::ExrCompression compression : rtd::exrCompressions()) {
        for (bool halfChannels : {false, true}) {
            SCOPED_TRACE(std::string(rtd::toString(compression)) +
                         (halfChannels ? " half" : " float"));
            const fs::path file = dir / (std::string(rtd::toString(compression)) + ".exr");
            rtd::writeExr(file, image, {compression, halfChannels});
            const Image back = rtd::readExr(file, kRgb);
            EXPECT_EQ(back.pixels, rtd::io_detail::readExrWithOpenExr(file, kRgb).pixels);
            ASSERT_EQ(back.pixels.size(), image.pixels.size());
            double maxOfRange = 0.0, maxOfValue = 0.0;  // errors over the range 2, the value
            std::size_t differing = 0;
            for (std::size_t i = 0; i < image.pixels.size(); ++i) {
                const float written = halfChannels ? float(half(image.pixels[i])) : image.pixels[i];
                const double error = std::abs(double(back.pixels[i]) - written);
                differing += back.pixels[i] != written;
                maxOfRange = std::max(maxOfRange, error / 2.0);
                maxOfValue = std::max(maxOfValue, error / std::abs(written));
            }
            if (rtd::isLossless(compression, halfChannels)) {
                EXPECT_EQ(differing, 0u) << "max error " << maxOfRange << " of the range";
            } else if (compression == rtd::ExrCompression::Pxr24) {
                // pxr24 rounds float to 15 mantissa bits: within 2^-16 of each value.
                EXPECT_GT(differing, 0u) << "called lossy, but gave every value back";
                EXPECT_LE(maxOfValue, std::ldexp(1.0, -16));
            } else {
                // b44 and dwa quantise blocks of halves (4x4, 8x8): within 1 % of the range on
                // this smooth image (0.2 % and 0.63 % measured).
                EXPECT_GT(differing, 0u) << "called lossy, but gave every value back";
                EXPECT_LT(maxOfRange, 0.01);
            }
        }
    }
}

// --half: the file's channels are HALF, and what is read back is each value rounded to the
// nearest half (65504 is the largest; beyond it, infinity).
TEST(Exr, HalfWritesHalfChannels) {
    TempDir dir;
    Image rgb = patternImage(5, 4, 3, 0.1f);
    rgb.pixels[0] = 0.1f;  // not a half: 0.0999755859375 comes back
    rgb.pixels[1] = 65504.0f;
    rgb.pixels[2] = 1e6f;
    rgb.pixels[3] = -2e-8f;  // nearer 0 than the smallest subnormal half, 2^-24: -0
    const fs::path file = dir / "half.exr";
    rtd::writeExr(file, rgb, {rtd::ExrCompression::Zip, true});
    {
        Imf::InputFile input(file.c_str());
        for (const char* name : {"R", "G", "B"}) {
            ASSERT_NE(input.header().channels().findChannel(name), nullptr) << name;
            EXPECT_EQ(input.header().channels().findChannel(name)->type, Imf::HALF) << name;
        }
        EXPECT_EQ(input.header().compression(), Imf::ZIP_COMPRESSION);
    }
    const Image back = rtd::readExr(file, kRgb);
    ASSERT_EQ(back.pixels.size(), rgb.pixels.size());
    for (std::size_t i = 0; i < rgb.pixels.size(); ++i)
        EXPECT_EQ(back.pixels[i], float(half(rgb.pixels[i]))) << i;
    EXPECT_EQ(back.pixels[0], 0.0999755859375f);
    EXPECT_EQ(back.pixels[1], 65504.0f);
    EXPECT_EQ(back.pixels[2], std::numeric_limits<float>::infinity());
    EXPECT_TRUE(back.pixels[3] == 0.0f && std::signbit(back.pixels[3]));
    // The default: FLOAT channels, uncompressed.
    rtd::writeExr(file, rgb);
    Imf::InputFile input(file.c_str());
    EXPECT_EQ(input.header().channels().findChannel("R")->type, Imf::FLOAT);
    EXPECT_EQ(input.header().compression(), Imf::NO_COMPRESSION);
}

TEST(Exr, CompressionNamesAndChoices) {
    for (rtd::ExrCompression compression : rtd::exrCompressions())
        EXPECT_EQ(rtd::exrCompressionNamed(rtd::toString(compression)), compression);
    EXPECT_EQ(rtd::exrCompressionNamed("ZIP"), rtd::ExrCompression::Zip);
    expectError([] { rtd::exrCompressionNamed("lzma"); }, ErrorCode::InvalidArgument,
                {"'lzma'", "'none'", "'rle'", "'zips'", "'zip'", "'piz'", "'pxr24'", "'b44'",
                 "'b44a'", "'dwaa'", "'dwab'"});
}

// The direct reader of none/zips/zip scan-line files gives what OpenEXR gives, for the layouts
// OpenEXR writes: any channel types and names, an offset data window, either line order.
TEST(Exr, DirectReaderAgreesWithOpenExr) {
    TempDir dir;
    const auto value = [](int c, int i) {
        return c == 3 ? float(i * 7 % 1000) : 0.37f * float(i % 41) - 3.0f + float(c);
    };
    const std::vector<std::pair<std::string, Imf::PixelType>> channels = {
        {"R", Imf::FLOAT}, {"G", Imf::HALF}, {"B", Imf::FLOAT}, {"N", Imf::UINT}};
    const std::vector<std::vector<std::string>> chosen = {{"R"}, {"G"}, {"B"}, {"N"}, {"R"}};
    int handled = 0;
    for (Imf::Compression compression :
         {Imf::NO_COMPRESSION, Imf::ZIPS_COMPRESSION, Imf::ZIP_COMPRESSION}) {
        for (int width : {1, 17, 64}) {
            const fs::path file = dir / "custom.exr";
            writeCustomExr(file, channels, width, 35, -3, 7, compression, value);
            const auto direct = rtd::io_detail::readExrBlocks(file, chosen);
            ASSERT_TRUE(direct.has_value()) << compression << " " << width;
            ++handled;
            const Image reference = rtd::io_detail::readExrWithOpenExr(file, chosen);
            EXPECT_EQ(direct->width, reference.width);
            EXPECT_EQ(direct->height, reference.height);
            EXPECT_EQ(direct->pixels, reference.pixels) << compression << " " << width;
        }
    }
    EXPECT_EQ(handled, 9);
    // Decreasing line order: the blocks lie bottom up, the offset table is still top down.
    const fs::path file = dir / "decreasing.exr";
    {
        Imf::Header header(19, 40);
        header.compression() = Imf::ZIP_COMPRESSION;
        header.lineOrder() = Imf::DECREASING_Y;
        header.channels().insert("Y", Imf::Channel(Imf::FLOAT));
        std::vector<float> values(19 * 40);
        for (std::size_t i = 0; i < values.size(); ++i) values[i] = float(i) * 0.5f;
        Imf::FrameBuffer frameBuffer;
        frameBuffer.insert("Y", Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(values.data()),
                                           sizeof(float), sizeof(float) * 19));
        Imf::OutputFile out(file.c_str(), header);
        out.setFrameBuffer(frameBuffer);
        out.writePixels(40);
    }
    const auto direct = rtd::io_detail::readExrBlocks(file, {{"Y"}});
    ASSERT_TRUE(direct.has_value());
    EXPECT_EQ(direct->pixels, rtd::io_detail::readExrWithOpenExr(file, {{"Y"}}).pixels);
    EXPECT_EQ(direct->pixels[19 * 40 - 1], float(19 * 40 - 1) * 0.5f);
    // Other compressions are OpenEXR's to read.
    writeCustomExr(file, channels, 8, 8, 0, 0, Imf::PIZ_COMPRESSION, value);
    EXPECT_FALSE(rtd::io_detail::readExrBlocks(file, chosen).has_value());
}

// The direct writer of uncompressed files writes what OpenEXR's writer writes, byte for byte.
TEST(Exr, UncompressedFilesAreOpenExrsBytes) {
    TempDir dir;
    for (int channels : {3, 1}) {
        for (bool halfChannels : {false, true}) {
            SCOPED_TRACE(std::to_string(channels) + (halfChannels ? " half" : " float"));
            const Image image = patternImage(13, 7, channels, -0.3f);
            rtd::writeExr(dir / "direct.exr", image, {rtd::ExrCompression::None, halfChannels});

            Imf::Header header(image.width, image.height, 1.0f, Imath::V2f(0, 0), 1.0f,
                               Imf::INCREASING_Y, Imf::NO_COMPRESSION);
            const std::vector<std::string> names = channels == 3
                                                       ? std::vector<std::string>{"R", "G", "B"}
                                                       : std::vector<std::string>{"Y"};
            std::vector<half> halves(image.pixels.begin(), image.pixels.end());
            Imf::FrameBuffer frameBuffer;
            for (int c = 0; c < channels; ++c) {
                header.channels().insert(names[c],
                                         Imf::Channel(halfChannels ? Imf::HALF : Imf::FLOAT));
                char* base =
                    halfChannels
                        ? reinterpret_cast<char*>(halves.data() + c)
                        : reinterpret_cast<char*>(const_cast<float*>(image.pixels.data() + c));
                const std::size_t size = halfChannels ? 2 : 4;
                frameBuffer.insert(names[c],
                                   Imf::Slice(halfChannels ? Imf::HALF : Imf::FLOAT, base,
                                              size * channels, size * channels * image.width));
            }
            {
                Imf::OutputFile out((dir / "openexr.exr").c_str(), header);
                out.setFrameBuffer(frameBuffer);
                out.writePixels(image.height);
            }
            EXPECT_EQ(readBytes(dir / "direct.exr"), readBytes(dir / "openexr.exr"));
        }
    }
}

// A ZIP block whose deflate stream is corrupt is not the direct reader's to report: readExr
// fails as OpenEXR does, naming the file.
TEST(Exr, CorruptBlockIsReportedByOpenExr) {
    TempDir dir;
    const fs::path file = dir / "corrupt.exr";
    Image image = patternImage(64, 64, 3, 0.5f);
    for (std::size_t i = 0; i < image.pixels.size(); ++i) image.pixels[i] += 1e-4f * float(i % 7);
    rtd::writeExr(file, image, {rtd::ExrCompression::Zip});
    std::string bytes = readBytes(file);
    for (std::size_t i = bytes.size() - 2000; i < bytes.size() - 1000; ++i) bytes[i] = char(0x5a);
    writeBytes(file, bytes);
    EXPECT_FALSE(rtd::io_detail::readExrBlocks(file, kRgb).has_value());
    expectError([&] { rtd::readExr(file, kRgb); }, ErrorCode::IoFailure, {file.string()});
}

// ZIP's byte transforms against their plain definitions, at lengths that take the 16-byte steps
// and every tail.
TEST(Exr, ZipPredictorAndInterleaveMatchTheirDefinitions) {
    for (std::size_t count = 0; count < 80; ++count) {
        std::vector<unsigned char> bytes(count);
        for (std::size_t i = 0; i < count; ++i) bytes[i] = static_cast<unsigned char>(i * 97 + 13);
        std::vector<unsigned char> expected = bytes;
        for (std::size_t i = 1; i < count; ++i)
            expected[i] = static_cast<unsigned char>(expected[i - 1] + expected[i] - 128);
        rtd::io_detail::undoZipPredictor(bytes.data(), count);
        EXPECT_EQ(bytes, expected) << count;

        std::vector<unsigned char> interleaved(count), reference(count);
        for (std::size_t i = 0, first = 0, second = (count + 1) / 2; i < count; ++i)
            reference[i] = i % 2 ? expected[second++] : expected[first++];
        rtd::io_detail::interleaveHalves(expected.data(), count, interleaved.data());
        EXPECT_EQ(interleaved, reference) << count;
    }
}

TEST(Exr, ReadsHalfChannelsWithOffsetDataWindow) {
    TempDir dir;
    const auto value = [](int c, int i) { return 0.1f * float(i) + 10.0f * float(c); };
    writeCustomExr(dir / "half.exr", {{"R", Imf::HALF}, {"G", Imf::HALF}, {"B", Imf::HALF}}, 4, 3,
                   10, 20, Imf::PIZ_COMPRESSION, value);
    const Image image = rtd::readExr(dir / "half.exr", kRgb);
    ASSERT_EQ(image.width, 4);
    ASSERT_EQ(image.height, 3);
    for (int i = 0; i < 12; ++i) {
        for (int c = 0; c < 3; ++c) {
            // The half value, not the float it was made from.
            EXPECT_EQ(image.pixels[i * 3 + c], float(half(value(c, i)))) << i << " " << c;
        }
    }
    EXPECT_NE(float(half(0.1f)), 0.1f);  // the check above does tell half from float
}

TEST(Exr, FindsChannelsByNameAmongOthers) {
    TempDir dir;
    // Stored order is alphabetical (B, G, R, ...) whatever the insertion order; extra channels.
    const auto value = [](int c, int i) { return float(100 * c + i); };
    writeCustomExr(dir / "many.exr",
                   {{"Z", Imf::FLOAT},
                    {"B", Imf::HALF},
                    {"A", Imf::FLOAT},
                    {"R", Imf::FLOAT},
                    {"G", Imf::FLOAT},
                    {"N", Imf::UINT}},
                   3, 2, 0, 0, Imf::NO_COMPRESSION, value);
    const Image rgb = rtd::readExr(dir / "many.exr", kRgb);
    for (int i = 0; i < 6; ++i) {
        EXPECT_EQ(rgb.pixels[i * 3 + 0], float(300 + i));  // R was the 4th channel written
        EXPECT_EQ(rgb.pixels[i * 3 + 1], float(400 + i));
        EXPECT_EQ(rgb.pixels[i * 3 + 2], float(100 + i));
    }
    // First match wins: no Y, so Z; a UINT channel comes back as float.
    const Image scalar = rtd::readExr(dir / "many.exr", {{"Y", "Z", "R"}, {"N"}, {"Z"}});
    ASSERT_EQ(scalar.channels, 3);
    for (int i = 0; i < 6; ++i) {
        EXPECT_EQ(scalar.pixels[i * 3 + 0], float(i));
        EXPECT_EQ(scalar.pixels[i * 3 + 1], float(500 + i));
        EXPECT_EQ(scalar.pixels[i * 3 + 2], float(i));  // the same channel twice
    }
}

TEST(Exr, MissingChannelNamesFileAndItsChannels) {
    TempDir dir;
    const fs::path file = dir / "depth.exr";
    rtd::writeExr(file, Image(2, 2, 1, 1.0f));
    expectError([&] { rtd::readExr(file, kRgb); }, ErrorCode::InvalidInput,
                {file.string(), "missing channel 'R'", "(has: Y)"});
    expectError(
        [&] {
            rtd::readExr(file, {{"Z", "R"}});
        },
        ErrorCode::InvalidInput, {file.string(), "'Z' or 'R'", "(has: Y)"});
}

TEST(Exr, TruncatedOrForeignFileIsIoFailure) {
    TempDir dir;
    const fs::path file = dir / "cut.exr";
    rtd::writeExr(file, patternImage(64, 64, 3, 0.0f));
    const std::string bytes = readBytes(file);
    writeBytes(file, bytes.substr(0, bytes.size() / 2));
    expectError([&] { rtd::readExr(file, kRgb); }, ErrorCode::IoFailure, {file.string()});

    const fs::path text = dir / "text.exr";
    writeBytes(text, "this is not an EXR file at all");
    expectError([&] { rtd::readExr(text, kRgb); }, ErrorCode::IoFailure, {text.string()});

    expectError([&] { rtd::readExr(dir / "none.exr", kRgb); }, ErrorCode::MissingFile,
                {(dir / "none.exr").string()});
}

TEST(Exr, WriteIntoMissingFolderFailsCleanly) {
    TempDir dir;
    const fs::path file = dir / "no" / "such" / "out.exr";
    expectError([&] { rtd::writeExr(file, Image(2, 2, 3)); }, ErrorCode::IoFailure,
                {file.string()});
    EXPECT_TRUE(dir.names().empty());
    expectError([&] { rtd::writeExr(dir / "two.exr", Image(2, 2, 2)); }, ErrorCode::InvalidArgument,
                {"two.exr"});
}

// ---- .mat ----

// A header that claims a huge image fails naming the file and the claimed size, before
// anything is allocated for it (it used to end in std::bad_alloc).
TEST(Exr, HeaderClaimingAHugeImageNamesTheClaimedSize) {
    TempDir dir;
    const fs::path file = dir / "huge.exr";
    rtd::writeExr(file, patternImage(8, 8, 3, 0.0f));
    std::string bytes = readBytes(file);
    // dataWindow: name, type "box2i", int32 size 16, then xMin yMin xMax yMax.
    const std::string attribute("dataWindow\0box2i\0", 17);
    const std::size_t at = bytes.find(attribute);
    ASSERT_NE(at, std::string::npos);
    const auto claim = [&](std::uint32_t width, std::uint32_t height) {
        std::string patched = bytes;
        std::string box;
        for (std::uint32_t v : {0u, 0u, width - 1, height - 1}) appendLe32(box, v);
        patched.replace(at + attribute.size() + 4, 16, box);
        writeBytes(file, patched);
    };
    claim(100000, 100000);
    expectError([&] { rtd::readExr(file, kRgb); }, ErrorCode::InvalidInput,
                {file.string(), "claims a 100000x100000 image"});
    expectError([&] { rtd::readExrSize(file, kRgb); }, ErrorCode::InvalidInput,
                {file.string(), "100000x100000"});
    // Under the maximum, but more blocks than the file has room for.
    claim(4000, 4000);
    expectError([&] { rtd::readExr(file, kRgb); }, ErrorCode::InvalidInput,
                {file.string(), "claims a 4000x4000 image", "truncated or corrupt"});
    claim(8, 8);
    EXPECT_EQ(rtd::readExrSize(file, kRgb).width, 8);
}

// After a test that abandons (files may no more be created), lets them be created again however
// it ends (an early return, a failed assertion): the other tests of this process write files.
struct CreationAllowedAgainAtEnd {
    ~CreationAllowedAgainAtEnd() { rtd::io_detail::allowCreationAgain(); }
};

// A signal handler's clean-up: every live temporary file goes, and an unfinished video's
// ffmpeg is killed (no process left writing into the folder).
TEST(Exr, AbandonTemporaryFilesRemovesLiveTemporaries) {
    CreationAllowedAgainAtEnd allowAgain;
    TempDir dir;
    const fs::path kept = dir / "kept.exr";
    rtd::writeExr(kept, patternImage(4, 4, 3, 0.0f));  // committed: no longer a temporary
    {
        rtd::io_detail::TemporaryFile temporary(dir / ".x.exr.tmp-1-1");
        writeBytes(temporary.path(), "partial");
        rtd::abandonTemporaryFiles();
        EXPECT_FALSE(fs::exists(temporary.path()));
    }
    EXPECT_TRUE(fs::exists(kept));
    if (!rtd::VideoWriter::ffmpegAvailable()) return;
    rtd::VideoWriter writer(dir / "v.mp4", 64, 64);
    writer.addFrame(Image(64, 64, 3, 0.5f));
    rtd::abandonTemporaryFiles();
    EXPECT_EQ(dir.names(), std::vector<std::string>{"kept.exr"});
    expectError([&] { writer.finish(); }, ErrorCode::IoFailure, {(dir / "v.mp4").string()});
    EXPECT_FALSE(fs::exists(dir / "v.mp4"));
}

// Once the clean-up has begun, a writer creates nothing: its write fails naming the file, and
// neither the file nor a temporary appears (the race: a path unlinked just before its writer
// created it).
TEST(Exr, NothingIsCreatedAfterTheCleanUpBegan) {
    CreationAllowedAgainAtEnd allowAgain;
    TempDir dir;
    rtd::abandonTemporaryFiles();
    expectError([&] { rtd::writeExr(dir / "late.exr", patternImage(4, 4, 3, 0.0f)); },
                ErrorCode::IoFailure, {(dir / "late.exr").string(), "interrupted"});
    expectError([&] { rtd::writePng(dir / "late.png", patternImage(4, 4, 3, 0.5f)); },
                ErrorCode::IoFailure, {(dir / "late.png").string(), "interrupted"});
    EXPECT_TRUE(dir.names().empty());
    rtd::io_detail::allowCreationAgain();
    rtd::writeExr(dir / "again.exr", patternImage(4, 4, 3, 0.0f));
    EXPECT_EQ(dir.names(), std::vector<std::string>{"again.exr"});
}

// The clean-up waits for a file being created (up to a second) and then removes it.
TEST(Exr, TheCleanUpWaitsForAFileBeingCreated) {
    CreationAllowedAgainAtEnd allowAgain;
    TempDir dir;
    const fs::path path = dir / ".x.exr.tmp-1-2";
    rtd::io_detail::TemporaryFile temporary(path);
    std::atomic<bool> cleaned{false};
    {
        rtd::io_detail::FileCreation creation(path);
        std::thread cleanUp([&] {
            rtd::abandonTemporaryFiles();
            cleaned = true;
        });
        std::this_thread::sleep_for(std::chrono::milliseconds(100));
        EXPECT_FALSE(cleaned.load());  // still waiting for the creation
        writeBytes(path, "partial");
        creation.finish();
        cleanUp.join();
    }
    EXPECT_TRUE(cleaned.load());
    EXPECT_FALSE(fs::exists(path));
}

TEST(Matrix, RoundTrip) {
    TempDir dir;
    writeMat(dir / "m.mat", 3);
    const rtd::MatrixFile read = rtd::readMatrixFile(dir / "m.mat");
    ASSERT_EQ(read.objectToWorld.size(), 3u);
    for (int k = 0; k < 3; ++k)
        EXPECT_EQ(read.objectToWorld[k].m, numbered(100.0f + 16.0f * float(k)).m);
    EXPECT_EQ(read.worldToCamera.m, numbered(200.0f).m);
    EXPECT_EQ(read.worldToScreen.m, numbered(300.0f).m);
    EXPECT_EQ(read.worldToScreen.m[1][2], 306.0f);  // row-major: m[row][col] = base + 4 row + col

    writeMat(dir / "zero.mat", 0);
    EXPECT_TRUE(rtd::readMatrixFile(dir / "zero.mat").objectToWorld.empty());
}

TEST(Matrix, BadFilesNameTheFile) {
    TempDir dir;
    const fs::path missing = dir / "missing.mat";
    expectError([&] { rtd::readMatrixFile(missing); }, ErrorCode::MissingFile, {missing.string()});

    const fs::path shortFile = dir / "short.mat";
    writeBytes(shortFile, std::string("\x01\x00", 2));
    expectError([&] { rtd::readMatrixFile(shortFile); }, ErrorCode::InvalidInput,
                {shortFile.string()});

    const fs::path negative = dir / "negative.mat";
    writeBytes(negative, matBytes(-1, {numbered(0), numbered(0)}));
    expectError([&] { rtd::readMatrixFile(negative); }, ErrorCode::InvalidInput,
                {negative.string(), "-1"});

    // K = 3 announced, matrices for K = 2 present: 4 + 5*64 = 324 expected, 260 found.
    const fs::path mismatch = dir / "mismatch.mat";
    writeBytes(mismatch, matBytes(3, {numbered(0), numbered(0), numbered(0), numbered(0)}));
    expectError([&] { rtd::readMatrixFile(mismatch); }, ErrorCode::InvalidInput,
                {mismatch.string(), "324", "260"});

    // A whole file cut short is a size mismatch too.
    const fs::path truncated = dir / "truncated.mat";
    writeMat(truncated, 2);
    writeBytes(truncated, readBytes(truncated).substr(0, 100));
    expectError([&] { rtd::readMatrixFile(truncated); }, ErrorCode::InvalidInput,
                {truncated.string(), "260", "100"});

    const fs::path nan = dir / "nan.mat";
    Matrix4 bad = numbered(0);
    bad.m[2][3] = std::numeric_limits<float>::quiet_NaN();
    writeBytes(nan, matBytes(0, {numbered(0), bad}));
    expectError([&] { rtd::readMatrixFile(nan); }, ErrorCode::InvalidInput,
                {nan.string(), "non-finite"});
}

// ---- sequences ----

TEST(Sequence, DiscoversFramesAndReadsThem) {
    TempDir dir;
    writeSequence(dir.path(), 3, 5, 4, 3);
    writeBytes(dir / "notes.txt", "ignored");
    writeBytes(dir / "beauty_x.exr", "ignored: not a frame number");
    const rtd::Sequence sequence(dir.path());
    EXPECT_EQ(sequence.frameCount(), 3);
    EXPECT_EQ(sequence.folder(), dir.path());

    const rtd::Frame frame = sequence.readFrame(2);
    EXPECT_EQ(frame.width(), 5);
    EXPECT_EQ(frame.height(), 4);
    EXPECT_EQ(frame.beauty.pixels, patternImage(5, 4, 3, 2.0f).pixels);
    EXPECT_EQ(frame.normal.pixels, patternImage(5, 4, 3, 2.0f).pixels);
    EXPECT_EQ(frame.position.pixels, patternImage(5, 4, 3, 3.0f).pixels);
    EXPECT_EQ(frame.depth.channels, 1);
    EXPECT_EQ(frame.depth.pixels, patternImage(5, 4, 1, 4.0f).pixels);
    ASSERT_EQ(frame.objectId.size(), 20u);
    EXPECT_EQ(frame.objectId[0], -1);
    EXPECT_EQ(frame.objectId[1], 1);
    EXPECT_EQ(frame.objectId[5 * 3 + 4], (4 + 3) % 3);
    ASSERT_EQ(frame.objectToWorld.size(), 3u);
    EXPECT_EQ(frame.objectToWorld[2].m, numbered(132.0f).m);
    EXPECT_EQ(frame.worldToCamera.m, numbered(200.0f).m);
    EXPECT_EQ(frame.worldToScreen.m, numbered(300.0f).m);
    EXPECT_FALSE(frame.albedo.has_value());

    expectError([&] { sequence.readFrame(3); }, ErrorCode::InvalidArgument, {"3"});
}

TEST(Sequence, ReadsOptionalAlbedo) {
    TempDir dir;
    writeSequence(dir.path(), 2, 4, 3, 2);
    const Image albedo = patternImage(4, 3, 3, 0.5f);
    rtd::writeExr(dir / "albedo_1.exr", albedo);
    const rtd::Sequence sequence(dir.path());
    EXPECT_FALSE(sequence.readFrame(0).albedo.has_value());
    const rtd::Frame frame = sequence.readFrame(1);
    ASSERT_TRUE(frame.albedo.has_value());
    EXPECT_EQ(frame.albedo->pixels, albedo.pixels);

    rtd::writeExr(dir / "albedo_0.exr", patternImage(3, 3, 3, 0.5f));
    expectError([&] { sequence.readFrame(0); }, ErrorCode::InvalidInput,
                {(dir / "albedo_0.exr").string(), "3x3", "4x3"});
}

TEST(Sequence, FolderProblems) {
    TempDir dir;
    const fs::path missing = dir / "nowhere";
    expectError([&] { rtd::Sequence s(missing); }, ErrorCode::MissingFile, {missing.string()});

    const fs::path file = dir / "file";
    writeBytes(file, "x");
    expectError([&] { rtd::Sequence s(file); }, ErrorCode::MissingFile, {file.string()});

    const fs::path empty = dir / "empty";
    fs::create_directories(empty);
    expectError([&] { rtd::Sequence s(empty); }, ErrorCode::MissingFile, {empty.string()});
}

TEST(Sequence, GapInNumberingNamesFirstMissingFrame) {
    TempDir dir;
    writeSequence(dir.path(), 6, 2, 2, 1);
    fs::remove(dir / "beauty_2.exr");
    fs::remove(dir / "beauty_4.exr");
    expectError([&] { rtd::Sequence s(dir.path()); }, ErrorCode::InvalidInput,
                {(dir / "beauty_2.exr").string() + " is missing", "0..1, 3 and 5"});

    fs::remove(dir / "beauty_0.exr");
    expectError([&] { rtd::Sequence s(dir.path()); }, ErrorCode::InvalidInput,
                {(dir / "beauty_0.exr").string() + " is missing"});
}

TEST(Sequence, MissingBufferNamesTheFile) {
    TempDir dir;
    writeSequence(dir.path(), 2, 3, 3, 2);
    fs::remove(dir / "depth_1.exr");
    const rtd::Sequence sequence(dir.path());
    EXPECT_NO_THROW(sequence.readFrame(0));
    expectError([&] { sequence.readFrame(1); }, ErrorCode::MissingFile,
                {(dir / "depth_1.exr").string()});

    fs::remove(dir / "matrix_0.mat");
    expectError([&] { sequence.readFrame(0); }, ErrorCode::MissingFile,
                {(dir / "matrix_0.mat").string()});
}

// Every frame's files checked from their headers (and .mat files) before any frame is read.
TEST(Sequence, CheckFramesFindsBadFilesOfEveryFrame) {
    TempDir dir;
    writeSequence(dir.path(), 3, 5, 4, 2);
    const rtd::Sequence sequence(dir.path());
    const std::vector<rtd::ExrSize> sizes = sequence.checkFrames(3);
    ASSERT_EQ(sizes.size(), 3u);
    EXPECT_EQ(sizes[2].width, 5);
    EXPECT_EQ(sizes[2].height, 4);

    rtd::writeExr(dir / "position_2.exr", patternImage(4, 4, 3, 0.0f));
    expectError([&] { sequence.checkFrames(3); }, ErrorCode::InvalidInput,
                {(dir / "position_2.exr").string(), "4x4", (dir / "beauty_2.exr").string()});
    EXPECT_NO_THROW(sequence.checkFrames(2));  // --frames 2: frame 2 is not needed
    fs::remove(dir / "position_2.exr");
    expectError([&] { sequence.checkFrames(3); }, ErrorCode::MissingFile,
                {(dir / "position_2.exr").string()});
    fs::create_directories(dir / "position_2.exr");
    expectError([&] { sequence.checkFrames(3); }, ErrorCode::InvalidInput,
                {(dir / "position_2.exr").string(), "is a folder"});
    fs::remove(dir / "position_2.exr");
    rtd::writeExr(dir / "position_2.exr", patternImage(5, 4, 3, 0.0f));
    fs::create_symlink("nowhere.exr", dir / "albedo_1.exr");  // optional, but broken
    expectError([&] { sequence.checkFrames(3); }, ErrorCode::MissingFile,
                {(dir / "albedo_1.exr").string(), "link to a file that does not exist"});
    fs::remove(dir / "albedo_1.exr");
    writeBytes(dir / "matrix_1.mat", "abc");
    expectError([&] { sequence.checkFrames(3); }, ErrorCode::InvalidInput,
                {(dir / "matrix_1.mat").string()});
}

// A folder or a dangling link of a frame's name is named as such, not counted as a frame.
TEST(Sequence, OnlyRegularFilesAreFrames) {
    TempDir dir;
    writeSequence(dir.path(), 2, 3, 3, 1);
    fs::create_symlink("beauty_0.exr", dir / "beauty_2.exr");  // a link to a file: a frame
    EXPECT_EQ(rtd::countFrames(dir.path(), "beauty"), 3);
    fs::remove(dir / "beauty_2.exr");
    fs::create_directories(dir / "beauty_2.exr");
    expectError([&] { rtd::Sequence s(dir.path()); }, ErrorCode::InvalidInput,
                {(dir / "beauty_2.exr").string(), "is a folder"});
    fs::remove(dir / "beauty_2.exr");
    fs::create_symlink("gone.exr", dir / "beauty_2.exr");
    expectError([&] { rtd::Sequence s(dir.path()); }, ErrorCode::MissingFile,
                {(dir / "beauty_2.exr").string(), "link to a file that does not exist"});
}

TEST(Sequence, RemoveNumberedFilesRemovesOnlyThoseFiles) {
    TempDir dir;
    for (const char* name : {"result_0.exr", "result_1.exr", "result_2.exr", "result_1.png",
                             "result_01.exr", "result_2.exr.bak", "other_2.exr"})
        writeBytes(dir / name, "x");
    fs::create_directories(dir / "result_3.exr");
    rtd::removeNumberedFiles(dir.path(), "result", ".exr", 1);
    EXPECT_EQ(dir.names(),
              (std::vector<std::string>{"other_2.exr", "result_0.exr", "result_01.exr",
                                        "result_1.png", "result_2.exr.bak", "result_3.exr"}));
    rtd::removeNumberedFiles(dir.path(), "result", ".png", 0);
    EXPECT_FALSE(fs::exists(dir / "result_1.png"));
}

TEST(Sequence, SizeMismatchNamesBothFiles) {
    TempDir dir;
    writeSequence(dir.path(), 1, 5, 4, 2);
    rtd::writeExr(dir / "normal_0.exr", patternImage(4, 4, 3, 0.0f));
    expectError([&] { rtd::Sequence(dir.path()).readFrame(0); }, ErrorCode::InvalidInput,
                {(dir / "normal_0.exr").string(), "4x4", (dir / "beauty_0.exr").string(), "5x4"});
}

TEST(Sequence, ObjectIdsMustBeIntegersInRange) {
    TempDir dir;
    writeSequence(dir.path(), 1, 5, 4, 2);
    const fs::path idFile = dir / "ID_0.exr";
    Image ids(5, 4, 1, 1.0f);
    ids.at(3, 2) = 2.0f;  // K = 2: only -1, 0 and 1 are valid
    rtd::writeExr(idFile, ids);
    expectError([&] { rtd::Sequence(dir.path()).readFrame(0); }, ErrorCode::InvalidInput,
                {idFile.string(), "(3, 2)", "2", "K = 2"});

    ids.at(3, 2) = 0.5f;
    ids.at(4, 3) = -7.0f;
    rtd::writeExr(idFile, ids);
    expectError([&] { rtd::Sequence(dir.path()).readFrame(0); }, ErrorCode::InvalidInput,
                {idFile.string(), "(3, 2)", "0.5"});

    ids.at(3, 2) = 1.0001f;  // near enough: stored as float, read as 1
    ids.at(4, 3) = -1.0f;
    rtd::writeExr(idFile, ids);
    const rtd::Frame frame = rtd::Sequence(dir.path()).readFrame(0);
    EXPECT_EQ(frame.objectId[2 * 5 + 3], 1);
    EXPECT_EQ(frame.objectId[3 * 5 + 4], -1);
}

TEST(Sequence, CourseBoxData) {
    const fs::path folder = fs::path(RTD_SHARED_DIR) / "data" / "box";
    if (!fs::exists(folder / "beauty_0.exr")) {
        GTEST_SKIP() << "course data not found at " << folder.string();
    }
    const rtd::Sequence sequence(folder);
    EXPECT_EQ(sequence.frameCount(), 20);
    const rtd::Frame frame = sequence.readFrame(0);
    EXPECT_EQ(frame.width(), 512);
    EXPECT_EQ(frame.height(), 512);

    // The check documented in shared/data/README.md.
    const float px = frame.position.at(100, 100, 0);
    const float py = frame.position.at(100, 100, 1);
    const float pz = frame.position.at(100, 100, 2);
    EXPECT_NEAR(px, -1.0f, 0.01f);
    EXPECT_NEAR(py, -0.937f, 0.01f);
    EXPECT_NEAR(pz, 0.937f, 0.01f);
    const auto s = transform(frame.worldToScreen, px, py, pz);
    EXPECT_NEAR(s[0] / s[3], 100.5f, 0.05f);
    EXPECT_NEAR(s[1] / s[3], 100.5f, 0.05f);
    EXPECT_NEAR(s[3], 6.0f, 0.01f);
    EXPECT_NEAR(frame.depth.at(100, 100), s[3], 0.01f);

    EXPECT_EQ(frame.objectToWorld.size(), 7u);
    bool anyBackground = false;
    for (int id : frame.objectId) anyBackground |= id == -1;
    EXPECT_TRUE(anyBackground);
    EXPECT_NO_THROW(sequence.readFrame(19));
}

// ---- display ----

TEST(ToneMap, AcesKnownValues) {
    EXPECT_EQ(rtd::acesFilm(0.0f), 0.0f);
    EXPECT_NEAR(rtd::acesFilm(1.0f), 2.54f / 3.16f, 1e-6f);  // 0.803797...
    EXPECT_NEAR(rtd::acesFilm(0.5f), (0.5f * 1.285f) / (0.5f * 1.805f + 0.14f), 1e-6f);
    EXPECT_EQ(rtd::acesFilm(100.0f), 1.0f);
    EXPECT_EQ(rtd::acesFilm(1e30f), 1.0f);
    EXPECT_EQ(rtd::acesFilm(std::numeric_limits<float>::infinity()), 1.0f);
    EXPECT_EQ(rtd::acesFilm(-1.0f), 0.0f);  // the raw fit would give 1.25 here
    EXPECT_EQ(rtd::acesFilm(std::nanf("")), 0.0f);
}

TEST(ToneMap, SrgbKnownValues) {
    EXPECT_EQ(rtd::linearToSrgb(0.0f), 0.0f);
    EXPECT_NEAR(rtd::linearToSrgb(1.0f), 1.0f, 1e-6f);
    EXPECT_NEAR(rtd::linearToSrgb(0.0031308f), 0.04045f, 1e-5f);
    EXPECT_NEAR(rtd::linearToSrgb(0.001f), 0.01292f, 1e-7f);
    EXPECT_NEAR(rtd::linearToSrgb(0.5f), 0.735357f, 1e-5f);
    EXPECT_EQ(rtd::linearToSrgb(-0.5f), 0.0f);
    EXPECT_EQ(rtd::linearToSrgb(2.0f), 1.0f);
}

TEST(ToneMap, ImageMapping) {
    Image gray(2, 1, 1);
    gray.pixels = {1.0f, std::nanf("")};
    const Image out = rtd::toneMap(gray, 0.5f);
    ASSERT_EQ(out.channels, 3);
    const float expected = rtd::linearToSrgb(rtd::acesFilm(0.5f));
    for (int c = 0; c < 3; ++c) {
        EXPECT_EQ(out.at(0, 0, c), expected);
        EXPECT_EQ(out.at(1, 0, c), 0.0f);
    }
    Image rgb(1, 1, 3);
    rgb.pixels = {std::numeric_limits<float>::infinity(), 3e38f, -2.0f};
    const Image mapped = rtd::toneMap(rgb, 10.0f);
    EXPECT_EQ(mapped.pixels, (std::vector<float>{0.0f, 1.0f, 0.0f}));
    expectError([] { rtd::toneMap(Image(1, 1, 2)); }, ErrorCode::InvalidArgument, {"2"});
    expectError([] { rtd::toneMap(Image(1, 1, 3), -1.0f); }, ErrorCode::InvalidArgument,
                {"exposure"});
}

// ---- PNG ----

namespace {

// Reads an 8-bit RGB PNG back with libpng's simplified API.
bool readPng(const fs::path& file, int& width, int& height, std::vector<unsigned char>& bytes) {
    png_image image;
    std::memset(&image, 0, sizeof(image));
    image.version = PNG_IMAGE_VERSION;
    if (!png_image_begin_read_from_file(&image, file.c_str())) return false;
    image.format = PNG_FORMAT_RGB;
    bytes.resize(PNG_IMAGE_SIZE(image));
    if (!png_image_finish_read(&image, nullptr, bytes.data(), 0, nullptr)) return false;
    width = int(image.width);
    height = int(image.height);
    return true;
}

}  // namespace

TEST(Png, WritesExpectedBytes) {
    TempDir dir;
    Image image(3, 2, 3);
    image.pixels = {0.0f,  1.0f,  0.5f,   2.0f, -1.0f, std::nanf(""), 0.2f, 0.8f,  0.01f,
                    0.25f, 0.75f, 0.999f, 0.4f, 0.6f,  1.0f,          0.0f, 0.02f, 0.98f};
    rtd::writePng(dir / "out.png", image);
    int width = 0;
    int height = 0;
    std::vector<unsigned char> bytes;
    ASSERT_TRUE(readPng(dir / "out.png", width, height, bytes));
    EXPECT_EQ(width, 3);
    EXPECT_EQ(height, 2);
    // round(v * 255), clamped; NaN is 0. The sRGB chunk keeps libpng from converting.
    EXPECT_EQ(bytes, (std::vector<unsigned char>{0, 255, 128, 255, 0, 0, 51, 204, 3, 64, 191, 255,
                                                 102, 153, 255, 0, 5, 250}));
    EXPECT_EQ(dir.names(), std::vector<std::string>{"out.png"});
}

TEST(Png, UnwritableDestinationIsIoFailure) {
    TempDir dir;
    const fs::path missingFolder = dir / "missing" / "out.png";
    expectError([&] { rtd::writePng(missingFolder, Image(2, 2, 3)); }, ErrorCode::IoFailure,
                {missingFolder.string()});
    EXPECT_TRUE(dir.names().empty());

    // /proc refuses new files even for root.
    const fs::path proc = "/proc/rtd_test_io_cannot_write.png";
    expectError([&] { rtd::writePng(proc, Image(2, 2, 3)); }, ErrorCode::IoFailure,
                {proc.string()});
    EXPECT_FALSE(fs::exists(proc));

    // A read-only folder (root ignores permissions, so only checked for other users).
    if (::geteuid() != 0) {
        const fs::path locked = dir / "locked";
        fs::create_directories(locked);
        fs::permissions(locked, fs::perms::owner_read | fs::perms::owner_exec);
        expectError([&] { rtd::writePng(locked / "out.png", Image(2, 2, 3)); },
                    ErrorCode::IoFailure, {(locked / "out.png").string()});
        fs::permissions(locked, fs::perms::owner_all);
        EXPECT_TRUE(fs::is_empty(locked));
    }
}

TEST(Png, WriteFileAtomicallyReplacesContent) {
    TempDir dir;
    const fs::path file = dir / "data.bin";
    rtd::writeFileAtomically(file, "first version");
    rtd::writeFileAtomically(file, std::string("second\0version", 14));
    EXPECT_EQ(readBytes(file), std::string("second\0version", 14));
    EXPECT_EQ(dir.names(), std::vector<std::string>{"data.bin"});
}

// ---- video ----

TEST(Video, MissingFfmpegIsMissingTool) {
    const char* saved = std::getenv("PATH");
    const std::string path = saved ? saved : "";
    TempDir dir;
    ::setenv("PATH", dir.path().c_str(), 1);
    const bool available = rtd::VideoWriter::ffmpegAvailable();
    ErrorCode code = ErrorCode::InvalidArgument;
    std::string message;
    try {
        rtd::VideoWriter writer(dir / "v.mp4", 4, 4);
    } catch (const Error& e) {
        code = e.code();
        message = e.what();
    }
    ::setenv("PATH", path.c_str(), 1);
    EXPECT_FALSE(available);
    EXPECT_EQ(static_cast<int>(code), static_cast<int>(ErrorCode::MissingTool));
    EXPECT_NE(message.find("ffmpeg not found on PATH"), std::string::npos) << message;
}

TEST(Video, WritesMp4) {
    if (!rtd::VideoWriter::ffmpegAvailable()) GTEST_SKIP() << "ffmpeg is not on PATH";
    TempDir dir;
    const fs::path file = dir / "it's a video.mp4";  // a quote in the name tests the quoting
    {
        rtd::VideoWriter writer(file, 33, 17, 10);  // odd size: ffmpeg pads for yuv420p
        for (int i = 0; i < 5; ++i) {
            Image frame(33, 17, 3, 0.2f * float(i));
            writer.addFrame(frame);
        }
        expectError([&] { writer.addFrame(Image(32, 17, 3)); }, ErrorCode::InvalidArgument,
                    {"32x17"});
        writer.finish();
    }
    ASSERT_TRUE(fs::exists(file));
    const std::string bytes = readBytes(file);
    ASSERT_GT(bytes.size(), 100u);
    EXPECT_EQ(bytes.substr(4, 4), "ftyp");  // an MP4's first box
    EXPECT_EQ(dir.names(), std::vector<std::string>{"it's a video.mp4"});
}

TEST(Video, AbandonedVideoLeavesNothing) {
    if (!rtd::VideoWriter::ffmpegAvailable()) GTEST_SKIP() << "ffmpeg is not on PATH";
    TempDir dir;
    {
        rtd::VideoWriter writer(dir / "v.mp4", 8, 8);
        writer.addFrame(Image(8, 8, 3, 0.5f));
    }  // no finish()
    EXPECT_TRUE(dir.names().empty());

    const fs::path inMissing = dir / "missing" / "v.mp4";
    expectError([&] { rtd::VideoWriter w(inMissing, 8, 8); }, ErrorCode::IoFailure,
                {inMissing.string()});
}

TEST(Video, FailingFfmpegIsIoFailure) {
    // A stand-in ffmpeg that complains and exits: writes to it hit a closed pipe (SIGPIPE must not
    // kill the test) and the error carries its message.
    TempDir dir;
    const fs::path bin = dir / "bin";
    fs::create_directories(bin);
    {
        std::ofstream script(bin / "ffmpeg");
        script << "#!/bin/sh\necho 'Unknown encoder libx264' >&2\nexit 3\n";
    }
    fs::permissions(bin / "ffmpeg", fs::perms::owner_all);
    const char* saved = std::getenv("PATH");
    const std::string path = saved ? saved : "";
    ::setenv("PATH", bin.c_str(), 1);
    const fs::path file = dir / "v.mp4";
    ErrorCode code = ErrorCode::InvalidArgument;
    std::string message;
    try {
        rtd::VideoWriter writer(file, 256, 256);
        for (int i = 0; i < 8; ++i) writer.addFrame(Image(256, 256, 3, 0.5f));
        writer.finish();
    } catch (const Error& e) {
        code = e.code();
        message = e.what();
    }
    ::setenv("PATH", path.c_str(), 1);
    EXPECT_EQ(static_cast<int>(code), static_cast<int>(ErrorCode::IoFailure)) << message;
    EXPECT_NE(message.find(file.string()), std::string::npos) << message;
    EXPECT_NE(message.find("Unknown encoder libx264"), std::string::npos) << message;
    EXPECT_EQ(dir.names(), std::vector<std::string>{"bin"});
}
