// Back-projection of each pixel into the previous frame (assignment formula):
//   Screen_{i-1} = WorldToScreen_{i-1} * M_{i-1}[id] * inverse(M_i[id]) * World_i
// The host folds the three matrices into one per object. The history is sampled bilinearly over
// the 2x2 taps that are inside the screen and hold the same object; the other taps' weights are
// dropped and the rest renormalised.
#pragma once

#include "kernels/views.h"

namespace rtd {

enum ReprojectionCode : std::uint8_t {
    kReprojectionValid = 0,
    kReprojectionOutsideScreen = 1,
    kReprojectionOtherObject = 2,
    kReprojectionBackground = 3,
    kReprojectionNoHistory = 4,
};

struct ObjectReprojection {
    Mat4 currentWorldToPreviousScreen;
    std::int32_t valid;  // 0 if the object did not exist in the previous frame or is singular
};

struct ReprojectKernel {
    GBufferView g;                         // current frame
    const std::int32_t* previousObjectId;  // previous frame's ID buffer (same layout)
    const ObjectReprojection* objects;     // one per object ID of the current frame
    Planes3 history;                       // previous frame's output
    Planes3 reprojected;                   // history sampled at each current pixel
    std::uint8_t* validity;                // ReprojectionCode per pixel (same layout)
    int hasHistory;                        // 0 on the first frame: nothing to reproject

    RTD_HOST_DEVICE RTD_INLINE void operator()(int x, int y) const {
        const Layout& L = g.layout;
        int i = L.index(x, y);
        std::int32_t id = g.objectId[i];
        reprojected.store(i, Float3{});
        if (id < 0) {
            validity[i] = kReprojectionBackground;
            return;
        }
        if (!hasHistory) {
            validity[i] = kReprojectionNoHistory;
            return;
        }
        const ObjectReprojection& object = objects[id];
        if (!object.valid) {
            validity[i] = kReprojectionOtherObject;
            return;
        }
        Float4 s = transformPoint(object.currentWorldToPreviousScreen, g.position.load(i));
        if (!(s.w > 0.0f)) {  // behind the previous camera (or NaN)
            validity[i] = kReprojectionOutsideScreen;
            return;
        }
        // Continuous coordinates in which pixel centres are integers.
        float sx = s.x / s.w - 0.5f, sy = s.y / s.w - 0.5f;
        if (!(sx > -1.0f && sx < float(L.width) && sy > -1.0f && sy < float(L.height))) {
            validity[i] = kReprojectionOutsideScreen;
            return;
        }
        int x0 = int(std::floor(sx)), y0 = int(std::floor(sy));
        float fx = sx - float(x0), fy = sy - float(y0);
        Float3 sum;
        float sumW = 0.0f;
        bool anyInside = false;
        for (int t = 0; t < 4; ++t) {
            int tx = x0 + (t & 1), ty = y0 + (t >> 1);
            if (tx < 0 || ty < 0 || tx >= L.width || ty >= L.height) continue;
            float w = ((t & 1) ? fx : 1.0f - fx) * ((t >> 1) ? fy : 1.0f - fy);
            if (w <= 0.0f) continue;
            anyInside = true;
            int j = L.index(tx, ty);
            if (previousObjectId[j] != id) continue;
            sum += history.load(j) * w;
            sumW += w;
        }
        if (sumW < 1e-4f) {
            validity[i] = anyInside ? kReprojectionOtherObject : kReprojectionOutsideScreen;
            return;
        }
        reprojected.store(i, sum * (1.0f / sumW));
        validity[i] = kReprojectionValid;
    }
};

}  // namespace rtd
