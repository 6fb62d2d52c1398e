#!/bin/sh
# scissor.sh - writes a scissor lift of N stages as a .mech file.
#
#   sh examples/scissor.sh N [OUTFILE]      (stdout when OUTFILE is absent)
#
# Each stage is two unit links crossed and pinned at their middles; the
# stages are pinned end to end, the bottom stage stands on a ground pivot
# and a floor slider, and the platform rides on the top pair of ends. The
# angle of the first link is driven, so the platform height has a closed
# form: N sin(theta(t)). NQ = 6N + 3 coordinates, as many rows.
# POSIX sh and awk only.

. "$(dirname "$0")/size_arg.sh"
size_arg 6 3 "$@"      # NQ = 6N + 3

gen() {
    awk -v n="$n" 'BEGIN {
        th = 0.6; c = cos(th); s = sin(th)
        printf "# scissor_%d.mech - a scissor lift of %d stage%s, written by examples/scissor.sh %d.\n", n, n, n == 1 ? "" : "s", n
        printf "#\n"
        printf "# What:    stage k (k = 1..N) is two unit links a<k> and b<k> crossed at\n"
        printf "#          their middles (pin m<k>). a<k> runs from bottom-left to top-right\n"
        printf "#          (phi = theta), b<k> from bottom-right to top-left (phi = pi -\n"
        printf "#          theta); body frames centred, local x along the link, ends at\n"
        printf "#          (-0.5, 0) (bottom) and (0.5, 0) (top). Between stages the top of\n"
        printf "#          a<k> is pinned to the bottom of b<k+1> (r<k>) and the top of b<k>\n"
        printf "#          to the bottom of a<k+1> (l<k>). a1 stands on the ground pivot\n"
        printf "#          (0, 0) (g), b1 on the floor (slider s: its bottom on y = 0). The\n"
        printf "#          platform `deck` (frame origin at its left end) is pinned to the\n"
        printf "#          top of b<N> (pl) and carries the top of a<N> on its x axis (pr).\n"
        printf "#          Driven: a1.phi = theta(t) = 0.6 + 0.4 sin(2 pi t) (0.2 .. 1.0 rad).\n"
        printf "# Coords:  x, y, phi of a1, b1, .., a<N>, b<N>, deck   NQ = 6N + 3 = %d\n", 6 * n + 3
        printf "# Rows:    g (2), s (1), m<k> (2 N), r<k> and l<k> (4 (N - 1)), pl (2),\n"
        printf "#          pr (1), lift (1)                           NH = 6N + 3 = %d, NV = 0\n", 6 * n + 3
        printf "# DOF:     0: fully driven.\n"
        printf "#\n"
        printf "# Closed form: every left end is at x = 0 and every right end at\n"
        printf "# x = cos(theta); stage k spans heights (k - 1) sin(theta) .. k sin(theta).\n"
        printf "#   deck.x = 0, deck.y = N sin(theta), deck.phi = 0,\n"
        printf "#   a<k> centred at (cos(theta)/2, (k - 1/2) sin(theta)), phi = theta,\n"
        printf "#   b<k> the same centre, phi = pi - theta.\n"
        printf "# The platform rises from N sin(0.2) = %.4f to N sin(1.0) = %.4f.\n", n * sin(0.2), n * sin(1.0)
        printf "# Initial values: the exact configuration at t = 0 (theta = 0.6).\n"
        printf "\n"
        printf "mechanism scissor_%d\n\n", n
        printf "param th0 = 0.6\n"
        printf "param amp = 0.4\n"
        printf "param omega = 2*pi\n\n"
        for (k = 1; k <= n; k++) {
            y = (k - 0.5) * s
            printf "body a%d x = %.17g y = %.17g phi = th0\n", k, c / 2, y
            printf "body b%d x = %.17g y = %.17g phi = pi - th0\n", k, c / 2, y
            if (k == 1) {
                printf "revolute g: ground(0, 0) a1(-0.5, 0)\n"
                printf "pointline s: ground(0, 0) b1(-0.5, 0) axis(1, 0)\n"
                printf "driver lift: a1.phi = th0 + amp*sin(omega*t)\n"
            } else {
                printf "revolute r%d: a%d(0.5, 0) b%d(-0.5, 0)\n", k - 1, k - 1, k
                printf "revolute l%d: b%d(0.5, 0) a%d(-0.5, 0)\n", k - 1, k - 1, k
            }
            printf "revolute m%d: a%d(0, 0) b%d(0, 0)\n", k, k, k
        }
        printf "body deck x = 0 y = %.17g phi = 0\n", n * s
        printf "revolute pl: b%d(0.5, 0) deck(0, 0)\n", n
        printf "pointline pr: deck(0, 0) a%d(0.5, 0) axis(1, 0)\n", n
    }'
}

size_out
