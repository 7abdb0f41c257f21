// The scene generator (random_scene.h). The distribution is documented, parameter by parameter,
// in docs/scene_generator.md: a change to any draw here changes kRandomSceneVersion and the docs.
#include "render/random_scene.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <initializer_list>
#include <utility>

#include "render/path_tracer.h"

namespace rtd::render {
namespace {

constexpr float kPi = 3.14159265358979f;

float radians(float degrees) {
    return degrees * (kPi / 180.0f);
}

int positiveModulo(int value, int period) {
    return ((value % period) + period) % period;
}

Vec3 mix(Vec3 a, Vec3 b, float t) {
    return a * (1.0f - t) + b * t;
}

// The generator's own random numbers (splitmix64): no standard-library distribution, whose
// results may differ between libraries, decides a draw. No expression makes two draws whose
// order the language leaves open (function arguments, operands): one draw per statement, or in
// a braced list (evaluated left to right), so that every compiler draws the same scene.
class Draw {
  public:
    // The state starts from a hash of the seed, so that neighbouring seeds share no pattern.
    explicit Draw(std::uint32_t seed) : state_(0x243f6a8885a308d3ull ^ std::uint64_t(seed)) {
        state_ = next();
    }

    std::uint64_t next() {
        std::uint64_t z = (state_ += 0x9e3779b97f4a7c15ull);
        z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
        z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
        return z ^ (z >> 31);
    }
    float uniform() { return float(next() >> 40) * 0x1p-24f; }  // [0, 1)
    float uniform(float lo, float hi) { return lo + (hi - lo) * uniform(); }
    float logUniform(float lo, float hi) { return lo * std::pow(hi / lo, uniform()); }
    int integer(int lo, int hi) {  // [lo, hi]
        return lo + int(next() % std::uint64_t(hi - lo + 1));
    }
    bool chance(float probability) { return uniform() < probability; }
    // An index drawn with the given weights (they need not sum to 1).
    int pick(std::initializer_list<float> weights) {
        float total = 0.0f;
        for (float w : weights) total += w;
        float u = uniform() * total;
        int index = 0;
        for (float w : weights) {
            if (u < w) return index;
            u -= w;
            ++index;
        }
        return index - 1;
    }

  private:
    std::uint64_t state_;
};

// ---- colours and materials ----

Vec3 hsv(float hue, float saturation, float value) {
    auto channel = [&](float n) {
        float k = std::fmod(n + hue * 6.0f, 6.0f);
        return value - value * saturation * std::clamp(std::min(k, 4.0f - k), 0.0f, 1.0f);
    };
    return {channel(5.0f), channel(3.0f), channel(1.0f)};
}

// Mostly muted colours (a third nearly grey), some saturated.
Vec3 drawAlbedo(Draw& d, float valueLo, float valueHi) {
    float hue = d.uniform();
    float saturation = d.chance(0.35f) ? d.uniform(0.0f, 0.15f) : d.uniform(0.2f, 0.8f);
    return hsv(hue, saturation, d.uniform(valueLo, valueHi));
}

// A light's colour of luminance 1: a warm to cool white, or (coloured) a saturated hue.
Vec3 drawLightColour(Draw& d, bool& coloured) {
    coloured = d.chance(0.3f);
    Vec3 c;
    if (coloured) {
        const float hue = d.uniform();
        c = hsv(hue, d.uniform(0.5f, 1.0f), 1.0f);
    } else {
        float t = d.uniform(-1.0f, 1.0f);  // -1 warm (~2700 K) .. 1 cool (~8000 K)
        c = t < 0.0f ? mix({1.0f, 1.0f, 1.0f}, {1.0f, 0.72f, 0.45f}, -t)
                     : mix({1.0f, 1.0f, 1.0f}, {0.78f, 0.88f, 1.0f}, t);
    }
    return c / luminance(c);
}

const char* textureKindName(Texture::Kind kind) {
    switch (kind) {
        case Texture::Kind::Constant:
            return "constant";
        case Texture::Kind::Checker:
            return "checker";
        case Texture::Kind::Stripes:
            return "stripes";
        case Texture::Kind::Noise:
            return "noise";
        case Texture::Kind::Tiles:
            return "tiles";
    }
    return "constant";
}

// A diffuse texture: kind, frequency (log-uniform in [frequencyLo, frequencyHi] per metre) and
// contrast (uniform in [0.1, 0.95]: how far the second colour is from the first, towards black or
// towards another colour).
Texture drawTexture(Draw& d, float frequencyLo, float frequencyHi) {
    const Vec3 base = drawAlbedo(d, 0.3f, 0.9f);
    const int kind = d.pick({0.25f, 0.2f, 0.15f, 0.25f, 0.15f});
    const float frequency = d.logUniform(frequencyLo, frequencyHi);
    const float contrast = d.uniform(0.1f, 0.95f);
    const Vec3 other = d.chance(0.6f) ? base * 0.05f : drawAlbedo(d, 0.05f, 0.9f);
    const Vec3 second = mix(base, other, contrast);
    switch (kind) {
        case 0:
            return Texture::constant(base);
        case 1:
            return Texture::checker(base, second, frequency);
        case 2:
            return Texture::stripes(base, second, frequency);
        case 3: {
            const int octaves = d.integer(1, 6);
            return Texture::noise(base, second, frequency, octaves, std::uint32_t(d.next()));
        }
        default:
            return Texture::tiles(base, second, frequency, d.uniform(0.04f, 0.3f));
    }
}

struct DrawnMaterial {
    Material material;
    std::string kind;
};

// An object's material: diffuse 45 %, glossy 25 % (GGX over a textured base, every roughness),
// metal 18 %, near-mirror 12 %.
DrawnMaterial drawObjectMaterial(Draw& d) {
    switch (d.pick({0.45f, 0.25f, 0.18f, 0.12f})) {
        case 0: {
            Material m;
            m.albedo = drawTexture(d, 0.5f, 40.0f);
            return {m, "diffuse"};
        }
        case 1: {
            Texture base = drawTexture(d, 0.5f, 40.0f);
            float specular = d.uniform(0.05f, 0.5f);
            return {Material::ggx(base, specular, d.uniform(0.02f, 1.0f)), "glossy"};
        }
        case 2: {
            static const Vec3 kMetals[] = {{0.95f, 0.93f, 0.88f},   // silver
                                           {1.0f, 0.78f, 0.34f},    // gold
                                           {0.95f, 0.64f, 0.54f},   // copper
                                           {0.91f, 0.92f, 0.92f}};  // aluminium
            int which = d.integer(0, 4);
            Vec3 tint = which < 4 ? kMetals[which] : drawAlbedo(d, 0.5f, 0.95f);
            tint = tint * d.uniform(0.6f, 1.0f);
            return {
                Material::ggx(Texture::constant(Vec3(0.0f)), 1.0f, d.uniform(0.05f, 0.6f), tint),
                "metal"};
        }
        default: {
            const Vec3 hue = drawAlbedo(d, 0.8f, 1.0f);
            const Vec3 tint = mix(Vec3(1.0f), hue, 0.2f) * d.uniform(0.85f, 0.97f);
            const float specular = d.uniform(0.9f, 1.0f);
            const Vec3 base = drawAlbedo(d, 0.1f, 0.6f);
            const float roughness = d.uniform(0.02f, 0.06f);
            return {Material::ggx(Texture::constant(base), specular, roughness, tint), "mirror"};
        }
    }
}

// A wall's, ceiling's or ground's material: textured diffuse (lower frequencies than objects'),
// a glossy floor with probability glossyProbability.
DrawnMaterial drawSurfaceMaterial(Draw& d, float glossyProbability) {
    Texture t = drawTexture(d, 0.3f, 8.0f);
    if (d.chance(glossyProbability)) {
        const float specular = d.uniform(0.05f, 0.3f);
        return {Material::ggx(t, specular, d.uniform(0.05f, 0.6f)), "glossy"};
    }
    Material m;
    m.albedo = t;
    return {m, "diffuse"};
}

// An emitter that also reflects (albedo 0.7): a grey panel or ball when switched off.
Material emitterMaterial(Vec3 emission) {
    Material m;
    m.albedo = Texture::constant(Vec3(0.7f));
    m.emission = emission;
    return m;
}

// ---- motion ----

const char* speedName(int speed) {
    static const char* kNames[] = {"slow", "medium", "fast"};
    return kNames[speed];
}

// Peak speeds per frame of each class: slow, medium, fast.
constexpr float kLinearSpeed[] = {0.01f, 0.04f, 0.12f};  // metres
constexpr float kAngularSpeed[] = {0.15f, 0.6f, 2.0f};   // degrees

Oscillation oscillationWithSpeed(Draw& d, float peakSpeed, float maxAmplitude) {
    Oscillation o;
    o.period = d.integer(24, 96);
    o.phase = d.uniform(0.0f, 2.0f * kPi);
    o.amplitude = std::min(maxAmplitude, peakSpeed * float(o.period) / (2.0f * kPi));
    return o;
}

// An object's motion (probability `moveProbability`): slide 35 %, spin 25 %, slide and spin 20 %,
// bounce 20 %, each slow, medium or fast; slides at most maxSlide metres from rest.
DrawnMotion drawObjectMotion(Draw& d, float moveProbability, float maxSlide) {
    DrawnMotion m;
    if (!d.chance(moveProbability)) return m;
    const int speed = d.pick({0.35f, 0.4f, 0.25f});
    const float jitter = d.uniform(0.7f, 1.4f);
    const int kind = d.pick({0.35f, 0.25f, 0.2f, 0.2f});
    const float angle = d.uniform(0.0f, 2.0f * kPi);
    m.axis = {std::cos(angle), 0.0f, std::sin(angle)};
    m.offset = oscillationWithSpeed(d, kLinearSpeed[speed] * jitter, maxSlide);
    m.spinDegreesPerFrame = kAngularSpeed[speed] * jitter * 2.0f * (d.chance(0.5f) ? 1.0f : -1.0f);
    switch (kind) {
        case 0:
            m.kind = DrawnMotion::Kind::Slide;
            break;
        case 1:
            m.kind = DrawnMotion::Kind::Spin;
            break;
        case 2:
            m.kind = DrawnMotion::Kind::SlideAndSpin;
            break;
        default:
            m.kind = DrawnMotion::Kind::Bounce;
            m.offset.amplitude = std::min(m.offset.amplitude, 0.6f);
            break;
    }
    return m;
}

DrawnSwitch drawSwitch(Draw& d, float probability) {
    DrawnSwitch s;
    if (!d.chance(probability)) return s;
    s.switches = true;
    s.period = d.integer(4, 32);
    s.onFrames =
        std::clamp(int(std::lround(float(s.period) * d.uniform(0.3f, 0.7f))), 1, s.period - 1);
    s.offset = d.integer(0, s.period - 1);
    return s;
}

// ---- geometry ----

Object makeObject(std::string name, std::vector<Primitive> primitives, Material m, bool light) {
    Object o;
    o.name = std::move(name);
    o.primitives = std::move(primitives);
    o.material = m;
    o.light = light;
    return o;
}

// The horizontal reach of an object's local geometry after `orientation` (for placement).
float horizontalRadius(const std::vector<Primitive>& primitives, const Matrix4& orientation) {
    float radius = 0.0f;
    for (const Primitive& p : primitives) {
        Vec3 lo, hi;
        switch (p.kind) {
            case Primitive::Kind::Box:
                lo = min(p.p0, p.p1);
                hi = max(p.p0, p.p1);
                break;
            case Primitive::Kind::Sphere:
                lo = p.p0 - Vec3(p.p1.x);
                hi = p.p0 + Vec3(p.p1.x);
                break;
            case Primitive::Kind::Quad:
                lo = min(min(p.p0, p.p0 + p.p1), min(p.p0 + p.p2, p.p0 + p.p1 + p.p2));
                hi = max(max(p.p0, p.p0 + p.p1), max(p.p0 + p.p2, p.p0 + p.p1 + p.p2));
                break;
        }
        for (int corner = 0; corner < 8; ++corner) {
            Vec3 q{corner & 1 ? hi.x : lo.x, corner & 2 ? hi.y : lo.y, corner & 4 ? hi.z : lo.z};
            Vec4 w = transformPoint(orientation, q);
            radius = std::max(radius, std::sqrt(w.x * w.x + w.z * w.z));
        }
    }
    return radius;
}

Primitive centredBox(Vec3 size) {
    return Primitive::box(size * -0.5f, size * 0.5f);
}

// A stage object's local geometry, orientation and resting height. kind: box, sphere, bar, grid,
// details, slab.
struct Shape {
    std::string kind;
    std::vector<Primitive> primitives;
    Matrix4 orientation = Matrix4::identity();
    float height = 0.0f;  // rest position's y
};

Shape drawShape(Draw& d, float ceiling) {
    Shape s;
    switch (d.pick({0.28f, 0.24f, 0.16f, 0.12f, 0.12f, 0.08f})) {
        case 0: {  // box: any proportions, sometimes floating and tilted
            s.kind = "box";
            Vec3 size{d.uniform(0.1f, 1.2f), d.uniform(0.1f, 1.2f), d.uniform(0.1f, 1.2f)};
            s.primitives = {centredBox(size)};
            s.height = 0.5f * size.y;
            if (d.chance(0.2f)) s.height += d.uniform(0.3f, 1.2f);
            if (d.chance(0.3f)) {
                const float aboutX = d.uniform(-40.0f, 40.0f);
                s.orientation =
                    rotationX(radians(aboutX)) * rotationZ(radians(d.uniform(-40.0f, 40.0f)));
                s.height += 0.3f * length(size);
            }
            break;
        }
        case 1: {  // sphere, resting or floating
            s.kind = "sphere";
            float r = d.uniform(0.08f, 0.7f);
            s.primitives = {Primitive::sphere({}, r)};
            s.height = r + (d.chance(0.2f) ? d.uniform(0.2f, 1.0f) : 0.0f);
            break;
        }
        case 2: {  // thin bar: a pole, a rail or a diagonal strut, 6 mm to 4 cm thick
            s.kind = "bar";
            float thickness = d.logUniform(0.006f, 0.04f);
            float len = std::min(d.uniform(0.5f, 3.0f), ceiling - 0.1f);
            s.primitives = {centredBox({len, thickness, thickness})};
            switch (d.pick({0.4f, 0.3f, 0.3f})) {
                case 0:
                    s.orientation = rotationZ(radians(90.0f));
                    s.height = 0.5f * len;
                    break;
                case 1:
                    s.height = d.uniform(0.2f, std::min(2.0f, ceiling - 0.2f));
                    break;
                default: {
                    float tilt = d.uniform(20.0f, 70.0f);
                    s.orientation = rotationZ(radians(tilt));
                    s.height = 0.5f * len * std::sin(radians(tilt)) + d.uniform(0.0f, 0.3f);
                    break;
                }
            }
            break;
        }
        case 3: {  // grid: a lattice of thin bars, standing, or overhead as a grate
            s.kind = "grid";
            float width = d.uniform(0.6f, 2.0f), tall = d.uniform(0.6f, 2.0f);
            float spacing = std::max(d.uniform(0.06f, 0.3f), std::max(width, tall) / 12.0f);
            float bar = d.logUniform(0.006f, 0.03f);
            for (float x = -0.5f * width; x <= 0.5f * width + 1e-4f; x += spacing)
                s.primitives.push_back(Primitive::box({x - 0.5f * bar, -0.5f * tall, -0.5f * bar},
                                                      {x + 0.5f * bar, 0.5f * tall, 0.5f * bar}));
            for (float y = -0.5f * tall; y <= 0.5f * tall + 1e-4f; y += spacing)
                s.primitives.push_back(Primitive::box({-0.5f * width, y - 0.5f * bar, -0.5f * bar},
                                                      {0.5f * width, y + 0.5f * bar, 0.5f * bar}));
            if (d.chance(0.2f)) {  // overhead: its shadow falls on everything below
                s.orientation = rotationX(radians(90.0f));
                s.height = std::max(0.5f, std::min(ceiling - 0.4f, d.uniform(1.6f, 2.8f)));
            } else {
                s.height = 0.5f * tall + d.uniform(0.0f, 0.4f);
            }
            break;
        }
        case 4: {  // small details: 6-30 small boxes and balls on a table or on the floor
            s.kind = "details";
            float table = d.chance(0.6f) ? d.uniform(0.4f, 0.9f) : 0.0f;
            Vec3 top{d.uniform(0.4f, 0.9f), 0.03f, d.uniform(0.3f, 0.7f)};
            if (table > 0.0f) {
                s.primitives.push_back(Primitive::box({-0.5f * top.x, table - top.y, -0.5f * top.z},
                                                      {0.5f * top.x, table, 0.5f * top.z}));
                float leg = d.uniform(0.015f, 0.04f);
                for (int i = 0; i < 4; ++i) {
                    float x = (i & 1 ? 0.5f : -0.5f) * (top.x - 2.0f * leg);
                    float z = (i & 2 ? 0.5f : -0.5f) * (top.z - 2.0f * leg);
                    s.primitives.push_back(
                        Primitive::box({x - 0.5f * leg, 0.0f, z - 0.5f * leg},
                                       {x + 0.5f * leg, table - top.y, z + 0.5f * leg}));
                }
            }
            int items = d.integer(6, 30);
            for (int i = 0; i < items; ++i) {
                float size = d.logUniform(0.01f, 0.06f);
                Vec3 c{d.uniform(-0.45f, 0.45f) * top.x, table + 0.5f * size,
                       d.uniform(-0.45f, 0.45f) * top.z};
                if (d.chance(0.5f)) {
                    Vec3 extent{size * d.uniform(0.5f, 1.5f), size, size * d.uniform(0.5f, 1.5f)};
                    s.primitives.push_back(Primitive::box(c - extent * 0.5f, c + extent * 0.5f));
                } else {
                    s.primitives.push_back(Primitive::sphere(c, 0.5f * size));
                }
            }
            break;
        }
        default: {  // slab: a board lying flat at some height or leaning
            s.kind = "slab";
            Vec3 size{d.uniform(0.4f, 1.5f), d.uniform(0.015f, 0.05f), d.uniform(0.4f, 1.2f)};
            s.primitives = {centredBox(size)};
            if (d.chance(0.5f)) {
                float tilt = d.uniform(15.0f, 75.0f);
                s.orientation = rotationX(radians(tilt));
                s.height = 0.5f * size.z * std::sin(radians(tilt)) + 0.5f * size.y;
            } else {
                s.height = d.uniform(0.0f, 1.0f) + 0.5f * size.y;
            }
            break;
        }
    }
    return s;
}

// Where objects may stand: a rectangle (rooms) or a disc (open scenes) on the floor.
struct Stage {
    bool disc = false;
    float x0 = 0, x1 = 0, z0 = 0, z1 = 0;  // rectangle
    float radius = 0;                      // disc about the origin
};

// A position for something of horizontal radius `reach` that keeps clear of the stage's edge and
// of what stands there already (the best of 8 candidates: the farthest from its nearest one).
Vec3 placeOnStage(Draw& d, const Stage& stage, float reach, const std::vector<Vec3>& taken) {
    Vec3 best{};
    float bestDistance = -1.0f;
    for (int attempt = 0; attempt < 8; ++attempt) {
        Vec3 p;
        if (stage.disc) {
            float r = std::max(0.0f, stage.radius - reach) * std::sqrt(d.uniform());
            float a = d.uniform(0.0f, 2.0f * kPi);
            p = {r * std::cos(a), 0.0f, r * std::sin(a)};
        } else {
            auto within = [&](float lo, float hi) {
                return lo + reach <= hi - reach ? d.uniform(lo + reach, hi - reach)
                                                : 0.5f * (lo + hi);
            };
            p = {within(stage.x0, stage.x1), 0.0f, within(stage.z0, stage.z1)};
        }
        float nearest = 1e9f;
        for (Vec3 q : taken) nearest = std::min(nearest, length(p - q));
        if (nearest > bestDistance) {
            bestDistance = nearest;
            best = p;
        }
    }
    return best;
}

// ---- rooms ----

// A wall as a quad corner + u + v (front face cross(u, v) inside), optionally with a rectangular
// hole [a0, a1] x [b0, b1] in its (u, v) parameters: four quads around it, one object.
std::vector<Primitive> wallWithHole(Vec3 corner, Vec3 u, Vec3 v, float a0, float a1, float b0,
                                    float b1) {
    auto piece = [&](float ua, float ub, float va, float vb) {
        return Primitive::quad(corner + u * ua + v * va, u * (ub - ua), v * (vb - va));
    };
    return {piece(0, 1, 0, b0), piece(0, 1, b1, 1), piece(0, a0, b0, b1), piece(a1, 1, b0, b1)};
}

struct Room {
    Vec3 lo, hi;
};

// ---- the draw ----

struct Generator {
    Draw d;
    RandomSceneRecipe r;
    Stage stage;
    std::vector<Vec3> taken;  // stage positions in use
    float ceiling = 100.0f;   // rooms: the height; open: a bound for tall things
    Room room;
    int lightCount = 0;

    explicit Generator(std::uint32_t seed) : d(seed) { r.seed = seed; }

    void add(DrawnObject o) { r.objects.push_back(std::move(o)); }

    DrawnObject surface(std::string name, std::vector<Primitive> primitives, float glossy) {
        DrawnMaterial m = drawSurfaceMaterial(d, glossy);
        DrawnObject o;
        o.object = makeObject(name, std::move(primitives), m.material, false);
        o.kind = std::move(name);
        o.materialKind = m.kind;
        return o;
    }

    void drawRoom(bool withWindow) {
        const Vec3 size{d.uniform(3.0f, 10.0f), d.uniform(2.4f, 4.5f), d.uniform(4.0f, 12.0f)};
        r.roomSize = size;
        room = {{-0.5f * size.x, 0.0f, -0.5f * size.z}, {0.5f * size.x, size.y, 0.5f * size.z}};
        ceiling = size.y;
        const Vec3 lo = room.lo, hi = room.hi, s = hi - lo;
        // The window's wall and hole: fractions [h0, h1] across the wall and [v0, v1] up it
        // (the ceiling: along x and along z).
        int windowWall = -1;
        float h0 = 0, h1 = 0, v0 = 0, v1 = 0;
        if (withWindow) {
            windowWall = d.pick({0.27f, 0.27f, 0.26f, 0.2f});  // left, right, back, ceiling
            static const char* kNames[] = {"left", "right", "back", "ceiling"};
            r.window = kNames[windowWall];
            // Large: the light that comes in through them lights the room indirectly, and a
            // small window makes that too rare for a 256-spp reference to converge.
            float width = windowWall == 3 ? d.uniform(0.25f, 0.5f) : d.uniform(0.35f, 0.75f);
            float tall = windowWall == 3 ? d.uniform(0.25f, 0.5f) : d.uniform(0.35f, 0.6f);
            h0 = d.uniform(0.1f, 0.9f - width);
            h1 = h0 + width;
            v0 = windowWall == 3 ? d.uniform(0.1f, 0.9f - tall) : d.uniform(0.2f, 0.95f - tall);
            v1 = v0 + tall;
        }
        // Walls share one material half of the time.
        const bool shared = d.chance(0.5f);
        DrawnMaterial wall = drawSurfaceMaterial(d, 0.0f);
        auto wallObject = [&](const char* name, Vec3 corner, Vec3 u, Vec3 v, int index,
                              float glossy) {
            std::vector<Primitive> p{Primitive::quad(corner, u, v)};
            if (index >= 0 && index == windowWall) {
                // The hole's vertical extent is along u when u points up.
                const bool uUp = u.y != 0.0f;
                const float a0 = uUp ? v0 : h0, a1 = uUp ? v1 : h1;
                const float b0 = uUp ? h0 : v0, b1 = uUp ? h1 : v1;
                p = wallWithHole(corner, u, v, a0, a1, b0, b1);
                r.skyPortals.push_back({corner + u * a0 + v * b0, u * (a1 - a0), v * (b1 - b0)});
            }
            DrawnObject o = surface(name, std::move(p), glossy);
            if (shared && glossy == 0.0f) {
                o.object.material = wall.material;
                o.materialKind = wall.kind;
            }
            add(std::move(o));
        };
        wallObject("floor", lo, {0, 0, s.z}, {s.x, 0, 0}, -1, 0.3f);
        wallObject("ceiling", {lo.x, hi.y, lo.z}, {s.x, 0, 0}, {0, 0, s.z}, 3, 0.0f);
        wallObject("back wall", {lo.x, lo.y, hi.z}, {0, s.y, 0}, {s.x, 0, 0}, 2, 0.0f);
        wallObject("left wall", lo, {0, s.y, 0}, {0, 0, s.z}, 0, 0.0f);
        wallObject("right wall", {hi.x, lo.y, lo.z}, {0, 0, s.z}, {0, s.y, 0}, 1, 0.0f);
        wallObject("front wall", lo, {s.x, 0, 0}, {0, s.y, 0}, -1, 0.0f);
        // Objects stand in the far 55 % of the room; the camera keeps to the near 40 %.
        stage = {false, lo.x + 0.3f, hi.x - 0.3f, lo.z + 0.45f * s.z, hi.z - 0.3f, 0.0f};
    }

    void drawOpen() {
        // The ground: 400 m across, so that its edge is beyond the horizon's pixels.
        add(surface("ground", {Primitive::quad({-200, 0, -200}, {0, 0, 400}, {400, 0, 0})}, 0.15f));
        const float radius = d.uniform(1.5f, 4.0f);
        stage = {true, 0, 0, 0, 0, radius};
        // Backdrops: long walls behind the stage that light bounces off.
        const int backdrops = d.pick({0.5f, 0.3f, 0.2f});
        for (int i = 0; i < backdrops; ++i) {
            float len = d.uniform(4.0f, 12.0f), tall = d.uniform(2.0f, 5.0f);
            DrawnObject o = surface(fmt::format("backdrop {}", i + 1),
                                    {centredBox({len, tall, d.uniform(0.2f, 0.6f)})}, 0.0f);
            o.kind = "backdrop";
            float a = d.uniform(0.0f, 2.0f * kPi);
            // Beyond the camera's farthest place (drawCamera: radius + 4 m, + 0.5 m of dolly or
            // 0.8 m of truck).
            o.position = Vec3(std::cos(a), 0.0f, std::sin(a)) * (radius + d.uniform(5.5f, 10.0f));
            o.position.y = 0.5f * tall;
            o.yawDegrees = -a * 180.0f / kPi + 90.0f;  // its length across the line to the centre
            add(std::move(o));
        }
    }

    // The sky of a day (blue above, pale at the horizon), an overcast day (grey) or a night.
    void drawSky(bool overcast) {
        if (r.night) {
            float level = d.uniform(0.0005f, 0.003f);
            r.sky = {Vec3(0.3f, 0.4f, 1.0f) * level, Vec3(0.5f, 0.5f, 0.8f) * level,
                     Vec3(0.2f) * level};
        } else if (overcast) {
            float level = d.uniform(0.6f, 1.5f);
            Vec3 grey = mix(Vec3(1.0f), drawAlbedo(d, 0.9f, 1.0f), 0.15f) * level;
            r.sky = {grey, grey * 1.1f, grey * d.uniform(0.1f, 0.3f)};
        } else {
            float level = d.uniform(0.4f, 1.0f);
            Vec3 zenith{d.uniform(0.15f, 0.4f), d.uniform(0.3f, 0.6f), d.uniform(0.7f, 1.0f)};
            Vec3 horizon{d.uniform(0.6f, 0.9f), d.uniform(0.7f, 0.9f), d.uniform(0.8f, 1.0f)};
            r.sky = {zenith * level, horizon * level,
                     Vec3(0.8f, 0.7f, 0.6f) * (level * d.uniform(0.05f, 0.2f))};
        }
    }

    // A sun at an elevation in [elevationLo, elevationHi] degrees and an azimuth within +-spread
    // of azimuth (degrees; 0 is +z, 90 is +x).
    void drawSun(float elevationLo, float elevationHi, float azimuth, float spread) {
        r.sunElevationDegrees = d.uniform(elevationLo, elevationHi);
        r.sunAzimuthDegrees = azimuth + d.uniform(-spread, spread);
        r.sun.angularRadiusDegrees = d.logUniform(0.25f, 1.5f);
        Vec3 warm = mix(Vec3(1.0f), Vec3(1.0f, 0.85f, 0.65f), d.uniform(0.0f, 1.0f));
        r.sun.irradiance = warm / luminance(warm) * d.uniform(2.0f, 6.0f);
        // The sun moves 15 % of the time: its shadows sweep (within +-30 degrees of azimuth, so
        // that a window keeps its sun).
        if (d.chance(0.15f))
            r.sunAzimuthMotion = oscillationWithSpeed(d, d.uniform(0.2f, 2.0f), 30.0f);
        r.sun.direction = sunDirection(0);
    }
    Vec3 sunDirection(int frame) const {
        float e = radians(r.sunElevationDegrees);
        float a = radians(r.sunAzimuthDegrees + r.sunAzimuthMotion.at(frame));
        return {std::cos(e) * std::sin(a), std::sin(e), std::cos(e) * std::cos(a)};
    }

    // ---- lights ----

    DrawnObject lightObject(std::string kind, std::vector<Primitive> primitives, Vec3 emission,
                            bool sampled) {
        DrawnObject o;
        o.object = makeObject(fmt::format("{} {}", kind, ++lightCount), std::move(primitives),
                              emitterMaterial(emission), sampled);
        o.kind = kind;
        o.lightKind = kind;
        o.materialKind = "emitter";
        return o;
    }

    Vec3 lightEmission(float lo, float hi) {
        bool coloured = false;
        Vec3 c = drawLightColour(d, coloured);
        return c * d.logUniform(lo, hi);
    }

    // A panel facing down under the ceiling (rooms) or floating 2.5-4 m up (open).
    void addAreaLight() {
        float sx = d.uniform(0.3f, 1.6f), sz = d.uniform(0.3f, 1.6f);
        Vec3 centre;
        if (stage.disc) {
            centre = placeOnStage(d, {true, 0, 0, 0, 0, stage.radius + 2.0f}, 0.0f, {});
            centre.y = d.uniform(2.5f, 4.0f);
        } else {
            sx = std::min(sx, 0.8f * (room.hi.x - room.lo.x));
            sz = std::min(sz, 0.8f * (room.hi.z - room.lo.z));
            centre = {d.uniform(room.lo.x + 0.5f * sx, room.hi.x - 0.5f * sx), room.hi.y - 0.002f,
                      d.uniform(room.lo.z + 0.5f * sz, room.hi.z - 0.5f * sz)};
        }
        DrawnObject o = lightObject(
            "area light", {Primitive::quad({-0.5f * sx, 0.0f, -0.5f * sz}, {sx, 0, 0}, {0, 0, sz})},
            lightEmission(4.0f, 20.0f), true);
        o.position = centre;
        if (d.chance(0.15f)) {  // slides along x, a few cm a frame at most
            o.motion.kind = DrawnMotion::Kind::Slide;
            o.motion.offset = oscillationWithSpeed(d, kLinearSpeed[d.integer(0, 1)], 0.5f);
        }
        add(std::move(o));
    }

    // A small, bright sphere (3-10 cm) high in the room or over the stage; orbits or slides 35 %.
    void addSmallLight() {
        float radius = d.uniform(0.03f, 0.1f);
        Vec3 p = placeOnStage(d, stage, 0.0f, taken);
        taken.push_back(p);
        p.y = stage.disc ? d.uniform(0.5f, 4.0f)
                         : d.uniform(0.5f * ceiling, std::max(0.5f * ceiling, ceiling - 0.3f));
        DrawnObject o = lightObject("small light", {Primitive::sphere({}, radius)},
                                    lightEmission(1.0f, 4.0f) / (radius * radius), true);
        o.position = p;
        if (d.chance(0.35f)) {
            const int speed = d.pick({0.35f, 0.4f, 0.25f});
            if (d.chance(0.5f)) {
                o.motion.kind = DrawnMotion::Kind::Orbit;
                o.motion.offset.amplitude = d.uniform(0.3f, 1.2f);
                // A circle of circumference 2 pi a at the class's speed: period 2 pi a / speed.
                o.motion.offset.period =
                    std::max(8, int(2.0f * kPi * o.motion.offset.amplitude / kLinearSpeed[speed]));
                o.motion.offset.phase = d.uniform(0.0f, 2.0f * kPi);
            } else {
                o.motion.kind = DrawnMotion::Kind::Slide;
                float angle = d.uniform(0.0f, 2.0f * kPi);
                o.motion.axis = {std::cos(angle), 0.0f, std::sin(angle)};
                o.motion.offset = oscillationWithSpeed(d, kLinearSpeed[speed], 1.0f);
            }
        }
        add(std::move(o));
    }

    // A glowing ball (sampled as a light) or a neon tube (found by BSDF sampling only) on the
    // stage; moves like an object 30 % of the time.
    void addEmissiveObject() {
        std::vector<Primitive> shape;
        float height = 0.0f, reach = 0.0f;
        const bool ball = d.chance(0.5f);
        Matrix4 orientation = Matrix4::identity();
        if (ball) {
            float radius = d.uniform(0.05f, 0.25f);
            shape = {Primitive::sphere({}, radius)};
            height = radius + (d.chance(0.4f) ? d.uniform(0.2f, 1.2f) : 0.0f);
            reach = radius;
        } else {
            float len = d.uniform(0.3f, 1.5f), thick = d.uniform(0.015f, 0.04f);
            shape = {centredBox({len, thick, thick})};
            if (d.chance(0.5f)) orientation = rotationZ(radians(90.0f));
            height = d.chance(0.5f) ? 0.5f * len + 0.05f : d.uniform(0.3f, 1.8f);
            reach = 0.5f * len;
        }
        DrawnObject o =
            lightObject("emissive object", std::move(shape), lightEmission(2.0f, 12.0f), ball);
        o.orientation = orientation;
        o.motion = drawObjectMotion(d, 0.3f, 0.6f);
        keepSlideOnStage(o.motion, reach);
        o.position = placeOnStage(d, stage, reach + o.motion.offset.amplitude, taken);
        o.position.y = height;
        o.yawDegrees = d.uniform(0.0f, 360.0f);
        taken.push_back(o.position);
        add(std::move(o));
    }

    // A panel on a side or back wall facing into the room.
    void addWallPanel() {
        float sx = d.uniform(0.3f, 1.2f), sy = d.uniform(0.2f, 0.8f);
        DrawnObject o = lightObject(
            "wall panel", {Primitive::quad({-0.5f * sx, -0.5f * sy, 0.0f}, {sx, 0, 0}, {0, sy, 0})},
            lightEmission(3.0f, 15.0f), true);
        placeFacingWall(o, sx, 0.01f, d.uniform(1.0f, std::max(1.0f, ceiling - 0.3f - 0.5f * sy)),
                        false);
        add(std::move(o));
    }

    // Hidden lights for indirect-only rooms: a panel facing the ceiling 0.5-1 m under it, or a
    // wall washer facing a wall 15-30 cm from it.
    void addHiddenLight() {
        float sx = d.uniform(0.6f, 2.0f), sz = d.uniform(0.6f, 2.0f);
        if (d.chance(0.6f)) {
            sx = std::min(sx, 0.6f * (room.hi.x - room.lo.x));
            sz = std::min(sz, 0.6f * (room.hi.z - room.lo.z));
            DrawnObject o = lightObject(
                "hidden light",
                {Primitive::quad({-0.5f * sx, 0.0f, -0.5f * sz}, {0, 0, sz}, {sx, 0, 0})},
                lightEmission(5.0f, 30.0f), true);
            // 0.5-1 m under the ceiling: nearer, its hot spot there is a source of fireflies
            // that even a reference cannot average away.
            o.position = {d.uniform(room.lo.x + 0.5f * sx, room.hi.x - 0.5f * sx),
                          room.hi.y - d.uniform(0.5f, std::min(1.0f, 0.4f * ceiling)),
                          d.uniform(stage.z0, room.hi.z - 0.5f * sz)};
            // Over the stage: at the camera's height in a low room, never in front of it.
            o.position.z = std::max(o.position.z, stage.z0 + 0.5f * sz);
            add(std::move(o));
        } else {
            DrawnObject o = lightObject(
                "hidden light",
                {Primitive::quad({-0.5f * sx, -0.5f * sz, 0.0f}, {sx, 0, 0}, {0, sz, 0})},
                lightEmission(5.0f, 30.0f), true);
            const float gap = d.uniform(0.15f, 0.3f);
            placeFacingWall(o, sx, gap, d.uniform(1.0f, std::max(1.0f, ceiling - 0.3f - 0.5f * sz)),
                            true);
            add(std::move(o));
        }
    }

    // Puts a panel (local front face +z, width `width`) at `gap` from the back, left or right
    // wall at `height`: facing the wall (towardsWall) or the room.
    void placeFacingWall(DrawnObject& o, float width, float gap, float height, bool towardsWall) {
        const int wall = d.integer(0, 2);  // back, left, right
        const float halfX = 0.5f * (room.hi.x - room.lo.x);
        if (wall == 0) {
            o.position = {d.uniform(-1.0f, 1.0f) * std::max(0.0f, halfX - 0.5f * width), height,
                          room.hi.z - gap};
            o.yawDegrees = towardsWall ? 0.0f : 180.0f;
        } else {
            const float side = wall == 1 ? -1.0f : 1.0f;
            o.position = {side * (halfX - gap), height,
                          d.uniform(stage.z0, std::max(stage.z0, room.hi.z - 0.5f * width))};
            o.yawDegrees = (towardsWall ? 90.0f : -90.0f) * side;
        }
    }

    // ---- objects and camera ----

    // The stage's half-size: the largest horizontal reach about a spot on it.
    float stageHalfSize() const {
        return stage.disc ? stage.radius
                          : 0.5f * std::min(stage.x1 - stage.x0, stage.z1 - stage.z0);
    }

    void keepSlideOnStage(DrawnMotion& motion, float reach) const {
        if (motion.kind == DrawnMotion::Kind::Slide ||
            motion.kind == DrawnMotion::Kind::SlideAndSpin)
            motion.offset.amplitude =
                std::min(motion.offset.amplitude, std::max(0.0f, stageHalfSize() - reach));
    }

    static void scale(std::vector<Primitive>& primitives, float k) {
        for (Primitive& p : primitives) {
            p.p0 = p.p0 * k;
            p.p1 = p.kind == Primitive::Kind::Sphere ? Vec3(p.p1.x * k, 0.0f, 0.0f) : p.p1 * k;
            p.p2 = p.p2 * k;
        }
    }

    void addObjects(int count) {
        for (int i = 0; i < count; ++i) {
            Shape shape = drawShape(d, ceiling);
            DrawnMaterial m = drawObjectMaterial(d);
            DrawnObject o;
            o.kind = shape.kind;
            o.materialKind = m.kind;
            o.object = makeObject(fmt::format("{} {}", shape.kind, i + 1),
                                  std::move(shape.primitives), m.material, false);
            o.orientation = shape.orientation;
            o.motion = drawObjectMotion(d, 0.35f, stage.disc ? 1.5f : 0.8f);
            float reach = horizontalRadius(o.object.primitives, o.orientation);
            // Nothing reaches beyond the stage, so nothing reaches the camera: a shape larger
            // than the stage shrinks to fit, a slide stops at its edge.
            if (reach > stageHalfSize()) {
                const float k = stageHalfSize() / reach;
                scale(o.object.primitives, k);
                shape.height *= k;
                reach *= k;
            }
            keepSlideOnStage(o.motion, reach);
            o.position = placeOnStage(d, stage, reach + o.motion.offset.amplitude, taken);
            o.position.y = shape.height;
            o.yawDegrees = d.uniform(0.0f, 360.0f);
            taken.push_back(o.position);
            add(std::move(o));
        }
    }

    void drawCamera() {
        DrawnCamera& c = r.camera;
        c.verticalFovDegrees = d.uniform(35.0f, 75.0f);
        if (stage.disc) {
            const float distance = stage.radius + d.uniform(0.5f, 4.0f);
            const float a = d.uniform(0.0f, 2.0f * kPi);
            c.position = {distance * std::cos(a), d.uniform(0.4f, 3.0f), distance * std::sin(a)};
            c.target = {d.uniform(-1.0f, 1.0f), d.uniform(0.2f, 1.2f), d.uniform(-1.0f, 1.0f)};
        } else {
            const float halfX = 0.5f * (room.hi.x - room.lo.x);
            const float zoneLo = room.lo.z + 0.3f, zoneHi = stage.z0 - 0.2f;
            c.position = {d.uniform(-0.3f, 0.3f) * std::max(0.0f, halfX - 0.5f),
                          d.uniform(1.0f, std::min(2.0f, ceiling - 0.4f)),
                          0.5f * (zoneLo + zoneHi)};
            c.target = {d.uniform(-0.25f, 0.25f) * 2.0f * halfX, d.uniform(0.3f, 1.2f),
                        d.uniform(stage.z0, stage.z1)};
        }
        const int motion = stage.disc
                               ? d.pick({0.22f, 0.13f, 0.05f, 0.1f, 0.1f, 0.15f, 0.1f, 0.15f})
                               : d.pick({0.25f, 0.15f, 0.07f, 0.12f, 0.12f, 0.0f, 0.12f, 0.17f});
        c.motion = DrawnCamera::Motion(motion);
        if (c.motion == DrawnCamera::Motion::Static) return;
        const int speed = d.pick({0.35f, 0.4f, 0.25f});
        c.speed = speedName(speed);
        const float jitter = d.uniform(0.7f, 1.4f);
        const float angular = kAngularSpeed[speed] * jitter, linear = kLinearSpeed[speed] * jitter;
        // How far the camera may move along a direction and stay in its part of the room (or,
        // outdoors, short of the stage).
        const Vec3 forward = normalize(c.target - c.position);
        const Vec3 right = normalize(cross({0.0f, 1.0f, 0.0f}, forward));
        auto roomToMove = [&](Vec3 along) {
            if (stage.disc) {
                const float distance = length(c.position);
                return std::min(0.8f * std::max(0.0f, distance - stage.radius - 0.5f),
                                std::max(0.0f, stage.radius + 4.5f - distance));
            }
            const float halfX = 0.5f * (room.hi.x - room.lo.x) - 0.3f;
            const float zoneHalf = 0.5f * (stage.z0 - 0.2f - room.lo.z - 0.3f);
            float limit = 10.0f;
            if (std::abs(along.x) > 1e-3f)
                limit = std::min(limit, (halfX - std::abs(c.position.x)) / std::abs(along.x));
            if (std::abs(along.z) > 1e-3f) limit = std::min(limit, zoneHalf / std::abs(along.z));
            if (std::abs(along.y) > 1e-3f)
                limit = std::min(limit, (std::min(c.position.y, ceiling - c.position.y) - 0.3f) /
                                            std::abs(along.y));
            return std::max(0.0f, limit);
        };
        switch (c.motion) {
            case DrawnCamera::Motion::Pan:
                c.rotation = oscillationWithSpeed(d, angular, 45.0f);
                break;
            case DrawnCamera::Motion::Tilt:
                c.rotation = oscillationWithSpeed(d, angular, 20.0f);
                break;
            case DrawnCamera::Motion::Dolly:
                c.translation = oscillationWithSpeed(d, linear, roomToMove(forward));
                break;
            case DrawnCamera::Motion::Truck:
                c.translation =
                    oscillationWithSpeed(d, linear, stage.disc ? 2.5f : roomToMove(right));
                break;
            case DrawnCamera::Motion::Orbit:
                c.orbitDegreesPerFrame = angular * (d.chance(0.5f) ? 1.0f : -1.0f);
                break;
            case DrawnCamera::Motion::Handheld:
                // A hand's shake: small, with a second, faster tremor (DrawnCamera::at).
                c.rotation = oscillationWithSpeed(d, 0.5f * angular, 1.5f);
                c.translation =
                    oscillationWithSpeed(d, 0.2f * linear, std::min(0.05f, roomToMove(right)));
                c.rotation.period = d.integer(12, 40);
                c.translation.period = d.integer(12, 40);
                break;
            case DrawnCamera::Motion::PanAndDolly:
                c.rotation = oscillationWithSpeed(d, angular, 45.0f);
                c.translation = oscillationWithSpeed(d, linear, roomToMove(forward));
                break;
            case DrawnCamera::Motion::Static:
                break;
        }
    }

    // Every light switches only if something else keeps lighting the scene: the first light
    // stays on when nothing else does.
    void keepOneSteadyLight() {
        if (r.sun.enabled() || (r.sky.enabled() && !r.night)) return;
        DrawnObject* first = nullptr;
        for (DrawnObject& o : r.objects) {
            if (o.lightKind.empty()) continue;
            if (!o.lightSwitch.switches) return;
            if (!first) first = &o;
        }
        if (first) first->lightSwitch = {};
    }

    // A still scene: no camera, object, light or sun motion and no switching.
    void stopEverything() {
        for (DrawnObject& o : r.objects) {
            o.motion = {};
            o.lightSwitch = {};
        }
        r.sunAzimuthMotion = {};
        r.sun.direction = sunDirection(0);
        r.camera.motion = DrawnCamera::Motion::Static;
        r.camera.speed = "none";
        r.camera.rotation = r.camera.translation = {};
        r.camera.orbitDegreesPerFrame = 0.0f;
    }

    RandomSceneRecipe run() {
        r.still = d.chance(0.1f);
        const int layout = d.pick({0.4f, 0.2f, 0.4f});
        r.layout = RandomSceneRecipe::Layout(layout);
        r.targetLuminance = d.logUniform(0.1f, 0.5f);
        switch (r.layout) {
            case RandomSceneRecipe::Layout::ClosedRoom: {
                drawRoom(false);
                r.indirectOnly = d.chance(0.35f);
                if (r.indirectOnly) {
                    for (int i = d.integer(1, 3); i > 0; --i) addHiddenLight();
                } else {
                    const int lights =
                        1 + d.pick({0.25f, 0.2f, 0.15f, 0.12f, 0.1f, 0.08f, 0.05f, 0.05f});
                    for (int i = 0; i < lights; ++i) {
                        switch (d.pick({0.4f, 0.3f, 0.15f, 0.15f})) {
                            case 0:
                                addAreaLight();
                                break;
                            case 1:
                                addSmallLight();
                                break;
                            case 2:
                                addEmissiveObject();
                                break;
                            default:
                                addWallPanel();
                                break;
                        }
                    }
                }
                break;
            }
            case RandomSceneRecipe::Layout::WindowRoom: {
                drawRoom(true);
                const bool sunny = d.chance(0.85f);
                drawSky(!sunny);
                if (sunny) {
                    if (r.window == "ceiling") {
                        drawSun(50.0f, 85.0f, 0.0f, 180.0f);
                    } else {
                        // Towards the window's outside: -x (left, azimuth -90), +x, +z.
                        float azimuth =
                            r.window == "left" ? -90.0f : (r.window == "right" ? 90.0f : 0.0f);
                        drawSun(15.0f, 50.0f, azimuth, 50.0f);
                    }
                }
                if (d.chance(0.35f))
                    for (int i = d.integer(1, 2); i > 0; --i)
                        d.chance(0.5f) ? addSmallLight() : addAreaLight();
                break;
            }
            case RandomSceneRecipe::Layout::Open: {
                drawOpen();
                r.night = d.chance(0.2f);
                const bool sunny = !r.night && d.chance(0.75f);
                drawSky(!sunny);
                if (sunny) drawSun(10.0f, 75.0f, 0.0f, 180.0f);
                const int local =
                    r.night ? d.integer(1, 5) : (d.chance(0.3f) ? d.integer(1, 2) : 0);
                for (int i = 0; i < local; ++i) {
                    switch (d.pick({0.4f, 0.3f, 0.3f})) {
                        case 0:
                            addSmallLight();
                            break;
                        case 1:
                            addAreaLight();
                            break;
                        default:
                            addEmissiveObject();
                            break;
                    }
                }
                break;
            }
        }
        addObjects(d.integer(2, 12));
        // Lights switch 25 % of the time (the built-in switching-light's failure).
        for (DrawnObject& o : r.objects)
            if (!o.lightKind.empty()) o.lightSwitch = drawSwitch(d, 0.25f);
        keepOneSteadyLight();
        drawCamera();
        if (r.still) stopEverything();
        return std::move(r);
    }
};

// ---- description ----

// "emissive object" -> "emissive-object": tags are single words.
std::string slug(std::string s) {
    std::replace(s.begin(), s.end(), ' ', '-');
    return s;
}

bool isStageObject(const std::string& kind) {
    return kind == "box" || kind == "sphere" || kind == "bar" || kind == "grid" ||
           kind == "details" || kind == "slab";
}

std::string json(float v) {
    return std::isfinite(v) ? fmt::format("{:.4g}", v) : "null";
}
std::string json(Vec3 v) {
    return fmt::format("[{}, {}, {}]", json(v.x), json(v.y), json(v.z));
}
std::string json(const std::string& s) {
    return "\"" + s + "\"";  // generator strings: no quotes or control characters
}
std::string json(bool b) {
    return b ? "true" : "false";
}

const char* motionName(DrawnMotion::Kind kind) {
    switch (kind) {
        case DrawnMotion::Kind::None:
            return "none";
        case DrawnMotion::Kind::Slide:
            return "slide";
        case DrawnMotion::Kind::Spin:
            return "spin";
        case DrawnMotion::Kind::SlideAndSpin:
            return "slide-and-spin";
        case DrawnMotion::Kind::Bounce:
            return "bounce";
        case DrawnMotion::Kind::Orbit:
            return "orbit";
    }
    return "none";
}

const char* cameraMotionName(DrawnCamera::Motion motion) {
    static const char* kNames[] = {"static", "pan",   "tilt",     "dolly",
                                   "truck",  "orbit", "handheld", "pan-and-dolly"};
    return kNames[int(motion)];
}

const char* layoutName(RandomSceneRecipe::Layout layout) {
    switch (layout) {
        case RandomSceneRecipe::Layout::ClosedRoom:
            return "closed-room";
        case RandomSceneRecipe::Layout::WindowRoom:
            return "window-room";
        case RandomSceneRecipe::Layout::Open:
            return "open";
    }
    return "open";
}

// The parameters a motion uses (a spin has no amplitude, a bounce no axis).
std::string motionJson(const DrawnMotion& m) {
    if (!m.moves()) return "null";
    std::string out = fmt::format("{{\"kind\": {}", json(std::string(motionName(m.kind))));
    if (m.kind == DrawnMotion::Kind::Slide || m.kind == DrawnMotion::Kind::SlideAndSpin)
        out += fmt::format(", \"axis\": {}", json(m.axis));
    if (m.kind != DrawnMotion::Kind::Spin)
        out += fmt::format(
            ", \"amplitude_m\": {}, \"period_frames\": {}, "
            "\"peak_speed_m_per_frame\": {}",
            json(m.offset.amplitude), m.offset.period, json(m.offset.peakSpeed()));
    if (m.kind == DrawnMotion::Kind::Spin || m.kind == DrawnMotion::Kind::SlideAndSpin)
        out += fmt::format(", \"spin_degrees_per_frame\": {}", json(m.spinDegreesPerFrame));
    return out + "}";
}

std::string materialJson(const DrawnObject& o) {
    const Material& m = o.object.material;
    const Texture& t = m.albedo;
    const float la = luminance(t.a), lb = luminance(t.b);
    const float contrast = t.kind == Texture::Kind::Constant
                               ? 0.0f
                               : std::abs(la - lb) / std::max(1e-6f, std::max(la, lb));
    std::string out = fmt::format(
        "{{\"kind\": {}, \"texture\": {}, \"frequency_per_m\": {}, \"contrast\": {}, "
        "\"colour\": {}, \"second_colour\": {}",
        json(o.materialKind), json(std::string(textureKindName(t.kind))), json(t.frequency),
        json(contrast), json(t.a), json(t.b));
    if (m.specular > 0.0f)
        out += fmt::format(", \"specular\": {}, \"roughness\": {}, \"specular_tint\": {}",
                           json(m.specular), json(m.roughness), json(m.specularTint));
    if (m.emissive()) out += fmt::format(", \"emission\": {}", json(m.emission));
    return out + "}";
}

}  // namespace

// ---- RandomSceneRecipe and its parts ----

float Oscillation::at(int frame) const {
    if (amplitude == 0.0f) return 0.0f;
    const int p = std::max(2, period);
    return amplitude * std::sin(2.0f * kPi * float(positiveModulo(frame, p)) / float(p) + phase);
}

float Oscillation::peakSpeed() const {
    return amplitude * 2.0f * kPi / float(std::max(2, period));
}

bool DrawnSwitch::on(int frame) const {
    return !switches || positiveModulo(frame + offset, std::max(2, period)) < onFrames;
}

Matrix4 DrawnObject::placement(int frame) const {
    Vec3 p = position;
    float yaw = yawDegrees;
    switch (motion.kind) {
        case DrawnMotion::Kind::None:
            break;
        case DrawnMotion::Kind::Slide:
            p += motion.axis * motion.offset.at(frame);
            break;
        case DrawnMotion::Kind::Spin:
            yaw += motion.spinDegreesPerFrame * float(frame);
            break;
        case DrawnMotion::Kind::SlideAndSpin:
            p += motion.axis * motion.offset.at(frame);
            yaw += motion.spinDegreesPerFrame * float(frame);
            break;
        case DrawnMotion::Kind::Bounce:
            p.y += std::abs(motion.offset.at(frame));
            break;
        case DrawnMotion::Kind::Orbit: {
            const int period = std::max(2, motion.offset.period);
            const float a = 2.0f * kPi * float(positiveModulo(frame, period)) / float(period) +
                            motion.offset.phase;
            p += Vec3(std::cos(a), 0.0f, std::sin(a)) * motion.offset.amplitude;
            break;
        }
    }
    return translation(p) * rotationY(radians(yaw)) * orientation;
}

Camera DrawnCamera::at(int frame) const {
    const Vec3 forward = normalize(target - position);
    float yaw = std::atan2(forward.x, forward.z);
    float pitch = std::asin(std::clamp(forward.y, -1.0f, 1.0f));
    const Vec3 right = normalize(cross({0.0f, 1.0f, 0.0f}, forward));
    Vec3 p = position;
    Camera c;
    c.verticalFovDegrees = verticalFovDegrees;
    switch (motion) {
        case Motion::Static:
            break;
        case Motion::Pan:
            yaw += radians(rotation.at(frame));
            break;
        case Motion::Tilt:
            pitch += radians(rotation.at(frame));
            break;
        case Motion::Dolly:
            p += forward * translation.at(frame);
            break;
        case Motion::Truck:
            p += right * translation.at(frame);
            break;
        case Motion::Orbit: {
            // About the vertical through the target, looking at it.
            const Vec4 q = transformPoint(rotationY(radians(orbitDegreesPerFrame * float(frame))),
                                          position - target);
            c.position = target + Vec3(q.x, q.y, q.z);
            c.target = target;
            return c;
        }
        case Motion::Handheld: {
            // Two incommensurate tremors on the yaw, the pitch and the position.
            Oscillation fast = rotation;
            fast.period = std::max(2, rotation.period * 2 / 5);
            fast.amplitude = 0.5f * rotation.amplitude;
            yaw += radians(rotation.at(frame) + fast.at(frame + 3));
            pitch += radians(0.7f * rotation.at(frame + 7) - fast.at(frame));
            Oscillation drift = translation;
            drift.period = std::max(2, translation.period * 3 / 7);
            p += right * translation.at(frame) + Vec3(0.0f, 1.0f, 0.0f) * drift.at(frame + 5);
            break;
        }
        case Motion::PanAndDolly:
            yaw += radians(rotation.at(frame));
            p += forward * translation.at(frame);
            break;
    }
    pitch = std::clamp(pitch, radians(-80.0f), radians(80.0f));
    c.position = p;
    c.target =
        p + Vec3(std::sin(yaw) * std::cos(pitch), std::sin(pitch), std::cos(yaw) * std::cos(pitch));
    return c;
}

Scene RandomSceneRecipe::build(int frame) const {
    Scene s;
    for (const DrawnObject& d : objects) {
        Object o = d.object;
        o.objectToWorld = d.placement(frame);
        o.material.emission =
            d.object.material.emission * (d.lightSwitch.on(frame) ? exposure : 0.0f);
        s.objects.push_back(std::move(o));
    }
    s.camera = camera.at(frame);
    s.sky = {sky.zenith * exposure, sky.horizon * exposure, sky.ground * exposure};
    s.skyPortals = skyPortals;
    if (sun.enabled()) {
        s.sun = sun;
        s.sun.irradiance = sun.irradiance * exposure;
        const float e = radians(sunElevationDegrees);
        const float a = radians(sunAzimuthDegrees + sunAzimuthMotion.at(frame));
        s.sun.direction = {std::cos(e) * std::sin(a), std::sin(e), std::cos(e) * std::cos(a)};
    }
    return s;
}

std::vector<std::string> RandomSceneRecipe::tags() const {
    std::vector<std::string> t;
    auto tag = [&t](std::string s) {
        if (std::find(t.begin(), t.end(), s) == t.end()) t.push_back(std::move(s));
    };
    tag(std::string("layout:") + layoutName(layout));
    if (indirectOnly || layout == Layout::WindowRoom) tag("lighting:indirect");
    if (night) tag("lighting:night");
    int lights = 0;
    bool objectsMove = false, objectsSpin = false, lightsMove = false, switching = false;
    for (const DrawnObject& o : objects) {
        const bool spins = o.motion.kind == DrawnMotion::Kind::Spin ||
                           o.motion.kind == DrawnMotion::Kind::SlideAndSpin;
        const bool translates = o.motion.moves() && o.motion.kind != DrawnMotion::Kind::Spin;
        if (!o.lightKind.empty()) {
            ++lights;
            tag("light:" + slug(o.lightKind));
            const Vec3 e = o.object.material.emission;
            const float spread = maxComponent(e) - std::min(e.x, std::min(e.y, e.z));
            if (spread > 0.35f * maxComponent(e)) tag("light:coloured");
            lightsMove = lightsMove || o.motion.moves();
            switching = switching || o.lightSwitch.switches;
        } else if (isStageObject(o.kind)) {
            tag("geometry:" + o.kind);
            objectsMove = objectsMove || translates;
            objectsSpin = objectsSpin || spins;
        }
        if (o.lightKind.empty()) {
            tag("material:" + o.materialKind);
            const Material& m = o.object.material;
            if (o.materialKind == "diffuse" || o.materialKind == "glossy")
                tag(std::string("texture:") + textureKindName(m.albedo.kind));
            if (m.lobe == Material::Lobe::Ggx && m.specular > 0.0f)
                tag(m.roughness < 0.1f
                        ? "roughness:low"
                        : (m.roughness < 0.4f ? "roughness:medium" : "roughness:high"));
        } else {
            tag("material:emitter");
        }
    }
    if (sun.enabled()) {
        ++lights;
        tag("light:sun");
    }
    if (sky.enabled()) tag(night ? "light:night-sky" : "light:sky");
    tag(lights >= 3 ? "lights:many" : (lights == 1 ? "lights:one" : "lights:two"));
    tag(std::string("camera:") + cameraMotionName(camera.motion));
    if (camera.motion != DrawnCamera::Motion::Static) tag("camera-speed:" + camera.speed);
    if (objectsMove) tag("motion:objects");
    if (objectsSpin) tag("motion:rotation");
    if (lightsMove) tag("motion:lights");
    if (switching) tag("motion:switching");
    if (sunAzimuthMotion.amplitude > 0.0f && sun.enabled()) tag("motion:sun");
    if (camera.motion == DrawnCamera::Motion::Static && !objectsMove && !objectsSpin &&
        !lightsMove && !switching && !(sunAzimuthMotion.amplitude > 0.0f && sun.enabled()))
        tag("motion:none");
    return t;
}

std::string RandomSceneRecipe::describeJson() const {
    std::string tagList, lights, others;
    for (const std::string& t : tags()) tagList += (tagList.empty() ? "" : ", ") + json(t);
    for (std::size_t k = 0; k < objects.size(); ++k) {
        const DrawnObject& o = objects[k];
        if (!o.lightKind.empty()) {
            const Vec3 e = o.object.material.emission;
            lights += fmt::format(
                "{}\n      {{\"id\": {}, \"name\": {}, \"kind\": {}, \"radiance\": {}, "
                "\"sampled\": {}, \"position\": {}, \"motion\": {}, \"switch\": {}}}",
                lights.empty() ? "" : ",", k, json(o.object.name), json(o.lightKind),
                json(e * exposure), json(o.object.light), json(o.position), motionJson(o.motion),
                o.lightSwitch.switches
                    ? fmt::format("{{\"period_frames\": {}, \"on_frames\": {}, \"offset\": {}}}",
                                  o.lightSwitch.period, o.lightSwitch.onFrames,
                                  o.lightSwitch.offset)
                    : "null");
        } else {
            others += fmt::format(
                "{}\n      {{\"id\": {}, \"name\": {}, \"kind\": {}, \"primitives\": {}, "
                "\"position\": {}, \"material\": {}, \"motion\": {}}}",
                others.empty() ? "" : ",", k, json(o.object.name), json(o.kind),
                o.object.primitives.size(), json(o.position), materialJson(o),
                motionJson(o.motion));
        }
    }
    const std::string skyJson =
        sky.enabled() ? fmt::format("{{\"zenith\": {}, \"horizon\": {}, \"ground\": {}}}",
                                    json(sky.zenith * exposure), json(sky.horizon * exposure),
                                    json(sky.ground * exposure))
                      : "null";
    const std::string sunJson =
        sun.enabled() ? fmt::format(
                            "{{\"irradiance\": {}, \"elevation_degrees\": {}, "
                            "\"azimuth_degrees\": {}, \"angular_radius_degrees\": {}, "
                            "\"azimuth_swing_degrees\": {}, \"swing_period_frames\": {}}}",
                            json(sun.irradiance * exposure), json(sunElevationDegrees),
                            json(sunAzimuthDegrees), json(sun.angularRadiusDegrees),
                            json(sunAzimuthMotion.amplitude), sunAzimuthMotion.period)
                      : "null";
    const DrawnCamera& c = camera;
    const std::string cameraJson = fmt::format(
        "{{\"motion\": {}, \"speed\": {}, \"position\": {}, \"target\": {}, "
        "\"vertical_fov_degrees\": {}, \"rotation_amplitude_degrees\": {}, "
        "\"rotation_period_frames\": {}, \"translation_amplitude_m\": {}, "
        "\"translation_period_frames\": {}, \"orbit_degrees_per_frame\": {}}}",
        json(std::string(cameraMotionName(c.motion))), json(c.speed), json(c.position),
        json(c.target), json(c.verticalFovDegrees), json(c.rotation.amplitude), c.rotation.period,
        json(c.translation.amplitude), c.translation.period, json(c.orbitDegreesPerFrame));
    return fmt::format(
        "{{\n    \"version\": {},\n    \"seed\": {},\n    \"tags\": [{}],\n"
        "    \"layout\": {},\n    \"room_size_m\": {},\n    \"window\": {},\n"
        "    \"indirect_only\": {},\n    \"night\": {},\n    \"still\": {},\n"
        "    \"target_luminance\": {},\n"
        "    \"exposure\": {},\n    \"sky\": {},\n    \"sun\": {},\n    \"camera\": {},\n"
        "    \"lights\": [{}\n    ],\n    \"objects\": [{}\n    ]\n  }}",
        json(std::string(kRandomSceneVersion)), seed, tagList,
        json(std::string(layoutName(layout))), layout == Layout::Open ? "null" : json(roomSize),
        window.empty() ? "null" : json(window), json(indirectOnly), json(night), json(still),
        json(targetLuminance), json(exposure), skyJson, sunJson, cameraJson, lights, others);
}

std::string RandomSceneRecipe::summary() const {
    int lights = sun.enabled() ? 1 : 0, things = 0;
    for (const DrawnObject& o : objects) {
        if (!o.lightKind.empty())
            ++lights;
        else if (isStageObject(o.kind))
            ++things;
    }
    std::string where;
    switch (layout) {
        case Layout::ClosedRoom:
            where = fmt::format("closed room {:.1f} x {:.1f} x {:.1f} m{}", roomSize.x, roomSize.y,
                                roomSize.z, indirectOnly ? " lit indirectly" : "");
            break;
        case Layout::WindowRoom:
            where = fmt::format("room {:.1f} x {:.1f} x {:.1f} m lit through a {} window",
                                roomSize.x, roomSize.y, roomSize.z, window);
            break;
        case Layout::Open:
            where = night ? "open scene at night"
                          : (sun.enabled() ? "open scene under sun and sky"
                                           : "open scene under an overcast sky");
            break;
    }
    return fmt::format(
        "generated scene (seed {}, {}): {}, {} light{}{}, {} objects, camera {}{}", seed,
        kRandomSceneVersion, where, lights, lights == 1 ? "" : "s",
        sky.enabled() ? " and the sky" : "", things, cameraMotionName(camera.motion),
        camera.motion == DrawnCamera::Motion::Static ? "" : " (" + camera.speed + ")");
}

std::string RandomSceneRecipe::motionSummary() const {
    std::vector<std::string> parts;
    if (camera.motion != DrawnCamera::Motion::Static)
        parts.push_back(
            fmt::format("the camera: {} ({})", cameraMotionName(camera.motion), camera.speed));
    for (const DrawnObject& o : objects) {
        if (o.motion.moves())
            parts.push_back(fmt::format("{}: {}", o.object.name, motionName(o.motion.kind)));
        if (o.lightSwitch.switches)
            parts.push_back(fmt::format("{}: on {} of every {} frames", o.object.name,
                                        o.lightSwitch.onFrames, o.lightSwitch.period));
    }
    if (sun.enabled() && sunAzimuthMotion.amplitude > 0.0f)
        parts.push_back(
            fmt::format("the sun: swings +-{:.0f} degrees of azimuth", sunAzimuthMotion.amplitude));
    if (parts.empty()) return "nothing";
    std::string out;
    for (const std::string& p : parts) out += (out.empty() ? "" : "; ") + p;
    return out;
}

RandomSceneRecipe drawRandomScene(std::uint32_t seed) {
    return Generator(seed).run();
}

void normaliseExposure(RandomSceneRecipe& recipe) {
    recipe.exposure = 1.0f;
    TraceSettings t;
    t.width = 32;
    t.height = 24;
    t.samplesPerPixel = 8;
    t.maxDepth = 5;
    t.seed = recipe.seed;
    t.stream = 7;  // its own random numbers, none of a render's
    const Image preview = renderRadiance(recipe.build(0), t);
    // The mean luminance of what the camera sees of the scene (the sky's brightness is drawn
    // apart), without the brightest 2 %: a light or the sun in view, or a preview's firefly,
    // would set the exposure alone.
    const Frame gbuffer = renderGBuffer(recipe.build(0), t.width, t.height);
    std::vector<float> values, all;
    for (std::size_t p = 0; p < preview.pixelCount(); ++p) {
        const float v = luminance(
            {preview.pixels[p * 3], preview.pixels[p * 3 + 1], preview.pixels[p * 3 + 2]});
        all.push_back(v);
        if (gbuffer.objectId[p] >= 0) values.push_back(v);
    }
    if (values.size() < all.size() / 10) values = all;  // mostly sky: the sky then
    std::sort(values.begin(), values.end());
    const std::size_t kept = values.size() - values.size() / 50;
    double sum = 0.0;
    for (std::size_t i = 0; i < kept; ++i) sum += values[i];
    const double mean = sum / double(kept);
    if (mean > 0.0 && std::isfinite(mean)) recipe.exposure = float(recipe.targetLuminance / mean);
}

SceneDefinition randomSceneDefinition(std::uint32_t seed) {
    RandomSceneRecipe recipe = drawRandomScene(seed);
    normaliseExposure(recipe);
    SceneDefinition d;
    d.name = kRandomSceneName;
    d.description = recipe.summary();
    d.motion = recipe.motionSummary();
    d.generator = recipe.describeJson();
    d.build = [recipe](int frame) { return recipe.build(frame); };
    return d;
}

}  // namespace rtd::render
