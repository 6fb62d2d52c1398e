#!/bin/sh
# error.sh - the error of a CSV (mechc sim's, or mujoco_sim's with the same column names) against a benchmark's exact or reference solution.
#
#   sh bench/mujoco/error.sh a01 CSV       P1's largest error (x or y) over the rows
#                                          against the exact solution (Jacobi elliptic
#                                          functions; examples/a01_pendulum.mech)
#   sh bench/mujoco/error.sh a02 N CSV     B0's largest error of position and velocity
#                                          (examples/a02_four_bar.sh --error N CSV)
#   sh bench/mujoco/error.sh andrews CSV   beta's relative error at the last row against
#                                          the Test Set's value at t = 0.03
#                                          (examples/andrews.mech, bench/dynamics.sh)
# POSIX sh and awk only.
set -u
root=$(cd "$(dirname "$0")/../.." && pwd)
case ${1:-} in
a01)
    [ $# -eq 2 ] || { echo "usage: sh $0 a01 CSV" >&2; exit 2; }
    # sin(phi/2) = k sn(K - w t | m), P1 = (2 k sn dn, 2 k^2 sn^2 - 1), k^2 = m = 1/2,
    # w = sqrt(9.81); sn and dn by the arithmetic-geometric mean (Abramowitz and
    # Stegun 16.4), the argument first reduced by the period 4 K.
    awk -F, '
    function asin(x) { return atan2(x, sqrt(1 - x * x)) }
    function elljac(u, m,    a, b, c, n, ph, i) {
        a[0] = 1; b = sqrt(1 - m); c[0] = sqrt(m); n = 0
        while ((c[n] < 0 ? -c[n] : c[n]) > 1e-15 && n < 20) {
            a[n + 1] = (a[n] + b) / 2; c[n + 1] = (a[n] - b) / 2; b = sqrt(a[n] * b); n++
        }
        ph = 2 ^ n * a[n] * u
        for (i = n; i > 0; i--) { ph = (ph + asin(c[i] / a[i] * sin(ph))) / 2 }
        sn = sin(ph); dn = sqrt(1 - m * sn * sn)   # dn > 0 for m < 1
    }
    BEGIN { kk = 1.8540746773013719184; m = 0.5; k = sqrt(m); w = sqrt(9.81); per = 4 * kk }
    NR == 1 { for (i = 1; i <= NF; i++) c[$i] = i; next }
    {
        u = kk - w * $1; u -= per * int(u / per); elljac(u, m)
        ex = $(c["P1.x"]) - 2 * k * sn * dn; ey = $(c["P1.y"]) - (2 * m * sn * sn - 1)
        if (ex < 0) ex = -ex; if (ey < 0) ey = -ey
        if (ex > worst) worst = ex; if (ey > worst) worst = ey
    }
    END { printf "%.3g\n", worst }' "$2" ;;
a02)
    [ $# -eq 3 ] || { echo "usage: sh $0 a02 N CSV" >&2; exit 2; }
    sh "$root/examples/a02_four_bar.sh" --error "$2" "$3" ;;
andrews)
    [ $# -eq 2 ] || { echo "usage: sh $0 andrews CSV" >&2; exit 2; }
    awk -F, 'NR == 1 { for (i = 1; i <= NF; i++) c[$i] = i; next }
             { b = $(c["beta"]) }
             END { d = (b - 15.81077119629904) / 15.81077119629904; if (d < 0) d = -d; printf "%.3g\n", d }' "$2" ;;
*)
    echo "usage: sh $0 a01 CSV | a02 N CSV | andrews CSV" >&2; exit 2 ;;
esac
