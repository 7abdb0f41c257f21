#!/usr/bin/env python3
"""How a chunk's frames differ from the same frames of one run over the whole shot, against the
warm-up W (issue 40; the table of docs/farm.md).

For each scene (rendered once, with a reference), method, chunk start A and warm-up W: the whole
shot is denoised once; the chunk A..A+L-1 is denoised with `--frames A:A+L --warmup W`; the
assembled shot (the whole run's frames before A, the chunk's from A) is scored against the whole
run with `rtdenoise compare`:
  - seam: the temporal error at frame A (display space: the mean |(x_A - x_A-1) - (w_A - w_A-1)|,
    where x_A-1 = w_A-1: the jump a viewer sees at the join that the whole run does not have);
  - relMSE at A and the largest relMSE over the chunk (linear; how long the difference lasts).
The scale a viewer judges the seam by is the flicker already there in every frame: the whole
run's own mean temporal error against the reference; `seam / flicker` is the table's ratio.

  scripts/seam_table.py RTDENOISE OUT_DIR [--size 128x96] [--frames 56] [--starts 24,40]
      [--length 8] [--warmups 0,1,2,4,8,12,16,24] [--methods ...] [--scenes ...]
Writes OUT_DIR/seams.json and prints a Markdown table; scenes are cached in OUT_DIR/scenes.
"""
import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile


def run(*args):
    result = subprocess.run([str(a) for a in args], capture_output=True, text=True)
    if result.returncode != 0:
        sys.exit(f"{' '.join(map(str, args))} failed:\n{result.stdout}{result.stderr}")
    return result.stdout


def compare(rtdenoise, results, reference, count, work):
    out = os.path.join(work, "compare.json")
    run(rtdenoise, "compare", results, reference, "--frames", f"0..{count - 1}", "--json", out)
    with open(out) as f:
        return json.load(f)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("rtdenoise")
    parser.add_argument("out")
    parser.add_argument("--size", default="128x96")
    parser.add_argument("--frames", type=int, default=56)
    parser.add_argument("--ref-spp", type=int, default=64)
    parser.add_argument("--starts", default="24,40")
    parser.add_argument("--length", type=int, default=8)
    parser.add_argument("--warmups", default="0,1,2,4,8,12,16,24")
    parser.add_argument("--methods", default="temporal,svgf,detail,jbf,atrous")
    parser.add_argument("--scenes", default="camera-pan,switching-light,moving-objects")
    args = parser.parse_args()
    width, height = args.size.split("x")
    starts = [int(a) for a in args.starts.split(",")]
    warmups = [int(w) for w in args.warmups.split(",")]
    os.makedirs(args.out, exist_ok=True)
    rows = []
    with tempfile.TemporaryDirectory() as work:
        for scene in args.scenes.split(","):
            scene_dir = os.path.join(args.out, "scenes", scene)
            if not os.path.exists(os.path.join(scene_dir, "reference")):
                run(args.rtdenoise, "render", scene, "-o", scene_dir, "--width", width,
                    "--height", height, "--frames", args.frames, "--ref-spp", args.ref_spp)
            for method in args.methods.split(","):
                whole = os.path.join(work, "whole")
                run(args.rtdenoise, "denoise", scene_dir, "-o", whole, "--method", method,
                    "--device", "cpu", "-q")
                own = compare(args.rtdenoise, whole, os.path.join(scene_dir, "reference"),
                              args.frames, work)
                flicker = own["mean"]["temporal_error"]
                for start in starts:
                    end = start + args.length
                    for warmup in warmups:
                        chunk = os.path.join(work, "chunk")
                        run(args.rtdenoise, "denoise", scene_dir, "-o", chunk, "--method", method,
                            "--device", "cpu", "-q", "--frames", f"{start}:{end}", "--warmup",
                            warmup)
                        assembled = os.path.join(work, "assembled")
                        shutil.rmtree(assembled, ignore_errors=True)
                        os.makedirs(assembled)
                        for i in range(end):
                            source = chunk if i >= start else whole
                            os.symlink(os.path.join(source, f"result_{i}.exr"),
                                       os.path.join(assembled, f"result_{i}.exr"))
                        scores = compare(args.rtdenoise, assembled, whole, end, work)["frames"]
                        chunk_scores = scores[start:end]
                        row = dict(scene=scene, method=method, start=start, warmup=warmup,
                                   seam=chunk_scores[0]["temporal_error"],
                                   flicker=flicker,
                                   rel_mse_at_start=chunk_scores[0]["rel_mse"],
                                   max_rel_mse=max(s["rel_mse"] for s in chunk_scores),
                                   rel_mse_at_end=chunk_scores[-1]["rel_mse"])
                        row["seam_over_flicker"] = row["seam"] / flicker if flicker else 0.0
                        rows.append(row)
                        print(json.dumps(row), file=sys.stderr, flush=True)
    with open(os.path.join(args.out, "seams.json"), "w") as f:
        json.dump(dict(args=vars(args), rows=rows), f, indent=1)

    # Markdown: per method and warm-up, the worst over scenes and starts.
    print("| method | flicker (own temporal error, mean over scenes) | " +
          " | ".join(f"W={w}" for w in warmups) + " |")
    print("|---|---|" + "---|" * len(warmups))
    for method in args.methods.split(","):
        mine = [r for r in rows if r["method"] == method]
        flicker = sum({(r["scene"]): r["flicker"] for r in mine}.values()) / len(args.scenes.split(","))
        cells = []
        for w in warmups:
            worst = max((r for r in mine if r["warmup"] == w), key=lambda r: r["seam_over_flicker"])
            cells.append(f"{worst['seam']:.2e} ({worst['seam_over_flicker']:.3f}) / "
                         f"{worst['max_rel_mse']:.1e}")
        print(f"| {method} | {flicker:.4f} | " + " | ".join(cells) + " |")


if __name__ == "__main__":
    main()
