#!/bin/sh
# bench/redundant.sh MECHC [STEPS] [REPEATS] - what redundant rows cost `run`:
# examples/four_bar_spatial_redundant.mech (24 rows for 21 coordinates, three
# redundant) against the same mechanism written without them (its fourth
# revolute, O4, as the two rows that are not redundant, O4x and O4y, written
# as `constraint` rows: 21 rows). Both run one crank turn in STEPS steps
# (default 20 000) with the jit engine, --linear auto (the default: dense for
# the first file, KLU for the second), dense and sparse; the figure is the
# CPU time of the steps (`mechc run --stats`, set-up and output excluded),
# the least of REPEATS runs (default 5), and the ratio of the two files.
set -u
if [ $# -lt 1 ]; then
    echo "usage: sh bench/redundant.sh PATH/TO/mechc [STEPS] [REPEATS]" >&2
    exit 2
fi
mechc=$1
steps=${2:-20000}
repeats=${3:-5}
here=$(dirname "$0")
red=$here/../examples/four_bar_spatial_redundant.mech
tmp=$(mktemp -d "${TMPDIR:-/tmp}/mechc_bench.XXXXXX") || exit 2
trap 'rm -rf "$tmp"' EXIT
sed -e 's/^revolute O4:.*/constraint O4x: rocker.x - c\/2*(rocker.e0^2 + rocker.e1^2 - rocker.e2^2 - rocker.e3^2) = d\
constraint O4y: rocker.y - c*(rocker.e1*rocker.e2 + rocker.e0*rocker.e3) = 0/' \
    -e 's/^mechanism .*/mechanism four_bar_spatial_plain/' "$red" > "$tmp/plain.mech"

# the least CPU time per step (ns) of $repeats runs of FILE with --linear L
least() {
    best=""
    i=0
    while [ "$i" -lt "$repeats" ]; do
        ns=$("$mechc" run "$1" --linear "$2" --steps "$steps" --stats --csv /dev/null 2>&1 |
             sed -n 's/.*CPU time in the steps: \([0-9]*\) ns per step.*/\1/p')
        if [ -z "$ns" ]; then
            echo "bench/redundant.sh: $1 did not run" >&2
            exit 1
        fi
        if [ -z "$best" ] || [ "$ns" -lt "$best" ]; then best=$ns; fi
        i=$((i + 1))
    done
    echo "$best"
}

printf '%-8s %16s %16s %8s\n' linear "without (ns)" "redundant (ns)" ratio
for lin in auto dense sparse; do
    a=$(least "$tmp/plain.mech" "$lin") || exit 1
    b=$(least "$red" "$lin") || exit 1
    awk -v l="$lin" -v a="$a" -v b="$b" 'BEGIN { printf "%-8s %16d %16d %8.2f\n", l, a, b, b / a }'
done
