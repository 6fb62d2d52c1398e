#!/bin/sh
# bench/sympy_time.sh MECHC - the timing yardstick: mechc's kernels against
# SymPy cse's, the same trig on both sides (libm), under gcc -O2, for the
# four-bar and chains of N = 10 and N = 100 loops (examples/chain.sh).
#
#   sh bench/sympy_time.sh build/mechc          (part of `make bench`)
#   REPEAT=31 CHAINS="10" GENFLAGS="--chunk 1000" sh bench/sympy_time.sh build/mechc
#
# Each mechanism is written by `mechc gen --prefix m --trig libm` and by
# bench/sympy_kernels.py (SymPy's derivation, sympy.cse, sympy.ccode), both
# built with gcc -O2 -fPIC -shared; bench/sympy_time.c checks they agree to
# 1e-12 and times phi, jac_nz and gamma of both, interleaved, in thread CPU
# time (medians of REPEAT rounds). Printed per kernel: ns per call of
# mechc and of SymPy, their ratio (the target: at most 0.8), and the
# ratio of what lies above the trig floor (sin and cos of every angle, the
# time that both must spend), and what the target leaves for everything
# but the trig: 0.8 SymPy - trig (negative: 0.8 is out of reach however
# fast the rest). Then, from the object code (objdump -d, with
# bench/stack_calls.awk), per kernel of both: libm trig calls (sincos, sin
# and cos call sites, each made once per call) against the angles, and
# stack stores and loads. Needs python3 with SymPy (else "skipped") and
# gcc; objdump for the second table. POSIX sh and awk only.
set -u
mechc=${1:-build/mechc}
repeat=${REPEAT:-21}
chains=${CHAINS:-"10 100"}
genflags=${GENFLAGS:-}
root=$(cd "$(dirname "$0")/.." && pwd)
[ -x "$mechc" ] || { echo "usage: sh bench/sympy_time.sh MECHC (run make first)" >&2; exit 2; }
if ! python3 -c 'import sympy' > /dev/null 2>&1; then
    echo "sympy_time: SymPy is not installed for python3; skipped"
    exit 0
fi
command -v gcc > /dev/null 2>&1 || { echo "bench/sympy_time.sh: gcc is missing" >&2; exit 1; }
tmp=$(mktemp -d "${TMPDIR:-/tmp}/mechc-sympy.XXXXXX") || exit 1
trap 'rm -rf "$tmp"' EXIT
trap 'exit 1' INT TERM

cc="gcc -std=c99 -O2 -fPIC -shared"
gcc -std=c99 -O2 -o "$tmp/sympy_time" "$root/bench/sympy_time.c" -ldl -lm || exit 1
files="four_bar:$root/examples/four_bar.mech"
for n in $chains; do
    sh "$root/examples/chain.sh" "$n" "$tmp/chain_$n.mech" || exit 1
    files="$files chain_$n:$tmp/chain_$n.mech"
done

# define NAME HEADER: the value of #define M_NAME in HEADER
define() { sed -n "s/^#define M_$1 *\([0-9]*\).*/\1/p" "$2"; }

printf 'mechc --trig libm against SymPy cse, gcc -O2, ns per call (median of %s interleaved rounds)\n\n' \
    "$repeat"
printf '%-10s %-7s %9s %9s %7s %11s %9s %11s\n' mechanism kernel mechc sympy ratio "above trig" "trig" \
    "0.8 s-trig"
status=0
for entry in $files; do
    name=${entry%%:*} mech=${entry#*:}
    d=$tmp/$name
    mkdir -p "$d"
    # shellcheck disable=SC2086 # genflags is a list of options
    "$mechc" gen "$mech" $genflags --prefix m --trig libm -o "$d/m.c" --header "$d/m.h" &&
    python3 "$root/bench/sympy_kernels.py" "$mechc" "$mech" "$d/m.c" "$d/s.c" &&
    $cc -I"$d" "$d/m.c" -o "$d/m.so" -lm &&
    $cc "$d/s.c" -o "$d/s.so" -lm || { status=1; continue; }
    nq=$(define NQ "$d/m.h") nr=$(($(define NH "$d/m.h") + $(define NV "$d/m.h"))) nnz=$(define NNZ "$d/m.h")
    "$tmp/sympy_time" "$repeat" "$nq" "$nr" "$nnz" "$d/m.so" "$d/s.so" > "$d/times" || { status=1; continue; }
    awk -v name="$name" '
        $1 == "trig" { trig = $2 }
        $1 != "trig" { k[++n] = $1; m[n] = $2; s[n] = $3; r[n] = $4; a[n] = $5 }
        END {
            for (i = 1; i <= n; i++)
                printf "%-10s %-7s %9.1f %9.1f %7.2f %11.2f %9s %11.1f\n", (i == 1 ? name : ""), k[i],
                    m[i], s[i], r[i], a[i], (i == 1 ? sprintf("%.1f", trig) : ""), 0.8 * s[i] - trig
        }' "$d/times"
    if command -v objdump > /dev/null 2>&1; then
        for v in m s; do
            objdump -d --no-show-raw-insn "$d/$v.so" | awk -v prefix=m -f "$root/bench/stack_calls.awk" \
                > "$d/$v.stack"
        done
    fi
done

command -v objdump > /dev/null 2>&1 || { echo "skip: object code counts (objdump is missing)"; exit $status; }
printf '\nobject code (objdump -d): libm trig calls for the angles, stack stores / loads\n\n'
printf '%-10s %-7s %7s %13s %13s %13s\n' mechanism kernel angles "trig m / s" "mechc st/ld" "sympy st/ld"
for entry in $files; do
    name=${entry%%:*}
    d=$tmp/$name
    [ -f "$d/m.stack" ] && [ -f "$d/s.stack" ] || continue
    awk -v name="$name" '
        FNR == 1 { file++ }
        { t[file, $1] = $2; st[file, $1] = $3; ld[file, $1] = $4 }
        END {
            n = split("phi jac_nz gamma", k, " ")
            for (i = 1; i <= n; i++)
                printf "%-10s %-7s %7s %13s %13s %13s\n", (i == 1 ? name : ""), k[i],
                    (i == 1 ? t[2, "trig"] : ""), t[1, k[i]] " / " t[2, k[i]],
                    st[1, k[i]] " / " ld[1, k[i]], st[2, k[i]] " / " ld[2, k[i]]
        }' "$d/m.stack" "$d/s.stack"
done
exit $status
