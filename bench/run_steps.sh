#!/bin/sh
# bench/run_steps.sh MECHC [FILE] [STEPS] [REPEATS] - the cost of one step of
# `mechc run` (predictor + Newton + velocity + acceleration), in calls of the
# fused kernel, for the slider-crank, the four-bar, the five-bar and a chain
# of N = 10 four-bar loops (examples/chain.sh), or for FILE alone; one
# revolution (t = 0..1) in STEPS steps (default 10 000). Two measures:
#
# time, per engine, median over REPEATS runs (default 5) of `mechc run --stats`:
#   ns/step        wall time of a step (output excluded: --csv /dev/null is
#                  written outside the timed part)
#   Newton it.     Newton iterations per step (the predictor's aim: 1)
#   all ns         one call of the fused kernel (Phi, Phi_q, nu, gamma)
#   step/all       the step's cost in calls of that kernel
# instructions (AOT engine, when valgrind is installed; one run of STEPS/5
# steps under callgrind, counting only inside the runtime's step,
# mechrt_step_lup (the pattern LU, what run uses up to 100 coordinates)
# or mechrt_step (the dense LU), so deterministic where wall times on a
# shared machine are not):
#   Ir/step        instructions per step call
#   Ir/all         instructions per call of the AOT `all` kernel
#   step/all Ir    the step's cost in `all` calls, by instructions
#   kernels        the kernel calls a step makes, and their instructions
# Engines that cannot run here are skipped.
set -u
if [ $# -lt 1 ]; then
    echo "usage: sh bench/run_steps.sh PATH/TO/mechc [FILE.mech] [STEPS] [REPEATS]" >&2
    exit 2
fi
mechc=$1
here=$(dirname "$0")
steps=${3:-10000}
repeats=${4:-5}
tmp=$(mktemp -d "${TMPDIR:-/tmp}/mechc_bench.XXXXXX") || exit 2
trap 'rm -rf "$tmp"' EXIT
if [ $# -ge 2 ] && [ -n "$2" ]; then
    files=$2
else
    sh "$here/../examples/chain.sh" 10 "$tmp/chain10.mech" || exit 2
    files="$here/../examples/slider_crank.mech $here/../examples/four_bar.mech
           $here/../examples/five_bar.mech $tmp/chain10.mech"
fi

median() { sort -g | awk '{ v[NR] = $1 } END { if (NR) print v[int((NR + 1) / 2)] }'; }

# time FILE: the timed table of one mechanism
time_file() {
    printf '%-8s %12s %12s %10s %11s\n' engine "ns/step" "Newton it." "all ns" "step/all"
    for engine in jit aot generic; do
        : > "$tmp/ns"; : > "$tmp/it"; : > "$tmp/all"; : > "$tmp/ratio"
        ok=1
        i=0
        while [ $i -lt "$repeats" ]; do
            if ! "$mechc" run "$1" --steps "$steps" --engine $engine --stats --csv /dev/null \
                    2> "$tmp/err"; then
                ok=0
                break
            fi
            sed -n 's/.*of analysis: \([0-9.]*\) ns per step.*/\1/p' "$tmp/err" >> "$tmp/ns"
            sed -n 's/.*stats: \([0-9.e+-]*\) Newton iterations per step.*/\1/p' "$tmp/err" >> "$tmp/it"
            sed -n 's/.*takes \([0-9.]*\) ns: a step costs \([0-9.]*\) of them.*/\1 \2/p' "$tmp/err" > "$tmp/line"
            cut -d' ' -f1 "$tmp/line" >> "$tmp/all"
            cut -d' ' -f2 "$tmp/line" >> "$tmp/ratio"
            i=$((i + 1))
        done
        if [ $ok = 0 ]; then
            printf '%-8s (skipped: %s)\n' $engine "$(grep -m1 error "$tmp/err" | cut -c1-60)"
            continue
        fi
        printf '%-8s %12s %12s %10s %11s\n' $engine "$(median < "$tmp/ns")" "$(median < "$tmp/it")" \
            "$(median < "$tmp/all")" "$(median < "$tmp/ratio")"
    done
}

# count FILE: the instruction counts of one mechanism (AOT, callgrind)
count_file() {
    n=$((steps / 5))
    if ! command -v valgrind > /dev/null 2>&1; then
        echo "instructions: skipped (no valgrind)"
        return
    fi
    if ! valgrind --tool=callgrind --toggle-collect=mechrt_step --toggle-collect=mechrt_step_lup \
            --callgrind-out-file="$tmp/cg" "$mechc" run "$1" --steps $n --engine aot \
            --csv /dev/null > /dev/null 2>&1; then
        echo "instructions: skipped (the aot engine or valgrind failed)"
        return
    fi
    total=$(sed -n 's/^summary: //p' "$tmp/cg")
    # the kernels the step called: name, calls and instructions, per step
    kernels=$(for k in all phi jac jac_nz nu gamma; do
        set -- $(awk -v fn=mechc_aot_$k -f "$here/callgrind_calls.awk" "$tmp/cg") 0 0
        [ "$1" -gt 0 ] && echo "$k $1 $2"
    done)
    # the unit: one `all` call, from run --stats' timing loop
    if ! valgrind --tool=callgrind --toggle-collect=engine_time_all \
            --callgrind-out-file="$tmp/cg2" "$mechc" run "$1" --steps 1 --engine aot --stats \
            --csv /dev/null > /dev/null 2>&1; then
        echo "instructions: skipped (the aot engine or valgrind failed)"
        return
    fi
    set -- $(awk -v fn=mechc_aot_all -f "$here/callgrind_calls.awk" "$tmp/cg2")
    # the step runs once at t0 (h = 0) and once per step
    echo "$kernels" | awk -v total="$total" -v calls="$1" -v ir="$2" -v n="$n" '
        NF == 3 { list = list sprintf("%s%s %.2f", sep, $1, $2 / (n + 1)); sep = ", "; kir += $3 }
        END {
            step = total / (n + 1); all = ir / calls
            printf "instructions (aot, %d steps): %.0f per step, %.0f per all call: step/all %.2f\n",
                   n, step, all, step / all
            printf "  kernels per step: %s (%.0f instructions, %.0f%%)\n", list,
                   kir / (n + 1), 100 * kir / total }'
}

for f in $files; do
    echo "mechc run $(basename "$f") --steps $steps: median of $repeats runs"
    time_file "$f"
    count_file "$f"
    echo
done
