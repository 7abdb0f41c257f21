# Sourced by the device check scripts (gpu_checklist.sh, gpu_detail_checks.sh), which set `out`
# (the log folder) and `status`.
# step NAME COMMAND...: runs it, its output in $out/NAME.log; prints its tail and the time it
# took; a failure sets status=1.
step() {
    local name=$1 start=$SECONDS
    shift
    echo "== $name: $*"
    if "$@" > "$out/$name.log" 2>&1; then
        tail -n 4 "$out/$name.log"
    else
        echo "   FAILED (exit $?), see $name.log"
        tail -n 25 "$out/$name.log"
        status=1
    fi
    echo "   ($((SECONDS - start)) s)"
}
