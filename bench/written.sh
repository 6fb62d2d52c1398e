#!/bin/sh
# bench/written.sh MECHC - the written file under the compilers firmware and
# quick builds use: tcc -shared, gcc -O0 and gcc -O2, for the four-bar and
# chains of N = 10 and N = 100 loops (examples/chain.sh).
#
#   sh bench/written.sh build/mechc          (part of `make bench`)
#   REPEAT=31 CHAINS="10" sh bench/written.sh build/mechc
#
# Each mechanism is written twice (`mechc gen --prefix m`, and with
# `--trig libm`), each built by the three compilers; bench/written_time.c
# loads the six shared objects, checks they compute the same values, and
# times every function of each, interleaved (ns per call, medians of REPEAT
# rounds). Printed side by side, per compiler:
#   phi jac jac_nz gamma all   ns per call of the default file
#   floor                      one memset of the dense Jacobian and NNZ
#                              stores at their places (the driver's, gcc -O2)
#   jac/(nz+fl)                the dense Jacobian against jac_nz plus that
#                              floor: 1 when the fill costs one memset
#   x libm: phi nz gam all     default file / --trig libm file (below 1:
#                              the default is faster)
# Then the CPU time (user + system) of `gcc -O2 -c` on the written N = 100
# file, default and --trig libm (median of 3 runs each, interleaved), and
# their ratio. Needs gcc, tcc and /usr/bin/time (what is missing is skipped).
# POSIX sh and awk only.
set -u
mechc=${1:-build/mechc}
repeat=${REPEAT:-21}
chains=${CHAINS:-"10 100"}
root=$(cd "$(dirname "$0")/.." && pwd)
[ -x "$mechc" ] || { echo "usage: sh bench/written.sh MECHC (run make first)" >&2; exit 2; }
command -v gcc > /dev/null 2>&1 || { echo "bench/written.sh: gcc is missing" >&2; exit 1; }
tmp=$(mktemp -d "${TMPDIR:-/tmp}/mechc-written.XXXXXX") || exit 1
trap 'rm -rf "$tmp"' EXIT
trap 'exit 1' INT TERM

gcc -std=c99 -O2 -o "$tmp/written_time" "$root/bench/written_time.c" -ldl -lm || exit 1
compilers="tcc|tcc -shared
gcc-O0|gcc -std=c99 -O0 -fPIC -shared
gcc-O2|gcc -std=c99 -O2 -fPIC -shared"
if ! command -v tcc > /dev/null 2>&1; then
    echo "skip: tcc is missing (apt-get install tcc)"
    compilers=$(echo "$compilers" | sed 1d)
fi

files="four_bar:$root/examples/four_bar.mech"
for n in $chains; do
    sh "$root/examples/chain.sh" "$n" "$tmp/chain_$n.mech" || exit 1
    files="$files chain_$n:$tmp/chain_$n.mech"
done

# define NAME HEADER: the value of #define M_NAME in HEADER
define() { sed -n "s/^#define M_$1 *\([0-9]*\).*/\1/p" "$2"; }

printf 'written files, ns per call (median of %s interleaved rounds)\n\n' "$repeat"
printf '%-10s %-7s | %8s %9s %8s %8s %9s | %9s %11s | %5s %5s %5s %5s\n' \
    mechanism compiler phi jac jac_nz gamma all floor "jac/(nz+fl)" "x libm" "" "" ""
printf '%-10s %-7s | %8s %9s %8s %8s %9s | %9s %11s | %5s %5s %5s %5s\n' \
    "" "" "" "" "" "" "" "" "" phi nz gam all
status=0
for entry in $files; do
    name=${entry%%:*} mech=${entry#*:}
    d=$tmp/$name
    mkdir -p "$d"
    "$mechc" gen "$mech" --prefix m -o "$d/m.c" --header "$d/m.h" &&
    "$mechc" gen "$mech" --prefix m --trig libm -o "$d/l.c" || { status=1; continue; }
    nq=$(define NQ "$d/m.h") nr=$(($(define NH "$d/m.h") + $(define NV "$d/m.h"))) nnz=$(define NNZ "$d/m.h")
    libs="" labels=""
    while IFS='|' read -r tag cc; do
        for v in m l; do
            # shellcheck disable=SC2086 # cc is a command with options
            $cc -I"$d" "$d/$v.c" -o "$d/$v-$tag.so" -lm || { status=1; continue 3; }
            libs="$libs $d/$v-$tag.so"
        done
        labels="$labels $tag"
    done <<EOF
$compilers
EOF
    # shellcheck disable=SC2086 # libs is a list of paths
    "$tmp/written_time" "$repeat" "$nq" "$nr" "$nnz" $libs > "$d/times" || status=1
    for tag in $labels; do
        awk -v name="$name" -v label="$tag" -v m="$d/m-$tag.so" -v l="$d/l-$tag.so" '
            $1 == m { for (i = 2; i <= 7; i++) a[i] = $i }
            $1 == l { for (i = 2; i <= 7; i++) b[i] = $i }
            $1 == "floor" { floor = $2 }
            function r(x, y) { return y > 0 ? sprintf("%.2f", x / y) : "-" }
            END {
                # columns of written_time: phi jac jac_nz nu gamma all
                printf "%-10s %-7s | %8.1f %9.1f %8.1f %8.1f %9.1f | %9.1f %11s | %5s %5s %5s %5s\n",
                    name, label, a[2], a[3], a[4], a[6], a[7], floor, r(a[3], a[4] + floor),
                    r(a[2], b[2]), r(a[4], b[4]), r(a[6], b[6]), r(a[7], b[7])
            }' "$d/times"
    done
done

echo
if [ -x /usr/bin/time ] && [ -f "$tmp/chain_100/m.c" ]; then
    echo "gcc -O2 -c of the written N = 100 file, CPU seconds (user + system), median of 3:"
    for i in 1 2 3; do
        for v in m l; do
            /usr/bin/time -f "$v %U %S" gcc -std=c99 -O2 -c "$tmp/chain_100/$v.c" -o "$tmp/$v.o" 2>&1 |
                tail -n 1
        done
    done | awk '
        { t[$1, ++n[$1]] = $2 + $3 }
        function median(v,   a, b, c, s) {
            a = t[v, 1]; b = t[v, 2]; c = t[v, 3]
            if (a > b) { s = a; a = b; b = s }
            if (b > c) { s = b; b = c; c = s }
            if (a > b) { s = a; a = b; b = s }
            return b
        }
        END {
            m = median("m"); l = median("l")
            printf "  default %.2f s, --trig libm %.2f s, ratio %.2f\n", m, l, (l > 0 ? m / l : 0)
        }'
else
    echo "skip: gcc -O2 compile time (needs /usr/bin/time and the N = 100 chain)"
fi
exit $status
