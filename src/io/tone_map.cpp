// Display transform for previews and videos: exposure, Narkowicz's ACES fit, the sRGB curve.
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <string>

#include "rtdenoise/error.h"
#include "rtdenoise/io.h"

namespace rtd {

float acesFilm(float x) {
    if (std::isnan(x) || x <= 0.0f) return 0.0f;  // negatives would map to positive values
    // The fit passes 1 near x = 7.25 and tends to 2.51/2.43; past this bound x*x could overflow.
    if (x > 1.0e6f) return 1.0f;
    const float y = x * (2.51f * x + 0.03f) / (x * (2.43f * x + 0.59f) + 0.14f);
    return std::clamp(y, 0.0f, 1.0f);
}

float linearToSrgb(float x) {
    if (std::isnan(x) || x <= 0.0f) return 0.0f;
    if (x >= 1.0f) return 1.0f;
    if (x <= 0.0031308f) return 12.92f * x;
    return 1.055f * std::pow(x, 1.0f / 2.4f) - 0.055f;
}

Image toneMap(const Image& linear, float exposure) {
    if (linear.channels != 1 && linear.channels != 3) {
        throw Error(ErrorCode::InvalidArgument, "toneMap needs a 1- or 3-channel image, got " +
                                                    std::to_string(linear.channels) + " channels");
    }
    if (!std::isfinite(exposure) || exposure < 0.0f) {
        throw Error(ErrorCode::InvalidArgument,
                    "toneMap exposure must be finite and >= 0, got " + std::to_string(exposure));
    }
    Image out(linear.width, linear.height, 3);
    const auto count = static_cast<std::ptrdiff_t>(linear.pixelCount());
    const int inChannels = linear.channels;
#pragma omp parallel for schedule(static)
    for (std::ptrdiff_t i = 0; i < count; ++i) {
        for (int c = 0; c < 3; ++c) {
            // A 1-channel image is gray: its one value goes to all three outputs.
            const float value = linear.pixels[i * inChannels + (inChannels == 3 ? c : 0)];
            // Non-finite input is a broken pixel: black, not white.
            out.pixels[i * 3 + c] =
                std::isfinite(value) ? linearToSrgb(acesFilm(exposure * value)) : 0.0f;
        }
    }
    return out;
}

}  // namespace rtd
