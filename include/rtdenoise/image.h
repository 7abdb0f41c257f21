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
    // 1 channel in [0, 1], optional: how far the history of each pixel still holds (NVIDIA NRD's
    // IN_DIFF_CONFIDENCE): 1 keeps it, 0 where the lighting changed (a light switched), drop it.
    std::optional<Image> confidence;
    // The split signal (optional; NVIDIA NRD's diffuse/specular inputs). specular: 3 channels, the
    // part of beauty that left the first surface through its glossy lobe (the diffuse part is
    // beauty - specular, demodulated by `albedo` as the beauty is; the specular part is not
    // demodulated). roughness: 1 channel in [0, 1] (sqrt of GGX alpha),
    // needed with specular. hitDistance: 1 channel, world units from the first surface to what
    // its specular ray hit (0: unknown), optional: it lets reflections be reprojected.
    std::optional<Image> specular;
    std::optional<Image> roughness;
    std::optional<Image> hitDistance;
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

// The element type of a buffer's values.
enum class DataType {
    Float32,
    Float16,  // IEEE 754 half (what GPU renderers keep RGBA buffers in)
    Int32,    // object IDs
};

// One image of a FrameView in the caller's layout (as OpenImageIO's image_span or OIDN's
// setImage): pixel (x, y) at data + y * rowStride + x * pixelStride bytes, its first `channels`
// values of `type`. Strides 0 mean packed. Converts from a packed float or int32 pointer, so
// that `view.beauty = rgb` keeps meaning interleaved RGB floats.
struct ImageView {
    const void* data = nullptr;
    DataType type = DataType::Float32;
    int channels = 0;             // values per pixel (0: the image's own count, e.g. 3 for RGB)
    std::size_t pixelStride = 0;  // bytes from one pixel to the next (0: channels * value size)
    std::size_t rowStride = 0;    // bytes from one row to the next (0: width * pixelStride)

    ImageView() = default;
    ImageView(std::nullptr_t) {}
    ImageView(const float* packed) : data(packed) {}
    ImageView(const std::int32_t* packed) : data(packed), type(DataType::Int32), channels(1) {}
    ImageView(const void* data, DataType type, int channels, std::size_t pixelStride = 0,
              std::size_t rowStride = 0)
        : data(data),
          type(type),
          channels(channels),
          pixelStride(pixelStride),
          rowStride(rowStride) {}
    explicit operator bool() const { return data != nullptr; }
};

// The result in the caller's layout: float or half, 3 channels (RGB) or 4 (alpha set to 1; to
// keep the caller's own alpha, give 3 channels and a 4-channel pixel stride).
struct OutputView {
    void* data = nullptr;
    DataType type = DataType::Float32;
    int channels = 3;
    std::size_t pixelStride = 0;
    std::size_t rowStride = 0;
};

// A frame in buffers the caller owns, rows top to bottom, width * height pixels each, all in
// `space` (the matrices are on the host). Nothing is copied where a buffer is packed float (int32
// IDs) in memory the device reads; other layouts are converted on the device.
// - beauty, albedo: RGB (3 or 4 channels, a 4th ignored); normal, position: xyz likewise;
// - depth: 1 channel, see depthKind; objectId: int32, or float (IDs rounded), -1 on background;
// - motion (optional): 2 channels in pixels, previous = current + motion (NVIDIA NRD's
//   convention; DenoiserSettings::motion converts others), optionally a 3rd: previous depth minus
//   current depth. With motion, no matrices are needed: objectCount alone bounds the IDs.
// - confidence (optional): 1 channel in [0, 1], 1 where the history holds, 0 where the lighting
//   changed (NRD's IN_DIFF_CONFIDENCE); a value outside [0, 1] is clamped, NaN reads as 1.
// - specular, roughness, hitDistance (optional, the split signal): as Frame's.
struct FrameView {
    int width = 0;
    int height = 0;
    MemorySpace space = MemorySpace::Host;
    ImageView beauty;
    ImageView normal;
    ImageView position;
    ImageView depth;
    DepthKind depthKind = DepthKind::ViewZ;
    ImageView objectId;                      // -1 or 0..objectCount-1 (checked on the device)
    ImageView albedo;                        // optional
    ImageView motion;                        // optional: replaces the matrices
    ImageView confidence;                    // optional: history confidence, 1 channel
    ImageView specular;                      // optional: the specular part of beauty, RGB
    ImageView roughness;                     // with specular: 1 channel in [0, 1]
    ImageView hitDistance;                   // optional, with specular: 1 channel
    const Matrix4* objectToWorld = nullptr;  // objectCount matrices (unused with motion)
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
    v.depthKind = frame.depthKind;
    v.objectId = frame.objectId.data();
    if (frame.albedo) v.albedo = frame.albedo->pixels.data();
    if (frame.motion)
        v.motion =
            ImageView(frame.motion->pixels.data(), DataType::Float32, frame.motion->channels);
    if (frame.confidence)
        v.confidence = ImageView(frame.confidence->pixels.data(), DataType::Float32,
                                 frame.confidence->channels);
    if (frame.specular) v.specular = frame.specular->pixels.data();
    if (frame.roughness)
        v.roughness = ImageView(frame.roughness->pixels.data(), DataType::Float32,
                                frame.roughness->channels);
    if (frame.hitDistance)
        v.hitDistance = ImageView(frame.hitDistance->pixels.data(), DataType::Float32,
                                  frame.hitDistance->channels);
    v.objectToWorld = frame.objectToWorld.data();
    v.objectCount = frame.objectCount > 0 ? frame.objectCount : int(frame.objectToWorld.size());
    v.worldToCamera = frame.worldToCamera;
    v.worldToScreen = frame.worldToScreen;
    return v;
}

}  // namespace rtd
