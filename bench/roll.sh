#!/bin/sh
# bench/roll.sh MECHC - loop-rolled against straight-line code (mechc gen
# --roll always / never) on chains of N four-bar loops (examples/chain.sh N,
# 6N + 3 coordinates).
#
#   sh bench/roll.sh build/mechc                      (part of `make bench`)
#   SIZES="100 1000" BIG_N= REPEAT=21 sh bench/roll.sh build/mechc
#
# Per size N in SIZES and mode (never: straight-line, always: rolled), the
# file `mechc gen --sparse --prefix m` writes:
#   KB             its size
#   gen s          CPU time (user + system) of mechc gen
#   gcc -O2 -c s   CPU time of gcc -std=c99 -O2 -c on it, and its peak memory
# straight-line files above STRAIGHT_MAX_N (1000) are left out (gcc takes
# minutes on them). gen writes these dense files up to N = 7722: past it
# the dense Jacobian's NR x NQ entries pass INT_MAX, which gen refuses
# (--max-jac-entries); larger chains are written --sparse-only, below.
# Then, for N in TIME_SIZES (100 1000), both files are built
# with gcc -O2 -fPIC -shared (and tcc -shared when tcc is installed: code
# as libtcc makes it, with libm's sin and cos) and bench/roll_time.c times
# their kernels side by side, interleaved, after checking they compute the
# same bytes: ns per call, medians of REPEAT rounds, and rolled/straight.
# Then the files gen writes by default (roll auto) for N in WRITTEN_SIZES
# (1000 10000): the ordinary one (dense P_jac and P_all; --sparse, past
# --max-jac-entries left out) and the --sparse-only one, their size and
# gcc -std=c99 -O2 -c's CPU time and peak memory.
# Then the N = BIG_N chain (10 000; empty: left out) from the file to
# machine code in process: `mechc run --steps 0 --stats` (jit, auto rolls
# it), its stages and the whole command's CPU time and peak memory; and
# the same source built by gcc (`--engine aot`, gcc -O2 -fPIC -shared
# timed through a CC wrapper, in a fresh cache): its size and gcc's CPU.
# Needs gcc and /usr/bin/time (without it the times say "-").
# POSIX sh and awk only.
set -u
mechc=${1:-build/mechc}
sizes=${SIZES:-"100 1000 7700"}
time_sizes=${TIME_SIZES:-"100 1000"}
straight_max=${STRAIGHT_MAX_N:-1000}
repeat=${REPEAT:-11}
big_n=${BIG_N-10000}
written_sizes=${WRITTEN_SIZES-"1000 10000"}
root=$(cd "$(dirname "$0")/.." && pwd)
[ -x "$mechc" ] || { echo "usage: sh bench/roll.sh MECHC (run make first)" >&2; exit 2; }
command -v gcc > /dev/null 2>&1 || { echo "bench/roll.sh: gcc is missing" >&2; exit 1; }
tmp=$(mktemp -d "${TMPDIR:-/tmp}/mechc-roll.XXXXXX") || exit 1
trap 'rm -rf "$tmp"' EXIT
trap 'exit 1' INT TERM
timer=
[ -x /usr/bin/time ] && timer=/usr/bin/time

# cpu OUT CMD...: runs CMD (stdout and stderr to OUT.log); "cpu_s maxrss_kb" in OUT.
cpu() {
    out=$1
    shift
    if [ -n "$timer" ]; then
        $timer -f "%U %S %M" -o "$out.t" "$@" > "$out.log" 2>&1
        tail -1 "$out.t" | awk '{ printf "%.2f %d\n", $1 + $2, $3 }' > "$out"
    else
        "$@" > "$out.log" 2>&1
        echo "- -" > "$out"
    fi
}

gcc -std=c99 -O2 -o "$tmp/roll_time" "$root/bench/roll_time.c" -ldl || exit 1
echo "== loop-rolled (gen --roll always) against straight-line (--roll never) C: chains =="
printf '%6s %7s %-7s %9s %7s %13s %10s\n' N NQ mode KB "gen s" "gcc -O2 -c s" "gcc MB"
for n in $sizes; do
    sh "$root/examples/chain.sh" "$n" "$tmp/c$n.mech" || exit 1
    for mode in never always; do
        if [ "$mode" = never ] && [ "$n" -gt "$straight_max" ]; then
            printf '%6s %7s %-7s %9s\n' "$n" $((6 * n + 3)) "$mode" "(left out: above STRAIGHT_MAX_N)"
            continue
        fi
        f=$tmp/c${n}_$mode
        cpu "$f.gen" "$mechc" gen "$tmp/c$n.mech" --sparse --prefix m --roll "$mode" \
            --max-jac-entries 2147483647 -o "$f.c"
        [ -s "$f.c" ] || { echo "bench/roll.sh: gen failed:"; cat "$f.gen.log"; exit 1; }
        cpu "$f.gcc" gcc -std=c99 -O2 -c "$f.c" -o "$f.o"
        kb=$(wc -c < "$f.c" | awk '{ printf "%.0f", $1 / 1024 }')
        read -r gs _ < "$f.gen"
        read -r gc gm < "$f.gcc"
        printf '%6s %7s %-7s %9s %7s %13s %10s\n' "$n" $((6 * n + 3)) "$mode" "$kb" "$gs" "$gc" \
            "$(echo "$gm" | awk '{ printf "%.0f", $1 / 1024 }')"
    done
done

for n in $time_sizes; do
    [ -f "$tmp/c$n.mech" ] || sh "$root/examples/chain.sh" "$n" "$tmp/c$n.mech" || exit 1
    for mode in never always; do
        [ -f "$tmp/c${n}_$mode.c" ] || "$mechc" gen "$tmp/c$n.mech" --sparse --prefix m \
            --roll "$mode" -o "$tmp/c${n}_$mode.c" || exit 1
    done
    sizes_line=$(grep -E '^#define M_(NQ|NH|NV|NNZ) ' "$tmp/c${n}_never.c" | awk '{ v[$2] = $3 }
        END { print v["M_NQ"], v["M_NH"] + v["M_NV"], v["M_NNZ"] }')
    for cc in "gcc-O2|gcc -std=c99 -O2 -fPIC -shared" "tcc|tcc -shared"; do
        name=${cc%%|*}
        cmd=${cc#*|}
        command -v "${cmd%% *}" > /dev/null 2>&1 || continue
        for mode in never always; do
            $cmd -o "$tmp/${name}_c${n}_$mode.so" "$tmp/c${n}_$mode.c" -lm || exit 1
        done
        echo
        echo "== N = $n, $name: kernels side by side (ns per call, median of $repeat) =="
        # shellcheck disable=SC2086
        "$tmp/roll_time" "$repeat" $sizes_line "$tmp/${name}_c${n}_never.so" \
            "$tmp/${name}_c${n}_always.so" > "$tmp/t.out" || exit 1
        awk 'NR == 1 { print; next } { print; for (i = 2; i <= NF; i++) v[NR, i] = $i; nf = NF }
             END { printf "%-28s", "rolled / straight"
                   for (i = 2; i <= nf; i++) printf " %10.2f", v[3, i] / v[2, i]; print "" }' "$tmp/t.out"
    done
done

if [ -n "$written_sizes" ]; then
    echo
    echo "== written files, roll auto: gen --sparse (dense P_jac, P_all too) and gen --sparse-only =="
    printf '%6s %7s %-12s %9s %7s %13s %10s\n' N NQ file KB "gen s" "gcc -O2 -c s" "gcc MB"
fi
for n in $written_sizes; do
    [ -f "$tmp/c$n.mech" ] || sh "$root/examples/chain.sh" "$n" "$tmp/c$n.mech" || exit 1
    for what in sparse sparse-only; do
        f=$tmp/w${n}_$what
        cpu "$f.gen" "$mechc" gen "$tmp/c$n.mech" "--$what" --prefix m -o "$f.c"
        if [ ! -s "$f.c" ]; then
            printf '%6s %7s %-12s %9s\n' "$n" $((6 * n + 3)) "$what" \
                "(gen refuses it: $(grep -o 'more than the limit of [0-9]*' "$f.gen.log"))"
            continue
        fi
        cpu "$f.gcc" gcc -std=c99 -O2 -c "$f.c" -o "$f.o"
        kb=$(wc -c < "$f.c" | awk '{ printf "%.0f", $1 / 1024 }')
        read -r gs _ < "$f.gen"
        read -r gc gm < "$f.gcc"
        printf '%6s %7s %-12s %9s %7s %13s %10s\n' "$n" $((6 * n + 3)) "$what" "$kb" "$gs" "$gc" \
            "$(echo "$gm" | awk '{ printf "%.0f", $1 / 1024 }')"
        rm -f "$f.c" "$f.o"
    done
done

if [ -n "$big_n" ]; then
    echo
    echo "== N = $big_n ($((6 * big_n + 3)) coordinates): file to machine code in process =="
    sh "$root/examples/chain.sh" "$big_n" "$tmp/big.mech" || exit 1
    cpu "$tmp/big" "$mechc" run "$tmp/big.mech" --steps 0 --stats --csv /dev/null
    grep 'set-up' "$tmp/big.log"
    read -r bs bm < "$tmp/big"
    echo "whole command (load, derivatives, emission, libtcc, assembly): $bs s CPU," \
         "$(echo "$bm" | awk '{ printf "%.0f", $1 / 1024 }') MB peak"
    # the same source under the system compiler: the aot engine's build,
    # through a CC that times gcc and keeps the file's size (a fresh cache)
    if [ -n "$timer" ]; then
        {
            echo '#!/bin/sh'
            echo "for a; do case \$a in *.c) wc -c < \"\$a\" > '$tmp/aot.size' ;; esac; done"
            echo "exec $timer -f '%U %S %M' -o '$tmp/aot.t' gcc \"\$@\""
        } > "$tmp/cc.sh"
        chmod +x "$tmp/cc.sh"
        XDG_CACHE_HOME=$tmp/cache CC=$tmp/cc.sh "$mechc" run "$tmp/big.mech" --engine aot \
            --steps 0 --csv /dev/null > /dev/null 2> "$tmp/aot.log" || { cat "$tmp/aot.log"; exit 1; }
        tail -1 "$tmp/aot.t" | awk -v bytes="$(cat "$tmp/aot.size")" '{
            printf "aot: gcc -O2 -fPIC -shared of its %.0f KB source: %.2f s CPU, %.0f MB peak\n",
                   bytes / 1024, $1 + $2, $3 / 1024 }'
    fi
fi
