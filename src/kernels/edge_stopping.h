// The joint bilateral weight's edge-stopping terms (assignment formula, shared/seeds/001), used by
// the JBF and the A-Trous filter.
#pragma once

#include <cstdint>

#include "core/math.h"

namespace rtd {

// 1 / (2 sigma^2) for each term, precomputed on the host.
struct EdgeStoppingTerms {
    float colorScale;     // 1 / (2 sigma_color^2)
    float normalScale;    // 1 / (2 sigma_normal^2)
    float planeScale;     // 1 / (2 sigma_plane^2)
    int separateObjects;  // 1: taps on another object ID get weight 0
};

// 1 if tap j may contribute to centre i: it holds an object (not background, not the border)
// and, when objects are kept apart, the same one.
RTD_HOST_DEVICE RTD_INLINE float tapMask(const EdgeStoppingTerms& t, std::int32_t centreId,
                                         std::int32_t tapId) {
    bool sameObject = tapId == centreId;
    bool anyObject = tapId >= 0;
    return (t.separateObjects ? sameObject : anyObject) ? 1.0f : 0.0f;
}

// Sum of the colour, normal and plane terms of J(i, j) (the exponent without its sign):
//   |C_i - C_j|^2 / 2sc^2 + acos(n_i . n_j)^2 / 2sn^2 + (n_i . (p_j - p_i)/|p_j - p_i|)^2 / 2sp^2
// D_plane is 0 where the positions coincide (no division by zero).
RTD_HOST_DEVICE RTD_INLINE float edgeStoppingExponent(const EdgeStoppingTerms& t, Float3 colorI,
                                                      Float3 colorJ, Float3 normalI, Float3 normalJ,
                                                      Float3 positionI, Float3 positionJ) {
    Float3 dc = colorI - colorJ;
    float dNormal = acosFast(dot(normalI, normalJ));
    Float3 dp = positionJ - positionI;
    // D_plane^2 = (n_i . dp)^2 / |dp|^2: no square root needed.
    float alongNormal = dot(normalI, dp);
    float dPlane2 = alongNormal * alongNormal / maxf(dot(dp, dp), 1e-20f);
    return dot(dc, dc) * t.colorScale + dNormal * dNormal * t.normalScale + dPlane2 * t.planeScale;
}

}  // namespace rtd
