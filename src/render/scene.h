// Scene description of the test-scene renderer: analytic primitives in each object's local space,
// one local-to-world matrix per object (what matrix_i.mat records), materials, a pinhole camera.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "render/vec.h"
#include "rtdenoise/image.h"

namespace rtd::render {

// A diffuse albedo that varies over the surface, in local units of the primitive's (u, v).
struct Texture {
    enum class Kind { Constant, Checker, Stripes, Noise, Tiles };
    Kind kind = Kind::Constant;
    Vec3 a{0.5f};                 // constant colour; even cells or stripes; noise low; tiles
    Vec3 b{0.5f};                 // odd cells or stripes; noise high; grout between tiles
    float frequency = 1.0f;       // cells (stripes, noise lattice cells, tiles) per local unit
    int noiseOctaves = 4;         // [1, 8] Noise: octaves of value noise, each twice the frequency
    float groutWidth = 0.1f;      // [0, 0.5) Tiles: the grout's width, a fraction of a tile
    std::uint32_t noiseSeed = 0;  // Noise: which lattice (textures with other seeds differ)

    static Texture constant(Vec3 c) { return {Kind::Constant, c, c, 1.0f}; }
    static Texture checker(Vec3 a, Vec3 b, float frequency) {
        return {Kind::Checker, a, b, frequency};
    }
    static Texture stripes(Vec3 a, Vec3 b, float frequency) {
        return {Kind::Stripes, a, b, frequency};
    }
    static Texture noise(Vec3 a, Vec3 b, float frequency, int octaves, std::uint32_t seed) {
        Texture t{Kind::Noise, a, b, frequency};
        t.noiseOctaves = octaves;
        t.noiseSeed = seed;
        return t;
    }
    static Texture tiles(Vec3 tile, Vec3 grout, float frequency, float groutWidth) {
        Texture t{Kind::Tiles, tile, grout, frequency};
        t.groutWidth = groutWidth;
        return t;
    }
    Vec3 evaluate(float u, float v) const;
};

// Diffuse (textured) plus an optional glossy lobe, plus emission. The glossy lobe is either the
// built-in scenes' normalised modified Phong, BRDF (1 - specular) albedo / pi + specular (n + 2)
// / (2 pi) cos^n, or a GGX microfacet lobe (Smith height-correlated shadowing, no Fresnel term)
// of weight specular and colour specularTint: a metal is specular 1 with its colour as the tint.
// Both conserve energy (GGX loses what its single scattering cannot reflect at high roughness).
struct Material {
    enum class Lobe { Phong, Ggx };
    Texture albedo;
    float specular = 0.0f;          // [0, 1] weight of the glossy lobe
    float exponent = 64.0f;         // [0, inf) Phong: exponent of the lobe
    Lobe lobe = Lobe::Phong;        // the glossy lobe's model
    float roughness = 0.5f;         // [0.02, 1] GGX: linear roughness, alpha = roughness^2
    Vec3 specularTint{1.0f};        // [0, 1]^3 GGX: colour of the lobe (a metal's colour)
    Vec3 emission{0.0f};            // radiance leaving the front face
    bool twoSidedEmission = false;  // both faces emit (the furnace's inside-out sphere)

    bool emissive() const { return maxComponent(emission) > 0.0f; }
    static Material ggx(Texture albedo, float specular, float roughness, Vec3 tint = Vec3(1.0f)) {
        Material m;
        m.albedo = albedo;
        m.specular = specular;
        m.lobe = Lobe::Ggx;
        m.roughness = roughness;
        m.specularTint = tint;
        return m;
    }
};

// One analytic shape in its object's local space.
struct Primitive {
    enum class Kind { Box, Sphere, Quad };
    Kind kind = Kind::Box;
    Vec3 p0;  // box: min corner; sphere: centre; quad: corner
    Vec3 p1;  // box: max corner; sphere: (radius, 0, 0); quad: edge u
    Vec3 p2;  // quad: edge v (front face: cross(u, v) side)

    static Primitive box(Vec3 lo, Vec3 hi) { return {Kind::Box, lo, hi, {}}; }
    static Primitive sphere(Vec3 centre, float radius) {
        return {Kind::Sphere, centre, {radius, 0.0f, 0.0f}, {}};
    }
    static Primitive quad(Vec3 corner, Vec3 u, Vec3 v) { return {Kind::Quad, corner, u, v}; }
};

// An object: one ID in the G-buffer, one matrix per frame. Its world geometry is
// objectToWorld * (primitives).
struct Object {
    std::string name;
    std::vector<Primitive> primitives;
    Material material;
    Matrix4 objectToWorld = Matrix4::identity();
    // Sampled by next-event estimation (quads, and spheres under a uniform scale); other
    // emitters are found by BSDF sampling only.
    bool light = false;
};

// Pinhole camera; camera space is x right, y up, z forward (depth = z), as in the course data.
struct Camera {
    Vec3 position{0.0f, 0.0f, -1.0f};
    Vec3 target{0.0f};
    Vec3 up{0.0f, 1.0f, 0.0f};
    float verticalFovDegrees = 45.0f;
};

// A distant light of small angular size (the sun): sharp shadows with a narrow penumbra. Sampled
// by next-event estimation as a cone of directions and found by rays that leave the scene.
struct Sun {
    Vec3 direction{0.0f, 1.0f, 0.0f};    // unit, from the scene towards the sun
    float angularRadiusDegrees = 0.27f;  // (0, 10] half the apparent size: the penumbra's width
    Vec3 irradiance{0.0f};               // on a surface facing the sun; 0: no sun

    bool enabled() const { return maxComponent(irradiance) > 0.0f; }
};

// An environment of rays that leave the scene: a gradient from the horizon to the zenith above
// and a uniform ground below (world y up). Found by BSDF sampling only.
struct Sky {
    Vec3 zenith{0.0f};   // radiance straight up
    Vec3 horizon{0.0f};  // radiance at the horizon
    Vec3 ground{0.0f};   // radiance of every direction below the horizon

    bool enabled() const {
        return maxComponent(zenith) > 0.0f || maxComponent(horizon) > 0.0f ||
               maxComponent(ground) > 0.0f;
    }
    Vec3 radiance(Vec3 direction) const;
};

// An opening (a window) through which a room sees the sky: next-event estimation samples points
// on it as an area light of the sky's radiance in each direction (a "portal"), so that a room
// lit through a window converges as one lit by a lamp. It adds no geometry.
struct SkyPortal {
    Vec3 corner;  // world space
    Vec3 edgeU, edgeV;
};

struct Scene {
    std::vector<Object> objects;  // index = object ID
    Camera camera;
    Vec3 background{0.0f};  // radiance of rays that leave the scene (added to sky and sun)
    Sky sky;
    Sun sun;
    std::vector<SkyPortal> skyPortals;  // openings to the sky and background (none: not sampled)
};

// The camera's world-space basis and focal length (pixels) for an image size: primary rays and
// the matrices come from this one place, so the G-buffer and the matrices agree.
struct CameraFrame {
    Vec3 position, right, up, forward;
    float focal = 1.0f;
    float halfWidth = 0.0f, halfHeight = 0.0f;
    // Unit direction through the continuous pixel coordinate (px, py); pixel centres are at
    // x + 0.5, row 0 at the top.
    Vec3 direction(float px, float py) const {
        return normalize(right * ((px - halfWidth) / focal) + up * ((halfHeight - py) / focal) +
                         forward);
    }
};
CameraFrame cameraFrame(const Camera& camera, int width, int height);

// ---- matrices ----

Matrix4 operator*(const Matrix4& a, const Matrix4& b);
Matrix4 translation(Vec3 t);
Matrix4 scaling(Vec3 s);
Matrix4 rotationX(float radians);
Matrix4 rotationY(float radians);
Matrix4 rotationZ(float radians);
// Rows: camera right, up, forward, with the translation that puts the camera at the origin.
Matrix4 worldToCamera(const Camera& camera);
// s = M (p, 1), pixel = (s.x / s.w, s.y / s.w) with pixel centres at x + 0.5, row 0 at the top,
// s.w = camera depth; s.z = s.w (no depth range is needed).
Matrix4 worldToScreen(const Camera& camera, int width, int height);
struct Vec4 {
    float x, y, z, w;
};
// M (p.x, p.y, p.z, 1), all four components.
Vec4 transformPoint(const Matrix4& m, Vec3 p);

}  // namespace rtd::render
