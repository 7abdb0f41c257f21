// libFuzzer target: Blender multilayer EXRs through rtd::BlenderSequence, as `rtdenoise denoise`
// reads them (the first file's passes, checkFrames' header checks, readFrame's read and
// validation), then denoised by svgf from their motion vectors. Two valid 5x4 frames lie in a
// scratch folder (0001.exr, 0002.exr); the input replaces the first byte's choice of them. An
// rtd::Error is the expected outcome; a crash, a leak, undefined behaviour, a huge allocation,
// another exception, a frame accepted that breaks readFrame's promises (one size, IDs in
// -1..objectCount-1, 2-channel motion where there is motion) or a non-finite denoised value
// is a finding.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "fuzz_support.h"
#include "rtdenoise/denoiser.h"
#include "rtdenoise/error.h"
#include "rtdenoise/io.h"

namespace {

const char* const kFiles[] = {"0001.exr", "0002.exr"};

rtd::Frame validFrame(float shift) {
    const int w = 5, h = 4;
    rtd::Frame f;
    f.beauty = rtd::Image(w, h, 3, 0.5f + shift);
    f.normal = rtd::Image(w, h, 3, 0.0f);
    f.position = rtd::Image(w, h, 3, 1.0f);
    f.depth = rtd::Image(w, h, 1, 4.0f);
    f.albedo = rtd::Image(w, h, 3, 0.8f);
    f.motion = rtd::Image(w, h, 2, shift);
    f.objectId.assign(std::size_t(w) * h, 0);
    for (int y = 2; y < h; ++y) f.objectId[y * w + 3] = 1;
    for (std::size_t i = 0; i < f.normal.pixelCount(); ++i) f.normal.pixels[3 * i + 2] = -1.0f;
    f.objectCount = 2;
    return f;
}

std::string readAll(const std::filesystem::path& file) {
    std::ifstream in(file, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

struct Scratch {
    std::filesystem::path folder;
    std::vector<std::string> valid;
};

const Scratch& scratch() {
    static const Scratch s = [] {
        Scratch r{rtd::fuzz::scratchFolder("blender"), {}};
        rtd::writeBlenderExr(r.folder / kFiles[0], validFrame(0.0f));
        rtd::writeBlenderExr(r.folder / kFiles[1], validFrame(0.25f));
        for (const char* name : kFiles) r.valid.push_back(readAll(r.folder / name));
        const rtd::BlenderSequence back(r.folder);
        RTD_FUZZ_CHECK(back.frameCount() == 2 && back.readFrame(1).motion);
        return r;
    }();
    return s;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    if (size == 0) return 0;
    const Scratch& s = scratch();
    const int which = data[0] % 2;
    const std::filesystem::path file = s.folder / kFiles[which];
    rtd::fuzz::writeBytes(file, data + 1, size - 1);
    try {
        const rtd::BlenderSequence sequence(s.folder);
        RTD_FUZZ_CHECK(sequence.frameCount() == 2);
        const std::vector<rtd::ExrSize> sizes = sequence.checkFrames(2);
        rtd::DenoiserSettings settings;
        settings.device = rtd::DeviceType::Cpu;
        rtd::Denoiser denoiser(settings);
        for (int i = 0; i < 2; ++i) {
            const rtd::Frame frame = sequence.readFrame(i);
            RTD_FUZZ_CHECK(frame.width() == sizes[i].width && frame.height() == sizes[i].height);
            const std::size_t pixels = frame.beauty.pixelCount();
            for (const rtd::Image* image : {&frame.normal, &frame.position, &frame.depth})
                RTD_FUZZ_CHECK(image->pixels.size() == pixels * std::size_t(image->channels));
            RTD_FUZZ_CHECK(frame.objectId.size() == pixels);
            for (std::int32_t id : frame.objectId)
                RTD_FUZZ_CHECK(id >= -1 && id < std::int64_t(frame.objectCount));
            // Without a Vector pass in the first file there is no motion (the command then
            // refuses a history method; the denoiser refuses a frame with neither motion nor
            // matrices).
            if (frame.motion)
                RTD_FUZZ_CHECK(frame.motion->channels == 2 && frame.motion->pixelCount() == pixels);
            // A header may declare a large or very thin frame (15109x4 took 70 s here under the
            // sanitizers: the planes' 32-pixel borders dominate). The reader is fuzzed at any
            // size, the denoiser up to this many pixels with those borders.
            constexpr std::size_t kMaxPaddedPixels = 512 * 512;
            if (std::size_t(frame.width() + 64) * std::size_t(frame.height() + 64) >
                kMaxPaddedPixels)
                continue;
            const rtd::Image result = denoiser.processFrame(frame);
            for (float v : result.pixels) RTD_FUZZ_CHECK(std::isfinite(v));
        }
    } catch (const rtd::Error&) {
    }
    rtd::fuzz::writeBytes(file, reinterpret_cast<const std::uint8_t*>(s.valid[which].data()),
                          s.valid[which].size());
    return 0;
}
