#!/bin/sh
# check.sh OUT - runs the firmware example built by this folder's Makefile
# in OUT: both host builds, then the Cortex-M4F image under QEMU's
# mps2-an386 and the Cortex-M3 image under mps2-an385, and compares each
# target's output with the host run of the same real type (compare.awk:
# float within 1e-4, double within 1e-12, relative to each column's size).
# The same for the Stewart platform's forward kinematics (stewart.c, float:
# host-stewart and m4f-stewart; each also checks itself against the
# closed-form trajectory and exits 1 when a pose is off).
#
# The images print through semihosting and end with its SYS_EXIT call;
# QEMU's exit status is the program's. Each run is bounded by a timeout
# (FIRMWARE_TIMEOUT seconds, default 60) in case an image never exits.
# The last line is "firmware_check: N passed, M failed"; the exit status is
# non-zero on any failure. POSIX sh.
# $qemu_opts is split into words on purpose.
# shellcheck disable=SC2086
set -u

out=${1:?usage: sh check.sh OUT}
here=$(cd "$(dirname "$0")" && pwd)
limit=${FIRMWARE_TIMEOUT:-60}
pass=0
fail=0

ok() { pass=$((pass + 1)); echo "ok: $1"; }
bad() { fail=$((fail + 1)); echo "FAIL: $1" >&2; }

# run NAME COMMAND...: runs COMMAND with stdout to OUT/NAME.out.
run() {
    name=$1
    shift
    if timeout "$limit" "$@" > "$out/$name.out" 2> "$out/$name.err"; then
        ok "$name runs and exits 0 ($(grep -c -v '^#' "$out/$name.out") result lines)"
    else
        bad "$name: exit status $? (124: timed out after $limit s)"
        sed -n '1,10s/^/    /p' "$out/$name.out" "$out/$name.err" >&2
    fi
}

# QEMU's options besides the machine and the image: semihosting on (output
# to QEMU's stdout), no display, monitor or serial port.
qemu_opts="-nographic -monitor none -serial none -semihosting-config enable=on,target=native"

# compare HOST TARGET RTOL
compare() {
    if awk -v rtol="$3" -f "$here/compare.awk" "$out/$1.out" "$out/$2.out" > "$out/$2.cmp"; then
        ok "$2 matches $1: $(tail -1 "$out/$2.cmp")"
    else
        bad "$2 differs from $1"
        sed -n '1,12s/^/    /p' "$out/$2.cmp" >&2
    fi
}

run host-double "$out/host-double"
run host-float "$out/host-float"
run m3 qemu-system-arm -M mps2-an385 $qemu_opts -kernel "$out/m3.elf"
run m4f qemu-system-arm -M mps2-an386 $qemu_opts -kernel "$out/m4f.elf"
run host-stewart "$out/host-stewart"
run m4f-stewart qemu-system-arm -M mps2-an386 $qemu_opts -kernel "$out/m4f-stewart.elf"
compare host-double m3 1e-12
compare host-float m4f 1e-4
compare host-stewart m4f-stewart 1e-4

echo "firmware_check: $pass passed, $fail failed"
[ "$fail" = 0 ]
