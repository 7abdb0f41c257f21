#!/usr/bin/env python3
"""Vector instructions in the inner pixel loop of CPU kernels, from the AVX-512 object file of a
build (objdump, no run): a check that a kernel change removed the operations it meant to, and
whether its loads are masked (a branch inside the vectorised pixel loop masks every load).

For each kernel it finds the OpenMP body its launcher forks (run<Kernel>), the innermost loop of
that body with over 500 zmm instructions (the unrolled 5x5 filters; smaller kernels are skipped
unless --min lowers the bar; the course's A-Trous level has two such loops, the rows run for
their stored weights only, then the full rows), and counts per loop iteration (16 pixels): vector arithmetic
(zmm instructions other than moves and broadcasts), per tap (--taps, default 25), and masked
loads.

  scripts/cpu_op_counts.py [--build build/release] [--taps 25] [--min 500] [KERNEL ...]
  default kernels: AtrousNarrowNormalKernel SvgfAtrousNormal128Kernel
"""
import argparse
import glob
import re
import subprocess
import sys


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--build", default="build/release")
    parser.add_argument("--taps", type=int, default=25)
    parser.add_argument("--min", type=int, default=500)
    parser.add_argument("kernels", nargs="*",
                        default=["AtrousNarrowNormalKernel", "SvgfAtrousNormal128Kernel"])
    args = parser.parse_args()
    objects = glob.glob(f"{args.build}/**/cpu_kernels_avx512.cpp.o", recursive=True)
    if not objects:
        sys.exit(f"no cpu_kernels_avx512.cpp.o under {args.build}: build it first")
    text = subprocess.run(["objdump", "-d", "--no-show-raw-insn", "-C", objects[0]],
                          capture_output=True, text=True, check=True).stdout.splitlines()
    starts = [i for i, l in enumerate(text) if re.match(r"^[0-9a-f]+ <", l)]
    functions = {}
    for k, i in enumerate(starts):
        name = text[i].split("<", 1)[1].rstrip(">:")
        functions[name] = text[i:starts[k + 1] if k + 1 < len(starts) else len(text)]

    def instructions(body):
        out = []
        for line in body:
            m = re.match(r"\s*([0-9a-f]+):\s+(\S+)\s*(.*)", line)
            if m:
                out.append((int(m.group(1), 16), m.group(2), m.group(3)))
        return out

    for kernel in args.kernels:
        launcher = [n for n in functions if re.search(rf"::run{kernel}\(", n)]
        if not launcher:
            print(f"{kernel}: no launcher in {objects[0]}")
            continue
        bodies = [m.group(1) for l in functions[launcher[0]]
                  for m in [re.search(r"<(\.omp_outlined\.[^>+]*)>", l)] if m]
        # Innermost loops with min+ zmm instructions (one per pixel loop of the kernel: the
        # course's A-Trous level has two, its weights-only rows and its full rows).
        loops = {}
        for body in bodies:
            code = instructions(functions.get(body, []))
            for address, op, operands in code:
                target = re.match(r"([0-9a-f]+)", operands)
                if not op.startswith("j") or not target or int(target.group(1), 16) >= address:
                    continue
                start = int(target.group(1), 16)
                loop = [(o, g) for a, o, g in code if start <= a <= address]
                if sum(1 for _, g in loop if "zmm" in g) >= args.min:
                    loops[(body, start, address)] = loop
        innermost = [key for key in loops
                     if not any(other != key and other[0] == key[0] and key[1] <= other[1]
                                and other[2] <= key[2] for other in loops)]
        if not innermost:
            print(f"{kernel}: no loop with {args.min}+ zmm instructions")
            continue
        printed = set()  # the launcher's row orders instantiate the same loop more than once
        for key in sorted(innermost, key=lambda k: len(loops[k])):
            loop = loops[key]
            arithmetic = sum(1 for o, g in loop
                             if "zmm" in g and not o.startswith(("vmov", "vbroadcast")))
            masked = sum(1 for o, g in loop if o.startswith("vmov") and "{%k" in g
                         and "(" in g.split(",")[0] and "%rsp" not in g)
            line = (f"{kernel}: {arithmetic} vector arithmetic instructions per 16 pixels, "
                    f"{arithmetic / args.taps:.1f} per tap ({args.taps} taps); {masked} masked loads")
            if line not in printed:
                printed.add(line)
                print(line)

if __name__ == "__main__":
    main()
