#!/usr/bin/env bash
# Smoke test of the Cycles validation scenes (docs/validation_scenes.md): renders all four at
# 64x48, 3 frames, a 16-spp reference (about 15 s on the 2-core machine), then checks
#   - every noisy frame holds the passes rtdenoise reads, FLOAT, finite;
#   - the noise differs from frame to frame (the animated seed) and the Vector pass moves where
#     the camera or an object does (keyframed motion);
#   - the equal-sample renders and the reference agree in energy, the light switch switches;
#   - a rerun renders nothing, a deleted frame is rendered again, other settings are refused;
#   - with RTDENOISE (the rtdenoise binary, first argument or environment): `denoise --method
#     svgf` and `compare` work on every scene, without warnings, and on the equal-sample links.
#
#   tests/test_validation_scenes.sh [RTDENOISE]      exit 0 pass, 1 fail, 77 skip (no Blender)
set -euo pipefail
here=$(cd "$(dirname "$0")/.." && pwd)
rtdenoise=${1:-${RTDENOISE:-}}
blender=${BLENDER:-blender}
if ! command -v "$blender" > /dev/null; then
    echo "SKIP: no Blender ($blender); Debian: apt-get install blender"
    exit 77
fi
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
out=$work/scenes
failures=0
fail() { echo "FAIL: $*"; failures=$((failures + 1)); }
start=$(date +%s)
args=(--width 64 --height 48 --frames 3 --reference-spp 16 --together)
"$here/scripts/validation_scenes.sh" "${args[@]}" "$out" > "$work/run1.log" 2>&1 ||
    { cat "$work/run1.log"; fail "the driver failed"; exit 1; }
echo "rendered in $(( $(date +%s) - start )) s"
scenes=(indirect-room texture-gallery small-lights light-switch)
python3 "$here/scripts/blender/check_validation_scenes.py" "$out" || fail "the renders' checks"

# Reruns: nothing to do; a deleted frame comes back; other settings are refused.
start=$(date +%s)
"$here/scripts/validation_scenes.sh" "${args[@]}" "$out" > "$work/run2.log" 2>&1 || fail "rerun failed"
[[ $(grep -c 'already rendered' "$work/run2.log") == 4 ]] ||
    { cat "$work/run2.log"; fail "the rerun rendered something"; }
rm "$out/texture-gallery/spp16/0002.exr"
"$here/scripts/validation_scenes.sh" "${args[@]}" --scenes texture-gallery --no-reference \
    "$out" > "$work/run3.log" 2>&1 || fail "rerun after deleting a frame failed"
[[ -f $out/texture-gallery/spp16/0002.exr ]] || fail "a deleted frame was not rendered again"
grep -q 'texture-gallery spp16 frame 2/3' "$out/logs/texture-gallery.log" ||
    fail "the log does not show frame 2 rendered again"
if "$here/scripts/validation_scenes.sh" --width 80 --height 48 --frames 3 --reference-spp 16 \
    "$out" > "$work/run4.log" 2>&1; then
    fail "a run with another size on the same folder was not refused"
fi
echo "checks and reruns done in $(( $(date +%s) - start )) s"

if [[ -n $rtdenoise ]]; then
    for scene in "${scenes[@]}"; do
        if ! "$rtdenoise" denoise "$out/$scene/noisy" -o "$work/svgf/$scene" --method svgf \
            > "$work/denoise.log" 2>&1; then
            cat "$work/denoise.log"; fail "$scene: rtdenoise denoise failed"; continue
        fi
        grep -i 'warning' "$work/denoise.log" && fail "$scene: rtdenoise denoise warned"
        for result in "$work/svgf/$scene" "$out/$scene/results/spp16"; do
            if ! "$rtdenoise" compare "$result" "$out/$scene/reference" \
                --json "$work/compare.json" > "$work/compare.log" 2>&1; then
                cat "$work/compare.log"; fail "$scene: rtdenoise compare $result failed"; continue
            fi
            python3 -c "import json, math; m = json.load(open('$work/compare.json'))['mean']; assert all(isinstance(v, (int, float)) and math.isfinite(v) for k, v in m.items() if k in ('mse', 'rel_mse', 'psnr', 'ssim')) and len(m) >= 4, m" ||
                fail "$scene: compare $result: non-finite means"
        done
    done
    echo "rtdenoise denoise and compare: every scene read"
else
    echo "no RTDENOISE given: rtdenoise not run"
fi
[[ $failures -eq 0 ]] || { echo "$failures failure(s)"; exit 1; }
echo "PASS"
