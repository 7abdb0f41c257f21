// Back-projection of each pixel into the previous frame (assignment formula):
//   Screen_{i-1} = WorldToScreen_{i-1} * M_{i-1}[id] * inverse(M_i[id]) * World_i
// The host folds the three matrices into one per object. The history is sampled bilinearly over
// the 2x2 taps that pass the history test (inside the screen, same object, and optionally depth
// and normal agreeing); the other taps' weights are dropped and the rest renormalised. When all
// four fail, an optional 3x3 search around the nearest pixel averages the taps that pass.
#pragma once

#include "kernels/history_test.h"
#include "kernels/views.h"

namespace rtd {

enum ReprojectionCode : std::uint8_t {
    kReprojectionValid = 0,
    kReprojectionOutsideScreen = 1,
    kReprojectionOtherObject = 2,  // or, with geometry tests, depth/normal disagree
    kReprojectionBackground = 3,
    kReprojectionNoHistory = 4,
    // Transient (DetailSpecularFollow to DetailSpecularSurface): the reflection could not be
    // followed, the surface's history is still to be found.
    kReprojectionPending = 5,
};

struct ObjectReprojection {
    Mat4 currentWorldToPreviousScreen;
    Mat4 currentWorldToPreviousWorld;  // rotates normals into the previous frame
    std::int32_t valid;  // 0 if the object did not exist in the previous frame or is singular
};

// What the previous frame looked like, for the history test, and where each pixel was in it.
struct PreviousGeometry {
    const std::int32_t* objectId;
    const float* depth;
    Planes3 normal;
    NormalDepth4 normalDepth = {};  // the GPU's: normal and depth interleaved (views.h)
    // With motion vectors (fromMotion): each pixel's previous position and expected depth
    // (MotionIngestKernel), in place of the object's matrix.
    Planes3 motion = {};
    int fromMotion = 0;
};

// Object `id`'s reprojection entry (entry 0 where `covered` is false: the caller then does not
// trust it). With motion vectors every object's entry is the same identity, held once, so that
// the table does not grow with the object count.
RTD_HOST_DEVICE RTD_INLINE const ObjectReprojection& objectEntry(const ObjectReprojection* objects,
                                                                 std::int32_t id, bool covered,
                                                                 const PreviousGeometry& previous) {
    return objects[covered && previous.fromMotion == 0 ? id : 0];
}

// Where pixel i was in the previous frame: continuous coordinates in which pixel centres are
// integers, and its expected view depth there. Motion vectors give both (the object's matrix is
// the identity then, and its transform unused); else the object's matrix. Both ways are computed
// and one selected: no branch. Without motion the position is loaded in their place: already
// loaded, no memory traffic.
struct PreviousPixel {
    float x, y, depth;
};
RTD_HOST_DEVICE RTD_INLINE PreviousPixel previousPixel(const GBufferView& g, PixelIndex i,
                                                       const PreviousGeometry& previous,
                                                       const ObjectReprojection& object) {
    const Float4 s = transformPoint(object.currentWorldToPreviousScreen, g.position.load(i));
    const bool fromMotion = previous.fromMotion != 0;
    const Float3 moved = (fromMotion ? previous.motion : g.position).load(i);
    const float inverseW = 1.0f / (s.w > 0.0f ? s.w : 1.0f);
    return {fromMotion ? moved.x : s.x * inverseW - 0.5f,
            fromMotion ? moved.y : s.y * inverseW - 0.5f, fromMotion ? moved.z : s.w};
}

// The previous-frame pixels that may hold pixel i's history, and their weights (summing to 1
// when code is valid, all 0 otherwise). Without the 3x3 search: the bilinear 2x2 block. With it:
// the 3x3 block around the nearest pixel, which always contains the 2x2 block, so one fixed set
// of taps serves both the bilinear weights and the search. Consumers loop over all the taps
// with no data-dependent control flow, which lets the CPU vectorise them.
template <int Taps>
struct HistoryTaps {
    static constexpr int kCount = Taps;
    // Always inside the padded plane, even when unused. The 2x2 block's taps are in raster
    // order, so index[1] = index[0] + 1 and index[3] = index[2] + 1 (loadTaps reads them in
    // pairs).
    PixelIndex index[Taps];
    float weight[Taps];
    std::uint8_t code;
};

// A plane's values at the taps. The 2x2 block: two pairs of neighbours (loadPair).
template <int Taps, class T>
RTD_HOST_DEVICE RTD_INLINE void loadTaps(const T* plane, const HistoryTaps<Taps>& taps,
                                         T (&values)[Taps]) {
    if constexpr (Taps == 4) {
        loadPair(plane + taps.index[0], values[0], values[1]);
        loadPair(plane + taps.index[2], values[2], values[3]);
    } else {
        RTD_UNROLL
        for (int t = 0; t < Taps; ++t) values[t] = plane[taps.index[t]];
    }
}

// Three planes' values at the taps (a colour, a normal).
template <int Taps>
RTD_HOST_DEVICE RTD_INLINE void loadTaps(const Planes3& planes, const HistoryTaps<Taps>& taps,
                                         float (&x)[Taps], float (&y)[Taps], float (&z)[Taps]) {
    loadTaps(planes.data, taps, x);
    loadTaps(planes.data + planes.planeSize, taps, y);
    loadTaps(planes.data + 2 * planes.planeSize, taps, z);
}

// The current frame's depth slopes and normal change at a pixel (GeometryDerivatives).
struct GeometrySlopes {
    float dzdx, dzdy, fwidthNormal;
};
RTD_HOST_DEVICE RTD_INLINE GeometrySlopes slopesAt(const PlaneSet& derivatives, PixelIndex i) {
    return {derivatives.at(0, i), derivatives.at(1, i), derivatives.at(2, i)};
}

// Locates pixel i's history. `slopes`: the current frame's at i (GeometryDerivatives).
// Search3x3: when all four bilinear taps fail the history test, average the 3x3 taps that pass.
// Branch-free: every test yields a mask, and a pixel that fails one still computes the rest on
// safe (clamped) coordinates; needs layout.padding >= 2.
// KnownId: the caller knows the pixel's object ID (`knownId`, the same for a whole run of pixels
// on the CPU, parallel_for.h), so the object's matrices are one value for the run rather than
// gathered per pixel. Interleaved: normals and depths from the interleaved copies (views.h), the
// current frame's and the previous one's.
template <bool Search3x3, bool KnownId = false, bool Interleaved = false>
RTD_HOST_DEVICE RTD_INLINE HistoryTaps<Search3x3 ? 9 : 4> findHistory(
    const GBufferView& g, PixelIndex i, const PreviousGeometry& previous,
    const ObjectReprojection* objects, int objectCount, GeometrySlopes slopes,
    const HistoryTest& test, int hasHistory, std::int32_t knownId = 0) {
    constexpr int kTaps = Search3x3 ? 9 : 4;
    const Layout& L = g.layout;
    std::int32_t id = KnownId ? knownId : g.objectId[i];
    // An ID the matrices do not cover (unchecked device input) reads object 0, then fails.
    bool covered = id >= 0 && id < objectCount;
    const ObjectReprojection& object = objectEntry(objects, id, covered, previous);
    bool trackable = covered && hasHistory && object.valid;

    const PreviousPixel before = previousPixel(g, i, previous, object);
    float expectedDepth = before.depth;
    bool inFront = expectedDepth > 0.0f;  // false behind the previous camera, or NaN
    float sx = before.x, sy = before.y;
    bool onScreen =
        inFront && sx > -1.0f && sx < float(L.width) && sy > -1.0f && sy < float(L.height);
    sx = onScreen ? sx : 0.0f;
    sy = onScreen ? sy : 0.0f;

    // Rigid motion (or uniform scale) assumed: the rotated normal, renormalised.
    Float3 normal;
    float depth;
    loadNormalDepth<Interleaved>(g, i, normal, depth);
    Float3 expectedNormal = normalize(transformVector(object.currentWorldToPreviousWorld, normal));
    float dzdx = slopes.dzdx, dzdy = slopes.dzdy;
    float fwidthDepth = absf(dzdx) + absf(dzdy);
    float fwidthNormal = slopes.fwidthNormal;

    float floorX = std::floor(sx), floorY = std::floor(sy);
    float fx = sx - floorX, fy = sy - floorY;
    int x0 = int(floorX), y0 = int(floorY);
    // The first tap: the 2x2 block's corner, or the 3x3 block's around the nearest pixel.
    int firstX = Search3x3 ? int(std::floor(sx + 0.5f)) - 1 : x0;
    int firstY = Search3x3 ? int(std::floor(sy + 0.5f)) - 1 : y0;
    constexpr int kSide = Search3x3 ? 3 : 2;

    HistoryTaps<kTaps> taps;
    RTD_UNROLL
    for (int t = 0; t < kTaps; ++t) taps.index[t] = L.index(firstX + t % kSide, firstY + t / kSide);
    // The previous frame's geometry at the taps (off the screen: the border, object ID -1, which
    // the ID test rejects).
    std::int32_t previousId[kTaps];
    float previousDepth[kTaps], previousNx[kTaps], previousNy[kTaps], previousNz[kTaps];
    loadTaps(previous.objectId, taps, previousId);
    if constexpr (Interleaved) {
        RTD_UNROLL
        for (int t = 0; t < kTaps; ++t) {
            Float3 n;
            previous.normalDepth.load(taps.index[t], n, previousDepth[t]);
            previousNx[t] = n.x;
            previousNy[t] = n.y;
            previousNz[t] = n.z;
        }
    } else {
        loadTaps(previous.depth, taps, previousDepth);
        loadTaps(previous.normal, taps, previousNx, previousNy, previousNz);
    }
    bool accepted[kTaps];
    float bilinearSum = 0.0f, acceptedCount = 0.0f;
    RTD_UNROLL
    for (int t = 0; t < kTaps; ++t) {
        int tx = firstX + t % kSide, ty = firstY + t / kSide;
        bool ok = acceptHistory(test, id, previousId[t], expectedDepth, previousDepth[t],
                                fwidthDepth, expectedNormal,
                                make3(previousNx[t], previousNy[t], previousNz[t]), fwidthNormal);
        float wx = tx == x0 ? 1.0f - fx : tx == x0 + 1 ? fx : 0.0f;
        float wy = ty == y0 ? 1.0f - fy : ty == y0 + 1 ? fy : 0.0f;
        accepted[t] = ok;
        taps.weight[t] = ok ? wx * wy : 0.0f;
        bilinearSum += taps.weight[t];
        acceptedCount += ok ? 1.0f : 0.0f;
    }
    bool search = Search3x3 && bilinearSum < 1e-4f;
    float total = search ? acceptedCount : bilinearSum;
    bool valid = trackable && onScreen && total >= 1e-4f;
    float scale = valid ? 1.0f / total : 0.0f;
    RTD_UNROLL
    for (int t = 0; t < kTaps; ++t)
        taps.weight[t] = (search ? (accepted[t] ? 1.0f : 0.0f) : taps.weight[t]) * scale;
    taps.code = id < 0        ? kReprojectionBackground
                : !hasHistory ? kReprojectionNoHistory
                : !trackable  ? kReprojectionOtherObject
                : !onScreen   ? kReprojectionOutsideScreen
                : !valid      ? kReprojectionOtherObject
                              : kReprojectionValid;
    return taps;
}

// Local depth slope and normal change of each pixel, from its neighbours on the same object
// (central differences where both exist, one-sided at object edges). Interleaved: normal and
// depth from the interleaved copy (views.h), the GPU's.
template <bool Interleaved = false>
struct GeometryDerivatives {
    GBufferView g;
    PlaneSet out;  // 0: dz/dx, 1: dz/dy, 2: fwidth(n) = |n(x+1)-n| + |n(y+1)-n| (or left/up)

    // (The half a caller does not use is never loaded: dead loads are dropped.)
    RTD_HOST_DEVICE RTD_INLINE float depthAt(PixelIndex j) const {
        Float3 n;
        float z;
        loadNormalDepth<Interleaved>(g, j, n, z);
        return z;
    }
    RTD_HOST_DEVICE RTD_INLINE Float3 normalAt(PixelIndex j) const {
        Float3 n;
        float z;
        loadNormalDepth<Interleaved>(g, j, n, z);
        return n;
    }
    RTD_HOST_DEVICE RTD_INLINE float slope(PixelIndex i, PixelIndex step) const {
        std::int32_t id = g.objectId[i];
        bool before = g.objectId[i - step] == id, after = g.objectId[i + step] == id;
        float z = depthAt(i);
        if (before && after) return 0.5f * (depthAt(i + step) - depthAt(i - step));
        if (after) return depthAt(i + step) - z;
        if (before) return z - depthAt(i - step);
        return 0.0f;
    }
    RTD_HOST_DEVICE RTD_INLINE float normalChange(PixelIndex i, PixelIndex step) const {
        std::int32_t id = g.objectId[i];
        bool after = g.objectId[i + step] == id, before = g.objectId[i - step] == id;
        // Selects between loaded neighbours, not a chosen index: the CPU then loads contiguous
        // vectors rather than gathering.
        Float3 n = normalAt(i), nAfter = normalAt(i + step), nBefore = normalAt(i - step);
        Float3 dAfter = nAfter - n, dBefore = nBefore - n;
        float dx = after ? dAfter.x : before ? dBefore.x : 0.0f;
        float dy = after ? dAfter.y : before ? dBefore.y : 0.0f;
        float dz = after ? dAfter.z : before ? dBefore.z : 0.0f;
        return std::sqrt(dx * dx + dy * dy + dz * dz);
    }
    RTD_HOST_DEVICE RTD_INLINE void operator()(int x, int y) const {
        const Layout& L = g.layout;
        PixelIndex i = L.index(x, y);
        if (g.objectId[i] < 0) {
            out.at(0, i) = 0.0f;
            out.at(1, i) = 0.0f;
            out.at(2, i) = 0.0f;
            return;
        }
        // All read before any store (the stores could alias the inputs for the compiler).
        GeometrySlopes s = slopes(i);
        out.at(0, i) = s.dzdx;
        out.at(1, i) = s.dzdy;
        out.at(2, i) = s.fwidthNormal;
    }
    // An object pixel's (ReprojectAccumulate computes them where it needs them).
    RTD_HOST_DEVICE RTD_INLINE GeometrySlopes slopes(PixelIndex i) const {
        const PixelIndex down = g.layout.pitch;
        return {slope(i, 1), slope(i, down), normalChange(i, 1) + normalChange(i, down)};
    }
};
using GeometryDerivativesKernel = GeometryDerivatives<false>;
using GeometryDerivativesInterleavedKernel = GeometryDerivatives<true>;

// The assignment's pipeline: history colour at each pixel (0 where invalid) and why.
struct ReprojectKernel {
    GBufferView g;  // current frame
    PreviousGeometry previous;
    const ObjectReprojection* objects;  // one per object ID of the current frame
    int objectCount;
    PlaneSet derivatives;
    HistoryTest test;
    Planes3 history;         // previous frame's output
    Planes3 reprojected;     // history sampled at each current pixel
    std::uint8_t* validity;  // ReprojectionCode per pixel
    int hasHistory;          // 0 on the first frame: nothing to reproject

    // Runs of pixels on one object (the CPU launcher, parallel_for.h): see findHistory.
    RTD_HOST_DEVICE RTD_INLINE std::int32_t runKey(int x, int y) const {
        return g.objectId[g.layout.index(x, y)];
    }
    RTD_HOST_DEVICE RTD_INLINE void operator()(int x, int y) const { pixel<false>(x, y, 0); }
    template <bool KnownId>
    RTD_HOST_DEVICE RTD_INLINE void pixel(int x, int y, std::int32_t id) const {
        PixelIndex i = g.layout.index(x, y);
        std::uint8_t code;
        reprojected.store(i, sample<KnownId>(i, id, code));
        validity[i] = code;
    }
    // Pixel i's history colour (0 where invalid) and why (`code`, a ReprojectionCode).
    template <bool KnownId>
    RTD_HOST_DEVICE RTD_INLINE Float3 sample(PixelIndex i, std::int32_t id,
                                             std::uint8_t& code) const {
        return sample<KnownId>(i, id, code, slopesAt(derivatives, i));
    }
    // With the slopes given (ReprojectAccumulate: computed, not read from `derivatives`).
    template <bool KnownId>
    RTD_HOST_DEVICE RTD_INLINE Float3 sample(PixelIndex i, std::int32_t id, std::uint8_t& code,
                                             GeometrySlopes slopes) const {
        auto taps = findHistory<false, KnownId>(g, i, previous, objects, objectCount, slopes, test,
                                                hasHistory, id);
        constexpr int kTaps = decltype(taps)::kCount;
        float r[kTaps], gr[kTaps], b[kTaps];
        loadTaps(history, taps, r, gr, b);
        Float3 sum;  // 0 where invalid: every weight is 0
        RTD_UNROLL
        for (int t = 0; t < kTaps; ++t) sum += make3(r[t], gr[t], b[t]) * taps.weight[t];
        code = taps.code;
        return sum;
    }
};

}  // namespace rtd
