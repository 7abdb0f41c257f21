#!/usr/bin/env bash
# Smoke test of scripts/make_corpus.sh (docs/corpus.md) at a tiny size: the sets are rendered
# with their references and a manifest, their seeds are disjoint, a rerun renders nothing, and a
# folder rendered with other settings is refused.
#   tests/test_corpus.sh RTDENOISE
set -euo pipefail
here=$(cd "$(dirname "$0")/.." && pwd)
export RTDENOISE=$1
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
fail() { echo "FAIL: $*"; exit 1; }
small=(--train 2 --validation 2 --width 24 --height 16 --frames 2 --ref-spp 2)
"$here/scripts/make_corpus.sh" "$work/corpus" "${small[@]}" > "$work/run1.log" 2>&1 ||
    { cat "$work/run1.log"; fail "the first run failed"; }
for dir in train/seed_1 train/seed_2 validation/seed_100001 validation/seed_100002; do
    for file in beauty_1.exr reference/reference_1.exr scene.json complete; do
        [ -f "$work/corpus/$dir/$file" ] || fail "$dir/$file is missing"
    done
done
python3 - "$work/corpus/manifest.json" <<'PY' || exit 1
import json, sys
m = json.load(open(sys.argv[1]))
train, validation = m["sets"]["train"]["seeds"], m["sets"]["validation"]["seeds"]
assert m["generator"].startswith("random-scene"), m["generator"]
assert train[1] < validation[0], (train, validation)  # disjoint seed ranges
assert m["sets"]["train"]["count"] == 2 and sum(m["sets"]["train"]["tags"].values()) > 0, m
PY
"$here/scripts/make_corpus.sh" "$work/corpus" "${small[@]}" > "$work/run2.log" 2>&1 ||
    fail "the rerun failed"
if grep -v "sequences" "$work/run2.log" | grep -q "seed"; then
    fail "the rerun rendered again: $(cat "$work/run2.log")"
fi
if "$here/scripts/make_corpus.sh" "$work/corpus" --train 2 --validation 2 --width 32 \
        --height 16 --frames 2 --ref-spp 2 > "$work/run3.log" 2>&1; then
    fail "other settings into the same folder were accepted"
fi
grep -q "choose another folder" "$work/run3.log" || fail "no reason given: $(cat "$work/run3.log")"
echo "corpus smoke test passed"
