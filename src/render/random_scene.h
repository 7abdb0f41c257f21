// The scene generator behind `rtdenoise render random --seed N`: each seed draws a different
// scene from one documented distribution (docs/scene_generator.md): closed rooms, rooms lit
// through a window and open scenes under a sky; boxes, spheres, thin bars, grids and small
// details; diffuse materials with procedural textures, GGX glossy of every roughness, metals and
// near-mirrors, emitters; one to many lights of every kind; camera, object and light motion and
// lights that switch. The draw is deterministic: the same seed and kRandomSceneVersion give the
// same scene, bit for bit, and so the same files.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "render/scene.h"
#include "render/scenes.h"

namespace rtd::render {

// The CLI's SCENE for generated scenes.
inline constexpr char kRandomSceneName[] = "random";
// Changes whenever a seed may draw another scene or the same scene may render differently: what
// scene.json records so that a corpus can say which generator made it.
inline constexpr char kRandomSceneVersion[] = "random-scene 1";

// Periodic motion in frames: offset(frame) = amplitude sin(2 pi frame / period + phase).
struct Oscillation {
    float amplitude = 0.0f;  // [0, inf) metres or degrees
    int period = 48;         // [2, inf) frames
    float phase = 0.0f;      // [0, 2 pi) radians

    float at(int frame) const;
    // Largest change per frame, amplitude 2 pi / period (what "speed" means in the docs).
    float peakSpeed() const;
};

// How a drawn object or light moves: slides along a horizontal axis, spins about the vertical,
// both, bounces (up and down, |sin|), or orbits a circle about its rest position.
struct DrawnMotion {
    enum class Kind { None, Slide, Spin, SlideAndSpin, Bounce, Orbit };
    Kind kind = Kind::None;
    Vec3 axis{1.0f, 0.0f, 0.0f};       // unit: the slide's direction
    Oscillation offset;                // metres along the axis (Orbit: its radius is amplitude)
    float spinDegreesPerFrame = 0.0f;  // Spin: the yaw's rate

    bool moves() const { return kind != Kind::None; }
};

// A light that switches on and off: on for onFrames of every period, starting at offset.
struct DrawnSwitch {
    bool switches = false;
    int period = 12;   // [2, inf) frames
    int onFrames = 6;  // [1, period) frames on in each period
    int offset = 0;    // [0, period) frame of the period at frame 0

    bool on(int frame) const;
};

// One object of a drawn scene: its geometry and material, where it rests and how it moves. Its
// matrix at a frame is translation(position + motion) * rotationY(yaw + spin) * orientation.
struct DrawnObject {
    Object object;             // name, local primitives, material (emission at exposure 1)
    std::string kind;          // "box", "sphere", "bar", "grid", "details", "slab", a
                               // wall's name, or a light's kind ("area light", ...)
    std::string materialKind;  // "diffuse", "glossy", "metal", "mirror", "emitter"
    std::string lightKind;     // empty, or the light's kind (docs/scene_generator.md)
    Vec3 position{0.0f};       // rest position (world)
    float yawDegrees = 0.0f;   // rest rotation about the vertical
    Matrix4 orientation = Matrix4::identity();  // tilt applied before the yaw
    DrawnMotion motion;
    DrawnSwitch lightSwitch;

    Matrix4 placement(int frame) const;
};

// A camera that stays, pans, tilts, dollies, trucks, orbits the scene's centre, shakes as if
// held, or pans and dollies at once; at a drawn speed.
struct DrawnCamera {
    enum class Motion { Static, Pan, Tilt, Dolly, Truck, Orbit, Handheld, PanAndDolly };
    Motion motion = Motion::Static;
    std::string speed = "none";  // "none", "slow", "medium", "fast"
    Vec3 position{0.0f, 1.5f, -3.0f};
    Vec3 target{0.0f, 1.0f, 0.0f};
    float verticalFovDegrees = 50.0f;
    Oscillation rotation;               // Pan, Tilt, PanAndDolly: degrees of yaw or pitch
    Oscillation translation;            // Dolly, Truck, PanAndDolly: metres
    float orbitDegreesPerFrame = 0.0f;  // Orbit: about the vertical through `target`

    Camera at(int frame) const;
};

// Everything a seed drew; build(frame) turns it into the scene of a frame.
struct RandomSceneRecipe {
    enum class Layout { ClosedRoom, WindowRoom, Open };
    std::uint32_t seed = 0;
    Layout layout = Layout::ClosedRoom;
    Vec3 roomSize{0.0f};  // rooms: width (x), height (y), depth (z); open: 0
    // Closed rooms: every light hidden from the camera's direct view (facing the ceiling or a
    // wall), so that the frame is lit indirectly.
    bool indirectOnly = false;
    bool night = false;                 // open: a dim sky and local lights, no sun
    bool still = false;                 // nothing moves or switches (drawn first, 10 %)
    std::string window;                 // window rooms: "left", "right", "back" or "ceiling"
    std::vector<SkyPortal> skyPortals;  // window rooms: the window, sampled as a light
    Sky sky;                            // at exposure 1
    Sun sun;                            // at exposure 1; direction at frame 0
    float sunElevationDegrees = 0.0f;
    float sunAzimuthDegrees = 0.0f;
    Oscillation sunAzimuthMotion;      // degrees: the sun's shadows sweep
    std::vector<DrawnObject> objects;  // index = object ID
    DrawnCamera camera;
    // Multiplies every emitter, the sky and the sun: the mean luminance of frame 0 (a small
    // preview) is targetLuminance after normaliseExposure.
    float targetLuminance = 0.25f;  // [0.1, 0.5] drawn log-uniformly
    float exposure = 1.0f;

    Scene build(int frame) const;
    // Categories the draw falls in ("layout:open", "light:sun", "material:metal",
    // "camera:pan", "motion:objects", ...): what a corpus summary counts.
    std::vector<std::string> tags() const;
    // The drawn parameters as one JSON object (version, seed, tags, layout, sky, sun, camera,
    // lights, objects): `render random --describe` prints it and scene.json records it.
    std::string describeJson() const;
    // One line for scene.json's description.
    std::string summary() const;
    // What moves, in words (scene.json's motion).
    std::string motionSummary() const;
};

// The parameters of seed `seed` (no rendering: fast, exposure 1).
RandomSceneRecipe drawRandomScene(std::uint32_t seed);

// Sets recipe.exposure from a 32x24, 8-spp preview of frame 0 (the mean luminance of its pixels
// on geometry, sky left out, without the brightest 2 %) so that the scene's brightness is its
// targetLuminance. Deterministic.
void normaliseExposure(RandomSceneRecipe& recipe);

// drawRandomScene and normaliseExposure as a scene definition named "random" whose generator
// field is describeJson().
SceneDefinition randomSceneDefinition(std::uint32_t seed);

}  // namespace rtd::render
