// The install test's io consumer: an EXR written and read back through rtdenoise_io, a missing
// file reported as rtdenoise's rtd::Error, and the denoiser (rtdenoise) reachable from the same
// link. Prints "io ok" on success.
#include <rtdenoise/denoiser.h>
#include <rtdenoise/error.h>
#include <rtdenoise/io.h>

#include <cstdio>
#include <filesystem>

int main(int argc, char** argv) {
    if (argc != 2) return 2;
    const std::filesystem::path file = std::filesystem::path(argv[1]) / "image.exr";
    rtd::Image image(8, 4, 3);
    for (std::size_t i = 0; i < image.pixels.size(); ++i) image.pixels[i] = float(i) * 0.25f;
    try {
        rtd::writeExr(file, image);
        const rtd::Image back = rtd::readExr(file, {{"R"}, {"G"}, {"B"}});
        if (back.width != image.width || back.height != image.height ||
            back.pixels != image.pixels) {
            std::fprintf(stderr, "the EXR read back differs from the one written\n");
            return 1;
        }
    } catch (const rtd::Error& e) {
        std::fprintf(stderr, "io failed: %s\n", e.what());
        return 1;
    }
    try {
        rtd::readExr(file.parent_path() / "missing.exr", {{"R"}});
        return 1;
    } catch (const rtd::Error& e) {
        if (e.code() != rtd::ErrorCode::MissingFile) return 1;
    }
    rtd::Denoiser denoiser(rtd::DenoiserSettings{});
    std::printf("io ok, device %s\n", denoiser.deviceName().c_str());
    return 0;
}
