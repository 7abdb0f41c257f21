// The library from a renderer: hand each frame's radiance and G-buffer to a Denoiser, get the
// denoised radiance back. Here a flat grey wall with noise, built in memory, stands in for the
// renderer: rtdenoise::rtdenoise alone, no image files (those are rtdenoise::rtdenoise_io's).
// `consumer DIR FRAMES` denoises a renderer's raw buffers instead, as examples/c_consumer does.
#include <rtdenoise/denoiser.h>
#include <rtdenoise/error.h>

#include <cstdint>
#include <cstdio>
#include <fstream>
#include <random>
#include <string>
#include <vector>

// DIR/frame_<i>.raw (examples/c_consumer/main.c's layout) into DIR/cpp_result_<i>.raw with the
// default method (detail).
int denoiseRawFrames(const std::string& dir, int frames) {
    rtd::DenoiserSettings settings;
    settings.device = rtd::DeviceType::Cpu;
    rtd::Denoiser denoiser(settings);
    for (int i = 0; i < frames; ++i) {
        std::ifstream in(dir + "/frame_" + std::to_string(i) + ".raw", std::ios::binary);
        std::int32_t size[3] = {};
        in.read(reinterpret_cast<char*>(size), sizeof size);
        const std::size_t n = std::size_t(size[0]) * std::size_t(size[1]);
        std::vector<float> buffer(11 * n + 16 * (std::size_t(size[2]) + 2));
        in.read(reinterpret_cast<char*>(buffer.data()), std::streamsize(buffer.size() * 4));
        if (!in) return std::fprintf(stderr, "frame %d: unreadable\n", i), 1;
        const float* m = buffer.data() + 11 * n;
        std::vector<rtd::Matrix4> matrices(std::size_t(size[2]) + 2);
        for (std::size_t k = 0; k < matrices.size(); ++k)
            for (int e = 0; e < 16; ++e) matrices[k].m[e / 4][e % 4] = m[16 * k + e];
        rtd::FrameView view;
        view.width = size[0];
        view.height = size[1];
        view.beauty = buffer.data();
        view.normal = buffer.data() + 3 * n;
        view.position = buffer.data() + 6 * n;
        view.depth = buffer.data() + 9 * n;
        view.objectId = rtd::ImageView(buffer.data() + 10 * n, rtd::DataType::Int32, 1);
        view.objectCount = size[2];
        view.objectToWorld = matrices.data();
        view.worldToCamera = matrices[std::size_t(size[2])];
        view.worldToScreen = matrices[std::size_t(size[2]) + 1];
        std::vector<float> output(3 * n);
        denoiser.processFrame(view, output.data());
        std::ofstream out(dir + "/cpp_result_" + std::to_string(i) + ".raw", std::ios::binary);
        out.write(reinterpret_cast<const char*>(output.data()), std::streamsize(output.size() * 4));
        if (!out) return std::fprintf(stderr, "frame %d: cannot write\n", i), 1;
    }
    std::printf("cpp consumer ok, %s\n", denoiser.deviceName().c_str());
    return 0;
}

int main(int argc, char** argv) {
    if (argc == 3) {
        try {
            return denoiseRawFrames(argv[1], std::stoi(argv[2]));
        } catch (const rtd::Error& e) {
            std::fprintf(stderr, "denoising failed: %s\n", e.what());
            return 1;
        }
    }
    const int width = 64, height = 48;
    rtd::DenoiserSettings settings;
    settings.method = rtd::Method::Temporal;  // filter + back-projection + accumulation
    settings.edges.sigmaColor = 0.6f;
    rtd::Denoiser denoiser(settings);

    rtd::Frame frame;
    frame.beauty = rtd::Image(width, height, 3);
    frame.normal = rtd::Image(width, height, 3);
    frame.position = rtd::Image(width, height, 3);
    frame.depth = rtd::Image(width, height, 1, 5.0f);
    frame.objectId.assign(std::size_t(width) * height, 0);  // one object, K = 1
    frame.objectToWorld = {rtd::Matrix4::identity()};
    // Pinhole camera at the origin looking down +z, focal length 64 pixels (s.w = depth).
    frame.worldToScreen.m = {
        {{64, 0, width / 2.0f, 0}, {0, 64, height / 2.0f, 0}, {0, 0, 1, 0}, {0, 0, 1, 0}}};
    std::mt19937 rng(1);
    std::uniform_real_distribution<float> noise(0.0f, 1.0f);
    double inputMean = 0, outputMean = 0;
    rtd::Image output;
    for (int f = 0; f < 4; ++f) {
        for (int y = 0; y < height; ++y)
            for (int x = 0; x < width; ++x) {
                for (int c = 0; c < 3; ++c) frame.beauty.at(x, y, c) = noise(rng);
                frame.normal.at(x, y, 2) = -1.0f;
                frame.position.at(x, y, 0) = (x + 0.5f - width / 2.0f) * 5.0f / 64.0f;
                frame.position.at(x, y, 1) = (y + 0.5f - height / 2.0f) * 5.0f / 64.0f;
                frame.position.at(x, y, 2) = 5.0f;
            }
        try {
            denoiser.processFrame(frame, output);  // output reused: no allocation per frame
        } catch (const rtd::Error& e) {
            std::fprintf(stderr, "denoising failed: %s\n", e.what());
            return 1;
        }
    }
    for (float v : frame.beauty.pixels) inputMean += v;
    for (float v : output.pixels) outputMean += v;
    std::printf("device %s, %zu passes, mean in %.3f out %.3f\n", denoiser.deviceName().c_str(),
                denoiser.passes().size(), inputMean / frame.beauty.pixels.size(),
                outputMean / output.pixels.size());
    return 0;
}
