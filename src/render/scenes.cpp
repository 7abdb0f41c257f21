#include "render/scenes.h"

#include <fmt/format.h>

#include <cmath>

#include "rtdenoise/error.h"

namespace rtd::render {
namespace {

constexpr float kPi = 3.14159265358979f;

// Motion is periodic in frames: phase(frame, period) runs over [0, 2 pi).
float phase(int frame, int period) {
    return 2.0f * kPi * float(frame % period) / float(period);
}
float degrees(float d) {
    return d * kPi / 180.0f;
}

// ---- materials ----

Material diffuse(Vec3 albedo) {
    Material m;
    m.albedo = Texture::constant(albedo);
    return m;
}
Material textured(Texture t) {
    Material m;
    m.albedo = t;
    return m;
}
Material glossy(Texture t, float specular, float exponent) {
    Material m;
    m.albedo = t;
    m.specular = specular;
    m.exponent = exponent;
    return m;
}
// A light panel: it reflects too (albedo 0.7), so it is a plain grey panel when switched off.
Material emitter(Vec3 emission) {
    Material m = diffuse(Vec3(0.7f));
    m.emission = emission;
    return m;
}

const Vec3 kWhite{0.75f, 0.75f, 0.75f};
const Vec3 kRed{0.63f, 0.065f, 0.05f};
const Vec3 kGreen{0.14f, 0.45f, 0.091f};

// ---- objects ----

Object quadObject(std::string name, Vec3 corner, Vec3 u, Vec3 v, Material m) {
    return {std::move(name), {Primitive::quad(corner, u, v)}, m, Matrix4::identity(), false};
}
// Static geometry: local = world, identity matrix.
Object boxObject(std::string name, Vec3 lo, Vec3 hi, Material m) {
    return {std::move(name), {Primitive::box(lo, hi)}, m, Matrix4::identity(), false};
}
Object sphereObject(std::string name, Vec3 centre, float radius, Material m) {
    return {std::move(name), {Primitive::sphere(centre, radius)}, m, Matrix4::identity(), false};
}
// Geometry around the local origin placed by a matrix (moving or rotated objects).
Object placed(Object o, const Matrix4& objectToWorld) {
    o.objectToWorld = objectToWorld;
    return o;
}
// A one-sided ceiling light of size sx x sz centred at (x, y, z), facing down.
Object ceilingLight(std::string name, Vec3 centre, float sx, float sz, Vec3 emission) {
    Object o = quadObject(std::move(name), centre - Vec3(0.5f * sx, 0.0f, 0.5f * sz),
                          {sx, 0.0f, 0.0f}, {0.0f, 0.0f, sz}, emitter(emission));
    o.light = true;
    return o;
}

struct RoomMaterials {
    Material floor, ceiling, back, left, right, front;
};

// Walls of the box lo..hi as quads whose front faces look inside; the front wall (z = lo.z) is
// left out when `closed` is false.
void addRoom(Scene& scene, Vec3 lo, Vec3 hi, const RoomMaterials& m, bool closed) {
    Vec3 d = hi - lo;
    auto& o = scene.objects;
    o.push_back(quadObject("floor", lo, {0, 0, d.z}, {d.x, 0, 0}, m.floor));
    o.push_back(quadObject("ceiling", {lo.x, hi.y, lo.z}, {d.x, 0, 0}, {0, 0, d.z}, m.ceiling));
    o.push_back(quadObject("back wall", {lo.x, lo.y, hi.z}, {0, d.y, 0}, {d.x, 0, 0}, m.back));
    o.push_back(quadObject("left wall", lo, {0, d.y, 0}, {0, 0, d.z}, m.left));
    o.push_back(quadObject("right wall", {hi.x, lo.y, lo.z}, {0, 0, d.z}, {0, d.y, 0}, m.right));
    if (closed) o.push_back(quadObject("front wall", lo, {d.x, 0, 0}, {0, d.y, 0}, m.front));
}

// (a) Objects moving in a Cornell box seen through its open front, static camera: disocclusion
// behind each object, ghosting of the moving textures, a glossy sphere.
Scene movingObjects(int frame) {
    Scene s;
    RoomMaterials m;
    m.floor = textured(Texture::checker({0.8f, 0.8f, 0.8f}, {0.15f, 0.15f, 0.15f}, 6.0f));
    m.ceiling = diffuse(kWhite);
    m.back = textured(Texture::stripes(kWhite, {0.35f, 0.35f, 0.5f}, 8.0f));
    m.left = diffuse(kRed);
    m.right = diffuse(kGreen);
    addRoom(s, {-1.0f, 0.0f, -1.0f}, {1.0f, 2.0f, 1.0f}, m, false);
    s.objects.push_back(ceilingLight("light", {0.0f, 1.98f, 0.0f}, 0.6f, 0.6f, {16, 13, 9}));

    float x = 0.55f * std::sin(phase(frame, 24));
    s.objects.push_back(placed(
        sphereObject("sphere", {}, 0.3f, glossy(Texture::constant({0.9f, 0.9f, 0.9f}), 0.3f, 80)),
        translation({x, 0.3f, -0.35f})));
    s.objects.push_back(placed(
        boxObject("spinning box", {-0.25f, 0.0f, -0.25f}, {0.25f, 1.1f, 0.25f},
                  textured(Texture::checker({0.85f, 0.7f, 0.2f}, {0.1f, 0.1f, 0.3f}, 12.0f))),
        translation({-0.45f, 0.0f, 0.4f}) * rotationY(degrees(20.0f + 5.0f * float(frame)))));
    float bounce = std::abs(std::sin(0.5f * phase(frame, 24)));
    s.objects.push_back(placed(
        boxObject("bouncing cube", Vec3(-0.15f), Vec3(0.15f),
                  textured(Texture::stripes({0.9f, 0.9f, 0.9f}, {0.1f, 0.25f, 0.7f}, 20.0f))),
        translation({0.5f, 0.15f + 0.6f * bounce, 0.4f}) * rotationY(degrees(30.0f))));

    s.camera.position = {0.0f, 1.0f, -3.5f};
    s.camera.target = {0.0f, 1.0f, 0.0f};
    s.camera.verticalFovDegrees = 35.0f;
    return s;
}

// (b) A closed hall with a fine checker floor, pillars and a glossy sphere; the camera pans
// (yaw) and dollies (forward and back): reprojection under camera motion, texture blur.
Scene cameraPan(int frame) {
    Scene s;
    RoomMaterials m;
    m.floor = textured(Texture::checker({0.85f, 0.85f, 0.8f}, {0.1f, 0.1f, 0.12f}, 4.0f));
    m.ceiling = diffuse({0.7f, 0.7f, 0.7f});
    Material wall = textured(Texture::stripes({0.75f, 0.6f, 0.45f}, {0.45f, 0.5f, 0.6f}, 3.0f));
    m.back = m.left = m.right = m.front = wall;
    addRoom(s, {-8.0f, 0.0f, -8.0f}, {8.0f, 4.0f, 8.0f}, m, true);
    for (int i = 0; i < 4; ++i) {
        float x = i % 2 ? 3.5f : -3.5f, z = i / 2 ? 3.5f : -3.5f;
        s.objects.push_back(
            ceilingLight(fmt::format("light {}", i + 1), {x, 3.98f, z}, 1.6f, 1.6f, Vec3(10.0f)));
    }
    Material pillar = textured(Texture::stripes(kWhite, {0.2f, 0.2f, 0.2f}, 10.0f));
    for (int i = 0; i < 4; ++i) {
        float x = i % 2 ? 2.0f : -2.0f, z = i / 2 ? 4.0f : 0.0f;
        s.objects.push_back(boxObject(fmt::format("pillar {}", i + 1), {x - 0.25f, 0.0f, z - 0.25f},
                                      {x + 0.25f, 4.0f, z + 0.25f}, pillar));
    }
    s.objects.push_back(sphereObject("sphere", {0.0f, 0.7f, 2.0f}, 0.7f,
                                     glossy(Texture::constant({0.6f, 0.1f, 0.1f}), 0.4f, 120)));
    s.objects.push_back(placed(
        boxObject("crate", Vec3(-0.5f), Vec3(0.5f),
                  textured(Texture::checker({0.8f, 0.55f, 0.3f}, {0.3f, 0.15f, 0.05f}, 8.0f))),
        translation({-1.0f, 0.5f, -1.0f}) * rotationY(degrees(35.0f))));

    float yaw = 0.45f * std::sin(phase(frame, 48));
    float pitch = -0.3f;
    Vec3 position{1.0f * std::sin(phase(frame, 64)), 1.6f,
                  -5.0f + 2.0f * std::sin(phase(frame, 64))};
    s.camera.position = position;
    s.camera.target = position + Vec3(std::sin(yaw) * std::cos(pitch), std::sin(pitch),
                                      std::cos(yaw) * std::cos(pitch));
    s.camera.verticalFovDegrees = 50.0f;
    return s;
}

// (c) A grid of 2-pixel bars sliding slowly in front of a wall, thin static poles and a
// diagonal wire, lit by a small sphere light that casts their sharp shadows: over-blur of thin
// geometry and of thin shadows.
Scene thinGeometry(int frame) {
    Scene s;
    RoomMaterials m;
    // Darker walls than the other rooms: less interreflection, so the direct light and the
    // bars' shadows dominate and the reference converges sooner.
    m.floor = textured(Texture::checker({0.5f, 0.5f, 0.5f}, {0.2f, 0.2f, 0.2f}, 2.0f));
    m.ceiling = m.front = diffuse(Vec3(0.4f));
    m.back = diffuse({0.5f, 0.48f, 0.45f});
    m.left = diffuse({0.3f, 0.35f, 0.5f});
    m.right = diffuse({0.5f, 0.35f, 0.3f});
    addRoom(s, {-2.5f, 0.0f, -3.0f}, {2.5f, 3.0f, 2.2f}, m, true);

    // Small, so that the bars' shadows on the wall have an umbra; a metre from the walls, so
    // that the hot spot it makes on them (a source of indirect noise) stays mild.
    Object spot = sphereObject("small light", {}, 0.04f, emitter(Vec3(1600.0f)));
    spot.light = true;
    s.objects.push_back(placed(spot, translation({-1.6f, 2.0f, 0.2f})));
    s.objects.push_back(ceilingLight("fill light", {0.5f, 2.98f, 0.0f}, 2.5f, 2.5f, Vec3(1.5f)));

    constexpr float kBar = 0.025f;
    Object grid{"grid", {}, glossy(Texture::constant({0.85f, 0.5f, 0.2f}), 0.2f, 40), {}, false};
    for (int k = 0; k <= 12; ++k) {
        float x = -1.2f + 0.2f * float(k);
        grid.primitives.push_back(Primitive::box({x - 0.5f * kBar, -1.0f, -0.5f * kBar},
                                                 {x + 0.5f * kBar, 1.0f, 0.5f * kBar}));
    }
    for (int k = 0; k <= 10; ++k) {
        float y = -1.0f + 0.2f * float(k);
        grid.primitives.push_back(Primitive::box({-1.2f, y - 0.5f * kBar, -0.5f * kBar},
                                                 {1.2f, y + 0.5f * kBar, 0.5f * kBar}));
    }
    s.objects.push_back(
        placed(grid, translation({0.15f * std::sin(phase(frame, 40)), 1.5f, 1.9f})));

    constexpr float kPole = 0.012f;  // about 1 pixel at 320x240
    const Vec3 poles[] = {{-1.7f, 0.0f, 0.6f}, {1.75f, 0.0f, 1.0f}, {-0.35f, 0.0f, 0.2f}};
    for (int i = 0; i < 3; ++i)
        s.objects.push_back(
            boxObject(fmt::format("pole {}", i + 1), poles[i] - Vec3(kPole, 0.0f, kPole),
                      poles[i] + Vec3(kPole, 3.0f, kPole), diffuse({0.9f, 0.9f, 0.9f})));
    s.objects.push_back(placed(boxObject("wire", {-2.0f, -0.008f, -0.008f}, {2.0f, 0.008f, 0.008f},
                                         diffuse({0.1f, 0.1f, 0.1f})),
                               translation({0.0f, 1.2f, 0.4f}) * rotationZ(degrees(25.0f))));

    s.camera.position = {0.0f, 1.5f, -2.0f};
    s.camera.target = {0.0f, 1.4f, 1.9f};
    s.camera.verticalFovDegrees = 45.0f;
    return s;
}

// (d) A static room and camera; the ceiling light switches off for 6 frames every 12 and a
// small sphere light circles under the ceiling: lighting changes that reprojection cannot see.
Scene switchingLight(int frame) {
    Scene s;
    RoomMaterials m;
    m.floor = textured(Texture::checker({0.75f, 0.75f, 0.75f}, {0.25f, 0.2f, 0.15f}, 4.0f));
    m.ceiling = m.front = diffuse(kWhite);
    m.back = textured(Texture::stripes(kWhite, {0.5f, 0.55f, 0.45f}, 6.0f));
    m.left = diffuse(kRed);
    m.right = diffuse(kGreen);
    addRoom(s, {-2.0f, 0.0f, -3.5f}, {2.0f, 2.5f, 2.0f}, m, true);

    bool on = (frame / 6) % 2 == 0;
    s.objects.push_back(ceilingLight("switching light", {0.0f, 2.48f, 0.0f}, 1.0f, 1.0f,
                                     on ? Vec3{14.0f, 13.0f, 11.0f} : Vec3(0.0f)));
    Object orbiting = sphereObject("orbiting light", {}, 0.1f, emitter({90.0f, 60.0f, 30.0f}));
    orbiting.light = true;
    float a = phase(frame, 32);
    s.objects.push_back(
        placed(orbiting, translation({1.2f * std::cos(a), 1.9f, 0.3f + 1.2f * std::sin(a)})));

    s.objects.push_back(sphereObject("glossy sphere", {-0.8f, 0.45f, 0.5f}, 0.45f,
                                     glossy(Texture::constant({0.2f, 0.3f, 0.8f}), 0.5f, 200)));
    s.objects.push_back(
        placed(boxObject("tall box", {-0.3f, 0.0f, -0.3f}, {0.3f, 1.2f, 0.3f},
                         textured(Texture::checker(kWhite, {0.3f, 0.3f, 0.3f}, 10.0f))),
               translation({0.8f, 0.0f, 0.8f}) * rotationY(degrees(25.0f))));
    s.objects.push_back(boxObject("low box", {-0.2f, 0.0f, -0.9f}, {0.4f, 0.35f, -0.3f},
                                  diffuse({0.8f, 0.75f, 0.6f})));

    s.camera.position = {0.0f, 1.3f, -3.2f};
    s.camera.target = {0.0f, 0.8f, 0.5f};
    s.camera.verticalFovDegrees = 50.0f;
    return s;
}

// (e) A mirror-like sphere and a glossy metal one on a glossy floor, in a room with striped and
// checkered walls, under a camera that trucks sideways and orbits: reflections move across the
// surfaces that hold them (the surface's motion is not the reflection's), so a history that
// follows the surface smears them.
Scene reflections(int frame) {
    Scene s;
    RoomMaterials m;
    m.floor = glossy(Texture::checker({0.7f, 0.7f, 0.7f}, {0.15f, 0.15f, 0.15f}, 3.0f), 0.3f, 400);
    m.ceiling = m.front = diffuse(kWhite);
    m.back = textured(Texture::stripes(kWhite, {0.2f, 0.3f, 0.6f}, 5.0f));
    m.left = textured(Texture::checker(kRed, {0.9f, 0.85f, 0.7f}, 4.0f));
    m.right = textured(Texture::stripes(kGreen, {0.9f, 0.85f, 0.7f}, 6.0f));
    addRoom(s, {-2.5f, 0.0f, -4.0f}, {2.5f, 2.8f, 2.5f}, m, true);
    s.objects.push_back(ceilingLight("light", {0.0f, 2.78f, 0.3f}, 1.2f, 1.2f, {14, 13, 11}));
    s.objects.push_back(sphereObject("mirror sphere", {-0.75f, 0.6f, 0.8f}, 0.6f,
                                     glossy(Texture::constant({0.9f, 0.9f, 0.9f}), 0.95f, 5000)));
    s.objects.push_back(sphereObject("metal sphere", {0.9f, 0.45f, 0.2f}, 0.45f,
                                     glossy(Texture::constant({0.8f, 0.6f, 0.3f}), 0.8f, 300)));
    s.objects.push_back(boxObject("block", {0.2f, 0.0f, 1.4f}, {1.0f, 0.8f, 2.0f},
                                  textured(Texture::checker(kWhite, {0.2f, 0.2f, 0.25f}, 8.0f))));
    float a = phase(frame, 40);
    Vec3 position{1.2f * std::sin(a), 1.3f, -3.0f + 0.4f * std::cos(a)};
    s.camera.position = position;
    s.camera.target = {0.2f * std::sin(a), 0.6f, 0.8f};
    s.camera.verticalFovDegrees = 50.0f;
    return s;
}

// The white furnace of the tests (scenes.h).
Scene furnace(int) {
    Scene s;
    Material m = diffuse(Vec3(kFurnaceAlbedo));
    m.emission = Vec3(kFurnaceEmission);
    m.twoSidedEmission = true;
    s.objects.push_back(sphereObject("furnace", {}, 1.0f, m));
    s.camera.position = {};
    s.camera.target = {0.0f, 0.0f, 1.0f};
    s.camera.verticalFovDegrees = 60.0f;
    return s;
}

}  // namespace

const std::vector<SceneDefinition>& builtInScenes() {
    static const std::vector<SceneDefinition> scenes{
        {"moving-objects",
         "objects moving in an open Cornell box, static camera (disocclusion, ghosting)",
         "a glossy sphere slides left and right, a checkered box spins, a striped cube bounces",
         movingObjects},
        {"camera-pan",
         "camera pan and dolly over a fine checker floor in a closed hall (camera reprojection, "
         "texture blur)",
         "the camera yaws +-26 degrees (period 48 frames) and dollies 2 m back and forth (period "
         "64 frames)",
         cameraPan},
        {"thin-geometry",
         "a grid of 2-pixel bars, thin poles and a wire in front of a wall, sharp shadows "
         "(over-blur)",
         "the grid slides 15 cm left and right (period 40 frames)", thinGeometry},
        {"switching-light",
         "static room and camera, a ceiling light switching every 6 frames and an orbiting light "
         "(lagging lighting)",
         "the ceiling light is on for frames 0-5, off for 6-11, and so on; a small sphere light "
         "circles under the ceiling (period 32 frames)",
         switchingLight},
        {"reflections",
         "a mirror-like and a glossy metal sphere on a glossy floor under a moving camera "
         "(reflections smear: they move unlike the surfaces that hold them)",
         "the camera trucks 2.4 m sideways and orbits the spheres (period 40 frames)", reflections},
        {"furnace",
         "white furnace: camera inside a sphere of albedo 0.5 and emission 0.5 (radiance "
         "1 - 0.5^depth, the renderer's known-answer test)",
         "nothing", furnace},
    };
    return scenes;
}

Scene buildScene(const std::string& name, int frame) {
    for (const SceneDefinition& d : builtInScenes())
        if (d.name == name) return d.build(frame);
    std::string known;
    for (const SceneDefinition& d : builtInScenes()) known += (known.empty() ? "" : ", ") + d.name;
    throw Error(ErrorCode::InvalidArgument,
                fmt::format("unknown scene '{}' (scenes: {})", name, known));
}

}  // namespace rtd::render
