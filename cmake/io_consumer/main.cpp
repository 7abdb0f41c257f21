// The install test's io consumer: an EXR written and read back through rtdenoise_io, a missing
// file reported as rtdenoise's rtd::Error, and the denoiser (rtdenoise) reachable from the same
// link. Prints "io ok" on success. `io_consumer --pack SCENE OUT` writes the sequence SCENE's
// frames as the raw buffers the install test hands to the C, C++ and Python consumers
// (OUT/frame_<i>.raw, examples/c_consumer/main.c's layout; no albedo).
#include <rtdenoise/denoiser.h>
#include <rtdenoise/error.h>
#include <rtdenoise/io.h>

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

namespace {
int pack(const std::filesystem::path& scene, const std::filesystem::path& out) {
    auto source = rtd::openFrameSource(scene);
    for (int i = 0; i < source->frameCount(); ++i) {
        const rtd::Frame f = source->readFrame(i);
        std::ofstream file(out / ("frame_" + std::to_string(i) + ".raw"), std::ios::binary);
        auto put = [&file](const void* data, std::size_t bytes) {
            file.write(static_cast<const char*>(data), std::streamsize(bytes));
        };
        const std::int32_t size[3] = {f.width(), f.height(), std::int32_t(f.objectToWorld.size())};
        put(size, sizeof size);
        for (const rtd::Image* image : {&f.beauty, &f.normal, &f.position, &f.depth})
            put(image->pixels.data(), image->pixels.size() * 4);
        put(f.objectId.data(), f.objectId.size() * 4);
        for (const rtd::Matrix4& m : f.objectToWorld) put(&m.m, 64);
        put(&f.worldToCamera.m, 64);
        put(&f.worldToScreen.m, 64);
        if (!file) return 1;
    }
    std::printf("packed %d frames\n", source->frameCount());
    return 0;
}
}  // namespace

int main(int argc, char** argv) {
    if (argc == 4 && std::string(argv[1]) == "--pack") {
        try {
            return pack(argv[2], argv[3]);
        } catch (const rtd::Error& e) {
            std::fprintf(stderr, "pack failed: %s\n", e.what());
            return 1;
        }
    }
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
