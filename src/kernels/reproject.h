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
};

struct ObjectReprojection {
    Mat4 currentWorldToPreviousScreen;
    Mat4 currentWorldToPreviousWorld;  // rotates normals into the previous frame
    std::int32_t valid;  // 0 if the object did not exist in the previous frame or is singular
};

// What the previous frame looked like, for the history test.
struct PreviousGeometry {
    const std::int32_t* objectId;
    const float* depth;
    Planes3 normal;
};

// Up to 9 previous-frame pixels and their weights (summing to 1 when code is valid).
struct HistoryTaps {
    PixelIndex index[9];
    float weight[9];
    int count;
    std::uint8_t code;
};

// Locates pixel i's history. `derivatives`: planes dz/dx, dz/dy, fwidth(n) of the current frame.
RTD_HOST_DEVICE RTD_INLINE HistoryTaps findHistory(const GBufferView& g, PixelIndex i,
                                                   const PreviousGeometry& previous,
                                                   const ObjectReprojection* objects,
                                                   int objectCount, const PlaneSet& derivatives,
                                                   const HistoryTest& test, int search3x3,
                                                   int hasHistory) {
    HistoryTaps taps;
    taps.count = 0;
    const Layout& L = g.layout;
    std::int32_t id = g.objectId[i];
    if (id < 0) {
        taps.code = kReprojectionBackground;
        return taps;
    }
    if (!hasHistory) {
        taps.code = kReprojectionNoHistory;
        return taps;
    }
    if (id >= objectCount) {  // an ID the matrices do not cover (unchecked device input)
        taps.code = kReprojectionOtherObject;
        return taps;
    }
    const ObjectReprojection& object = objects[id];
    if (!object.valid) {
        taps.code = kReprojectionOtherObject;
        return taps;
    }
    Float3 position = g.position.load(i);
    Float4 s = transformPoint(object.currentWorldToPreviousScreen, position);
    if (!(s.w > 0.0f)) {  // behind the previous camera (or NaN)
        taps.code = kReprojectionOutsideScreen;
        return taps;
    }
    // Continuous coordinates in which pixel centres are integers.
    float sx = s.x / s.w - 0.5f, sy = s.y / s.w - 0.5f;
    if (!(sx > -1.0f && sx < float(L.width) && sy > -1.0f && sy < float(L.height))) {
        taps.code = kReprojectionOutsideScreen;
        return taps;
    }
    // Rigid motion (or uniform scale) assumed: the rotated normal, renormalised.
    Float3 expectedNormal =
        normalize(transformVector(object.currentWorldToPreviousWorld, g.normal.load(i)));
    float dzdx = derivatives.at(0, i), dzdy = derivatives.at(1, i);
    float fwidthDepth = (dzdx < 0 ? -dzdx : dzdx) + (dzdy < 0 ? -dzdy : dzdy);
    float fwidthNormal = derivatives.at(2, i);
    auto accepted = [&](int tx, int ty) {
        PixelIndex j = L.index(tx, ty);
        return acceptHistory(test, id, previous.objectId[j], s.w, previous.depth[j], fwidthDepth,
                             expectedNormal, previous.normal.load(j), fwidthNormal);
    };

    int x0 = int(std::floor(sx)), y0 = int(std::floor(sy));
    float fx = sx - float(x0), fy = sy - float(y0);
    float sumW = 0.0f;
    for (int t = 0; t < 4; ++t) {
        int tx = x0 + (t & 1), ty = y0 + (t >> 1);
        float w = ((t & 1) ? fx : 1.0f - fx) * ((t >> 1) ? fy : 1.0f - fy);
        if (tx < 0 || ty < 0 || tx >= L.width || ty >= L.height || w <= 0.0f) continue;
        if (!accepted(tx, ty)) continue;
        taps.index[taps.count] = L.index(tx, ty);
        taps.weight[taps.count] = w;
        ++taps.count;
        sumW += w;
    }
    if (sumW < 1e-4f && search3x3) {
        taps.count = 0;
        sumW = 0.0f;
        int cx = int(std::floor(sx + 0.5f)), cy = int(std::floor(sy + 0.5f));
        for (int dy = -1; dy <= 1; ++dy)
            for (int dx = -1; dx <= 1; ++dx) {
                int tx = cx + dx, ty = cy + dy;
                if (tx < 0 || ty < 0 || tx >= L.width || ty >= L.height) continue;
                if (!accepted(tx, ty)) continue;
                taps.index[taps.count] = L.index(tx, ty);
                taps.weight[taps.count] = 1.0f;
                ++taps.count;
                sumW += 1.0f;
            }
    }
    if (sumW < 1e-4f) {
        taps.count = 0;
        taps.code = kReprojectionOtherObject;
        return taps;
    }
    for (int t = 0; t < taps.count; ++t) taps.weight[t] /= sumW;
    taps.code = kReprojectionValid;
    return taps;
}

// Local depth slope and normal change of each pixel, from its neighbours on the same object
// (central differences where both exist, one-sided at object edges).
struct GeometryDerivativesKernel {
    GBufferView g;
    PlaneSet out;  // 0: dz/dx, 1: dz/dy, 2: fwidth(n) = |n(x+1)-n| + |n(y+1)-n| (or left/up)

    RTD_HOST_DEVICE RTD_INLINE float slope(PixelIndex i, PixelIndex step) const {
        std::int32_t id = g.objectId[i];
        bool before = g.objectId[i - step] == id, after = g.objectId[i + step] == id;
        float z = g.depth[i];
        if (before && after) return 0.5f * (g.depth[i + step] - g.depth[i - step]);
        if (after) return g.depth[i + step] - z;
        if (before) return z - g.depth[i - step];
        return 0.0f;
    }
    RTD_HOST_DEVICE RTD_INLINE float normalChange(PixelIndex i, PixelIndex step) const {
        std::int32_t id = g.objectId[i];
        PixelIndex j = g.objectId[i + step] == id ? i + step : g.objectId[i - step] == id ? i - step : i;
        Float3 d = g.normal.load(j) - g.normal.load(i);
        return std::sqrt(dot(d, d));
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
        out.at(0, i) = slope(i, 1);
        out.at(1, i) = slope(i, L.pitch);
        out.at(2, i) = normalChange(i, 1) + normalChange(i, L.pitch);
    }
};

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

    RTD_HOST_DEVICE RTD_INLINE void operator()(int x, int y) const {
        PixelIndex i = g.layout.index(x, y);
        HistoryTaps taps =
            findHistory(g, i, previous, objects, objectCount, derivatives, test, 0, hasHistory);
        Float3 sum;
        for (int t = 0; t < taps.count; ++t) sum += history.load(taps.index[t]) * taps.weight[t];
        reprojected.store(i, sum);
        validity[i] = taps.code;
    }
};

}  // namespace rtd
