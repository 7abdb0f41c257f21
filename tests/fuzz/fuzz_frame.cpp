// libFuzzer target: a whole frame through rtd::Sequence, as `rtdenoise denoise` reads it
// (Sequence's frame count, checkFrames' header checks, readFrame's read and validation). A valid
// 5x4 frame 0 (with albedo, two objects) lies in a scratch folder; the input's first byte picks
// which of its seven files the rest of the input replaces. An rtd::Error is the expected
// outcome; a crash, a leak, undefined behaviour, a huge allocation, another exception, or a frame
// accepted that breaks readFrame's promises (one size, IDs in -1..K-1) is a finding.
#include <cstddef>
#include <cstdint>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "fuzz_support.h"
#include "rtdenoise/error.h"
#include "rtdenoise/io.h"

namespace {

const char* const kFiles[] = {"beauty_0.exr", "normal_0.exr", "position_0.exr", "depth_0.exr",
                              "ID_0.exr",     "albedo_0.exr", "matrix_0.mat"};
constexpr int kFileCount = 7;

rtd::Frame validFrame() {
    const int w = 5, h = 4;
    rtd::Frame f;
    f.beauty = rtd::Image(w, h, 3, 0.5f);
    f.normal = rtd::Image(w, h, 3, 0.0f);
    f.position = rtd::Image(w, h, 3, 1.0f);
    f.depth = rtd::Image(w, h, 1, 4.0f);
    f.albedo = rtd::Image(w, h, 3, 0.8f);
    f.objectId.assign(std::size_t(w) * h, 0);
    for (int x = 0; x < w; ++x) f.objectId[x] = -1;         // a background row
    for (int y = 2; y < h; ++y) f.objectId[y * w + 3] = 1;  // and a second object
    for (std::size_t i = 0; i < f.normal.pixelCount(); ++i) f.normal.pixels[3 * i + 2] = -1.0f;
    f.objectToWorld.assign(2, rtd::Matrix4::identity());
    return f;
}

std::string readAll(const std::filesystem::path& file) {
    std::ifstream in(file, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

struct Scratch {
    std::filesystem::path folder;
    std::vector<std::string> valid;  // each file's valid bytes, to put back after an input
};

const Scratch& scratch() {
    static const Scratch s = [] {
        Scratch r{rtd::fuzz::scratchFolder("frame"), {}};
        rtd::writeFrame(r.folder, 0, validFrame());
        for (const char* name : kFiles) r.valid.push_back(readAll(r.folder / name));
        // The valid frame reads back: otherwise every input would end in the same error.
        const rtd::Frame back = rtd::Sequence(r.folder).readFrame(0);
        RTD_FUZZ_CHECK(back.width() == 5 && back.height() == 4 && back.albedo);
        return r;
    }();
    return s;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    if (size == 0) return 0;
    const Scratch& s = scratch();
    const int which = data[0] % kFileCount;
    const std::filesystem::path file = s.folder / kFiles[which];
    rtd::fuzz::writeBytes(file, data + 1, size - 1);
    try {
        const rtd::Sequence sequence(s.folder);
        RTD_FUZZ_CHECK(sequence.frameCount() == 1);
        const std::vector<rtd::ExrSize> sizes = sequence.checkFrames(1);
        RTD_FUZZ_CHECK(sizes.size() == 1);
        const rtd::Frame frame = sequence.readFrame(0);
        // checkFrames passed every header readFrame then read: the same size.
        RTD_FUZZ_CHECK(frame.width() == sizes[0].width && frame.height() == sizes[0].height);
        const std::size_t pixels = frame.beauty.pixelCount();
        for (const rtd::Image* image : {&frame.normal, &frame.position, &frame.depth}) {
            RTD_FUZZ_CHECK(image->width == frame.width() && image->height == frame.height());
            RTD_FUZZ_CHECK(image->pixels.size() == pixels * std::size_t(image->channels));
        }
        RTD_FUZZ_CHECK(frame.albedo && frame.albedo->pixelCount() == pixels);
        RTD_FUZZ_CHECK(frame.objectId.size() == pixels);
        const auto objects = std::int64_t(frame.objectToWorld.size());
        for (std::int32_t id : frame.objectId) RTD_FUZZ_CHECK(id >= -1 && id < objects);
    } catch (const rtd::Error&) {
    }
    rtd::fuzz::writeBytes(file, reinterpret_cast<const std::uint8_t*>(s.valid[which].data()),
                          s.valid[which].size());
    return 0;
}
