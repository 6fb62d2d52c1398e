#!/bin/sh
# train.sh - writes a tractor pulling N trailers on knife edges (the
# on-axle N-trailer system, nonholonomic) as a .mech file.
#
#   sh examples/train.sh N [OUTFILE]        (stdout when OUTFILE is absent)
#
# The tractor drives round a circle (forward speed v, turn rate w: velocity
# drivers); trailer i's drawbar is pinned to the axle of the body before
# it, and every axle is a knife edge. NQ = 3 (N + 1), NH = 2 N (the pins),
# NV = N + 3 (the knife edges and the two drivers): fully driven, and run
# integrates the positions. N = 300 gives 903 coordinates, beyond --linear
# auto's 100: KLU solves the velocities and SuiteSparseQR projects.
# POSIX sh and awk only.

. "$(dirname "$0")/size_arg.sh"
size_arg 3 3 "$@"      # NQ = 3N + 3

gen() {
    awk -v n="$n" 'BEGIN {
        printf "# train_%d.mech - a tractor and %d trailer%s on knife edges, written by\n", n, n, n == 1 ? "" : "s"
        printf "# examples/train.sh %d.\n", n
        printf "#\n"
        printf "# What:    the tractor `car` has its reference point on its rear axle, a\n"
        printf "#          knife edge there along its x axis, and velocity drivers for its\n"
        printf "#          forward speed v and turn rate w: its axle runs on the circle of\n"
        printf "#          radius v/w = 4 about the origin. Trailer i (tr1..tr%d) has its\n", n
        printf "#          reference point on its axle (a knife edge along its x axis) and\n"
        printf "#          its drawbar end at local (L, 0), pinned to the axle of the body\n"
        printf "#          before it (on-axle hitching). At t = 0 the train heads +y at\n"
        printf "#          x = 4, the trailers in a straight line behind the tractor\n"
        printf "#          (axle i at (4, -i L)).\n"
        printf "# Coords:  x, y, phi of car, tr1..tr%d                   NQ = 3 (N + 1) = %d\n", n, 3 * (n + 1)
        printf "# Rows:    hitch1..hitch%d (revolute): 2 N = %d holonomic; blade0..blade%d\n", n, 2 * n, n
        printf "#          (knife), fwd, turn (velocity drivers): N + 3 = %d velocity-level\n", n + 3
        printf "# DOF:     0: fully driven; `mechc run` integrates the positions.\n"
        printf "#\n"
        printf "# Reference: the N-trailer equations (on-axle hitching), with theta_i the\n"
        printf "# heading of body i and v_i the speed of its axle:\n"
        printf "#   d(theta_i)/dt = (v_{i-1} / L) sin(theta_{i-1} - theta_i),\n"
        printf "#   v_i = v_{i-1} cos(theta_{i-1} - theta_i),\n"
        printf "# which tests/run_cli.sh integrates independently (awk, RK4).\n"
        printf "# Every trailer tends to a circle of radius sqrt(R_{i-1}^2 - L^2).\n"
        printf "\n"
        printf "mechanism train_%d\n\n", n
        printf "param v = 2          # tractor speed\n"
        printf "param w = 0.5        # tractor turn rate (circle of radius v/w = 4)\n"
        printf "param L = 1          # drawbar: axle to hitch\n\n"
        printf "body car x = 4 y = 0 phi = pi/2\n"
        printf "knife  blade0: car axis(1, 0)\n"
        printf "driver fwd:    der(car.x)*cos(car.phi) + der(car.y)*sin(car.phi) = v\n"
        printf "driver turn:   der(car.phi) = w\n"
        prev = "car"
        for (i = 1; i <= n; i++) {
            printf "body tr%d x = 4 y = %d phi = pi/2\n", i, -i
            printf "revolute hitch%d: %s(0, 0) tr%d(L, 0)\n", i, prev, i
            printf "knife  blade%d: tr%d axis(1, 0)\n", i, i
            prev = "tr" i
        }
    }'
}

size_out
