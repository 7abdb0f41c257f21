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
    parser.add_argument("--light-power", type=float, default=160.0,
                        help="the ceiling light's power (W)")
    parser.add_argument("--filter-width", type=float, default=0.01,
                        help="pixel filter width: 0.01 puts every sample at the pixel centre, "
                             "so a 1-spp G-buffer is the primary ray through the centre")
    return parser.parse_args(argv)


def principled(name, color, roughness=0.8, metallic=0.0):
    mat = bpy.data.materials.new(name)
    mat.use_nodes = True
    bsdf = mat.node_tree.nodes["Principled BSDF"]
    bsdf.inputs["Base Color"].default_value = (*color, 1.0)
    bsdf.inputs["Roughness"].default_value = roughness
    bsdf.inputs["Metallic"].default_value = metallic
    bsdf.inputs["Specular"].default_value = 0.0 if metallic == 0.0 else 0.5
    return mat


def checker(name, color1, color2, scale):
    """A diffuse checkerboard in object coordinates, 1 / scale metres a square."""
    mat = principled(name, color1)
    nodes, links = mat.node_tree.nodes, mat.node_tree.links
    coordinates = nodes.new("ShaderNodeTexCoord")
    texture = nodes.new("ShaderNodeTexChecker")
    texture.inputs["Color1"].default_value = (*color1, 1.0)
    texture.inputs["Color2"].default_value = (*color2, 1.0)
    texture.inputs["Scale"].default_value = scale
    links.new(coordinates.outputs["Object"], texture.inputs["Vector"])
    links.new(texture.outputs["Color"], nodes["Principled BSDF"].inputs["Base Color"])
    return mat


def mesh_object(name, vertices, faces, materials, face_materials, pass_index):
    mesh = bpy.data.meshes.new(name)
    mesh.from_pydata(vertices, [], faces)
    for mat in materials:
        mesh.materials.append(mat)
    for polygon, index in zip(mesh.polygons, face_materials):
        polygon.material_index = index
    mesh.update()
    obj = bpy.data.objects.new(name, mesh)
    bpy.context.scene.collection.objects.link(obj)
    obj.pass_index = pass_index
    return obj


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


# The room: x -W..W, y FRONT..BACK, z 0..H; the camera stands inside it near the front wall.
ROOM_W, ROOM_FRONT, ROOM_BACK, ROOM_H = 2.5, -2.6, 3.0, 2.6
# The window in the back wall (x0, x1, z0, z1): the only opening, the sky behind it.
WINDOW = (-0.9, 1.5, 1.25, 2.45)
CAMERA_LOCATION = (0.0, -2.2, 1.3)


def build_room():
    """Walls and ceiling as one mesh (pass_index 1), faces towards the inside."""
    w, f, b, h = ROOM_W, ROOM_FRONT, ROOM_BACK, ROOM_H
    x0, x1, z0, z1 = WINDOW
    vertices, faces, face_materials = [], [], []

    def quad(corners, material_index):
        start = len(vertices)
        vertices.extend(corners)
        faces.append(tuple(range(start, start + 4)))
        face_materials.append(material_index)

    quad([(-w, f, 0), (-w, b, 0), (-w, b, h), (-w, f, h)], 1)  # left, red
    quad([(w, b, 0), (w, f, 0), (w, f, h), (w, b, h)], 2)  # right, green
    quad([(w, f, 0), (-w, f, 0), (-w, f, h), (w, f, h)], 0)  # front, behind the camera
    quad([(-w, f, h), (-w, b, h), (w, b, h), (w, f, h)], 0)  # ceiling
    # The back wall around the window.
    quad([(-w, b, 0), (w, b, 0), (w, b, z0), (-w, b, z0)], 0)
    quad([(-w, b, z1), (w, b, z1), (w, b, h), (-w, b, h)], 0)
    quad([(-w, b, z0), (x0, b, z0), (x0, b, z1), (-w, b, z1)], 0)
    quad([(x1, b, z0), (w, b, z0), (w, b, z1), (x1, b, z1)], 0)
    materials = [principled("white", (0.72, 0.70, 0.65)), principled("red", (0.65, 0.12, 0.08)),
                 principled("green", (0.14, 0.45, 0.16))]
    return mesh_object("Room", vertices, faces, materials, face_materials, 1)


def build_scene(args):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    first, last = args.first_frame, args.first_frame + args.frames - 1

    w, f, b = ROOM_W, ROOM_FRONT, ROOM_BACK
    floor = mesh_object("Floor", [(-w, f, 0), (w, f, 0), (w, b, 0), (-w, b, 0)], [(0, 1, 2, 3)],
                        [checker("floor", (0.70, 0.62, 0.48), (0.22, 0.20, 0.18), 2.0)], [0], 0)
    room = build_room()
    bpy.ops.mesh.primitive_uv_sphere_add(radius=0.6, location=(-1.2, 1.7, 0.6), segments=32,
                                         ring_count=16)
    sphere = bpy.context.object
    bpy.ops.object.shade_smooth()
    add_object(sphere, principled("glossy", (0.8, 0.8, 0.85), roughness=0.3, metallic=1.0), 2)
    sphere.name = "GlossySphere"
    cube_start = Vector((0.1, 0.9, 0.4))
    bpy.ops.mesh.primitive_cube_add(size=0.8, location=cube_start)
    cube = bpy.context.object
    cube.rotation_euler = (0, 0, math.radians(20))
    add_object(cube, principled("cube", (0.15, 0.3, 0.75)), 3).name = "MovingCube"
    linear_keys(cube, "location",
                [(first, cube_start),
                 (last, cube_start + Vector((args.cube_step * (last - first), 0, 0)))])

    # A 1.2 m square ceiling light facing down, above and ahead of the camera on its left, out of
    # its view: the far half of the room is lit mostly by bounced light.
    bpy.ops.object.light_add(type="AREA", location=(-1.6, -1.6, ROOM_H - 0.02))
    light = bpy.context.object
    light.data.energy = args.light_power
    light.data.size = 1.2

    world = bpy.data.worlds.new("World")
    scene.world = world
    world.use_nodes = True
    world.node_tree.nodes["Background"].inputs["Color"].default_value = (0.05, 0.07, 0.12, 1)
    world.node_tree.nodes["Background"].inputs["Strength"].default_value = 1.0

    location = Vector(CAMERA_LOCATION)
    bpy.ops.object.camera_add(location=location, rotation=(math.radians(82), 0, 0))
    camera = bpy.context.object
    camera.data.lens = 32
    camera.data.sensor_fit = "HORIZONTAL"
    scene.camera = camera
    if args.camera == "pan":
        linear_keys(camera, "location",
                    [(first, location),
                     (last, location + Vector((0.1 * (last - first), 0, 0)))])
        linear_keys(camera, "rotation_euler",
                    [(first, Vector((math.radians(82), 0, 0))),
                     (last, Vector((math.radians(82), 0, math.radians(1.0 * (last - first)))))])
    elif args.camera == "dolly":
        linear_keys(camera, "location",
                    [(first, location),
                     (last, location + Vector((0, 0.2 * (last - first), 0)))])

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
    # Cycles' default bounces (12 in all, 4 diffuse, 4 glossy), no clamping.
    scene.cycles.sample_clamp_direct = 0.0
    scene.cycles.sample_clamp_indirect = 0.0
    scene.view_settings.view_transform = "Standard"
    return scene, camera, [floor, room, sphere, cube]


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
            "filterWidth": args.filter_width, "lightPower": args.light_power,
            "blender": bpy.app.version_string,
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
