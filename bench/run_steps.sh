#!/bin/sh
# bench/run_steps.sh MECHC [FILE] [STEPS] [REPEATS] - the cost of one step of
# `mechc run`: a slider-crank revolution (examples/slider_crank.mech, t = 0..1)
# in 10 000 steps, per engine. For each engine it reports the median over
# REPEATS runs (default 5) of
#   ns per step          wall time of predictor + Newton + velocity +
#                        acceleration per step (output excluded: --csv /dev/null
#                        is written outside the timed part)
#   Newton it. per step  Newton iterations per step (the predictor's aim: < 2)
#   all ns               one call of the fused kernel (Phi, Phi_q, nu, gamma)
#   step / all           the step's cost in calls of that kernel
# taken from `mechc run --stats`. Engines that cannot run here are skipped.
set -u
if [ $# -lt 1 ]; then
    echo "usage: sh bench/run_steps.sh PATH/TO/mechc [FILE.mech] [STEPS] [REPEATS]" >&2
    exit 2
fi
mechc=$1
file=${2:-$(dirname "$0")/../examples/slider_crank.mech}
steps=${3:-10000}
repeats=${4:-5}
tmp=$(mktemp -d "${TMPDIR:-/tmp}/mechc_bench.XXXXXX") || exit 2
trap 'rm -rf "$tmp"' EXIT

median() { sort -g | awk '{ v[NR] = $1 } END { if (NR) print v[int((NR + 1) / 2)] }'; }

echo "mechc run $(basename "$file") --steps $steps: median of $repeats runs"
printf '%-8s %12s %18s %10s %11s\n' engine "ns/step" "Newton it./step" "all ns" "step/all"
for engine in jit aot generic; do
    : > "$tmp/ns"; : > "$tmp/it"; : > "$tmp/all"; : > "$tmp/ratio"
    ok=1
    i=0
    while [ $i -lt "$repeats" ]; do
        if ! "$mechc" run "$file" --steps "$steps" --engine $engine --stats --csv /dev/null \
                2> "$tmp/err"; then
            ok=0
            break
        fi
        sed -n 's/.*: \([0-9.]*\) ns per step.*/\1/p' "$tmp/err" >> "$tmp/ns"
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
    printf '%-8s %12s %18s %10s %11s\n' $engine "$(median < "$tmp/ns")" "$(median < "$tmp/it")" \
        "$(median < "$tmp/all")" "$(median < "$tmp/ratio")"
done
