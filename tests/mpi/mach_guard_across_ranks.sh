#!/usr/bin/env bash
# The Mach guard on many ranks (issue #7, DESIGN.md §7): the coarse 2D dam break with c0 = 10 m/s
# stops on the Mach guard at the same step on 1 and 3 ranks with the same message, which names the
# fastest fluid particle over all ranks. The named particle is owned fluid in exactly one rank's
# emergency_stepN_rankR.csv, at the speed the message gives, and no owned fluid row of any rank is
# faster; the owned fluid rows of all ranks are the one-rank run's fluid, and halo copies are
# labelled halo, not fluid.
#   mach_guard_across_ranks.sh SPHDEM_BINARY SCENE WORKDIR
set -uo pipefail
bin=$1; scene=$2; work=$3
rm -rf "$work"; mkdir -p "$work"
export OMP_NUM_THREADS=1 OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
args=(--set sph.dp=0.0073 --set time.end=0.5 --set time.cfl=0.2 --set guards.mach_max=0.15
      --set fluid.c0=10 --quiet)
fail() { echo "FAIL: $*"; exit 1; }
"$bin" run "$scene" --out "$work/one" "${args[@]}"; rc=$?
[ "$rc" -eq 3 ] || fail "one rank: exit status $rc, not 3 (unstable)"
mpirun --oversubscribe -n 3 "$bin" run "$scene" --out "$work/many" "${args[@]}" >/dev/null 2>&1; rc=$?
[ "$rc" -ne 0 ] || fail "3 ranks: the run did not stop"
one=$(grep "^ERROR: " "$work/one/run.log") || fail "one rank: no ERROR line"
many=$(grep "^ERROR: " "$work/many/run.log") || fail "3 ranks: no ERROR line"
case "$one" in *"Mach number too high"*"the fastest is fluid particle id "*) ;;
  *) fail "one rank: not the Mach guard naming a particle: $one" ;; esac
[ "$one" = "$many" ] || fail "the messages differ: '$one' against '$many'"
step=$(echo "$one" | sed -n 's/.*(step \([0-9]*\)).*/\1/p')
id=$(echo "$one" | sed -n 's/.*the fastest is fluid particle id \([0-9]*\) .*/\1/p')
speed=$(echo "$one" | sed -n 's/.*, speed \([0-9.e+-]*\) m\/s.*/\1/p')
[ -n "$step" ] && [ -n "$id" ] && [ -n "$speed" ] || fail "cannot parse step/id/speed from: $one"
files=("$work/many/emergency_step${step}_rank"*.csv)
[ "${#files[@]}" -eq 3 ] || fail "expected 3 rank files, found ${#files[@]}"
awk -F, -v id="$id" -v speed="$speed" '
  FNR == 1 { next }
  { s = sqrt($6 * $6 + $7 * $7 + $8 * $8) }
  $2 == "fluid" { ++fluid; if (s > top) top = s; if ($1 == id) { ++owners; named = s } }
  $2 == "halo" { ++halo }
  END {
    bad = 0
    if (owners != 1) { print "particle " id " is owned fluid in " owners " rank files"; bad = 1 }
    d = named - speed; if (d < 0) d = -d
    if (d > 1e-5 * speed) { print "its speed " named " is not the message'"'"'s " speed; bad = 1 }
    if (top > named) { print "a faster owned fluid row: " top " > " named; bad = 1 }
    if (halo < 1) { print "no halo rows"; bad = 1 }
    printf "%d owned fluid, %d halo rows\n", fluid, halo > "/dev/stderr"
    print fluid > "'"$work"'/fluid_rows"
    exit bad }' "${files[@]}" || fail "the emergency state does not hold the named particle as the fastest"
one_fluid=$(grep -c ",fluid," "$work/one/emergency_step${step}.csv")
[ "$(cat "$work/fluid_rows")" -eq "$one_fluid" ] ||
  fail "owned fluid rows over the ranks: $(cat "$work/fluid_rows"), one rank: $one_fluid"
echo "Mach guard on 3 ranks: step $step, particle $id at $speed m/s, as on one rank"
