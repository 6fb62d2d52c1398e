#!/bin/sh
# tests/sparse_cli.sh MECHC - `mechc run --linear`: every example run dense
# and sparse (KLU) gives the same states to 1e-10 (relative, at least
# absolute) and the same exit status, including the states written before a
# failure; a chain of 50 four-bar loops goes sparse under auto and matches
# the dense run; bad values, velocity-level rows and the generic engine are
# refused with exit 2; a singular sparse failure names its time, row and
# coordinate. gen --sparse writes PREFIX_all_nz (and only then), a C99 file
# whose all_nz agrees with phi, jac_nz, nu and gamma; the dense-Jacobian
# limit (--max-jac-entries) binds only runs that form one, and a chain of
# 1000 loops runs sparse in less address space than its dense Jacobian.
# gen --lu writes the unrolled LU and P_step (and only then, and only for
# stepped mechanisms), and the written step alone follows the
# slider-crank's closed form.
#
#   sh tests/sparse_cli.sh build/mechc
set -u
# shellcheck source=tests/lib.sh
. "$(dirname "$0")/lib.sh"
suite_begin sparse_cli "${1:-build/mechc}"

run() { run_mechc run "$@"; }

# same_csv A B [TOL]: same shape, every number within TOL (1e-10) * max(1, |a|).
same_csv() {
    awk -F, 'NR == FNR { n1 = FNR; w1 = NF; for (i = 1; i <= NF; i++) a[FNR, i] = $i; next }
        FNR == 1 { n2 = 1; if ($0 != hdr) bad = 1; next }
        { n2 = FNR; if (NF != w1) bad = 1
          for (i = 1; i <= NF; i++) { x = a[FNR, i] + 0; d = x - $i; if (d < 0) d = -d
                                      s = x < 0 ? -x : x; if (s < 1) s = 1
                                      if (!(d <= tol * s)) bad = 1 } }
        END { exit bad || n1 != n2 }' "$1" hdr="$(head -1 "$1")" tol="${3:-1e-10}" "$2"
}

# ---- every example, dense against sparse ------------------------------------
compared=0
for f in "$ex"/*.mech; do
    b=$(basename "$f" .mech)
    run "$f" --linear dense --csv "$tmp/$b.d.csv"
    rd=$rc
    run "$f" --linear sparse --csv "$tmp/$b.s.csv"
    rs=$rc
    if grep -q "does not support velocity-level rows" "$tmp/err"; then
        check "$b: velocity-level rows refused by --linear sparse with exit 2" status_is 2
        continue
    fi
    check "$b: same exit status dense ($rd) and sparse ($rs)" test "$rd" = "$rs"
    # through singular positions the directions the Jacobian loses come
    # from the prediction: there the two paths' roundings differ more
    case $b in
        a02_chain|locomotive|parallelogram_four_bar) tol=1e-6 ;;
        *) tol=1e-10 ;;
    esac
    if [ -s "$tmp/$b.d.csv" ]; then
        check "$b: dense and sparse states agree to $tol" same_csv "$tmp/$b.d.csv" "$tmp/$b.s.csv" $tol
        compared=$((compared + 1))
    fi
done
check "at least 12 examples compared (got $compared)" test "$compared" -ge 12

# ---- a chain of 50 loops (303 coordinates): auto is sparse -----------------
sh "$ex/chain.sh" 50 "$tmp/chain50.mech"
run "$tmp/chain50.mech" --steps 20 --linear dense --csv "$tmp/c.d.csv"
check "chain 50 dense: exit 0" status_is 0
run "$tmp/chain50.mech" --steps 20 --csv "$tmp/c.a.csv" --stats
check "chain 50 auto: exit 0" status_is 0
check "chain 50 auto: went sparse (KLU stats)" err_has "sparse LU (KLU)"
check "chain 50: auto (sparse) equals dense to 1e-10" same_csv "$tmp/c.d.csv" "$tmp/c.a.csv"
run "$ex/slider_crank.mech" --steps 2 --stats --csv "$tmp/sc.csv"
check "slider_crank auto: stays dense" sh -c "! grep -q KLU '$tmp/err'"

# ---- refusals ------------------------------------------------------------------
run "$ex/slider_crank.mech" --linear banded
check "--linear banded: exit 2" status_is 2
check "--linear banded: names the choices" err_matches "dense.*sparse"
run "$ex/knife_cart.mech" --linear sparse
check "knife_cart --linear sparse: exit 2" status_is 2
check "knife_cart --linear sparse: says why" err_has "velocity-level rows"
run "$ex/knife_cart.mech" --linear auto --steps 2 --csv "$tmp/k.csv"
check "knife_cart --linear auto: runs (dense)" status_is 0
run "$ex/slider_crank.mech" --linear sparse --engine generic
check "--linear sparse --engine generic: exit 2" status_is 2
check "--linear sparse --engine generic: says why" err_has "generic engine"
run "$ex/slider_crank.mech" --linear sparse --engine generic --steps 2 --linear dense \
    --csv "$tmp/g.csv"
check "the last --linear wins" status_is 0

# ---- gen --sparse: PREFIX_all_nz --------------------------------------------
run_mechc gen "$ex/four_bar.mech" --prefix fb -o "$tmp/fb.c"
check "gen: no all_nz without --sparse" sh -c "! grep -q all_nz '$tmp/fb.c'"
run_mechc gen "$ex/four_bar.mech" --prefix fb --sparse -o "$tmp/fbs.c" --header "$tmp/fbs.h"
check "gen --sparse: exit 0" status_is 0
check "gen --sparse: all_nz declared" grep -q "^void fb_all_nz(const fb_real \*q" "$tmp/fbs.h"
check "gen --sparse: all_nz defined" grep -q "^void fb_all_nz(const fb_real \*q" "$tmp/fbs.c"
check "gen --sparse: its ops in the banner" grep -q "all [0-9]*, all_nz [0-9]*" "$tmp/fbs.c"
if have cc; then
    cat > "$tmp/fbs_main.c" << 'EOF'
#include "fbs.h"
#include <math.h>
int main(void)
{
    fb_real q[FB_NQ], qd[FB_NQ], phi[FB_NR], nu[FB_NR], g[FB_NR], v[FB_NNZ];
    fb_real phi2[FB_NR], nu2[FB_NR], g2[FB_NR], v2[FB_NNZ];
    int i, bad = 0;
    for (i = 0; i < FB_NQ; i++) {
        q[i] = fb_q0[i] + 0.01 * i;
        qd[i] = 0.5 - 0.1 * i;
    }
    fb_all_nz(q, qd, 0.2, phi, v, nu, g);
    fb_phi(q, 0.2, phi2);
    fb_jac_nz(q, 0.2, v2);
    fb_nu(q, 0.2, nu2);
    fb_gamma(q, qd, 0.2, g2);
    for (i = 0; i < FB_NH; i++) bad += !(fabs(phi[i] - phi2[i]) <= 1e-12);
    for (i = 0; i < FB_NNZ; i++) bad += !(fabs(v[i] - v2[i]) <= 1e-12);
    for (i = 0; i < FB_NR; i++) bad += !(fabs(nu[i] - nu2[i]) <= 1e-12 && fabs(g[i] - g2[i]) <= 1e-12);
    return bad != 0;
}
EOF
    check "gen --sparse: compiles as C99 without warnings" \
        cc -std=c99 -pedantic -Wall -Wextra -Werror -O1 -I"$tmp" "$tmp/fbs.c" "$tmp/fbs_main.c" \
        -lm -o "$tmp/fbs_main"
    check "gen --sparse: all_nz agrees with phi, jac_nz, nu, gamma" "$tmp/fbs_main"
else
    skip "no cc: the written all_nz is not compiled"
fi

# ---- the dense-Jacobian limit binds dense runs only ---------------------------
run "$tmp/chain50.mech" --steps 4 --max-jac-entries 1000 --csv "$tmp/lim.csv"
check "chain 50, --max-jac-entries 1000, auto: runs sparse" status_is 0
run "$tmp/chain50.mech" --steps 4 --max-jac-entries 1000 --linear dense
check "... --linear dense: exit 2" status_is 2
check "... --linear dense: the limit named" err_has "more than the limit of 1000"
run "$tmp/chain50.mech" --steps 4 --max-jac-entries 1000 --engine generic
check "... --engine generic (dense only): exit 2" status_is 2
check "... --engine generic: says sparse cannot serve" err_has "the sparse path cannot serve"

# ---- no nr x nq matrix on the sparse path: 1000 loops in 250 MB of address
# space, where the dense Jacobian alone takes 288 MB (skipped where the
# build cannot start under that limit: sanitizers reserve terabytes) -------
sh "$ex/chain.sh" 1000 "$tmp/chain1000.mech"
if (ulimit -v 250000 && "$mechc" run "$ex/four_bar.mech" --steps 1 > /dev/null 2>&1); then
    (ulimit -v 250000 && "$mechc" run "$tmp/chain1000.mech" --steps 2 --linear sparse \
        --csv "$tmp/c1000.csv") > "$tmp/out" 2> "$tmp/err"
    rc=$?
    check "chain 1000 sparse within 250 MB of address space: exit 0" status_is 0
    check "chain 1000 sparse: 3 states" test "$(wc -l < "$tmp/c1000.csv")" = 4
    # the subshell waits (no exec of its last command), so the abort's
    # report goes to its stderr, not the suite's
    (ulimit -v 250000; "$mechc" run "$tmp/chain1000.mech" --steps 2 --linear dense \
        --csv /dev/null; echo $? > "$tmp/rc") > "$tmp/out" 2> "$tmp/err"
    rc=$(cat "$tmp/rc")
    check "chain 1000 dense within 250 MB: out of memory (the limit means something)" \
        test "$rc" != 0
else
    skip "the build does not start within 250 MB of address space"
fi

# ---- singular, sparse ---------------------------------------------------------
# the toggle passes on the sparse path too (the dense rank-revealing
# fallback, tests/test_branch.c); a redundant row at t0 names KLU's pivot
run "$ex/slider_crank_toggle.mech" --linear sparse --stats
check "toggle sparse: exit 0, through t = 0.25" status_is 0
check "toggle sparse: the fallback is counted" err_has "where KLU found the Jacobian singular"
run "$ex/parallelogram_redundant.mech" --linear sparse
check "redundant sparse: exit 1" status_is 1
check "redundant sparse: at t = 0" err_matches "error: t = 0: "
check "redundant sparse: singular" err_has "singular Jacobian"
check "redundant sparse: names the pivot's row and coordinate" \
    err_matches "sparse LU found no pivot for [a-z0-9]*\.[a-z]* in row [A-Z0-9]*\.[a-z]*"

# ---- gen --lu: the unrolled LU and step -----------------------------------------
# written only with --lu and for stepped mechanisms; the written P_step alone
# (no runtime) turns the slider-crank along its closed form
check "gen: no lu without --lu" sh -c "! grep -q lu_factor '$tmp/fb.c'"
run_mechc gen "$ex/knife_cart.mech" --lu -o "$tmp/kc.c"
check "gen --lu, velocity rows: exit 0, no lu" sh -c "[ $rc = 0 ] && ! grep -q lu_factor '$tmp/kc.c'"
run_mechc gen "$ex/slider_crank.mech" --prefix sc --lu -o "$tmp/sclu.c" --header "$tmp/sclu.h"
check "gen --lu: exit 0" status_is 0
check "gen --lu: factor, solve and step declared" sh -c "grep -q '^int sc_lu_factor(' '$tmp/sclu.h' \
    && grep -q '^void sc_lu_solve(' '$tmp/sclu.h' && grep -q '^int sc_step(' '$tmp/sclu.h' \
    && grep -q '^#define SC_LU_NSLOTS [0-9]' '$tmp/sclu.h'"
if have cc; then
    cat > "$tmp/sclu_main.c" << 'EOF'
#include "sclu.h"
#include <math.h>
#include <stdio.h>
int main(void)
{
    sc_real s[3 * SC_NQ], tol[4] = {1e-10, 1e-10, 1e-12, 1e4}, out[2], worst = 0;
    int i, iout[2], k;
    for (i = 0; i < 3 * SC_NQ; i++)
        s[i] = i < SC_NQ ? sc_q0[i] : 0;
    for (k = 0; k <= 100; k++) {
        double t = k == 0 ? 0 : (k - 1) / 100.0, h = k == 0 ? 0 : 0.01, th;
        if (sc_step(s, s + SC_NQ, s + 2 * SC_NQ, t, h, tol, 25, out, iout) != 0)
            return 2;
        th = 2 * 3.141592653589793 * (t + h);   /* slider.x is q[6] */
        th = 0.1 * cos(th) + sqrt(0.09 - 0.01 * sin(th) * sin(th)) - s[6];
        worst = fabs(th) > worst ? fabs(th) : worst;
    }
    printf("%.3g\n", worst);
    return worst < 1e-9 ? 0 : 1;
}
EOF
    check "gen --lu: the written step alone follows the closed form to 1e-9" \
        sh -c "cc -std=c99 -O2 -I'$tmp' -o '$tmp/sclu_main' '$tmp/sclu_main.c' '$tmp/sclu.c' -lm \
               && '$tmp/sclu_main'"
fi

suite_end
