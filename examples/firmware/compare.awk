# compare.awk - compares the firmware example's output on a target with the
# host run of the same program.
#
#   awk -v rtol=1e-12 -f compare.awk HOST.out TARGET.out
#
# Both files must have the same lines. Lines starting with '#' must be
# identical. Other lines are "step t x xd xdd": the same number of fields,
# the step numbers equal, and every other field within rtol relative to
# the size of its column: |a - b| <= rtol * max(|a|, |b|, max |column|),
# where max |column| is taken over the host file. The column scale keeps
# values that pass through zero (the slider's velocity at the dead
# centres, 1e-17 in double, 4e-8 in float) from demanding digits that
# rounding never gave them. Prints each mismatch and a summary line; the
# exit status is 1 on any mismatch.

function abs(x) { return x < 0 ? -x : x }

BEGIN {
    if (rtol == "") rtol = 1e-12
    bad = 0; worst = 0; nhost = 0; ntarget = 0
}

# First file: the host's output, kept whole.
NR == FNR {
    host[FNR] = $0
    nhost = FNR
    if ($0 !~ /^#/)
        for (i = 2; i <= NF; i++)
            if (abs($i + 0) > scale[i]) scale[i] = abs($i + 0)
    next
}

# Second file: the target's output, line by line against the host's.
{
    n = ntarget = FNR
    if (n > nhost) { mismatch(n, "extra line: " $0); next }
    h = host[n]
    if (h ~ /^#/ || $0 ~ /^#/) {
        if (h != $0) mismatch(n, "host '" h "' target '" $0 "'")
        next
    }
    nf = split(h, hf, " ")
    if (nf != NF) { mismatch(n, "host has " nf " fields, target " NF); next }
    if (hf[1] != $1) { mismatch(n, "step " hf[1] " against " $1); next }
    for (i = 2; i <= NF; i++) {
        a = hf[i] + 0; b = $i + 0
        s = abs(a) > abs(b) ? abs(a) : abs(b)
        if (scale[i] > s) s = scale[i]
        if (abs(a - b) > rtol * s)
            mismatch(n, sprintf("field %d: host %s target %s (|diff| %.3g > %.3g)",
                                i, hf[i], $i, abs(a - b), rtol * s))
        else if (abs(a - b) / (s > 0 ? s : 1) > worst)
            worst = abs(a - b) / (s > 0 ? s : 1)
    }
}

function mismatch(line, what) {
    bad++
    if (bad <= 10) printf "compare: line %d: %s\n", line, what
}

END {
    if (ntarget < nhost) mismatch(ntarget + 1, "target output ends early")
    if (nhost == 0) mismatch(1, "no host output")
    printf "compare: %d lines, %d mismatches, worst relative difference %.3g (rtol %g)\n",
           nhost, bad, worst, rtol
    exit bad > 0
}
