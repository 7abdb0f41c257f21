// `rtdenoise render`'s engine: renders a built-in scene into a sequence folder in the course
// layout (shared/data/README.md) with a converged reference from the same camera.
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

namespace rtd::render {

struct RenderSettings {
    int width = 320;
    int height = 240;
    int frames = 16;
    int spp = 1;             // samples per pixel of the noisy beauty
    int referenceSpp = 256;  // samples per pixel of reference/reference_<i>.exr
    std::uint32_t seed = 1;
    int maxDepth = 8;          // surface interactions per path
    bool gbufferOnly = false;  // beauty and G-buffers only: no reference
};

struct SceneInfo {
    std::string name, description;
};
std::vector<SceneInfo> listScenes();

// Writes, for i = 0..frames-1, beauty_i.exr, albedo_i.exr, normal_i.exr, position_i.exr,
// depth_i.exr, ID_i.exr, matrix_i.mat and (unless gbufferOnly) reference/reference_i.exr, plus
// scene.json describing the render (written last). Files of the layout numbered >= frames, left
// by an earlier longer render, are removed so that they cannot join the sequence; so is an old
// reference with gbufferOnly. `progress(done, total)` is called after each frame. Throws
// rtd::Error for an unknown scene (listing the scenes), a bad setting (naming it) or an
// unwritable folder.
void renderSequence(const std::string& scene, const RenderSettings& settings,
                    const std::filesystem::path& outDir,
                    const std::function<void(int done, int total)>& progress = {});

// Camera paths a render traces (beauty and reference, G-buffer rays not counted): for speed
// reports.
double pathCount(const RenderSettings& settings);

// Throws rtd::Error (InvalidArgument) naming the first setting out of range.
void validate(const RenderSettings& settings);

}  // namespace rtd::render
