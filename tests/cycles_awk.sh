#!/bin/sh
# tests/cycles_awk.sh MECHC - examples/firmware/cycles.awk (the Cortex-M4
# cycle estimate of the Stewart firmware example) on a made-up disassembly
# and QEMU trace whose cycles are counted by hand below: no QEMU needed.
#
#   sh tests/cycles_awk.sh build/mechc
set -u
# shellcheck source=tests/lib.sh
. "$(dirname "$0")/lib.sh"
suite_begin cycles_awk "${1:-build/mechc}"

tab=$(printf '\t')
cat > "$tmp/dis" <<DIS
00000100 <mark_fk_pred>:
     100:${tab}4770      ${tab}bx${tab}lr

00000102 <work>:
     102:${tab}6808      ${tab}ldr${tab}r0, [r1, #0]
     104:${tab}6849      ${tab}ldr${tab}r1, [r1, #4]
     106:${tab}ee20 0a01 ${tab}vmul.f32${tab}s0, s0, s2
     10a:${tab}eec0 0a01 ${tab}vdiv.f32${tab}s1, s0, s2
     10e:${tab}2800      ${tab}cmp${tab}r0, #0
     110:${tab}d1f7      ${tab}bne.n${tab}102 <work>
     112:${tab}b510      ${tab}push${tab}{r4, lr}
     114:${tab}bd10      ${tab}pop${tab}{r4, pc}

00000200 <mark_off>:
     200:${tab}4770      ${tab}bx${tab}lr
DIS
# The loop twice (bne taken, then not), then push and pop {.., pc}.
for a in 100 102 104 106 10a 10e 110 102 104 106 10a 10e 110 112 114 200; do
    printf 'Trace 0: 0x7f653c000100 [00800408/%08x/00000110/ff000201] work\n' "0x$a"
done > "$tmp/trace"
awk -f "$root/examples/firmware/cycles.awk" "$tmp/dis" "$tmp/trace" > "$tmp/out"

# High: 2 2 1 14 1 (1+3) | 2 2 1 14 1 1 | 3 | 3+3 = 54. Low: the second
# load of each pair 1, P = 1: 2 1 1 14 1 2 | 2 1 1 14 1 1 | 3 | 4 = 48.
check "the window's instructions and cycles" \
    out_has "forward kinematics with the predictor: 14 instructions, 48 to 54 cycles (mean of 1)"
check "a part without a window says so" out_has "forward kinematics from the previous pose: no window in the trace"
check "no unknown address" sh -c "! grep -q warning '$tmp/out'"
suite_end
