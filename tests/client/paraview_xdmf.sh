#!/usr/bin/env bash
# A real client: Debian's pvpython (python3-paraview) opens the XDMF of a short run and finds the
# frames, the points of each block and the arrays (app/paraview_check.py).
# Usage: paraview_xdmf.sh SPHDEM PVPYTHON SOURCE_DIR OUT
set -euo pipefail
sphdem=$1 pvpython=$2 src=$3 out=$4
rm -rf "$out"
# 10 steps, a frame at every step (frames.every below dt) and the final one: 11 frames.
"$sphdem" run "$src/inputs/dam_break_2d.yaml" --out "$out" --quiet --max-steps 10 \
  --set sph.dp=0.0146 --set frames.every=1e-9
read -r fluid wall < <(sed -n 's/^particles: \([0-9]*\) fluid, \([0-9]*\) wall.*/\1 \2/p' "$out/run.log")
echo "run: $fluid fluid, $wall wall particles"
[ "$fluid" -gt 0 ] && [ "$wall" -gt 0 ]
"$pvpython" "$src/app/paraview_check.py" "$out/frames.xdmf" 11 $((fluid + wall)) \
  --block fluid="$fluid" --block walls="$wall"
# And it fails when the counts are wrong (the check can fail).
if "$pvpython" "$src/app/paraview_check.py" "$out/frames.xdmf" 11 $((fluid + wall + 1)) \
  > /dev/null 2>&1; then
  echo "paraview_check.py accepted a wrong point count"
  exit 1
fi
