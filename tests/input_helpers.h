// Test helpers for the renderer-facing inputs: motion vectors from a frame's matrices, and
// buffers laid out as renderers keep them (half, RGBA, strides).
#pragma once

#include <gtest/gtest.h>

#include <cstring>
#include <vector>

#include "core/math.h"
#include "kernels/convert.h"
#include "rtdenoise/image.h"

namespace rtd::test {

inline Mat4 toMat4(const Matrix4& m) {
    Mat4 r{};
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j) r.m[i][j] = m.m[i][j];
    return r;
}

// Frame `current`'s motion vectors (NRD's convention, 3 channels: pixels and the depth change)
// from the matrices of it and `previous`, as the back-projection computes them.
inline Image motionFromMatrices(const Frame& previous, const Frame& current) {
    const int w = current.width(), h = current.height();
    Image motion(w, h, 3);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            std::int32_t id = current.objectId[std::size_t(y) * w + x];
            if (id < 0) continue;
            Mat4 inverseModel;
            EXPECT_TRUE(invert(toMat4(current.objectToWorld[id]), inverseModel));
            Mat4 toScreen = multiply(toMat4(previous.worldToScreen),
                                     multiply(toMat4(previous.objectToWorld[id]), inverseModel));
            Float3 p = make3(current.position.at(x, y, 0), current.position.at(x, y, 1),
                             current.position.at(x, y, 2));
            Float4 s = transformPoint(toScreen, p);
            // As findHistory computes the previous pixel (by the reciprocal), so that adding
            // the pixel back gives its value.
            float inverseW = 1.0f / s.w;
            motion.at(x, y, 0) = (s.x * inverseW - 0.5f) - float(x);
            motion.at(x, y, 1) = (s.y * inverseW - 0.5f) - float(y);
            motion.at(x, y, 2) = s.w - current.depth.at(x, y);
        }
    return motion;
}

// The frames with motion vectors in place of their matrices.
inline std::vector<Frame> withMotion(std::vector<Frame> frames, int channels = 3) {
    std::vector<Frame> out = frames;
    for (std::size_t i = 0; i < frames.size(); ++i) {
        Image m = motionFromMatrices(frames[i == 0 ? 0 : i - 1], frames[i]);
        if (channels == 2) {
            Image two(m.width, m.height, 2);
            for (std::size_t p = 0; p < m.pixelCount(); ++p)
                for (int c = 0; c < 2; ++c) two.pixels[2 * p + c] = m.pixels[3 * p + c];
            m = two;
        }
        out[i].motion = m;
        out[i].objectCount = int(frames[i].objectToWorld.size());
        out[i].objectToWorld.clear();
    }
    return out;
}

// Packed floats as `channels` values of `type` per pixel, `padBytes` after each pixel and
// `rowPadBytes` after each row.
struct Strided {
    std::vector<unsigned char> bytes;
    ImageView view;
};
inline Strided strided(const std::vector<float>& packed, int width, int height, int ownChannels,
                       DataType type, int channels, int padBytes, int rowPadBytes) {
    const std::size_t valueBytes = type == DataType::Float16 ? 2 : 4;
    const std::size_t pixelStride = channels * valueBytes + padBytes;
    const std::size_t rowStride = width * pixelStride + rowPadBytes;
    Strided s;
    s.bytes.assign(rowStride * height, 0xAB);  // padding that must never be read as values
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x)
            for (int c = 0; c < channels; ++c) {
                float v = c < ownChannels ? packed[(std::size_t(y) * width + x) * ownChannels + c]
                                          : 7.0f;  // a 4th channel: ignored
                unsigned char* p = &s.bytes[y * rowStride + x * pixelStride + c * valueBytes];
                if (type == DataType::Float16) {
                    std::uint16_t hv = floatToHalf(v);
                    std::memcpy(p, &hv, 2);
                } else if (type == DataType::Int32) {
                    std::int32_t iv = std::int32_t(v);
                    std::memcpy(p, &iv, 4);
                } else {
                    std::memcpy(p, &v, 4);
                }
            }
    s.view = ImageView(s.bytes.data(), type, channels, pixelStride, rowStride);
    return s;
}

inline std::vector<float> halfRounded(std::vector<float> v) {
    for (float& x : v) x = halfToFloat(floatToHalf(x));
    return v;
}

}  // namespace rtd::test
