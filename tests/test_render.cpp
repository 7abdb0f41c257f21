// The test-scene renderer against known answers: the white furnace and area lights with analytic
// irradiance, the reference against independent 1-spp frames, G-buffers against the matrices,
// back-projection of moving objects, determinism, the written folder and the command line.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

#include "render/confidence.h"
#include "render/path_tracer.h"
#include "render/random_scene.h"
#include "render/render_sequence.h"
#include "render/scenes.h"
#include "test_support.h"

namespace fs = std::filesystem;

namespace rtd::render {
namespace {

constexpr double kPi = 3.14159265358979323846;

// Mean of channel c over all pixels, and its standard error from the spread of the pixels
// (pixels use disjoint random streams, so they are independent estimates).
struct Estimate {
    double mean = 0.0;
    double standardError = 0.0;
};

Estimate pixelMean(const Image& image, int c) {
    double sum = 0.0, sum2 = 0.0;
    const double n = double(image.pixelCount());
    for (std::size_t p = 0; p < image.pixelCount(); ++p) {
        double v = image.pixels[p * image.channels + c];
        sum += v;
        sum2 += v * v;
    }
    double mean = sum / n;
    double variance = std::max(0.0, (sum2 - n * mean * mean) / (n - 1.0));
    return {mean, std::sqrt(variance / n)};
}

// Point of Matrix4 * (p, 1) divided by w.
Vec3 project(const Matrix4& m, Vec3 p, float& w) {
    Vec4 s = transformPoint(m, p);
    w = s.w;
    return {s.x / s.w, s.y / s.w, s.z / s.w};
}

Vec3 pixelVec(const Image& image, int x, int y) {
    return {image.at(x, y, 0), image.at(x, y, 1), image.at(x, y, 2)};
}

Vec3 applyAffine(const Affine& a, Vec3 p) {
    return a.point(p);
}

// Distance from a local-space point to the surface of a primitive.
float distanceToSurface(const Primitive& prim, Vec3 p) {
    switch (prim.kind) {
        case Primitive::Kind::Box: {
            Vec3 centre = (prim.p0 + prim.p1) * 0.5f, half = (prim.p1 - prim.p0) * 0.5f;
            Vec3 q = max(p - centre, centre - p) - half;
            float outside = length(max(q, Vec3(0.0f)));
            float inside = std::min(maxComponent(q), 0.0f);
            return std::abs(outside + inside);
        }
        case Primitive::Kind::Sphere:
            return std::abs(length(p - prim.p0) - prim.p1.x);
        case Primitive::Kind::Quad: {
            Vec3 n = normalize(cross(prim.p1, prim.p2));
            Vec3 rel = p - prim.p0;
            float a = dot(rel, prim.p1) / dot(prim.p1, prim.p1);
            float b = dot(rel, prim.p2) / dot(prim.p2, prim.p2);
            if (a < -1e-3f || a > 1.001f || b < -1e-3f || b > 1.001f) return 1e9f;
            return std::abs(dot(rel, n));
        }
    }
    return 1e9f;
}

int objectIndex(const Scene& scene, const std::string& name) {
    for (std::size_t k = 0; k < scene.objects.size(); ++k)
        if (scene.objects[k].name == name) return int(k);
    ADD_FAILURE() << "no object " << name;
    return -1;
}

// ---- known answers ----

TEST(Render, WhiteFurnaceConvergesToItsAnalyticValue) {
    const Scene scene = buildScene("furnace", 0);
    const double a = kFurnaceAlbedo, le = kFurnaceEmission;
    for (int depth : {1, 3, 8, 64}) {
        TraceSettings t;
        t.width = 32;
        t.height = 24;
        t.samplesPerPixel = 64;
        t.maxDepth = depth;
        Image image = renderRadiance(scene, t);
        // Emission counted at hits 1..depth: Le (1 + a + ... + a^(depth-1)).
        double expected = le * (1.0 - std::pow(a, depth)) / (1.0 - a);
        for (int c = 0; c < 3; ++c) {
            Estimate e = pixelMean(image, c);
            if (depth <= 3) {
                // Russian roulette starts at the third hit and cosine sampling makes f cos / pdf
                // = a exactly: every path returns the same value.
                EXPECT_NEAR(e.mean, expected, 1e-5) << "depth " << depth;
                EXPECT_LT(e.standardError, 1e-6) << "depth " << depth;
            } else {
                // 768 independent pixels of 64 paths each: 5 standard errors (estimated from the
                // pixels' spread) leave a false alarm once in ~2 million runs, and the error
                // must be small enough (< 0.5 %) that a 2 % bias cannot hide in it.
                EXPECT_LT(e.standardError, 0.005 * expected) << "depth " << depth;
                EXPECT_NEAR(e.mean, expected, 5.0 * e.standardError) << "depth " << depth;
            }
        }
    }
}

// A Lambertian floor (albedo rho) under an area light of radiance Le with nothing else: the
// radiance leaving the floor is rho Le F, F the point-to-light form factor. Next-event estimation
// and BSDF sampling both reach the light, so a wrong MIS weight or double counting shows.
Scene lightOverFloor(const Object& light, float albedo) {
    Scene s;
    Material floor;
    floor.albedo = Texture::constant(Vec3(albedo));
    s.objects.push_back({"floor",
                         {Primitive::quad({-50.0f, 0.0f, -50.0f}, {0, 0, 100.0f}, {100.0f, 0, 0})},
                         floor,
                         Matrix4::identity(),
                         false});
    s.objects.push_back(light);
    // Looks at the origin from the side, below the light, with a narrow field of view (the 16
    // pixels cover +-1 cm, where the form factor changes by < 1e-4).
    s.camera.position = {0.0f, 0.5f, -1.5f};
    s.camera.target = {0.0f, 0.0f, 0.0f};
    s.camera.verticalFovDegrees = 0.8f;
    return s;
}

void expectFloorRadiance(const Scene& scene, double expected, const char* what) {
    TraceSettings t;
    t.width = 16;
    t.height = 16;
    t.samplesPerPixel = 256;
    Image image = renderRadiance(scene, t);
    Estimate e = pixelMean(image, 0);
    EXPECT_LT(e.standardError, 0.003 * expected) << what;
    // 5 standard errors plus 1e-3 relative for the pixels' spread around the origin.
    EXPECT_NEAR(e.mean, expected, 5.0 * e.standardError + 1e-3 * expected) << what;
}

TEST(Render, QuadLightIlluminationMatchesTheFormFactor) {
    // A 2 x 2 light at height h = 1 centred above the origin, facing down.
    const float half = 1.0f, h = 1.0f, le = 2.0f, rho = 0.5f;
    Material m;
    m.albedo = Texture::constant(Vec3(0.0f));
    m.emission = Vec3(le);
    Object light{"light",
                 {Primitive::quad({-half, h, -half}, {2 * half, 0, 0}, {0, 0, 2 * half})},
                 m,
                 Matrix4::identity(),
                 true};
    // Parallel rectangle seen from below one corner (Howell's catalogue, C-11), four corners.
    auto corner = [](double x, double y) {
        double sx = std::sqrt(1 + x * x), sy = std::sqrt(1 + y * y);
        return (x / sx * std::atan(y / sx) + y / sy * std::atan(x / sy)) / (2.0 * kPi);
    };
    double f = 4.0 * corner(half / h, half / h);
    expectFloorRadiance(lightOverFloor(light, rho), rho * le * f, "quad light");
    // The same light placed by a matrix (a transformed, rotated quad) gives the same answer.
    // Local front face +z; the rotation turns it to -y.
    light.primitives = {Primitive::quad({-half, -half, 0}, {2 * half, 0, 0}, {0, 2 * half, 0})};
    light.objectToWorld = translation({0.0f, h, 0.0f}) * rotationX(float(kPi / 2));
    expectFloorRadiance(lightOverFloor(light, rho), rho * le * f, "transformed quad light");
}

TEST(Render, SphereLightIlluminationMatchesTheFormFactor) {
    // A sphere of radius R whose centre is d above the origin: F = (R / d)^2.
    const float radius = 0.5f, d = 1.5f, le = 3.0f, rho = 0.8f;
    Material m;
    m.albedo = Texture::constant(Vec3(0.0f));
    m.emission = Vec3(le);
    Object light{"light", {Primitive::sphere({}, radius)}, m, translation({0.0f, d, 0.0f}), true};
    expectFloorRadiance(lightOverFloor(light, rho), rho * le * (radius / d) * (radius / d),
                        "sphere light");
}

TEST(Render, ReferenceMeanEqualsTheMeanOfIndependentFrames) {
    const Scene scene = buildScene("moving-objects", 3);
    TraceSettings t;
    t.width = 64;
    t.height = 48;
    t.frameIndex = 3;
    constexpr int kFrames = 64, kReferenceSpp = 256, kBlock = 16;
    constexpr int kBlocksX = 4, kBlocksY = 3, kBlocks = kBlocksX * kBlocksY;
    auto blockMeans = [&](const Image& image) {
        std::array<double, kBlocks> m{};
        for (int y = 0; y < t.height; ++y)
            for (int x = 0; x < t.width; ++x)
                m[(y / kBlock) * kBlocksX + x / kBlock] +=
                    luminance(pixelVec(image, x, y)) / double(kBlock * kBlock);
        return m;
    };
    // 1-spp frames with different seeds: the mean of each 16x16 block and its standard error.
    std::array<double, kBlocks> sum{}, sum2{};
    for (int i = 0; i < kFrames; ++i) {
        t.seed = 100u + unsigned(i);
        auto m = blockMeans(renderRadiance(scene, t));
        for (int b = 0; b < kBlocks; ++b) {
            sum[b] += m[b];
            sum2[b] += m[b] * m[b];
        }
    }
    t.seed = 1;
    t.stream = kReferenceStream;
    t.samplesPerPixel = kReferenceSpp;
    auto reference = blockMeans(renderRadiance(scene, t));
    for (int b = 0; b < kBlocks; ++b) {
        double mean = sum[b] / kFrames;
        double variance = (sum2[b] - kFrames * mean * mean) / (kFrames - 1);  // of one frame
        // The reference block is the mean of 256 frames' worth of samples.
        double error = std::sqrt(variance / kFrames + variance / kReferenceSpp);
        EXPECT_GT(mean, 0.01) << "block " << b;  // something lit in every block
        EXPECT_NEAR(reference[b], mean, 5.0 * error) << "block " << b;
    }
}

// ---- G-buffer and matrices ----

// maxBackground: the largest fraction of background pixels allowed (open scenes show the sky).
void expectGBufferAgreesWithScene(const Scene& scene, const Frame& f, const std::string& what,
                                  double maxBackground = 0.1) {
    const int w = f.width() > 0 ? f.width() : f.depth.width, h = f.depth.height;
    ASSERT_EQ(f.objectToWorld.size(), scene.objects.size()) << what;
    std::vector<Affine> toLocal;
    for (const Matrix4& m : f.objectToWorld) toLocal.push_back(inverse(toAffine(m)));
    int worstProjection = 0, background = 0, offSurface = 0;
    float maxPixelError = 0.0f;
    for (int y = 0; y < h; ++y) {
        for (int x = 0; x < w; ++x) {
            int id = f.objectId[std::size_t(y) * w + x];
            Vec3 p = pixelVec(f.position, x, y);
            Vec3 n = pixelVec(f.normal, x, y);
            if (id < 0) {
                ++background;
                EXPECT_EQ(id, -1);
                EXPECT_EQ(f.depth.at(x, y), 0.0f);
                EXPECT_EQ(length(n), 0.0f);
                EXPECT_LT(length(p - scene.camera.position), 1e-6f);
                continue;
            }
            ASSERT_LT(id, int(scene.objects.size())) << what;
            // worldToScreen maps the position to the pixel centre, w = depth = camera z.
            float sw = 0.0f;
            Vec3 s = project(f.worldToScreen, p, sw);
            float error =
                std::max(std::abs(s.x - (float(x) + 0.5f)), std::abs(s.y - (float(y) + 0.5f)));
            if (error > maxPixelError) {
                maxPixelError = error;
                worstProjection = y * w + x;
            }
            float depth = f.depth.at(x, y);
            EXPECT_NEAR(sw, depth, 1e-4f * depth) << what << " pixel " << x << "," << y;
            EXPECT_NEAR(transformPoint(f.worldToCamera, p).z, depth, 1e-4f * depth) << what;
            EXPECT_NEAR(length(n), 1.0f, 1e-4f) << what;
            // The object's world geometry is objectToWorld * (its local geometry).
            Vec3 local = applyAffine(toLocal[id], p);
            float nearest = 1e9f;
            for (const Primitive& prim : scene.objects[id].primitives)
                nearest = std::min(nearest, distanceToSurface(prim, local));
            if (nearest > 1e-3f) ++offSurface;
        }
    }
    EXPECT_LT(maxPixelError, 1e-3f)
        << what << ": worst at pixel " << worstProjection % w << "," << worstProjection / w;
    EXPECT_EQ(offSurface, 0) << what << ": positions not on M * local geometry";
    // Mostly enclosed: a small background fraction at most.
    EXPECT_LT(background, maxBackground * w * h) << what;
}

TEST(Render, GBufferAgreesWithTheMatricesInEveryScene) {
    for (const SceneInfo& info : listScenes()) {
        for (int frame : {0, 5}) {
            Scene scene = buildScene(info.name, frame);
            Frame f = renderGBuffer(scene, 80, 60);
            expectGBufferAgreesWithScene(scene, f, info.name + " frame " + std::to_string(frame));
        }
    }
    // The open box shows some background, and it is marked.
    Frame f = renderGBuffer(buildScene("moving-objects", 0), 80, 60);
    EXPECT_GT(std::count(f.objectId.begin(), f.objectId.end(), -1), 0);
}

TEST(Render, EveryPixelIsFiniteInEveryScene) {
    for (const SceneInfo& info : listScenes()) {
        TraceSettings t;
        t.width = 40;
        t.height = 30;
        t.samplesPerPixel = 4;
        t.frameIndex = 7;
        Image image = renderRadiance(buildScene(info.name, 7), t);
        double sum = 0.0;
        for (float v : image.pixels) {
            ASSERT_TRUE(std::isfinite(v)) << info.name;
            ASSERT_GE(v, 0.0f) << info.name;
            sum += v;
        }
        EXPECT_GT(sum / double(image.pixels.size()), 0.02) << info.name << " is too dark";
    }
}

// Back-projection of README: Screen_{i-1} = W2S_{i-1} M_{i-1}[id] M_i[id]^-1 P_i lands on the
// same object in frame i-1, and on the same surface point.
TEST(Render, MovingObjectsBackProjectOntoThemselves) {
    constexpr int kW = 128, kH = 96;
    const int frame = 5;
    Scene previousScene = buildScene("moving-objects", frame - 1);
    Scene scene = buildScene("moving-objects", frame);
    Frame previous = renderGBuffer(previousScene, kW, kH);
    Frame current = renderGBuffer(scene, kW, kH);
    const float focal = 0.5f * kH / std::tan(scene.camera.verticalFovDegrees * float(kPi) / 360.0f);
    for (const char* name : {"sphere", "spinning box", "bouncing cube"}) {
        int id = objectIndex(scene, name);
        ASSERT_GE(id, 0);
        Affine toLocal = inverse(toAffine(current.objectToWorld[id]));
        Affine toPreviousWorld = toAffine(previous.objectToWorld[id]);
        // visible: lands on screen and nothing nearer covers it in frame i-1 (else disoccluded)
        int pixels = 0, visible = 0, sameObject = 0, samePoint = 0, samePixelSameObject = 0;
        double motion = 0.0;
        for (int y = 0; y < kH; ++y) {
            for (int x = 0; x < kW; ++x) {
                if (current.objectId[std::size_t(y) * kW + x] != id) continue;
                ++pixels;
                if (previous.objectId[std::size_t(y) * kW + x] == id) ++samePixelSameObject;
                Vec3 world = toPreviousWorld.point(toLocal.point(pixelVec(current.position, x, y)));
                float w = 0.0f;
                Vec3 s = project(previous.worldToScreen, world, w);
                motion += std::hypot(s.x - (float(x) + 0.5f), s.y - (float(y) + 0.5f));
                int px = int(std::floor(s.x)), py = int(std::floor(s.y));
                if (px < 0 || py < 0 || px >= kW || py >= kH) continue;
                float footprint = 2.0f * w / focal;  // two pixels at that depth
                int previousId = previous.objectId[std::size_t(py) * kW + px];
                if (previousId != id && previous.depth.at(px, py) < w - 10.0f * footprint)
                    continue;  // covered by a nearer object in frame i-1
                ++visible;
                if (previousId != id) continue;
                ++sameObject;
                if (length(pixelVec(previous.position, px, py) - world) < footprint) ++samePoint;
            }
        }
        ASSERT_GT(pixels, 50) << name;
        EXPECT_GT(motion / pixels, 0.2) << name << " should move";
        EXPECT_GT(visible, pixels / 2) << name;
        // Only the silhouette's rounding may land beside the object.
        EXPECT_GT(sameObject, 0.97 * visible) << name;
        EXPECT_GT(samePoint, 0.9 * sameObject) << name;
        if (std::string(name) == "sphere") {
            // In front of everything, moving by pixels: it finds itself everywhere, which
            // it would not without the matrices.
            EXPECT_GT(motion / pixels, 2.0);
            EXPECT_GT(sameObject, 0.97 * pixels);
            EXPECT_LT(samePixelSameObject, 0.9 * pixels);
        }
    }
}

TEST(Render, ScenesMoveWhatTheyAreMeantTo) {
    auto moves = [](const std::string& scene, auto&& changed) {
        Scene first = buildScene(scene, 0);
        for (int i = 1; i < 16; ++i)
            if (changed(first, buildScene(scene, i))) return true;
        return false;
    };
    auto cameraMoves = [](const Scene& a, const Scene& b) {
        return length(a.camera.position - b.camera.position) > 0.0f ||
               length(a.camera.target - b.camera.target) > 0.0f;
    };
    auto objectMoves = [](const Scene& a, const Scene& b) {
        for (std::size_t k = 0; k < a.objects.size(); ++k)
            if (a.objects[k].objectToWorld.m != b.objects[k].objectToWorld.m) return true;
        return false;
    };
    auto lightChanges = [](const Scene& a, const Scene& b) {
        for (std::size_t k = 0; k < a.objects.size(); ++k)
            if (length(a.objects[k].material.emission - b.objects[k].material.emission) > 0.0f)
                return true;
        return false;
    };
    EXPECT_FALSE(moves("moving-objects", cameraMoves));
    EXPECT_TRUE(moves("moving-objects", objectMoves));
    EXPECT_TRUE(moves("camera-pan", cameraMoves));
    EXPECT_FALSE(moves("camera-pan", objectMoves));
    EXPECT_TRUE(moves("thin-geometry", objectMoves));
    EXPECT_FALSE(moves("switching-light", cameraMoves));
    EXPECT_TRUE(moves("switching-light", lightChanges));
    // Sphere lights are sampled as spheres: their matrices may not scale unevenly.
    for (const SceneInfo& info : listScenes()) {
        Scene s = buildScene(info.name, 3);
        for (const Object& o : s.objects) {
            if (!o.light) continue;
            Affine a = toAffine(o.objectToWorld);
            float sx = length(a.vector({1, 0, 0})), sy = length(a.vector({0, 1, 0})),
                  sz = length(a.vector({0, 0, 1}));
            EXPECT_NEAR(sx, sy, 1e-5f * sx) << info.name << " " << o.name;
            EXPECT_NEAR(sx, sz, 1e-5f * sx) << info.name << " " << o.name;
        }
    }
}

TEST(Render, UnknownSceneIsAnErrorListingTheScenes) {
    try {
        buildScene("teapot", 0);
        FAIL() << "no error";
    } catch (const Error& e) {
        EXPECT_EQ(e.code(), ErrorCode::InvalidArgument);
        std::string message = e.what();
        EXPECT_NE(message.find("teapot"), std::string::npos) << message;
        for (const SceneInfo& info : listScenes())
            EXPECT_NE(message.find(info.name), std::string::npos) << message;
    }
    RenderSettings bad;
    bad.width = 0;
    test::TempFolder dir("render-bad");
    EXPECT_THROW(renderSequence("furnace", bad, dir.path() / "out"), Error);
    EXPECT_FALSE(fs::exists(dir.path() / "out"));
}

// ---- the split signal (specular, roughness, hit distance) ----

// The reflections scene with every glossy lobe removed (diffuse materials only).
Scene withoutGlossyLobes(Scene scene) {
    for (Object& o : scene.objects) o.material.specular = 0.0f;
    return scene;
}

TEST(RenderSplit, SpecularIsExactlyZeroWithoutAGlossyLobe) {
    TraceSettings t;
    t.width = 32;
    t.height = 24;
    t.samplesPerPixel = 2;
    Image specular;
    const Image beauty =
        renderRadiance(withoutGlossyLobes(buildScene("reflections", 0)), t, &specular);
    ASSERT_EQ(specular.width, 32);
    ASSERT_EQ(specular.height, 24);
    ASSERT_EQ(specular.channels, 3);
    EXPECT_GT(pixelMean(beauty, 0).mean, 0.01);
    for (float v : specular.pixels) ASSERT_EQ(v, 0.0f);
}

TEST(RenderSplit, SpecularIsTheGlossyPartOfTheSameBeauty) {
    const Scene scene = buildScene("reflections", 0);
    TraceSettings t;
    t.width = 48;
    t.height = 36;
    t.samplesPerPixel = 4;
    Image specular;
    const Image split = renderRadiance(scene, t, &specular);
    // The beauty and its random numbers are the same with or without the split.
    EXPECT_EQ(split.pixels, renderRadiance(scene, t).pixels);
    // Every term of the glossy part is at most the whole term (all values are >= 0), so per
    // channel 0 <= specular <= beauty up to rounding: the diffuse part is beauty - specular.
    for (std::size_t i = 0; i < specular.pixels.size(); ++i) {
        ASSERT_TRUE(std::isfinite(specular.pixels[i]));
        ASSERT_GE(specular.pixels[i], 0.0f);
        ASSERT_LE(specular.pixels[i], split.pixels[i] * (1.0f + 1e-4f) + 1e-6f) << "value " << i;
    }
    // The near-mirror sphere (specular 0.95, exponent 5000) is mostly specular; the diffuse
    // block has none (inside its outline: the samples of an edge pixel see its neighbours).
    const Frame g = renderGBuffer(scene, t.width, t.height);
    const int mirror = objectIndex(scene, "mirror sphere"), block = objectIndex(scene, "block");
    double mirrorBeauty = 0.0, mirrorSpecular = 0.0, blockSpecular = 0.0;
    int mirrorPixels = 0, blockPixels = 0;
    for (int y = 1; y + 1 < t.height; ++y)
        for (int x = 1; x + 1 < t.width; ++x) {
            const int id = g.objectId[std::size_t(y) * t.width + x];
            bool inside = true;
            for (int dy = -1; dy <= 1; ++dy)
                for (int dx = -1; dx <= 1; ++dx)
                    inside = inside && g.objectId[std::size_t(y + dy) * t.width + x + dx] == id;
            if (!inside) continue;
            if (id == mirror) {
                mirrorBeauty += luminance(pixelVec(split, x, y));
                mirrorSpecular += luminance(pixelVec(specular, x, y));
                ++mirrorPixels;
            } else if (id == block) {
                blockSpecular += maxComponent(pixelVec(specular, x, y));
                ++blockPixels;
            }
        }
    ASSERT_GT(mirrorPixels, 20);
    ASSERT_GT(blockPixels, 0);
    EXPECT_GT(mirrorSpecular, 0.85 * mirrorBeauty);
    EXPECT_EQ(blockSpecular, 0.0);
    // The glossy floor (specular 0.3) holds some of both.
    double specularTotal = 0.0, beautyTotal = 0.0;
    for (std::size_t i = 0; i < split.pixels.size(); ++i) {
        specularTotal += specular.pixels[i];
        beautyTotal += split.pixels[i];
    }
    EXPECT_GT(specularTotal, 0.05 * beautyTotal);
    EXPECT_LT(specularTotal, 0.95 * beautyTotal);
}

float expectedRoughness(float exponent) {
    return std::sqrt(std::sqrt(2.0f / (exponent + 2.0f)));
}

TEST(RenderSplit, GBufferHasRoughnessAndHitDistanceAndTheSameAlbedo) {
    for (int frame : {0, 7}) {
        const Scene scene = buildScene("reflections", frame);
        const Frame plain = renderGBuffer(scene, 40, 30);
        const Frame split = renderGBuffer(scene, 40, 30, true);
        EXPECT_FALSE(plain.roughness.has_value());
        EXPECT_FALSE(plain.hitDistance.has_value());
        ASSERT_TRUE(split.roughness.has_value());
        ASSERT_TRUE(split.hitDistance.has_value());
        ASSERT_EQ(split.roughness->channels, 1);
        ASSERT_EQ(split.hitDistance->channels, 1);
        // Everything else is the default G-buffer's.
        EXPECT_EQ(split.objectId, plain.objectId);
        EXPECT_EQ(split.depth.pixels, plain.depth.pixels);
        EXPECT_EQ(split.normal.pixels, plain.normal.pixels);
        EXPECT_EQ(split.albedo->pixels, plain.albedo->pixels);
        for (int y = 0; y < 30; ++y)
            for (int x = 0; x < 40; ++x) {
                const int id = split.objectId[std::size_t(y) * 40 + x];
                const float r = split.roughness->at(x, y);
                if (id < 0) {
                    EXPECT_EQ(r, 0.0f);
                    EXPECT_EQ(split.hitDistance->at(x, y), 0.0f);
                    continue;
                }
                const Material& m = scene.objects[id].material;
                if (m.specular > 0.0f) {
                    EXPECT_NEAR(r, expectedRoughness(m.exponent), 1e-6f);
                } else {
                    EXPECT_EQ(r, 1.0f);
                    EXPECT_EQ(split.hitDistance->at(x, y), 0.0f);
                }
                // The closed room: every mirror ray hits something.
                if (m.specular > 0.0f) EXPECT_GT(split.hitDistance->at(x, y), 0.0f);
            }
    }
    // A constant texture c: the default albedo is c (1 - s) + s exactly as before.
    const Scene scene = buildScene("reflections", 0);
    const Frame plain = renderGBuffer(scene, 40, 30);
    const int metal = objectIndex(scene, "metal sphere");
    const Material& m = scene.objects[metal].material;
    int seen = 0;
    for (int y = 0; y < 30; ++y)
        for (int x = 0; x < 40; ++x)
            if (plain.objectId[std::size_t(y) * 40 + x] == metal) {
                ++seen;
                const Vec3 c = m.albedo.a;
                for (int k = 0; k < 3; ++k)
                    EXPECT_FLOAT_EQ(plain.albedo->at(x, y, k),
                                    c[k] * (1.0f - m.specular) + m.specular);
            }
    EXPECT_GT(seen, 0);
    EXPECT_NEAR(expectedRoughness(300.0f), 0.28527f, 1e-5f);  // (2 / 302)^(1/4)
}

// A camera looking straight at a glossy quad at z = 0 from z = -1, a wall at z = -d behind the
// camera: the mirror ray of the centre pixel comes back along the axis and hits the wall at d.
Scene mirrorFacingWall(float d, bool wall, float specular) {
    Scene s;
    Material mirror;
    mirror.albedo = Texture::constant(Vec3(0.5f));
    mirror.specular = specular;
    mirror.exponent = 1000.0f;
    s.objects.push_back({"mirror",
                         {Primitive::quad({-1.0f, -1.0f, 0.0f}, {0, 2.0f, 0}, {2.0f, 0, 0})},
                         mirror,
                         Matrix4::identity(),
                         false});
    if (wall)
        s.objects.push_back({"wall",
                             {Primitive::quad({-5.0f, -5.0f, -d}, {10.0f, 0, 0}, {0, 10.0f, 0})},
                             Material{},
                             Matrix4::identity(),
                             false});
    s.camera.position = {0.0f, 0.0f, -1.0f};
    s.camera.target = {0.0f, 0.0f, 0.0f};
    s.camera.verticalFovDegrees = 10.0f;
    return s;
}

TEST(RenderSplit, HitDistanceIsTheMirrorRaysDistance) {
    for (float d : {3.0f, 7.5f}) {
        const Frame f = renderGBuffer(mirrorFacingWall(d, true, 0.9f), 5, 5, true);
        ASSERT_EQ(f.objectId[2 * 5 + 2], 0);
        EXPECT_NEAR(f.hitDistance->at(2, 2), d, 1e-3f * d) << "d " << d;
        EXPECT_NEAR(f.roughness->at(2, 2), expectedRoughness(1000.0f), 1e-6f);
        for (int y = 0; y < 5; ++y)  // the wall is large: every mirror ray hits it, near d
            for (int x = 0; x < 5; ++x) EXPECT_NEAR(f.hitDistance->at(x, y), d, 0.01f * d);
    }
    // Nothing to hit, or no glossy lobe: 0 (unknown).
    Frame f = renderGBuffer(mirrorFacingWall(3.0f, false, 0.9f), 5, 5, true);
    EXPECT_EQ(f.hitDistance->at(2, 2), 0.0f);
    f = renderGBuffer(mirrorFacingWall(3.0f, true, 0.0f), 5, 5, true);
    EXPECT_EQ(f.hitDistance->at(2, 2), 0.0f);
    EXPECT_EQ(f.roughness->at(2, 2), 1.0f);
    EXPECT_EQ(f.albedo->at(2, 2, 0), 0.5f);
}

TEST(RenderSplit, SequenceWritesTheSplitAndRemovesItWithout) {
    test::TempFolder dir("render-split");
    RenderSettings settings;
    settings.width = 24;
    settings.height = 16;
    settings.frames = 2;
    settings.gbufferOnly = true;
    settings.split = true;
    const fs::path out = dir.path() / "seq";
    renderSequence("reflections", settings, out);
    for (int i = 0; i < 2; ++i) {
        for (const char* stem : {"specular", "roughness", "hit_distance"})
            EXPECT_TRUE(fs::exists(out / fmt::format("{}_{}.exr", stem, i))) << stem << i;
        TraceSettings t;
        t.width = 24;
        t.height = 16;
        t.frameIndex = i;
        const Frame expected = renderFrame(buildScene("reflections", i), t, true);
        const Frame f = Sequence(out).readFrame(i);
        ASSERT_TRUE(f.specular && f.roughness && f.hitDistance && f.albedo);
        EXPECT_EQ(f.specular->pixels, expected.specular->pixels);
        EXPECT_EQ(f.roughness->pixels, expected.roughness->pixels);
        EXPECT_EQ(f.hitDistance->pixels, expected.hitDistance->pixels);
        EXPECT_EQ(f.albedo->pixels, expected.albedo->pixels);
        EXPECT_EQ(f.beauty.pixels, renderRadiance(buildScene("reflections", i), t).pixels);
    }
    // Without the split, none of them stays to be read as this render's.
    settings.split = false;
    renderSequence("reflections", settings, out);
    for (const char* stem : {"specular", "roughness", "hit_distance"})
        EXPECT_FALSE(fs::exists(out / fmt::format("{}_0.exr", stem))) << stem;
    EXPECT_FALSE(Sequence(out).readFrame(0).specular.has_value());
    // Blender's multilayer files have no such passes.
    settings.split = true;
    settings.format = OutputFormat::Multilayer;
    EXPECT_THROW(validate(settings), Error);
}

// ---- determinism and the written folder ----

TEST(Render, SameSeedSameImageOtherSeedDifferent) {
    const Scene scene = buildScene("switching-light", 2);
    TraceSettings t;
    t.width = 48;
    t.height = 36;
    t.frameIndex = 2;
    t.seed = 7;
    Image a = renderRadiance(scene, t);
    Image b = renderRadiance(scene, t);
    EXPECT_EQ(a.pixels, b.pixels);
    t.seed = 8;
    Image c = renderRadiance(scene, t);
    std::size_t differ = 0;
    for (std::size_t i = 0; i < a.pixels.size(); ++i) differ += a.pixels[i] != c.pixels[i];
    EXPECT_GT(differ, a.pixels.size() / 2);
    // Another frame index or the reference stream also gives other numbers.
    t.seed = 7;
    t.stream = kReferenceStream;
    Image d = renderRadiance(scene, t);
    differ = 0;
    for (std::size_t i = 0; i < a.pixels.size(); ++i) differ += a.pixels[i] != d.pixels[i];
    EXPECT_GT(differ, a.pixels.size() / 2);
}

std::string fileBytes(const fs::path& file) {
    std::ifstream in(file, std::ios::binary);
    std::stringstream s;
    s << in.rdbuf();
    return s.str();
}

TEST(Render, WrittenFolderIsASequenceWithReferenceAndSceneJson) {
    test::TempFolder dir("render-seq");
    RenderSettings settings;
    settings.width = 40;
    settings.height = 30;
    settings.frames = 3;
    settings.referenceSpp = 4;
    const fs::path out = dir.path() / "seq";
    // A frame left from an earlier, longer render must not join this sequence.
    fs::create_directories(out);
    writeExr(out / "beauty_5.exr", Image(40, 30, 3));
    int calls = 0;
    renderSequence("moving-objects", settings, out, [&](int done, int total) {
        EXPECT_EQ(done, ++calls);
        EXPECT_EQ(total, 3);
    });
    EXPECT_EQ(calls, 3);
    EXPECT_FALSE(fs::exists(out / "beauty_5.exr"));

    Sequence sequence(out);
    ASSERT_EQ(sequence.frameCount(), 3);
    for (int i = 0; i < 3; ++i) {
        Frame f = sequence.readFrame(i);
        EXPECT_EQ(f.width(), 40);
        EXPECT_EQ(f.height(), 30);
        ASSERT_TRUE(f.albedo.has_value());
        EXPECT_EQ(f.objectToWorld.size(), buildScene("moving-objects", i).objects.size());
        // The file holds what the renderer computed (the matrices survive the round trip).
        Scene scene = buildScene("moving-objects", i);
        expectGBufferAgreesWithScene(scene, f, "file frame " + std::to_string(i));
        // The reference is the scene's frame i traced with the reference stream.
        fs::path ref = out / "reference" / ("reference_" + std::to_string(i) + ".exr");
        ASSERT_TRUE(fs::exists(ref));
        Image reference = readExr(ref, {{"R"}, {"G"}, {"B"}});
        TraceSettings t;
        t.width = 40;
        t.height = 30;
        t.frameIndex = i;
        t.samplesPerPixel = 4;
        t.stream = kReferenceStream;
        EXPECT_EQ(reference.pixels, renderRadiance(scene, t).pixels) << "frame " << i;
    }
    std::string json = fileBytes(out / "scene.json");
    for (const char* key :
         {"\"scene\": \"moving-objects\"", "\"width\": 40", "\"height\": 30", "\"frames\": 3",
          "\"spp\": 1", "\"reference_spp\": 4", "\"seed\": 1", "\"camera\": false", "\"sphere\""})
        EXPECT_NE(json.find(key), std::string::npos) << key << " in\n" << json;

    // The same settings write the same bytes; --gbuffer-only writes no reference.
    settings.gbufferOnly = true;
    renderSequence("moving-objects", settings, dir.path() / "again");
    EXPECT_EQ(fileBytes(out / "beauty_2.exr"), fileBytes(dir.path() / "again" / "beauty_2.exr"));
    EXPECT_FALSE(fs::exists(dir.path() / "again" / "reference"));
    EXPECT_NE(fileBytes(dir.path() / "again" / "scene.json").find("\"reference\": false"),
              std::string::npos);
}

// ---- GGX, the sun, sky portals and textures ----

// A camera inside a sphere of the given material (whole frame on it), nothing else: with
// maxDepth 2 every path is one bounce to the sky.
Scene sphereUnderSky(const Material& m, const Sky& sky) {
    Scene s;
    s.objects.push_back(
        {"sphere", {Primitive::sphere({}, 1.0f)}, m, translation({0.0f, 0.0f, 3.0f}), false});
    s.sky = sky;
    s.camera.position = {};
    s.camera.target = {0.0f, 0.0f, 3.0f};
    s.camera.verticalFovDegrees = 24.0f;  // the sphere (19.5 degrees half-angle) fills it
    return s;
}

// White furnace for the GGX lobe: under a uniform sky of radiance 1, a convex white metal
// reflects its directional albedo, which must not exceed 1 and, with the multiple-scattering lobe
// giving back what single scattering loses (70 % at roughness 1), is 1 at every roughness. A lobe
// that gains or loses energy (a wrong D, G, pdf or compensation) fails.
TEST(RenderGgx, WhiteMetalUnderAUniformSkyReflectsAllOfItAtEveryRoughness) {
    const Sky uniform{Vec3(1.0f), Vec3(1.0f), Vec3(1.0f)};
    TraceSettings t;
    t.width = t.height = 24;
    t.samplesPerPixel = 64;
    t.maxDepth = 2;
    for (float roughness : {0.02f, 0.3f, 0.6f, 1.0f}) {
        const Scene scene = sphereUnderSky(
            Material::ggx(Texture::constant(Vec3(0.0f)), 1.0f, roughness, Vec3(1.0f)), uniform);
        const Estimate e = pixelMean(renderRadiance(scene, t), 0);
        EXPECT_LT(e.standardError, 0.003) << "roughness " << roughness;
        // 1e-5: float rounding, which a near-mirror's all but noiseless estimate does not hide
        // (under the sanitizers' -O1 its mean came out 1 + 1e-7).
        EXPECT_LE(e.mean, 1.0 + 4.0 * e.standardError + 1e-5) << "roughness " << roughness;
        EXPECT_NEAR(e.mean, 1.0, 0.01 + 4.0 * e.standardError) << "roughness " << roughness;
    }
    // Half glossy over a white diffuse base reflects all of it too; a dark tint reflects its own
    // luminance at most.
    Estimate e = pixelMean(
        renderRadiance(
            sphereUnderSky(Material::ggx(Texture::constant(Vec3(1.0f)), 0.5f, 0.4f), uniform), t),
        1);
    EXPECT_NEAR(e.mean, 1.0, 0.01 + 4.0 * e.standardError);
    e = pixelMean(renderRadiance(sphereUnderSky(Material::ggx(Texture::constant(Vec3(0.0f)), 1.0f,
                                                              0.8f, Vec3(0.5f)),
                                                uniform),
                                 t),
                  0);
    EXPECT_LE(e.mean, 0.5 + 4.0 * e.standardError + 1e-5);
    EXPECT_GT(e.mean, 0.45);
}

// A rough metal floor and a glossy one under a quad light: next-event estimation with MIS and
// BSDF sampling alone (the same light left out of the light list) are two unbiased estimates
// of the same radiance, which agree only if the lobe's value, pdf and sampling agree.
TEST(RenderGgx, NextEventEstimationAndBsdfSamplingAgree) {
    for (const Material& floorMaterial :
         {Material::ggx(Texture::constant(Vec3(0.0f)), 1.0f, 0.35f, {0.9f, 0.7f, 0.4f}),
          Material::ggx(Texture::constant(Vec3(0.6f)), 0.3f, 0.15f)}) {
        Material lightMaterial;
        lightMaterial.albedo = Texture::constant(Vec3(0.0f));
        lightMaterial.emission = Vec3(2.0f);
        Object light{"light",
                     {Primitive::quad({-1.0f, 1.0f, 1.0f}, {2.0f, 0, 0}, {0, 0, 2.0f})},
                     lightMaterial,
                     Matrix4::identity(),
                     true};
        Scene scene = lightOverFloor(light, 0.5f);
        scene.objects[0].material = floorMaterial;
        TraceSettings t;
        t.width = t.height = 24;
        t.samplesPerPixel = 256;
        const Estimate withLight = pixelMean(renderRadiance(scene, t), 0);
        scene.objects[1].light = false;
        const Estimate bsdfOnly = pixelMean(renderRadiance(scene, t), 0);
        ASSERT_GT(withLight.mean, 0.01);
        const double error = std::hypot(withLight.standardError, bsdfOnly.standardError);
        EXPECT_LT(error, 0.015 * withLight.mean);
        EXPECT_NEAR(withLight.mean, bsdfOnly.mean, 5.0 * error + 2e-3 * withLight.mean);
    }
}

// A sun at elevation 45 degrees over a diffuse floor, behind a black wall 1 m tall: the floor
// reflects rho / pi E cos(45) where it sees the sun, exactly 0 in the wall's shadow (nothing
// else is lit), and the edge between them is as sharp as the sun's 0.27-degree radius makes it:
// about 2 cm, two of the view's 1-cm pixels.
TEST(RenderSun, LightsAFloorToItsIrradianceAndCastsAHardShadow) {
    constexpr float kElevation = 45.0f * float(kPi) / 180.0f, kIrradiance = 2.0f, kAlbedo = 0.5f;
    Scene s;
    Material floor;
    floor.albedo = Texture::constant(Vec3(kAlbedo));
    s.objects.push_back({"floor",
                         {Primitive::quad({-5, 0, -5}, {0, 0, 10}, {10, 0, 0})},
                         floor,
                         Matrix4::identity(),
                         false});
    Material black;
    black.albedo = Texture::constant(Vec3(0.0f));
    s.objects.push_back({"wall",
                         {Primitive::box({-5.0f, 0.0f, -0.05f}, {5.0f, 1.0f, 0.05f})},
                         black,
                         Matrix4::identity(),
                         false});
    // Light travels towards +z and down: the wall's top edge shadows the floor up to z = 1.05.
    s.sun.direction = {0.0f, std::sin(kElevation), -std::cos(kElevation)};
    s.sun.irradiance = Vec3(kIrradiance);
    s.sun.angularRadiusDegrees = 0.27f;
    // Straight down at the edge from 2 m: 40 pixels over 0.4 m.
    s.camera.position = {0.0f, 2.0f, 1.05f};
    s.camera.target = {0.0f, 0.0f, 1.05f};
    s.camera.up = {0.0f, 0.0f, 1.0f};
    s.camera.verticalFovDegrees = 2.0f * std::atan(0.2f / 2.0f) * 180.0f / float(kPi);
    TraceSettings t;
    t.width = t.height = 40;
    t.samplesPerPixel = 16;
    const Image image = renderRadiance(s, t);
    const Frame g = renderGBuffer(s, t.width, t.height);
    const double lit = kAlbedo / kPi * kIrradiance * std::sin(kElevation);
    int transition = 0, litPixels = 0, shadowPixels = 0;
    for (int y = 0; y < t.height; ++y)
        for (int x = 0; x < t.width; ++x) {
            const float z = g.position.at(x, y, 2), v = image.at(x, y, 0);
            if (z < 1.05f - 0.025f) {  // the penumbra's half-width and a pixel
                ASSERT_EQ(v, 0.0f) << x << "," << y;
                ++shadowPixels;
            } else if (z > 1.05f + 0.025f) {
                ASSERT_NEAR(v, lit, 0.01 * lit) << x << "," << y;
                ++litPixels;
            } else {
                ++transition;
            }
        }
    EXPECT_GT(shadowPixels, 600);
    EXPECT_GT(litPixels, 600);
    EXPECT_LE(transition, 6 * t.width);
}

// A room lit by the sky through a window: sampling the window as a portal light changes the noise,
// not the mean (MIS against BSDF sampling), and makes that noise much smaller.
TEST(RenderPortal, AWindowSampledAsALightKeepsTheMeanAndCutsTheNoise) {
    Scene s;
    Material wall;
    wall.albedo = Texture::constant(Vec3(0.6f));
    const Vec3 lo{-2.0f, 0.0f, -2.0f}, hi{2.0f, 2.5f, 2.0f}, size = hi - lo;
    auto add = [&](std::vector<Primitive> p) {
        s.objects.push_back({"wall", std::move(p), wall, Matrix4::identity(), false});
    };
    add({Primitive::quad(lo, {0, 0, size.z}, {size.x, 0, 0})});                  // floor
    add({Primitive::quad({lo.x, hi.y, lo.z}, {size.x, 0, 0}, {0, 0, size.z})});  // ceiling
    add({Primitive::quad(lo, {size.x, 0, 0}, {0, size.y, 0})});                  // front
    add({Primitive::quad(lo, {0, size.y, 0}, {0, 0, size.z})});                  // left
    add({Primitive::quad({hi.x, lo.y, lo.z}, {0, 0, size.z}, {0, size.y, 0})});  // right
    // The back wall with a 2 x 1 m window from x -1..1, y 1..2.
    add({Primitive::quad({lo.x, 0, hi.z}, {size.x, 0, 0}, {0, 1.0f, 0}),
         Primitive::quad({lo.x, 2.0f, hi.z}, {size.x, 0, 0}, {0, 0.5f, 0}),
         Primitive::quad({lo.x, 1.0f, hi.z}, {1.0f, 0, 0}, {0, 1.0f, 0}),
         Primitive::quad({1.0f, 1.0f, hi.z}, {1.0f, 0, 0}, {0, 1.0f, 0})});
    s.sky = {{0.4f, 0.6f, 1.0f}, {1.0f, 1.0f, 1.0f}, {0.3f, 0.3f, 0.3f}};
    s.camera.position = {0.0f, 1.2f, -1.8f};
    s.camera.target = {0.0f, 0.3f, 1.0f};
    TraceSettings t;
    t.width = t.height = 16;
    t.samplesPerPixel = 128;
    t.maxDepth = 4;
    const Estimate bsdfOnly = pixelMean(renderRadiance(s, t), 2);
    s.skyPortals.push_back({{-1.0f, 1.0f, hi.z}, {2.0f, 0, 0}, {0, 1.0f, 0}});
    const Estimate portal = pixelMean(renderRadiance(s, t), 2);
    const double error = std::hypot(bsdfOnly.standardError, portal.standardError);
    EXPECT_GT(portal.mean, 0.02);
    EXPECT_NEAR(portal.mean, bsdfOnly.mean, 5.0 * error);
    // The noise of the sky's direct light (maxDepth 2), which the portal samples: the rms
    // difference of two renders with other seeds over the lower half of the view (the floor;
    // above it the window's edge, seen directly, is as noisy either way).
    auto noise = [&](bool withPortal) {
        Scene scene = s;
        if (!withPortal) scene.skyPortals.clear();
        TraceSettings a = t;
        a.samplesPerPixel = 4;
        a.maxDepth = 2;
        TraceSettings b = a;
        b.seed = 2;
        const Image x = renderRadiance(scene, a), y = renderRadiance(scene, b);
        const std::size_t half = x.pixels.size() / 2;
        double sum = 0.0;
        for (std::size_t i = half; i < x.pixels.size(); ++i)
            sum += double(x.pixels[i] - y.pixels[i]) * double(x.pixels[i] - y.pixels[i]);
        return std::sqrt(sum / double(x.pixels.size() - half));
    };
    EXPECT_LT(noise(true), 0.2 * noise(false));
}

TEST(RenderTexture, NoiseAndTilesStayBetweenTheirColoursAndVary) {
    const Vec3 a{0.8f, 0.6f, 0.2f}, b{0.1f, 0.2f, 0.5f};
    const Texture noise = Texture::noise(a, b, 3.0f, 4, 17u),
                  tiles = Texture::tiles(a, b, 2.0f, 0.2f);
    double sum = 0.0, sum2 = 0.0;
    int grout = 0, n = 0;
    for (int i = 0; i < 200; ++i)
        for (int j = 0; j < 200; ++j, ++n) {
            const float u = -3.0f + 0.031f * float(i), v = -2.0f + 0.027f * float(j);
            const Vec3 c = noise.evaluate(u, v);
            for (int k = 0; k < 3; ++k) {
                ASSERT_GE(c[k], std::min(a[k], b[k]) - 1e-6f);
                ASSERT_LE(c[k], std::max(a[k], b[k]) + 1e-6f);
            }
            sum += c.x;
            sum2 += double(c.x) * c.x;
            const Vec3 t = tiles.evaluate(u, v);
            ASSERT_TRUE(t.x == a.x || t.x == b.x);
            grout += t.x == b.x;
            EXPECT_EQ(noise.evaluate(u, v).x, c.x);  // a function of (u, v) alone
        }
    const double mean = sum / n, spread = std::sqrt(sum2 / n - mean * mean);
    EXPECT_GT(spread, 0.1 * (a.x - b.x));  // it varies across its range
    // A grout of 0.2 of a tile covers 1 - 0.8^2 = 36 % of the surface.
    EXPECT_NEAR(double(grout) / n, 0.36, 0.03);
    // Another seed is another pattern.
    EXPECT_NE(Texture::noise(a, b, 3.0f, 4, 18u).evaluate(0.37f, 0.71f).x,
              noise.evaluate(0.37f, 0.71f).x);
}

// ---- the scene generator ----

// Tags of seeds 1..count (drawn, not rendered).
std::map<std::string, int> tagCounts(int count) {
    std::map<std::string, int> counts;
    for (int seed = 1; seed <= count; ++seed)
        for (const std::string& tag : drawRandomScene(std::uint32_t(seed)).tags()) ++counts[tag];
    return counts;
}

TEST(RandomScene, DistributionCoversEveryCategory) {
    const std::map<std::string, int> counts = tagCounts(200);
    std::string all;
    for (const auto& [tag, n] : counts) all += fmt::format("{} {}\n", tag, n);
    for (const char* tag : {"layout:closed-room", "layout:window-room",
                            "layout:open",        "lighting:indirect",
                            "lighting:night",     "light:area-light",
                            "light:small-light",  "light:emissive-object",
                            "light:wall-panel",   "light:hidden-light",
                            "light:sun",          "light:sky",
                            "light:coloured",     "lights:one",
                            "lights:many",        "material:diffuse",
                            "material:glossy",    "material:metal",
                            "material:mirror",    "material:emitter",
                            "texture:constant",   "texture:checker",
                            "texture:stripes",    "texture:noise",
                            "texture:tiles",      "roughness:low",
                            "roughness:medium",   "roughness:high",
                            "geometry:box",       "geometry:sphere",
                            "geometry:bar",       "geometry:grid",
                            "geometry:details",   "geometry:slab",
                            "camera:static",      "camera:pan",
                            "camera:tilt",        "camera:dolly",
                            "camera:truck",       "camera:orbit",
                            "camera:handheld",    "camera:pan-and-dolly",
                            "camera-speed:slow",  "camera-speed:medium",
                            "camera-speed:fast",  "motion:objects",
                            "motion:rotation",    "motion:lights",
                            "motion:switching",   "motion:sun",
                            "motion:none"}) {
        const auto it = counts.find(tag);
        EXPECT_GE(it == counts.end() ? 0 : it->second, 4) << tag << " in 200 seeds:\n" << all;
    }
    // The layouts in their documented shares (40 / 20 / 40 %), loosely.
    EXPECT_NEAR(counts.at("layout:closed-room"), 80, 25) << all;
    EXPECT_NEAR(counts.at("layout:window-room"), 40, 20) << all;
    EXPECT_NEAR(counts.at("layout:open"), 80, 25) << all;
    EXPECT_NEAR(counts.at("camera:static"), 63, 22) << all;  // 10 % still + 90 % x ~24 %
}

TEST(RandomScene, SameSeedSameSceneOtherSeedsOtherScenes) {
    // Every parameter: the description without its seed.
    auto parameters = [](std::uint32_t seed) {
        std::string json = drawRandomScene(seed).describeJson();
        const std::size_t at = json.find("\"seed\"");
        return json.erase(at, json.find('\n', at) - at);
    };
    std::set<std::string> seen;
    for (std::uint32_t seed = 1; seed <= 200; ++seed) seen.insert(parameters(seed));
    EXPECT_EQ(seen.size(), 200u);
    EXPECT_EQ(drawRandomScene(77).describeJson(), drawRandomScene(77).describeJson());
    // The same seed, the same frames, bit for bit (the exposure's preview included).
    const SceneDefinition a = randomSceneDefinition(77), b = randomSceneDefinition(77);
    EXPECT_EQ(a.generator, b.generator);
    TraceSettings t;
    t.width = 24;
    t.height = 16;
    t.frameIndex = 3;
    EXPECT_EQ(renderFrame(a.build(3), t, true).beauty.pixels,
              renderFrame(b.build(3), t, true).beauty.pixels);
    const Image other = renderRadiance(randomSceneDefinition(78).build(3), t);
    EXPECT_NE(renderRadiance(a.build(3), t).pixels, other.pixels);
}

// Seeds of each layout (the first two of each among 1, 2, ...).
std::vector<std::uint32_t> seedsOfEveryLayout() {
    std::map<int, int> found;
    std::vector<std::uint32_t> seeds;
    for (std::uint32_t seed = 1; seeds.size() < 6; ++seed) {
        const int layout = int(drawRandomScene(seed).layout);
        if (found[layout]++ < 2) seeds.push_back(seed);
    }
    return seeds;
}

// The G-buffer conventions hold for every new material, light and shape: finite values, unit
// normals facing the camera, positions on M * local geometry that project to their pixel, IDs in
// range and -1 with zero normal and depth on background, albedo and roughness in [0, 1]; the
// beauty finite and >= 0 with its specular part at most itself.
TEST(RandomScene, GBufferAndBeautyAreValidOnEveryLayout) {
    for (std::uint32_t seed : seedsOfEveryLayout()) {
        const SceneDefinition d = randomSceneDefinition(seed);
        for (int frame : {0, 5}) {
            const std::string what = fmt::format("seed {} frame {}", seed, frame);
            const Scene scene = d.build(frame);
            TraceSettings t;
            t.width = 40;
            t.height = 30;
            t.frameIndex = frame;
            t.seed = seed;
            const Frame f = renderFrame(scene, t, true);
            expectGBufferAgreesWithScene(scene, f, what, 1.01);
            const std::size_t pixels = std::size_t(t.width) * t.height;
            for (std::size_t p = 0; p < pixels; ++p) {
                const Vec3 position{f.position.pixels[p * 3], f.position.pixels[p * 3 + 1],
                                    f.position.pixels[p * 3 + 2]};
                const Vec3 normal{f.normal.pixels[p * 3], f.normal.pixels[p * 3 + 1],
                                  f.normal.pixels[p * 3 + 2]};
                ASSERT_TRUE(isFinite(position) && isFinite(normal)) << what;
                if (f.objectId[p] >= 0)  // facing the camera
                    ASSERT_LE(dot(normal, position - scene.camera.position), 1e-4f) << what;
                for (int c = 0; c < 3; ++c) {
                    const float albedo = f.albedo->pixels[p * 3 + c],
                                beauty = f.beauty.pixels[p * 3 + c],
                                specular = f.specular->pixels[p * 3 + c];
                    ASSERT_TRUE(albedo >= 0.0f && albedo <= 1.0f) << what;
                    ASSERT_TRUE(std::isfinite(beauty) && beauty >= 0.0f) << what;
                    ASSERT_TRUE(specular >= 0.0f && specular <= beauty * (1.0f + 1e-4f) + 1e-6f)
                        << what;
                }
                ASSERT_TRUE(f.roughness->pixels[p] >= 0.0f && f.roughness->pixels[p] <= 1.0f)
                    << what;
                ASSERT_TRUE(std::isfinite(f.depth.pixels[p]) &&
                            std::isfinite(f.hitDistance->pixels[p]))
                    << what;
            }
            double sum = 0.0;
            for (float v : f.beauty.pixels) sum += v;
            EXPECT_GT(sum, 0.0) << what << ": black";
        }
    }
}

TEST(RandomScene, SequenceIsDeterministicAndSceneJsonRecordsTheDraw) {
    test::TempFolder dir("render-random");
    RenderSettings settings;
    settings.width = 24;
    settings.height = 16;
    settings.frames = 2;
    settings.referenceSpp = 2;
    settings.seed = 31;
    renderSequence("random", settings, dir.path() / "a");
    renderSequence("random", settings, dir.path() / "b");
    for (const char* file : {"beauty_1.exr", "normal_1.exr", "ID_1.exr", "matrix_1.mat",
                             "reference/reference_1.exr", "scene.json"})
        EXPECT_EQ(fileBytes(dir.path() / "a" / file), fileBytes(dir.path() / "b" / file)) << file;
    const std::string json = fileBytes(dir.path() / "a" / "scene.json");
    for (const char* key :
         {"\"scene\": \"random\"", "\"generator\": {", "\"version\": \"random-scene 1\"",
          "\"seed\": 31", "\"tags\": [", "\"exposure\""})
        EXPECT_NE(json.find(key), std::string::npos) << key << " in\n" << json;
    EXPECT_EQ(Sequence(dir.path() / "a").frameCount(), 2);
    settings.seed = 32;
    renderSequence("random", settings, dir.path() / "c");
    EXPECT_NE(fileBytes(dir.path() / "a" / "scene.json"),
              fileBytes(dir.path() / "c" / "scene.json"));
}

// ---- the command ----

// The confidence images of frames 0..frames-1 of `scene` rendered with --confidence.
std::vector<Image> renderConfidence(const std::string& scene, int size, int frames) {
    test::TempFolder dir("confidence-" + scene);
    RenderSettings r;
    r.width = r.height = size;
    r.frames = frames;
    r.gbufferOnly = true;
    r.confidence = true;
    renderSequence(scene, r, dir.path());
    std::vector<Image> out;
    for (int i = 0; i < frames; ++i)
        out.push_back(readExr(dir.path() / fmt::format("confidence_{}.exr", i), {{"Y"}}));
    return out;
}

// switching-light's ceiling light goes off at frame 6: the history of what it lit is stale
// there, and only there. "What it lit": pixels that keep under 25% of their light (frames 5 and 6
// at 16 spp, 3x3 box); elsewhere the orbiting light, which moves a little each frame, dominates.
TEST(Confidence, DropsOnTheFrameTheLightSwitchesAndStaysNearOneElsewhere) {
    constexpr int kSize = 48;
    const std::vector<Image> confidence = renderConfidence("switching-light", kSize, 8);
    TraceSettings t;
    t.width = t.height = kSize;
    t.samplesPerPixel = 16;
    const Image on = renderRadiance(buildScene("switching-light", 5), t);
    const Image off = renderRadiance(buildScene("switching-light", 6), t);
    auto boxLuminance = [&](const Image& image, int x, int y) {
        double sum = 0.0;
        for (int dy = -1; dy <= 1; ++dy)
            for (int dx = -1; dx <= 1; ++dx) {
                const int sx = std::clamp(x + dx, 0, kSize - 1),
                          sy = std::clamp(y + dy, 0, kSize - 1);
                sum += luminance({image.at(sx, sy, 0), image.at(sx, sy, 1), image.at(sx, sy, 2)});
            }
        return sum;
    };
    for (float v : confidence[0].pixels) ASSERT_EQ(v, 1.0f);  // frame 0: no history
    for (int i = 1; i < 8; ++i) {
        for (float v : confidence[i].pixels) ASSERT_TRUE(v >= 0.0f && v <= 1.0f);
        double litSum = 0.0;
        int lit = 0;
        for (int y = 0; y < kSize; ++y)
            for (int x = 0; x < kSize; ++x)
                if (boxLuminance(off, x, y) < 0.25 * boxLuminance(on, x, y)) {
                    litSum += confidence[i].at(x, y);
                    ++lit;
                }
        ASSERT_GT(lit, kSize * kSize / 4);  // the ceiling light lights most of the room
        const double litMean = litSum / lit;
        if (i == 6) {
            // gain 1: confidence is about the share of the light kept, under 25% here.
            EXPECT_LT(litMean, 0.3) << "frame " << i;
        } else if (i == 7) {
            // Lit by the orbiting light alone, the room's lighting changes by a fifth a frame.
            EXPECT_GT(test::meanValue(confidence[i]), 0.65) << "frame " << i;
        } else {
            EXPECT_GT(litMean, 0.85) << "frame " << i;
            EXPECT_GT(test::meanValue(confidence[i]), 0.85) << "frame " << i;
        }
    }
}

// Nothing changes: last frame's sample re-shaded is the same path (the same random numbers),
// so noise cannot lower the confidence; the furnace through renderSequence, and a still frame of
// switching-light through historyConfidence.
TEST(Confidence, IsOneWhereNothingChanges) {
    for (const Image& image : renderConfidence("furnace", 48, 3))
        for (float v : image.pixels) ASSERT_EQ(v, 1.0f);
    const Scene still = buildScene("switching-light", 2);
    TraceSettings t;
    t.width = 48;
    t.height = 40;
    t.frameIndex = 3;
    const Frame gbuffer = renderGBuffer(still, t.width, t.height);
    const Image c = historyConfidence(still, still, gbuffer, t);
    ASSERT_EQ(c.width, 48);
    ASSERT_EQ(c.height, 40);
    EXPECT_EQ(test::meanValue(c), 1.0);
}

using test::CliResult;
using test::runCli;

TEST(RenderCli, ListsTheScenes) {
    CliResult r = runCli("render --list");
    EXPECT_EQ(r.exitCode, 0) << r.output;
    for (const SceneInfo& info : listScenes()) {
        EXPECT_NE(r.output.find(info.name), std::string::npos) << r.output;
        EXPECT_NE(r.output.find(info.description), std::string::npos) << r.output;
    }
}

TEST(RenderCli, RendersASequenceAndRejectsBadArguments) {
    test::TempFolder dir("render-cli");
    std::string out = "'" + (dir.path() / "out").string() + "'";
    CliResult r =
        runCli("render thin-geometry -o " + out + " --width 24 --height 16 --frames 2 --ref-spp 2");
    ASSERT_EQ(r.exitCode, 0) << r.output;
    EXPECT_NE(r.output.find("Mpaths/s"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("frame 2/2"), std::string::npos) << r.output;
    EXPECT_EQ(Sequence(dir.path() / "out").frameCount(), 2);
    EXPECT_TRUE(fs::exists(dir.path() / "out" / "reference" / "reference_1.exr"));
    EXPECT_TRUE(fs::exists(dir.path() / "out" / "scene.json"));

    r = runCli("render teapot -o " + out);
    EXPECT_NE(r.exitCode, 0);
    EXPECT_NE(r.output.find("teapot"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("moving-objects"), std::string::npos) << r.output;
    for (const char* bad : {"--width 0", "--frames -1", "--spp abc", "--ref-spp 0"}) {
        r = runCli("render furnace -o " + out + " " + bad);
        EXPECT_NE(r.exitCode, 0) << bad;
    }
    r = runCli("render reflections -o " + out +
               " --width 8 --height 6 --frames 1 --gbuffer-only --split");
    ASSERT_EQ(r.exitCode, 0) << r.output;
    EXPECT_TRUE(fs::exists(dir.path() / "out" / "specular_0.exr"));
    EXPECT_TRUE(fs::exists(dir.path() / "out" / "hit_distance_0.exr"));
    r = runCli("render reflections -o " + out + " --split --format multilayer");
    EXPECT_NE(r.exitCode, 0);
    r = runCli("render -o " + out);  // no scene
    EXPECT_NE(r.exitCode, 0);
    EXPECT_NE(r.output.find("furnace"), std::string::npos) << r.output;
}

TEST(RenderCli, DescribesAndRendersAGeneratedScene) {
    CliResult r = runCli("render random --seed 5 --describe");
    ASSERT_EQ(r.exitCode, 0) << r.output;
    for (const char* key :
         {"\"version\": \"random-scene 1\"", "\"seed\": 5", "\"tags\"", "\"camera\""})
        EXPECT_NE(r.output.find(key), std::string::npos) << key << " in\n" << r.output;
    EXPECT_EQ(r.output, runCli("render random --seed 5 --describe").output);
    EXPECT_NE(r.output, runCli("render random --seed 6 --describe").output);
    r = runCli("render --list");
    EXPECT_NE(r.output.find("random"), std::string::npos) << r.output;
    test::TempFolder dir("render-cli-random");
    r = runCli("render random --seed 5 -q --width 16 --height 12 --frames 2 --ref-spp 2 -o '" +
               (dir.path() / "out").string() + "'");
    ASSERT_EQ(r.exitCode, 0) << r.output;
    EXPECT_EQ(Sequence(dir.path() / "out").frameCount(), 2);
    EXPECT_NE(fileBytes(dir.path() / "out" / "scene.json").find("\"generator\""),
              std::string::npos);
}

}  // namespace
}  // namespace rtd::render
