#include "render/scene.h"

#include <cmath>
#include <cstdint>

namespace rtd::render {

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
    }
    return a;
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
