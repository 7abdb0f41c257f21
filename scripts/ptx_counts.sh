#!/usr/bin/env bash
# PTX instructions per CUDA kernel, from nvcc alone (no GPU needed): a first look at what a
# kernel change does to the GPU code where no GPU is at hand. ptxas optimises further (operand
# modifiers, address arithmetic, a PTX mul and add fused into one FMA), so these are a guide,
# not the machine code's counts.
#   scripts/ptx_counts.sh [REGEX]   (default: the A-Trous iterations at stride 4)
set -euo pipefail
cd "$(dirname "$0")/.."
pattern="${1:-FixedStride<rtd::(Atrous|SvgfAtrous)<.*, 4>}"
nvcc="${NVCC:-$(command -v nvcc || echo /usr/local/cuda/bin/nvcc)}"
ptx=$(mktemp --suffix=.ptx)
trap 'rm -f "$ptx"' EXIT
"$nvcc" -O3 -DNDEBUG -DRTD_HAS_CUDA=1 -arch=sm_90 -std=c++17 --expt-relaxed-constexpr --ftz=true \
    -I include -I src -ptx src/devices/cuda/cuda_device.cu -o "$ptx"
python3 - "$ptx" "$pattern" <<'PY'
import re, subprocess, sys
path, pattern = sys.argv[1:3]
lines = open(path).read().split("\n")
entries = [(i, l.split()[1].rstrip("(")) for i, l in enumerate(lines) if l.startswith(".entry")]
names = subprocess.run(["c++filt"], input="\n".join(n for _, n in entries), text=True,
                       capture_output=True).stdout.split("\n")
for k, (start, _) in enumerate(entries):
    name = names[k].replace("rtd::(anonymous namespace)::", "")
    if not re.search(pattern, name):
        continue
    end = entries[k + 1][0] if k + 1 < len(entries) else len(lines)
    count = 0
    for line in lines[start:end]:
        line = line.strip()
        if line and not line.startswith((".", "//", "{", "}", "$", "(", ")")) \
                and not line.endswith(":"):
            count += 1
    print(f"{count:6d}  {name}")
PY
