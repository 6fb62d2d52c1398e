#!/bin/sh
# bench/batch.sh MECHC - the batch kernels (mechc gen --batch) against single
# calls of the same written file: four-bar and the N = 10 chain
# (examples/chain.sh), gamma, the fused all and all_nz.
#
#   sh bench/batch.sh build/mechc            (part of `make bench`)
#   REPEAT=11 STATES=4096 sh bench/batch.sh build/mechc
#
# Each mechanism is written once (`mechc gen --batch --sparse --prefix m`)
# and built by gcc -std=c99 -O2 -march=native (the vector extensions this
# machine has; ISO C, so no FMA contraction: the batch equals the single
# calls to the bit) and by gcc -std=c99 -O2 (what the aot engine builds,
# SSE2 on x86-64). bench/batch_time.c times 10^6 evaluations of each kernel
# over STATES states (default 1000): STATES calls of m_NAME on rows, one
# m_NAME_batch call on the same rows, one m_NAME_batch_soa call on the
# states by coordinate, in turn, REPEAT (default 7) CPU times each, and
# prints ns per evaluation (minimum and median) and the ratios single /
# batch by minima (above 1: the batch is faster). It exits 1 when the
# outputs differ. POSIX sh.
set -u
mechc=${1:-build/mechc}
repeat=${REPEAT:-7}
states=${STATES:-1000}
root=$(cd "$(dirname "$0")/.." && pwd)
[ -x "$mechc" ] || { echo "usage: sh bench/batch.sh MECHC (run make first)" >&2; exit 2; }
command -v gcc > /dev/null 2>&1 || { echo "bench/batch.sh: gcc is missing" >&2; exit 1; }
tmp=$(mktemp -d "${TMPDIR:-/tmp}/mechc-batch.XXXXXX") || exit 1
trap 'rm -rf "$tmp"' EXIT
trap 'exit 1' INT TERM

gcc -std=c99 -O2 -o "$tmp/batch_time" "$root/bench/batch_time.c" -ldl -lm || exit 1
sh "$root/examples/chain.sh" 10 "$tmp/chain_10.mech" || exit 1
# the vector extensions -march=native enables, of those that matter here
ext=$(gcc -march=native -Q --help=target 2>/dev/null |
      awk '$2 == "[enabled]" && $1 ~ /^-m(sse2|avx|avx2|fma|avx512f)$/ { printf "%s ", substr($1, 3) }')

# define NAME HEADER: the value of #define M_NAME in HEADER
define() { sed -n "s/^#define M_$1 *\([0-9]*\).*/\1/p" "$2"; }

printf 'batch kernels against single calls: 10^6 evaluations over %s states, %s rounds\n' "$states" "$repeat"
printf 'in turn; -march=native here: %s\n\n' "$ext"
status=0
for entry in "four_bar:$root/examples/four_bar.mech" "chain_10:$tmp/chain_10.mech"; do
    name=${entry%%:*}
    file=${entry#*:}
    "$mechc" gen "$file" --batch --sparse --prefix m -o "$tmp/$name.c" --header "$tmp/$name.h" \
        || exit 1
    nq=$(define NQ "$tmp/$name.h")
    nr=$(( $(define NH "$tmp/$name.h") + $(define NV "$tmp/$name.h") ))
    nnz=$(define NNZ "$tmp/$name.h")
    for flags in "-O2 -march=native" "-O2"; do
        gcc -std=c99 $flags -fPIC -shared -I"$tmp" -o "$tmp/$name.so" "$tmp/$name.c" -lm || exit 1
        echo "$name (NQ $nq), gcc -std=c99 $flags:"
        "$tmp/batch_time" "$repeat" "$states" "$nq" "$nr" "$nnz" "$tmp/$name.so" | sed 's/^/  /' \
            || status=1
    done
done
exit $status
