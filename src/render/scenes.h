// The built-in test scenes: each one provokes a different denoiser failure. A scene is a function
// of the frame index (motion is periodic in frames, so any frame count is valid and a short
// sequence shows the start of the same animation).
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "render/scene.h"

namespace rtd::render {

struct SceneDefinition {
    std::string name;         // lower case, the CLI's SCENE
    std::string description;  // one line: what it shows and which failure it provokes
    std::string motion;       // what moves, in words (scene.json)
    std::function<Scene(int frame)> build;
    // What a scene generator drew, a JSON object (scene.json's "generator"); empty for the
    // built-in scenes.
    std::string generator{};
};

const std::vector<SceneDefinition>& builtInScenes();

// The scene `name` at frame `frame`; throws rtd::Error (InvalidArgument) naming the scene and
// listing the known ones.
Scene buildScene(const std::string& name, int frame);

// The white furnace: the camera inside a sphere whose surface has diffuse albedo
// kFurnaceAlbedo and emission kFurnaceEmission (both sides), so the radiance is
// Le (1 - a^maxDepth) / (1 - a) everywhere (Le / (1 - a) for unbounded paths).
constexpr float kFurnaceAlbedo = 0.5f;
constexpr float kFurnaceEmission = 0.5f;

}  // namespace rtd::render
