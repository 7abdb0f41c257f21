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

// True when normals more than 90 degrees apart weigh nothing at float precision:
// (pi/2)^2 / 2sn^2 >= 88 (sigma_normal <= 0.118, the assignment's 0.1 included) makes their
// weight e^-88 or less, under 2^-126.
inline bool oppositeNormalsVanish(const EdgeStoppingTerms& t) {
    return t.normalScale * 2.4674011f >= 88.0f;
}

// D_normal^2 = acos(c)^2. OppositeNormalsVanish (see above): c < 0 may then be read as 0, whose
// (pi/2)^2 weighs nothing too, and on [0, 1] acos(c)^2 = (1 - c) p(c)^2 (acosFast's fit,
// squared) needs no square root.
template <bool OppositeNormalsVanish>
RTD_HOST_DEVICE RTD_INLINE float normalAngleSquared(float cosine) {
    if constexpr (OppositeNormalsVanish) {
        float c = clampf(cosine, 0.0f, 1.0f);
        return (1.0f - c) * square(acosSqrtFactor(c));
    } else {
        return square(acosFast(cosine));
    }
}

// The terms of J(i, j) (the exponent without its sign), with the plane term's division left to
// the caller (two taps can share one: pairExponents):
//   |C_i - C_j|^2 / 2sc^2 + acos(n_i . n_j)^2 / 2sn^2 + (n_i . (p_j - p_i)/|p_j - p_i|)^2 / 2sp^2
// D_plane^2 = (n_i . dp)^2 / |dp|^2: no square root needed. |dp|^2 is floored at 1e-18, so D_plane
// is 0 where the positions coincide (no division by zero) and two floors multiply to a normal
// float.
struct EdgeStoppingParts {
    float colorAndNormal;    // the colour and normal terms
    float planeNumerator;    // (n_i . dp)^2 / 2sp^2
    float planeDenominator;  // |dp|^2
};

template <bool OppositeNormalsVanish = false>
RTD_HOST_DEVICE RTD_INLINE EdgeStoppingParts edgeStoppingParts(const EdgeStoppingTerms& t,
                                                               Float3 colorI, Float3 colorJ,
                                                               Float3 normalI, Float3 normalJ,
                                                               Float3 positionI, Float3 positionJ) {
    Float3 dc = colorI - colorJ;
    float dNormal2 = normalAngleSquared<OppositeNormalsVanish>(dot(normalI, normalJ));
    Float3 dp = positionJ - positionI;
    float alongNormal = dot(normalI, dp);
    return {dot(dc, dc) * t.colorScale + dNormal2 * t.normalScale,
            alongNormal * alongNormal * t.planeScale, maxf(dot(dp, dp), 1e-18f)};
}

// The whole exponent of one tap.
template <bool OppositeNormalsVanish = false>
RTD_HOST_DEVICE RTD_INLINE float edgeStoppingExponent(const EdgeStoppingTerms& t, Float3 colorI,
                                                      Float3 colorJ, Float3 normalI, Float3 normalJ,
                                                      Float3 positionI, Float3 positionJ) {
    EdgeStoppingParts p = edgeStoppingParts<OppositeNormalsVanish>(t, colorI, colorJ, normalI,
                                                                   normalJ, positionI, positionJ);
    return p.colorAndNormal + divideApprox(p.planeNumerator, p.planeDenominator);
}

// The exponents of two taps with one division between them: 1 / (d_a d_b) times d_b, then d_a.
RTD_HOST_DEVICE RTD_INLINE void pairExponents(const EdgeStoppingParts& a,
                                              const EdgeStoppingParts& b, float& exponentA,
                                              float& exponentB) {
    float inverseProduct = divideApprox(1.0f, a.planeDenominator * b.planeDenominator);
    exponentA = a.colorAndNormal + a.planeNumerator * (b.planeDenominator * inverseProduct);
    exponentB = b.colorAndNormal + b.planeNumerator * (a.planeDenominator * inverseProduct);
}

}  // namespace rtd
