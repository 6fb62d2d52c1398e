#!/bin/sh
# seeds.sh - writes the fuzzer's seeds taken from examples/ into DIR: every
# examples/*.mech, and what each generator script examples/*.sh writes at
# N = 1, 2 and 3 (small, so that one input stays fast). Run by `make fuzz`,
# so that a new example is a seed without being copied into tests/fuzz.
#
#   sh tests/fuzz/seeds.sh DIR
#
# POSIX sh only.
set -eu
[ $# -eq 1 ] || { echo "usage: sh tests/fuzz/seeds.sh DIR" >&2; exit 2; }
dir=$1
root=$(dirname "$0")/../..
mkdir -p "$dir"
n=0
for f in "$root"/examples/*.mech; do
    cp "$f" "$dir/"
    n=$((n + 1))
done
for s in "$root"/examples/*.sh; do
    name=$(basename "$s" .sh)
    [ "$name" = size_arg ] && continue      # sourced by the generators, not one
    for size in 1 2 3; do
        sh "$s" "$size" "$dir/${name}_$size.mech"
        n=$((n + 1))
    done
done
echo "tests/fuzz/seeds.sh: $n seeds from examples/ in $dir"
