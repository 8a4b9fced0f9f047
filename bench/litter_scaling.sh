#!/usr/bin/env bash
# sere litter's scaling over MPI ranks (issue #21), measured: not a timed test, a report.
#
#   bench/litter_scaling.sh [REPS]     (default 5; SERE=path/to/sere, default build/sere)
#
# Strong scaling: the same 16 small leaves (seed 1, drawn species, 400 points, at most 300
# frames each) on 1 and then 2 ranks of 1 thread. Weak scaling: 8 red maples per rank (400
# points, 300 frames: every leaf the same work, so 2 ranks have exactly twice the work of 1) on
# 1 and 2 ranks. The configurations run interleaved (A B A B ...) so that a change in the
# machine's load falls on both; each time is the median of REPS. Two times per run: "litter", the
# command's own wall time from summary.json (drying, the gather to rank 0, the scene written), and
# "command", the whole mpirun including Open MPI's start-up. Prints the load (uptime) before and
# after: on a shared machine the second core may be busy with other work, which shows as a lower
# speed-up.
set -euo pipefail
cd "$(dirname "$0")/.."
reps=${1:-5}
sere=${SERE:-build/sere}
"$sere" litter --help | grep -q "Built with MPI" || { echo "$sere was built without MPI" >&2; exit 1; }
command -v mpirun >/dev/null || { echo "no mpirun on the PATH" >&2; exit 1; }
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

# run NAME NP ARGS...: one litter into a fresh directory; appends "litter command" seconds to
# $work/NAME.
run() {
	local name=$1 np=$2
	shift 2
	rm -rf "$work/out"
	local t0 t1
	t0=$(date +%s.%N)
	mpirun --allow-run-as-root --oversubscribe -np "$np" "$sere" litter --threads 1 --progress 86400 \
		--out "$work/out" "$@" >/dev/null
	t1=$(date +%s.%N)
	local litter
	litter=$(grep -o '"wall_seconds": [0-9.]*' "$work/out/summary.json" | grep -o '[0-9.]*$')
	echo "$litter $(echo "$t1 - $t0" | bc -l)" >>"$work/$name"
}

# median NAME COLUMN
median() {
	sort -g -k"$2","$2" "$work/$1" | awk -v c="$2" '{ v[NR] = $c } END { printf "%.3f", NR % 2 ? v[(NR + 1) / 2] : (v[NR / 2] + v[NR / 2 + 1]) / 2 }'
}

strong=(--leaves 16 --seed 1 --points 400 --frames 300)
echo "load before: $(uptime)"
for ((i = 0; i < reps; ++i)); do
	run strong1 1 "${strong[@]}"
	run strong2 2 "${strong[@]}"
	run weak1 1 --leaves 8 --seed 1 --points 400 --frames 300 --preset maple-red
	run weak2 2 --leaves 16 --seed 1 --points 400 --frames 300 --preset maple-red
done
echo "load after:  $(uptime)"
echo "medians of $reps, seconds (litter = sere's own wall time; command = the whole mpirun):"
for c in strong1 strong2 weak1 weak2; do
	echo "  $c: litter $(median $c 1), command $(median $c 2)   [$(awk '{ printf "%s ", $1 }' "$work/$c")]"
done
for col in 1 2; do
	what=$([ $col = 1 ] && echo litter || echo command)
	s1=$(median strong1 $col) s2=$(median strong2 $col) w1=$(median weak1 $col) w2=$(median weak2 $col)
	echo "$what: strong scaling 16 leaves 1 -> 2 ranks: $(echo "$s1 / $s2" | bc -l | xargs printf %.2f)x;" \
		"weak scaling 8 -> 16 red maples on 1 -> 2 ranks: efficiency $(echo "100 * $w1 / $w2" | bc -l | xargs printf %.0f)%"
done
