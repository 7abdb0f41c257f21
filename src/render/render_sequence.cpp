#include "render/render_sequence.h"

#include <fmt/format.h>

#include <array>
#include <charconv>
#include <cmath>
#include <optional>
#include <string_view>
#include <system_error>

#include "render/confidence.h"
#include "render/path_tracer.h"
#include "render/random_scene.h"
#include "render/scenes.h"
#include "rtdenoise/error.h"
#include "rtdenoise/io.h"

namespace fs = std::filesystem;

namespace rtd::render {
namespace {

std::string jsonString(std::string_view s) {
    std::string out = "\"";
    for (char c : s) {
        if (c == '"' || c == '\\') {
            out += '\\';
            out += c;
        } else if (static_cast<unsigned char>(c) < 0x20) {
            out += fmt::format("\\u{:04x}", int(c));
        } else {
            out += c;
        }
    }
    return out + "\"";
}

std::string jsonList(const std::vector<std::string>& items) {
    std::string out = "[";
    for (std::size_t i = 0; i < items.size(); ++i) out += (i ? ", " : "") + jsonString(items[i]);
    return out + "]";
}

bool sameMatrix(const Matrix4& a, const Matrix4& b) {
    return a.m == b.m;
}

bool sameCamera(const Camera& a, const Camera& b) {
    auto same = [](Vec3 x, Vec3 y) { return x.x == y.x && x.y == y.y && x.z == y.z; };
    return same(a.position, b.position) && same(a.target, b.target) && same(a.up, b.up) &&
           a.verticalFovDegrees == b.verticalFovDegrees;
}

// What changes over the frames, found by comparing every frame's scene with frame 0, so that
// scene.json states what the render really did.
struct Motion {
    std::vector<bool> objectMoves;
    std::vector<bool> emissionChanges;
    bool camera = false;
};

Motion findMotion(const std::vector<Scene>& scenes) {
    const Scene& first = scenes.front();
    Motion m;
    m.objectMoves.assign(first.objects.size(), false);
    m.emissionChanges.assign(first.objects.size(), false);
    for (const Scene& s : scenes) {
        m.camera = m.camera || !sameCamera(s.camera, first.camera);
        for (std::size_t k = 0; k < s.objects.size(); ++k) {
            if (!sameMatrix(s.objects[k].objectToWorld, first.objects[k].objectToWorld))
                m.objectMoves[k] = true;
            Vec3 a = s.objects[k].material.emission, b = first.objects[k].material.emission;
            if (a.x != b.x || a.y != b.y || a.z != b.z) m.emissionChanges[k] = true;
        }
    }
    return m;
}

std::string sceneJson(const SceneDefinition& d, const RenderSettings& s,
                      const std::vector<Scene>& scenes) {
    Motion motion = findMotion(scenes);
    const Scene& first = scenes.front();
    std::vector<std::string> movingObjects, changingLights;
    std::string objects;
    for (std::size_t k = 0; k < first.objects.size(); ++k) {
        const Object& o = first.objects[k];
        bool emits = false;
        for (const Scene& sc : scenes) emits = emits || sc.objects[k].material.emissive();
        if (motion.objectMoves[k]) movingObjects.push_back(o.name);
        if (emits && (motion.objectMoves[k] || motion.emissionChanges[k]))
            changingLights.push_back(o.name);
        objects += fmt::format("{}    {{\"id\": {}, \"name\": {}, \"moves\": {}, \"emits\": {}}}",
                               k ? ",\n" : "", k, jsonString(o.name), motion.objectMoves[k], emits);
    }
    return fmt::format(
        "{{\n"
        "  \"scene\": {},\n"
        "  \"description\": {},\n"
        "  \"width\": {},\n"
        "  \"height\": {},\n"
        "  \"frames\": {},\n"
        "  \"spp\": {},\n"
        "  \"reference_spp\": {},\n"
        "  \"reference\": {},\n"
        "  \"seed\": {},\n"
        "  \"max_depth\": {},\n"
        "  \"format\": {},\n"
        "  \"motion\": {},\n"
        "  \"moving\": {{\"objects\": {}, \"camera\": {}, \"lights\": {}}},\n"
        "  \"objects\": [\n{}\n  ]{}\n"
        "}}\n",
        jsonString(d.name), jsonString(d.description), s.width, s.height, s.frames, s.spp,
        s.gbufferOnly ? 0 : s.referenceSpp, !s.gbufferOnly, s.seed, s.maxDepth,
        jsonString(s.format == OutputFormat::Multilayer ? "multilayer" : "folder"),
        jsonString(d.motion), jsonList(movingObjects), motion.camera, jsonList(changingLights),
        objects, d.generator.empty() ? "" : ",\n  \"generator\": " + d.generator);
}

// "<prefix>_<n>.<ext>" of the layout with n >= frames: left from an earlier, longer render they
// would be read as part of this sequence.
void removeStaleFrames(const fs::path& folder, int frames) {
    static const std::string_view kStems[] = {"beauty",   "albedo",    "normal",      "position",
                                              "depth",    "ID",        "reference",   "confidence",
                                              "specular", "roughness", "hit_distance"};
    for (std::string_view stem : kStems) removeNumberedFiles(folder, stem, ".exr", frames);
    removeNumberedFiles(folder, "matrix", ".mat", frames);
}

// The multilayer layout's name of frame i: Blender's default, frame numbers from 1, 4 digits.
std::string multilayerName(int index) {
    return fmt::format("{:04d}.exr", index + 1);
}

// Multilayer frames "<n>.exr" (as multilayerName writes them) of index >= frames: the same
// reason as removeStaleFrames, for the other layout.
void removeStaleMultilayerFrames(const fs::path& folder, int frames) {
    std::error_code ec;
    std::vector<fs::path> stale;
    for (fs::directory_iterator it(folder, ec); !ec && it != fs::directory_iterator();
         it.increment(ec)) {
        const std::string name = it->path().filename().string();
        if (!name.ends_with(".exr") || name.size() < 8) continue;
        const std::string_view digits(name.data(), name.size() - 4);
        int number = 0;
        const auto [end, error] =
            std::from_chars(digits.data(), digits.data() + digits.size(), number);
        std::error_code typeError;
        if (error == std::errc() && end == digits.data() + digits.size() && number >= 1 &&
            multilayerName(number - 1) == name && number - 1 >= frames &&
            it->is_regular_file(typeError))
            stale.push_back(it->path());
    }
    for (const fs::path& file : stale) {
        fs::remove(file, ec);
        if (ec)
            throw Error(ErrorCode::IoFailure, file.string() +
                                                  ": cannot remove this output of an earlier "
                                                  "run: " +
                                                  ec.message());
    }
}

// Double precision for the motion vectors: they are the reference the reader's are tested
// against, to a thousandth of a pixel.
using Matrix4d = std::array<std::array<double, 4>, 4>;

Matrix4d toDouble(const Matrix4& m) {
    Matrix4d r{};
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j) r[i][j] = m.m[i][j];
    return r;
}

Matrix4d multiply(const Matrix4d& a, const Matrix4d& b) {
    Matrix4d r{};
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j)
            for (int k = 0; k < 4; ++k) r[i][j] += a[i][k] * b[k][j];
    return r;
}

// Gauss-Jordan with partial pivoting; a singular matrix (a zero scale) gives nullopt.
std::optional<Matrix4d> inverse(Matrix4d a) {
    Matrix4d r{};
    for (int i = 0; i < 4; ++i) r[i][i] = 1.0;
    for (int col = 0; col < 4; ++col) {
        int pivot = col;
        for (int row = col + 1; row < 4; ++row)
            if (std::abs(a[row][col]) > std::abs(a[pivot][col])) pivot = row;
        if (std::abs(a[pivot][col]) < 1e-12) return std::nullopt;
        std::swap(a[col], a[pivot]);
        std::swap(r[col], r[pivot]);
        const double scale = 1.0 / a[col][col];
        for (int j = 0; j < 4; ++j) {
            a[col][j] *= scale;
            r[col][j] *= scale;
        }
        for (int row = 0; row < 4; ++row) {
            if (row == col) continue;
            const double factor = a[row][col];
            for (int j = 0; j < 4; ++j) {
                a[row][j] -= factor * a[col][j];
                r[row][j] -= factor * r[col][j];
            }
        }
    }
    return r;
}

}  // namespace

std::vector<SceneInfo> listScenes() {
    std::vector<SceneInfo> out;
    for (const SceneDefinition& d : builtInScenes()) out.push_back({d.name, d.description});
    return out;
}

void validate(const RenderSettings& s) {
    auto check = [](bool ok, const char* what, long long value, const char* range) {
        if (!ok)
            throw Error(ErrorCode::InvalidArgument,
                        fmt::format("{} = {} is out of range ({})", what, value, range));
    };
    check(s.width >= 1 && s.width <= 16384, "width", s.width, "1..16384");
    check(s.height >= 1 && s.height <= 16384, "height", s.height, "1..16384");
    check(s.frames >= 1 && s.frames <= 100000, "frames", s.frames, "1..100000");
    check(s.spp >= 1 && s.spp <= 1 << 20, "spp", s.spp, "1..1048576");
    check(s.referenceSpp >= 1 && s.referenceSpp <= 1 << 20, "reference spp", s.referenceSpp,
          "1..1048576");
    check(s.maxDepth >= 1 && s.maxDepth <= 64, "max depth", s.maxDepth, "1..64");
    if (s.confidence && s.format == OutputFormat::Multilayer)
        throw Error(ErrorCode::InvalidArgument,
                    "confidence is written in the folder layout only (Blender's files have no "
                    "such pass)");
    if (s.split && s.format == OutputFormat::Multilayer)
        throw Error(ErrorCode::InvalidArgument,
                    "the split signal (specular, roughness, hit distance) is written in the "
                    "folder layout only");
}

Image screenMotion(const Frame& frame, const Scene& current, const Scene& other) {
    const int width = frame.width(), height = frame.height();
    // Off-screen by far, so that history there is rejected as outside the screen.
    constexpr float kBehindCamera = 1e6f;
    const Matrix4d currentToScreen = toDouble(worldToScreen(current.camera, width, height));
    const Matrix4d otherToScreen = toDouble(worldToScreen(other.camera, width, height));
    std::vector<std::optional<Matrix4d>> currentToOther;  // per object: world now -> screen there
    for (std::size_t k = 0; k < current.objects.size() && k < other.objects.size(); ++k) {
        const std::optional<Matrix4d> toLocal = inverse(toDouble(current.objects[k].objectToWorld));
        currentToOther.push_back(
            toLocal
                ? std::optional<Matrix4d>(multiply(
                      otherToScreen, multiply(toDouble(other.objects[k].objectToWorld), *toLocal)))
                : std::nullopt);
    }
    Image motion(width, height, 2);
    for (int y = 0; y < height; ++y) {
        for (int x = 0; x < width; ++x) {
            const std::size_t i = std::size_t(y) * width + x;
            const int id = frame.objectId[i];
            if (id < 0) continue;
            const double p[4] = {frame.position.pixels[i * 3], frame.position.pixels[i * 3 + 1],
                                 frame.position.pixels[i * 3 + 2], 1.0};
            const auto project = [&p](const Matrix4d& m, double& sx, double& sy) {
                double s[4] = {};
                for (int r = 0; r < 4; ++r)
                    for (int c = 0; c < 4; ++c) s[r] += m[r][c] * p[c];
                if (!(s[3] > 1e-9)) return false;
                sx = s[0] / s[3];
                sy = s[1] / s[3];
                return true;
            };
            double cx = 0, cy = 0, ox = 0, oy = 0;
            const bool known = std::size_t(id) < currentToOther.size() && currentToOther[id] &&
                               project(currentToScreen, cx, cy) &&
                               project(*currentToOther[id], ox, oy);
            motion.at(x, y, 0) = known ? float(ox - cx) : kBehindCamera;
            motion.at(x, y, 1) = known ? float(oy - cy) : kBehindCamera;
        }
    }
    return motion;
}

double pathCount(const RenderSettings& s) {
    const double pixels = double(s.width) * s.height;
    // Confidence: 2 paths per 3x3 stratum on every frame but the first.
    const double strata = double((s.width + 2) / 3) * double((s.height + 2) / 3);
    const double confidencePaths = s.confidence ? 2.0 * strata * (s.frames - 1) : 0.0;
    // The split signal adds none: specular comes from the beauty's own paths (its one mirror ray
    // per pixel is a G-buffer ray).
    return pixels * s.frames * (s.spp + (s.gbufferOnly ? 0 : s.referenceSpp)) + confidencePaths;
}

void renderSequence(const std::string& sceneName, const RenderSettings& settings,
                    const fs::path& outDir, const std::function<void(int, int)>& progress) {
    validate(settings);
    const SceneDefinition* definition = nullptr;
    for (const SceneDefinition& d : builtInScenes())
        if (d.name == sceneName) definition = &d;
    // The generator's scenes: the seed draws the scene (and, as always, the noise).
    const SceneDefinition generated =
        sceneName == kRandomSceneName ? randomSceneDefinition(settings.seed) : SceneDefinition{};
    if (sceneName == kRandomSceneName) definition = &generated;
    if (!definition) buildScene(sceneName, 0);  // throws, listing the scenes

    std::vector<Scene> scenes;
    for (int i = 0; i < settings.frames; ++i) {
        scenes.push_back(definition->build(i));
        if (scenes.back().objects.size() != scenes.front().objects.size())
            throw Error(
                ErrorCode::InvalidArgument,
                fmt::format("scene '{}': the object count changes at frame {}", sceneName, i));
    }
    prepareOutputFolder(outDir);
    const fs::path referenceDir = outDir / "reference";
    if (!settings.gbufferOnly) prepareOutputFolder(referenceDir);
    // A folder holds one render: the other layout's frames go, so it is read as this one.
    const bool multilayer = settings.format == OutputFormat::Multilayer;
    const int kept = settings.gbufferOnly ? 0 : settings.frames;
    removeStaleFrames(outDir, multilayer ? 0 : settings.frames);
    // Without confidence none of an earlier render's may stay to be read as this one's.
    if (!settings.confidence) removeNumberedFiles(outDir, "confidence", ".exr", 0);
    if (!settings.split)
        for (std::string_view stem : {"specular", "roughness", "hit_distance"})
            removeNumberedFiles(outDir, stem, ".exr", 0);
    removeStaleMultilayerFrames(outDir, multilayer ? settings.frames : 0);
    if (fs::is_directory(referenceDir)) {
        removeStaleFrames(referenceDir, multilayer ? 0 : kept);
        removeStaleMultilayerFrames(referenceDir, multilayer ? kept : 0);
    }
    // The scenes before the first frame and after the last: Cycles' Vector pass also points
    // there (scenes are functions of any frame index, negative ones included).
    const Scene beforeFirst = definition->build(-1);
    const Scene afterLast = definition->build(settings.frames);

    for (int i = 0; i < settings.frames; ++i) {
        TraceSettings trace;
        trace.width = settings.width;
        trace.height = settings.height;
        trace.samplesPerPixel = settings.spp;
        trace.maxDepth = settings.maxDepth;
        trace.seed = settings.seed;
        trace.frameIndex = i;
        trace.stream = kBeautyStream;
        Frame frame = renderFrame(scenes[i], trace, settings.split);
        if (settings.confidence)
            frame.confidence = i == 0 ? Image(settings.width, settings.height, 1, 1.0f)
                                      : historyConfidence(scenes[i - 1], scenes[i], frame, trace);
        if (multilayer) {
            const Scene& previous = i > 0 ? scenes[i - 1] : beforeFirst;
            const Scene& next = i + 1 < settings.frames ? scenes[i + 1] : afterLast;
            frame.motion = screenMotion(frame, scenes[i], previous);
            const Image motionToNext = screenMotion(frame, scenes[i], next);
            writeBlenderExr(outDir / multilayerName(i), frame, &motionToNext);
        } else {
            writeFrame(outDir, i, frame);
        }
        if (!settings.gbufferOnly) {
            trace.samplesPerPixel = settings.referenceSpp;
            trace.stream = kReferenceStream;
            writeExr(referenceDir /
                         (multilayer ? multilayerName(i) : fmt::format("reference_{}.exr", i)),
                     renderRadiance(scenes[i], trace));
        }
        if (progress) progress(i + 1, settings.frames);
    }
    // Written last: its presence says the folder is complete.
    writeFileAtomically(outDir / "scene.json", sceneJson(*definition, settings, scenes));
}

}  // namespace rtd::render
