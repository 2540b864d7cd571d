#!/usr/bin/env bash
# Runs every libFuzzer target of a `fuzz` preset build over a seed corpus made from the shipped
# assets and the tests' data (docs/fuzzing.md):
#
#   fuzz/run_fuzzers.sh BUILD_DIR RUNS [TARGETS]
#
# RUNS executions per target after the seeds (deterministic: -seed=1). Prints a table (target,
# executions, seconds, corpus size, outcome) and exits non-zero when any target crashed, leaked,
# timed out or ran out of memory; the input that did it is kept in BUILD_DIR/fuzz-artifacts/.
set -uo pipefail
BUILD=${1:?usage: fuzz/run_fuzzers.sh BUILD_DIR RUNS}
RUNS=${2:?usage: fuzz/run_fuzzers.sh BUILD_DIR RUNS}
TARGETS=${3:-fuzz_scene_loader fuzz_mesh_import fuzz_editor_script}  # a subset, space-separated
ROOT=$(cd "$(dirname "$0")/.." && pwd)
CORPORA="$BUILD/fuzz-corpus"
ARTIFACTS="$BUILD/fuzz-artifacts"
mkdir -p "$ARTIFACTS"

seed() {  # seed TARGET FILES... (a mesh target's files prefixed by their format byte)
    local target=$1
    shift
    mkdir -p "$CORPORA/$target"
    for f in "$@"; do
        [[ -f $f ]] || continue
        local name
        name=$(basename "$f")
        case $target in
        fuzz_mesh_import)
            case $f in
            *.obj) byte='\x00' ;; *.ply) byte='\x01' ;; *.gltf) byte='\x02' ;; *.glb) byte='\x03' ;; *) continue ;;
            esac
            # shellcheck disable=SC2059  # the byte is an escape for printf to expand
            { printf "$byte"; cat "$f"; } > "$CORPORA/$target/seed_$name" ;;
        *) cp "$f" "$CORPORA/$target/seed_$name" ;;
        esac
    done
}
seed fuzz_scene_loader "$ROOT"/assets/scenes/*.toml "$ROOT"/tests/scene/data/*.toml
seed fuzz_mesh_import "$ROOT"/tests/scene/data/*.obj "$ROOT"/tests/scene/data/*.ply "$ROOT"/tests/scene/data/*.gltf
seed fuzz_editor_script "$ROOT"/tests/editor/data/*.txt

failed=0
printf '| target | executions | seconds | corpus files | outcome |\n|---|---|---|---|---|\n'
for target in $TARGETS; do
    bin="$BUILD/bin/$target"
    if [[ ! -x $bin ]]; then
        printf '| %s | — | — | — | not built |\n' "$target"
        continue
    fi
    log="$BUILD/$target.log"
    start=$(date +%s.%N)
    # -timeout: one input may take this long (s); -rss_limit_mb: the memory a run may reach.
    ASAN_OPTIONS=detect_leaks=1 LSAN_OPTIONS="suppressions=$ROOT/fuzz/lsan.supp" \
        UBSAN_OPTIONS=halt_on_error=1:print_stacktrace=1 \
        "$bin" "$CORPORA/$target" -runs="$RUNS" -seed=1 -timeout=10 -rss_limit_mb=2048 -max_len=65536 \
        -artifact_prefix="$ARTIFACTS/$target-" -print_final_stats=1 > "$log" 2>&1
    rc=$?
    seconds=$(awk "BEGIN { printf \"%.1f\", $(date +%s.%N) - $start }")
    execs=$(grep -oE 'stat::number_of_executed_units: *[0-9]+' "$log" | grep -oE '[0-9]+$' | tail -1)
    files=$(find "$CORPORA/$target" -type f | wc -l)
    if [[ $rc -eq 0 ]]; then
        outcome="no crash"
    else
        outcome="FAILED (exit $rc): $(grep -m1 -E 'ERROR: |SUMMARY: |runtime error' "$log" | cut -c1-120)"
        failed=$((failed + 1))
    fi
    printf '| %s | %s | %s | %s | %s |\n' "$target" "${execs:-?}" "$seconds" "$files" "$outcome"
done
exit "$failed"
