#!/bin/sh
# bench/scaling.sh MECHC - how `mechc run` grows with the mechanism: chains
# of N four-bar loops (examples/chain.sh N, 6N + 3 coordinates), run with
# the dense LU and with the sparse one (KLU) for N = 10, 100, 1000 and
# 10 000, then the target run (doc/figures.md, Loop-rolled code).
#
#   sh bench/scaling.sh build/mechc                    (part of `make bench`)
#   SIZES="10 100 1000 3000" STEPS=100 sh bench/scaling.sh build/mechc
#
# Per size and linear algebra, one `mechc run --steps STEPS --csv /dev/null
# --stats` (the dense LU's O(n^3) steps are few at N >= DENSE_FEW_N: their
# per-step figures are still per step; above DENSE_MAX_N, 1000, the dense
# matrix alone would take gigabytes and the dense runs are left out):
#   gen s          generation: derivatives and emission of the C (--stats'
#                  stage times, wall)
#   compile s      libtcc's compilation of it (--stats, wall)
#   step ms        wall time of one step, inside run (--stats; output excluded)
#   step CPU ms    the process's CPU time of one step (--stats)
#   wall s, CPU s  the whole command: parse, generate, JIT-compile, assemble,
#                  STEPS steps, CSV formatted to /dev/null (/usr/bin/time)
#   max RSS MB     peak resident memory (/usr/bin/time -f %M)
# and the ratio dense / sparse of the step CPU time. Then the target run:
# N = TARGET_N, `run --steps 1000` (auto: sparse), CSV to a file, whole
# command CPU and peak memory, split into set-up (the same command with
# --steps 0: parse, derivatives, emission, libtcc, assembly), the steps
# (--stats) and the rest, the printing of 3 x 6003 x 1001 numbers; the same
# with --digits 6. Then, when BIG_N is set (empty by default: the table has
# N = 10 000), N = BIG_N, `run --steps BIG_STEPS`: set-up CPU and its
# stages (--stats, wall), CPU per step, peak memory.
# Without /usr/bin/time the whole-command columns say "-".
# POSIX sh and awk only.
set -u
mechc=${1:-build/mechc}
sizes=${SIZES:-"10 100 1000 10000"}
steps=${STEPS:-100}
dense_few_n=${DENSE_FEW_N:-1000}
dense_few_steps=${DENSE_FEW_STEPS:-2}
dense_max_n=${DENSE_MAX_N:-1000}
target_n=${TARGET_N:-1000}
big_n=${BIG_N:-}
big_steps=${BIG_STEPS:-100}
if [ ! -x "$mechc" ]; then
    echo "usage: sh bench/scaling.sh MECHC   ('$mechc' is not an executable; run make first)" >&2
    exit 2
fi
here=$(dirname "$0")
tmp=$(mktemp -d "${TMPDIR:-/tmp}/mechc_scaling.XXXXXX") || exit 2
trap 'rm -rf "$tmp"' EXIT
trap 'exit 2' INT TERM
timer=
[ -x /usr/bin/time ] && timer=/usr/bin/time

# timed OUT ARGS...: mechc run ARGS, stderr to OUT.err; "wall cpu maxrss_kb" in OUT.time.
timed() {
    out=$1
    shift
    if [ -n "$timer" ]; then
        $timer -f "%e %U %S %M" -o "$out.t" "$mechc" run "$@" > /dev/null 2> "$out.err"
        tail -1 "$out.t" > "$out.time"     # after "Command exited with ..." on failure
    else
        "$mechc" run "$@" > /dev/null 2> "$out.err"
        echo "- - - -" > "$out.time"
    fi
}

# stat FILE WHAT: the ns per step of a --stats line ("analysis" or "CPU"),
# or the ns of one kernel call ("kernel").
stat() {
    case $2 in
        analysis) sed -n 's/.*of analysis: \([0-9.]*\) ns per step.*/\1/p' "$1" ;;
        CPU) sed -n 's/.*of CPU time in the steps: \([0-9.]*\) ns per step.*/\1/p' "$1" ;;
        kernel) sed -n 's/.*kernel call .* takes \([0-9.]*\) ns.*/\1/p' "$1" ;;
    esac
}

echo "mechc run on chains of N four-bar loops (examples/chain.sh N), dense LU against KLU"
printf '%6s %6s %-6s %5s %7s %9s %10s %12s %8s %8s %10s\n' \
    N nq linear steps "gen s" "compile s" "step ms" "step CPU ms" "wall s" "CPU s" "max RSS MB"
for n in $sizes; do
    sh "$here/../examples/chain.sh" "$n" "$tmp/chain.mech" || exit 2
    nq=$((6 * n + 3))
    for lin in dense sparse; do
        s=$steps
        [ "$lin" = dense ] && [ "$n" -ge "$dense_few_n" ] && s=$dense_few_steps
        if [ "$lin" = dense ] && [ "$n" -gt "$dense_max_n" ]; then
            printf '%6s %6s %-6s %5s skipped (nq^2 doubles: %s MB)\n' "$n" "$nq" "$lin" - \
                $((nq * nq / 131072))
            continue
        fi
        timed "$tmp/r" "$tmp/chain.mech" --steps "$s" --linear "$lin" --csv /dev/null --stats
        a=$(stat "$tmp/r.err" analysis)
        c=$(stat "$tmp/r.err" CPU)
        if [ -z "$a" ]; then
            printf '%6s %6s %-6s %5s failed: %s\n' "$n" "$nq" "$lin" "$s" "$(head -1 "$tmp/r.err")"
            continue
        fi
        eval "cpu_$lin=$c"
        read -r wall user sys rss < "$tmp/r.time"
        awk -v n="$n" -v nq="$nq" -v l="$lin" -v s="$s" -v a="$a" -v c="$c" -v w="$wall" \
            -v u="$user" -v y="$sys" -v r="$rss" \
            -v st="$(sed -n 's/.*stats: set-up: //p' "$tmp/r.err")" 'BEGIN {
            cpu = (u == "-") ? "-" : sprintf("%.2f", u + y)
            mb = (r == "-") ? "-" : sprintf("%.1f", r / 1024)
            # "load A s, derivatives B s, emission C s, compilation D s"
            nf = split(st, f, /[ ,]+/)
            for (i = 1; i < nf; i++) v[f[i]] = f[i + 1]
            printf "%6d %6d %-6s %5d %7.3f %9.3f %10.3f %12.3f %8s %8s %10s\n", n, nq, l, s,
                   v["derivatives"] + v["emission"], v["compilation"], a / 1e6, c / 1e6, w, cpu, mb }'
    done
    awk -v n="$n" -v d="${cpu_dense:-}" -v s="${cpu_sparse:-}" 'BEGIN {
        if (d != "" && s != "" && s > 0) printf "%6d  dense / sparse step CPU time: %.1f\n", n, d / s }'
    cpu_dense=
    cpu_sparse=
done

echo
echo "target: chain N = $target_n, mechc run --steps 1000 (auto), whole command"
sh "$here/../examples/chain.sh" "$target_n" "$tmp/target.mech" || exit 2
timed "$tmp/s" "$tmp/target.mech" --steps 0 --csv /dev/null
read -r wall user sys rss < "$tmp/s.time"
setup=$(awk -v u="$user" -v y="$sys" 'BEGIN { print (u == "-") ? "-" : u + y }')
for digits in "" 6; do
    timed "$tmp/t" "$tmp/target.mech" --steps 1000 --csv "$tmp/target.csv" --stats \
        ${digits:+--digits "$digits"}
    read -r wall user sys rss < "$tmp/t.time"
    c=$(stat "$tmp/t.err" CPU)
    awk -v w="$wall" -v u="$user" -v y="$sys" -v r="$rss" -v c="$c" -v d="$digits" \
        -v su="$setup" -v b="$(wc -c < "$tmp/target.csv" 2> /dev/null || echo 0)" 'BEGIN {
        how = (d == "") ? "shortest round-trip CSV" : "CSV with --digits " d
        mb = (r == "-") ? "-" : sprintf("%.1f", r / 1024)
        steps = c * 1000 / 1e9
        if (u == "-" || su == "-") {
            printf "  %-24s wall %s s, max RSS %s MB; steps %.2f s CPU; CSV %.0f MB\n",
                   how, w, mb, steps, b / 1e6
        } else {
            printf "  %-24s wall %s s, CPU %.2f s = set-up %.2f + steps %.2f + printing %.2f; max RSS %s MB; CSV %.0f MB\n",
                   how, w, u + y, su, steps, u + y - su - steps, mb, b / 1e6
        }
    }'
done

[ -n "$big_n" ] || exit 0
echo
echo "chain N = $big_n ($((6 * big_n + 3)) coordinates), mechc run --steps $big_steps (auto: sparse)"
sh "$here/../examples/chain.sh" "$big_n" "$tmp/big.mech" || exit 2
timed "$tmp/b0" "$tmp/big.mech" --steps 0 --csv /dev/null --stats
timed "$tmp/b" "$tmp/big.mech" --steps "$big_steps" --csv /dev/null --stats
if [ -z "$(stat "$tmp/b.err" CPU)" ]; then
    echo "  failed: $(grep -v stats "$tmp/b.err" | head -1)"
    exit 0
fi
read -r wall0 user0 sys0 rss0 < "$tmp/b0.time"
read -r wall user sys rss < "$tmp/b.time"
awk -v u0="$user0" -v y0="$sys0" -v w="$wall" -v u="$user" -v y="$sys" -v r="$rss" \
    -v c="$(stat "$tmp/b.err" CPU)" -v a="$(stat "$tmp/b.err" analysis)" -v st="$big_steps" \
    -v k="$(stat "$tmp/b.err" kernel)" \
    -v stages="$(sed -n 's/.*stats: set-up: //p' "$tmp/b0.err")" 'BEGIN {
    mb = (r == "-") ? "-" : sprintf("%.1f", r / 1024)
    su = (u0 == "-") ? "-" : sprintf("%.2f", u0 + y0)
    cpu = (u == "-") ? "-" : sprintf("%.2f", u + y)
    printf "  set-up %s s CPU (wall, by stage: %s)\n", su, stages
    printf "  %d steps: %.1f ms per step, %.1f ms CPU; one all_nz call %.2f ms; whole command wall %s s, CPU %s s; max RSS %s MB\n",
           st, a / 1e6, c / 1e6, k / 1e6, w, cpu, mb }'
