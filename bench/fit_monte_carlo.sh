#!/bin/sh
# bench/fit_monte_carlo.sh MECHC [DRAWS] - are fit's standard errors right?
#
#   sh bench/fit_monte_carlo.sh build/mechc 200
#
# Adds Gaussian noise (sigma = 1e-4 m, 0.1 mm) to the exact leg lengths of
# examples/stewart_calibration.csv, weights them 1/sigma^2, and fits the 36
# joint-centre coordinates from the nominal design, DRAWS times (default
# 100) with different noise. For every parameter it compares the spread of
# the estimates over the draws (their sample standard deviation) with the
# standard error fit reports (the mean over the draws): the ratio should be
# 1 within the sampling error of a standard deviation from DRAWS draws,
# about 1/sqrt(2 DRAWS) (0.07 for 100). Prints the ratios' smallest, median
# and largest, and the largest |mean estimate - true| in standard errors.
# POSIX sh and awk only (awk's srand/rand with a fixed seed per draw).

set -u
mechc=${1:-build/mechc}
draws=${2:-100}
mech=examples/stewart_calibration.mech
data=examples/stewart_calibration.csv
tmp=$(mktemp -d "${TMPDIR:-/tmp}/mechc-mc.XXXXXX") || exit 1
trap 'rm -rf "$tmp"' EXIT

# the exact fit: the true design, to compare the means with
"$mechc" fit "$mech" --data "$data" --json > "$tmp/exact.json" || exit 1
d=1
while [ "$d" -le "$draws" ]; do
    awk -F, -v seed="$d" -v sigma=1e-4 '
        BEGIN { srand(seed); OFS = "," }
        function gauss() { return sigma * sqrt(-2 * log(1 - rand())) * cos(6.283185307179586 * rand()) }
        /^#/ { next }
        NR == 2 || $1 == "t" { h = $0; for (i = 2; i <= NF; i++) h = h ",w(" $i ")"; print h; n = NF; next }
        { line = $1; for (i = 2; i <= n; i++) line = line "," sprintf("%.17g", $i + gauss());
          for (i = 2; i <= n; i++) line = line "," 1 / (sigma * sigma); print line }' \
        "$data" > "$tmp/noisy.csv"
    "$mechc" fit "$mech" --data "$tmp/noisy.csv" --json > "$tmp/fit.json" || exit 1
    sed -n 's/.*"name": "\([^"]*\)", "start": [^,]*, "estimate": \([^,]*\), "std_error": \([^}]*\)}.*/\1 \2 \3/p' \
        "$tmp/fit.json" >> "$tmp/estimates"
    d=$((d + 1))
done
sed -n 's/.*"name": "\([^"]*\)", "start": [^,]*, "estimate": \([^,]*\), "std_error": [^}]*}.*/\1 \2/p' \
    "$tmp/exact.json" > "$tmp/true"
awk -v draws="$draws" '
    FNR == NR { truth[$1] = $2; next }
    { n[$1]++; s[$1] += $2; ss[$1] += $2 * $2; se[$1] += $3 }
    END {
        k = 0
        for (p in n) {
            mean = s[p] / n[p]; sd = sqrt((ss[p] - n[p] * mean * mean) / (n[p] - 1))
            r[++k] = sd / (se[p] / n[p])
            bias = (mean - truth[p]) / (se[p] / n[p]) * sqrt(n[p])
            if (bias < 0) bias = -bias
            if (bias > worst) worst = bias
        }
        for (i = 1; i <= k; i++) for (j = i + 1; j <= k; j++) if (r[j] < r[i]) { x = r[i]; r[i] = r[j]; r[j] = x }
        printf "fit Monte Carlo, %d draws, %d parameters (examples/stewart_calibration.mech, sigma 0.1 mm):\n", draws, k
        printf "  spread of the estimates / reported standard error: min %.3f, median %.3f, max %.3f\n", r[1], r[int((k + 1) / 2)], r[k]
        printf "  (sampling error of a standard deviation from %d draws: %.3f)\n", draws, 1 / sqrt(2 * draws)
        printf "  largest |mean estimate - true value|: %.2f standard errors of the mean\n", worst
    }' "$tmp/true" "$tmp/estimates"
