// Blender multilayer input: the committed Cycles fixture (tests/data/blender, made by
// scripts/blender/make_fixture.py) read as Frames, `render --format multilayer` read back
// against the folder layout of the same render, and every way a Blender sequence can be broken.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "metrics/metrics.h"
#include "render/render_sequence.h"
#include "rtdenoise/io.h"
#include "rtdenoise/rtdenoise.hpp"
#include "test_support.h"

namespace fs = std::filesystem;

namespace rtd {
namespace {

using test::quoted;
using test::runCli;

const fs::path kFixture = fs::path(RTD_SOURCE_DIR) / "tests" / "data" / "blender";
constexpr int kFixtureFrames = 4;
constexpr int kFixtureFirstFrame = 1;
constexpr int kMovingCubeIndex = 3;  // the script's pass_index of the moving cube

std::string messageOf(const std::function<void()>& action) {
    try {
        action();
    } catch (const Error& e) {
        return e.what();
    }
    return "(no error)";
}

bool contains(const std::string& text, const std::string& part) {
    return text.find(part) != std::string::npos;
}

int occurrences(const std::string& text, const std::string& part) {
    int count = 0;
    for (std::size_t at = text.find(part); at != std::string::npos; at = text.find(part, at + 1))
        ++count;
    return count;
}

// ---- multilayer files rewritten for the tests ----

// Every channel of an EXR as a 1-channel image, by name.
std::map<std::string, Image> readAllChannels(const fs::path& file) {
    const ExrContents contents = readExrContents(file);
    std::vector<ChannelChoices> choices;
    for (const std::string& name : contents.channels) choices.push_back({{name}});
    std::vector<Image> images = readExrImages(file, choices);
    std::map<std::string, Image> channels;
    for (std::size_t i = 0; i < images.size(); ++i)
        channels.emplace(contents.channels[i], std::move(images[i]));
    return channels;
}

void writeAllChannels(const fs::path& file, const std::map<std::string, Image>& channels) {
    std::vector<ExrChannelGroup> groups;
    for (const auto& [name, image] : channels) groups.push_back({&image, {name}, false});
    writeExrChannels(file, groups);
}

// The pass of a channel name "layer.pass.component".
std::string passOf(const std::string& channel) {
    const std::size_t last = channel.rfind('.');
    const std::size_t middle = channel.rfind('.', last - 1);
    return channel.substr(middle + 1, last - middle - 1);
}

// The fixture's frames copied into `folder` as <prefix><number, padded to digits>.exr, numbered
// from `first`; `edit(index, channels)` may change a frame's channels first.
void copyFixture(const fs::path& folder,
                 const std::function<void(int, std::map<std::string, Image>&)>& edit = {},
                 int first = kFixtureFirstFrame, const std::string& prefix = "", int digits = 4) {
    fs::create_directories(folder);
    for (int i = 0; i < kFixtureFrames; ++i) {
        const fs::path source = kFixture / "noisy" / fmt::format("{:04d}.exr", i + 1);
        const fs::path target = folder / fmt::format("{}{:0{}d}.exr", prefix, first + i, digits);
        if (!edit) {
            fs::copy_file(source, target, fs::copy_options::overwrite_existing);
            continue;
        }
        std::map<std::string, Image> channels = readAllChannels(source);
        edit(i, channels);
        writeAllChannels(target, channels);
    }
}

// An edit that drops `pass` from the frames of the given indices (all when empty).
std::function<void(int, std::map<std::string, Image>&)> withoutPass(const std::string& pass,
                                                                    std::set<int> frames = {}) {
    return [pass, frames](int index, std::map<std::string, Image>& channels) {
        if (!frames.empty() && !frames.count(index)) return;
        std::erase_if(channels, [&](const auto& entry) { return passOf(entry.first) == pass; });
    };
}

// An edit that drops the channels of `pass` with the given components ("Z") from the frames of
// the given indices (all when empty).
std::function<void(int, std::map<std::string, Image>&)> withoutChannels(
    const std::string& pass, const std::string& components, std::set<int> frames = {}) {
    return [pass, components, frames](int index, std::map<std::string, Image>& channels) {
        if (!frames.empty() && !frames.count(index)) return;
        std::erase_if(channels, [&](const auto& entry) {
            return passOf(entry.first) == pass &&
                   components.find(entry.first.back()) != std::string::npos;
        });
    };
}

// An edit that crops frame `frame`'s channels to their top-left width x height pixels.
std::function<void(int, std::map<std::string, Image>&)> croppedTo(int frame, int width,
                                                                  int height) {
    return [frame, width, height](int index, std::map<std::string, Image>& channels) {
        if (index != frame) return;
        for (auto& [name, image] : channels) {
            Image cropped(width, height, image.channels);
            for (int y = 0; y < height; ++y)
                for (int x = 0; x < width; ++x)
                    for (int c = 0; c < image.channels; ++c)
                        cropped.at(x, y, c) = image.at(x, y, c);
            image = std::move(cropped);
        }
    };
}

// ---- the fixture's matrices (matrices.txt, written by the script) ----

using Matrix4d = std::array<std::array<double, 4>, 4>;

struct FixtureFrame {
    Matrix4d worldToScreen{};
    std::array<double, 3> camera{};
    std::map<int, Matrix4d> objectToWorld;  // by pass_index
};

std::map<int, FixtureFrame> readFixtureMatrices() {
    std::ifstream in(kFixture / "matrices.txt");
    std::map<int, FixtureFrame> frames;
    std::string line;
    const auto readMatrix = [](std::istringstream& s) {
        Matrix4d m{};
        for (auto& row : m)
            for (double& v : row) s >> v;
        return m;
    };
    while (std::getline(in, line)) {
        if (line.empty() || line[0] == '#') continue;
        std::istringstream s(line);
        int frame = 0;
        std::string kind;
        s >> frame >> kind;
        if (kind == "screen") frames[frame].worldToScreen = readMatrix(s);
        if (kind == "camera")
            s >> frames[frame].camera[0] >> frames[frame].camera[1] >> frames[frame].camera[2];
        if (kind == "object") {
            int passIndex = 0;
            s >> passIndex;
            frames[frame].objectToWorld[passIndex] = readMatrix(s);
        }
    }
    return frames;
}

std::array<double, 4> transformPoint(const Matrix4d& m, const std::array<double, 4>& p) {
    std::array<double, 4> r{};
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j) r[i] += m[i][j] * p[j];
    return r;
}

// The inverse of an affine matrix (rotation-scale and translation, last row 0 0 0 1).
Matrix4d affineInverse(const Matrix4d& m) {
    const auto a = [&m](int r, int c) { return m[r][c]; };
    const double det = a(0, 0) * (a(1, 1) * a(2, 2) - a(1, 2) * a(2, 1)) -
                       a(0, 1) * (a(1, 0) * a(2, 2) - a(1, 2) * a(2, 0)) +
                       a(0, 2) * (a(1, 0) * a(2, 1) - a(1, 1) * a(2, 0));
    Matrix4d r{};
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) {
            const int i1 = (j + 1) % 3, i2 = (j + 2) % 3, j1 = (i + 1) % 3, j2 = (i + 2) % 3;
            r[i][j] = (a(i1, j1) * a(i2, j2) - a(i1, j2) * a(i2, j1)) / det;
        }
    for (int i = 0; i < 3; ++i)
        r[i][3] = -(r[i][0] * m[0][3] + r[i][1] * m[1][3] + r[i][2] * m[2][3]);
    r[3][3] = 1.0;
    return r;
}

Matrix4d toDouble(const Matrix4& m) {
    Matrix4d r{};
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j) r[i][j] = m.m[i][j];
    return r;
}

// previous - current on screen of the point at `position` of an object whose local-to-world is
// `model` now and `previousModel` in the other frame.
std::array<double, 2> backProjectionMotion(const std::array<double, 4>& position,
                                           const Matrix4d& worldToScreen, const Matrix4d& model,
                                           const Matrix4d& previousWorldToScreen,
                                           const Matrix4d& previousModel) {
    const auto now = transformPoint(worldToScreen, position);
    const auto local = transformPoint(affineInverse(model), position);
    const auto before = transformPoint(previousWorldToScreen, transformPoint(previousModel, local));
    return {before[0] / before[3] - now[0] / now[3], before[1] / before[3] - now[1] / now[3]};
}

// ---- the fixture's quality, for the end-to-end test once the denoiser uses motion ----

// Mean relMSE over the fixture's frames of `images` (one per frame, in order) against
// tests/data/blender/reference.
double fixtureRelMse(const std::vector<Image>& images) {
    double sum = 0.0;
    for (std::size_t i = 0; i < images.size(); ++i) {
        const fs::path file = kFixture / "reference" / fmt::format("{:04d}.exr", i + 1);
        sum += metrics::relMse(images[i], readExr(file, colourChannelsOf(file)));
    }
    return sum / double(images.size());
}

// ---- the fixture ----

TEST(BlenderFixture, IsFoundAsABlenderSequenceWithEveryPass) {
    const std::unique_ptr<FrameSource> source = openFrameSource(kFixture / "noisy");
    const auto* blender = dynamic_cast<const BlenderSequence*>(source.get());
    ASSERT_NE(blender, nullptr) << source->describe();
    EXPECT_EQ(blender->frameCount(), kFixtureFrames);
    EXPECT_EQ(blender->files().first, kFixtureFirstFrame);
    EXPECT_EQ(blender->files().digits, 4);
    EXPECT_EQ(blender->viewLayer(), "ViewLayer");
    EXPECT_EQ(blender->colourPass(), "Combined");  // denoising was off: no Noisy Image
    EXPECT_TRUE(blender->hasObjectIndex());
    EXPECT_TRUE(blender->hasAlbedo());
    EXPECT_TRUE(blender->hasMotion());
    EXPECT_TRUE(blender->warnings().empty());
    EXPECT_EQ(blender->backProjectionProblem(), "");
    EXPECT_EQ(blender->frameFile(0), kFixture / "noisy" / "0001.exr");
    const std::vector<ExrSize> sizes = blender->checkFrames(kFixtureFrames);
    ASSERT_EQ(sizes.size(), std::size_t(kFixtureFrames));
    for (const ExrSize& size : sizes) {
        EXPECT_EQ(size.width, 64);
        EXPECT_EQ(size.height, 48);
    }
}

TEST(BlenderFixture, FramesHoldTheGBufferAsImageHDocumentsIt) {
    const BlenderSequence sequence(kFixture / "noisy");
    for (int index = 0; index < kFixtureFrames; ++index) {
        SCOPED_TRACE(index);
        const Frame frame = sequence.readFrame(index);
        ASSERT_EQ(frame.width(), 64);
        ASSERT_EQ(frame.height(), 48);
        EXPECT_EQ(frame.beauty.channels, 3);
        EXPECT_EQ(frame.normal.channels, 3);
        EXPECT_EQ(frame.position.channels, 3);
        EXPECT_EQ(frame.depth.channels, 1);
        ASSERT_TRUE(frame.albedo);
        ASSERT_TRUE(frame.motion);
        EXPECT_EQ(frame.motion->channels, 2);
        EXPECT_EQ(frame.depthKind, DepthKind::ViewZ);
        EXPECT_TRUE(frame.objectToWorld.empty());
        // The floor, the room (walls and ceiling), the sphere and the cube have pass_index 0..3.
        EXPECT_EQ(frame.objectCount, 4);

        const fs::path file = sequence.frameFile(index);
        const Image rawDepth = readExr(file, {{"ViewLayer.Depth.Z"}});
        std::set<int> ids;
        int background = 0;
        for (std::size_t i = 0; i < frame.objectId.size(); ++i) {
            const int id = frame.objectId[i];
            ids.insert(id);
            const bool miss = rawDepth.pixels[i] == kCyclesMissDepth;
            ASSERT_EQ(id == -1, miss) << "pixel " << i;
            if (miss) {
                ++background;
                EXPECT_EQ(frame.depth.pixels[i], 0.0f);
                for (int c = 0; c < 3; ++c) EXPECT_EQ(frame.normal.pixels[i * 3 + c], 0.0f);
                continue;
            }
            EXPECT_EQ(frame.depth.pixels[i], rawDepth.pixels[i]);
            const float* n = &frame.normal.pixels[i * 3];
            EXPECT_NEAR(std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]), 1.0f, 1e-3f);
        }
        EXPECT_GT(background, 64 * 4);  // the sky through the window in the back wall
        EXPECT_EQ(ids, (std::set<int>{-1, 0, 1, 2, 3}));
    }
}

// Depth is the distance from the camera plane: the w of the script's worldToScreen (the camera's
// -z), not the distance from the camera.
TEST(BlenderFixture, DepthIsViewDepthNotRayDistance) {
    const std::map<int, FixtureFrame> matrices = readFixtureMatrices();
    const BlenderSequence sequence(kFixture / "noisy");
    const Frame frame = sequence.readFrame(1);
    const FixtureFrame& m = matrices.at(kFixtureFirstFrame + 1);
    double worstViewZ = 0.0, smallestRayGap = 1e9;
    for (std::size_t i = 0; i < frame.objectId.size(); ++i) {
        if (frame.objectId[i] < 0) continue;
        const std::array<double, 4> p{frame.position.pixels[i * 3],
                                      frame.position.pixels[i * 3 + 1],
                                      frame.position.pixels[i * 3 + 2], 1.0};
        const double w = transformPoint(m.worldToScreen, p)[3];
        const double ray = std::hypot(p[0] - m.camera[0], p[1] - m.camera[1], p[2] - m.camera[2]);
        worstViewZ = std::max(worstViewZ, std::abs(frame.depth.pixels[i] - w) / w);
        // Off the image centre a ray is longer than its view depth.
        const std::size_t x = i % 64;
        if (x < 8 || x >= 56) smallestRayGap = std::min(smallestRayGap, ray - w);
    }
    EXPECT_LT(worstViewZ, 1e-5);
    EXPECT_GT(smallestRayGap, 0.05);
}

// The Vector pass, converted, is where each pixel's point was in the previous frame: the
// back-projection through the script's own matrices (camera pan, moving cube).
TEST(BlenderFixture, MotionMatchesTheScriptsMatrices) {
    const std::map<int, FixtureFrame> matrices = readFixtureMatrices();
    const BlenderSequence sequence(kFixture / "noisy");
    for (int index = 0; index < kFixtureFrames; ++index) {
        SCOPED_TRACE(index);
        const Frame frame = sequence.readFrame(index);
        const FixtureFrame& now = matrices.at(kFixtureFirstFrame + index);
        const FixtureFrame& before = matrices.at(kFixtureFirstFrame + index - 1);
        double worst = 0.0, cubeMotionX = 0.0, wallMotionX = 0.0;
        int cubePixels = 0, wallPixels = 0;
        for (std::size_t i = 0; i < frame.objectId.size(); ++i) {
            const int id = frame.objectId[i];
            if (id < 0) continue;
            const std::array<double, 4> p{frame.position.pixels[i * 3],
                                          frame.position.pixels[i * 3 + 1],
                                          frame.position.pixels[i * 3 + 2], 1.0};
            const auto expected =
                backProjectionMotion(p, now.worldToScreen, now.objectToWorld.at(id),
                                     before.worldToScreen, before.objectToWorld.at(id));
            const float mx = frame.motion->pixels[i * 2], my = frame.motion->pixels[i * 2 + 1];
            worst = std::max({worst, std::abs(mx - expected[0]), std::abs(my - expected[1])});
            if (id == kMovingCubeIndex) {
                cubeMotionX += mx;
                ++cubePixels;
            } else if (id == 1) {
                wallMotionX += mx;
                ++wallPixels;
            }
        }
        EXPECT_LT(worst, 1e-3);
        ASSERT_GT(cubePixels, 20);
        ASSERT_GT(wallPixels, 20);
        // The cube slides right, so it came from further left than the walls behind it did.
        EXPECT_LT(cubeMotionX / cubePixels, wallMotionX / wallPixels - 0.5);
    }
}

TEST(BlenderFixture, RelMseHelperScoresTheNoisyInput) {
    const BlenderSequence sequence(kFixture / "noisy");
    std::vector<Image> inputs;
    for (int i = 0; i < kFixtureFrames; ++i) inputs.push_back(sequence.readFrame(i).beauty);
    const double input = fixtureRelMse(inputs);
    EXPECT_GT(input, 0.5);  // 1 spp of a room lit mostly by bounced light is very noisy
    EXPECT_TRUE(std::isfinite(input));
}

// End to end: Blender's passes (motion from its Vector pass, no matrices) denoised by every
// method, scored against the fixture's 4096-spp reference. The figures:
// tests/data/blender/README.md.
TEST(BlenderFixture, DenoisingBeatsTheInput) {
    const BlenderSequence sequence(kFixture / "noisy");
    std::vector<Image> inputs;
    std::vector<Frame> frames;
    for (int i = 0; i < kFixtureFrames; ++i) {
        frames.push_back(sequence.readFrame(i));
        inputs.push_back(frames.back().beauty);
    }
    const double input = fixtureRelMse(inputs);
    double svgf = 0.0;
    for (Method method : {Method::Jbf, Method::Atrous, Method::Temporal, Method::Svgf}) {
        Denoiser denoiser(test::cpuSettings(method));
        std::vector<Image> outputs;
        for (const Frame& frame : frames) outputs.push_back(denoiser.processFrame(frame));
        const double error = fixtureRelMse(outputs);
        std::printf("%-8s relMSE %.4f (input %.4f)\n", toString(method), error, input);
        EXPECT_LT(error, 0.8 * input) << toString(method);
        if (method == Method::Svgf) svgf = error;
    }
    EXPECT_LT(svgf, 0.5 * input);
    // The history helps: svgf without motion (every frame its first) is worse.
    Denoiser noHistory(test::cpuSettings(Method::Svgf));
    std::vector<Image> firstFrames;
    for (const Frame& frame : frames) {
        noHistory.reset();
        firstFrames.push_back(noHistory.processFrame(frame));
    }
    EXPECT_LT(svgf, fixtureRelMse(firstFrames));
}

TEST(BlenderFixture, ItsReferenceIsReadByCompare) {
    test::TempFolder dir("blender-compare");
    fs::create_directories(dir.path() / "out");
    for (int i = 0; i < kFixtureFrames; ++i)
        writeExr(dir.path() / "out" / fmt::format("result_{}.exr", i),
                 readExr(kFixture / "reference" / fmt::format("{:04d}.exr", i + 1),
                         {{"R"}, {"G"}, {"B"}}));
    const test::CliResult r =
        runCli("compare " + quoted(dir.path() / "out") + " " + quoted(kFixture / "reference"));
    EXPECT_EQ(r.exitCode, 0) << r.output;
    EXPECT_TRUE(contains(r.output, "inf")) << r.output;  // identical frames
}

// ---- render --format multilayer ----

struct TwoLayouts {
    std::vector<Frame> folder;  // with matrices, no motion
    std::vector<Frame> multilayer;
    fs::path multilayerDir;
};

TwoLayouts renderBothLayouts(const test::TempFolder& dir, const std::string& scene) {
    render::RenderSettings settings;
    settings.width = 48;
    settings.height = 32;
    settings.frames = 3;
    settings.gbufferOnly = true;
    render::renderSequence(scene, settings, dir.path() / "folder");
    settings.format = render::OutputFormat::Multilayer;
    render::renderSequence(scene, settings, dir.path() / "multilayer");
    TwoLayouts out;
    out.multilayerDir = dir.path() / "multilayer";
    const Sequence folder(dir.path() / "folder");
    const std::unique_ptr<FrameSource> multilayer = openFrameSource(out.multilayerDir);
    EXPECT_NE(dynamic_cast<const BlenderSequence*>(multilayer.get()), nullptr);
    EXPECT_EQ(multilayer->frameCount(), settings.frames);
    for (int i = 0; i < settings.frames; ++i) {
        out.folder.push_back(folder.readFrame(i));
        out.multilayer.push_back(multilayer->readFrame(i));
    }
    return out;
}

void expectSameImage(const Image& a, const Image& b, const char* what) {
    ASSERT_EQ(a.width, b.width) << what;
    ASSERT_EQ(a.height, b.height) << what;
    ASSERT_EQ(a.channels, b.channels) << what;
    EXPECT_EQ(a.pixels, b.pixels) << what;
}

TEST(MultilayerRender, ReadsBackAsTheFolderLayoutsFrames) {
    for (const std::string scene : {"moving-objects", "camera-pan"}) {
        SCOPED_TRACE(scene);
        test::TempFolder dir("multilayer-" + scene);
        const TwoLayouts both = renderBothLayouts(dir, scene);
        for (std::size_t i = 0; i < both.folder.size(); ++i) {
            SCOPED_TRACE(i);
            const Frame& a = both.folder[i];
            const Frame& b = both.multilayer[i];
            expectSameImage(a.beauty, b.beauty, "beauty");
            expectSameImage(a.normal, b.normal, "normal");
            expectSameImage(a.depth, b.depth, "depth");
            ASSERT_TRUE(a.albedo && b.albedo);
            expectSameImage(*a.albedo, *b.albedo, "albedo");
            EXPECT_EQ(a.objectId, b.objectId);
            EXPECT_EQ(b.depthKind, DepthKind::ViewZ);
            int largest = -1;
            for (int id : a.objectId) largest = std::max(largest, id);
            EXPECT_EQ(b.objectCount, largest + 1);
            // Position: the folder layout holds the camera position on background, Cycles 0.
            for (std::size_t p = 0; p < a.objectId.size(); ++p)
                for (int c = 0; c < 3; ++c)
                    ASSERT_EQ(b.position.pixels[p * 3 + c],
                              a.objectId[p] < 0 ? 0.0f : a.position.pixels[p * 3 + c])
                        << "pixel " << p;
        }
    }
}

// The motion read back is the back-projection of shared/data/README.md through the folder
// layout's matrices; Vector's Z, W (to the next frame, Blender's sign) likewise.
TEST(MultilayerRender, MotionIsTheMatricesBackProjection) {
    for (const std::string scene : {"moving-objects", "camera-pan"}) {
        SCOPED_TRACE(scene);
        test::TempFolder dir("multilayer-motion-" + scene);
        const TwoLayouts both = renderBothLayouts(dir, scene);
        for (std::size_t i = 0; i < both.folder.size(); ++i) {
            SCOPED_TRACE(i);
            const Frame& now = both.folder[i];
            ASSERT_TRUE(both.multilayer[i].motion);
            const Image& motion = *both.multilayer[i].motion;
            const Image vector = readExr(both.multilayerDir / fmt::format("{:04d}.exr", i + 1),
                                         {{"ViewLayer.Vector.Z"}, {"ViewLayer.Vector.W"}});
            double worst = 0.0, largest = 0.0;
            for (std::size_t p = 0; p < now.objectId.size(); ++p) {
                const int id = now.objectId[p];
                if (id < 0) continue;
                const std::array<double, 4> position{now.position.pixels[p * 3],
                                                     now.position.pixels[p * 3 + 1],
                                                     now.position.pixels[p * 3 + 2], 1.0};
                const auto towards = [&](const Frame& other) {
                    return backProjectionMotion(
                        position, toDouble(now.worldToScreen), toDouble(now.objectToWorld[id]),
                        toDouble(other.worldToScreen), toDouble(other.objectToWorld[id]));
                };
                if (i > 0) {
                    const auto expected = towards(both.folder[i - 1]);
                    worst = std::max({worst, std::abs(motion.pixels[p * 2] - expected[0]),
                                      std::abs(motion.pixels[p * 2 + 1] - expected[1])});
                    largest = std::max(largest, std::hypot(expected[0], expected[1]));
                }
                if (i + 1 < both.folder.size()) {
                    const auto next = towards(both.folder[i + 1]);  // next - current, y down
                    worst = std::max({worst, std::abs(vector.pixels[p * 2] + next[0]),
                                      std::abs(vector.pixels[p * 2 + 1] - next[1])});
                }
            }
            EXPECT_LT(worst, 1e-3);
            if (i > 0) EXPECT_GT(largest, 0.5);  // the scene really moves
        }
    }
}

// Every built-in scene is a test of the Blender path: its multilayer render (motion from the
// Vector pass, no matrices, no depth change) denoises as its folder layout (the matrices) does.
TEST(MultilayerRender, EveryScenesMotionDenoisesAsItsMatrices) {
    for (const render::SceneInfo& info : render::listScenes()) {
        SCOPED_TRACE(info.name);
        test::TempFolder dir("multilayer-denoise-" + info.name);
        const TwoLayouts both = renderBothLayouts(dir, info.name);
        for (Method method : {Method::Temporal, Method::Svgf}) {
            Denoiser matrices(test::cpuSettings(method)), motion(test::cpuSettings(method));
            for (std::size_t i = 0; i < both.folder.size(); ++i) {
                const Image a = matrices.processFrame(both.folder[i]);
                const Image b = motion.processFrame(both.multilayer[i]);
                const double difference = metrics::relMse(b, a);
                EXPECT_LT(difference, 1e-3) << toString(method) << " frame " << i;
            }
        }
    }
}

TEST(MultilayerRender, CliWritesItAndCompareReadsItsReference) {
    test::TempFolder dir("multilayer-cli");
    const fs::path out = dir.path() / "scene";
    test::CliResult r = runCli(
        "render moving-objects -q --width 32 --height 24 --frames 2 "
        "--ref-spp 4 --format multilayer -o " +
        quoted(out));
    ASSERT_EQ(r.exitCode, 0) << r.output;
    EXPECT_TRUE(fs::exists(out / "0001.exr"));
    EXPECT_TRUE(fs::exists(out / "0002.exr"));
    EXPECT_TRUE(fs::exists(out / "reference" / "0002.exr"));
    EXPECT_FALSE(fs::exists(out / "beauty_0.exr"));
    fs::create_directories(dir.path() / "results");
    for (int i = 0; i < 2; ++i)
        fs::copy_file(out / "reference" / fmt::format("{:04d}.exr", i + 1),
                      dir.path() / "results" / fmt::format("result_{}.exr", i));
    r = runCli("compare " + quoted(dir.path() / "results") + " " + quoted(out / "reference"));
    EXPECT_EQ(r.exitCode, 0) << r.output;
    EXPECT_TRUE(contains(r.output, "inf")) << r.output;

    // The folder layout into the same folder replaces the multilayer frames.
    r = runCli("render moving-objects -q --width 32 --height 24 --frames 2 --gbuffer-only -o " +
               quoted(out));
    ASSERT_EQ(r.exitCode, 0) << r.output;
    EXPECT_FALSE(fs::exists(out / "0001.exr"));
    EXPECT_TRUE(fs::exists(out / "beauty_1.exr"));
    r = runCli("render moving-objects --format exr -o " + quoted(out));
    EXPECT_NE(r.exitCode, 0);
}

// ---- broken sequences ----

class BlenderBroken : public ::testing::Test {
  protected:
    test::TempFolder dir{"blender-broken"};
};

TEST_F(BlenderBroken, EachMissingRequiredPassFailsNamingThePassAndTheFile) {
    for (const std::string pass : {"Combined", "Depth", "Normal", "Position"}) {
        SCOPED_TRACE(pass);
        // Missing from the first frame: found when the sequence is opened.
        const fs::path first = dir.path() / ("first-" + pass);
        copyFixture(first, withoutPass(pass, {0}));
        std::string message = messageOf([&] { BlenderSequence sequence(first); });
        EXPECT_TRUE(contains(message, "no " + pass + " pass")) << message;
        EXPECT_TRUE(contains(message, (first / "0001.exr").string())) << message;

        // Missing from a later frame: found by checkFrames, before any frame is denoised.
        const fs::path later = dir.path() / ("later-" + pass);
        copyFixture(later, withoutPass(pass, {2}));
        const BlenderSequence sequence(later);
        message = messageOf([&] { sequence.checkFrames(kFixtureFrames); });
        EXPECT_TRUE(contains(message, "no " + pass + " pass")) << message;
        EXPECT_TRUE(contains(message, (later / "0003.exr").string())) << message;
        message = messageOf([&] { sequence.readFrame(2); });
        EXPECT_TRUE(contains(message, "no " + pass + " pass")) << message;

        // The command fails before it writes anything.
        const fs::path output = dir.path() / ("out-" + pass);
        const test::CliResult r =
            runCli("denoise " + quoted(later) + " --method jbf -o " + quoted(output));
        EXPECT_NE(r.exitCode, 0);
        EXPECT_TRUE(contains(r.output, "no " + pass + " pass")) << r.output;
        EXPECT_TRUE(contains(r.output, "0003.exr")) << r.output;
        EXPECT_FALSE(fs::exists(output));
    }
}

TEST_F(BlenderBroken, AMissingAlbedoWarnsOnceAndReadsWithoutIt) {
    copyFixture(dir.path() / "in", withoutPass("Denoising Albedo"));
    const BlenderSequence sequence(dir.path() / "in");
    ASSERT_EQ(sequence.warnings().size(), 1u);
    EXPECT_TRUE(contains(sequence.warnings()[0], "no Denoising Albedo pass"));
    EXPECT_TRUE(contains(sequence.warnings()[0], "denoising_store_passes"));
    EXPECT_FALSE(sequence.readFrame(0).albedo);
    const test::CliResult r = runCli("denoise " + quoted(dir.path() / "in") + " --method jbf -o " +
                                     quoted(dir.path() / "out"));
    EXPECT_EQ(occurrences(r.output, "no Denoising Albedo pass"), 1) << r.output;
}

TEST_F(BlenderBroken, AMissingObjectIndexWarnsOnceAndMakesEveryObjectIdZero) {
    copyFixture(dir.path() / "in", withoutPass("IndexOB"));
    const BlenderSequence sequence(dir.path() / "in");
    ASSERT_EQ(sequence.warnings().size(), 1u);
    EXPECT_TRUE(contains(sequence.warnings()[0], "no IndexOB pass"));
    const Frame frame = sequence.readFrame(1);
    EXPECT_EQ(frame.objectCount, 1);
    EXPECT_EQ(std::set<int>(frame.objectId.begin(), frame.objectId.end()), (std::set<int>{-1, 0}));
    const test::CliResult r = runCli("denoise " + quoted(dir.path() / "in") + " --method jbf -o " +
                                     quoted(dir.path() / "out"));
    EXPECT_EQ(occurrences(r.output, "no IndexOB pass"), 1) << r.output;
}

TEST_F(BlenderBroken, WithoutVectorHistoryMethodsFailNamingThePass) {
    copyFixture(dir.path() / "in", withoutPass("Vector"));
    const BlenderSequence sequence(dir.path() / "in");
    EXPECT_FALSE(sequence.readFrame(0).motion);
    EXPECT_TRUE(sequence.warnings().empty());
    EXPECT_TRUE(contains(sequence.backProjectionProblem(), "no Vector pass"));
    for (const std::string method : {"svgf", "temporal"}) {
        const fs::path output = dir.path() / ("out-" + method);
        const test::CliResult r = runCli("denoise " + quoted(dir.path() / "in") + " --method " +
                                         method + " -o " + quoted(output));
        EXPECT_NE(r.exitCode, 0);
        EXPECT_TRUE(contains(r.output, "no Vector pass")) << r.output;
        EXPECT_TRUE(contains(r.output, (dir.path() / "in" / "0001.exr").string())) << r.output;
        EXPECT_TRUE(contains(r.output, "use_motion_blur")) << r.output;
        EXPECT_FALSE(fs::exists(output));
    }
    // A spatial method needs no history.
    const test::CliResult r = runCli("denoise " + quoted(dir.path() / "in") +
                                     " --method atrous -o " + quoted(dir.path() / "out"));
    EXPECT_FALSE(contains(r.output, "Vector")) << r.output;
}

// What Cycles writes with motion blur on: a Vector pass of zeros.
TEST_F(BlenderBroken, AVectorPassOfZerosWarnsOnce) {
    copyFixture(dir.path() / "in", [](int, std::map<std::string, Image>& channels) {
        for (auto& [name, image] : channels)
            if (passOf(name) == "Vector") std::fill(image.pixels.begin(), image.pixels.end(), 0.0f);
    });
    const BlenderSequence sequence(dir.path() / "in");
    ASSERT_EQ(sequence.warnings().size(), 1u);
    EXPECT_TRUE(contains(sequence.warnings()[0], "Vector pass is zero at every pixel"));
    EXPECT_TRUE(contains(sequence.warnings()[0], "0002.exr"));
    const test::CliResult r = runCli("denoise " + quoted(dir.path() / "in") + " --method jbf -o " +
                                     quoted(dir.path() / "out"));
    EXPECT_EQ(occurrences(r.output, "use_motion_blur"), 1) << r.output;
}

TEST_F(BlenderBroken, AnOptionalPassMissingFromALaterFrameIsAnError) {
    copyFixture(dir.path() / "in", withoutPass("Vector", {3}));
    const BlenderSequence sequence(dir.path() / "in");
    const std::string message = messageOf([&] { sequence.checkFrames(kFixtureFrames); });
    EXPECT_TRUE(contains(message, (dir.path() / "in" / "0004.exr").string())) << message;
    EXPECT_TRUE(contains(message, "no Vector pass")) << message;
}

// Issue 37 item 3: an optional pass the first frame lacks and later frames have is judged as one
// a later frame lacks (refused, naming the file and the pass), not dropped from every frame.
TEST_F(BlenderBroken, AnOptionalPassMissingFromTheFirstFrameOnlyIsAnError) {
    for (const std::string pass : {"IndexOB", "Denoising Albedo", "Vector"}) {
        SCOPED_TRACE(pass);
        const fs::path in = dir.path() / ("first-" + pass);
        copyFixture(in, withoutPass(pass, {0}));
        const BlenderSequence sequence(in);
        std::string message = messageOf([&] { sequence.checkFrames(kFixtureFrames); });
        EXPECT_TRUE(contains(message, (in / "0001.exr").string() + ": no " + pass + " pass"))
            << message;
        EXPECT_TRUE(contains(message, (in / "0002.exr").string())) << message;
        message = messageOf([&] { sequence.readFrame(1); });
        EXPECT_TRUE(contains(message, "no " + pass + " pass")) << message;

        // The command fails before it writes anything.
        const fs::path output = dir.path() / ("out-" + pass);
        const test::CliResult r =
            runCli("denoise " + quoted(in) + " --method jbf -o " + quoted(output));
        EXPECT_NE(r.exitCode, 0);
        EXPECT_TRUE(contains(r.output, "0001.exr: no " + pass + " pass")) << r.output;
        EXPECT_FALSE(fs::exists(output));
    }
}

// Issue 37 item 12: a pass with one channel missing names that channel, in the first frame or a
// later one; a Vector pass without Y is a broken file, not a render with motion blur on.
TEST_F(BlenderBroken, APartlyMissingPassNamesTheMissingChannel) {
    const fs::path normal = dir.path() / "normal-z";
    copyFixture(normal, withoutChannels("Normal", "Z"));
    std::string message = messageOf([&] { BlenderSequence sequence(normal); });
    EXPECT_TRUE(contains(message, (normal / "0001.exr").string())) << message;
    EXPECT_TRUE(contains(message, "no channel 'ViewLayer.Normal.Z'")) << message;
    EXPECT_FALSE(contains(message, "Normal.X")) << message;

    const fs::path laterNormal = dir.path() / "later-normal-z";
    copyFixture(laterNormal, withoutChannels("Normal", "Z", {2}));
    message = messageOf([&] { BlenderSequence(laterNormal).checkFrames(kFixtureFrames); });
    EXPECT_TRUE(contains(message, (laterNormal / "0003.exr").string())) << message;
    EXPECT_TRUE(contains(message, "no channel 'ViewLayer.Normal.Z'")) << message;

    const fs::path vector = dir.path() / "vector-y";
    copyFixture(vector, withoutChannels("Vector", "Y"));
    for (const std::string method : {"svgf", "jbf"}) {
        const fs::path output = dir.path() / ("out-" + method);
        const test::CliResult r =
            runCli("denoise " + quoted(vector) + " --method " + method + " -o " + quoted(output));
        EXPECT_NE(r.exitCode, 0) << method;
        EXPECT_TRUE(contains(r.output, (vector / "0001.exr").string())) << r.output;
        EXPECT_TRUE(contains(r.output, "no channel 'ViewLayer.Vector.Y'")) << r.output;
        EXPECT_FALSE(contains(r.output, "use_motion_blur")) << r.output;
        EXPECT_FALSE(fs::exists(output));
    }

    const fs::path laterVector = dir.path() / "later-vector-y";
    copyFixture(laterVector, withoutChannels("Vector", "Y", {3}));
    message = messageOf([&] { BlenderSequence(laterVector).checkFrames(kFixtureFrames); });
    EXPECT_TRUE(contains(message, (laterVector / "0004.exr").string())) << message;
    EXPECT_TRUE(contains(message, "no channel 'ViewLayer.Vector.Y'")) << message;
}

// Issue 37 item 14: a frame of another size restarts the history (by design); the command says so
// at that frame, naming the file and both sizes, and its summary counts the frames of each size.
TEST_F(BlenderBroken, AFrameOfAnotherSizeIsWarnedAboutAndSummarisedTruthfully) {
    const fs::path in = dir.path() / "in";
    copyFixture(in, croppedTo(2, 32, 24));
    const test::CliResult r =
        runCli("denoise " + quoted(in) + " --method svgf -o " + quoted(dir.path() / "out"));
    ASSERT_EQ(r.exitCode, 0) << r.output;
    EXPECT_TRUE(contains(r.output, "warning: " + (in / "0003.exr").string() +
                                       ": 32x24, but the frame before it is 64x48"))
        << r.output;
    EXPECT_TRUE(contains(r.output, "warning: " + (in / "0004.exr").string() +
                                       ": 64x48, but the frame before it is 32x24"))
        << r.output;
    EXPECT_EQ(occurrences(r.output, "the history restarts"), 2) << r.output;
    EXPECT_TRUE(contains(r.output, "4 frames (3 of 64x48, 1 of 32x24) in")) << r.output;
    EXPECT_EQ(readExr(dir.path() / "out" / "result_2.exr", {{"R"}, {"G"}, {"B"}}).width, 32);
    EXPECT_EQ(readExr(dir.path() / "out" / "result_3.exr", {{"R"}, {"G"}, {"B"}}).width, 64);

    // One size: the summary as before.
    const test::CliResult same = runCli("denoise " + quoted(kFixture / "noisy") +
                                        " --method jbf -o " + quoted(dir.path() / "out-same"));
    ASSERT_EQ(same.exitCode, 0) << same.output;
    EXPECT_TRUE(contains(same.output, "4 frames of 64x48 in")) << same.output;
    EXPECT_FALSE(contains(same.output, "history restarts")) << same.output;
}

// A Depth pass of NaN (a broken pass, not Cycles' miss value) or a Normal pass of zeros leaves
// the frame as noisy as it came: the run succeeds, but names the file and the pass at that frame.
TEST_F(BlenderBroken, AFrameWithoutUsableGeometryIsNamedWithItsPass) {
    const fs::path in = dir.path() / "in";
    copyFixture(in, [](int index, std::map<std::string, Image>& channels) {
        for (auto& [name, image] : channels) {
            if (index == 1 && passOf(name) == "Depth")
                for (float& v : image.pixels) v = std::nanf("");
            if (index == 2 && passOf(name) == "Normal")
                for (float& v : image.pixels) v = 0.0f;
        }
    });
    const test::CliResult r =
        runCli("denoise " + quoted(in) + " --method svgf -o " + quoted(dir.path() / "out"));
    ASSERT_EQ(r.exitCode, 0) << r.output;
    EXPECT_TRUE(contains(r.output, (in / "0002.exr").string() + ": ")) << r.output;
    EXPECT_TRUE(contains(r.output, "NaN or Inf depth or position")) << r.output;
    EXPECT_TRUE(contains(r.output, "(frame 1; is the depth pass broken?)")) << r.output;
    EXPECT_TRUE(contains(r.output, (in / "0003.exr").string() + ": ")) << r.output;
    EXPECT_TRUE(contains(r.output, "(frame 2; is the normal pass broken?)")) << r.output;
    EXPECT_FALSE(contains(r.output, "frame 0;")) << r.output;
    EXPECT_FALSE(contains(r.output, "frame 3;")) << r.output;
}

TEST_F(BlenderBroken, AGapInTheNumberingNamesTheMissingFile) {
    copyFixture(dir.path() / "in", {}, 7);  // 0007..0010
    EXPECT_EQ(BlenderSequence(dir.path() / "in").files().first, 7);
    fs::remove(dir.path() / "in" / "0009.exr");
    std::string message = messageOf([&] { BlenderSequence sequence(dir.path() / "in"); });
    EXPECT_TRUE(contains(message, (dir.path() / "in" / "0009.exr").string() + " is missing"))
        << message;
    message = messageOf([&] { BlenderSequence sequence(dir.path() / "in" / "####.exr"); });
    EXPECT_TRUE(contains(message, "0009.exr is missing")) << message;
    const test::CliResult r =
        runCli("denoise " + quoted(dir.path() / "in") + " -o " + quoted(dir.path() / "out"));
    EXPECT_NE(r.exitCode, 0);
    EXPECT_TRUE(contains(r.output, "0009.exr is missing")) << r.output;
}

TEST_F(BlenderBroken, NonIntegralObjectIndexFailsNamingThePixel) {
    copyFixture(dir.path() / "in", [](int index, std::map<std::string, Image>& channels) {
        if (index == 1) channels.at("ViewLayer.IndexOB.X").pixels[40 * 64 + 10] = 1.5f;
    });
    const BlenderSequence sequence(dir.path() / "in");
    const std::string message = messageOf([&] { sequence.readFrame(1); });
    EXPECT_TRUE(contains(message, "0002.exr: pixel (10, 40) holds IndexOB 1.5")) << message;
}

TEST_F(BlenderBroken, APlainExrIsNotAMultilayerFile) {
    fs::create_directories(dir.path() / "in");
    writeExr(dir.path() / "in" / "0001.exr", Image(4, 4, 3));
    const std::string message = messageOf([&] { BlenderSequence sequence(dir.path() / "in"); });
    EXPECT_TRUE(contains(message, "not a Blender multilayer EXR")) << message;
}

// ---- names, patterns, layers ----

TEST(BlenderNames, PrintfAndHashPatternsNameTheFrames) {
    test::TempFolder dir("blender-patterns");
    copyFixture(dir.path() / "padded", {}, 1, "frame_", 4);
    copyFixture(dir.path() / "plain", {}, 8, "shot.", 1);  // shot.8.exr .. shot.11.exr
    for (const std::string pattern : {"frame_%04d.exr", "frame_####.exr"}) {
        const std::unique_ptr<FrameSource> source =
            openFrameSource(dir.path() / "padded" / pattern);
        EXPECT_EQ(source->frameCount(), kFixtureFrames) << pattern;
        EXPECT_EQ(source->frameFile(3), dir.path() / "padded" / "frame_0004.exr") << pattern;
    }
    EXPECT_EQ(openFrameSource(dir.path() / "padded")->frameFile(0),
              dir.path() / "padded" / "frame_0001.exr");
    const std::unique_ptr<FrameSource> plain =
        openFrameSource(dir.path() / "plain" / "shot.%d.exr");
    EXPECT_EQ(plain->frameCount(), kFixtureFrames);
    EXPECT_EQ(plain->frameFile(3), dir.path() / "plain" / "shot.11.exr");
    EXPECT_EQ(openFrameSource(dir.path() / "plain")->frameCount(), kFixtureFrames);
    // A pattern of another width matches none of them.
    std::string message =
        messageOf([&] { openFrameSource(dir.path() / "padded" / "frame_##.exr"); });
    EXPECT_TRUE(contains(message, "no frames")) << message;
    message = messageOf([&] { openFrameSource(dir.path() / "padded" / "frame_%4d.exr"); });
    EXPECT_TRUE(contains(message, "%04d")) << message;
    // Two names in one folder need a pattern.
    copyFixture(dir.path() / "padded", {}, 1, "other_", 4);
    message = messageOf([&] { openFrameSource(dir.path() / "padded"); });
    EXPECT_TRUE(contains(message, "several names")) << message;
    EXPECT_EQ(openFrameSource(dir.path() / "padded" / "other_####.exr")->frameCount(),
              kFixtureFrames);
    // The command takes patterns too (it fails later, at the denoiser, until it uses motion).
    const test::CliResult r = runCli("denoise " + quoted(dir.path() / "padded" / "frame_####.exr") +
                                     " --method jbf -q -o " + quoted(dir.path() / "out"));
    EXPECT_FALSE(contains(r.output, "frame_####")) << r.output;
    EXPECT_FALSE(contains(r.output, "no frames")) << r.output;
}

TEST(BlenderNames, NoisyImageIsPreferredToCombined) {
    test::TempFolder dir("blender-noisy-image");
    copyFixture(dir.path() / "in", [](int, std::map<std::string, Image>& channels) {
        for (const char* c : {"R", "G", "B"}) {
            const std::string combined = std::string("ViewLayer.Combined.") + c;
            channels.emplace(std::string("ViewLayer.Noisy Image.") + c, channels.at(combined));
            std::fill(channels.at(combined).pixels.begin(), channels.at(combined).pixels.end(),
                      0.25f);  // as if denoised
        }
    });
    const BlenderSequence sequence(dir.path() / "in");
    EXPECT_EQ(sequence.colourPass(), "Noisy Image");
    const Frame noisy = sequence.readFrame(0);
    const Frame original = BlenderSequence(kFixture / "noisy").readFrame(0);
    EXPECT_EQ(noisy.beauty.pixels, original.beauty.pixels);
}

TEST(BlenderNames, TheFirstUsableViewLayerIsReadUnlessOneIsNamed) {
    test::TempFolder dir("blender-layers");
    // "A" (first in the file) has only a Combined pass; "Second" is a full copy with its colour
    // halved.
    copyFixture(dir.path() / "in", [](int, std::map<std::string, Image>& channels) {
        std::map<std::string, Image> added;
        for (const auto& [name, image] : channels) {
            Image copy = image;
            if (passOf(name) == "Combined") {
                added.emplace("A" + name.substr(name.find('.')), image);
                for (float& v : copy.pixels) v *= 0.5f;
            }
            added.emplace("Second" + name.substr(name.find('.')), copy);
        }
        channels.merge(added);
    });
    const Frame original = BlenderSequence(kFixture / "noisy").readFrame(0);
    const BlenderSequence first(dir.path() / "in");
    EXPECT_EQ(first.viewLayer(), "Second");
    EXPECT_FLOAT_EQ(first.readFrame(0).beauty.pixels[100], 0.5f * original.beauty.pixels[100]);
    const std::unique_ptr<FrameSource> named =
        openFrameSource(dir.path() / "in", FrameSourceOptions{"ViewLayer"});
    EXPECT_EQ(named->readFrame(0).beauty.pixels, original.beauty.pixels);
    std::string message = messageOf([&] { BlenderSequence sequence(dir.path() / "in", "Nope"); });
    EXPECT_TRUE(contains(message, "no view layer 'Nope'")) << message;
    EXPECT_TRUE(contains(message, "'ViewLayer'")) << message;
    message = messageOf([&] { BlenderSequence sequence(dir.path() / "in", "A"); });
    EXPECT_TRUE(contains(message, "no Depth pass in view layer 'A'")) << message;
    const test::CliResult r = runCli("denoise " + quoted(dir.path() / "in") +
                                     " --view-layer Nope -o " + quoted(dir.path() / "out"));
    EXPECT_NE(r.exitCode, 0);
    EXPECT_TRUE(contains(r.output, "no view layer 'Nope'")) << r.output;
}

// Issue 37 item 2: a folder whose files fit more than one numbering (0001..0004 and a stray 5.exr
// or 12.exr) is refused naming both, as a folder of several names is; a pattern chooses one.
TEST(BlenderNames, AFolderOfTwoNumberingsIsRefusedNamingBoth) {
    test::TempFolder dir("blender-numberings");
    for (const std::string stray : {"5.exr", "12.exr"}) {
        SCOPED_TRACE(stray);
        const fs::path in = dir.path() / stray;
        copyFixture(in);
        fs::copy_file(in / "0001.exr", in / stray);
        const std::string message = messageOf([&] { openFrameSource(in); });
        EXPECT_TRUE(contains(message, "several numberings")) << message;
        EXPECT_TRUE(contains(message, "0001.exr")) << message;
        EXPECT_TRUE(contains(message, "0004.exr")) << message;
        EXPECT_TRUE(contains(message, stray)) << message;
        EXPECT_TRUE(contains(message, (in / "####.exr").string())) << message;
        EXPECT_EQ(openFrameSource(in / "####.exr")->frameCount(), kFixtureFrames);

        const fs::path output = dir.path() / ("out-" + stray);
        const test::CliResult r =
            runCli("denoise " + quoted(in) + " --method jbf -o " + quoted(output));
        EXPECT_NE(r.exitCode, 0);
        EXPECT_TRUE(contains(r.output, "several numberings")) << r.output;
        EXPECT_TRUE(contains(r.output, stray)) << r.output;
        EXPECT_FALSE(fs::exists(output));
    }
    // Numbers that outgrow their padding are one numbering: 0998, 0999, 1000, 1001.
    copyFixture(dir.path() / "thousand", {}, 998);
    const BlenderSequence thousand(dir.path() / "thousand");
    EXPECT_EQ(thousand.files().first, 998);
    EXPECT_EQ(thousand.frameCount(), kFixtureFrames);
    EXPECT_EQ(thousand.frameFile(3), dir.path() / "thousand" / "1001.exr");
    // Unpadded: shot.8 .. shot.11 (two widths, one numbering).
    copyFixture(dir.path() / "plain", {}, 8, "shot.", 1);
    EXPECT_EQ(openFrameSource(dir.path() / "plain")->frameFile(3),
              dir.path() / "plain" / "shot.11.exr");
}

// Issue 37 item 13: by default the first view layer with every required pass is read; when none
// has them all, the error says which layer lacks which passes.
TEST(BlenderNames, TheFirstCompleteViewLayerIsReadByDefault) {
    test::TempFolder dir("blender-complete-layer");
    // "A" (first in the file) has Combined and Depth but no Normal or Position; "ViewLayer" has
    // all.
    copyFixture(dir.path() / "in", [](int, std::map<std::string, Image>& channels) {
        std::map<std::string, Image> added;
        for (const auto& [name, image] : channels)
            if (passOf(name) == "Combined" || passOf(name) == "Depth")
                added.emplace("A" + name.substr(name.find('.')), image);
        channels.merge(added);
    });
    std::string message = messageOf([&] {
        const BlenderSequence sequence(dir.path() / "in");
        EXPECT_EQ(sequence.viewLayer(), "ViewLayer");
        EXPECT_EQ(sequence.readFrame(0).beauty.pixels,
                  BlenderSequence(kFixture / "noisy").readFrame(0).beauty.pixels);
    });
    EXPECT_EQ(message, "(no error)");
    message = messageOf([&] { BlenderSequence sequence(dir.path() / "in", "A"); });
    EXPECT_TRUE(contains(message, "no Normal pass in view layer 'A'")) << message;

    // No complete layer: "A" lacks Position, "B" lacks Depth.
    copyFixture(dir.path() / "none", [](int, std::map<std::string, Image>& channels) {
        std::map<std::string, Image> layers;
        for (const auto& [name, image] : channels) {
            const std::string pass = passOf(name), rest = name.substr(name.find('.'));
            if (pass != "Position") layers.emplace("A" + rest, image);
            if (pass != "Depth") layers.emplace("B" + rest, image);
        }
        channels = std::move(layers);
    });
    message = messageOf([&] { BlenderSequence sequence(dir.path() / "none"); });
    EXPECT_TRUE(contains(message, (dir.path() / "none" / "0001.exr").string())) << message;
    EXPECT_TRUE(contains(message, "'A' lacks Position")) << message;
    EXPECT_TRUE(contains(message, "'B' lacks Depth")) << message;
    EXPECT_TRUE(contains(message, "--view-layer")) << message;
    const test::CliResult r = runCli("denoise " + quoted(dir.path() / "none") +
                                     " --method jbf -o " + quoted(dir.path() / "out"));
    EXPECT_NE(r.exitCode, 0);
    EXPECT_TRUE(contains(r.output, "'B' lacks Depth")) << r.output;
    EXPECT_FALSE(fs::exists(dir.path() / "out"));
}

TEST(BlenderNames, ACourseFolderIsStillACourseFolder) {
    test::TempFolder dir("blender-course");
    render::RenderSettings settings;
    settings.width = 16;
    settings.height = 16;
    settings.frames = 2;
    settings.gbufferOnly = true;
    render::renderSequence("moving-objects", settings, dir.path());
    const std::unique_ptr<FrameSource> source = openFrameSource(dir.path());
    EXPECT_NE(dynamic_cast<const Sequence*>(source.get()), nullptr);
    EXPECT_EQ(source->frameFile(1), dir.path() / "beauty_1.exr");
    const std::string message =
        messageOf([&] { openFrameSource(dir.path(), FrameSourceOptions{"ViewLayer"}); });
    EXPECT_TRUE(contains(message, "course-layout")) << message;
    test::TempFolder empty("blender-empty");
    EXPECT_TRUE(contains(messageOf([&] { openFrameSource(empty.path()); }), "no frames"));
}

}  // namespace
}  // namespace rtd
