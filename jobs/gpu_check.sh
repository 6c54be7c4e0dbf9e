#!/usr/bin/env bash
# The GPU checks in one pass, for a machine with a CUDA GPU: the gpu test label with
# SPHDEM_REQUIRE_GPU=1, compute-sanitizer (memcheck, racecheck) on the GPU tests, the device
# benchmark (jobs/bench_gpu.sh) and a 2-rank run sharing one GPU (the halo's host staging path).
# Usage: OUT=dir jobs/gpu_check.sh     (binaries: build/ double, build-gpu-float/ float; build the
# latter with `make BUILD=build-gpu-float PRECISION=float`)
# Writes OUT/log.txt, OUT/bench_gpu.jsonl, OUT/memcheck.txt, OUT/racecheck.txt.
set -uo pipefail
cd "$(dirname "$0")/.."
OUT=${OUT:-gpu_check_out}
mkdir -p "$OUT"
exec > >(tee -a "$OUT/log.txt") 2>&1
B=${B:-build}
F=${F:-build-gpu-float}
step() { echo; echo "=== $* ($(date +%T))"; }
step nvidia-smi; nvidia-smi --query-gpu=name,driver_version,memory.total,clocks.sm,clocks.mem --format=csv
step info; "$B/sphdem" info
step gpu tests, double; SPHDEM_REQUIRE_GPU=1 timeout 120 "$B/tests/gpu_tests"; echo "rc=$?"
if [ -x "$F/tests/gpu_tests" ]; then
  step gpu tests, float; SPHDEM_REQUIRE_GPU=1 timeout 120 "$F/tests/gpu_tests"; echo "rc=$?"
fi
step bench; BINS="$B/sphdem $F/sphdem" timeout "${BENCH_S:-300}" jobs/bench_gpu.sh "${STEPS:-20}" |
  tee "$OUT/bench_gpu.jsonl"
step memcheck; timeout 150 compute-sanitizer --tool memcheck --error-exitcode 9 \
  "$B/tests/gpu_tests" > "$OUT/memcheck.txt" 2>&1; echo "rc=$?"; tail -5 "$OUT/memcheck.txt"
step racecheck; timeout 90 compute-sanitizer --tool racecheck --error-exitcode 9 \
  "$B/tests/gpu_tests" --gtest_filter='*Sort*' > "$OUT/racecheck.txt" 2>&1; echo "rc=$?"
tail -5 "$OUT/racecheck.txt"
step two ranks on one GPU; timeout 90 mpirun --oversubscribe -x LD_LIBRARY_PATH -n 2 "$B/sphdem" \
  bench inputs/dam_break_3d.yaml --particles 170000 --steps 10 --warmup 3 --backend device
echo "rc=$?"
step done
