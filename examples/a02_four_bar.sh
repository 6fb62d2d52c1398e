#!/bin/sh
# a02_four_bar.sh - writes IFToMM / UDC benchmark A02 (N four-bar mechanism) as a .mech file with masses, or its initial velocities.
#
#   sh examples/a02_four_bar.sh N [OUTFILE]   the .mech (stdout without OUTFILE)
#   sh examples/a02_four_bar.sh --qd N        the --qd list for `mechc sim`
#   sh examples/a02_four_bar.sh --error N CSV the largest error of B0's position
#                                             and velocity in sim's CSV against
#                                             the exact solution (below; RK4 at 1e-4 s)
#
#   sh examples/a02_four_bar.sh 40 a02.mech
#   mechc sim a02.mech --t1 20 --steps 400 --qd "$(sh examples/a02_four_bar.sh --qd 40)"
#
# Benchmark definition (M. Gonzalez, D. Dopico, U. Lugris, J. Cuadrado,
# Univ. of A Coruna, 2005; Multibody System Dynamics 16 (2006) 179-190;
# http://lim.ii.udc.es/mbsbenchmark/dist/A02/A02_specification.xml):
# "2N+1 links of 1 m length with a uniformly distributed mass of 1 kg",
# gravity 9.81 N/kg along -y, N = 40, a dynamic simulation of 20 s, the
# x-velocity of B0 (the top of the first rod) 1 m/s at the start; reference:
# the position and velocity of B0, allowed errors 1e-1 / 1e-3 with 400
# output steps. Initial position (the spec's figure, as reproduced in
# RehabEngGroup/MBSbenchmarksInOpenSim src/A02-NFourBarMechanism): rods
# vertical, couplers horizontal: the geometry of examples/chain.sh, without
# its driver. Whenever the rods lie flat the Jacobian loses N ranks
# (1 -> N + 1 DOF); the first time at t = 0.72158102482565682761 s.
#
# The benchmark's own reference data file (A02_solution_data.txt) was not
# available to us: the reference is the EXACT solution of the published
# definition. Every loop stays a parallelogram, so all rods share one angle
# th (from +x) and the couplers translate; with m = L = 1
#   I th'' = -K cos th,  I = (N+1)/3 + N,  K = g ((N+1)/2 + N),
#   th(0) = pi/2, th'(0) = -1, B0 = (cos th, sin th),
# energy (zero at y = 0) E0 = I/2 + K (N = 40: 620.338333333333 J).
# N = 40, t = 20: B0 = (0.41090115376284, 0.91167990097203),
# B0' = (1.5667853719089, -0.70616223559353).
# Initial velocities: every rod phi' = -1, centre (0.5, 0); every coupler
# phi' = 0, centre (1, 0) (the --qd list).
# Coords: x, y, phi of rod0, then of cpl i and rod i+1: NQ = 3 (2N + 1);
# rows 2 (N + 1) + 4 N = NQ - 1: 1 DOF, free. N is bounded as in the other
# generator scripts (examples/size_arg.sh). POSIX sh and awk only.

. "$(dirname "$0")/size_arg.sh"

mode=gen
case ${1:-} in
    --qd | --error)
        mode=${1#--}
        shift
        if [ $# -ne "$([ "$mode" = qd ] && echo 1 || echo 2)" ]; then
            echo "usage: sh $0 N [OUTFILE] | --qd N | --error N CSV   (N a positive integer)" >&2
            exit 2
        fi ;;
esac
if [ "$mode" = gen ]; then
    size_arg 6 3 "$@"  # NQ = 6N + 3
else
    size_arg 6 3 "$1"
fi

# The exact solution at each row's t (I th'' = -K cos th by RK4, h = 1e-4,
# to 1e-12), B0's position and velocity against the CSV's columns.
if [ "$mode" = error ]; then
    awk -F, -v n="$n" '
    BEGIN { pi = atan2(0, -1); ii = (n + 1) / 3 + n; k = 9.81 * ((n + 1) / 2 + n)
            th = pi / 2; w = -1; tt = 0; h = 1e-4 }
    function acc(a) { return -k * cos(a) / ii }
    NR == 1 { for (i = 1; i <= NF; i++) c[$i] = i
              split("B0.x B0.y d(B0.x) d(B0.y)", need, " ")
              for (j = 1; j <= 4; j++) if (!(need[j] in c)) {
                  printf "%s: no column %s: give the CSV of mechc sim on the file this script writes\n", FILENAME, need[j] > "/dev/stderr"
                  bad = 1; exit 2
              }
              next }
    { rows++
        while (tt < $1 - 1e-12) {
            hh = ($1 - tt < h) ? $1 - tt : h
            k1 = w; l1 = acc(th); k2 = w + hh / 2 * l1; l2 = acc(th + hh / 2 * k1)
            k3 = w + hh / 2 * l2; l3 = acc(th + hh / 2 * k2); k4 = w + hh * l3; l4 = acc(th + hh * k3)
            th += hh / 6 * (k1 + 2 * k2 + 2 * k3 + k4); w += hh / 6 * (l1 + 2 * l2 + 2 * l3 + l4); tt += hh
        }
        e[1] = $(c["B0.x"]) - cos(th); e[2] = $(c["B0.y"]) - sin(th)
        e[3] = $(c["d(B0.x)"]) + sin(th) * w; e[4] = $(c["d(B0.y)"]) - cos(th) * w
        for (j = 1; j <= 4; j++) { d = e[j] < 0 ? -e[j] : e[j]; if (d > worst) worst = d }
    }
    END { if (bad) exit 2
          if (!rows) { printf "%s: no data row\n", FILENAME > "/dev/stderr"; exit 2 }
          printf "%.3g\n", worst }' "$2" || exit 2
    exit
fi

if [ "$mode" = qd ]; then
    # one piece at a time: growing one string is quadratic (N = 33332: 18 s)
    awk -v n="$n" 'BEGIN { printf "0.5,0,-1"; for (i = 0; i < n; i++) printf ",1,0,0,0.5,0,-1"; print "" }'
    exit 0
fi

gen() {
    awk -v n="$n" 'BEGIN {
        nq = 3 * (2 * n + 1); nh = 2 * (n + 1) + 4 * n
        ii = (n + 1) / 3 + n; k = 9.81 * ((n + 1) / 2 + n)
        printf "# a02_four_bar.mech - IFToMM / UDC benchmark A02, the N four-bar mechanism, N = %d (sh examples/a02_four_bar.sh %d).\n", n, n
        printf "#\n"
        printf "# 2N+1 unit links of 1 kg (J = 1/12 about the centre), gravity 9.81 along -y;\n"
        printf "# rods vertical, couplers horizontal; simulate with the initial velocities of\n"
        printf "# sh examples/a02_four_bar.sh --qd %d. Reference: the exact solution of the\n", n
        printf "# benchmark definition (the benchmark data file was not available; see the\n"
        printf "# script): I th'"'"''"'"' = -K cos th, I = %.15g, K = %.15g, th(0) = pi/2,\n", ii, k
        printf "# th'"'"'(0) = -1, B0 = (cos th, sin th), energy I/2 + K = %.15g J.\n", ii / 2 + k
        printf "# Coords:  x, y, phi of rod0, then cpl i and rod i+1, i = 0..N-1    NQ = %d\n", nq
        printf "# Rows:    g0..g%d (ground pivots), a_i, b_i (coupler ends)         NH = %d\n", n, nh
        printf "# DOF:     1, free (N + 1 where the rods lie flat).\n"
        printf "\nmechanism a02_four_bar_%d\n\n", n
        printf "param g = 9.81\nparam mrod = 1\nparam Jrod = mrod/12           # a uniform 1 m link about its centre\n\n"
        printf "gravity (0, -g)\n\n"
        printf "body rod0 x = 0 y = 0.5 phi = pi/2\n"
        printf "revolute g0: ground(0, 0) rod0(-0.5, 0)\n"
        printf "mass rod0 m = mrod J = Jrod\n"
        for (i = 0; i < n; i++) {
            printf "body cpl%d x = %d.5 y = 1 phi = 0\n", i, i
            printf "body rod%d x = %d y = 0.5 phi = pi/2\n", i + 1, i + 1
            printf "revolute g%d: ground(%d, 0) rod%d(-0.5, 0)\n", i + 1, i + 1, i + 1
            printf "revolute a%d: rod%d(0.5, 0) cpl%d(-0.5, 0)\n", i, i, i
            printf "revolute b%d: cpl%d(0.5, 0) rod%d(0.5, 0)\n", i, i, i + 1
            printf "mass cpl%d m = mrod J = Jrod\n", i
            printf "mass rod%d m = mrod J = Jrod\n", i + 1
        }
        printf "\noutput B0: rod0(0.5, 0)\n"
    }'
}

size_out
