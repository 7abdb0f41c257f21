# The Cycles validation scenes (docs/validation_scenes.md): four scenes built here from nothing
# (geometry, materials, lights and animation; no .blend file), rendered as Blender writes them
# for a user: 1-spp multilayer EXRs with the passes rtdenoise reads, equal-sample renders and a
# point-sampled reference.
#
#   blender -b -noaudio --python-exit-code 1 --factory-startup \
#       -P scripts/blender/validation_scenes.py -- OUT_DIR --scene NAME [options]
#
# OUT_DIR/NAME/noisy/0001.exr ...      1 spp, OpenEXR MultiLayer (FLOAT), passes Combined, Depth,
#                                      Normal, Position, IndexOB, Vector, Denoising Albedo (and
#                                      Denoising Normal, Denoising Depth)
# OUT_DIR/NAME/spp4/0001.exr ...       equal-sample renders, RGB float EXR (--equal-spp)
# OUT_DIR/NAME/reference/0001.exr ...  RGB float EXR at --reference-spp
# OUT_DIR/NAME/scene.json              every setting and, per frame (one before the first to one
#                                      after the last), worldToScreen and cameraToWorld
# OUT_DIR/NAME/render_times.tsv        seconds per rendered frame
#
# Frames already on disk are kept (a frame is written to OUT_DIR/NAME/tmp/ and moved into place
# when complete), so an interrupted run resumes; a scene.json written with other settings
# (size, frames, seed, VERSION) is an error rather than a mix of two renders.
#
# VERSION names the scenes: change it with any change to what a scene renders (geometry,
# materials, lights, animation, render settings), so that old caches are refused, not mixed.
#
# Facts this relies on (Blender 3.4.1, measured; see scripts/blender/make_fixture.py and
# docs/inputs.md):
# - Cycles computes the Vector pass from the scene evaluated at frames i-1 and i+1: every moving
#   thing is keyframed (a transform set by a script alone gives Vector = 0 everywhere), with
#   linear extrapolation so the first and last frames move too; motion blur is off (with it on,
#   Vector is all zeros).
# - With the box filter Cycles spreads every sample after the first over the pixel, so an N-spp
#   render is anti-aliased while a 1-spp one is a point sample. Every render here uses a Gaussian
#   pixel filter 0.01 px wide: all samples at the pixel centre, so the reference is the 1-spp
#   input's expected value.
# - Debian's build has no OpenImageDenoise: denoising must be off (Denoising Data still writes
#   Denoising Albedo; there is no Noisy Image pass).
# - Cycles 3.4 renders mesh lights (emission with Multiple Importance on) differently from run to
#   run: every Emission material here has it off (emission()), so a frame rendered again is the
#   same to 1e-4 (floating-point order), the noise included.
import argparse
import json
import math
import os
import sys
import time

import bmesh
import bpy
from mathutils import Matrix, Vector

VERSION = "validation-scenes 2"
SCENES = ("indirect-room", "texture-gallery", "small-lights", "light-switch")
SEED_OFFSETS = {"noisy": 0, "reference": 1000}  # sppN: N; distinct seeds, independent noise


def parse_arguments():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    parser = argparse.ArgumentParser(prog="validation_scenes.py")
    parser.add_argument("out_dir")
    parser.add_argument("--scene", choices=SCENES, required=True)
    parser.add_argument("--kinds", default="noisy,spp4,spp16,spp64,reference",
                        help="what to render, in order: noisy, sppN (an N-spp render), reference")
    parser.add_argument("--width", type=int, default=320)
    parser.add_argument("--height", type=int, default=240)
    parser.add_argument("--frames", type=int, default=16)
    parser.add_argument("--reference-spp", type=int, default=1024)
    parser.add_argument("--seed", type=int, default=1,
                        help="base seed; each kind adds its own offset, animated per frame")
    parser.add_argument("--png", action="store_true",
                        help="also write NAME/preview/<kind>_0001.png (Standard view, sRGB)")
    return parser.parse_args(argv)


# ---- materials ----

def principled(name, color, roughness=0.8, metallic=0.0, specular=0.5, clearcoat=0.0):
    mat = bpy.data.materials.new(name)
    mat.use_nodes = True
    bsdf = mat.node_tree.nodes["Principled BSDF"]
    bsdf.inputs["Base Color"].default_value = (*color, 1.0)
    bsdf.inputs["Roughness"].default_value = roughness
    bsdf.inputs["Metallic"].default_value = metallic
    bsdf.inputs["Specular"].default_value = specular
    bsdf.inputs["Clearcoat"].default_value = clearcoat
    return mat


def _object_coordinates(mat):
    return mat.node_tree.nodes.new("ShaderNodeTexCoord").outputs["Object"]


def checker(name, color1, color2, scale, roughness=0.8, metallic=0.0, specular=0.5):
    """Checkerboard in object coordinates (metres): Blender's checker of scale s has squares
    1 / (2 s) m wide."""
    mat = principled(name, color1, roughness, metallic, specular)
    nodes, links = mat.node_tree.nodes, mat.node_tree.links
    texture = nodes.new("ShaderNodeTexChecker")
    texture.inputs["Color1"].default_value = (*color1, 1.0)
    texture.inputs["Color2"].default_value = (*color2, 1.0)
    texture.inputs["Scale"].default_value = scale
    links.new(_object_coordinates(mat), texture.inputs["Vector"])
    links.new(texture.outputs["Color"], nodes["Principled BSDF"].inputs["Base Color"])
    return mat


def brick(name, brick1, brick2, mortar, scale, roughness=0.6, roughness_noise=0.0):
    """Brick texture (object coordinates); roughness_noise > 0 varies the roughness with a noise
    texture of the same frequency band (glossy patches)."""
    mat = principled(name, brick1, roughness)
    nodes, links = mat.node_tree.nodes, mat.node_tree.links
    coords = _object_coordinates(mat)
    texture = nodes.new("ShaderNodeTexBrick")
    texture.inputs["Color1"].default_value = (*brick1, 1.0)
    texture.inputs["Color2"].default_value = (*brick2, 1.0)
    texture.inputs["Mortar"].default_value = (*mortar, 1.0)
    texture.inputs["Scale"].default_value = scale
    texture.inputs["Mortar Size"].default_value = 0.015
    links.new(coords, texture.inputs["Vector"])
    bsdf = nodes["Principled BSDF"]
    links.new(texture.outputs["Color"], bsdf.inputs["Base Color"])
    if roughness_noise > 0.0:
        noise = nodes.new("ShaderNodeTexNoise")
        noise.inputs["Scale"].default_value = scale * 0.7
        noise.inputs["Detail"].default_value = 4.0
        ramp = nodes.new("ShaderNodeMapRange")
        ramp.inputs["To Min"].default_value = max(0.0, roughness - roughness_noise)
        ramp.inputs["To Max"].default_value = min(1.0, roughness + roughness_noise)
        links.new(coords, noise.inputs["Vector"])
        links.new(noise.outputs["Fac"], ramp.inputs["Value"])
        links.new(ramp.outputs["Result"], bsdf.inputs["Roughness"])
    return mat


def noise_color(name, color1, color2, scale, detail, roughness=0.8, distortion=0.0,
                metallic=0.0, specular=0.5):
    """Two colours mixed by a noise texture (object coordinates), contrast from a colour ramp."""
    mat = principled(name, color1, roughness, metallic, specular)
    nodes, links = mat.node_tree.nodes, mat.node_tree.links
    noise = nodes.new("ShaderNodeTexNoise")
    noise.inputs["Scale"].default_value = scale
    noise.inputs["Detail"].default_value = detail
    noise.inputs["Distortion"].default_value = distortion
    ramp = nodes.new("ShaderNodeValToRGB")
    ramp.color_ramp.elements[0].position = 0.35
    ramp.color_ramp.elements[0].color = (*color1, 1.0)
    ramp.color_ramp.elements[1].position = 0.65
    ramp.color_ramp.elements[1].color = (*color2, 1.0)
    links.new(_object_coordinates(mat), noise.inputs["Vector"])
    links.new(noise.outputs["Fac"], ramp.inputs["Fac"])
    links.new(ramp.outputs["Color"], nodes["Principled BSDF"].inputs["Base Color"])
    return mat


def emission(name, color, strength):
    """An Emission shader with Multiple Importance off (Material > Settings > Surface): Cycles
    finds the surface only by hitting it, not by sampling it as a light. Users do this for small
    or decorative emitters; here it is also what keeps a render reproducible: with it on, Cycles
    3.4 renders a scene with a mesh light differently from run to run (measured: a plane, a cube
    and one emissive sphere rendered four times, 50 % of the pixels differ between any two runs;
    with it off, none)."""
    mat = bpy.data.materials.new(name)
    mat.cycles.sample_as_light = False
    mat.use_nodes = True
    nodes = mat.node_tree.nodes
    nodes.remove(nodes["Principled BSDF"])
    node = nodes.new("ShaderNodeEmission")
    node.inputs["Color"].default_value = (*color, 1.0)
    node.inputs["Strength"].default_value = strength
    mat.node_tree.links.new(node.outputs["Emission"], nodes["Material Output"].inputs["Surface"])
    return mat, node


# ---- geometry ----

def mesh_object(name, vertices, faces, materials, face_materials, pass_index,
                location=(0, 0, 0), smooth=False):
    mesh = bpy.data.meshes.new(name)
    mesh.from_pydata(vertices, [], faces)
    for mat in materials:
        mesh.materials.append(mat)
    for polygon, index in zip(mesh.polygons, face_materials):
        polygon.material_index = index
        polygon.use_smooth = smooth
    mesh.update()
    obj = bpy.data.objects.new(name, mesh)
    obj.location = location
    bpy.context.scene.collection.objects.link(obj)
    obj.pass_index = pass_index
    return obj


def box(name, center, size, mat, pass_index, rotation_z=0.0):
    """An axis-aligned box of size (sx, sy, sz) around its origin, placed at center: object
    coordinates are metres, so textures keep their scale."""
    hx, hy, hz = (s / 2 for s in size)
    v = [(-hx, -hy, -hz), (hx, -hy, -hz), (hx, hy, -hz), (-hx, hy, -hz),
         (-hx, -hy, hz), (hx, -hy, hz), (hx, hy, hz), (-hx, hy, hz)]
    f = [(0, 3, 2, 1), (4, 5, 6, 7), (0, 1, 5, 4), (1, 2, 6, 5), (2, 3, 7, 6), (3, 0, 4, 7)]
    obj = mesh_object(name, v, f, [mat], [0] * 6, pass_index, location=center)
    obj.rotation_euler = (0, 0, rotation_z)
    return obj


def sphere(name, center, radius, mat, pass_index, segments=48, rings=24):
    bpy.ops.mesh.primitive_uv_sphere_add(radius=radius, location=center, segments=segments,
                                         ring_count=rings)
    obj = bpy.context.object
    bpy.ops.object.shade_smooth()
    obj.name = name
    obj.data.materials.append(mat)
    obj.pass_index = pass_index
    return obj


def spheres_object(name, location, centers, radius, materials, pass_index):
    """One mesh of small spheres (sphere i: centers[i] relative to `location`, materials[i]),
    moving as one object."""
    mesh = bpy.data.meshes.new(name)
    bm = bmesh.new()
    for index, center in enumerate(centers):
        geometry = bmesh.ops.create_uvsphere(bm, u_segments=16, v_segments=8, radius=radius)
        bmesh.ops.translate(bm, verts=geometry["verts"], vec=Vector(center))
        for face in {f for v in geometry["verts"] for f in v.link_faces}:
            face.material_index = index
            face.smooth = True
    bm.to_mesh(mesh)
    bm.free()
    for mat in materials:
        mesh.materials.append(mat)
    obj = bpy.data.objects.new(name, mesh)
    obj.location = location
    bpy.context.scene.collection.objects.link(obj)
    obj.pass_index = pass_index
    return obj


def wall_with_holes(origin, u_axis, v_axis, u_len, v_len, holes):
    """Quads covering the rectangle origin + [0, u_len] u_axis + [0, v_len] v_axis except the
    holes ((u0, u1, v0, v1), ...): the grid their edges make, minus the cells inside a hole."""
    us = sorted({0.0, u_len, *[h[0] for h in holes], *[h[1] for h in holes]})
    vs = sorted({0.0, v_len, *[h[2] for h in holes], *[h[3] for h in holes]})
    o, du, dv = Vector(origin), Vector(u_axis), Vector(v_axis)
    quads = []
    for i in range(len(us) - 1):
        for j in range(len(vs) - 1):
            cu, cv = (us[i] + us[i + 1]) / 2, (vs[j] + vs[j + 1]) / 2
            if any(h[0] <= cu <= h[1] and h[2] <= cv <= h[3] for h in holes):
                continue
            quads.append([tuple(o + du * a + dv * b) for a, b in
                          ((us[i], vs[j]), (us[i + 1], vs[j]), (us[i + 1], vs[j + 1]),
                           (us[i], vs[j + 1]))])
    return quads


def room(name, x0, x1, y0, y1, z0, z1, materials, wall_material, holes=None, ceiling=True,
         pass_index=1, skip=()):
    """Walls (and ceiling) of a box room, faces towards the inside. wall_material: the material
    index of each of left (x0), right (x1), front (y0), back (y1), ceiling; holes: per wall name,
    rectangles in that wall's (u, v) metres, u along the wall from its first corner, v up;
    skip: walls left out (shared with another room)."""
    holes = holes or {}
    w, d, h = x1 - x0, y1 - y0, z1 - z0
    walls = {
        # name: origin, u axis, v axis, u length, v length (u x v points into the room)
        "left": ((x0, y1, z0), (0, -1, 0), (0, 0, 1), d, h),
        "right": ((x1, y0, z0), (0, 1, 0), (0, 0, 1), d, h),
        "front": ((x0, y0, z0), (1, 0, 0), (0, 0, 1), w, h),
        "back": ((x1, y1, z0), (-1, 0, 0), (0, 0, 1), w, h),
    }
    if ceiling:
        walls["ceiling"] = ((x0, y0, z1), (0, 1, 0), (1, 0, 0), d, w)
    vertices, faces, face_materials = [], [], []
    for wall, (origin, u, v, ul, vl) in walls.items():
        if wall in skip:
            continue
        for quad in wall_with_holes(origin, u, v, ul, vl, holes.get(wall, [])):
            start = len(vertices)
            vertices.extend(quad)
            faces.append(tuple(range(start, start + 4)))
            face_materials.append(wall_material[wall])
    return mesh_object(name, vertices, faces, materials, face_materials, pass_index)


def floor(name, x0, x1, y0, y1, mat, pass_index, z=0.0):
    return mesh_object(name, [(x0, y0, z), (x1, y0, z), (x1, y1, z), (x0, y1, z)],
                       [(0, 1, 2, 3)], [mat], [0], pass_index)


# ---- animation ----

def linear_keys(owner, path, frames_and_values):
    """Keys with linear interpolation and linear extrapolation: the scene at first - 1 and
    last + 1 (the Vector pass of the first and last frames) continues the motion."""
    for frame, value in frames_and_values:
        setattr(owner, path, value)
        owner.keyframe_insert(data_path=path, frame=frame)
    _set_curves(owner, path, "LINEAR", "LINEAR")


def constant_keys(owner, path, frames_and_values):
    """Step keys (a light switched): the value holds until the next key."""
    for frame, value in frames_and_values:
        setattr(owner, path, value)
        owner.keyframe_insert(data_path=path, frame=frame)
    _set_curves(owner, path, "CONSTANT", "CONSTANT")


def _set_curves(owner, path, interpolation, extrapolation):
    for curve in owner.animation_data.action.fcurves:
        if curve.data_path != path:
            continue
        curve.extrapolation = extrapolation
        for key in curve.keyframe_points:
            key.interpolation = interpolation


def keyed_emission_strength(node, frames_and_values):
    """Keys an emission node's strength (a visible lamp panel switched with its light)."""
    socket = node.inputs["Strength"]
    for frame, value in frames_and_values:
        socket.default_value = value
        socket.keyframe_insert("default_value", frame=frame)
    tree = node.id_data
    for curve in tree.animation_data.action.fcurves:
        curve.extrapolation = "CONSTANT"
        for key in curve.keyframe_points:
            key.interpolation = "CONSTANT"


# ---- lights, world, camera ----

def area_light(name, location, rotation, size, energy, color=(1, 1, 1), size_y=None):
    data = bpy.data.lights.new(name, "AREA")
    data.energy = energy
    data.color = color
    if size_y is None:
        data.shape = "SQUARE"
        data.size = size
    else:
        data.shape = "RECTANGLE"
        data.size, data.size_y = size, size_y
    obj = bpy.data.objects.new(name, data)
    obj.location, obj.rotation_euler = location, rotation
    bpy.context.scene.collection.objects.link(obj)
    return obj


def point_light(name, location, energy, radius, color=(1, 1, 1)):
    data = bpy.data.lights.new(name, "POINT")
    data.energy, data.shadow_soft_size, data.color = energy, radius, color
    obj = bpy.data.objects.new(name, data)
    obj.location = location
    bpy.context.scene.collection.objects.link(obj)
    return obj


def spot_light(name, location, rotation, energy, radius, angle_deg, blend, color=(1, 1, 1)):
    data = bpy.data.lights.new(name, "SPOT")
    data.energy, data.shadow_soft_size, data.color = energy, radius, color
    data.spot_size, data.spot_blend = math.radians(angle_deg), blend
    obj = bpy.data.objects.new(name, data)
    obj.location, obj.rotation_euler = location, rotation
    bpy.context.scene.collection.objects.link(obj)
    return obj


def sun_light(name, rotation, strength, angle_deg, color=(1, 1, 1)):
    data = bpy.data.lights.new(name, "SUN")
    data.energy, data.angle, data.color = strength, math.radians(angle_deg), color
    obj = bpy.data.objects.new(name, data)
    obj.rotation_euler = rotation
    bpy.context.scene.collection.objects.link(obj)
    return obj


def world(color, strength):
    w = bpy.data.worlds.new("World")
    bpy.context.scene.world = w
    w.use_nodes = True
    background = w.node_tree.nodes["Background"]
    background.inputs["Color"].default_value = (*color, 1)
    background.inputs["Strength"].default_value = strength


def camera(location, rotation_deg, lens=28.0):
    bpy.ops.object.camera_add(location=location,
                              rotation=tuple(math.radians(a) for a in rotation_deg))
    cam = bpy.context.object
    cam.data.lens = lens
    cam.data.sensor_fit = "HORIZONTAL"
    bpy.context.scene.camera = cam
    return cam


def camera_move(cam, first, last, move=(0, 0, 0), turn_deg=(0, 0, 0)):
    """Keyframed camera motion: `move` metres and `turn_deg` degrees (Euler XYZ) per frame."""
    location, rotation = Vector(cam.location), Vector(cam.rotation_euler)
    frames = last - first
    linear_keys(cam, "location", [(first, location),
                                  (last, location + Vector(move) * frames)])
    linear_keys(cam, "rotation_euler",
                [(first, rotation),
                 (last, rotation + Vector([math.radians(a) for a in turn_deg]) * frames)])


# ---- the scenes ----
# Coordinates: metres, z up; each scene returns (camera, moving/notable objects, description).

def scene_indirect_room(first, last):
    """(a) Indirect light dominant. A closed room whose only opening is a doorway in its right
    wall, onto a roofless courtyard where the sun falls on the far floor and wall, not through
    the door; and a strip light hidden on top of a tall cabinet, aimed at the ceiling. Nothing in
    view but the ceiling patch and the courtyard is lit directly: the room is lit by one and
    two bounces. A box slides out from behind the table (disocclusion), the camera dollies in."""
    white = principled("plaster", (0.75, 0.73, 0.68), roughness=0.9)
    blue = principled("blue paint", (0.20, 0.32, 0.62), roughness=0.85)
    ochre = principled("ochre render", (0.70, 0.52, 0.30), roughness=0.9)
    wood = noise_color("wood floor", (0.42, 0.28, 0.16), (0.58, 0.42, 0.26), scale=3.0,
                       detail=6.0, roughness=0.55, distortion=1.5)
    stone = noise_color("courtyard stone", (0.55, 0.52, 0.46), (0.72, 0.69, 0.62), scale=6.0,
                        detail=4.0, roughness=0.9)
    room("Room", -2.5, 2.5, -3.0, 3.0, 0.0, 2.8, [white, blue],
         {"left": 1, "right": 0, "front": 0, "back": 0, "ceiling": 0},
         holes={"right": [(3.4, 4.5, 0.0, 2.1)]}, pass_index=1)
    floor("Floor", -2.5, 2.5, -3.0, 3.0, wood, 2)
    # Its west wall is the room's right wall (the door: y 0.4..1.5).
    room("Courtyard", 2.5, 7.0, -1.5, 3.0, 0.0, 3.6, [ochre],
         {"left": 0, "right": 0, "front": 0, "back": 0}, ceiling=False, pass_index=3,
         skip=("left",))
    floor("CourtyardFloor", 2.5, 7.0, -1.5, 3.0, stone, 4)
    # The cabinet hiding the strip light (on its top, aimed at the ceiling), against the left wall.
    box("Cabinet", (-2.05, 0.9, 1.05), (0.7, 1.6, 2.1), principled("cabinet", (0.35, 0.22, 0.14),
        roughness=0.6), 5)
    area_light("CoveLight", (-2.05, 0.9, 2.12), (math.pi, 0, 0), 0.3, 220.0, color=(1.0, 0.85, 0.7),
               size_y=1.4)
    # A table with thin legs, a sphere on it, a column, the sliding box.
    table = principled("table", (0.65, 0.62, 0.58), roughness=0.4)
    box("TableTop", (0.3, 1.2, 0.74), (1.4, 0.8, 0.04), table, 6)
    for i, (dx, dy) in enumerate(((-0.65, -0.35), (0.65, -0.35), (-0.65, 0.35), (0.65, 0.35))):
        box(f"TableLeg{i}", (0.3 + dx, 1.2 + dy, 0.36), (0.04, 0.04, 0.72), table, 6)
    sphere("Sphere", (0.0, 1.2, 0.96), 0.2, principled("sphere", (0.8, 0.8, 0.8), 0.5), 7)
    box("Column", (1.6, 2.2, 1.4), (0.35, 0.35, 2.8), white, 8)
    slider = box("SlidingBox", (0.4, 1.5, 0.25), (0.5, 0.5, 0.5),
                 principled("red box", (0.70, 0.15, 0.10), roughness=0.7), 9,
                 rotation_z=math.radians(15))
    linear_keys(slider, "location", [(first, Vector(slider.location)),
                                     (last, Vector(slider.location)
                                      + Vector((-0.06, -0.05, 0)) * (last - first))])
    # Sun from the left, high: it falls past the door onto the courtyard's far half and its far
    # wall (light travels along the lamp's -z).
    sun_light("Sun", (math.radians(38), 0, math.radians(-90)), 4.0, 1.0, color=(1.0, 0.95, 0.88))
    world((0.45, 0.6, 0.9), 0.6)
    cam = camera((-1.2, -2.7, 1.45), (85, 0, -18), lens=24)
    camera_move(cam, first, last, move=(0.015, 0.05, 0), turn_deg=(0, 0, 0.3))
    return cam, [slider]


def scene_texture_gallery(first, last):
    """(b) Textures at several frequencies, glossy and metal. A room with a brick floor whose
    roughness varies (glossy patches), a noise-textured wall, a fine checker wall near the pixel
    frequency, a near-mirror panel, a row of spheres (near-mirror chrome, brushed-like metals of
    rough 0.2 and 0.45, a glossy red dielectric, a textured glossy sphere) and a slowly rotating
    clear-coated textured cube; the camera pans and slides."""
    bricks = brick("brick floor", (0.55, 0.25, 0.16), (0.38, 0.20, 0.14), (0.75, 0.72, 0.66),
                   scale=2.0, roughness=0.3, roughness_noise=0.2)
    plaster = noise_color("noise wall", (0.30, 0.45, 0.55), (0.80, 0.78, 0.70), scale=2.5,
                          detail=10.0, roughness=0.9)
    fine = checker("fine checker", (0.85, 0.85, 0.82), (0.08, 0.08, 0.09), scale=6.0)
    white = principled("white", (0.8, 0.8, 0.78), roughness=0.8)
    room("Room", -3.0, 3.0, -2.5, 5.0, 0.0, 3.0, [plaster, fine, white],
         {"left": 1, "right": 0, "front": 2, "back": 0, "ceiling": 2}, pass_index=1)
    floor("Floor", -3.0, 3.0, -2.5, 5.0, bricks, 2)
    # The mirror: 1.8 x 1.8 m on the back wall behind the spheres, 1 cm in front of it.
    mirror = principled("near mirror", (0.92, 0.92, 0.92), roughness=0.02, metallic=1.0)
    mesh_object("Mirror", [(0.6, 4.99, 0.4), (2.4, 4.99, 0.4), (2.4, 4.99, 2.2),
                           (0.6, 4.99, 2.2)], [(0, 1, 2, 3)], [mirror], [0], 3)
    spheres = [
        ("Chrome", principled("chrome", (0.95, 0.95, 0.95), roughness=0.03, metallic=1.0)),
        ("Gold", principled("gold", (1.0, 0.77, 0.34), roughness=0.2, metallic=1.0)),
        ("Copper", principled("copper", (0.95, 0.64, 0.54), roughness=0.45, metallic=1.0)),
        ("RedGloss", principled("red gloss", (0.7, 0.06, 0.05), roughness=0.08)),
        ("NoiseGloss", noise_color("noise gloss", (0.1, 0.3, 0.12), (0.85, 0.8, 0.2), 8.0,
                                   4.0, roughness=0.25)),
    ]
    for i, (name, mat) in enumerate(spheres):
        sphere(name, (-2.0 + i * 1.0, 2.6, 0.4), 0.38, mat, 4 + i)
    cube_mat = checker("cube checker", (0.9, 0.5, 0.1), (0.1, 0.1, 0.3), scale=3.0,
                       roughness=0.35)
    cube_mat.node_tree.nodes["Principled BSDF"].inputs["Clearcoat"].default_value = 1.0
    cube = box("RotatingCube", (0.3, 1.0, 0.35), (0.7, 0.7, 0.7), cube_mat, 9)
    linear_keys(cube, "rotation_euler", [(first, Vector((0, 0, 0))),
                                         (last, Vector((0, 0, math.radians(3.0 * (last - first)))))])
    area_light("CeilingLight", (0.0, 1.2, 2.98), (0, 0, 0), 2.0, 300.0, size_y=1.0)
    area_light("SideLight", (-2.9, -1.0, 1.8), (0, math.radians(-90), 0), 0.6, 80.0,
               color=(0.8, 0.9, 1.0))
    world((0.05, 0.05, 0.05), 1.0)
    cam = camera((-1.6, -2.2, 1.5), (80, 0, 4), lens=26)
    camera_move(cam, first, last, move=(0.04, 0.0, 0.0), turn_deg=(0, 0, -1.0))
    return cam, [cube]


def scene_small_lights(first, last):
    """(c) Small bright lights. A dim room lit only by small sources: three tiny coloured point
    lights (2 cm), a narrow spot, a 10 cm area light and four emissive beads (4 cm) that orbit a
    rotating chrome torus, over a glossy tiled floor. At 1 spp most pixels see none of them and
    a few see one through a glossy bounce: fireflies. The camera stands still; the beads, their
    light and the torus move."""
    tiles = checker("glossy tiles", (0.25, 0.25, 0.27), (0.06, 0.06, 0.07), scale=1.5,
                    roughness=0.15)
    grey = principled("grey wall", (0.45, 0.45, 0.45), roughness=0.85)
    dark = principled("dark wall", (0.12, 0.14, 0.2), roughness=0.7)
    room("Room", -3.0, 3.0, -2.5, 4.0, 0.0, 2.6, [grey, dark],
         {"left": 0, "right": 0, "front": 0, "back": 1, "ceiling": 0}, pass_index=1)
    floor("Floor", -3.0, 3.0, -2.5, 4.0, tiles, 2)
    box("Plinth", (0.0, 1.5, 0.3), (0.8, 0.8, 0.6),
        principled("plinth", (0.6, 0.6, 0.62), roughness=0.5), 3)
    bpy.ops.mesh.primitive_torus_add(location=(0.0, 1.5, 0.95), major_radius=0.3,
                                     minor_radius=0.08, major_segments=64, minor_segments=24,
                                     rotation=(math.radians(90), 0, 0))
    torus = bpy.context.object
    torus.name = "Torus"
    bpy.ops.object.shade_smooth()
    torus.data.materials.append(principled("torus metal", (0.9, 0.9, 0.92), roughness=0.1,
                                           metallic=1.0))
    torus.pass_index = 4
    linear_keys(torus, "rotation_euler",
                [(first, Vector(torus.rotation_euler)),
                 (last, Vector(torus.rotation_euler)
                  + Vector((0, 0, math.radians(4.0 * (last - first)))))])
    sphere("Ball", (-1.3, 0.6, 0.35), 0.35,
           principled("ball", (0.8, 0.75, 0.7), roughness=0.35, specular=0.5), 5)
    box("Crate", (1.5, 0.4, 0.3), (0.6, 0.6, 0.6), principled("crate", (0.5, 0.35, 0.2), 0.8), 6,
        rotation_z=math.radians(30))
    # The orbiting beads: one object (see spheres_object) spinning about the torus' axis.
    colours = [(1.0, 0.5, 0.2), (0.3, 0.6, 1.0), (1.0, 0.2, 0.6), (0.6, 1.0, 0.4)]
    beads = spheres_object(
        "Beads", (0.0, 1.5, 0.95),
        [(0.7 * math.cos(i * math.pi / 2), 0.7 * math.sin(i * math.pi / 2), 0.15 * (i % 2) - 0.05)
         for i in range(4)], 0.04,
        [emission(f"bead{i}", colour, 120.0)[0] for i, colour in enumerate(colours)], 10)
    linear_keys(beads, "rotation_euler",
                [(first, Vector((0, 0, 0))),
                 (last, Vector((0, 0, math.radians(6.0 * (last - first)))))])
    point_light("WarmPoint", (-2.4, 3.4, 2.2), 40.0, 0.02, color=(1.0, 0.7, 0.4))
    point_light("CoolPoint", (2.5, 3.0, 0.4), 25.0, 0.02, color=(0.4, 0.6, 1.0))
    point_light("MagentaPoint", (2.2, -1.0, 2.3), 30.0, 0.02, color=(1.0, 0.3, 0.8))
    spot_light("Spot", (-1.5, 1.0, 2.55), (0, 0, 0), 300.0, 0.01, 25.0, 0.15)
    area_light("SmallArea", (2.9, 1.8, 1.6), (0, math.radians(90), 0), 0.1, 15.0)
    world((0.0, 0.0, 0.0), 0.0)
    cam = camera((0.3, -2.2, 1.35), (78, 0, 2), lens=26)
    return cam, [torus, beads]


def switch_keys(first, frames, on_at_start, switches):
    """(frame, on) keys: the state at `first`, then a toggle at each fraction of the sequence."""
    keys, on = [(first, on_at_start)], on_at_start
    for fraction in switches:
        on = not on
        keys.append((first + max(1, round(fraction * frames)), on))
    return keys


def scene_light_switch(first, last):
    """(d) Lighting that changes, with camera motion. A living room at dusk: a dim blue sky
    through a window, a ceiling panel that switches off at 30 % of the sequence and on again at
    65 %, a floor lamp (spot) that switches on at 45 %; the camera dollies in and pans. Light
    changes on every surface at once, under motion: history must be dropped there, not
    ghosted."""
    frames = last - first + 1
    wall = principled("wall", (0.72, 0.68, 0.6), roughness=0.9)
    accent = principled("accent wall", (0.55, 0.25, 0.2), roughness=0.9)
    carpet = noise_color("carpet", (0.25, 0.28, 0.35), (0.4, 0.42, 0.5), scale=20.0, detail=3.0,
                         roughness=1.0)
    room("Room", -3.0, 3.0, -3.0, 3.0, 0.0, 2.7, [wall, accent],
         {"left": 0, "right": 0, "front": 0, "back": 1, "ceiling": 0},
         holes={"left": [(1.2, 3.2, 0.9, 2.2)]}, pass_index=1)
    floor("Floor", -3.0, 3.0, -3.0, 3.0, carpet, 2)
    sofa = principled("sofa", (0.2, 0.35, 0.3), roughness=0.9)
    box("SofaBase", (0.6, 2.3, 0.22), (2.2, 0.9, 0.44), sofa, 3)
    box("SofaBack", (0.6, 2.65, 0.6), (2.2, 0.2, 0.5), sofa, 3)
    table = principled("coffee table", (0.3, 0.2, 0.12), roughness=0.3, clearcoat=0.5)
    box("CoffeeTable", (0.6, 1.1, 0.22), (1.2, 0.6, 0.06), table, 4)
    for i, (dx, dy) in enumerate(((-0.55, -0.25), (0.55, -0.25), (-0.55, 0.25), (0.55, 0.25))):
        box(f"CoffeeLeg{i}", (0.6 + dx, 1.1 + dy, 0.1), (0.04, 0.04, 0.2), table, 4)
    shelf = principled("shelf", (0.7, 0.68, 0.62), roughness=0.5)
    for i in range(4):
        box(f"Shelf{i}", (2.75, -0.5, 0.4 + 0.45 * i), (0.4, 1.6, 0.03), shelf, 5)
    for i, colour in enumerate(((0.7, 0.2, 0.1), (0.1, 0.3, 0.6), (0.8, 0.7, 0.2),
                                (0.2, 0.5, 0.2))):
        box(f"Book{i}", (2.75, -1.0 + 0.3 * i, 0.56 + 0.45 * (i % 3)), (0.25, 0.12, 0.3),
            principled(f"book{i}", colour, roughness=0.6), 6)
    sphere("Vase", (0.4, 1.1, 0.4), 0.13, principled("vase", (0.9, 0.9, 0.95), 0.1), 7)
    # The floor lamp: a pole, a shade and a spot inside it, aimed down at the sofa's end.
    metal = principled("lamp metal", (0.8, 0.8, 0.8), roughness=0.3, metallic=1.0)
    box("LampPole", (-1.0, 2.4, 0.8), (0.04, 0.04, 1.6), metal, 8)
    # The glowing lamp shade and ceiling panel: one object, one ID.
    shade_mat, shade_emission = emission("lamp shade glow", (1.0, 0.75, 0.45), 0.0)
    ceiling_mat, ceiling_emission = emission("ceiling panel glow", (1.0, 0.95, 0.9), 12.0)
    sx, sy, sz, h = -1.0, 2.4, 1.7, 0.175
    shade = [(sx + a * h, sy + b * h, sz + c * 0.125) for c in (-1, 1) for b in (-1, 1)
             for a in (-1, 1)]  # index a + 2 b + 4 c with a, b, c in {0, 1}
    panel = [(-0.1, 0.4, 2.69), (0.7, 0.4, 2.69), (0.7, 1.2, 2.69), (-0.1, 1.2, 2.69)]
    mesh_object("LampGlow", shade + panel,
                [(0, 2, 3, 1), (4, 5, 7, 6), (0, 1, 5, 4), (1, 3, 7, 5), (3, 2, 6, 7),
                 (2, 0, 4, 6), (11, 10, 9, 8)],
                [shade_mat, ceiling_mat], [0, 0, 0, 0, 0, 0, 1], 9)
    ceiling_light = area_light("CeilingLight", (0.3, 0.8, 2.68), (0, 0, 0), 0.8, 260.0)
    # The spot hangs just under the (closed) shade, tilted towards +x; the shade glows when on.
    lamp = spot_light("FloorLamp", (-1.0, 2.4, 1.55), (0, math.radians(-25), 0), 180.0, 0.05,
                      100.0, 0.4, color=(1.0, 0.75, 0.45))
    ceiling_keys = switch_keys(first, frames, True, (0.3, 0.65))
    lamp_keys = switch_keys(first, frames, False, (0.45,))
    constant_keys(ceiling_light.data, "energy", [(f, 260.0 if on else 0.0)
                                                 for f, on in ceiling_keys])
    keyed_emission_strength(ceiling_emission, [(f, 12.0 if on else 0.0) for f, on in ceiling_keys])
    constant_keys(lamp.data, "energy", [(f, 180.0 if on else 0.0) for f, on in lamp_keys])
    keyed_emission_strength(shade_emission, [(f, 6.0 if on else 0.0) for f, on in lamp_keys])
    world((0.25, 0.35, 0.6), 3.0)
    cam = camera((-2.2, -2.6, 1.4), (82, 0, -28), lens=24)
    camera_move(cam, first, last, move=(0.03, 0.06, 0), turn_deg=(0, 0, 1.2))
    return cam, [], {"ceilingLight": ceiling_keys, "floorLamp": lamp_keys}


BUILDERS = {
    "indirect-room": scene_indirect_room,
    "texture-gallery": scene_texture_gallery,
    "small-lights": scene_small_lights,
    "light-switch": scene_light_switch,
}


# ---- render settings ----

def build(args):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    first, last = 1, args.frames
    built = BUILDERS[args.scene](first, last)
    extra = built[2] if len(built) > 2 else {}
    scene.frame_start, scene.frame_end = first, last
    scene.render.resolution_x, scene.render.resolution_y = args.width, args.height
    scene.render.resolution_percentage = 100
    scene.render.use_motion_blur = False  # with it on, Cycles writes a Vector pass of zeros
    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.use_animated_seed = True  # the seed is hashed with the frame: new noise a frame
    scene.cycles.use_adaptive_sampling = False  # exactly N samples in every pixel
    scene.cycles.use_denoising = False  # the noisy frames are the input; Debian's build lacks OIDN
    scene.cycles.pixel_filter_type = "GAUSSIAN"
    scene.cycles.filter_width = 0.01  # every sample at the pixel centre (see the header)
    # Everything else as a user finds it (the factory defaults, recorded in scene.json): 12
    # bounces (4 diffuse, 4 glossy, 12 transmission, 8 transparent), clamp direct 0 (off) and
    # indirect 10, filter glossy 1.0, caustics on, light threshold 0.01, PMJ sampling.
    scene.view_settings.view_transform = "Standard"  # only the optional PNG previews use it
    return scene, built[0], built[1], extra


CYCLES_SETTINGS = ("samples", "seed", "use_animated_seed", "use_adaptive_sampling",
                   "use_denoising", "pixel_filter_type", "filter_width", "max_bounces",
                   "diffuse_bounces", "glossy_bounces", "transmission_bounces", "volume_bounces",
                   "transparent_max_bounces", "sample_clamp_direct", "sample_clamp_indirect",
                   "blur_glossy", "caustics_reflective", "caustics_refractive",
                   "light_sampling_threshold", "sampling_pattern", "film_exposure",
                   "scrambling_distance", "device")


def row_major(m):
    return [[float(m[r][c]) for c in range(4)] for r in range(4)]


def world_to_screen(cam, width, height):
    # Clip coordinates with w = -z_camera; pixels: x right, y down, pixel centres at +0.5.
    depsgraph = bpy.context.evaluated_depsgraph_get()
    projection = cam.calc_matrix_camera(depsgraph, x=width, y=height)
    to_pixels = Matrix(((width / 2, 0, 0, width / 2), (0, -height / 2, 0, height / 2),
                        (0, 0, 0, 1), (0, 0, 0, 1)))
    return to_pixels @ projection @ cam.matrix_world.inverted()


def scene_info(scene, cam, args, extra):
    frames = []
    for frame in range(scene.frame_start - 1, scene.frame_end + 2):
        scene.frame_set(frame)
        frames.append({"frame": frame,
                       "worldToScreen": row_major(world_to_screen(cam, args.width, args.height)),
                       "cameraToWorld": row_major(cam.matrix_world)})
    scene.frame_set(scene.frame_start)
    lights = {o.name: {"type": o.data.type, "energy": o.data.energy,
                       "color": list(o.data.color)} for o in scene.objects if o.type == "LIGHT"}
    return {
        "version": VERSION, "scene": args.scene, "width": args.width, "height": args.height,
        "firstFrame": scene.frame_start, "frameCount": args.frames, "seed": args.seed,
        "blender": bpy.app.version_string,
        "cycles": {k: _plain(getattr(scene.cycles, k)) for k in CYCLES_SETTINGS
                   if k != "samples" and k != "seed"},
        "motionBlur": scene.render.use_motion_blur,
        "lights": lights, "switches": extra,
        "objects": {o.name: o.pass_index for o in scene.objects if o.type == "MESH"},
        "frames": frames,
    }


def _plain(value):
    return value if isinstance(value, (bool, int, float, str)) else str(value)


def write_or_check_info(path, info):
    """The first run writes scene.json; a later one must have the same settings."""
    keys = ("version", "scene", "width", "height", "firstFrame", "frameCount", "seed", "blender")
    if os.path.exists(path):
        with open(path) as f:
            old = json.load(f)
        changed = [k for k in keys if old.get(k) != info[k]]
        if changed:
            sys.exit(f"{path}: rendered with other settings ("
                     + ", ".join(f"{k} {old.get(k)} now {info[k]}" for k in changed)
                     + "): choose another OUT_DIR or delete this scene's folder")
        info["renders"] = old.get("renders", {})
    else:
        info["renders"] = {}
    return info


def save_info(path, info):
    tmp = path + ".tmp"
    with open(tmp, "w") as f:
        json.dump(info, f, indent=1)
    os.replace(tmp, path)


def configure_kind(scene, kind):
    layer = scene.view_layers[0]
    data = kind == "noisy"
    layer.use_pass_combined = True
    layer.use_pass_z = data
    layer.use_pass_normal = data
    layer.use_pass_position = data
    layer.use_pass_object_index = data
    layer.use_pass_vector = data
    layer.cycles.denoising_store_passes = data  # Denoising Albedo (and Normal, Depth)
    settings = scene.render.image_settings
    if data:
        settings.file_format = "OPEN_EXR_MULTILAYER"
        # Float, not half: a 1-spp firefly from a small light can exceed half's 65504.
        settings.color_depth = "32"
    else:
        settings.file_format = "OPEN_EXR"
        settings.color_mode = "RGB"
        settings.color_depth = "32"
    settings.exr_codec = "ZIP"


def kind_spp(kind, args):
    if kind == "noisy":
        return 1
    if kind == "reference":
        return args.reference_spp
    if kind.startswith("spp") and kind[3:].isdigit() and int(kind[3:]) > 0:
        return int(kind[3:])
    sys.exit(f"unknown kind {kind!r}: noisy, reference or sppN")


def save_png(scene, path):
    settings = scene.render.image_settings
    saved = (settings.file_format, settings.color_mode, settings.color_depth)
    settings.file_format, settings.color_mode, settings.color_depth = "PNG", "RGB", "8"
    bpy.data.images["Render Result"].save_render(path, scene=scene)
    settings.file_format, settings.color_mode, settings.color_depth = saved


def render_kind(scene, scene_dir, kind, args, info, info_path):
    spp = kind_spp(kind, args)
    seed = args.seed + SEED_OFFSETS.get(kind, spp)
    configure_kind(scene, kind)
    scene.cycles.samples = spp
    scene.cycles.seed = seed
    folder = os.path.join(scene_dir, kind)
    old = info["renders"].get(kind)
    if old and old.get("spp") != spp and os.path.isdir(folder) \
            and any(f.endswith(".exr") for f in os.listdir(folder)):
        sys.exit(f"{folder}: rendered at {old.get('spp')} spp, now {spp}: choose another "
                 "OUT_DIR or delete that folder")
    tmp_dir = os.path.join(scene_dir, "tmp")
    os.makedirs(folder, exist_ok=True)
    os.makedirs(tmp_dir, exist_ok=True)
    info["renders"][kind] = {"spp": spp, "seed": seed, "format": scene.render.image_settings
                             .file_format, "colorDepth": scene.render.image_settings.color_depth,
                             "codec": scene.render.image_settings.exr_codec}
    save_info(info_path, info)
    times = os.path.join(scene_dir, "render_times.tsv")
    if not os.path.exists(times):
        with open(times, "w") as f:
            f.write("date\tkind\tframe\tspp\twidth\theight\tseconds\n")
    rendered = 0
    for frame in range(scene.frame_start, scene.frame_end + 1):
        final = os.path.join(folder, f"{frame:04d}.exr")
        if os.path.exists(final):
            continue
        scene.frame_set(frame)
        partial = os.path.join(tmp_dir, f"{kind}_{frame:04d}.exr")
        scene.render.filepath = partial
        start = time.time()
        bpy.ops.render.render(write_still=True)
        seconds = time.time() - start
        if not os.path.exists(partial):
            sys.exit(f"{partial}: Blender wrote no file")
        os.replace(partial, final)
        if args.png:
            os.makedirs(os.path.join(scene_dir, "preview"), exist_ok=True)
            save_png(scene, os.path.join(scene_dir, "preview", f"{kind}_{frame:04d}.png"))
        with open(times, "a") as f:
            f.write(f"{time.strftime('%Y-%m-%dT%H:%M:%S')}\t{kind}\t{frame}\t{spp}\t"
                    f"{args.width}\t{args.height}\t{seconds:.2f}\n")
        rendered += 1
        print(f"validation_scenes: {args.scene} {kind} frame {frame}/{scene.frame_end} "
              f"({spp} spp) {seconds:.1f} s", flush=True)
    if not os.listdir(tmp_dir):
        os.rmdir(tmp_dir)
    if rendered == 0:
        print(f"validation_scenes: {args.scene} {kind}: all {args.frames} frames already there",
              flush=True)


def main():
    args = parse_arguments()
    if args.width < 1 or args.height < 1 or args.frames < 1 or args.reference_spp < 1:
        sys.exit("--width, --height, --frames and --reference-spp must be >= 1")
    kinds = [k for k in args.kinds.split(",") if k]
    for kind in kinds:
        kind_spp(kind, args)
    scene_dir = os.path.join(os.path.abspath(args.out_dir), args.scene)
    os.makedirs(scene_dir, exist_ok=True)
    scene, cam, _, extra = build(args)
    info_path = os.path.join(scene_dir, "scene.json")
    info = write_or_check_info(info_path, scene_info(scene, cam, args, extra))
    save_info(info_path, info)
    for kind in kinds:
        render_kind(scene, scene_dir, kind, args, info, info_path)


main()
