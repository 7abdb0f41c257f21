// Writes the fuzz targets' seed corpora into <folder>/{exr,frame,matrix,config}: small valid
// inputs (a few hundred bytes each) that reach every reader's paths, from which libFuzzer
// mutates. Usage: fuzz_make_seeds tests/fuzz/corpus (the output is committed).
#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfOutputFile.h>
#include <ImfTiledOutputFile.h>
#include <fmt/format.h>
#include <half.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "rtdenoise/io.h"

namespace fs = std::filesystem;

namespace {

std::string readAll(const fs::path& file) {
    std::ifstream in(file, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

void writeAll(const fs::path& file, const std::string& bytes) {
    std::ofstream out(file, std::ios::binary);
    out << bytes;
}

struct ExrSpec {
    std::string name;
    Imf::Compression compression = Imf::ZIP_COMPRESSION;
    Imf::PixelType type = Imf::FLOAT;
    std::vector<std::string> channels{"R", "G", "B"};
    int width = 3, height = 2;
    Imath::V2i origin{0, 0};
    bool tiled = false;
};

// An EXR of the spec, with values that differ per pixel and channel; returns its bytes.
std::string writeExr(const fs::path& folder, const ExrSpec& s) {
    const fs::path file = folder / (s.name + ".exr");
    const Imath::Box2i window(s.origin, s.origin + Imath::V2i(s.width - 1, s.height - 1));
    Imf::Header header(window, window, 1.0f, Imath::V2f(0, 0), 1.0f, Imf::INCREASING_Y,
                       s.compression);
    for (const auto& c : s.channels) header.channels().insert(c, Imf::Channel(s.type));
    const std::size_t n = std::size_t(s.width) * s.height * s.channels.size();
    std::vector<float> f(n);
    std::vector<std::uint16_t> h(n);
    for (std::size_t i = 0; i < n; ++i) {
        f[i] = 0.25f * float(i % 7) + 0.1f * float(i / 7);
        h[i] = half(f[i]).bits();
    }
    const std::size_t px = (s.type == Imf::FLOAT ? 4 : 2) * s.channels.size();
    char* base = s.type == Imf::FLOAT ? reinterpret_cast<char*>(f.data())
                                      : reinterpret_cast<char*>(h.data());
    Imf::FrameBuffer fb;
    for (std::size_t c = 0; c < s.channels.size(); ++c) {
        const std::size_t bytes = s.type == Imf::FLOAT ? 4 : 2;
        char* origin = base + c * bytes -
                       (std::ptrdiff_t(s.origin.y) * s.width + s.origin.x) * std::ptrdiff_t(px);
        fb.insert(s.channels[c], Imf::Slice(s.type, origin, px, px * s.width));
    }
    if (s.tiled) {
        header.setTileDescription(Imf::TileDescription(2, 2, Imf::ONE_LEVEL));
        Imf::TiledOutputFile out(file.c_str(), header);
        out.setFrameBuffer(fb);
        out.writeTiles(0, out.numXTiles() - 1, 0, out.numYTiles() - 1);
    } else {
        Imf::OutputFile out(file.c_str(), header);
        out.setFrameBuffer(fb);
        out.writePixels(s.height);
    }
    return readAll(file);
}

rtd::Frame validFrame(int w, int h, int objects) {
    rtd::Frame f;
    f.beauty = rtd::Image(w, h, 3, 0.5f);
    f.normal = rtd::Image(w, h, 3, 0.0f);
    f.position = rtd::Image(w, h, 3, 1.0f);
    f.depth = rtd::Image(w, h, 1, 4.0f);
    f.albedo = rtd::Image(w, h, 3, 0.8f);
    f.objectId.assign(std::size_t(w) * h, 0);
    for (int x = 0; x < w; ++x) f.objectId[x] = -1;
    if (objects > 1)
        for (int y = 2; y < h; ++y) f.objectId[y * w + 3] = 1;
    for (std::size_t i = 0; i < f.normal.pixelCount(); ++i) f.normal.pixels[3 * i + 2] = -1.0f;
    f.objectToWorld.assign(objects, rtd::Matrix4::identity());
    return f;
}

}  // namespace

int main(int argc, char** argv) {
    if (argc != 2) {
        std::fprintf(stderr, "usage: %s CORPUS_FOLDER\n", argv[0]);
        return 2;
    }
    const fs::path root = argv[1];
    const fs::path tmp = root / "tmp";
    for (const char* d : {"exr", "frame", "matrix", "config", "tmp"})
        fs::create_directories(root / d);

    // EXR: every compression for FLOAT and HALF RGB; the scalar names; a shifted data window;
    // tiles; an image of one pixel. The last byte picks fuzz_exr's channel choices (0..3).
    const std::pair<const char*, Imf::Compression> compressions[] = {
        {"none", Imf::NO_COMPRESSION},   {"rle", Imf::RLE_COMPRESSION},
        {"zips", Imf::ZIPS_COMPRESSION}, {"zip", Imf::ZIP_COMPRESSION},
        {"piz", Imf::PIZ_COMPRESSION},   {"pxr24", Imf::PXR24_COMPRESSION},
        {"b44", Imf::B44_COMPRESSION},   {"b44a", Imf::B44A_COMPRESSION},
        {"dwaa", Imf::DWAA_COMPRESSION}, {"dwab", Imf::DWAB_COMPRESSION}};
    std::vector<ExrSpec> specs;
    for (const auto& [name, c] : compressions) {
        ExrSpec f{std::string("rgb-float-") + name, c, Imf::FLOAT};
        ExrSpec h{std::string("rgb-half-") + name, c, Imf::HALF};
        specs.push_back(f);
        specs.push_back(h);
    }
    {
        ExrSpec s{"y-float-zip"};
        s.channels = {"Y"};
        specs.push_back(s);
        s.name = "z-half-piz", s.channels = {"Z"}, s.type = Imf::HALF,
        s.compression = Imf::PIZ_COMPRESSION;
        specs.push_back(s);
        s.name = "layer-depth-float-none", s.channels = {"depth.Y"}, s.type = Imf::FLOAT;
        s.compression = Imf::NO_COMPRESSION;
        specs.push_back(s);
        ExrSpec w{"rgb-float-zip-window"};
        w.origin = {-2, 5};
        specs.push_back(w);
        ExrSpec t{"rgb-half-zip-tiled", Imf::ZIP_COMPRESSION, Imf::HALF};
        t.tiled = true, t.width = 5, t.height = 3;
        specs.push_back(t);
        ExrSpec one{"rgba-float-none-1x1", Imf::NO_COMPRESSION};
        one.width = one.height = 1, one.channels = {"A", "B", "G", "R"};
        specs.push_back(one);
        ExrSpec tall{"rgb-half-rle-2x40", Imf::RLE_COMPRESSION, Imf::HALF};
        tall.width = 2, tall.height = 40;
        specs.push_back(tall);
    }
    int pick = 0;
    for (const ExrSpec& s : specs) {
        std::string bytes = writeExr(tmp, s);
        const int choice = s.channels.size() == 1 ? 1 + (pick++ % 2) : (pick++ % 2) * 3;
        bytes.push_back(char(choice));
        writeAll(root / "exr" / (s.name + ".exr"), bytes);
    }

    // Regressions (fuzz_exr's finds, refused since by the header walk in exr_io.cpp): an
    // attribute of an unknown type claiming 2 GB in a 400-byte file; a value of a fixed-size
    // type whose size claims more than the type's (OpenEXR reads the type's 4 bytes and takes
    // the rest, another attribute of 2 GB here, for the next attribute: the fuzzer's find was a
    // channel list shorter than its size).
    {
        const std::string valid = readAll(root / "exr" / "rgb-float-zip.exr");
        const std::string hidden = std::string("x\0blob\0", 7) + std::string("\x00\x00\x00\x78", 4);
        writeAll(
            root / "exr" / "regress-attribute-2gb.exr",
            valid.substr(0, 8) + std::string("junk\0", 5) + hidden.substr(2) + valid.substr(8));
        std::string desync = valid;
        const std::string ratio("pixelAspectRatio\0float\0", 23);
        const std::size_t at = desync.find(ratio) + ratio.size();  // its int32 size, then 4 bytes
        desync[at] = char(4 + hidden.size());
        desync.insert(at + 8, hidden);
        writeAll(root / "exr" / "regress-size-desync.exr", desync);
    }

    // Frames: each of a valid frame's seven files, after the byte that picks it; and a few
    // files that fail readFrame's checks (another size, an ID out of range, K = 1).
    const char* const files[] = {"beauty_0.exr", "normal_0.exr", "position_0.exr", "depth_0.exr",
                                 "ID_0.exr",     "albedo_0.exr", "matrix_0.mat"};
    rtd::writeFrame(tmp / "valid", 0, validFrame(5, 4, 2));
    rtd::writeFrame(tmp / "other-size", 0, validFrame(4, 4, 2));
    rtd::writeFrame(tmp / "one-object", 0, validFrame(5, 4, 1));
    for (int i = 0; i < 7; ++i) {
        writeAll(root / "frame" / fmt::format("{}-valid", i),
                 std::string(1, char(i)) + readAll(tmp / "valid" / files[i]));
        writeAll(root / "frame" / fmt::format("{}-other-size", i),
                 std::string(1, char(i)) + readAll(tmp / "other-size" / files[i]));
    }
    writeAll(root / "frame" / "6-one-object",
             std::string(1, char(6)) + readAll(tmp / "one-object" / "matrix_0.mat"));
    writeAll(root / "frame" / "1-half-piz",
             std::string(1, char(1)) + readAll(root / "exr" / "rgb-half-piz.exr"));

    // .mat: K = 0, 1, 3 with distinct values.
    for (int k : {0, 1, 3}) {
        rtd::MatrixFile m;
        for (int i = 0; i < k; ++i) {
            rtd::Matrix4 a = rtd::Matrix4::identity();
            a.m[0][3] = float(i) + 0.5f;
            m.objectToWorld.push_back(a);
        }
        m.worldToScreen.m[0] = {64.0f, 0.0f, 16.0f, 0.0f};
        m.worldToScreen.m[3] = {0.0f, 0.0f, 1.0f, 0.0f};
        rtd::writeMatrixFile(root / "matrix" / fmt::format("k{}.mat", k), m);
    }

    // Config files: TOML and INI forms, every kind of option (choices, numbers, flags and
    // their negations, underscores for dashes, a section); the first byte's low bit is
    // fuzz_config's command-line switch ('#' is odd: with it; 'm' is odd too, so some start
    // with a space).
    const std::pair<const char*, const char*> configs[] = {
        {"method.toml", "method = \"jbf\"\nradius = 8\nsigma-color = 0.8\n"},
        {"svgf.toml",
         " method = \"svgf\"\nsvgf-iterations = 5\nsvgf_feedback = 1\n"
         "svgf-max-history = 32\nsvgf-clamp-k = 1.5\n"},
        {"temporal.ini",
         "# temporal with the A-Trous filter\n[denoise]\nmethod=temporal\n"
         "spatial-filter=atrous\nalpha=0.2\nclamp-k=1.0\nclamp-radius=3\n"},
        {"flags.toml",
         " outlier = false\nno-albedo = true\ngeometry-tests = true\n"
         "separate-objects = false\noutlier-radius = 2\noutlier-k = 3\n"},
        {"device.toml",
         "device = \"cpu\"\nframes = 3\npng = true\n"
         "exposure = 1.5\nfps = 30\nquiet = true\n"},
        {"paths.toml",
         " output = \"out dir\"\nvideo = \"v.mp4\"\ndebug = true\n"
         "atrous-passes = 4\ndepth-tolerance = 0.1\nnormal-tolerance = 0.5\n"},
    };
    for (const auto& [name, text] : configs) writeAll(root / "config" / name, text);

    fs::remove_all(tmp);
    std::printf("seeds written under %s\n", root.c_str());
    return 0;
}
