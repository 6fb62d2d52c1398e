#!/bin/sh
# chain_spatial.sh - writes a spatial chain of N bodies (N - 1 closed loops) as a .mech file, for scaling tests and benchmarks.
#
#   sh examples/chain_spatial.sh N [OUTFILE]     (stdout when OUTFILE is absent)
#
# The spatial counterpart of chain.sh, counted in bodies. N unit rods
# rod0..rod(N-1) stand on the ground at (i, 0, 0), each on a revolute about
# the global y axis (5 rows); the tops of consecutive rods keep their unit
# distance (a `distance` row: a coupler with a ball joint at each end,
# written as what it does, as in rssr.mech). Each loop (ground, rod i,
# coupler, rod i+1) is a parallelogram, a unit square in the plane y = 0 at
# t = 0, and the first rod's angle is driven, angle(g0) = amp sin(omega t),
# so every rod turns with it:
#   NQ = 7N coordinates (x y z e0 e1 e2 e3 of each rod),
#   rows N .norm + 5N revolute + (N - 1) distance + 1 driver = 7N = NQ.
# N = 100 gives 700 coordinates and 700 rows. POSIX sh and awk only.

. "$(dirname "$0")/size_arg.sh"
size_arg 7 0 "$@"      # NQ = 7N

gen() {
    awk -v n="$n" 'BEGIN {
        nq = 7 * n
        printf "# chain_spatial_%d.mech - a spatial chain of %d bodies, written by examples/chain_spatial.sh %d.\n", n, n, n
        printf "#\n"
        printf "# What:    N = %d unit rods rod0..rod%d on revolutes g0..g%d about the\n", n, n - 1, n - 1
        printf "#          global y axis through (i, 0, 0), the rod along its local z;\n"
        printf "#          c_i keeps the tops of rod i and rod i+1 at unit distance\n"
        printf "#          (a ball-ended coupler); angle(g0) = amp sin(omega t).\n"
        printf "# Coords:  x y z e0 e1 e2 e3 of rod0 .. rod%d            NQ = 7N = %d\n", n - 1, nq
        printf "# Rows:    .norm N = %d; g_i 5N = %d; c_i N - 1 = %d; drive 1\n", n, 5 * n, n - 1
        printf "#                                              NH = 7N = %d, NV = 0\n", nq
        printf "# DOF:     %d - %d - 0 = 0: fully driven.\n", nq, nq
        printf "#\n"
        printf "# Initial values: the exact configuration at t = 0, rods upright.\n"
        printf "# Closed form: every rod turns by a = amp sin(omega t) about y, its top\n"
        printf "# at (i + sin(a), 0, cos(a)); the swing of +-amp = 0.5 rad keeps the\n"
        printf "# loops away from the flat (change-point) configurations at a = +-pi/2.\n"
        printf "\n"
        printf "mechanism chain_spatial_%d\n", n
        printf "spatial\n\n"
        printf "param amp   = 0.5\n"
        printf "param omega = 2*pi\n\n"
        printf "body rod0 x = 0 y = 0 z = 0\n"
        printf "revolute g0: ground(0, 0, 0) rod0(0, 0, 0) axis(0, 1, 0)\n"
        printf "driver drive: angle(g0) = amp*sin(omega*t)\n"
        for (i = 1; i < n; i++) {
            printf "body rod%d x = %d y = 0 z = 0\n", i, i
            printf "revolute g%d: ground(%d, 0, 0) rod%d(0, 0, 0) axis(0, 1, 0)\n", i, i, i
            printf "distance c%d: rod%d(0, 0, 1) rod%d(0, 0, 1) length = 1\n", i - 1, i - 1, i
        }
    }'
}

size_out
