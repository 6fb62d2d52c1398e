#!/bin/sh
# cycles.sh ELF - runs a -DSTEP_TRACE build of stewart.c on QEMU's Cortex-M4F
# one instruction at a time and prints, per part of a step, the executed
# instructions and their cycles by the Cortex-M4 TRM's tables (cycles.awk
# says which and under what assumptions). QEMU itself counts no cycles.
set -eu
elf=$1
here=$(dirname "$0")
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT INT TERM
arm-none-eabi-objdump -d "$elf" > "$tmp/dis"
mkfifo "$tmp/trace"
# The trace (about 800 MB for 200 steps) goes through the pipe, never to disk.
awk -f "$here/cycles.awk" "$tmp/dis" "$tmp/trace" > "$tmp/out" &
reader=$!
qemu-system-arm -M mps2-an386 -nographic -monitor none -serial none \
    -semihosting-config enable=on,target=native -singlestep -d exec,nochain \
    -D "$tmp/trace" -kernel "$elf" > "$tmp/program"
wait "$reader"
grep -q '^# done' "$tmp/program" || { cat "$tmp/program" >&2; exit 1; }
cat "$tmp/out"
