// Whether a previous-frame pixel may serve as the history of a current pixel (Schied et al. 2017,
// as in Falcor's SVGF): same object, depth within a tolerance scaled by the local depth change per
// pixel, normal within a tolerance scaled by the local normal change per pixel. Used by the
// temporal and SVGF reprojections.
#pragma once

#include "kernels/views.h"

namespace rtd {

struct HistoryTest {
    int geometry;           // 0: the object ID alone decides (the assignment's test)
    float depthTolerance;   // reject if |dz| / (fwidth(z) + 0.01) exceeds it (Falcor: 10)
    float normalTolerance;  // reject if |dn| / (fwidth(n) + 0.01) exceeds it (Falcor: 16)
};

// `expectedDepth`/`expectedNormal`: the current surface point seen from the previous frame.
RTD_HOST_DEVICE RTD_INLINE bool acceptHistory(const HistoryTest& t, std::int32_t id,
                                              std::int32_t previousId, float expectedDepth,
                                              float previousDepth, float fwidthDepth,
                                              Float3 expectedNormal, Float3 previousNormal,
                                              float fwidthNormal) {
    // Every term evaluated and combined with & and |, not early returns: no branch on the
    // setting (or per tap) inside the CPU's vectorised pixel loop.
    float dz = expectedDepth - previousDepth;
    bool depthOk = absf(dz) <= t.depthTolerance * (fwidthDepth + 0.01f);
    Float3 dn = expectedNormal - previousNormal;
    // A pixel without a normal (0, the ingest's) on either side: the normal test is neutral.
    bool eitherWithoutNormal =
        dot(expectedNormal, expectedNormal) * dot(previousNormal, previousNormal) < 0.25f;
    bool normalOk =
        (dot(dn, dn) <= square(t.normalTolerance * (fwidthNormal + 0.01f))) | eitherWithoutNormal;
    return (previousId == id) & ((!t.geometry) | (depthOk & normalOk));
}

}  // namespace rtd
