// The library from a renderer: hand each frame's radiance and G-buffer to a Denoiser, get the
// denoised radiance back. Here a flat grey wall with noise, built in memory, stands in for the
// renderer: rtdenoise::rtdenoise alone, no image files (those are rtdenoise::rtdenoise_io's).
#include <rtdenoise/denoiser.h>
#include <rtdenoise/error.h>

#include <cstdio>
#include <random>

int main() {
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
