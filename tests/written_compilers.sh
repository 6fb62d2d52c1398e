#!/bin/sh
# tests/written_compilers.sh MECHC - the written file computes what the JIT
# computes under every compiler that builds it: tcc, gcc -O0 and gcc -O2.
#
#   sh tests/written_compilers.sh build/mechc
#
# A written file picks its trig when it is compiled (libm's sin and cos
# under tcc and without optimisation, its own sincos pair otherwise) and
# zero-fills the dense Jacobian with memset (or, optimised and small, with
# stores). For four-bar (the default direct and --jac spread Jacobian), slider-crank,
# all_statements and a chain of 20 loops (both Jacobians; a sincos pair
# called out of line under gcc -O2), each build is linked with a driver
# that evaluates every function at a state near q0 with velocities, the
# Jacobian outputs first filled with NaN, and prints Phi, Phi_q, nu and
# gamma; these must equal `mechc eval --json` (the JIT) at that state to
# 1e-12 (relative above 1). The driver also requires jac from jac_nz,
# all and jac to agree exactly. Checks too that the trig is the one chosen:
# the sincos table is in the gcc -O2 object and not in the others, and the
# pair is always_inline in the four-bar's file, noinline in chain_20's, and
# that values used alone cost only their libm calls under tcc and gcc -O0
# (objdump, x86-64).
. "$(dirname "$0")/lib.sh"
suite_begin written_compilers "${1:-build/mechc}"
if [ -n "${MECHC_SKIP_GCC_ONLY:-}" ]; then
    skip "MECHC_SKIP_GCC_ONLY (make check-asan, check-valgrind): every check here builds the written C"
    suite_end
    exit
fi

cat > "$tmp/driver.c" <<'EOF'
/* Evaluates the written file m at q0 + 0.01 (i mod 5), qd 0.1 (i mod 7 - 3), t 0.3. */
#include <math.h>
#include <stdio.h>
#include "m.h"
static m_real q[M_NQ], qd[M_NQ], phi[M_NH + 1], jac[M_NR * M_NQ], jac2[M_NR * M_NQ];
static m_real vals[M_NNZ], nu[M_NR], gamma_[M_NR], phi2[M_NH + 1], nu2[M_NR], gamma2[M_NR];
int main(void)
{
    int i, bad = 0;
    m_real t = 0.3;
    for (i = 0; i < M_NQ; i++) {
        q[i] = m_q0[i] + 0.01 * (i % 5);
        qd[i] = 0.1 * (i % 7 - 3);
    }
    for (i = 0; i < M_NR * M_NQ; i++)
        jac[i] = jac2[i] = NAN;
    m_phi(q, t, phi);
    m_jac(q, t, jac);
    m_jac_nz(q, t, vals);
    m_nu(q, t, nu);
    m_gamma(q, qd, t, gamma_);
    m_all(q, qd, t, phi2, jac2, nu2, gamma2);
    for (i = 0; i < M_NR * M_NQ; i++)
        bad |= jac[i] != jac2[i];
    for (i = 0; i < M_NNZ; i++)
        bad |= vals[i] != jac[m_jac_row[i] * M_NQ + m_jac_col[i]];
    for (i = 0; i < M_NR; i++)
        bad |= nu[i] != nu2[i] || gamma_[i] != gamma2[i] || (i < M_NH && phi[i] != phi2[i]);
    if (bad) {
        fprintf(stderr, "jac, jac_nz and all disagree\n");
        return 1;
    }
    for (i = 0; i < M_NQ; i++)
        printf("%s%.17g", i ? "," : "q ", q[i]);
    for (i = 0; i < M_NQ; i++)
        printf("%s%.17g", i ? "," : "\nqd ", qd[i]);
    printf("\n");
    for (i = 0; i < M_NH; i++)
        printf("%.17g\n", phi[i]);
    for (i = 0; i < M_NR * M_NQ; i++)
        printf("%.17g\n", jac[i]);
    for (i = 0; i < M_NR; i++)
        printf("%.17g\n", nu[i]);
    for (i = 0; i < M_NR; i++)
        printf("%.17g\n", gamma_[i]);
    return 0;
}
EOF

# values JSON: the numbers of phi, jac, nu and gamma, one a line, in order
values() {
    tr -d '\n' < "$1" | awk '{
        n = split("phi jac nu gamma", key, " ")
        for (k = 1; k <= n; k++) {
            if (!match($0, "\"" key[k] "\": \\[[^\"]*\\]")) { print "no " key[k] > "/dev/stderr"; exit 1 }
            s = substr($0, RSTART + length(key[k]) + 4, RLENGTH - length(key[k]) - 4)
            gsub(/[][ ]/, "", s)
            m = split(s, v, ",")
            for (i = 1; i <= m; i++) if (v[i] != "") print v[i]
        }
    }'
}

# same_values A B: the same count of numbers, each within 1e-12 (relative above 1)
same_values() {
    paste -d ' ' "$1" "$2" | awk '
        NF != 2 { print "count differs at line " NR; bad = 1; exit }
        { d = $1 - $2; if (d < 0) d = -d; m = $2 < 0 ? -$2 : $2; if (m < 1) m = 1
          if (!(d <= 1e-12 * m)) { print "line " NR ": " $1 " written, " $2 " JIT"; bad = 1 } }
        END { exit bad }'
}

sh "$ex/chain.sh" 20 "$tmp/chain_20.mech"
cases="four_bar:$ex/four_bar.mech:
four_bar_spread:$ex/four_bar.mech:--jac spread
slider_crank:$ex/slider_crank.mech:
all_statements:$ex/all_statements.mech:
chain_20:$tmp/chain_20.mech:
chain_20_spread:$tmp/chain_20.mech:--jac spread"
compilers="gcc_O2|gcc -std=c99 -O2 -Wall -Wextra -Wpedantic -Werror
gcc_O0|gcc -std=c99 -O0 -Wall -Wextra -Wpedantic -Werror"
if have tcc; then
    compilers="$compilers
tcc|tcc -Wall -Werror"
else
    skip "tcc is missing: its builds"
fi
if ! have gcc; then
    skip "gcc is missing"
    suite_end
    exit
fi

echo "$cases" | while IFS=: read -r name mech opts; do
    d=$tmp/$name
    mkdir -p "$d"
    # shellcheck disable=SC2086 # opts is a list of options
    if ! "$mechc" gen "$mech" --prefix m $opts -o "$d/m.c" --header "$d/m.h" 2> "$tmp/err"; then
        echo "bad $name: gen"
        continue
    fi
    gcc -std=c99 -O2 -I"$d" -c "$tmp/driver.c" -o "$d/driver.o" 2> "$tmp/err" || { echo "bad $name: driver"; continue; }
    echo "$compilers" | while IFS='|' read -r cname cc; do
        # shellcheck disable=SC2086 # cc is a command with options
        if ! $cc -I"$d" -c "$d/m.c" -o "$d/m-$cname.o" > "$tmp/err" 2>&1; then
            echo "bad $name ($cname): compile: $(head -n 3 "$tmp/err" | tr '\n' ' ')"
            continue
        fi
        if ! gcc "$d/driver.o" "$d/m-$cname.o" -lm -o "$d/run-$cname" 2> "$tmp/err" ||
           ! "$d/run-$cname" > "$d/out-$cname" 2> "$tmp/err"; then
            echo "bad $name ($cname): run: $(head -n 3 "$tmp/err" | tr '\n' ' ')"
            continue
        fi
        echo "ok"
        qs=$(sed -n 's/^q //p' "$d/out-$cname")
        qds=$(sed -n 's/^qd //p' "$d/out-$cname")
        # the JIT's values at that state, once per case: every compiler's
        # driver prints the same state (jit_key lives for the case's loop)
        # shellcheck disable=SC2086
        if { [ "${jit_key:-}" = "$qs $qds" ] ||
             { "$mechc" eval "$mech" --q "$qs" --qd "$qds" --t 0.3 --json > "$d/jit.json" 2> "$tmp/err" &&
               values "$d/jit.json" > "$d/jit.txt" && jit_key="$qs $qds"; }; } &&
           sed '1,2d' "$d/out-$cname" > "$d/got.txt" &&
           same_values "$d/got.txt" "$d/jit.txt" > "$tmp/why"; then
            echo "ok"
        else
            echo "bad $name ($cname): values differ from the JIT's: $(head -n 3 "$tmp/why" | tr '\n' ' ')"
        fi
        # the trig chosen: the sincos pair's table only where optimising
        if grep -q m_sincos_table "$d/m.c"; then
            table=$(nm "$d/m-$cname.o" | grep -c m_sincos_table)
            case $cname in
                gcc_O2) want=1 ;;
                *) want=0 ;;
            esac
            if [ "$table" = "$want" ]; then echo "ok"; else echo "bad $name ($cname): sincos table symbols $table, expected $want"; fi
        fi
    done
done > "$tmp/results"

while read -r verdict rest; do
    if [ "$verdict" = ok ]; then ok; else : > "$tmp/err"; bad "$rest"; fi
done < "$tmp/results"
# the pair is inlined on x86-64 in small files only (96 calls in chain_20 since trig is computed once per function)
check "four_bar: the sincos pair always_inline on x86-64" \
    grep -q '^#define M_TRIG static inline __attribute__((always_inline))$' "$tmp/four_bar/m.c"
check "chain_20: one noinline copy of the sincos pair" \
    grep -q '^#define M_TRIG static __attribute__((noinline))$' "$tmp/chain_20/m.c"
# values used alone: Phi of a driver y = sin t needs no cos (lone), of
# y = sin t + cos 2t neither cos t nor sin 2t (lone2, one two-angle call).
# Under tcc and gcc -O0 m_phi makes only the libm calls of the values used,
# not the pair's; under gcc -O2 the inlined pair keeps no cos work for lone
# (no cos in its rare case)
printf 'point m x = 3 y = 1\nconstraint line: m.x - 3 = 0\ndriver d: m.y = sin(t)\n' > "$tmp/lone.mech"
printf 'point m x = 3 y = 1\nconstraint line: m.x - 3 = 0\ndriver d: m.y = sin(t) + cos(2*t)\n' > "$tmp/lone2.mech"
# phi_calls OBJECT: the functions m_phi of OBJECT calls, on one line, sorted
phi_calls() {
    objdump -dr "$1" | awk '/^[0-9a-f]+ <m_phi>:/ { p = 1; next } /^[0-9a-f]+ </ { p = 0 }
        p && /R_X86_64_PLT32/ { sub(/-0x4$/, "", $NF); print $NF }' | sort | tr '\n' ' '
}
if ! have objdump || [ "$(uname -m)" != x86_64 ]; then
    skip "objdump or x86-64 is missing: the calls of values used alone"
elif "$mechc" gen "$tmp/lone.mech" --prefix m -o "$tmp/lone.c" 2> "$tmp/err" &&
     "$mechc" gen "$tmp/lone2.mech" --prefix m -o "$tmp/lone2.c" 2> "$tmp/err"; then
    check "lone: written as m_sincos_s" grep -q '^    m_sincos_s(t, &u0, &w0);$' "$tmp/lone.c"
    check "lone2: written as m_sincos2_some" \
        grep -q '^    m_sincos2_some(2.0 \* t, t, &w0, &u0, &u1, &w1, 6);$' "$tmp/lone2.c"
    echo "$compilers" | while IFS='|' read -r cname cc; do
        for m in lone lone2; do
            # shellcheck disable=SC2086 # cc is a command with options
            $cc -c "$tmp/$m.c" -o "$tmp/$m-$cname.o" 2> "$tmp/err" || { echo "bad $m-$cname"; continue; }
            calls=$(phi_calls "$tmp/$m-$cname.o")
            case $cname:$m in
                gcc_O2:lone) want="sin " ;;
                gcc_O2:*) continue ;;
                *:lone) want="sin " ;;
                *) want="cos sin " ;;
            esac
            if [ "$calls" = "$want" ]; then echo "ok $m-$cname"; else echo "bad $m-$cname: m_phi calls $calls"; fi
        done
    done > "$tmp/lone"
    while read -r verdict rest; do
        if [ "$verdict" = ok ]; then ok; else bad "values used alone, $rest"; fi
    done < "$tmp/lone"
else
    bad "lone: gen"
fi
# every case and compiler gave its 3 results (all 6 cases use sin/cos)
n=$(grep -c . "$tmp/results")
want=$(($(echo "$compilers" | grep -c .) * 6 * 3))
if [ "$n" = "$want" ]; then ok; else bad "$n results, expected $want"; fi
suite_end
