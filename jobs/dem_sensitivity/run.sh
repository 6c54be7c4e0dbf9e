#!/usr/bin/env bash
# LS-DEM studies on the small rock collapse (mini_collapse.yaml), issue #5.
#   resolution (default): the default node and grid spacing with three pack seeds (the
#     run-to-run spread), then the node spacing and the phi-grid spacing each made 1.5x coarser
#     and 1.5x finer ("how results change with node count and grid spacing");
#   friction: the grain-grain and grain-wall friction coefficients, from Table 2's 0.1 up, at the
#     default resolution (how much of the repose angle comes from the shape, how much from mu);
#   walls: Table 2's 0.1 between rocks, and the floor's and the side walls' own coefficients
#     varied apart (mini_collapse_walls.yaml: the tank split into floor and sides; the baffle
#     keeps grain_wall's 0.5).
# Usage: jobs/dem_sensitivity/run.sh OUTDIR [PARALLEL] [resolution|friction|walls]
#   -> OUTDIR/summary.csv
# One OpenMP thread per run; PARALLEL runs at a time (default 1).
set -euo pipefail
cd "$(dirname "$0")/../.."
out=${1:?output folder}
par=${2:-1}
study=${3:-resolution}
bin=${SPHDEM:-build/sphdem}
mkdir -p "$out"
# name:node_spacing:grid_spacing:seed:mu_grain_grain:mu_grain_wall[:mu_floor:mu_sides]
scene=jobs/dem_sensitivity/mini_collapse.yaml
case "$study" in
  resolution)
    cases="default_s3:0.0018:0.0006:3:0.5:0.5 default_s4:0.0018:0.0006:4:0.5:0.5
default_s5:0.0018:0.0006:5:0.5:0.5 nodes_coarse:0.0027:0.0006:3:0.5:0.5
nodes_fine:0.0012:0.0006:3:0.5:0.5 grid_coarse:0.0018:0.0009:3:0.5:0.5
grid_fine:0.0018:0.0004:3:0.5:0.5" ;;
  friction)
    cases="mu0.1_0.1_s3:0.0018:0.0006:3:0.1:0.1 mu0.1_0.1_s4:0.0018:0.0006:4:0.1:0.1
mu0.3_0.3_s3:0.0018:0.0006:3:0.3:0.3 mu0.7_0.7_s3:0.0018:0.0006:3:0.7:0.7
mu0.1_0.5_s3:0.0018:0.0006:3:0.1:0.5 mu0.5_0.1_s3:0.0018:0.0006:3:0.5:0.1
mu0.5_0.5_s3:0.0018:0.0006:3:0.5:0.5" ;;
  walls)
    scene=jobs/dem_sensitivity/mini_collapse_walls.yaml
    cases="floor0.5_sides0.5_s3:0.0018:0.0006:3:0.1:0.5:0.5:0.5
floor0.5_sides0.1_s3:0.0018:0.0006:3:0.1:0.5:0.5:0.1
floor0.1_sides0.5_s3:0.0018:0.0006:3:0.1:0.5:0.1:0.5" ;;
  *) echo "run.sh: unknown study '$study' (resolution, friction or walls)" >&2; exit 2 ;;
esac
one() {
  IFS=: read -r name ns gs seed mgg mgw mfl msd <<<"$1"
  local walls=()
  if [ -n "$mfl" ]; then  # walls[0] is the floor, walls[1] the sides (mini_collapse_walls.yaml)
    walls=(--set "dem.walls[0].friction=$mfl" --set "dem.walls[1].friction=$msd")
  fi
  OMP_NUM_THREADS=1 "$bin" run "$scene" --out "$out/$name" --quiet \
    --set "dem.shapes[0].node_spacing=$ns" --set "dem.shapes[0].grid_spacing=$gs" \
    --set "dem.packs[0].seed=$seed" --set "dem.grain_grain.friction=$mgg" \
    --set "dem.grain_wall.friction=$mgw" "${walls[@]}" > /dev/null 2>&1 || true
}
export -f one; export out bin scene
printf '%s\n' $cases | xargs -P "$par" -I{} bash -c 'one {}'
echo "case,node_spacing_m,grid_spacing_m,seed,mu_grain_grain,mu_grain_wall,mu_floor,mu_sides,nodes_mean,repose_deg,runout_m,height_m,ke_final_J,status,wall_s" > "$out/summary.csv"
for c in $cases; do
  IFS=: read -r name ns gs seed mgg mgw mfl msd <<<"$c"
  d="$out/$name"
  nodes=$(grep -o '[0-9]* nodes (spacing' "$d/run.log" | awk '{s+=$1; n++} END {if (n) printf "%.1f", s/n}')
  heap=$(grep '^heap:' "$d/run.log" | tail -1)
  ang=$(sed -n 's/.*repose angle \([-0-9.e]*\) deg.*/\1/p' <<<"$heap")
  ro=$(sed -n 's/.*run-out from x = [-0-9.e]*: \([-0-9.e]*\) m.*/\1/p' <<<"$heap")
  ht=$(sed -n 's/.*height \([-0-9.e]*\) m.*/\1/p' <<<"$heap")
  ke=$(tail -1 "$d/grains.csv" | cut -d, -f2)
  st=$(sed -n 's/.*"status": "\([a-z]*\)".*/\1/p' "$d/summary.json")
  wall=$(sed -n 's/.*"wall_seconds": \([0-9.e]*\).*/\1/p' "$d/summary.json")
  echo "$name,$ns,$gs,$seed,$mgg,$mgw,${mfl:-$mgw},${msd:-$mgw},$nodes,$ang,$ro,$ht,$ke,$st,$wall" >> "$out/summary.csv"
done
cat "$out/summary.csv"
