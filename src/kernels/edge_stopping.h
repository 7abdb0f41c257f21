// The joint bilateral weight's edge-stopping terms (assignment formula, shared/seeds/001), used by
// the JBF and the A-Trous filter.
#pragma once

#include <cstdint>

#include "core/math.h"
#include "kernels/views.h"

namespace rtd {

// 1 / (2 sigma^2) for each term, precomputed on the host.
struct EdgeStoppingTerms {
    float colorScale;   // 1 / (2 sigma_color^2)
    float normalScale;  // 1 / (2 sigma_normal^2)
    float planeScale;   // 1 / (2 sigma_plane^2)
};

// True when normals far apart weigh nothing at float precision: (pi/2)^2 / 2sn^2 >= 88
// (sigma_normal <= 0.118, the assignment's 0.1 included) makes the weight of normals 90 degrees
// apart e^-88 or less, under 2^-126, and that of normals 53 degrees apart (cosine 0.6) e^-30 or
// less, under 1e-13 of a centre tap's: the normal term then needs to be exact only near c = 1.
inline bool oppositeNormalsVanish(const EdgeStoppingTerms& t) {
    return t.normalScale * 2.4674011f >= 88.0f;
}

// D_normal^2 = acos(c)^2. OppositeNormalsVanish (see above): acos(c)^2 = (1 - c) q(c) with q
// fitted on [0.6, 1] (acosSquaredFactorNearOne) needs no square root; below 0.6 the weight is
// e^-30 or less (sigma_normal <= 0.118 and (1 - c) q(c) >= 0.86) for the fit as for acos, so
// normals further apart, opposite ones included, weigh nothing either way. c is capped at 1
// (normals a little longer than 1 would otherwise weigh more than parallel ones).
template <bool OppositeNormalsVanish>
RTD_HOST_DEVICE RTD_INLINE float normalAngleSquared(float cosine) {
    if constexpr (OppositeNormalsVanish) {
        float c = atMostOneOrSaturated(cosine);
        return (1.0f - c) * acosSquaredFactorNearOne(c);
    } else {
        return square(acosFast(cosine));
    }
}

// The terms of J(i, j) (the exponent without its sign), with the plane term's division left to
// the caller (two taps can share one: pairExponents):
//   |C_i - C_j|^2 / 2sc^2 + acos(n_i . n_j)^2 / 2sn^2 + (n_i . (p_j - p_i)/|p_j - p_i|)^2 / 2sp^2
// D_plane^2 = (n_i . dp)^2 / |dp|^2: no square root needed. |dp|^2 gets 1e-18 added (no
// division by zero where the positions coincide, D_plane is 0 there; two such floors multiply to
// a normal float), which moves it by under 1e-6 relative wherever positions differ by more than
// 1e-6.
struct EdgeStoppingParts {
    float colorAndNormal;    // the colour and normal terms, minus the caller's `bias`
    float planeNumerator;    // (n_i . dp)^2 / 2sp^2
    float planeDenominator;  // |dp|^2 + 1e-18
};

// The scales in base 2 (each times log2(e)): exponents that feed exp2 directly.
RTD_HOST_DEVICE RTD_INLINE EdgeStoppingTerms base2(EdgeStoppingTerms t) {
    t.colorScale *= kLog2e;
    t.normalScale *= kLog2e;
    t.planeScale *= kLog2e;
    return t;
}

// What the terms need of the centre pixel, with the scales folded in where that saves a
// multiplication per tap: the plane term's normal scaled by sqrt(1 / 2sp^2).
struct EdgeStoppingCentre {
    Float3 color, normal, position;
    Float3 planeNormal;  // normal * sqrt(planeScale)
    float normalScale;   // the terms' normalScale, 0 for a centre without a normal (views.h)
};
RTD_HOST_DEVICE RTD_INLINE EdgeStoppingCentre edgeStoppingCentre(const EdgeStoppingTerms& t,
                                                                 Float3 color, Float3 normal,
                                                                 Float3 position) {
    return {color, normal, position, normal * std::sqrt(t.planeScale),
            t.normalScale * guideNormalWeight(normal)};
}

// bias: subtracted from the colour and normal terms, where it costs no operation (the A-Trous
// kernel's log2 of its spline weight).
template <bool OppositeNormalsVanish = false>
RTD_HOST_DEVICE RTD_INLINE EdgeStoppingParts edgeStoppingParts(const EdgeStoppingTerms& t,
                                                               const EdgeStoppingCentre& c,
                                                               Float3 colorJ, Float3 normalJ,
                                                               Float3 positionJ,
                                                               float bias = 0.0f) {
    Float3 dc = c.color - colorJ;
    float cosine = dot(c.normal, normalJ);
    // The centre's scale: 0 without a normal (its taps are without one too: the same key).
    float normalTerm;
    if constexpr (OppositeNormalsVanish) {
        // (1 - c) q(c) / 2sn^2, the scale entering as (s - s c): no multiplication.
        float cc = atMostOneOrSaturated(cosine);
        normalTerm = (c.normalScale - c.normalScale * cc) * acosSquaredFactorNearOne(cc) - bias;
    } else {
        normalTerm = normalAngleSquared<false>(cosine) * c.normalScale - bias;
    }
    Float3 dp = positionJ - c.position;
    float alongNormal = dot(c.planeNormal, dp);  // (n_i . dp) sqrt(1 / 2sp^2)
    return {dot(dc, dc) * t.colorScale + normalTerm, alongNormal * alongNormal,
            dp.x * dp.x + (dp.y * dp.y + (dp.z * dp.z + 1e-18f))};
}

// J(i, j) and J(j, i) together: they share the colour and normal terms (symmetric in i and j,
// as is the spline's bias) and |dp|^2; only the plane term's numerator differs, each direction
// taking its own centre's normal. The CPU's A-Trous form evaluates each pair of pixels once for
// both (Atrous::filterSharingPairs).
struct EdgeStoppingPairParts {
    EdgeStoppingParts centre;  // J(i, j), as edgeStoppingParts
    float tapNumerator;  // (n_j . dp)^2, unscaled: the caller scales its reciprocal by 1/2sp^2
};
template <bool OppositeNormalsVanish = false>
RTD_HOST_DEVICE RTD_INLINE EdgeStoppingPairParts
edgeStoppingPairParts(const EdgeStoppingTerms& t, const EdgeStoppingCentre& c, Float3 colorJ,
                      Float3 normalJ, Float3 positionJ, float bias = 0.0f) {
    EdgeStoppingParts parts =
        edgeStoppingParts<OppositeNormalsVanish>(t, c, colorJ, normalJ, positionJ, bias);
    float alongTapNormal = dot(normalJ, positionJ - c.position);
    return {parts, alongTapNormal * alongTapNormal};
}

// The whole exponent of one tap, minus `bias` (as in edgeStoppingParts).
template <bool OppositeNormalsVanish = false>
RTD_HOST_DEVICE RTD_INLINE float edgeStoppingExponent(const EdgeStoppingTerms& t,
                                                      const EdgeStoppingCentre& c, Float3 colorJ,
                                                      Float3 normalJ, Float3 positionJ,
                                                      float bias = 0.0f) {
    EdgeStoppingParts p =
        edgeStoppingParts<OppositeNormalsVanish>(t, c, colorJ, normalJ, positionJ, bias);
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
