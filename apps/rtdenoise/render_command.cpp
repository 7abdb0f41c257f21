// `rtdenoise render SCENE -o OUT_DIR`: renders a built-in test scene, or with SCENE "random" the
// scene generator's scene of --seed, into a sequence folder with its G-buffers and a converged
// reference (`rtdenoise render --list` names the scenes; `--describe` prints what a seed draws).
#include <fmt/format.h>

#include <chrono>
#include <memory>
#include <string>

#include "commands.h"
#include "progress.h"
#include "render/random_scene.h"
#include "render/render_sequence.h"
#include "rtdenoise/error.h"

namespace fs = std::filesystem;

namespace rtd::cli {
namespace {

struct RenderOptions {
    std::string scene;
    fs::path output;
    bool list = false;
    bool describe = false;
    bool quiet = false;
    render::RenderSettings settings;
};

std::string sceneList() {
    std::string out;
    for (const render::SceneInfo& s : render::listScenes())
        out += fmt::format("  {:<16} {}\n", s.name, s.description);
    out += fmt::format("  {:<16} {}\n", render::kRandomSceneName,
                       "a generated scene, a different one for each --seed (rooms and open scenes, "
                       "every kind of light, material and motion; docs/scene_generator.md)");
    return out;
}

// What SCENE is and draws, as JSON: the generator's parameters for "random", the name,
// description and motion of a built-in scene.
std::string describeScene(const RenderOptions& options) {
    if (options.scene == render::kRandomSceneName) {
        render::RandomSceneRecipe recipe = render::drawRandomScene(options.settings.seed);
        render::normaliseExposure(recipe);
        return fmt::format(
            "{{\n  \"scene\": \"{}\",\n  \"description\": \"{}\",\n  "
            "\"generator\": {}\n}}\n",
            render::kRandomSceneName, recipe.summary(), recipe.describeJson());
    }
    for (const render::SceneInfo& info : render::listScenes())
        if (info.name == options.scene)
            return fmt::format("{{\n  \"scene\": \"{}\",\n  \"description\": \"{}\"\n}}\n",
                               info.name, info.description);
    throw Error(ErrorCode::InvalidArgument,
                fmt::format("unknown scene '{}'; scenes:\n{}", options.scene, sceneList()));
}

int runRender(const RenderOptions& options) {
    if (options.list) {
        fmt::print("scenes:\n{}", sceneList());
        return 0;
    }
    if (options.scene.empty())
        throw Error(ErrorCode::InvalidArgument,
                    "render: name a SCENE (or use --list); scenes:\n" + sceneList());
    if (options.describe) {
        fmt::print("{}", describeScene(options));
        return 0;
    }
    if (options.output.empty())
        throw Error(ErrorCode::InvalidArgument, "render: -o OUT_DIR is required");

    const render::RenderSettings& s = options.settings;
    bool known = options.scene == render::kRandomSceneName;
    for (const render::SceneInfo& info : render::listScenes())
        known = known || info.name == options.scene;
    if (!known)
        throw Error(ErrorCode::InvalidArgument,
                    fmt::format("unknown scene '{}'; scenes:\n{}", options.scene, sceneList()));
    if (!options.quiet)
        fmt::print(
            stderr, "rtdenoise: rendering {} into {}: {} frames of {}x{}, {} spp{}\n",
            options.scene == render::kRandomSceneName
                ? fmt::format("{} (seed {})", options.scene, s.seed)
                : options.scene,
            options.output.string(), s.frames, s.width, s.height, s.spp,
            s.gbufferOnly ? ", no reference" : fmt::format(", reference {} spp", s.referenceSpp));

    Progress progress(s.frames, options.quiet);
    auto start = std::chrono::steady_clock::now();
    render::renderSequence(options.scene, s, options.output,
                           [&progress](int done, int) { progress.update(done); });
    progress.finish();
    double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (!options.quiet) {
        double paths = render::pathCount(s);
        fmt::print(
            "{} frames of {}x{} in {:.2f} s ({:.2f} s/frame), {:.1f} M camera paths, "
            "{:.2f} Mpaths/s (files included)\n",
            s.frames, s.width, s.height, seconds, seconds / s.frames, paths * 1e-6,
            seconds > 0.0 ? paths * 1e-6 / seconds : 0.0);
        fmt::print(
            "output: {}{}{}\n", options.output.string(),
            s.format == render::OutputFormat::Multilayer ? " (multilayer 0001.exr, ...)" : "",
            s.gbufferOnly ? "" : " (reference in reference/)");
    }
    return 0;
}

}  // namespace

Command addRenderCommand(CLI::App& app) {
    auto options = std::make_shared<RenderOptions>();
    render::RenderSettings& s = options->settings;
    CLI::App* c = app.add_subcommand(
        "render",
        "Render a built-in test scene, or a generated one (SCENE random, one scene per --seed), "
        "into OUT_DIR: beauty_i.exr (noisy), albedo, normal, position, depth, ID, matrix_i.mat, "
        "reference/reference_i.exr, scene.json");
    c->add_option("SCENE", options->scene, "Scene name (see --list), or random");
    c->add_option("-o,--output", options->output, "Output folder (created if missing)");
    c->add_flag("--list", options->list, "List the scenes with what each one tests");
    c->add_flag("--describe", options->describe,
                "Print what SCENE is as JSON and render nothing: for random, every parameter the "
                "seed drew (as scene.json's \"generator\" records it)");
    c->add_option("--width", s.width, "Image width in pixels")
        ->check(CLI::Range(1, 16384))
        ->capture_default_str();
    c->add_option("--height", s.height, "Image height in pixels")
        ->check(CLI::Range(1, 16384))
        ->capture_default_str();
    c->add_option("--frames", s.frames, "Number of frames")
        ->check(CLI::Range(1, 100000))
        ->capture_default_str();
    c->add_option("--spp", s.spp, "Samples per pixel of the noisy beauty")
        ->check(CLI::Range(1, 1 << 20))
        ->capture_default_str();
    c->add_option("--ref-spp", s.referenceSpp, "Samples per pixel of the reference")
        ->check(CLI::Range(1, 1 << 20))
        ->capture_default_str();
    c->add_option("--seed", s.seed,
                  "Random seed (same seed, same files); for SCENE random also the scene drawn")
        ->capture_default_str();
    c->add_option("--max-depth", s.maxDepth, "Surface interactions per path")
        ->check(CLI::Range(1, 64))
        ->capture_default_str();
    c->add_flag("--gbuffer-only", s.gbufferOnly,
                "Skip the reference: noisy beauty and G-buffers only");
    c->add_flag("--confidence", s.confidence,
                "Also confidence_<i>.exr: history confidence in [0, 1] from A-SVGF temporal "
                "gradients (0 where the lighting changed; folder layout only)");
    c->add_flag("--split", s.split,
                "Also the split signal: specular_<i>.exr (the beauty's part that left the first "
                "surface through its glossy lobe, same paths and spp), roughness_<i>.exr (linear "
                "roughness) and hit_distance_<i>.exr (mirror-ray hit distance, 0 = unknown) "
                "(folder layout only)");
    c->add_option_function<std::string>(
         "--format",
         [&s](const std::string& value) {
             s.format = value == "multilayer" ? render::OutputFormat::Multilayer
                                              : render::OutputFormat::Folder;
         },
         "folder: the course layout (beauty_i.exr, ..., matrix_i.mat, reference/reference_i.exr); "
         "multilayer: one Blender-style multilayer EXR a frame (0001.exr, ...: Combined, Depth, "
         "Normal, Position, IndexOB, Denoising Albedo, Vector) and reference/0001.exr, ...")
        ->check(CLI::IsMember({"folder", "multilayer"}))
        ->option_text("folder|multilayer (default folder)");
    c->add_flag("-q,--quiet", options->quiet, "No progress or summary");
    return {c, [options] { return runRender(*options); }};
}

}  // namespace rtd::cli
