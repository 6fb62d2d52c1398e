#!/bin/sh
# bench/dynamics.sh MECHC - forward dynamics timed: Andrews' squeezer to t = 0.03, IFToMM A02 over 20 s, and the dynamics kernels per engine.
#
#   sh bench/dynamics.sh build/mechc                  (part of `make bench`)
#   A02_N=40 A02_T1=1 REPEAT=3 sh bench/dynamics.sh build/mechc   (A02 over 1 s: quick)
#   A02_DENSE=1 sh bench/dynamics.sh build/mechc      (A02 on the dense path too: ~10 s)
#
# 1. Andrews (examples/andrews.mech, jit, rk8pd, --rtol/--atol 1e-8: the
#    loosest tolerance that keeps 7 correct digits with a margin): the CPU
#    time of the integration alone (`sim --stats`: no parsing, generation
#    or compilation), best and median of REPEAT runs, and beta's relative
#    error against the Test Set's reference at t = 0.03.
# 2. A02 (sh examples/a02_four_bar.sh A02_N, default 40: 243 coordinates)
#    over A02_T1 seconds (default the benchmark's 20) with 400 output steps
#    per 20 s, rk8pd at A02_RTOL (default 1e-6; B0's error is about 1e-7
#    from 1e-8 to 2e-6), the sparse path (`--linear auto` above 100
#    coordinates), best and median of REPEAT runs, and with A02_DENSE=1 the
#    dense path once: the integration's CPU time, the largest error
#    of B0's position and velocity against the exact solution of the
#    published definition (the one-angle equation of the parallelogram
#    branch; the benchmark's data file was not available), and the energy;
#    then the same with `--interpolate` (rk8pd's own steps across the
#    output times, the states there interpolated; A02_INTERP=0 skips it).
# 3. `mechc bench` on Andrews, the double pendulum, A02 and two spatial
#    files (heavy_top, slider_crank_spatial_torque): ns per call of
#    mass, force, m+q (both) and eom for generic, jit and aot, and the
#    speed-ups generated / generic against the targets (3x jit,
#    5x aot).
# POSIX sh and awk only.
set -u
mechc=${1:-build/mechc}
repeat=${REPEAT:-5}
a02_n=${A02_N:-40}
a02_t1=${A02_T1:-20}
a02_rtol=${A02_RTOL:-1e-6}
a02_dense=${A02_DENSE:-0}
a02_interp=${A02_INTERP:-1}
if [ ! -x "$mechc" ]; then
    echo "usage: sh bench/dynamics.sh MECHC   ('$mechc' is not an executable; run make first)" >&2
    exit 2
fi
root=$(cd "$(dirname "$0")/.." && pwd)
tmp=$(mktemp -d "${TMPDIR:-/tmp}/mechc_dynbench.XXXXXX") || exit 2
trap 'rm -rf "$tmp"' EXIT

# cpu_ms: the integration's CPU milliseconds in a `sim --stats` stderr ($1)
cpu_ms() { sed -n 's/.* ms of integration (\([0-9.e+-]*\) ms CPU).*/\1/p' "$1"; }

echo "== Andrews' squeezing mechanism to t = 0.03 (jit, rk8pd, --rtol 1e-8 --atol 1e-8)"
i=0
: > "$tmp/andrews.ms"
while [ "$i" -lt "$repeat" ]; do
    "$mechc" sim "$root/examples/andrews.mech" --t1 0.03 --steps 1 --rtol 1e-8 --atol 1e-8 \
        --stats --csv "$tmp/andrews.csv" 2> "$tmp/andrews.err" || { cat "$tmp/andrews.err" >&2; exit 1; }
    cpu_ms "$tmp/andrews.err" >> "$tmp/andrews.ms"
    i=$((i + 1))
done
sort -g "$tmp/andrews.ms" | awk '{ v[NR] = $1 } END {
    printf "integration CPU: best %.3f ms, median %.3f ms of %d runs (target: under 20 ms)\n",
           v[1], v[int((NR + 1) / 2)], NR }'
awk -F, 'NR == 3 { d = ($2 - 15.81077119629904) / 15.81077119629904; if (d < 0) d = -d
                   printf "beta(0.03) = %s, relative error against the Test Set %.2g\n", $2, d }' \
    "$tmp/andrews.csv"
grep 'integrator steps' "$tmp/andrews.err" | sed 's/^mechc sim: stats: /  /'

echo
echo "== IFToMM A02, N = $a02_n, ${a02_t1} s (jit, rk8pd, --rtol $a02_rtol --atol $a02_rtol)"
sh "$root/examples/a02_four_bar.sh" "$a02_n" "$tmp/a02.mech"
steps=$(awk -v t="$a02_t1" 'BEGIN { s = int(t * 20 + 0.5); print s < 1 ? 1 : s }')
qd=$(sh "$root/examples/a02_four_bar.sh" --qd "$a02_n")
# a02_sim LINEAR [OPTION]: one simulation, its stats in a02.err, states in a02.csv
a02_sim() {
    "$mechc" sim "$tmp/a02.mech" --linear "$1" --t1 "$a02_t1" --steps "$steps" --rtol "$a02_rtol" \
        --atol "$a02_rtol" --qd "$qd" --stats --csv "$tmp/a02.csv" ${2:+"$2"} 2> "$tmp/a02.err" \
        || { tail -3 "$tmp/a02.err" >&2; exit 1; }
}
# a02_timed [OPTION]: REPEAT simulations on the sparse path, best and median CPU
a02_timed() {
    i=0
    : > "$tmp/a02.ms"
    while [ "$i" -lt "$repeat" ]; do
        a02_sim auto ${1:+"$1"}
        cpu_ms "$tmp/a02.err" >> "$tmp/a02.ms"
        i=$((i + 1))
    done
    sort -g "$tmp/a02.ms" | awk -v o="${1:-}" '{ v[NR] = $1 } END {
        printf "%sintegration CPU: best %.1f ms, median %.1f ms of %d runs (target: under 100 ms for 20 s at N = 40)\n",
               o == "" ? "" : o ": ", v[1], v[int((NR + 1) / 2)], NR }'
    grep 'integrator steps\|dependent row\|augmented matrix' "$tmp/a02.err" | sed 's/^mechc sim: stats: /  /'
    a02_check
}
if [ "$a02_dense" = 1 ]; then
    a02_sim dense
    printf 'dense path (null-space method, QR/SVD projections): integration CPU %s ms\n' \
        "$(cpu_ms "$tmp/a02.err")"
fi
# a02_check: B0 in a02.csv against the exact solution, and the energy
a02_check() {
printf 'B0 against the exact solution: largest error %s over %d states (benchmark: 1e-3)\n' \
    "$(sh "$root/examples/a02_four_bar.sh" --error "$a02_n" "$tmp/a02.csv")" \
    "$(($(wc -l < "$tmp/a02.csv") - 1))"
awk -F, -v n="$a02_n" '
    BEGIN { ii = (n + 1) / 3 + n; k = 9.81 * ((n + 1) / 2 + n) }
    NR == 1 { for (i = 1; i <= NF; i++) c[$i] = i; next }
    {
        en = 0
        for (i = 0; i <= n; i++) en += body("rod" i)
        for (i = 0; i < n; i++) en += body("cpl" i)
        d = en - (ii / 2 + k); if (d < 0) d = -d; if (d > we) we = d
    }
    function body(b) {
        return 0.5 * ($(c["d(" b ".x)"])^2 + $(c["d(" b ".y)"])^2) + 0.5 / 12 * $(c["d(" b ".phi)"])^2 \
               + 9.81 * $(c[b ".y"])
    }
    END { printf "energy: largest |E - E0| %.3g J of E0 = %.12g J\n", we, ii / 2 + k }' "$tmp/a02.csv"
}
a02_timed
[ "$a02_interp" = 1 ] && a02_timed --interpolate

echo
echo "== dynamics kernels per call (mechc bench; target: generated / generic >= 3x jit, 5x aot)"
for f in "$root/examples/andrews.mech" "$root/examples/double_pendulum.mech" "$tmp/a02.mech" \
         "$root/examples/heavy_top.mech" "$root/examples/slider_crank_spatial_torque.mech"; do
    "$mechc" bench "$f" --repeat "$repeat" > "$tmp/bench.txt" 2> "$tmp/bench.err" \
        || { cat "$tmp/bench.err" >&2; exit 1; }
    sed -n '1p' "$tmp/bench.txt"
    awk 'NR == 3 || /^(mass|force|m\+q|eom) / { print "  " $0 }' "$tmp/bench.txt"
done
