#!/bin/sh
# a02.sh - writes IFToMM A02, the N four-bar mechanism (examples/a02_four_bar.sh N), as a MuJoCo model (MJCF) on stdout.
#
#   sh bench/mujoco/a02.sh N > a02.xml
#
# The same mechanism as mechc's file: 2N + 1 unit links of 1 kg (J = 1/12
# about the centre), gravity 9.81 along -y, rods vertical on ground pivots
# at (i, 0), couplers horizontal; B0 (site) the top of rod0. MuJoCo needs
# trees: rod i (hinge on the ground, angle from +x) carries coupler i
# (hinge at rod i's top), and coupler i's free end is tied to rod i+1's top
# by an equality `connect` (three soft rows, one of them, along z, empty:
# MuJoCo's constraints are spatial). The keyframe is the benchmark's
# initial state: every rod turning at -1 rad/s, the couplers not turning
# (+1 relative to their rod). qpos0 (the joints' ref) is the assembled
# state, where MuJoCo's compiler places each connect's second anchor.
# POSIX sh and awk only.
set -u
case ${1:-} in
'' | *[!0-9]*) echo "usage: sh $0 N   (N a positive integer)" >&2; exit 2 ;;
esac
awk -v n="$1" 'BEGIN {
    hp = atan2(1, 0); j = 1 / 12
    printf "<!-- a02, N = %d: written by sh bench/mujoco/a02.sh %d -->\n", n, n
    printf "<mujoco model=\"a02_four_bar_%d\">\n  <compiler angle=\"radian\"/>\n", n
    printf "  <option gravity=\"0 -9.81 0\"/>\n"
    printf "  <size njmax=\"%d\"/>\n", 3 * n + 10   # MuJoCo 2.2 has a fixed constraint buffer
    printf "  <default><joint type=\"hinge\" axis=\"0 0 1\"/></default>\n  <worldbody>\n"
    for (i = 0; i <= n; i++) {
        printf "    <body name=\"rod%d\" pos=\"%d 0 0\" euler=\"0 0 %.17g\">\n", i, i, hp
        printf "      <joint name=\"g%d\" ref=\"%.17g\"/>\n", i, hp
        printf "      <inertial pos=\"0.5 0 0\" mass=\"1\" diaginertia=\"%.17g %.17g %.17g\"/>\n", j, j, j
        if (i == 0)
            printf "      <site name=\"B0\" pos=\"1 0 0\"/>\n"
        if (i < n) {
            printf "      <body name=\"cpl%d\" pos=\"1 0 0\" euler=\"0 0 %.17g\">\n", i, -hp
            printf "        <joint name=\"a%d\"/>\n", i
            printf "        <inertial pos=\"0.5 0 0\" mass=\"1\" diaginertia=\"%.17g %.17g %.17g\"/>\n", j, j, j
            printf "      </body>\n"
        }
        printf "    </body>\n"
    }
    printf "  </worldbody>\n  <equality>\n"
    for (i = 0; i < n; i++)
        printf "    <connect name=\"b%d\" body1=\"cpl%d\" body2=\"rod%d\" anchor=\"1 0 0\"/>\n", i, i, i + 1
    printf "  </equality>\n  <keyframe>\n    <key qpos=\""
    for (i = 0; i <= n; i++) printf "%s%.17g%s", i ? " " : "", hp, i < n ? " 0" : ""
    printf "\" qvel=\""
    for (i = 0; i <= n; i++) printf "%s-1%s", i ? " " : "", i < n ? " 1" : ""
    printf "\"/>\n  </keyframe>\n</mujoco>\n"
}'
