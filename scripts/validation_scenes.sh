#!/usr/bin/env bash
# Renders the Cycles validation scenes (docs/validation_scenes.md) with Blender 3.4 into a cache
# folder, skipping frames already rendered; logs in OUT_DIR/logs/.
#
#   scripts/validation_scenes.sh [options] [OUT_DIR]      (default OUT_DIR: cache/validation_scenes)
#
#   --width W             image width (default 320)
#   --height H            image height (default 240)
#   --frames N            frames per scene, 1..N (default 16)
#   --reference-spp S     the reference's samples per pixel (default 1024)
#   --equal-spp LIST      the equal-sample renders, comma-separated (default 4,16,64; "" for none)
#   --scenes LIST         comma-separated, of: indirect-room, texture-gallery, small-lights,
#                         light-switch (default: all four)
#   --seed N              base seed (default 1)
#   --no-reference        render the noisy frames and equal-sample renders only
#   --png                 also write OUT_DIR/SCENE/preview/<kind>_<frame>.png
#   --together            render each scene's noisy frames, equal-sample renders and reference
#                         in one Blender run (for tiny test renders: Blender's start-up, 2-3 s,
#                         then dominates)
#   BLENDER=path          the Blender to run (default: blender on PATH)
#
# Order: first every scene's noisy frames and equal-sample renders, then every reference (the
# slow part), so a usable set exists early. Each scene:
#   OUT_DIR/SCENE/noisy/0001.exr ...        1-spp multilayer EXRs: `rtdenoise denoise` reads them
#   OUT_DIR/SCENE/reference/0001.exr ...    `rtdenoise compare RESULT_DIR OUT_DIR/SCENE/reference`
#   OUT_DIR/SCENE/sppN/0001.exr ...         N-spp renders, RGB
#   OUT_DIR/SCENE/results/sppN/result_<i>.exr  links to them, named as `rtdenoise compare` reads
#                                           results: compare OUT_DIR/SCENE/results/spp16 ...
#   OUT_DIR/SCENE/scene.json, render_times.tsv
# Run it niced on a shared machine: nice -n 15 scripts/validation_scenes.sh
set -euo pipefail
# Everything is in main, read whole before it runs: editing this file during a run of hours
# cannot change what the run does.
main() {
    here=$(cd "$(dirname "$0")/.." && pwd)
    script=$here/scripts/blender/validation_scenes.py
    blender=${BLENDER:-blender}

    width=320 height=240 frames=16 reference_spp=1024 equal_spp=4,16,64 seed=1
    scenes=indirect-room,texture-gallery,small-lights,light-switch
    reference=1 png=() out="" together=0
    usage() { sed -n '2,/^set -euo/p' "$0" | sed '$d; s/^# \{0,1\}//'; }
    need() { [[ $# -ge 2 ]] || { echo "validation_scenes.sh: $1 needs a value" >&2; exit 2; }; }
    while [[ $# -gt 0 ]]; do
        case $1 in
            --width) need "$@"; width=$2; shift 2 ;;
            --height) need "$@"; height=$2; shift 2 ;;
            --frames) need "$@"; frames=$2; shift 2 ;;
            --reference-spp) need "$@"; reference_spp=$2; shift 2 ;;
            --equal-spp) need "$@"; equal_spp=$2; shift 2 ;;
            --scenes) need "$@"; scenes=$2; shift 2 ;;
            --seed) need "$@"; seed=$2; shift 2 ;;
            --no-reference) reference=0; shift ;;
            --png) png=(--png); shift ;;
            --together) together=1; shift ;;
            -h|--help) usage; exit 0 ;;
            -*) echo "validation_scenes.sh: unknown option $1 (--help lists them)" >&2; exit 2 ;;
            *) [[ -z $out ]] || { echo "validation_scenes.sh: one OUT_DIR only" >&2; exit 2; }
               out=$1; shift ;;
        esac
    done
    for value in "$width" "$height" "$frames" "$reference_spp" "$seed"; do
        [[ $value =~ ^[0-9]+$ ]] ||
            { echo "validation_scenes.sh: not a number: $value" >&2; exit 2; }
    done
    [[ $width -ge 1 && $height -ge 1 && $frames -ge 1 && $reference_spp -ge 1 ]] ||
        { echo "validation_scenes.sh: sizes, frames and samples must be >= 1" >&2; exit 2; }
    equal=()
    IFS=, read -r -a spps <<< "$equal_spp"
    for n in "${spps[@]}"; do
        [[ $n =~ ^[1-9][0-9]*$ ]] ||
            { echo "validation_scenes.sh: --equal-spp: not a count: $n" >&2; exit 2; }
        equal+=("spp$n")
    done
    IFS=, read -r -a scene_list <<< "$scenes"
    for s in "${scene_list[@]}"; do
        case $s in indirect-room|texture-gallery|small-lights|light-switch) ;;
            *) echo "validation_scenes.sh: unknown scene $s" >&2; exit 2 ;; esac
    done
    command -v "$blender" > /dev/null || {
        echo "validation_scenes.sh: no $blender: install Blender 3.4" \
             "(Debian: apt-get install blender)" >&2
        exit 1; }

    out=${out:-$here/cache/validation_scenes}
    mkdir -p "$out/logs"
    out=$(cd "$out" && pwd)
    log=$out/logs/driver.log
    exec 9> "$out/.lock"
    flock -n 9 ||
        { echo "validation_scenes.sh: $out is being rendered by another run" >&2; exit 1; }

    # One OUT_DIR, one set of settings: frames already there are kept, so mixing two would be wrong.
    # The version names the scenes (VERSION in the Blender script).
    version=$(sed -n 's/^VERSION = "\(.*\)"$/\1/p' "$script")
    settings="version=$version width=$width height=$height frames=$frames seed=$seed"
    settings+=" reference_spp=$reference_spp"
    if [[ -f $out/settings.txt ]]; then
        old=$(cat "$out/settings.txt")
        if [[ $old != "$settings" ]]; then
            echo "validation_scenes.sh: $out was rendered with $old, now $settings:" \
                 "choose another OUT_DIR or delete it" >&2
            exit 1
        fi
    else
        echo "$settings" > "$out/settings.txt"
    fi

    say() { echo "$(date '+%F %T') $*" | tee -a "$log"; }

    # Whether every frame of SCENE/KIND is on disk.
    complete() {
        local f
        for ((f = 1; f <= frames; ++f)); do
            [[ -f $out/$1/$2/$(printf %04d "$f").exr ]] || return 1
        done
    }

    # render SCENE KIND...: one Blender run for the kinds not yet complete.
    render() {
        local scene=$1 kind todo=() start status
        shift
        for kind in "$@"; do complete "$scene" "$kind" || todo+=("$kind"); done
        if [[ ${#todo[@]} -eq 0 ]]; then
            say "$scene: $* already rendered"
            return 0
        fi
        local kinds
        kinds=$(IFS=,; echo "${todo[*]}")
        say "$scene: rendering $kinds (${width}x$height, $frames frames; log logs/$scene.log)"
        start=$(date +%s)
        status=0
        "$blender" -b -noaudio --python-exit-code 1 --factory-startup -P "$script" -- "$out" \
            --scene "$scene" --kinds "$kinds" --width "$width" --height "$height" \
            --frames "$frames" --reference-spp "$reference_spp" --seed "$seed" "${png[@]}" \
            >> "$out/logs/$scene.log" 2>&1 || status=$?
        grep -h '^validation_scenes: \|rendered with other settings' "$out/logs/$scene.log" |
            tail -n 1 | sed 's/^/    last: /' >> "$log" || true
        if [[ $status -ne 0 ]]; then
            say "$scene: Blender failed (exit $status); the end of logs/$scene.log:"
            tail -n 15 "$out/logs/$scene.log" | tee -a "$log" >&2
            return 1
        fi
        say "$scene: $kinds done in $(( $(date +%s) - start )) s"
    }

    # results/sppN/result_<i>.exr -> ../../sppN/<frame>.exr, for `rtdenoise compare`.
    link_results() {
        local scene=$1 kind f
        for kind in "${equal[@]}"; do
            complete "$scene" "$kind" || continue
            mkdir -p "$out/$scene/results/$kind"
            for ((f = 1; f <= frames; ++f)); do
                ln -sfn "../../$kind/$(printf %04d "$f").exr" \
                    "$out/$scene/results/$kind/result_$((f - 1)).exr"
            done
        done
    }

    say "start: ${width}x$height, $frames frames, reference $reference_spp spp," \
        "equal ${equal[*]:-none}, seed $seed, scenes ${scene_list[*]} -> $out" \
        "($("$blender" --version 2>/dev/null | head -n 1), $version)"
    total=$(date +%s)
    failed=0
    last=()
    [[ $reference -eq 1 && $together -eq 1 ]] && last=(reference)
    for scene in "${scene_list[@]}"; do
        render "$scene" noisy "${equal[@]}" "${last[@]}" || failed=1
        link_results "$scene"
    done
    if [[ $reference -eq 1 && $together -eq 0 ]]; then
        for scene in "${scene_list[@]}"; do
            render "$scene" reference || failed=1
        done
    fi
    say "end: $(( $(date +%s) - total )) s, $(du -sh "$out" | cut -f1) in $out" \
        "$([[ $failed -eq 0 ]] && echo ok || echo '(with failures: see above)')"
    return $failed
}

main "$@"
