#!/bin/sh
# bench/design.sh MECHC - design parameters: what sensitivities and fits cost.
#
#   sh bench/design.sh build/mechc          (part of `make bench`)
#
# 1. run --sens against the plain run: the CPU time per state of the
#    sensitivities to every design parameter beside the CPU time of the
#    run's own step, both from one run (run --stats, 20000 steps), each
#    less what an empty span between its two clock() readings reads (run
#    --stats measures it after the run: clock() is a system call of about
#    1.6 us on the loaded virtual machine these figures come from, twice
#    a four-bar's step), and the ratio 1 + sens/step against the issue's
#    budget 1 + 0.3 k for k parameters; median of 5 runs.
# 2. fit: CPU time of the three synthesis and calibration examples (fit's
#    own report, compilation excluded), median of 5.
# 3. the sensitivity kernels generated (jit, aot) against the generic
#    engine's (mechc bench, Stewart calibration).
# 4. bench/fit_monte_carlo.sh: fit's standard errors against the spread of
#    100 noisy fits.
# POSIX sh and awk only.

set -u
mechc=${1:-build/mechc}
printf 'run --sens, 20000 steps (CPU time per state less the clock() span, run --stats; median of 5)\n'
printf '%-22s %4s %12s %12s %8s %8s\n' mechanism k "step ns" "sens ns" ratio budget
for f in freudenstein coupler_synthesis stewart_calibration; do
    i=0
    while [ $i -lt 5 ]; do
        "$mechc" run "examples/$f.mech" --t0 0.4 --t1 2 --steps 20000 --sens --csv /dev/null \
            --stats 2>&1 | awk '
            /sensitivities to/ { k = $6 }
            /an empty clock\(\) span reads/ {
                for (i = 1; i <= NF; i++) {
                    if ($i == "sensitivities") sens = $(i + 1)
                    if ($i == "steps") step = $(i + 1)
                }
            }
            END { printf "%d %d %d %.4f\n", k, step, sens, 1 + sens / step }'
        i=$((i + 1))
    done | sort -k4 -g | awk -v f="$f" 'NR == 3 {
        printf "%-22s %4d %12d %12d %8.2f %8.2f\n", f, $1, $2, $3, $4, 1 + 0.3 * $1 }'
done
printf '\nfit (CPU ms of the fit, median of 5; mechc fit examples/X.mech --data examples/X.csv)\n'
for f in freudenstein coupler_synthesis stewart_calibration; do
    i=0
    while [ $i -lt 5 ]; do
        "$mechc" fit "examples/$f.mech" --data "examples/$f.csv" --json | sed -n 's/.*"cpu_seconds": \([^,}]*\).*/\1/p'
        i=$((i + 1))
    done | sort -g | awk -v f="$f" '{ v[NR] = $1 } END { printf "  %-22s %8.2f ms\n", f, 1e3 * v[3] }'
done
printf '\nsensitivity kernels, Stewart calibration (ns per call; mechc bench):\n'
"$mechc" bench examples/stewart_calibration.mech --repeat 5 2>/dev/null | awk '
    /^ +generic/ || /^(phi_p|sens_v|sens_g|sens_y) / { print "  " $0 }'
printf '\n'
sh bench/fit_monte_carlo.sh "$mechc" 100
