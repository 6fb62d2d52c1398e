#!/bin/sh
# chain.sh - writes a chain of N four-bar loops as a .mech file, for scaling
# tests and benchmarks.
#
#   sh examples/chain.sh N [OUTFILE]        (stdout when OUTFILE is absent)
#
# N + 1 unit rods stand on ground pivots (i, 0), i = 0..N; N unit couplers
# join the tops of consecutive rods. Every loop (ground, rod i, coupler i,
# rod i + 1) is a parallelogram (here a unit square), and the first rod's
# angle is driven, so the chain is fully driven:
#   NQ = 3 (2N + 1) coordinates, rows 2 (N + 1) + 4 N + 1 = 6N + 3 = NQ.
# N = 1000 gives 6003 coordinates and 6003 rows.
# POSIX sh and awk only.

. "$(dirname "$0")/size_arg.sh"
size_arg 6 3 "$@"      # NQ = 6N + 3

gen() {
    awk -v n="$n" 'BEGIN {
        nq = 3 * (2 * n + 1)
        loops = (n == 1) ? "loop" : "loops"
        printf "# chain_%d.mech - a chain of %d four-bar %s, written by examples/chain.sh %d.\n", n, n, loops, n
        printf "#\n"
        printf "# What:    N = %d; N + 1 unit rods rod0..rod%d pivoted on the ground at\n", n, n
        printf "#          (i, 0), and N unit couplers cpl0..cpl%d; coupler i joins the top of\n", n - 1
        printf "#          rod i to the top of rod i+1, so each loop is a parallelogram\n"
        printf "#          (a unit square at t = 0).\n"
        printf "#          Body frames are centred, local x along the link, ends at (-0.5, 0)\n"
        printf "#          and (0.5, 0); a rod goes from its ground pivot (-0.5, 0) to its\n"
        printf "#          top (0.5, 0). The first rod swings: rod0.phi = pi/2 + amp sin(omega t).\n"
        printf "# Coords:  x, y, phi of each body in declaration order: rod0, then cpl i\n"
        printf "#          and rod i+1 for i = 0..N-1                  NQ = 3 (2N + 1) = %d\n", nq
        printf "# Rows:    g0..g%d (ground pivots, revolute): 2 (N + 1) = %d;\n", n, 2 * (n + 1)
        printf "#          a_i, b_i (coupler ends, revolute): 4N = %d; drive (driver): 1\n", 4 * n
        printf "#          in statement order (g0, drive, then per loop g, a, b)\n"
        printf "#                                                     NH = 6N + 3 = %d, NV = 0\n", 6 * n + 3
        printf "# DOF:     %d - %d - 0 = 0: fully driven.\n", nq, 6 * n + 3
        printf "#\n"
        printf "# Initial values: the exact configuration at t = 0, rods vertical\n"
        printf "# (rod i centred at (i, 0.5), phi = pi/2), couplers horizontal at y = 1\n"
        printf "# (coupler i centred at (i + 0.5, 1), phi = 0).\n"
        printf "# Closed form: every rod has the angle of rod0 and every coupler stays\n"
        printf "# horizontal: rod i centre = (i + 0.5 cos(phi), 0.5 sin(phi)),\n"
        printf "# coupler i centre = (i + 0.5 + cos(phi), sin(phi)), phi = rod0.phi.\n"
        printf "# The swing of +-amp = 0.5 rad keeps the loops away from the flat\n"
        printf "# (change-point) configurations at phi = 0 and pi.\n"
        printf "\n"
        printf "mechanism chain_%d\n\n", n
        printf "param amp   = 0.5\n"
        printf "param omega = 2*pi\n\n"
        printf "body rod0 x = 0 y = 0.5 phi = pi/2\n"
        printf "revolute g0: ground(0, 0) rod0(-0.5, 0)\n"
        printf "driver drive: rod0.phi = pi/2 + amp*sin(omega*t)\n"
        for (i = 0; i < n; i++) {
            printf "body cpl%d x = %d.5 y = 1 phi = 0\n", i, i
            printf "body rod%d x = %d y = 0.5 phi = pi/2\n", i + 1, i + 1
            printf "revolute g%d: ground(%d, 0) rod%d(-0.5, 0)\n", i + 1, i + 1, i + 1
            printf "revolute a%d: rod%d(0.5, 0) cpl%d(-0.5, 0)\n", i, i, i
            printf "revolute b%d: cpl%d(0.5, 0) rod%d(0.5, 0)\n", i, i, i + 1
        }
    }'
}

size_out
