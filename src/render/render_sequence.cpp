#include "render/render_sequence.h"

#include <fmt/format.h>

#include <charconv>
#include <string_view>
#include <system_error>

#include "render/path_tracer.h"
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
        "  \"motion\": {},\n"
        "  \"moving\": {{\"objects\": {}, \"camera\": {}, \"lights\": {}}},\n"
        "  \"objects\": [\n{}\n  ]\n"
        "}}\n",
        jsonString(d.name), jsonString(d.description), s.width, s.height, s.frames, s.spp,
        s.gbufferOnly ? 0 : s.referenceSpp, !s.gbufferOnly, s.seed, s.maxDepth,
        jsonString(d.motion), jsonList(movingObjects), motion.camera, jsonList(changingLights),
        objects);
}

// "<prefix>_<n>.<ext>" of the layout with n >= frames: left from an earlier, longer render they
// would be read as part of this sequence.
void removeStaleFrames(const fs::path& folder, int frames) {
    static const std::string_view kStems[] = {"beauty", "albedo", "normal",   "position",
                                              "depth",  "ID",     "reference"};
    for (std::string_view stem : kStems) removeNumberedFiles(folder, stem, ".exr", frames);
    removeNumberedFiles(folder, "matrix", ".mat", frames);
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
}

double pathCount(const RenderSettings& s) {
    return double(s.width) * s.height * s.frames * (s.spp + (s.gbufferOnly ? 0 : s.referenceSpp));
}

void renderSequence(const std::string& sceneName, const RenderSettings& settings,
                    const fs::path& outDir, const std::function<void(int, int)>& progress) {
    validate(settings);
    const SceneDefinition* definition = nullptr;
    for (const SceneDefinition& d : builtInScenes())
        if (d.name == sceneName) definition = &d;
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
    removeStaleFrames(outDir, settings.frames);
    if (fs::is_directory(referenceDir))
        removeStaleFrames(referenceDir, settings.gbufferOnly ? 0 : settings.frames);

    for (int i = 0; i < settings.frames; ++i) {
        TraceSettings trace;
        trace.width = settings.width;
        trace.height = settings.height;
        trace.samplesPerPixel = settings.spp;
        trace.maxDepth = settings.maxDepth;
        trace.seed = settings.seed;
        trace.frameIndex = i;
        trace.stream = kBeautyStream;
        writeFrame(outDir, i, renderFrame(scenes[i], trace));
        if (!settings.gbufferOnly) {
            trace.samplesPerPixel = settings.referenceSpp;
            trace.stream = kReferenceStream;
            writeExr(referenceDir / fmt::format("reference_{}.exr", i),
                     renderRadiance(scenes[i], trace));
        }
        if (progress) progress(i + 1, settings.frames);
    }
    // Written last: its presence says the folder is complete.
    writeFileAtomically(outDir / "scene.json", sceneJson(*definition, settings, scenes));
}

}  // namespace rtd::render
