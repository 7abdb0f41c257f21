#!/usr/bin/env bash
# The generated corpora (issue 38; docs/corpus.md): a train set and a validation set of scenes from
# `rtdenoise render random`, other seeds each, with their references, in a cache folder that git
# ignores. Defaults and parameters are chosen on the train set only; the validation set is for
# reporting. A sequence already rendered (its folder complete) is kept: a rerun renders what is
# missing, so an interrupted build resumes.
#   scripts/make_corpus.sh [OUT=cache/corpus] [--train N=100] [--validation M=24] [--width W=256]
#                          [--height H=256] [--frames F=16] [--ref-spp S=256] [--spp 1]
# Train seeds are 1..N, validation seeds 100001..100000+M: disjoint for any N < 100001.
# Environment: RTDENOISE (default build/release/rtdenoise).
set -euo pipefail
cd "$(dirname "$0")/.."
out=cache/corpus train=100 validation=24 width=256 height=256 frames=16 refspp=256 spp=1
while [ $# -gt 0 ]; do
  case "$1" in
    --train) train=$2; shift 2 ;;
    --validation) validation=$2; shift 2 ;;
    --width) width=$2; shift 2 ;;
    --height) height=$2; shift 2 ;;
    --frames) frames=$2; shift 2 ;;
    --ref-spp) refspp=$2; shift 2 ;;
    --spp) spp=$2; shift 2 ;;
    -*) echo "make_corpus.sh: unknown option $1" >&2; exit 2 ;;
    *) out=$1; shift ;;
  esac
done
bin=${RTDENOISE:-build/release/rtdenoise}
[ -x "$bin" ] || { echo "make_corpus.sh: $bin not built (cmake --build --preset release)" >&2; exit 1; }
settings="--width $width --height $height --frames $frames --spp $spp --ref-spp $refspp"
mkdir -p "$out/logs"
# One corpus, one set of settings: a folder rendered with others is refused, not mixed in.
if [ -f "$out/settings.txt" ] && [ "$(cat "$out/settings.txt")" != "$settings" ]; then
  echo "make_corpus.sh: $out holds a corpus rendered with '$(cat "$out/settings.txt")', not" \
       "'$settings': choose another folder" >&2
  exit 1
fi
echo "$settings" > "$out/settings.txt"
version=$("$bin" render random --seed 1 --describe | python3 -c 'import json,sys; print(json.load(sys.stdin)["generator"]["version"])')

render_set() {  # name first_seed count
  local name=$1 first=$2 count=$3 seed dir
  for ((seed = first; seed < first + count; seed++)); do
    dir="$out/$name/seed_$seed"
    [ -f "$dir/complete" ] && continue
    rm -rf "$dir" "$dir.partial"
    local start=$SECONDS
    # shellcheck disable=SC2086
    "$bin" render random --seed "$seed" -o "$dir.partial" $settings -q \
        > "$out/logs/$name-$seed.log" 2>&1 ||
        { echo "make_corpus.sh: seed $seed failed: $out/logs/$name-$seed.log" >&2; exit 1; }
    echo "$((SECONDS - start)) s" > "$dir.partial/complete"
    mv "$dir.partial" "$dir"
    echo "$name seed $seed: $((SECONDS - start)) s"
  done
}
render_set train 1 "$train"
render_set validation 100001 "$validation"

# The manifest: what was drawn, with which generator and settings; the tags counted per set.
python3 - "$out" "$version" "$settings" "$train" "$validation" <<'PY'
import collections, json, pathlib, sys
out, version, settings, train, validation = sys.argv[1:6]
manifest = {"generator": version, "settings": settings, "sets": {}}
for name, first, count in (("train", 1, int(train)), ("validation", 100001, int(validation))):
    tags = collections.Counter()
    seeds = list(range(first, first + count))
    for seed in seeds:
        scene = json.loads((pathlib.Path(out) / name / f"seed_{seed}" / "scene.json").read_text())
        tags.update(scene["generator"]["tags"])
    manifest["sets"][name] = {"seeds": [seeds[0], seeds[-1]] if seeds else [], "count": count,
                              "tags": dict(sorted(tags.items()))}
(pathlib.Path(out) / "manifest.json").write_text(json.dumps(manifest, indent=1) + "\n")
print(f"{out}: {train} train and {validation} validation sequences ({version}; {settings})")
PY
