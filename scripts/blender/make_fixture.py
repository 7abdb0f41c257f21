# Builds a small Cycles scene and renders the noisy frames (multilayer EXR with the passes
# rtdenoise reads) and their converged reference, plus scene.json with each frame's matrices.
#
#   blender -b --factory-startup --python scripts/blender/make_fixture.py -- OUT_DIR [options]
#
# OUT_DIR/noisy/0001.exr ...      multilayer: Combined, Depth, Normal, Position, IndexOB,
#                                 Vector, Denoising Albedo (HALF for colours, FLOAT for data)
# OUT_DIR/reference/0001.exr ...  RGB float EXR at --ref-spp
# OUT_DIR/scene.json              the settings, and per frame (one before the first to one after
#                                 the last): worldToScreen (pixels, y down, w = view depth),
#                                 worldToCamera and each object's local-to-world, row-major
# OUT_DIR/matrices.txt            the same matrices as plain numbers, for the C++ tests
import argparse
import json
import math
import os
import sys

import bpy
from mathutils import Matrix, Vector


def parse_arguments():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    parser = argparse.ArgumentParser(prog="make_fixture.py")
    parser.add_argument("out_dir")
    parser.add_argument("--width", type=int, default=64)
    parser.add_argument("--height", type=int, default=48)
    parser.add_argument("--frames", type=int, default=4)
    parser.add_argument("--first-frame", type=int, default=1)
    parser.add_argument("--spp", type=int, default=1)
    parser.add_argument("--ref-spp", type=int, default=4096)
    parser.add_argument("--seed", type=int, default=7)
    parser.add_argument("--no-reference", action="store_true")
    parser.add_argument("--camera", choices=["static", "pan", "dolly"], default="pan",
                        help="static; pan: yaw 1 degree a frame and a sideways slide; dolly: "
                             "forward 0.2 a frame")
    parser.add_argument("--cube-step", type=float, default=0.15,
                        help="the moving cube's +x translation a frame (world units)")
    parser.add_argument("--filter-width", type=float, default=0.01,
                        help="pixel filter width: 0.01 puts every sample at the pixel centre, "
                             "so a 1-spp G-buffer is the primary ray through the centre")
    return parser.parse_args(argv)


def material(name, color, roughness=0.8, metallic=0.0):
    mat = bpy.data.materials.new(name)
    mat.use_nodes = True
    bsdf = mat.node_tree.nodes["Principled BSDF"]
    bsdf.inputs["Base Color"].default_value = (*color, 1.0)
    bsdf.inputs["Roughness"].default_value = roughness
    bsdf.inputs["Metallic"].default_value = metallic
    return mat


def add_object(obj, mat, pass_index):
    obj.data.materials.append(mat)
    obj.pass_index = pass_index
    return obj


def linear_keys(obj, path, frames_and_values):
    for frame, value in frames_and_values:
        setattr(obj, path, value)
        obj.keyframe_insert(data_path=path, frame=frame)
    for curve in obj.animation_data.action.fcurves:
        curve.extrapolation = "LINEAR"  # so frame 0 (the first frame's "previous") moves too
        for key in curve.keyframe_points:
            key.interpolation = "LINEAR"


def build_scene(args):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    first, last = args.first_frame, args.first_frame + args.frames - 1

    bpy.ops.mesh.primitive_plane_add(size=20, location=(0, 0, 0))
    add_object(bpy.context.object, material("floor", (0.6, 0.6, 0.55)), 0).name = "Floor"
    # The wall does not reach the top of the image: the sky above it is background.
    bpy.ops.mesh.primitive_cube_add(size=1, location=(0, 4, 1.0))
    wall = bpy.context.object
    wall.scale = (12, 0.2, 2.0)
    add_object(wall, material("wall", (0.7, 0.3, 0.25)), 1).name = "Wall"
    bpy.ops.mesh.primitive_uv_sphere_add(radius=0.7, location=(-1.3, 1.5, 0.7), segments=32,
                                         ring_count=16)
    sphere = bpy.context.object
    bpy.ops.object.shade_smooth()
    add_object(sphere, material("glossy", (0.8, 0.8, 0.85), roughness=0.25, metallic=1.0), 2)
    sphere.name = "GlossySphere"
    bpy.ops.mesh.primitive_cube_add(size=1.0, location=(0.2, 0.8, 0.5))
    cube = bpy.context.object
    add_object(cube, material("cube", (0.2, 0.4, 0.8)), 3).name = "MovingCube"
    linear_keys(cube, "location", [(first, Vector((0.2, 0.8, 0.5))),
                                   (last, Vector((0.2 + args.cube_step * (last - first), 0.8,
                                                  0.5)))])

    bpy.ops.object.light_add(type="AREA", location=(1.5, -1.0, 4.0))
    light = bpy.context.object
    light.data.energy = 400.0
    light.data.size = 1.5
    light.rotation_euler = (math.radians(20), math.radians(10), 0)

    world = bpy.data.worlds.new("World")
    scene.world = world
    world.use_nodes = True
    world.node_tree.nodes["Background"].inputs["Color"].default_value = (0.05, 0.07, 0.12, 1)
    world.node_tree.nodes["Background"].inputs["Strength"].default_value = 1.0

    bpy.ops.object.camera_add(location=(0, -6, 1.6), rotation=(math.radians(82), 0, 0))
    camera = bpy.context.object
    camera.data.lens = 32
    camera.data.sensor_fit = "HORIZONTAL"
    scene.camera = camera
    if args.camera == "pan":
        linear_keys(camera, "location",
                    [(first, Vector((0, -6, 1.6))),
                     (last, Vector((0.1 * (last - first), -6, 1.6)))])
        linear_keys(camera, "rotation_euler",
                    [(first, Vector((math.radians(82), 0, 0))),
                     (last, Vector((math.radians(82), 0, math.radians(1.0 * (last - first)))))])
    elif args.camera == "dolly":
        linear_keys(camera, "location",
                    [(first, Vector((0, -6, 1.6))),
                     (last, Vector((0, -6 + 0.2 * (last - first), 1.6)))])

    scene.frame_start, scene.frame_end = first, last
    scene.render.resolution_x, scene.render.resolution_y = args.width, args.height
    scene.render.resolution_percentage = 100
    scene.render.use_motion_blur = False  # with it on, Cycles writes a Vector pass of zeros
    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.seed = args.seed
    scene.cycles.use_animated_seed = True  # independent noise per frame, still deterministic
    scene.cycles.use_adaptive_sampling = False
    scene.cycles.use_denoising = False  # the noisy frames are the input; Debian's build lacks OIDN
    scene.cycles.filter_width = args.filter_width
    scene.cycles.max_bounces = 6
    scene.cycles.sample_clamp_indirect = 0.0
    scene.view_settings.view_transform = "Standard"
    return scene, camera, [bpy.data.objects[n] for n in
                           ("Floor", "Wall", "GlossySphere", "MovingCube")]


def enable_passes(view_layer):
    view_layer.use_pass_combined = True
    view_layer.use_pass_z = True
    view_layer.use_pass_normal = True
    view_layer.use_pass_position = True
    view_layer.use_pass_object_index = True
    view_layer.use_pass_vector = True
    view_layer.cycles.denoising_store_passes = True  # Denoising Albedo (and Normal)


def row_major(m):
    return [[float(m[r][c]) for c in range(4)] for r in range(4)]


def world_to_screen(scene, camera, width, height):
    # Blender's projection gives clip coordinates with w = -z_camera (camera looks down -z);
    # pixels: x right from the left edge, y down from the top edge, pixel centres at +0.5.
    depsgraph = bpy.context.evaluated_depsgraph_get()
    projection = camera.calc_matrix_camera(depsgraph, x=width, y=height)
    to_pixels = Matrix(((width / 2, 0, 0, width / 2), (0, -height / 2, 0, height / 2),
                        (0, 0, 0, 1), (0, 0, 0, 1)))
    return to_pixels @ projection @ camera.matrix_world.inverted()


def write_scene_json(path, scene, camera, objects, args):
    frames = []
    for frame in range(scene.frame_start - 1, scene.frame_end + 1):
        scene.frame_set(frame)
        frames.append({
            "frame": frame,
            "worldToScreen": row_major(world_to_screen(scene, camera, args.width, args.height)),
            "worldToCamera": row_major(camera.matrix_world.inverted()),
            "cameraToWorld": row_major(camera.matrix_world),
            "objects": {o.name: {"passIndex": o.pass_index,
                                 "objectToWorld": row_major(o.matrix_world)} for o in objects},
        })
    scene.frame_set(scene.frame_start)
    with open(os.path.join(os.path.dirname(path), "matrices.txt"), "w") as f:
        f.write("# <frame> screen <worldToScreen, 16 numbers row-major: pixels, y down, w = view "
                "depth>\n# <frame> camera <x y z: the camera position>\n"
                "# <frame> object <pass_index> <objectToWorld, 16 numbers row-major>\n")
        for entry in frames:
            numbers = lambda m: " ".join(repr(v) for row in m for v in row)
            f.write(f"{entry['frame']} screen {numbers(entry['worldToScreen'])}\n")
            position = [entry["cameraToWorld"][r][3] for r in range(3)]
            f.write(f"{entry['frame']} camera {' '.join(repr(v) for v in position)}\n")
            for name, o in entry["objects"].items():
                f.write(f"{entry['frame']} object {o['passIndex']} "
                        f"{numbers(o['objectToWorld'])}\n")
    info = {"width": args.width, "height": args.height, "firstFrame": scene.frame_start,
            "frameCount": args.frames, "spp": args.spp, "referenceSpp": args.ref_spp,
            "seed": args.seed, "camera": args.camera, "cubeStep": args.cube_step,
            "filterWidth": args.filter_width, "blender": bpy.app.version_string,
            "frames": frames}
    with open(path, "w") as f:
        json.dump(info, f, indent=1)


def render_noisy(scene, out_dir, spp):
    enable_passes(scene.view_layers[0])
    scene.cycles.samples = spp
    settings = scene.render.image_settings
    settings.file_format = "OPEN_EXR_MULTILAYER"
    settings.color_depth = "16"  # Blender keeps its data passes FLOAT in a half file
    settings.exr_codec = "ZIP"
    scene.render.filepath = os.path.join(out_dir, "noisy", "")
    bpy.ops.render.render(animation=True)


def render_reference(scene, out_dir, spp):
    layer = scene.view_layers[0]
    for name in ("use_pass_z", "use_pass_normal", "use_pass_position", "use_pass_object_index",
                 "use_pass_vector"):
        setattr(layer, name, False)
    layer.cycles.denoising_store_passes = False
    scene.cycles.samples = spp
    # The same pixel filter as the noisy frames: the reference is their expected value.
    settings = scene.render.image_settings
    settings.file_format = "OPEN_EXR"
    settings.color_mode = "RGB"
    settings.color_depth = "32"
    settings.exr_codec = "ZIP"
    scene.render.filepath = os.path.join(out_dir, "reference", "")
    bpy.ops.render.render(animation=True)


def main():
    args = parse_arguments()
    out_dir = os.path.abspath(args.out_dir)
    os.makedirs(out_dir, exist_ok=True)
    scene, camera, objects = build_scene(args)
    write_scene_json(os.path.join(out_dir, "scene.json"), scene, camera, objects, args)
    render_noisy(scene, out_dir, args.spp)
    if not args.no_reference:
        render_reference(scene, out_dir, args.ref_spp)


main()
