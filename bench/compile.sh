#!/bin/sh
# bench/compile.sh MECHC - how compile times grow with the mechanism: chains
# of N four-bar loops (examples/chain.sh), N = 10, 100, 1000, then spatial
# chains of N bodies (examples/chain_spatial.sh), N = 10, 100.
#
# Columns: coordinates; operations of the fused `all`; CPU seconds (user +
# system, so that other load on the machine does not count) of `mechc gen
# --stats`, which goes from the file to machine code in process (read,
# derive, emit the written C and the JIT's, libtcc; median of 5 runs), its
# ratio to N = 100; peak memory; then the CPU time of `gcc -O2 -c` on the
# written C (one run; GCC=... to choose the compiler, GCC_O2=0 to skip).
# CHAINS=... and SPATIAL=... choose the N of each table ("" leaves it out).
# Needs /usr/bin/time. POSIX sh and awk only.
set -u
mechc=${1:-build/mechc}
gcc=${GCC:-gcc}
chains=${CHAINS-"10 100 1000"}
spatial=${SPATIAL-"10 100"}
[ -x "$mechc" ] || { echo "usage: sh bench/compile.sh MECHC (run make first)" >&2; exit 2; }
tmp=$(mktemp -d "${TMPDIR:-/tmp}/mechc-compile.XXXXXX") || exit 1
trap 'rm -rf "$tmp"' EXIT
trap 'exit 1' INT TERM

median5() {     # median5 FILE.mech: median of 5 CPU times of mechc gen --stats
    for i in 1 2 3 4 5; do
        /usr/bin/time -f '%U %S' "$mechc" gen "$1" --stats -o "$tmp/out.c" 2>&1 >/dev/null \
            | tail -1 | awk '{ printf "%.3f\n", $1 + $2 }'
    done | sort -n | sed -n 3p
}

# table TITLE SCRIPT NS: one row per N, the mechanism written by SCRIPT N
table() {
    [ -n "$3" ] || return 0
    printf '%s\n\n' "$1"
    printf '%6s %7s %8s | %9s %9s %9s | %9s\n' N nq "all ops" "code cpu" "x N=100" "peak MB" "gcc cpu s"
    base=""
    for n in $3; do
        f=$tmp/chain_$n.mech
        sh "$2" "$n" "$f" || exit 1
        stats=$("$mechc" gen "$f" --stats -o "$tmp/out.c" 2>&1)
        nq=$(echo "$stats" | sed -n 's/.*: \([0-9]*\) coordinates.*/\1/p')
        ops=$(echo "$stats" | sed -n 's/.*all \([0-9]*\).*/\1/p')
        secs=-
        [ -x /usr/bin/time ] && secs=$(median5 "$f")
        [ "$n" = 100 ] && base=$secs
        ratio=$(awk -v s="$secs" -v b="$base" 'BEGIN { if (b > 0) printf "%.1f", s / b; else print "-" }')
        peak=-
        if [ -x /usr/bin/time ]; then
            peak=$(/usr/bin/time -f '%M' "$mechc" gen "$f" --stats -o "$tmp/out.c" 2>&1 >/dev/null | tail -1)
            peak=$(awk -v k="$peak" 'BEGIN { printf "%.0f", k / 1024 }')
        fi
        gsecs=-
        if [ "${GCC_O2:-1}" != 0 ] && [ -x /usr/bin/time ] && command -v "$gcc" >/dev/null 2>&1; then
            gsecs=$(/usr/bin/time -f '%U %S' "$gcc" -std=c99 -O2 -c "$tmp/out.c" -o "$tmp/out.o" 2>&1 \
                    | tail -1 | awk '{ printf "%.1f", $1 + $2 }')
        fi
        printf '%6s %7s %8s | %9s %9s %9s | %9s\n' "$n" "$nq" "$ops" "$secs" "$ratio" "$peak" "$gsecs"
    done
}

table 'compile times, chains of N four-bar loops' examples/chain.sh "$chains"
[ -n "$chains" ] && [ -n "$spatial" ] && echo
table 'compile times, spatial chains of N bodies (N - 1 loops)' examples/chain_spatial.sh "$spatial"
