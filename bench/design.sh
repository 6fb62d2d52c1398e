#!/bin/sh
# bench/design.sh MECHC - design parameters: what sensitivities and fits cost.
#
#   sh bench/design.sh build/mechc          (part of `make bench`)
#
# 1. run --sens against the plain run: CPU time per state of the
#    sensitivities to every design parameter (run --stats) beside the CPU
#    time of the run's own step, 20000 steps, and the ratio (1 + sens/step)
#    with the budget 1 + 0.3 k for k parameters.
# 2. fit: CPU time of the three synthesis and calibration examples (fit's
#    own report, compilation excluded), median of 5.
# 3. the sensitivity kernels generated (jit, aot) against the generic
#    engine's (mechc bench, Stewart calibration).
# 4. bench/fit_monte_carlo.sh: fit's standard errors against the spread of
#    100 noisy fits.
# POSIX sh and awk only.

set -u
mechc=${1:-build/mechc}
printf 'run --sens, 20000 steps (CPU time per state, run --stats)\n'
printf '%-22s %4s %12s %12s %8s %8s\n' mechanism k "step ns" "sens ns" ratio budget
for f in freudenstein coupler_synthesis stewart_calibration; do
    "$mechc" run "examples/$f.mech" --t0 0.4 --t1 2 --steps 20000 --sens --csv /dev/null \
        --stats 2>&1 | awk -v f="$f" '
        /CPU time in the steps/ { for (i = 1; i <= NF; i++) if ($i == "ns") step = $(i - 1) }
        /sensitivities to/ { k = $6; for (i = 1; i <= NF; i++) if ($i == "ns") sens = $(i - 1) }
        END { printf "%-22s %4d %12d %12d %8.2f %8.2f\n", f, k, step, sens, 1 + sens / step, 1 + 0.3 * k }'
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
