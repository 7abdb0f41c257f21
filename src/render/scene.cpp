#include "render/scene.h"

#include <algorithm>
#include <cmath>
#include <cstdint>

namespace rtd::render {

namespace {

// A value in [0, 1) for an integer lattice point: value noise's corner values.
float latticeValue(std::int64_t i, std::int64_t j, std::uint32_t seed) {
    std::uint64_t h = std::uint64_t(i) * 0x9e3779b97f4a7c15ull ^
                      (std::uint64_t(j) + 0x632be59bd9b4e019ull) * 0xbf58476d1ce4e5b9ull ^
                      std::uint64_t(seed) * 0x94d049bb133111ebull;
    h = (h ^ (h >> 31)) * 0xd6e8feb86659fd93ull;
    h ^= h >> 32;
    return float(h & 0xffffffu) * 0x1p-24f;
}

// Smoothly interpolated value noise in [0, 1).
float valueNoise(float u, float v, std::uint32_t seed) {
    const float fu = std::floor(u), fv = std::floor(v);
    const auto i = std::int64_t(fu), j = std::int64_t(fv);
    float x = u - fu, y = v - fv;
    x = x * x * (3.0f - 2.0f * x);
    y = y * y * (3.0f - 2.0f * y);
    const float a = latticeValue(i, j, seed), b = latticeValue(i + 1, j, seed);
    const float c = latticeValue(i, j + 1, seed), d = latticeValue(i + 1, j + 1, seed);
    return (a + (b - a) * x) * (1.0f - y) + (c + (d - c) * x) * y;
}

Vec3 mix(Vec3 a, Vec3 b, float t) {
    return a * (1.0f - t) + b * t;
}

}  // namespace

Vec3 Texture::evaluate(float u, float v) const {
    switch (kind) {
        case Kind::Constant:
            return a;
        case Kind::Checker: {
            auto cell =
                std::int64_t(std::floor(u * frequency)) + std::int64_t(std::floor(v * frequency));
            return (cell & 1) ? b : a;
        }
        case Kind::Stripes:
            return (std::int64_t(std::floor(u * frequency)) & 1) ? b : a;
        case Kind::Noise: {
            // Fractal sum of octaves (gain 1/2), stretched so that most of [a, b] is used: the
            // sum alone clusters around its middle.
            float sum = 0.0f, weight = 1.0f, total = 0.0f, scale = frequency;
            for (int octave = 0; octave < std::clamp(noiseOctaves, 1, 8); ++octave) {
                sum += weight * valueNoise(u * scale, v * scale, noiseSeed + std::uint32_t(octave));
                total += weight;
                weight *= 0.5f;
                scale *= 2.0f;
            }
            return mix(a, b, std::clamp(0.5f + 1.8f * (sum / total - 0.5f), 0.0f, 1.0f));
        }
        case Kind::Tiles: {
            const float x = u * frequency - std::floor(u * frequency);
            const float y = v * frequency - std::floor(v * frequency);
            const float half = 0.5f * groutWidth;
            const bool grout = x < half || x > 1.0f - half || y < half || y > 1.0f - half;
            return grout ? b : a;
        }
    }
    return a;
}

Vec3 Sky::radiance(Vec3 direction) const {
    if (direction.y < 0.0f) return ground;
    // sqrt: the sky stays near the horizon's colour for the low directions that most rays take.
    return mix(horizon, zenith, std::sqrt(std::min(1.0f, direction.y)));
}

Matrix4 operator*(const Matrix4& a, const Matrix4& b) {
    Matrix4 r;
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j) {
            double s = 0.0;
            for (int k = 0; k < 4; ++k) s += double(a.m[i][k]) * b.m[k][j];
            r.m[i][j] = float(s);
        }
    return r;
}

Matrix4 translation(Vec3 t) {
    Matrix4 m = Matrix4::identity();
    m.m[0][3] = t.x;
    m.m[1][3] = t.y;
    m.m[2][3] = t.z;
    return m;
}

Matrix4 scaling(Vec3 s) {
    Matrix4 m = Matrix4::identity();
    m.m[0][0] = s.x;
    m.m[1][1] = s.y;
    m.m[2][2] = s.z;
    return m;
}

Matrix4 rotationX(float radians) {
    Matrix4 m = Matrix4::identity();
    float c = std::cos(radians), s = std::sin(radians);
    m.m[1][1] = c;
    m.m[1][2] = -s;
    m.m[2][1] = s;
    m.m[2][2] = c;
    return m;
}

Matrix4 rotationY(float radians) {
    Matrix4 m = Matrix4::identity();
    float c = std::cos(radians), s = std::sin(radians);
    m.m[0][0] = c;
    m.m[0][2] = s;
    m.m[2][0] = -s;
    m.m[2][2] = c;
    return m;
}

Matrix4 rotationZ(float radians) {
    Matrix4 m = Matrix4::identity();
    float c = std::cos(radians), s = std::sin(radians);
    m.m[0][0] = c;
    m.m[0][1] = -s;
    m.m[1][0] = s;
    m.m[1][1] = c;
    return m;
}

namespace {

void setRow(Matrix4& m, int row, Vec3 v, Vec3 origin) {
    m.m[row] = {v.x, v.y, v.z, -dot(v, origin)};
}

}  // namespace

CameraFrame cameraFrame(const Camera& camera, int width, int height) {
    CameraFrame f;
    f.position = camera.position;
    f.forward = normalize(camera.target - camera.position);
    f.right = normalize(cross(camera.up, f.forward));
    f.up = cross(f.forward, f.right);
    f.halfWidth = 0.5f * float(width);
    f.halfHeight = 0.5f * float(height);
    f.focal = f.halfHeight / std::tan(camera.verticalFovDegrees * (3.14159265358979f / 360.0f));
    return f;
}

Matrix4 worldToCamera(const Camera& camera) {
    CameraFrame f = cameraFrame(camera, 1, 1);
    Matrix4 m = Matrix4::identity();
    setRow(m, 0, f.right, f.position);
    setRow(m, 1, f.up, f.position);
    setRow(m, 2, f.forward, f.position);
    return m;
}

Matrix4 worldToScreen(const Camera& camera, int width, int height) {
    CameraFrame f = cameraFrame(camera, width, height);
    Matrix4 m;
    setRow(m, 0, f.right * f.focal + f.forward * f.halfWidth, f.position);
    setRow(m, 1, f.up * -f.focal + f.forward * f.halfHeight, f.position);
    setRow(m, 2, f.forward, f.position);
    setRow(m, 3, f.forward, f.position);
    return m;
}

Vec4 transformPoint(const Matrix4& m, Vec3 p) {
    float r[4];
    for (int i = 0; i < 4; ++i)
        r[i] = m.m[i][0] * p.x + m.m[i][1] * p.y + m.m[i][2] * p.z + m.m[i][3];
    return {r[0], r[1], r[2], r[3]};
}

}  // namespace rtd::render
