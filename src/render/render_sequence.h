// `rtdenoise render`'s engine: renders a built-in scene, or the scene generator's scene of a seed
// (render/random_scene.h), into a sequence folder in the course layout (shared/data/README.md)
// with a converged reference from the same camera.
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "render/scene.h"
#include "rtdenoise/image.h"

namespace rtd::render {

// How renderSequence lays out its files.
enum class OutputFormat {
    Folder,      // the course layout: beauty_i.exr, ..., matrix_i.mat, reference/reference_i.exr
    Multilayer,  // Blender's: one multilayer EXR a frame, 0001.exr ..., reference/0001.exr ...
};

struct RenderSettings {
    int width = 320;
    int height = 240;
    int frames = 16;
    int spp = 1;               // samples per pixel of the noisy beauty
    int referenceSpp = 256;    // samples per pixel of reference/reference_<i>.exr
    std::uint32_t seed = 1;    // the noise's; for the scene "random" also the scene drawn
    int maxDepth = 8;          // surface interactions per path
    bool gbufferOnly = false;  // beauty and G-buffers only: no reference
    // Also confidence_<i>.exr (folder layout only): the history confidence of A-SVGF's temporal
    // gradients (render/confidence.h), 1 on frame 0; about 2/9 more paths than a 1-spp beauty.
    bool confidence = false;
    // The split signal too (folder layout only): specular_<i>.exr (the beauty's glossy part, at
    // its spp, from the same paths), roughness_<i>.exr and hit_distance_<i>.exr
    // (render/path_tracer.h's renderFrame with split). No extra paths.
    bool split = false;
    OutputFormat format = OutputFormat::Folder;
};

struct SceneInfo {
    std::string name, description;
};
std::vector<SceneInfo> listScenes();

// Writes, for i = 0..frames-1, beauty_i.exr, albedo_i.exr, normal_i.exr, position_i.exr,
// depth_i.exr, ID_i.exr, matrix_i.mat, confidence_i.exr (with `confidence`), specular_i.exr,
// roughness_i.exr and hit_distance_i.exr (with `split`) and (unless
// gbufferOnly) reference/reference_i.exr, plus
// scene.json describing the render (written last; for "random" with "generator": what the seed
// drew, render/random_scene.h's describeJson). With OutputFormat::Multilayer, frame i is
// instead the Blender-style multilayer <i+1>.exr (0001.exr ..., writeBlenderExr: motion vectors
// from the matrices of frames i-1 and i+1) and its reference reference/<i+1>.exr (R, G, B).
// Files of the layout numbered >= frames, left by an earlier longer render, are removed so that
// they cannot join the sequence, and so are the other layout's frames; so is an old reference
// with gbufferOnly. `progress(done, total)` is called after each frame. Throws
// rtd::Error for an unknown scene (listing the scenes), a bad setting (naming it) or an
// unwritable folder.
void renderSequence(const std::string& scene, const RenderSettings& settings,
                    const std::filesystem::path& outDir,
                    const std::function<void(int done, int total)>& progress = {});

// The motion of each pixel of `frame` (rendered from `current`) to where its point is in
// `other`, from the scenes' own matrices: other's worldToScreen * other's objectToWorld[id] *
// inverse(current's objectToWorld[id]) * position, minus the pixel's own projection. 2 channels,
// pixels, y down (rtd::Frame::motion's convention when `other` is the previous frame); 0 on
// background; far off-screen where the point is behind other's camera.
Image screenMotion(const Frame& frame, const Scene& current, const Scene& other);

// Camera paths a render traces (beauty and reference, G-buffer rays not counted): for speed
// reports.
double pathCount(const RenderSettings& settings);

// Throws rtd::Error (InvalidArgument) naming the first setting out of range.
void validate(const RenderSettings& settings);

}  // namespace rtd::render
