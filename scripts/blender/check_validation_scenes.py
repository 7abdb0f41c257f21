#!/usr/bin/env python3
# Checks a folder of Cycles validation scenes (scripts/validation_scenes.sh) in plain Python 3:
#   - every noisy frame holds the passes rtdenoise reads (docs/inputs.md), FLOAT and finite;
#   - the 1-spp noise differs from frame to frame (the animated seed): frame i's Combined.R
#     differs from frame i-1's in at least 40 % of the pixels non-zero in either;
#   - the Vector pass moves where the camera or an object does (keyframed motion: a transform
#     set by a script alone gives Vector = 0), and on the room's walls (ID 1, static) it is the
#     motion scene.json's camera matrices give, within 0.01 px, in the first and last frames too;
#   - each equal-sample render's mean is within --energy-tolerance of the reference's, frame by
#     frame (same pixel filter, same settings: the same expected value);
#   - the light-switch scene's reference gets darker when its ceiling light goes off and
#     brighter when it comes on.
#
#   scripts/blender/check_validation_scenes.py OUT_DIR [--scenes a,b] [--energy-tolerance 0.1]
#
# Prints one line per scene and a FAIL line per problem; exit 1 on any.
import argparse
import json
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from exr_stats import read_exr, stats  # noqa: E402

SCENES = ("indirect-room", "texture-gallery", "small-lights", "light-switch")
PASSES = ["Combined.R", "Combined.G", "Combined.B", "Combined.A", "Depth.Z", "Normal.X",
          "Normal.Y", "Normal.Z", "Position.X", "Position.Y", "Position.Z", "IndexOB.X",
          "Vector.X", "Vector.Y", "Vector.Z", "Vector.W", "Denoising Albedo.R",
          "Denoising Albedo.G", "Denoising Albedo.B"]
# The fraction of pixels whose Vector.X must be non-zero: the camera moves in all but one.
MOVING = {"indirect-room": 0.9, "texture-gallery": 0.9, "small-lights": 0.002,
          "light-switch": 0.9}


def project(m, p):
    v = [sum(m[r][c] * p[c] for c in range(3)) + m[r][3] for r in range(4)]
    return v[0] / v[3], v[1] / v[3]


def vector_error(channels, screens, frame):
    """The largest difference (px) between Vector and the motion of the camera matrices over
    the room's pixels (ID 1: never moves). Vector: X, Y = previous - current, Z, W = current -
    next, y up (docs/inputs.md); the matrices' pixels have y down."""
    g = lambda n: channels["ViewLayer." + n][1]
    px, py, pz = g("Position.X"), g("Position.Y"), g("Position.Z")
    vx, vy, vz, vw = g("Vector.X"), g("Vector.Y"), g("Vector.Z"), g("Vector.W")
    ids, worst = g("IndexOB.X"), 0.0
    for i in range(0, len(ids), 3):
        if ids[i] != 1:
            continue
        p = (px[i], py[i], pz[i])
        cx, cy = project(screens[frame], p)
        bx, by = project(screens[frame - 1], p)
        nx, ny = project(screens[frame + 1], p)
        worst = max(worst, abs(vx[i] - (bx - cx)), abs(vy[i] + (by - cy)),
                    abs(vz[i] - (cx - nx)), abs(vw[i] + (cy - ny)))
    return worst


def mean_rgb(path):
    channels, _, _ = read_exr(path)
    means = [stats(*channels[c])["mean"] for c in ("R", "G", "B")]
    return sum(means) / 3


def check_scene(folder, scene, tolerance, problems):
    with open(os.path.join(folder, "scene.json")) as f:
        info = json.load(f)
    frames = list(range(info["firstFrame"], info["firstFrame"] + info["frameCount"]))
    name = lambda f: f"{f:04d}.exr"
    kinds = sorted(k for k in info.get("renders", {}) if k != "noisy")

    def problem(text):
        problems.append(f"{scene}: {text}")

    noisy = os.path.join(folder, "noisy")
    screens = {f["frame"]: f["worldToScreen"] for f in info["frames"]}
    previous, vector_worst = None, 0.0
    for frame in frames:
        path = os.path.join(noisy, name(frame))
        if not os.path.exists(path):
            problem(f"noisy/{name(frame)} missing")
            continue
        channels, _, _ = read_exr(path)
        for p in PASSES:
            entry = channels.get("ViewLayer." + p)
            if entry is None or entry[0] != "FLOAT":
                problem(f"noisy/{name(frame)}: ViewLayer.{p} missing or not FLOAT")
        bad = sum(stats(*v)["nonfinite"] for v in channels.values())
        if bad:
            problem(f"noisy/{name(frame)}: {bad} non-finite values")
        vector = channels.get("ViewLayer.Vector.X")
        if vector is not None:
            moving = stats(*vector)["nonzero"]
            if moving < MOVING[scene]:
                problem(f"noisy/{name(frame)}: Vector.X non-zero in {moving:.3f} of the pixels "
                        f"(at least {MOVING[scene]})")
        if frame in (frames[0], frames[-1]) and all(
                "ViewLayer." + p in channels for p in PASSES):
            error = vector_error(channels, screens, frame)
            vector_worst = max(vector_worst, error)
            if error > 0.01:
                problem(f"noisy/{name(frame)}: Vector differs from the camera's motion by "
                        f"{error:.4f} px on the room's walls")
        colour = channels.get("ViewLayer.Combined.R")
        if colour is not None and previous is not None:
            # Over the pixels lit in either frame (at 1 spp in a dark frame most are black).
            lit = [(a, b) for a, b in zip(previous, colour[1]) if a != 0 or b != 0]
            differ = sum(1 for a, b in lit if a != b) / max(1, len(lit))
            if differ < 0.4:
                problem(f"noisy/{name(frame)}: differs from the frame before in only "
                        f"{differ:.2f} of the pixels lit in either (is the seed animated?)")
        previous = colour[1] if colour is not None else None

    reference = {}
    for kind in kinds:
        for frame in frames:
            path = os.path.join(folder, kind, name(frame))
            if not os.path.exists(path):
                problem(f"{kind}/{name(frame)} missing")
                continue
            channels, _, _ = read_exr(path)
            bad = sum(stats(*v)["nonfinite"] for v in channels.values())
            if bad:
                problem(f"{kind}/{name(frame)}: {bad} non-finite values")
            if kind == "reference":
                reference[frame] = mean_rgb(path)
    ratios = []
    for kind in kinds:
        if kind == "reference":
            continue
        for frame in frames:
            path = os.path.join(folder, kind, name(frame))
            if frame not in reference or not os.path.exists(path):
                continue
            ratio = mean_rgb(path) / reference[frame]
            ratios.append(ratio)
            if abs(ratio - 1) > tolerance:
                problem(f"{kind}/{name(frame)}: mean {ratio:.3f} of the reference's")

    switches = info.get("switches", {}).get("ceilingLight", [])
    for frame, on in switches[1:]:
        if frame in reference and frame - 1 in reference:
            before, after = reference[frame - 1], reference[frame]
            if (on and after <= before) or (not on and after >= 0.7 * before):
                problem(f"the ceiling light switches {'on' if on else 'off'} at frame {frame}, "
                        f"but the reference's mean goes from {before:.4f} to {after:.4f}")
    span = f"{min(ratios):.3f}..{max(ratios):.3f}" if ratios else "-"
    print(f"{scene}: {len(frames)} frames, renders {', '.join(kinds) or 'none'}; equal-sample "
          f"mean / reference mean {span}; Vector against the matrices {vector_worst:.1e} px")


def main():
    parser = argparse.ArgumentParser(prog="check_validation_scenes.py")
    parser.add_argument("out_dir")
    parser.add_argument("--scenes", default=",".join(SCENES))
    parser.add_argument("--energy-tolerance", type=float, default=0.1)
    args = parser.parse_args()
    problems = []
    for scene in args.scenes.split(","):
        folder = os.path.join(args.out_dir, scene)
        if not os.path.exists(os.path.join(folder, "scene.json")):
            problems.append(f"{scene}: {folder}/scene.json missing")
            continue
        check_scene(folder, scene, args.energy_tolerance, problems)
    for p in problems:
        print("FAIL:", p)
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
