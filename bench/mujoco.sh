#!/bin/sh
# bench/mujoco.sh MECHC - mechc sim against MuJoCo (its C API) on IFToMM A01, A02 (N = 2, 40, 400) and Andrews: error, CPU time and peak memory side by side.
#
#   make bench-mujoco                                  (installs libmujoco-dev: .ci/deps bench)
#   sh bench/mujoco.sh build/mechc
#   CASES="a01 andrews" sh bench/mujoco.sh build/mechc (some cases; default all five)
#
# Each case is one problem with the same masses, lengths, gravity, initial
# state, span and output grid in both tools (mechc: examples/a01_pendulum.mech,
# examples/a02_four_bar.sh N, examples/andrews.mech; MuJoCo:
# bench/mujoco/a01.xml, bench/mujoco/a02.sh N, bench/mujoco/andrews.xml),
# and one error against the exact or reference solution, computed from
# either tool's CSV by the same code (bench/mujoco/error.sh):
#   a01      2000 s, 4000 outputs: P1's largest error over the outputs
#            (exact: Jacobi elliptic functions)
#   a02_N    20 s, 400 outputs: B0's largest error of position and velocity
#            (exact: the one-angle equation of the parallelogram branch)
#   andrews  t = 0.03: beta's relative error (the Test Set's reference)
# Runs: mechc sim at its defaults and at a hand-tuned --rtol/--atol (JIT);
# MuJoCo 2.x (bench/mujoco/mujoco_sim.c, mj_step) at several fixed steps
# with RK4 and with its implicit integrator, Newton solver, sparse
# Jacobians where MuJoCo picks them, every equality constraint at MuJoCo's
# stiffest impedance (solimp 0.9999) and the stiffest time constant that
# stays stable (solref timeconst H/2 for RK4, 2 H for implicit: H/3 and H
# diverge; refsafe off), dampratio 1. Every run is its own process under
# bench/mujoco/peak_run.c: process CPU (user + system) and peak RSS of that
# run alone; "integration" is the CPU time of the time loop alone (mechc
# sim --stats; mujoco_sim's CLOCK_PROCESS_CPUTIME_ID around its mj_step
# loop). The summary puts beside each mechc run the cheapest MuJoCo run at
# least as accurate, or else MuJoCo's most accurate run; the ratio is
# MuJoCo's CPU over mechc's. About 3 minutes of CPU (A02 N = 400 most).
# POSIX sh and awk; gcc, and MuJoCo's header and library.
set -u
mechc=${1:-build/mechc}
cases=${CASES:-a01 a02_2 a02_40 a02_400 andrews}
if [ ! -x "$mechc" ]; then
    echo "usage: sh bench/mujoco.sh MECHC   ('$mechc' is not an executable; run make first)" >&2
    exit 2
fi
if [ ! -f /usr/include/mujoco/mujoco.h ]; then
    echo "bench/mujoco.sh: MuJoCo is not installed (Debian's libmujoco-dev): make bench-mujoco installs it (sh .ci/deps bench); skipped" >&2
    exit 0
fi
root=$(cd "$(dirname "$0")/.." && pwd)
tmp=$(mktemp -d "${TMPDIR:-/tmp}/mechc_mujoco.XXXXXX") || exit 2
trap 'rm -rf "$tmp"' EXIT
gcc -std=c11 -O2 -D_DEFAULT_SOURCE -o "$tmp/mujoco_sim" "$root/bench/mujoco/mujoco_sim.c" -lmujoco -lm || exit 1
gcc -std=c11 -O2 -D_DEFAULT_SOURCE -o "$tmp/peak_run" "$root/bench/mujoco/peak_run.c" || exit 1
mj_version=$(dpkg-query -W -f='${Version}' libmujoco-dev 2>/dev/null || echo unknown)

# case_setup CASE: the problem's files, span, outputs, tuned tolerance and MuJoCo's runs
case_setup() {
    qd=""; errargs=""
    case $1 in
    a01)
        mech=$root/examples/a01_pendulum.mech; xml=$root/bench/mujoco/a01.xml
        t1=2000; steps=4000; tuned=1e-11; errcase=a01
        mjruns="rk4:1e-2 rk4:5e-3 rk4:2.5e-3 rk4:2e-3 implicit:2e-3" ;;
    a02_*)
        n=${1#a02_}
        sh "$root/examples/a02_four_bar.sh" "$n" "$tmp/$1.mech"
        sh "$root/bench/mujoco/a02.sh" "$n" > "$tmp/$1.xml"
        mech=$tmp/$1.mech; xml=$tmp/$1.xml; qd=$(sh "$root/examples/a02_four_bar.sh" --qd "$n")
        t1=20; steps=400; errcase=a02; errargs=$n
        case $n in
        2) tuned=1e-6; mjruns="rk4:1e-3 rk4:2e-4 rk4:1e-4 implicit:1e-4" ;;
        40) tuned=1e-3; mjruns="rk4:5e-3 rk4:1e-3 rk4:2e-4 implicit:1e-3" ;;
        # no implicit run: MuJoCo 2.2's implicit step factorises a dense
        # 801 x 801 matrix; at h 2e-3 it had not finished after 290 s of CPU
        *) tuned=1e-3; mjruns="rk4:5e-3 rk4:2e-3" ;;
        esac ;;
    andrews)
        mech=$root/examples/andrews.mech; xml=$root/bench/mujoco/andrews.xml
        t1=0.03; steps=1; tuned=1e-8; errcase=andrews
        mjruns="rk4:1e-5 rk4:1e-6 rk4:1e-7 implicit:1e-6" ;;
    *) echo "bench/mujoco.sh: unknown case '$1' (a01, a02_N, andrews)" >&2; exit 2 ;;
    esac
}

# peak FILE: "process_ms rss_kb" from peak_run's line in FILE
peak() { sed -n 's/^peak_run: CPU \([0-9.]*\) ms, peak RSS \([0-9]*\) kB.*/\1 \2/p' "$1"; }

# record CASE LABEL STATUS INTEGRATION_MS: one line of CASE's runs, the error from $tmp/out.csv
record() {
    if [ "$3" = 0 ]; then
        err=$(sh "$root/bench/mujoco/error.sh" "$errcase" $errargs "$tmp/out.csv")
    elif [ "$3" = 1 ]; then
        err=diverged
    else
        err="failed (exit $3)"
    fi
    echo "$2|$err|$4|$(peak "$tmp/run.err")" >> "$tmp/$1.runs"
}

# mechc_run CASE LABEL [--rtol R --atol R]
mechc_run() {
    c=$1; label=$2; shift 2
    "$tmp/peak_run" "$mechc" sim "$mech" --t1 "$t1" --steps "$steps" ${qd:+--qd "$qd"} \
        --stats --csv "$tmp/out.csv" "$@" 2> "$tmp/run.err"
    st=$?
    [ "$st" = 0 ] || tail -3 "$tmp/run.err" >&2
    record "$c" "$label" "$st" "$(sed -n 's/.* ms of integration (\([0-9.e+-]*\) ms CPU).*/\1/p' "$tmp/run.err")"
}

# mujoco_run CASE INTEGRATOR:DT
mujoco_run() {
    int=${2%%:*}; dt=${2#*:}
    tc=$(awk -v h="$dt" -v i="$int" 'BEGIN { printf "%.3g", i == "rk4" ? h / 2 : 2 * h }')
    "$tmp/peak_run" "$tmp/mujoco_sim" "$xml" --t1 "$t1" --steps "$steps" --dt "$dt" \
        --integrator "$int" --timeconst "$tc" --imp 0.9999 --csv "$tmp/out.csv" 2> "$tmp/run.err"
    st=$?
    record "$1" "MuJoCo $int, h $dt, timeconst $tc" "$st" \
        "$(sed -n 's/.*integration \([0-9.]*\) ms CPU.*/\1/p' "$tmp/run.err")"
}

echo "== mechc sim against MuJoCo $mj_version (C API), one process per run"
for c in $cases; do
    case_setup "$c"
    : > "$tmp/$c.runs"
    mechc_run "$c" "mechc sim, defaults"
    mechc_run "$c" "mechc sim, --rtol $tuned" --rtol "$tuned" --atol "$tuned"
    for r in $mjruns; do
        mujoco_run "$c" "$r"
    done
    echo
    echo "$c ($t1 s, $steps outputs):"
    echo "| run | error | integration CPU ms | process CPU ms | peak RSS kB |"
    echo "|---|---|---|---|---|"
    awk -F'|' '{ split($4, p, " "); printf "| %s | %s | %.1f | %.1f | %d |\n", $1, $2, $3, p[1], p[2] }' "$tmp/$c.runs"
done

echo
echo "== summary: each mechc run beside the cheapest MuJoCo run at least as accurate (else MuJoCo's most accurate)"
echo "| case | mechc sim | error | CPU ms (process) | peak RSS kB | MuJoCo | error | CPU ms (process) | peak RSS kB | MuJoCo CPU / mechc |"
echo "|---|---|---|---|---|---|---|---|---|---|"
for c in $cases; do
    awk -F'|' -v c="$c" '
    { split($4, p, " "); lab[NR] = $1; err[NR] = $2; cpu[NR] = $3; proc[NR] = p[1]; rss[NR] = p[2] }
    END {
        for (k = 1; k <= 2; k++) {
            best = 0; match_ = 0
            for (i = 3; i <= NR; i++) {
                if (err[i] !~ /^[0-9]/) continue
                if (!best || err[i] + 0 < err[best] + 0) best = i
                if (err[i] + 0 <= err[k] + 0 && (!match_ || cpu[i] + 0 < cpu[match_] + 0)) match_ = i
            }
            m = match_ ? match_ : best; ml = lab[m]; kl = lab[k]
            sub(/^MuJoCo /, "", ml); sub(/^mechc sim, /, "", kl)
            printf "| %s | %s | %s | %.1f (%.0f) | %d | %s%s | %s | %.1f (%.0f) | %d | %.1fx (%.1fx) |\n",
                c, kl, err[k], cpu[k], proc[k], rss[k], match_ ? "" : "never as accurate; best: ", ml,
                err[m], cpu[m], proc[m], rss[m], cpu[m] / cpu[k], proc[m] / proc[k]
        }
    }' "$tmp/$c.runs"
done
echo "(CPU: the time loop's; in brackets the whole process's, loading and compiling included)"
