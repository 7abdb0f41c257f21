// Scene description of the test-scene renderer: analytic primitives in each object's local space,
// one local-to-world matrix per object (what matrix_i.mat records), materials, a pinhole camera.
#pragma once

#include <string>
#include <vector>

#include "render/vec.h"
#include "rtdenoise/image.h"

namespace rtd::render {

// A diffuse albedo that varies over the surface, in local units of the primitive's (u, v).
struct Texture {
    enum class Kind { Constant, Checker, Stripes };
    Kind kind = Kind::Constant;
    Vec3 a{0.5f};            // constant colour; even cells or stripes
    Vec3 b{0.5f};            // odd cells or stripes
    float frequency = 1.0f;  // cells (stripes) per local unit

    static Texture constant(Vec3 c) { return {Kind::Constant, c, c, 1.0f}; }
    static Texture checker(Vec3 a, Vec3 b, float frequency) {
        return {Kind::Checker, a, b, frequency};
    }
    static Texture stripes(Vec3 a, Vec3 b, float frequency) {
        return {Kind::Stripes, a, b, frequency};
    }
    Vec3 evaluate(float u, float v) const;
};

// Diffuse (textured) plus an optional normalised modified-Phong lobe, plus emission. The
// BRDF (1 - specular) albedo / pi + specular (n + 2) / (2 pi) cos^n conserves energy.
struct Material {
    Texture albedo;
    float specular = 0.0f;          // weight of the glossy lobe, 0..1
    float exponent = 64.0f;         // Phong exponent of the glossy lobe
    Vec3 emission{0.0f};            // radiance leaving the front face
    bool twoSidedEmission = false;  // both faces emit (the furnace's inside-out sphere)

    bool emissive() const { return maxComponent(emission) > 0.0f; }
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

struct Scene {
    std::vector<Object> objects;  // index = object ID
    Camera camera;
    Vec3 background{0.0f};  // radiance of rays that leave the scene
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
