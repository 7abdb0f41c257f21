// Host-side images and frames: what a renderer hands to the denoiser and what it gets back.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <vector>

namespace rtd {

// Radiance (and albedo) magnitudes above this are clamped to it as a frame is read, and counted
// (FrameStats::radianceClamped): the filters' sums of squares over their windows then stay
// finite at any finite input (1e16 squared, times the 31x31 widest window, is under 1e36).
constexpr float kMaxRadiance = 1e16f;

// A float image with 1 to 4 interleaved channels, rows top to bottom.
struct Image {
    int width = 0;
    int height = 0;
    int channels = 0;
    std::vector<float> pixels;  // width * height * channels values

    Image() = default;
    Image(int w, int h, int c, float fill = 0.0f)
        : width(w), height(h), channels(c), pixels(std::size_t(w) * h * c, fill) {}

    std::size_t pixelCount() const { return std::size_t(width) * height; }
    float& at(int x, int y, int c = 0) {
        return pixels[(std::size_t(y) * width + x) * channels + c];
    }
    float at(int x, int y, int c = 0) const {
        return pixels[(std::size_t(y) * width + x) * channels + c];
    }
    bool empty() const { return pixels.empty(); }
};

// Row-major 4x4 matrix (m[row][col]); points are column vectors: s = M * (x, y, z, 1).
struct Matrix4 {
    std::array<std::array<float, 4>, 4> m{};
    static Matrix4 identity() {
        Matrix4 r;
        for (int i = 0; i < 4; ++i) r.m[i][i] = 1.0f;
        return r;
    }
};

// What a depth buffer holds. The history test compares depths across frames: both kinds work;
// with matrices (no motion vectors) a ray distance is turned into view depth from the position.
enum class DepthKind {
    ViewZ,        // distance from the camera plane (w after projection)
    RayDistance,  // distance from the camera along the pixel's ray (Cycles' Depth is ViewZ:
                  // measured on Blender 3.4, docs/inputs.md)
};

// One frame of a path-traced sequence with its G-buffer (layout: shared/data/README.md).
// Back-projection into the previous frame comes from the per-object matrices or, where the frame
// has them, from its motion vectors (then no matrices are needed).
struct Frame {
    Image beauty;    // 3 channels, noisy linear radiance
    Image normal;    // 3 channels, world-space unit normal, (0,0,0) on background
    Image position;  // 3 channels, world-space hit position
    Image depth;     // 1 channel, see depthKind
    DepthKind depthKind = DepthKind::ViewZ;
    std::vector<std::int32_t> objectId;  // width * height, 0..K-1, -1 on background
    std::optional<Image> albedo;         // 3 channels, optional
    // 2 channels, pixels (x right, y down): a pixel's point was at (x, y) + motion in the
    // previous frame (NVIDIA NRD's convention: previous = current + motion). A third channel,
    // where given, is the point's previous depth minus its current one (same units as depth).
    std::optional<Image> motion;
    std::vector<Matrix4> objectToWorld;  // K matrices, object k's local-to-world (none: motion)
    // With motion vectors and no matrices: IDs are -1..objectCount-1 (0: objectToWorld.size()).
    int objectCount = 0;
    Matrix4 worldToCamera = Matrix4::identity();
    Matrix4 worldToScreen = Matrix4::identity();

    int width() const { return beauty.width; }
    int height() const { return beauty.height; }
};

// Where the buffers of a FrameView live.
enum class MemorySpace {
    Host,    // ordinary memory
    Device,  // memory of the denoiser's GPU (a renderer that keeps its G-buffer there); needs
             // a Denoiser on a GPU device
};

// A frame in buffers the caller owns (nothing is copied on the host side): beauty, normal,
// position and albedo interleaved RGB floats, depth one float, IDs one int32 per pixel, rows
// top to bottom, width * height pixels each, all in `space`. The matrices are on the host.
struct FrameView {
    int width = 0;
    int height = 0;
    MemorySpace space = MemorySpace::Host;
    const float* beauty = nullptr;
    const float* normal = nullptr;
    const float* position = nullptr;
    const float* depth = nullptr;
    const std::int32_t* objectId = nullptr;  // -1 or 0..objectCount-1 (checked on the device)
    const float* albedo = nullptr;           // optional
    const Matrix4* objectToWorld = nullptr;  // objectCount matrices
    int objectCount = 0;
    Matrix4 worldToCamera = Matrix4::identity();
    Matrix4 worldToScreen = Matrix4::identity();
};

// A host view of `frame` (valid while `frame` lives).
inline FrameView viewOf(const Frame& frame) {
    FrameView v;
    v.width = frame.width();
    v.height = frame.height();
    v.beauty = frame.beauty.pixels.data();
    v.normal = frame.normal.pixels.data();
    v.position = frame.position.pixels.data();
    v.depth = frame.depth.pixels.data();
    v.objectId = frame.objectId.data();
    v.albedo = frame.albedo ? frame.albedo->pixels.data() : nullptr;
    v.objectToWorld = frame.objectToWorld.data();
    v.objectCount = int(frame.objectToWorld.size());
    v.worldToCamera = frame.worldToCamera;
    v.worldToScreen = frame.worldToScreen;
    return v;
}

}  // namespace rtd
