// The test-scene path tracer (~1150 lines, a tool beside the library, not in it): BVH, materials,
// lights and the sampler are one unit, read together when a reference looks wrong.
#include "render/path_tracer.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <optional>
#include <vector>

namespace rtd::render {
namespace {

constexpr float kPi = 3.14159265358979f;
constexpr float kInfinity = std::numeric_limits<float>::infinity();
// GGX below this linear roughness (alpha 4e-4) would overflow D in float: a near-mirror.
constexpr float kMinimumGgxRoughness = 0.02f;

// ---- random numbers ----

constexpr std::uint64_t splitMix64(std::uint64_t x) {
    x += 0x9e3779b97f4a7c15ull;
    x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
    x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
    return x ^ (x >> 31);
}

// PCG32 (O'Neill), one generator per camera sample.
class Rng {
  public:
    Rng(std::uint64_t state, std::uint64_t sequence) : inc_((sequence << 1) | 1u) {
        next();
        state_ += state;
        next();
    }
    std::uint32_t next() {
        std::uint64_t old = state_;
        state_ = old * 6364136223846793005ull + inc_;
        auto xorShifted = std::uint32_t(((old >> 18) ^ old) >> 27);
        auto rot = std::uint32_t(old >> 59);
        return (xorShifted >> rot) | (xorShifted << ((32u - rot) & 31u));
    }
    // Uniform in [0, 1): the top 24 bits, so 1 is never returned.
    float uniform() { return float(next() >> 8) * 0x1p-24f; }

  private:
    std::uint64_t state_ = 0;
    std::uint64_t inc_;
};

Rng sampleRng(const TraceSettings& s, std::uint64_t pixel, std::uint64_t sample) {
    std::uint64_t h = splitMix64((std::uint64_t(s.seed) << 32) | s.stream);
    h = splitMix64(h ^ std::uint64_t(std::uint32_t(s.frameIndex)));
    h = splitMix64(h ^ pixel);
    h = splitMix64(h ^ sample);
    return Rng(h, splitMix64(h));
}

// ---- geometry ----

struct Ray {
    Vec3 origin;
    Vec3 direction;  // unit
};

// Moves a surface point off the surface along n (the side the next ray leaves on); the offset
// grows with the coordinates' magnitude, above float rounding of the hit point.
Vec3 offsetPoint(Vec3 p, Vec3 n) {
    float scale = 1.0f + maxComponent(max(p, -p));
    return p + n * (1e-4f * scale);
}

// A primitive with what its ray test needs precomputed (local space).
struct TracePrimitive {
    Primitive::Kind kind = Primitive::Kind::Box;
    Vec3 a;                    // box min; sphere centre; quad corner
    Vec3 b;                    // box max; quad normal cross(u, v)
    Vec3 alphaAxis, betaAxis;  // quad: the parameters along u and v are dot(rel, axis)
    float radius2 = 0.0f;      // sphere

    explicit TracePrimitive(const Primitive& p) : kind(p.kind), a(p.p0), b(p.p1) {
        if (kind == Primitive::Kind::Box) {
            a = min(p.p0, p.p1);
            b = max(p.p0, p.p1);
        } else if (kind == Primitive::Kind::Sphere) {
            radius2 = p.p1.x * p.p1.x;
        } else {
            b = cross(p.p1, p.p2);
            Vec3 w = b / dot(b, b);
            // dot(w, cross(rel, v)) = dot(rel, cross(v, w)), likewise for u.
            alphaAxis = cross(p.p2, w);
            betaAxis = cross(w, p.p1);
        }
    }
};

// Ray/primitive tests in the primitive's local space; `d` need not be unit (t is then the world
// ray's parameter). Return t in (0, tMax) or kInfinity.
float intersectBox(const TracePrimitive& box, Vec3 o, Vec3 invD, float tMax) {
    // Branch-free slabs: a grid of bars tests many boxes per ray. The face is found from the
    // hit point afterwards (boxFace).
    Vec3 t0 = (box.a - o) * invD, t1 = (box.b - o) * invD;
    float tNear = maxComponent(min(t0, t1));
    Vec3 far = max(t0, t1);
    float tFar = std::min(far.x, std::min(far.y, far.z));
    float t = tNear > 0.0f ? tNear : tFar;  // from inside: the exit face
    return tNear <= tFar && t > 0.0f && t < tMax ? t : kInfinity;
}

// The face of a box that a local point lies on: axis * 2 + (1 for the max side).
int boxFace(const Primitive& box, Vec3 p) {
    Vec3 lo = min(box.p0, box.p1), hi = max(box.p0, box.p1);
    int face = 0;
    float best = kInfinity;
    for (int axis = 0; axis < 3; ++axis) {
        float dLo = std::abs(p[axis] - lo[axis]), dHi = std::abs(p[axis] - hi[axis]);
        if (dLo < best) {
            best = dLo;
            face = axis * 2;
        }
        if (dHi < best) {
            best = dHi;
            face = axis * 2 + 1;
        }
    }
    return face;
}

float intersectSphere(const TracePrimitive& sphere, Vec3 o, Vec3 d, float tMax) {
    Vec3 oc = o - sphere.a;
    float a = dot(d, d);
    float b = dot(oc, d);
    float c = dot(oc, oc) - sphere.radius2;
    float disc = b * b - a * c;
    if (disc < 0.0f) return kInfinity;
    float root = std::sqrt(disc);
    float t = (-b - root) / a;
    if (t > 0.0f && t < tMax) return t;
    t = (-b + root) / a;
    if (t > 0.0f && t < tMax) return t;
    return kInfinity;
}

float intersectQuad(const TracePrimitive& q, Vec3 o, Vec3 d, float tMax, float& alpha,
                    float& beta) {
    float denom = dot(q.b, d);
    if (denom == 0.0f) return kInfinity;
    float t = dot(q.b, q.a - o) / denom;
    if (!(t > 0.0f && t < tMax)) return kInfinity;
    Vec3 rel = o + d * t - q.a;
    alpha = dot(rel, q.alphaAxis);
    beta = dot(rel, q.betaAxis);
    if (alpha < 0.0f || alpha > 1.0f || beta < 0.0f || beta > 1.0f) return kInfinity;
    return t;
}

struct CompiledObject {
    Affine toLocal;
    Affine toWorld;
    bool identity = false;    // local = world: no ray transform
    bool testBounds = true;   // false for a lone quad, whose own test is as cheap
    Vec3 boundsLo, boundsHi;  // world space, padded
    int firstPrimitive = 0;
    int primitiveCount = 0;
};

// A light sampled by next-event estimation, in world space: an area light or the sun.
struct Light {
    bool sphere = false;
    bool sun = false;     // a cone of directions around sunDirection, at infinity
    bool portal = false;  // a quad (both sides) through which background and sky are seen
    Vec3 sunDirection;
    float sunOneMinusCos = 0.0f;        // 1 - cos of the sun's angular radius
    float sunConePdf = 0.0f;            // solid-angle pdf of uniform cone sampling
    Vec3 corner, edgeU, edgeV, normal;  // quad; normal on the front face
    float area = 0.0f;
    Vec3 centre;  // sphere
    float radius = 0.0f;
    Vec3 emission;
    bool twoSided = false;
    float probability = 0.0f;  // of being picked
    float cdf = 0.0f;          // of this and the lights before it
};

struct Hit {
    float t = kInfinity;
    int object = -1;
    int primitive = -1;
    float alpha = 0.0f, beta = 0.0f;  // quad parameters
};

struct Surface {
    Vec3 position;
    Vec3 normal;  // world, unit, as modelled (outward / front face)
    float u = 0.0f, v = 0.0f;
};

struct LightSample {
    Vec3 direction;
    float distance = 0.0f;
    Vec3 emission;
    float pdf = 0.0f;  // solid angle, selection included
};

// Solid-angle pdf of cone sampling a sphere seen from `x`; 0 from inside.
float sphereConePdf(const Light& l, Vec3 x, float& cosMax) {
    Vec3 d = l.centre - x;
    float dist2 = dot(d, d);
    float r2 = l.radius * l.radius;
    if (dist2 <= r2) return 0.0f;
    float sin2 = r2 / dist2;
    cosMax = std::sqrt(std::max(0.0f, 1.0f - sin2));
    float oneMinusCos = sin2 / (1.0f + cosMax);  // 1 - cosMax without cancellation
    return 1.0f / (2.0f * kPi * oneMinusCos);
}

// ---- GGX ----

// Smith's Lambda of GGX for a local direction w (z along the normal).
float ggxLambda(float alpha, Vec3 w) {
    float tan2 = (w.x * w.x + w.y * w.y) / (w.z * w.z);
    return 0.5f * (std::sqrt(1.0f + alpha * alpha * tan2) - 1.0f);
}

// A normal of GGX's visible-normal distribution seen from local wo (Heitz 2018).
Vec3 sampleVisibleNormal(float alpha, Vec3 wo, float u1, float u2) {
    Vec3 v = normalize(Vec3(alpha * wo.x, alpha * wo.y, wo.z));
    float lengthSquared = v.x * v.x + v.y * v.y;
    Vec3 t1 = lengthSquared > 0.0f ? Vec3(-v.y, v.x, 0.0f) / std::sqrt(lengthSquared)
                                   : Vec3(1.0f, 0.0f, 0.0f);
    Vec3 t2 = cross(v, t1);
    float r = std::sqrt(u1), phi = 2.0f * kPi * u2;
    float p1 = r * std::cos(phi), p2 = r * std::sin(phi);
    float s = 0.5f * (1.0f + v.z);
    p2 = (1.0f - s) * std::sqrt(std::max(0.0f, 1.0f - p1 * p1)) + s * p2;
    Vec3 visible = t1 * p1 + t2 * p2 + v * std::sqrt(std::max(0.0f, 1.0f - p1 * p1 - p2 * p2));
    return normalize(Vec3(alpha * visible.x, alpha * visible.y, std::max(1e-6f, visible.z)));
}

// The directional albedo E(mu, roughness) of the single-scattering GGX lobe (no Fresnel term) and
// its cosine-weighted mean over mu. Single scattering loses up to 70 % at roughness 1 (what light
// would leave after bouncing between microfacets); Kulla and Conty's (2017) lobe
// (1 - E(mu_o)) (1 - E(mu_i)) / (pi (1 - E_avg)) gives it back, so a white metal reflects 1 at
// every roughness. Computed once, with fixed stratified samples: the same table every run.
class GgxAlbedoTable {
  public:
    static constexpr int kSize = 32;  // roughness 0..1 and mu (midpoints of 32 bins) each

    GgxAlbedoTable() {
        constexpr int kStrata = 16;
        for (int r = 0; r < kSize; ++r) {
            const float roughness = std::max(kMinimumGgxRoughness, float(r) / float(kSize - 1));
            const float alpha = roughness * roughness;
            double average = 0.0;
            for (int m = 0; m < kSize; ++m) {
                const float mu = (float(m) + 0.5f) / float(kSize);
                const Vec3 wo{std::sqrt(1.0f - mu * mu), 0.0f, mu};
                const float lambdaO = ggxLambda(alpha, wo);
                double sum = 0.0;  // of G2 / G1, each visible-normal sample's f cos / pdf
                for (int i = 0; i < kStrata; ++i)
                    for (int j = 0; j < kStrata; ++j) {
                        const Vec3 h = sampleVisibleNormal(alpha, wo, (float(i) + 0.5f) / kStrata,
                                                           (float(j) + 0.5f) / kStrata);
                        const Vec3 wi = h * (2.0f * dot(wo, h)) - wo;
                        if (wi.z > 0.0f)
                            sum += (1.0 + lambdaO) / (1.0 + lambdaO + ggxLambda(alpha, wi));
                    }
                albedo_[r][m] = float(sum / (kStrata * kStrata));
                average += 2.0 * albedo_[r][m] * mu / kSize;
            }
            average_[r] = float(average);
        }
    }
    // Linear in roughness and mu between the table's points (clamped at its ends).
    float albedo(float roughness, float mu) const {
        const auto [r0, r1, rt] = locate(roughness * float(kSize - 1));
        const auto [m0, m1, mt] = locate(mu * float(kSize) - 0.5f);
        const float low = albedo_[r0][m0] + (albedo_[r0][m1] - albedo_[r0][m0]) * mt;
        const float high = albedo_[r1][m0] + (albedo_[r1][m1] - albedo_[r1][m0]) * mt;
        return low + (high - low) * rt;
    }
    float average(float roughness) const {
        const auto [r0, r1, rt] = locate(roughness * float(kSize - 1));
        return average_[r0] + (average_[r1] - average_[r0]) * rt;
    }

  private:
    struct Cell {
        int lo, hi;
        float t;
    };
    static Cell locate(float x) {
        x = std::clamp(x, 0.0f, float(kSize - 1));
        const int lo = std::min(int(x), kSize - 2);
        return {lo, lo + 1, x - float(lo)};
    }
    float albedo_[kSize][kSize] = {};
    float average_[kSize] = {};
};

const GgxAlbedoTable& ggxAlbedo() {
    static const GgxAlbedoTable table;
    return table;
}

// Diffuse plus a glossy lobe (normalised Phong, or GGX: Material) at one shading point; n faces
// wo. The Phong lobe's code is the built-in scenes' as it was (its images differ from before the
// GGX lobe in their last bits only: contraction follows the code around it).
struct Bsdf {
    Vec3 diffuse;  // (1 - specular) albedo
    float specular = 0.0f;
    float exponent = 1.0f;
    Vec3 n, reflected;
    float specularProbability = 0.0f;
    // GGX: the lobe's alpha, colour, and the shading frame (tangent, bitangent, n) in which wo is
    // woLocal; its multiple-scattering lobe is multipleScattering * (1 - E(mu_i)).
    bool ggx = false;
    float roughness = 1.0f;
    float alpha = 1.0f;
    float multipleScattering = 0.0f;
    Vec3 tint{1.0f};
    Vec3 tangent, bitangent, woLocal;

    Bsdf(const Material& m, Vec3 albedo, Vec3 normal, Vec3 wo)
        : diffuse(albedo * (1.0f - m.specular)),
          specular(m.specular),
          exponent(m.exponent),
          n(normal),
          reflected(normal * (2.0f * dot(wo, normal)) - wo) {
        float weight = specular + luminance(diffuse);
        specularProbability = weight > 0.0f ? specular / weight : 0.0f;
        if (m.lobe == Material::Lobe::Ggx && specular > 0.0f) setUpGgx(m, wo);
    }
    void setUpGgx(const Material& m, Vec3 wo) {
        ggx = true;
        roughness = std::clamp(m.roughness, kMinimumGgxRoughness, 1.0f);
        alpha = roughness * roughness;
        tint = m.specularTint;
        orthonormalBasis(n, tangent, bitangent);
        woLocal = toLocal(wo);
        const GgxAlbedoTable& table = ggxAlbedo();
        const float single = table.albedo(roughness, std::max(0.0f, woLocal.z));
        const float average = table.average(roughness);
        multipleScattering = average < 0.9999f ? (1.0f - single) / (kPi * (1.0f - average)) : 0.0f;
        // Lobes picked by the albedo they reflect, the tint's included: visible-normal sampling
        // for the single-scattering part, cosine sampling for the rest (multiple scattering and
        // diffuse, both nearly cosine-shaped).
        float glossy = specular * luminance(tint);
        float weight = glossy + luminance(diffuse);
        specularProbability = weight > 0.0f ? glossy * single / weight : 0.0f;
    }
    bool black() const { return specular <= 0.0f && maxComponent(diffuse) <= 0.0f; }

    Vec3 toLocal(Vec3 w) const { return {dot(w, tangent), dot(w, bitangent), dot(w, n)}; }
    Vec3 fromLocal(Vec3 l) const { return tangent * l.x + bitangent * l.y + n * l.z; }

    // GGX (Walter et al. 2007) in the local frame: the normal distribution D and Smith's Lambda.
    float ggxDistribution(Vec3 h) const {
        float a2 = alpha * alpha;
        float d = (h.x * h.x + h.y * h.y) / a2 + h.z * h.z;
        return 1.0f / (kPi * a2 * d * d);
    }
    // D G2 / (4 cos_o cos_i) with height-correlated G2 = 1 / (1 + Lambda_o + Lambda_i); 0 when
    // either direction is below the surface.
    // The half vector of wo and l (local), or false where either is below the surface or they
    // are opposite: then the lobe's value and pdf are 0.
    bool ggxHalfVector(Vec3 l, Vec3& h) const {
        if (!(woLocal.z > 0.0f) || !(l.z > 0.0f)) return false;
        h = woLocal + l;
        const float len = length(h);
        if (!(len > 0.0f)) return false;
        h = h / len;
        return true;
    }
    float ggxValue(Vec3 wi) const {
        const Vec3 l = toLocal(wi);
        Vec3 h;
        if (!ggxHalfVector(l, h)) return 0.0f;
        return ggxDistribution(h) /
               (4.0f * woLocal.z * l.z * (1.0f + ggxLambda(alpha, woLocal) + ggxLambda(alpha, l)));
    }
    // Of sampling visible normals: G1(wo) D(h) / (4 cos_o).
    float ggxPdf(Vec3 wi) const {
        Vec3 h;
        if (!ggxHalfVector(toLocal(wi), h)) return 0.0f;
        return ggxDistribution(h) / (4.0f * woLocal.z * (1.0f + ggxLambda(alpha, woLocal)));
    }
    // Visible-normal sampling (Heitz 2018): for the single-scattering lobe alone f cos / pdf =
    // G2 / G1 <= 1, so no sample is a firefly of the lobe's own making.
    Vec3 sampleGgxLobe(float u1, float u2) const {
        const Vec3 m = sampleVisibleNormal(alpha, woLocal, u1, u2);
        return fromLocal(m * (2.0f * dot(woLocal, m)) - woLocal);
    }
    // Kulla and Conty's multiple-scattering lobe (GgxAlbedoTable); 0 below the surface.
    float multipleScatteringValue(Vec3 wi) const {
        const float mu = dot(wi, n);
        if (!(mu > 0.0f) || multipleScattering <= 0.0f) return 0.0f;
        return multipleScattering * (1.0f - ggxAlbedo().albedo(roughness, mu));
    }

    float lobe(Vec3 wi) const {  // cos^n of the angle to the mirror direction, 0 behind
        float c = dot(reflected, wi);
        return c > 0.0f ? std::pow(c, exponent) : 0.0f;
    }
    // The glossy lobe's part of evaluate() (the same expression), for the split signal.
    Vec3 evaluateSpecular(Vec3 wi) const {
        return ggx ? tint * (specular * (ggxValue(wi) + multipleScatteringValue(wi)))
                   : Vec3(evaluateSpecularPhong(wi));
    }
    Vec3 evaluate(Vec3 wi) const { return ggx ? evaluateGgx(wi) : evaluatePhong(wi); }
    float pdf(Vec3 wi) const { return ggx ? pdfGgx(wi) : pdfPhong(wi); }
    // A direction from the mixture; false when it points below the surface.
    bool sample(Rng& rng, Vec3& wi) const {
        return ggx ? sampleGgx(rng, wi) : samplePhong(rng, wi);
    }

    float evaluateSpecularPhong(Vec3 wi) const {
        return specular > 0.0f ? specular * (exponent + 2.0f) / (2.0f * kPi) * lobe(wi) : 0.0f;
    }
    Vec3 evaluatePhong(Vec3 wi) const {
        Vec3 f = diffuse * (1.0f / kPi);
        if (specular > 0.0f) f += Vec3(specular * (exponent + 2.0f) / (2.0f * kPi) * lobe(wi));
        return f;
    }
    float pdfPhong(Vec3 wi) const {
        float p = (1.0f - specularProbability) * std::max(0.0f, dot(wi, n)) / kPi;
        if (specularProbability > 0.0f)
            p += specularProbability * (exponent + 1.0f) / (2.0f * kPi) * lobe(wi);
        return p;
    }
    bool samplePhong(Rng& rng, Vec3& wi) const {
        float choice = rng.uniform(), u1 = rng.uniform(), u2 = rng.uniform();
        float phi = 2.0f * kPi * u2;
        Vec3 t, b;
        if (choice < specularProbability) {
            float cosA = std::pow(u1, 1.0f / (exponent + 1.0f));
            float sinA = std::sqrt(std::max(0.0f, 1.0f - cosA * cosA));
            orthonormalBasis(reflected, t, b);
            wi = t * (sinA * std::cos(phi)) + b * (sinA * std::sin(phi)) + reflected * cosA;
        } else {
            float r = std::sqrt(u1);
            orthonormalBasis(n, t, b);
            wi = t * (r * std::cos(phi)) + b * (r * std::sin(phi)) +
                 n * std::sqrt(std::max(0.0f, 1.0f - u1));
        }
        return dot(wi, n) > 0.0f;
    }

    Vec3 evaluateGgx(Vec3 wi) const {
        return diffuse * (1.0f / kPi) +
               tint * (specular * (ggxValue(wi) + multipleScatteringValue(wi)));
    }
    float pdfGgx(Vec3 wi) const {
        return (1.0f - specularProbability) * std::max(0.0f, dot(wi, n)) / kPi +
               specularProbability * ggxPdf(wi);
    }
    // The same three random numbers as Phong's: lobe choice, then two for the direction.
    bool sampleGgx(Rng& rng, Vec3& wi) const {
        float choice = rng.uniform(), u1 = rng.uniform(), u2 = rng.uniform();
        if (choice < specularProbability) {
            wi = sampleGgxLobe(u1, u2);
        } else {
            float r = std::sqrt(u1), phi = 2.0f * kPi * u2;
            wi = fromLocal(
                {r * std::cos(phi), r * std::sin(phi), std::sqrt(std::max(0.0f, 1.0f - u1))});
        }
        return dot(wi, n) > 0.0f;
    }
};

float powerHeuristic(float a, float b) {
    float a2 = a * a, b2 = b * b;
    return a2 / (a2 + b2);
}

// The scene with inverse matrices, world bounds and the light list, ready for tracing.
class CompiledScene {
  public:
    explicit CompiledScene(const Scene& scene) : scene_(scene) {
        for (const Object& object : scene.objects) {
            CompiledObject c;
            c.toWorld = toAffine(object.objectToWorld);
            c.toLocal = inverse(c.toWorld);
            c.identity = object.objectToWorld.m == Matrix4::identity().m;
            c.testBounds = !(object.primitives.size() == 1 &&
                             object.primitives[0].kind == Primitive::Kind::Quad);
            c.firstPrimitive = int(primitives_.size());
            c.primitiveCount = int(object.primitives.size());
            Vec3 lo(kInfinity), hi(-kInfinity);
            for (const Primitive& p : object.primitives) {
                sourcePrimitives_.push_back(p);
                primitives_.emplace_back(p);
                lightOf_.push_back(-1);
                Vec3 plo, phi;
                localBounds(p, plo, phi);
                for (int corner = 0; corner < 8; ++corner) {
                    Vec3 q{corner & 1 ? phi.x : plo.x, corner & 2 ? phi.y : plo.y,
                           corner & 4 ? phi.z : plo.z};
                    Vec3 w = c.toWorld.point(q);
                    lo = min(lo, w);
                    hi = max(hi, w);
                }
            }
            // Padding keeps flat quads' boxes non-degenerate and covers rounding.
            Vec3 pad(1e-4f * (1.0f + maxComponent(max(max(lo, -lo), max(hi, -hi)))));
            c.boundsLo = lo - pad;
            c.boundsHi = hi + pad;
            objects_.push_back(c);
        }
        buildLights();
    }

    const Scene& scene() const { return scene_; }

    Hit closest(const Ray& ray, float tMax = kInfinity) const {
        Hit hit = traverse<false>(ray, tMax);
        if (hit.object < 0) hit.t = kInfinity;
        return hit;
    }

    bool occluded(const Ray& ray, float tMax) const {
        return traverse<true>(ray, tMax).object >= 0;
    }

    // World position, outward normal and texture coordinates (local units) of a hit.
    Surface surface(const Ray& ray, const Hit& hit) const {
        const CompiledObject& c = objects_[hit.object];
        const Primitive& prim = sourcePrimitives_[hit.primitive];
        Surface s;
        // The world point on the ray, so that the G-buffer projects exactly to the pixel.
        s.position = ray.origin + ray.direction * hit.t;
        Vec3 local = c.toLocal.point(s.position);
        Vec3 localNormal;
        switch (prim.kind) {
            case Primitive::Kind::Box: {
                int face = boxFace(prim, local);
                int axis = face / 2;
                float sign = face % 2 ? 1.0f : -1.0f;
                localNormal = {axis == 0 ? sign : 0.0f, axis == 1 ? sign : 0.0f,
                               axis == 2 ? sign : 0.0f};
                s.u = axis == 0 ? local.z : local.x;
                s.v = axis == 1 ? local.z : local.y;
                break;
            }
            case Primitive::Kind::Sphere: {
                float r = prim.p1.x;
                Vec3 q = local - prim.p0;
                localNormal = q;
                s.u = (std::atan2(q.z, q.x) + kPi) * r;
                s.v = std::acos(std::clamp(q.y / length(q), -1.0f, 1.0f)) * r;
                break;
            }
            case Primitive::Kind::Quad:
                localNormal = cross(prim.p1, prim.p2);
                s.u = hit.alpha * length(prim.p1);
                s.v = hit.beta * length(prim.p2);
                break;
        }
        s.normal = normalize(c.toLocal.transposedVector(localNormal));
        return s;
    }

    const Material& material(int object) const { return scene_.objects[object].material; }

    // Radiance along a ray that leaves the scene: background, sky and, inside the sun's cone, the
    // sun. bsdfPdf > 0: the ray is a BSDF sample, and the sun shares it with next-event
    // estimation by MIS; 0 (camera rays): the sun counts in full. Without sky or sun it is the
    // background, as it always was.
    Vec3 escapedRadiance(Vec3 origin, Vec3 direction, float bsdfPdf) const {
        if (!scene_.sky.enabled() && sunLight_ < 0 && portals_.empty()) return scene_.background;
        Vec3 l = scene_.background;
        if (scene_.sky.enabled()) l += scene_.sky.radiance(direction);
        // Through a portal, background and sky share the path with its next-event estimation.
        if (bsdfPdf > 0.0f && !portals_.empty()) {
            float portalPdf = 0.0f;
            for (int index : portals_)
                portalPdf += pdfThroughPortal(lights_[std::size_t(index)], origin, direction);
            if (portalPdf > 0.0f) l = l * powerHeuristic(bsdfPdf, portalPdf);
        }
        if (sunLight_ >= 0) {
            const Light& sun = lights_[std::size_t(sunLight_)];
            if (1.0f - dot(direction, sun.sunDirection) <= sun.sunOneMinusCos) {
                float weight = bsdfPdf > 0.0f
                                   ? powerHeuristic(bsdfPdf, sun.probability * sun.sunConePdf)
                                   : 1.0f;
                l += sun.emission * weight;
            }
        }
        return l;
    }
    int lightOf(int primitive) const { return lightOf_[primitive]; }
    bool hasLights() const { return !lights_.empty(); }

    // Solid-angle pdf with which next-event estimation from `x` picks the point that a ray
    // from `x` along `direction` hits at distance t on light `index` (normal n there).
    float lightPdf(int index, Vec3 x, Vec3 direction, float t, Vec3 n) const {
        const Light& l = lights_[index];
        if (l.sphere) {
            float cosMax = 0.0f;
            return l.probability * sphereConePdf(l, x, cosMax);
        }
        float cosLight = std::abs(dot(n, direction));
        if (cosLight <= 0.0f) return 0.0f;
        return l.probability * t * t / (cosLight * l.area);
    }

    // Solid-angle pdf with which next-event estimation from `x` samples `direction` through
    // portal `l` (0 when the ray misses it).
    static float pdfThroughPortal(const Light& l, Vec3 x, Vec3 direction) {
        const float denominator = dot(l.normal, direction);
        if (denominator == 0.0f) return 0.0f;
        const float t = dot(l.normal, l.corner - x) / denominator;
        if (!(t > 0.0f)) return 0.0f;
        const Vec3 rel = x + direction * t - l.corner;
        const float a = dot(rel, l.edgeU) / dot(l.edgeU, l.edgeU);
        const float b = dot(rel, l.edgeV) / dot(l.edgeV, l.edgeV);
        if (a < 0.0f || a > 1.0f || b < 0.0f || b > 1.0f) return 0.0f;
        return l.probability * t * t / (std::abs(denominator) * l.area);
    }

    bool sampleLight(Vec3 x, Rng& rng, LightSample& out) const {
        float pick = rng.uniform(), u1 = rng.uniform(), u2 = rng.uniform();
        std::size_t index = 0;
        while (index + 1 < lights_.size() && pick >= lights_[index].cdf) ++index;
        const Light& l = lights_[index];
        if (l.sun) {
            float cosT = 1.0f - u1 * l.sunOneMinusCos;
            float sinT = std::sqrt(std::max(0.0f, 1.0f - cosT * cosT));
            float phi = 2.0f * kPi * u2;
            Vec3 t, b;
            orthonormalBasis(l.sunDirection, t, b);
            out.direction =
                t * (sinT * std::cos(phi)) + b * (sinT * std::sin(phi)) + l.sunDirection * cosT;
            out.distance = kInfinity;
            out.emission = l.emission;
            out.pdf = l.probability * l.sunConePdf;
            return true;
        }
        if (l.sphere) {
            float cosMax = 0.0f;
            float pdf = sphereConePdf(l, x, cosMax);
            if (pdf <= 0.0f) return false;
            Vec3 toCentre = l.centre - x;
            float dist = length(toCentre);
            Vec3 w = toCentre / dist;
            float cosT = 1.0f - u1 * (1.0f - cosMax);
            float sinT = std::sqrt(std::max(0.0f, 1.0f - cosT * cosT));
            float phi = 2.0f * kPi * u2;
            Vec3 t, b;
            orthonormalBasis(w, t, b);
            out.direction = t * (sinT * std::cos(phi)) + b * (sinT * std::sin(phi)) + w * cosT;
            // Distance to the near side of the sphere along the sampled direction.
            float proj = dot(toCentre, out.direction);
            float disc = std::max(0.0f, l.radius * l.radius - (dist * dist - proj * proj));
            out.distance = proj - std::sqrt(disc);
            out.emission = l.emission;
            out.pdf = l.probability * pdf;
            return out.distance > 0.0f;
        }
        Vec3 y = l.corner + l.edgeU * u1 + l.edgeV * u2;
        Vec3 d = y - x;
        float dist2 = dot(d, d);
        if (dist2 <= 0.0f) return false;
        out.distance = std::sqrt(dist2);
        out.direction = d / out.distance;
        if (l.portal) {  // the sky beyond it: unoccluded all the way out
            const float cosPortal = std::abs(dot(l.normal, out.direction));
            if (cosPortal <= 0.0f) return false;
            out.emission = scene_.background + scene_.sky.radiance(out.direction);
            out.pdf = l.probability * dist2 / (cosPortal * l.area);
            out.distance = kInfinity;
            return true;
        }
        float cosLight = -dot(l.normal, out.direction);
        if (!l.twoSided && cosLight <= 0.0f) return false;  // the back of a one-sided light
        cosLight = std::abs(cosLight);
        if (cosLight <= 0.0f) return false;
        out.emission = l.emission;
        out.pdf = l.probability * dist2 / (cosLight * l.area);
        return true;
    }

  private:
    // Nearest hit before tMax, or with anyHit the first one found (shadow rays).
    template <bool anyHit>
    Hit traverse(const Ray& ray, float tMax) const {
        Hit hit;
        hit.t = tMax;
        Vec3 invDir{1.0f / ray.direction.x, 1.0f / ray.direction.y, 1.0f / ray.direction.z};
        for (int i = 0; i < int(objects_.size()); ++i) {
            const CompiledObject& c = objects_[i];
            if (c.testBounds && !hitsBounds(c, ray.origin, invDir, hit.t)) continue;
            Vec3 o = ray.origin, d = ray.direction, invD = invDir;
            if (!c.identity) {
                o = c.toLocal.point(ray.origin);
                d = c.toLocal.vector(ray.direction);
                invD = {1.0f / d.x, 1.0f / d.y, 1.0f / d.z};
            }
            for (int p = c.firstPrimitive; p < c.firstPrimitive + c.primitiveCount; ++p) {
                const TracePrimitive& prim = primitives_[p];
                float alpha = 0.0f, beta = 0.0f, t = kInfinity;
                switch (prim.kind) {
                    case Primitive::Kind::Box:
                        t = intersectBox(prim, o, invD, hit.t);
                        break;
                    case Primitive::Kind::Sphere:
                        t = intersectSphere(prim, o, d, hit.t);
                        break;
                    case Primitive::Kind::Quad:
                        t = intersectQuad(prim, o, d, hit.t, alpha, beta);
                        break;
                }
                if (t < hit.t) {
                    hit = {t, i, p, alpha, beta};
                    if constexpr (anyHit) return hit;
                }
            }
        }
        return hit;
    }

    static void localBounds(const Primitive& p, Vec3& lo, Vec3& hi) {
        switch (p.kind) {
            case Primitive::Kind::Box:
                lo = min(p.p0, p.p1);
                hi = max(p.p0, p.p1);
                return;
            case Primitive::Kind::Sphere:
                lo = p.p0 - Vec3(p.p1.x);
                hi = p.p0 + Vec3(p.p1.x);
                return;
            case Primitive::Kind::Quad: {
                Vec3 a = p.p0, b = p.p0 + p.p1, c = p.p0 + p.p2, d = p.p0 + p.p1 + p.p2;
                lo = min(min(a, b), min(c, d));
                hi = max(max(a, b), max(c, d));
                return;
            }
        }
    }

    static bool hitsBounds(const CompiledObject& c, Vec3 o, Vec3 invDir, float tMax) {
        float tNear = 0.0f, tFar = tMax;
        for (int a = 0; a < 3; ++a) {
            float t0 = (c.boundsLo[a] - o[a]) * invDir[a];
            float t1 = (c.boundsHi[a] - o[a]) * invDir[a];
            tNear = std::max(tNear, std::min(t0, t1));
            tFar = std::min(tFar, std::max(t0, t1));
        }
        return tNear <= tFar;
    }

    void buildLights() {
        double total = 0.0;
        std::vector<double> power;
        for (std::size_t i = 0; i < scene_.objects.size(); ++i) {
            const Object& object = scene_.objects[i];
            if (!object.light || !object.material.emissive()) continue;
            const CompiledObject& c = objects_[i];
            for (int p = 0; p < c.primitiveCount; ++p) {
                const Primitive& prim = sourcePrimitives_[c.firstPrimitive + p];
                Light l;
                l.emission = object.material.emission;
                l.twoSided = object.material.twoSidedEmission;
                if (prim.kind == Primitive::Kind::Quad) {
                    l.corner = c.toWorld.point(prim.p0);
                    l.edgeU = c.toWorld.vector(prim.p1);
                    l.edgeV = c.toWorld.vector(prim.p2);
                    l.area = length(cross(l.edgeU, l.edgeV));
                    l.normal = normalize(c.toLocal.transposedVector(cross(prim.p1, prim.p2)));
                    if (!(l.area > 0.0f)) continue;
                } else if (prim.kind == Primitive::Kind::Sphere) {
                    // A uniform scale is assumed (checked by the scene tests).
                    l.sphere = true;
                    l.centre = c.toWorld.point(prim.p0);
                    l.radius = length(c.toWorld.vector({prim.p1.x, 0.0f, 0.0f}));
                    l.area = 4.0f * kPi * l.radius * l.radius;
                } else {
                    continue;  // boxes are found by BSDF sampling only
                }
                double watts = double(luminance(l.emission)) * l.area * (l.twoSided ? 2.0 : 1.0);
                if (!(watts > 0.0)) continue;
                lightOf_[c.firstPrimitive + p] = int(lights_.size());
                lights_.push_back(l);
                power.push_back(watts);
                total += watts;
            }
        }
        // Portals: by the power of the mean of the sky's zenith and horizon through them (the
        // ground's is seen from inside through few of them).
        for (const SkyPortal& portal : scene_.skyPortals) {
            Light l;
            l.portal = true;
            l.twoSided = true;
            l.corner = portal.corner;
            l.edgeU = portal.edgeU;
            l.edgeV = portal.edgeV;
            l.area = length(cross(l.edgeU, l.edgeV));
            if (!(l.area > 0.0f)) continue;
            l.normal = cross(l.edgeU, l.edgeV) / l.area;
            const Vec3 radiance =
                scene_.background + (scene_.sky.zenith + scene_.sky.horizon) * 0.5f;
            const double watts = double(luminance(radiance)) * l.area;
            if (!(watts > 0.0)) continue;
            portals_.push_back(int(lights_.size()));
            lights_.push_back(l);
            power.push_back(watts);
            total += watts;
        }
        // The sun's power is not comparable to an area light's: with both, each gets half the
        // samples (area lights among themselves by power).
        const bool sun = scene_.sun.enabled();
        const double areaShare = sun && !lights_.empty() ? 0.5 : 1.0;
        double running = 0.0;
        for (std::size_t i = 0; i < lights_.size(); ++i) {
            running += power[i];
            lights_[i].probability = float(power[i] / total * areaShare);
            lights_[i].cdf = float(running / total * areaShare);
        }
        if (sun) {
            const Sun& s = scene_.sun;
            Light l;
            l.sun = true;
            l.sunDirection = normalize(s.direction);
            const float radius = std::clamp(s.angularRadiusDegrees, 1e-3f, 10.0f) * (kPi / 180.0f);
            const float sinHalf = std::sin(0.5f * radius);
            l.sunOneMinusCos = 2.0f * sinHalf * sinHalf;  // without cancellation
            l.sunConePdf = 1.0f / (2.0f * kPi * l.sunOneMinusCos);
            // A uniform disc of radiance L and angular radius r gives irradiance L pi sin^2 r.
            const float sinRadius = std::sin(radius);
            l.emission = s.irradiance * (1.0f / (kPi * sinRadius * sinRadius));
            l.probability = float(1.0 - (lights_.empty() ? 0.0 : areaShare));
            l.cdf = 1.0f;
            sunLight_ = int(lights_.size());
            lights_.push_back(l);
        }
    }

    const Scene& scene_;
    std::vector<CompiledObject> objects_;
    std::vector<Primitive> sourcePrimitives_;
    std::vector<TracePrimitive> primitives_;
    std::vector<int> lightOf_;  // per primitive: its light, or -1
    std::vector<Light> lights_;
    int sunLight_ = -1;         // the sun's index in lights_, or -1
    std::vector<int> portals_;  // the portals' indices in lights_
};

// One camera path. With `specular`, it also receives the part of the radiance that left the
// first surface (depth 0) through its glossy lobe: at depth 0 next-event estimation adds the
// glossy term of the BSDF alone (same light sample, same MIS weight), and every later
// contribution is carried by specularThroughput, the throughput with the first vertex's BSDF
// replaced by its glossy lobe (f_specular cos / pdf at the sampled direction). Emission seen at
// depth 0 and background seen by the camera count as diffuse. The split only adds arithmetic on
// its own values: the random numbers and the radiance are those without it. (One function with a
// run-time switch, not a template: a second instantiation changes what the compiler inlines,
// and with contraction the beauty's last bits.)
Vec3 radiance(const CompiledScene& scene, Ray ray, int maxDepth, Rng& rng,
              Vec3* specular = nullptr) {
    Vec3 result(0.0f), throughput(1.0f);
    Vec3 specularResult(0.0f), specularThroughput(0.0f);
    const bool split = specular != nullptr;
    float previousPdf = 0.0f;  // solid-angle pdf of the BSDF sample that made `ray`
    for (int depth = 0; depth < maxDepth; ++depth) {
        Hit hit = scene.closest(ray);
        if (hit.object < 0) {
            const Vec3 escaped = scene.escapedRadiance(ray.origin, ray.direction, previousPdf);
            result += throughput * escaped;
            if (split)
                if (depth > 0) specularResult += specularThroughput * escaped;
            break;
        }
        Surface s = scene.surface(ray, hit);
        const Material& m = scene.material(hit.object);
        bool front = dot(s.normal, ray.direction) < 0.0f;
        Vec3 n = front ? s.normal : -s.normal;

        if (m.emissive() && (front || m.twoSidedEmission)) {
            float weight = 1.0f;
            int light = scene.lightOf(hit.primitive);
            // Lights that next-event estimation also reaches share the path by MIS; camera
            // rays and unsampled emitters count in full.
            if (depth > 0 && light >= 0)
                weight = powerHeuristic(
                    previousPdf, scene.lightPdf(light, ray.origin, ray.direction, hit.t, s.normal));
            result += throughput * m.emission * weight;
            if (split)
                if (depth > 0) specularResult += specularThroughput * m.emission * weight;
        }
        if (depth + 1 >= maxDepth) break;  // the next vertex would be past the limit

        Vec3 wo = -ray.direction;
        Bsdf bsdf(m, m.albedo.evaluate(s.u, s.v), n, wo);
        if (bsdf.black()) break;
        Vec3 x = offsetPoint(s.position, n);

        if (scene.hasLights()) {
            LightSample ls;
            if (scene.sampleLight(x, rng, ls)) {
                float cosSurface = dot(ls.direction, n);
                if (cosSurface > 0.0f &&
                    !scene.occluded({x, ls.direction}, ls.distance * 0.9999f)) {
                    float weight = powerHeuristic(ls.pdf, bsdf.pdf(ls.direction));
                    result += throughput * bsdf.evaluate(ls.direction) * ls.emission *
                              (cosSurface * weight / ls.pdf);
                    if (split) {
                        if (depth == 0)
                            specularResult += throughput *
                                              Vec3(bsdf.evaluateSpecular(ls.direction)) *
                                              ls.emission * (cosSurface * weight / ls.pdf);
                        else
                            specularResult += specularThroughput * bsdf.evaluate(ls.direction) *
                                              ls.emission * (cosSurface * weight / ls.pdf);
                    }
                }
            }
        }

        Vec3 wi;
        if (!bsdf.sample(rng, wi)) break;
        float pdf = bsdf.pdf(wi);
        if (!(pdf > 0.0f)) break;
        if (split) {
            if (depth == 0)
                specularThroughput =
                    throughput * Vec3(bsdf.evaluateSpecular(wi)) * (dot(wi, n) / pdf);
            else
                specularThroughput *= bsdf.evaluate(wi) * (dot(wi, n) / pdf);
        }
        throughput *= bsdf.evaluate(wi) * (dot(wi, n) / pdf);
        previousPdf = pdf;

        if (depth >= 2) {  // Russian roulette; unbiased since survivors are divided by q
            float q = std::min(0.95f, maxComponent(throughput));
            if (!(rng.uniform() < q)) break;
            throughput *= 1.0f / q;
            if (split) specularThroughput *= 1.0f / q;
        }
        ray = {x, wi};
    }
    if (split) *specular = specularResult;
    return result;
}

// Gauss-Jordan with partial pivoting (in double); a singular matrix (a zero scale) gives none.
std::optional<Matrix4> inverseOf(const Matrix4& m) {
    double a[4][8] = {};
    for (int i = 0; i < 4; ++i) {
        for (int j = 0; j < 4; ++j) a[i][j] = m.m[i][j];
        a[i][4 + i] = 1.0;
    }
    for (int col = 0; col < 4; ++col) {
        int pivot = col;
        for (int row = col + 1; row < 4; ++row)
            if (std::abs(a[row][col]) > std::abs(a[pivot][col])) pivot = row;
        if (std::abs(a[pivot][col]) < 1e-12) return std::nullopt;
        std::swap(a[col], a[pivot]);
        const double scale = 1.0 / a[col][col];
        for (double& v : a[col]) v *= scale;
        for (int row = 0; row < 4; ++row) {
            if (row == col) continue;
            const double factor = a[row][col];
            for (int j = 0; j < 8; ++j) a[row][j] -= factor * a[col][j];
        }
    }
    Matrix4 r;
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j) r.m[i][j] = float(a[i][4 + j]);
    return r;
}

}  // namespace

Image renderRadiance(const Scene& scene, const TraceSettings& settings, Image* specularOut) {
    CompiledScene compiled(scene);
    const int w = settings.width, h = settings.height;
    CameraFrame camera = cameraFrame(scene.camera, w, h);
    Image image(w, h, 3);
    const bool split = specularOut != nullptr;
    if (split) *specularOut = Image(w, h, 3);
    const int spp = std::max(1, settings.samplesPerPixel);
#pragma omp parallel for schedule(monotonic : dynamic)
    for (int y = 0; y < h; ++y) {
        for (int x = 0; x < w; ++x) {
            std::uint64_t pixel = std::uint64_t(y) * std::uint64_t(w) + std::uint64_t(x);
            double sum[3] = {0.0, 0.0, 0.0};
            double specularSum[3] = {0.0, 0.0, 0.0};
            for (int s = 0; s < spp; ++s) {
                Rng rng = sampleRng(settings, pixel, std::uint64_t(s));
                float px = float(x) + rng.uniform(), py = float(y) + rng.uniform();
                Ray ray{camera.position, camera.direction(px, py)};
                Vec3 specular(0.0f);
                Vec3 l =
                    radiance(compiled, ray, settings.maxDepth, rng, split ? &specular : nullptr);
                if (!isFinite(l)) continue;  // never write NaN/Inf; the sample counts as 0
                sum[0] += l.x;
                sum[1] += l.y;
                sum[2] += l.z;
                if (split && isFinite(specular)) {  // a non-finite one counts as 0 too
                    specularSum[0] += specular.x;
                    specularSum[1] += specular.y;
                    specularSum[2] += specular.z;
                }
            }
            for (int c = 0; c < 3; ++c) image.at(x, y, c) = float(sum[c] / spp);
            if (split)
                for (int c = 0; c < 3; ++c) specularOut->at(x, y, c) = float(specularSum[c] / spp);
        }
    }
    return image;
}

std::vector<GradientSample> traceGradientSamples(const Scene& previous, const Scene& current,
                                                 const TraceSettings& last,
                                                 const std::vector<PixelCoord>& pixels) {
    CompiledScene before(previous), now(current);
    const int w = last.width, h = last.height;
    const CameraFrame cameraBefore = cameraFrame(previous.camera, w, h);
    const CameraFrame cameraNow = cameraFrame(current.camera, w, h);
    const Matrix4 toScreenNow = worldToScreen(current.camera, w, h);
    const bool cameraMoved = std::memcmp(&cameraBefore, &cameraNow, sizeof(CameraFrame)) != 0;
    // Per object: previous world -> local -> current world (none: it cannot be inverted).
    std::vector<std::optional<Matrix4>> carry;
    std::vector<bool> moved;
    for (std::size_t k = 0; k < previous.objects.size() && k < current.objects.size(); ++k) {
        const Matrix4& from = previous.objects[k].objectToWorld;
        const Matrix4& to = current.objects[k].objectToWorld;
        std::optional<Matrix4> toLocal = inverseOf(from);
        carry.push_back(toLocal ? std::optional<Matrix4>(to * *toLocal) : std::nullopt);
        moved.push_back(from.m != to.m);
    }
    std::vector<GradientSample> out(pixels.size());
#pragma omp parallel for schedule(monotonic : dynamic, 64)
    for (std::ptrdiff_t i = 0; i < std::ptrdiff_t(pixels.size()); ++i) {
        const PixelCoord p = pixels[std::size_t(i)];
        GradientSample& g = out[std::size_t(i)];
        std::uint64_t pixel = std::uint64_t(p.y) * std::uint64_t(w) + std::uint64_t(p.x);
        Rng rng = sampleRng(last, pixel, 0);
        float px = float(p.x) + rng.uniform(), py = float(p.y) + rng.uniform();
        const Rng afterJitter = rng;  // the path's own random numbers, for the re-shading
        Ray ray{cameraBefore.position, cameraBefore.direction(px, py)};
        const Hit first = before.closest(ray);
        if (first.object < 0 || std::size_t(first.object) >= carry.size() || !carry[first.object])
            continue;
        Vec3 l = radiance(before, ray, last.maxDepth, rng);
        g.before = isFinite(l) ? l : Vec3(0.0f);
        // Nothing moved: the very same ray, so that a still scene re-shades to the same value.
        Ray again = ray;
        if (cameraMoved || moved[first.object]) {
            const Vec3 point = before.surface(ray, first).position;
            const Vec4 moved4 = transformPoint(*carry[first.object], point);
            const Vec3 movedPoint{moved4.x, moved4.y, moved4.z};
            const Vec4 s = transformPoint(toScreenNow, movedPoint);
            if (!(s.w > 0.0f)) continue;
            const float sx = s.x / s.w, sy = s.y / s.w;
            if (!(sx >= 0.0f && sx < float(w) && sy >= 0.0f && sy < float(h))) continue;
            px = sx;
            py = sy;
            const Vec3 toPoint = movedPoint - cameraNow.position;
            const float distance = length(toPoint);
            again = {cameraNow.position, toPoint / distance};
            const Hit seen = now.closest(again);
            if (seen.object != first.object || std::abs(seen.t - distance) > 1e-3f * distance)
                continue;  // hidden now: a disocclusion, which reprojection handles
        }
        Rng same = afterJitter;
        l = radiance(now, again, last.maxDepth, same);
        g.now = isFinite(l) ? l : Vec3(0.0f);
        g.pixel = {std::min(w - 1, int(px)), std::min(h - 1, int(py))};
        g.valid = true;
    }
    return out;
}

namespace {

float linearRoughness(const Material& m) {
    if (!(m.specular > 0.0f)) return 1.0f;  // no glossy lobe: as rough as it gets
    if (m.lobe == Material::Lobe::Ggx) return std::clamp(m.roughness, kMinimumGgxRoughness, 1.0f);
    // Phong exponent n ~ Beckmann/GGX alpha = sqrt(2 / (n + 2)); linear roughness = sqrt(alpha).
    float alpha = std::sqrt(2.0f / (std::max(0.0f, m.exponent) + 2.0f));
    return std::clamp(std::sqrt(alpha), 0.0f, 1.0f);
}

}  // namespace

Frame renderGBuffer(const Scene& scene, int width, int height, bool split) {
    CompiledScene compiled(scene);
    CameraFrame camera = cameraFrame(scene.camera, width, height);
    Frame f;
    f.normal = Image(width, height, 3);
    f.position = Image(width, height, 3);
    f.depth = Image(width, height, 1);
    f.albedo = Image(width, height, 3);
    f.objectId.assign(std::size_t(width) * height, -1);
    if (split) {
        f.roughness = Image(width, height, 1);
        f.hitDistance = Image(width, height, 1);
    }
#pragma omp parallel for schedule(monotonic : dynamic)
    for (int y = 0; y < height; ++y) {
        for (int x = 0; x < width; ++x) {
            Ray ray{camera.position, camera.direction(float(x) + 0.5f, float(y) + 0.5f)};
            Hit hit = compiled.closest(ray);
            Vec3 p = camera.position, n{}, albedo{};
            float depth = 0.0f;
            int id = -1;
            if (hit.object >= 0) {
                Surface s = compiled.surface(ray, hit);
                const Material& m = compiled.material(hit.object);
                p = s.position;
                n = dot(s.normal, ray.direction) < 0.0f ? s.normal : -s.normal;
                depth = dot(p - camera.position, camera.forward);
                // The glossy lobe's share counts with its colour (a metal's albedo is its tint);
                // Phong's lobe is white, and its expression is the one it always was.
                if (m.lobe == Material::Lobe::Ggx)
                    albedo = m.albedo.evaluate(s.u, s.v) * (1.0f - m.specular) +
                             m.specularTint * m.specular;
                else
                    albedo = m.albedo.evaluate(s.u, s.v) * (1.0f - m.specular) + Vec3(m.specular);
                if (split) {
                    f.roughness->at(x, y) = linearRoughness(m);
                    // The mirror direction's hit distance: deterministic and noise-free (not the
                    // distance of the path's sampled glossy ray), 0 on a miss or without a lobe.
                    float hitDistance = 0.0f;
                    if (m.specular > 0.0f) {
                        Vec3 wo = -ray.direction;
                        Ray mirror{offsetPoint(p, n), n * (2.0f * dot(wo, n)) - wo};
                        Hit reflected = compiled.closest(mirror);
                        if (reflected.object >= 0) hitDistance = reflected.t;
                    }
                    f.hitDistance->at(x, y) = hitDistance;
                }
                id = hit.object;
            }
            for (int c = 0; c < 3; ++c) {
                f.position.at(x, y, c) = p[c];
                f.normal.at(x, y, c) = n[c];
                f.albedo->at(x, y, c) = albedo[c];
            }
            f.depth.at(x, y) = depth;
            f.objectId[std::size_t(y) * width + x] = id;
        }
    }
    for (const Object& object : scene.objects) f.objectToWorld.push_back(object.objectToWorld);
    f.worldToCamera = worldToCamera(scene.camera);
    f.worldToScreen = worldToScreen(scene.camera, width, height);
    return f;
}

Frame renderFrame(const Scene& scene, const TraceSettings& settings, bool split) {
    Frame f = renderGBuffer(scene, settings.width, settings.height, split);
    if (split) {
        Image specular;
        f.beauty = renderRadiance(scene, settings, &specular);
        f.specular = std::move(specular);
    } else {
        f.beauty = renderRadiance(scene, settings);
    }
    return f;
}

}  // namespace rtd::render
