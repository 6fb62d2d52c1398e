#!/bin/sh
# bench/assembly.sh MECHC - Newton iterations of `mechc run` at t0 for every
# runnable example: with its initial values as written, with every angle
# guess (phi = ...) set to 0, and with every initial value left out (0).
# Prints a Markdown table; "fails" when run could not assemble.
set -u
mechc=${1:-build/mechc}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
iterations() {
    "$mechc" run "$1" --steps 0 --csv /dev/null --stats 2>&1 >/dev/null \
        | sed -n 's/.*assembly at t0 in \([0-9]*\) Newton.*/\1/p' | head -1
}
echo "| example | as written | angle guesses 0 | every guess 0 |"
echo "|---|---|---|---|"
for f in examples/*.mech; do
    n=$(basename "$f" .mech)
    "$mechc" run "$f" --steps 0 --csv /dev/null > /dev/null 2>&1 || continue
    sed -E '/^body/ s/phi *= *[^ ]+/phi = 0/' "$f" > "$tmp/a.mech"
    sed -E 's/^(body +[A-Za-z_0-9]+).*/\1/; s/^(point +[A-Za-z_0-9]+).*/\1/' "$f" > "$tmp/b.mech"
    a=$(iterations "$f"); b=$(iterations "$tmp/a.mech"); c=$(iterations "$tmp/b.mech")
    echo "| $n | ${a:-fails} | ${b:-fails} | ${c:-fails} |"
done
