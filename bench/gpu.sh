#!/bin/sh
# bench/gpu.sh - the native crowd benchmark (bench/bench_gl.c) unattended on a GPU (issue 43, item 5):
# the palette (per-vertex blending), the bone pass, the bone pass with the runtimes' animation LOD (its
# tiers drawn apart, as the herds ship it) and the VAT of the same frames, each one instanced draw of
# 1,000 to 300,000 Cows into a 960x540 offscreen target, timed by GL timer queries; then the largest
# herd each method draws at 60 fps. OpenGL 3.3 core through EGL's device platform: the GPU's
# own driver (NVIDIA's libEGL_nvidia), no window, no display server.
#
#   sh bench/gpu.sh [MODEL.glb] [OUT_DIR]
#
# MODEL defaults to the shared Cow (../shared/assets, else shared/assets, else build/samples' quadruped);
# OUT_DIR to $OUT (the device runner's) or build/gpu-bench. Writes there: gpu.txt (nvidia-smi, the
# driver's EGL), check.txt (the methods draw the same image), bench.json (bench_gl's numbers)
# and summary.txt (frame ms per count and method, and the largest herd at 60 fps). Needs build/bench_gl,
# built beforehand (make build/bench_gl) since a lent GPU machine may have no compiler or packages:
# it says which shared library is missing rather than failing later. The counts go up in turn,
# all within GPU_BENCH_SECONDS (480) of the start, so the whole run stays under 10 minutes; a count
# that fails or runs out of time ends the series, and the summary says so.
set -u
cd "$(dirname "$0")/.."
BENCH=${BENCH_GL:-build/bench_gl}
MODEL=${1:-}
OUT_DIR=${2:-${OUT:-build/gpu-bench}}
COUNTS=${GPU_BENCH_COUNTS:-1000 3000 10000 30000 100000 300000}
FRAMES=${GPU_BENCH_FRAMES:-9}
mkdir -p "$OUT_DIR"
if [ -z "$MODEL" ]; then
    for m in ../shared/assets/quaternius-cow/Cow.glb shared/assets/quaternius-cow/Cow.glb build/samples/quadruped.glb; do
        if [ -f "$m" ]; then MODEL=$m; break; fi
    done
fi
say() { echo "gpu.sh: $*" | tee -a "$OUT_DIR/summary.txt"; }
: > "$OUT_DIR/summary.txt"
[ -n "$MODEL" ] && [ -f "$MODEL" ] || { say "no model (give MODEL.glb: the shared Cow is ../shared/assets/quaternius-cow/Cow.glb)"; exit 2; }
[ -x "$BENCH" ] || { say "$BENCH is not built: run 'make build/bench_gl' on a machine with the packages, and carry build/"; exit 2; }
if ldd "$BENCH" 2>/dev/null | grep -q "not found"; then
    say "$BENCH lacks shared libraries here: $(ldd "$BENCH" | grep 'not found' | tr -s ' \t' ' ' | tr '\n' ';')"
    exit 2
fi
if command -v nvidia-smi > /dev/null; then
    { nvidia-smi -L 2>&1; nvidia-smi --query-gpu=name,driver_version,memory.total,clocks.max.sm --format=csv 2>&1; } \
        > "$OUT_DIR/gpu.txt" || true
else
    echo "no nvidia-smi here (not an NVIDIA machine): the driver bench_gl reports below is the one measured" > "$OUT_DIR/gpu.txt"
fi
say "model $MODEL; counts $COUNTS; $FRAMES frames each (median); GPU: $(head -1 "$OUT_DIR/gpu.txt")"
# EGL's device platform is bench_gl's default; EGL_PLATFORM (Mesa's surfaceless) would pick the CPU.
unset EGL_PLATFORM
if ! timeout 60 "$BENCH" "$MODEL" --check > "$OUT_DIR/check.txt" 2>&1; then
    say "the image check failed (the three methods must draw the same herd): $(tail -1 "$OUT_DIR/check.txt")"
    exit 1
fi
say "$(cat "$OUT_DIR/check.txt")"
# Two bench_gl runs per count (palette, bone pass and VAT; then the bone pass with LOD and the VAT
# again, its ratio taken in the same run), so that a count past its limit (or the GPU's memory)
# keeps the others; all of them within 480 s of now (with the check and the start, under 10 minutes).
: > "$OUT_DIR/bench.jsonl"
: > "$OUT_DIR/lod.jsonl"
DEADLINE=$(( $(date +%s) + ${GPU_BENCH_SECONDS:-480} ))
measure() { # COUNT JSONL [--lod]
    LEFT=$(( DEADLINE - $(date +%s) ))
    if [ "$LEFT" -lt 10 ]; then say "$1 instances and up: skipped, out of time"; return 1; fi
    if ! timeout "$LEFT" "$BENCH" "$MODEL" "$1" --frames "$FRAMES" ${3:-} >> "$2" 2>> "$OUT_DIR/stderr.txt"; then
        say "$1 instances${3:+ ($3)}: bench_gl failed or ran past the time left ($LEFT s); larger counts skipped ($(tail -1 "$OUT_DIR/stderr.txt" 2>/dev/null))"
        return 1
    fi
}
for n in $COUNTS; do
    measure "$n" "$OUT_DIR/bench.jsonl" && measure "$n" "$OUT_DIR/lod.jsonl" --lod || break
done
python3 bench/gpu_summary.py "$OUT_DIR/bench.jsonl" "$OUT_DIR/bench.json" "$OUT_DIR/lod.jsonl" | tee -a "$OUT_DIR/summary.txt"
