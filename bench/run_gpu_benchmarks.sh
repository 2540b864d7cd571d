#!/usr/bin/env bash
# GPU benchmark run for a host with one CUDA GPU (measured on an H100 with 16 cores): the CUDA kernel
# benchmarks, the flag scene at 80K, 200K and 1.2M triangles on the CUDA backend, and the CPU backend
# at 80K and 200K for comparison. Every stage has its own time limit; together at most ~6.5 min
# (expected ~2-3 min on an H100 host).
#
#   bench/run_gpu_benchmarks.sh BUILD_DIR OUT_DIR
#
# BUILD_DIR holds bin/weft and bin/weft_cuda_bench (cmake -S . -B BUILD_DIR -G Ninja && cmake --build
# BUILD_DIR). OUT_DIR receives, per stage, NAME.json and NAME.log:
#   cuda_kernels          weft_cuda_bench: copy bandwidth, SpMV, PCG iteration, whole step, memory
#   flag_80k_cuda         weft bench flag, cells [250,160]  =    80,000 triangles, dt 1/60 s, 2 substeps
#   flag_200k_cuda        weft bench flag, cells [400,250]  =   200,000 triangles, dt 1/60 s, 2 substeps
#   flag_1200k_cuda       weft bench flag, cells [1000,600] = 1,200,000 triangles, dt 0.004 s, 1 substep
#                         (P-Cloth's setting: one implicit step of 1/250 s per frame)
#   flag_80k_cpu, flag_200k_cpu   the same scenes on --backend cpu --threads 16, few frames
#   collide_twist_cuda    weft bench twist, 317 x 317 vertices (200K triangles), cloth collisions on the GPU
#   collide_sphere_cuda   weft bench sphere, cells [316,316] (200K triangles)
#   collide_falling_cuda  weft bench falling, cells [147,147] (4 x 43K = 173K triangles)
#   collide_layers_cuda   weft bench layers, 50 sheets of cells [69,69] (476K triangles)
#                         (the scenes' Try: sizes; impact zones still run on the host, see
#                         cuda/src/device_collisions.h; COLLIDE_FRAMES frames each)
# then prints a summary (summary.txt). Exit status: the number of stages that failed (0: all ran).
set -uo pipefail

source "$(dirname "$0")/common/bench_dirs.sh"
bench_dirs exact "" "$@"
WEFT="$BUILD/bin/weft"
KERNELS="$BUILD/bin/weft_cuda_bench"
for exe in "$WEFT" "$KERNELS"; do
    [[ -x "$exe" ]] || { echo "$0: $exe not found (build first; weft_cuda_bench needs the CUDA backend)" >&2; exit 2; }
done

# Frames per stage (override through the environment).
CUDA_FRAMES=${CUDA_FRAMES:-100}    # 80K and 200K on the GPU
CUDA_WARMUP=${CUDA_WARMUP:-10}
LARGE_FRAMES=${LARGE_FRAMES:-40}   # 1.2M on the GPU
LARGE_WARMUP=${LARGE_WARMUP:-5}
CPU_FRAMES=${CPU_FRAMES:-5}        # CPU: ~2.7 s/frame at 80K on 2 cores; fewer with 16
CPU_WARMUP=${CPU_WARMUP:-1}
CPU_THREADS=${CPU_THREADS:-16}
COLLIDE_FRAMES=${COLLIDE_FRAMES:-10}  # collision scenes at their Try: sizes on the GPU
COLLIDE_WARMUP=${COLLIDE_WARMUP:-2}

CELLS_80K='cloth.flag.mesh.grid.cells=[250,160]'
CELLS_200K='cloth.flag.mesh.grid.cells=[400,250]'
CELLS_1200K='cloth.flag.mesh.grid.cells=[1000,600]'
LARGE_DT='solver.dt=0.004'
LARGE_SUBSTEPS='solver.substeps=1'

failed=0
declare -a STATUS=()

# stage NAME LIMIT_SECONDS COMMAND...: runs COMMAND with a time limit, output to OUT/NAME.log.
stage() {
    local name=$1 limit=$2
    shift 2
    echo "== $name (limit ${limit}s): $*"
    local start=$SECONDS rc
    {
        echo "# $*"
        timeout --signal=INT --kill-after=15 "$limit" "$@"
    } >"$OUT/$name.log" 2>&1
    rc=$?
    local took=$((SECONDS - start))
    if [[ $rc -eq 0 ]]; then
        STATUS+=("$name: ok (${took}s)")
    else
        [[ $rc -eq 124 ]] && echo "   $name: timed out after ${limit}s" | tee -a "$OUT/$name.log"
        STATUS+=("$name: FAILED rc=$rc (${took}s, see $name.log)")
        failed=$((failed + 1))
    fi
    tail -n 30 "$OUT/$name.log"
    echo
}

echo "Weft GPU benchmarks: build $BUILD, results in $OUT"
{ nvidia-smi --query-gpu=name,driver_version,memory.total,clocks.max.memory --format=csv 2>/dev/null || true; } | tee "$OUT/gpu.txt"
{ nproc; lscpu 2>/dev/null | grep -E 'Model name|^CPU\(s\)' || true; } > "$OUT/cpu.txt"
"$WEFT" info >"$OUT/weft_info.txt" 2>&1 || true
echo

# (a) kernels: copy bandwidth, SpMV, PCG iteration, whole step, memory; 1.2M at dt 0.004, 1 substep.
stage cuda_kernels 120 "$KERNELS" --json "$OUT/cuda_kernels.json" \
    --size 80000 --size 200000 --size "1200000@$LARGE_DT@$LARGE_SUBSTEPS"

# (b) whole scene on the CUDA backend.
stage flag_80k_cuda 40 "$WEFT" bench flag --backend cuda --set "$CELLS_80K" \
    --frames "$CUDA_FRAMES" --warmup "$CUDA_WARMUP" --json "$OUT/flag_80k_cuda.json"
stage flag_200k_cuda 40 "$WEFT" bench flag --backend cuda --set "$CELLS_200K" \
    --frames "$CUDA_FRAMES" --warmup "$CUDA_WARMUP" --json "$OUT/flag_200k_cuda.json"
stage flag_1200k_cuda 60 "$WEFT" bench flag --backend cuda --set "$CELLS_1200K" --set "$LARGE_DT" \
    --set "$LARGE_SUBSTEPS" --frames "$LARGE_FRAMES" --warmup "$LARGE_WARMUP" --json "$OUT/flag_1200k_cuda.json"

# (c) the same scenes on the CPU backend (slow: few frames, capped).
stage flag_80k_cpu 45 "$WEFT" bench flag --backend cpu --threads "$CPU_THREADS" --set "$CELLS_80K" \
    --frames "$CPU_FRAMES" --warmup "$CPU_WARMUP" --json "$OUT/flag_80k_cpu.json"
stage flag_200k_cpu 75 "$WEFT" bench flag --backend cpu --threads "$CPU_THREADS" --set "$CELLS_200K" \
    --frames "$CPU_FRAMES" --warmup "$CPU_WARMUP" --json "$OUT/flag_200k_cpu.json"

# (d) collision scenes at their Try: sizes on the CUDA backend (per-stage times in the summary).
stage collide_twist_cuda 90 "$WEFT" bench twist --backend cuda --set 'cloth.sheet.mesh.grid.cells=[316,316]' \
    --set cloth.sheet.mesh.grid.width=3.16 --set cloth.sheet.mesh.grid.height=3.16 \
    --frames "$COLLIDE_FRAMES" --warmup "$COLLIDE_WARMUP" --json "$OUT/collide_twist_cuda.json"
stage collide_sphere_cuda 90 "$WEFT" bench sphere --backend cuda --set 'cloth.sheet.mesh.grid.cells=[316,316]' \
    --frames "$COLLIDE_FRAMES" --warmup "$COLLIDE_WARMUP" --json "$OUT/collide_sphere_cuda.json"
stage collide_falling_cuda 90 "$WEFT" bench falling --backend cuda --set 'cloth.sheet.mesh.grid.cells=[147,147]' \
    --frames "$COLLIDE_FRAMES" --warmup "$COLLIDE_WARMUP" --json "$OUT/collide_falling_cuda.json"
stage collide_layers_cuda 120 "$WEFT" bench layers --backend cuda --set cloth.sheets.repeat.count=50 \
    --set 'cloth.sheets.mesh.grid.cells=[69,69]' \
    --frames "$COLLIDE_FRAMES" --warmup "$COLLIDE_WARMUP" --json "$OUT/collide_layers_cuda.json"

# ---- summary --------------------------------------------------------------------------------------
summarize() {
    echo "Stages:"
    printf '  %s\n' "${STATUS[@]}"
    echo
    if ! command -v python3 >/dev/null 2>&1; then
        echo "(python3 not found: no table; see the JSON files in $OUT)"
        return
    fi
    python3 - "$OUT" <<'PY'
import json, os, sys
out = sys.argv[1]

def load(name):
    path = os.path.join(out, name + ".json")
    try:
        with open(path) as f:
            return json.load(f)
    except (OSError, ValueError):
        return None

def fmt(v, d=1):
    return "-" if v is None else f"{v:.{d}f}"

k = load("cuda_kernels")
if k is None:
    print("cuda_kernels: no results")
elif not k.get("cuda_available"):
    print("cuda_kernels: no CUDA device:", k.get("reason"))
else:
    print(f"GPU: {k['gpu']['name']}  (L2 {k['gpu']['l2_bytes'] / 2**20:.0f} MiB)")
    print(f"{'size':>10} {'cells':>10} {'copy GB/s':>10} {'SpMV warm':>16} {'SpMV cold':>16} "
          f"{'PCG it us':>10} {'PCG GB/s':>16} {'step ms':>9} {'CG it':>7} {'B/tri':>7}")
    for s in k["sizes"]:
        cells = "x".join(str(c) for c in s["cells"])
        if "error" in s:
            print(f"{s['label']:>10} {cells:>10}  failed: {s['error']}")
            continue
        sp, pc = s["spmv"], s["pcg_iteration"]["graph"]
        rate = lambda r: f"{r['gb_per_s']:.0f} ({100 * r['ratio_to_copy']:.0f}%)"
        print(f"{s['triangles']:>10} {cells:>10} {s['copy']['gb_per_s']:>10.0f} {rate(sp['warm']):>16} "
              f"{rate(sp['cold']):>16} {1000 * pc['ms_per_iteration']['median']:>10.1f} {rate(pc):>16} "
              f"{s['step']['wall_ms']['median']:>9.2f} {s['step']['cg_iterations_per_step']['mean']:>7.1f} "
              f"{s['memory']['bytes_per_triangle']:>7.0f}")
    print("  (SpMV target: >= 60% of copy bandwidth; cold = L2 flushed before each SpMV)")
print()

rows = []
for name in ("flag_80k_cuda", "flag_200k_cuda", "flag_1200k_cuda", "flag_80k_cpu", "flag_200k_cpu"):
    r = load(name)
    if not r:
        rows.append((name, None))
        continue
    rows.append((name, r[0]))
print(f"{'run':<17} {'backend':<8} {'triangles':>10} {'dt':>8} {'sub':>4} {'frames/s':>9} {'step ms':>10} "
      f"{'solve ms':>10} {'CG it/step':>10} {'B/tri':>7} {'not conv':>8}")
for name, r in rows:
    if r is None:
        print(f"{name:<17} no results")
        continue
    st = r["stage_ms"]
    print(f"{name:<17} {r['backend']:<8} {r['triangles']:>10} {r['dt']:>8.5f} {r['substeps']:>4} {r['fps']:>9.2f} "
          f"{st['step']['median']:>10.2f} {st['solve']['median']:>10.2f} {r['cg_iterations']['mean']:>10.1f} "
          f"{r['memory_bytes_per_triangle']:>7.0f} {r['cg_not_converged']:>8}")
def fps(name):
    r = dict(rows).get(name)
    return r["fps"] if r else None
for size in ("80k", "200k"):
    g, c = fps(f"flag_{size}_cuda"), fps(f"flag_{size}_cpu")
    if g and c:
        print(f"speed-up CUDA / CPU ({size}): {g / c:.1f}x")
print()
print("collision scenes on the CUDA backend, median ms per step by stage:")
for name in ("collide_twist_cuda", "collide_sphere_cuda", "collide_falling_cuda", "collide_layers_cuda"):
    r = load(name)
    if not r:
        print(f"  {name:<22} no results")
        continue
    r = r[0]
    st = r["stage_ms"]
    parts = "  ".join(f"{k} {v['median']:.2f}" for k, v in st.items() if v.get("median", 0) > 0)
    print(f"  {name:<22} {r['triangles']:>8} tri  {parts}")
PY
}

echo "================ summary ================"
summarize | tee "$OUT/summary.txt"
echo
echo "logs and JSON: $OUT"
exit "$failed"
