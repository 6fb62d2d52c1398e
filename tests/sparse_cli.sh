#!/bin/sh
# tests/sparse_cli.sh MECHC - `mechc run --linear`: every example run dense
# and sparse (KLU) gives the same states to 1e-10 (relative, at least
# absolute) and the same exit status, including the states written before a
# failure, velocity-level rows included (KLU for the velocities,
# SuiteSparseQR's minimum-norm projection); trains of knife-edge trailers
# (examples/train.sh) against the N-trailer equations integrated here, dense
# against sparse, and auto going sparse at 903 coordinates; a chain of 50
# four-bar loops goes sparse under auto and matches the dense run; bad
# values and the generic engine are refused with exit 2; a singular sparse
# failure names its time, row and coordinate. gen --sparse writes
# PREFIX_all_nz (and only then), a C99 file whose all_nz agrees with phi,
# jac_nz, nu and gamma; the dense-Jacobian limit (--max-jac-entries) binds
# only runs that form one, and a chain of 1000 loops runs sparse in less
# address space than its dense Jacobian.
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
# A's header line read by the shell (a head process costs 5 to 8 ms of CPU).
same_csv() {
    csv_hdr=
    IFS= read -r csv_hdr < "$1"
    awk -F, 'NR == FNR { n1 = FNR; w1 = NF; for (i = 1; i <= NF; i++) a[FNR, i] = $i; next }
        FNR == 1 { n2 = 1; if ($0 != hdr) bad = 1; next }
        { n2 = FNR; if (NF != w1) bad = 1
          for (i = 1; i <= NF; i++) { x = a[FNR, i] + 0; d = x - $i; if (d < 0) d = -d
                                      s = x < 0 ? -x : x; if (s < 1) s = 1
                                      if (!(d <= tol * s)) bad = 1 } }
        END { exit bad || n1 != n2 }' "$1" hdr="$csv_hdr" tol="${3:-1e-10}" "$2"
}

# ---- every example, dense against sparse ------------------------------------
compared=0
for f in "$ex"/*.mech; do
    b=${f##*/}; b=${b%.mech}
    run "$f" --linear dense --csv "$tmp/$b.d.csv"
    rd=$rc
    run "$f" --linear sparse --csv "$tmp/$b.s.csv"
    rs=$rc
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
check "slider_crank auto: stays dense" err_lacks KLU

# ---- run --sens on the sparse path: KLU of Phi_q, the dense path's numbers ----
# a chain of 20 loops with the drive's amplitude, its speed and a ground
# pivot designed (123 coordinates: auto is sparse)
sh "$ex/chain.sh" 20 "$tmp/chain20.mech"
sed 's/^param amp .*/design amp = 0.5/; s/^param omega .*/design omega = 2*pi\ndesign gx = 1/
     s/^revolute g1: ground(1, 0)/revolute g1: ground(gx, 0)/' "$tmp/chain20.mech" > "$tmp/chain20d.mech"
run "$tmp/chain20d.mech" --steps 10 --sens --linear dense --csv "$tmp/cs.d.csv" --stats
check "chain 20 --sens dense: exit 0" status_is 0
check "chain 20 --sens dense: the dense LU" err_lacks 'KLU of Phi_q'
run "$tmp/chain20d.mech" --steps 10 --sens --csv "$tmp/cs.a.csv" --stats
check "chain 20 --sens auto: exit 0" status_is 0
check "chain 20 --sens auto: sensitivities by KLU" \
    err_has "sensitivities to 3 design parameters (KLU of Phi_q)"
check "chain 20 --sens: the columns are there" \
    sh -c "head -1 '$tmp/cs.a.csv' | grep -q ',d(dd(rod20.phi))/d(gx)'"
check "chain 20 --sens: sparse equals dense to 1e-9" same_csv "$tmp/cs.d.csv" "$tmp/cs.a.csv" 1e-9
# the dense path solves with the run's own LU at every state (a pattern LU
# up to ANALYSIS_DENSE_MAX_NQ coordinates), the sparse path with KLU's
run "$ex/freudenstein.mech" --steps 10 --sens --csv "$tmp/fr.d.csv" --stats
check "freudenstein --sens: the run's LU at every state" err_has "reused at 11 of 11"
check "freudenstein --sens: the ratio less the clock() span" err_has "run --sens costs"
run "$ex/freudenstein.mech" --steps 10 --sens --linear sparse --csv "$tmp/fr.s.csv" --stats
check "freudenstein --sens sparse: KLU's own" err_has "(KLU of Phi_q): "
check "freudenstein --sens sparse: no run's LU" err_has "reused at 0 of 11"
check "freudenstein --sens: sparse (phi_p_nz) equals dense to 1e-12" \
    same_csv "$tmp/fr.d.csv" "$tmp/fr.s.csv" 1e-12

# ---- refusals ------------------------------------------------------------------
run "$ex/slider_crank.mech" --linear banded
check "--linear banded: exit 2" status_is 2
check "--linear banded: names the choices" err_matches "dense.*sparse"
run "$ex/knife_cart.mech" --linear sparse --steps 2 --stats --csv "$tmp/k.csv"
check "knife_cart --linear sparse: runs" status_is 0
check "knife_cart --linear sparse: velocity solves by KLU" err_has "sparse LU (KLU)"
run "$ex/knife_cart.mech" --linear auto --steps 2 --stats --csv "$tmp/k.csv"
check "knife_cart --linear auto: runs dense" err_lacks KLU
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

# ---- the size limits refuse larger mechanisms with the line, exit 2 ---------
sh "$ex/chain.sh" 1000 "$tmp/chain1000.mech"
run "$tmp/chain1000.mech" --steps 1 --max-coords 5000 --csv /dev/null
check "chain 1000 past --max-coords 5000: exit 2" status_is 2
check "... the coordinate that passes it, with line and column" \
    err_matches "chain1000.mech:4196:6: error: too many coordinates (the limit is 5000)"
run "$tmp/chain1000.mech" --steps 1 --max-rows 5000 --csv /dev/null
check "chain 1000 past --max-rows 5000: exit 2" status_is 2
check "... the row that passes it" err_matches "chain1000.mech:4199:1: error: too many rows"

# ---- no nr x nq matrix on the sparse path: 1000 loops in 250 MB of address
# space, where the dense Jacobian alone takes 288 MB (skipped where the
# build cannot start under that limit: sanitizers reserve terabytes) -------
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

# ---- velocity-level rows at scale: a tractor and trailers on knife edges ----
# train_of N: N + 3 velocity-level rows, 2 N holonomic (the pins)
# trailer_ref N T: the headings and axle positions of the last trailer at T
# from the N-trailer equations, integrated by RK4 here (independent of
# mechc): d(theta_i)/dt = v_{i-1} / L sin(theta_{i-1} - theta_i),
# v_i = v_{i-1} cos(theta_{i-1} - theta_i), axle_i = axle_{i-1} - L e_i.
trailer_ref() {
    awk -v n="$1" -v t1="$2" 'function f(tt, th, d,   i, vp) {
            d[0] = 0; vp = 2; th0 = pi / 2 + 0.5 * tt
            for (i = 1; i <= n; i++) {
                prevth = i == 1 ? th0 : th[i - 1]
                d[i] = vp * sin(prevth - th[i]); vp = vp * cos(prevth - th[i])
            }
        }
        BEGIN { pi = atan2(0, -1); steps = 4000; h = t1 / steps
            for (i = 1; i <= n; i++) th[i] = pi / 2
            for (s = 0; s < steps; s++) {
                tt = s * h
                f(tt, th, k1); for (i = 1; i <= n; i++) y[i] = th[i] + h / 2 * k1[i]
                f(tt + h / 2, y, k2); for (i = 1; i <= n; i++) y[i] = th[i] + h / 2 * k2[i]
                f(tt + h / 2, y, k3); for (i = 1; i <= n; i++) y[i] = th[i] + h * k3[i]
                f(tt + h, y, k4)
                for (i = 1; i <= n; i++) th[i] += h / 6 * (k1[i] + 2 * k2[i] + 2 * k3[i] + k4[i])
            }
            x = 4 * cos(0.5 * t1); y0 = 4 * sin(0.5 * t1)
            for (i = 1; i <= n; i++) { x -= cos(th[i]); y0 -= sin(th[i]) }
            printf "%.15g %.15g %.15g\n", x, y0, th[n] }'
}
# near CSV VALUES: the last row's last three columns within 1e-8 of VALUES
near_last() {
    tail -1 "$1" | awk -F, -v ref="$2" '{ split(ref, r, " "); bad = 0
        for (k = 1; k <= 3; k++) { d = $(NF - 3 + k) - r[k]; if (d < 0) d = -d; if (!(d <= 1e-8)) bad = 1 }
        exit bad }'
}
sh "$ex/train.sh" 3 "$tmp/train3.mech"
run "$tmp/train3.mech" --t1 4 --steps 8 --csv "$tmp/tr3.csv"
check "train 3: exit 0" status_is 0
cut -d, -f1-13 "$tmp/tr3.csv" > "$tmp/tr3q.csv"
check "train 3: the last trailer's axle and heading at t = 4 as the N-trailer equations'" \
    near_last "$tmp/tr3q.csv" "$(trailer_ref 3 4)"
sh "$ex/train.sh" 60 "$tmp/train60.mech"
run "$tmp/train60.mech" --t1 2 --steps 4 --linear dense --csv "$tmp/tr60.d.csv"
check "train 60 dense: exit 0" status_is 0
run "$tmp/train60.mech" --t1 2 --steps 4 --linear sparse --csv "$tmp/tr60.s.csv"
check "train 60 sparse: exit 0" status_is 0
check "train 60: dense and sparse agree to 1e-10" same_csv "$tmp/tr60.d.csv" "$tmp/tr60.s.csv"
sh "$ex/train.sh" 300 "$tmp/train300.mech"
run "$tmp/train300.mech" --t1 2 --steps 4 --stats --csv "$tmp/tr300.csv"
check "train 300 (903 coordinates) auto: exit 0" status_is 0
check "train 300 auto: went sparse (KLU stats)" err_has "sparse LU (KLU)"
# the bodies ahead of a trailer do not feel it: trailer 3 moves as in a train of 3
cut -d, -f1-13 "$tmp/tr300.csv" > "$tmp/tr300q.csv"
check "train 300: trailer 3 at t = 2 as the N-trailer equations'" \
    near_last "$tmp/tr300q.csv" "$(trailer_ref 3 2)"
cut -d, -f1-904 "$tmp/tr300.csv" > "$tmp/tr300q.csv"
check "train 300: the last trailer at t = 2 as the N-trailer equations'" \
    near_last "$tmp/tr300q.csv" "$(trailer_ref 300 2)"

# ---- a scissor lift of N stages (examples/scissor.sh) -------------------------
# deck_closed N CSV: every state's platform against the closed form in the
# driver, deck.y = N sin(theta), theta = 0.6 + 0.4 sin(2 pi t), with its
# rate and acceleration, and deck.x = 0 (positions 1e-9, rates 1e-7,
# accelerations 1e-5, absolute)
deck_closed() {
    awk -F, -v n="$1" 'NR == 1 { for (i = 1; i <= NF; i++) c[$i] = i; next }
        { t = $1; pi = atan2(0, -1); th = 0.6 + 0.4 * sin(2 * pi * t)
          thd = 0.8 * pi * cos(2 * pi * t); thdd = -1.6 * pi * pi * sin(2 * pi * t)
          e[1] = $(c["deck.y"]) - n * sin(th); e[2] = $(c["deck.x"])
          e[3] = $(c["d(deck.y)"]) - n * cos(th) * thd
          e[4] = $(c["dd(deck.y)"]) - n * (cos(th) * thdd - sin(th) * thd * thd)
          tol[1] = tol[2] = 1e-9; tol[3] = 1e-7; tol[4] = 1e-5
          for (k = 1; k <= 4; k++) if (!((e[k] < 0 ? -e[k] : e[k]) <= tol[k])) bad = 1
          rows++ }
        END { exit bad || rows != 101 }' "$2"
}
# the generators' N: bounded by what the default --max-coords admits, exit 2
sh "$ex/scissor.sh" 99999999999 "$tmp/sc_huge.mech" 2> "$tmp/err"
rc=$?
check "scissor.sh 99999999999: exit 2" status_is 2
check "scissor.sh 99999999999: names the bound" \
    err_has "gives more than 200000 coordinates (mechc's default --max-coords): N is at most 33332"
check "scissor.sh 99999999999: no file written" test ! -s "$tmp/sc_huge.mech"
sh "$ex/train.sh" 66666 "$tmp/tr_big.mech" 2> "$tmp/err"
rc=$?
check "train.sh 66666 (200001 coordinates): exit 2" status_is 2
check "train.sh 66666: names its bound" err_has "N is at most 66665"
# a02_four_bar.sh took any N (2.4 GB a minute); 6N + 3 coordinates as chain.sh
for a in "99999999999 $tmp/a02_huge.mech" "33333 $tmp/a02_huge.mech" "--qd 33333"; do
    # shellcheck disable=SC2086 # the arguments split on purpose
    sh "$ex/a02_four_bar.sh" $a > "$tmp/out" 2> "$tmp/err"
    rc=$?
    check "a02_four_bar.sh $a: exit 2" status_is 2
    check "a02_four_bar.sh $a: names the bound" \
        err_has "gives more than 200000 coordinates (mechc's default --max-coords): N is at most 33332"
    check "a02_four_bar.sh $a: nothing written" sh -c '[ ! -s "$1" ] && [ ! -s "$2" ]' _ "$tmp/out" "$tmp/a02_huge.mech"
done
sh "$ex/a02_four_bar.sh" --qd 33332 > "$tmp/out" 2> "$tmp/err"
rc=$?
check "a02_four_bar.sh --qd 33332 (the bound): exit 0" status_is 0
sh "$ex/a02_four_bar.sh" 0 > "$tmp/out" 2> "$tmp/err"
rc=$?
check "a02_four_bar.sh 0: the usage, exit 2" sh -c "[ $rc = 2 ] && grep -q 'positive integer' '$tmp/err'"
sh "$ex/chain.sh" 0 "$tmp/c0.mech" 2> "$tmp/err"
rc=$?
check "chain.sh 0: the usage, exit 2" sh -c "[ $rc = 2 ] && grep -q 'positive integer' '$tmp/err'"
sh "$ex/scissor.sh" 5 "$tmp/sc5.mech"
run "$tmp/sc5.mech" --csv "$tmp/sc5.csv"
check "scissor 5: exit 0" status_is 0
check "scissor 5: the platform at every state as N sin(theta)" deck_closed 5 "$tmp/sc5.csv"
sh "$ex/scissor.sh" 20 "$tmp/sc20.mech"
run "$tmp/sc20.mech" --linear dense --steps 20 --csv "$tmp/sc20.d.csv"
run "$tmp/sc20.mech" --linear sparse --steps 20 --csv "$tmp/sc20.s.csv"
check "scissor 20: dense and sparse agree to 1e-10" same_csv "$tmp/sc20.d.csv" "$tmp/sc20.s.csv"
sh "$ex/scissor.sh" 200 "$tmp/sc200.mech"
run "$tmp/sc200.mech" --stats --csv "$tmp/sc200.csv"
check "scissor 200 (1203 coordinates): exit 0, sparse" err_has "sparse LU (KLU)"
check "scissor 200: the platform at every state as N sin(theta)" deck_closed 200 "$tmp/sc200.csv"

# ---- check on the sparse path ------------------------------------------------
# chain N = 1200 (7203 coordinates, past the default dense-Jacobian limit):
# auto checks the Jacobian's nonzeros; --linear dense is refused at the limit
sh "$ex/chain.sh" 1200 "$tmp/c1200.mech"
run_mechc check "$tmp/c1200.mech" --no-aot --samples 3
check "check chain 1200: exit 0" status_is 0
check "check chain 1200: sparse" out_has "sparse: the Jacobian's 24005 nonzeros"
check "check chain 1200: assembled (KLU)" out_has "around the configuration assembled at t = 0"
check "check chain 1200: the verdict" out_has "ok: every comparison is within its tolerance"
run_mechc check "$tmp/c1200.mech" --no-aot --linear dense
check "check chain 1200 --linear dense: exit 2" status_is 2
check "check chain 1200 --linear dense: the limit named" \
    err_has "the dense Jacobian would have 51883209 entries, more than the limit of 50000000"
sh "$ex/train.sh" 60 "$tmp/train60.mech"
run_mechc check "$tmp/train60.mech" --no-aot --samples 3 --linear sparse
check "check train 60 --linear sparse (velocity rows by groups of qd): exit 0" status_is 0

# ---- singular, sparse ---------------------------------------------------------
# the toggle passes on the sparse path too (the dense rank-revealing
# fallback, tests/test_qr_rank.c); a redundant row at t0 names KLU's pivot
run "$ex/slider_crank_toggle.mech" --linear sparse --stats
check "toggle sparse: exit 0, through t = 0.25" status_is 0
check "toggle sparse: the fallback is counted" err_has "where KLU found the Jacobian singular"
run "$ex/parallelogram_redundant.mech" --linear sparse
check "redundant sparse: exit 1" status_is 1
check "redundant sparse: at t = 0" err_matches "error: t = 0: "
check "redundant sparse: singular" err_has "singular Jacobian"
check "redundant sparse: names the pivot's row and coordinate" \
    err_matches "sparse LU found no pivot for [a-z0-9]*\.[a-z]* in row [A-Z0-9]*\.[a-z]*"
# velocity-level rows that repeat each other: KLU's failing pivot named too
cat > "$tmp/ksing.mech" << 'EOF'
mechanism ksing
body cart x = 1  y = 0  phi = pi/2
knife  blade: cart axis(1, 0)
driver side:  der(cart.y)*cos(cart.phi) - der(cart.x)*sin(cart.phi) = 0
driver turn:  der(cart.phi) = 1
EOF
run "$tmp/ksing.mech" --linear sparse --csv /dev/null
check "velocity rows singular, sparse: exit 1" status_is 1
check "velocity rows singular, sparse: the time, the pivot's coordinate and row" \
    err_matches "error: t = 0: velocity and acceleration analysis failed: singular Jacobian.*sparse LU found no pivot for cart.y in row side"

# ---- gen --lu: the unrolled LU and step -----------------------------------------
# written only with --lu and for stepped mechanisms; the written P_step alone
# (no runtime) turns the slider-crank along its closed form
check "gen: no lu without --lu" sh -c "! grep -q lu_factor '$tmp/fb.c'"
run_mechc gen "$ex/knife_cart.mech" --lu -o "$tmp/kc.c"
check "gen --lu, velocity rows: exit 0, no lu" sh -c "[ $rc = 0 ] && ! grep -q lu_factor '$tmp/kc.c'"
check "gen --lu, velocity rows: a note says why" \
    err_has "mechc gen: note: --lu not written: the mechanism has 3 velocity-level rows"
sh "$ex/chain.sh" 100 "$tmp/c100.mech"
run_mechc gen "$tmp/c100.mech" --lu -o "$tmp/c100.c"
check "gen --lu, 603 coordinates: exit 0, no lu" sh -c "[ $rc = 0 ] && ! grep -q lu_factor '$tmp/c100.c'"
check "gen --lu, 603 coordinates: a note says why" \
    err_has "mechc gen: note: --lu not written: 603 coordinates, more than 100"
run_mechc gen "$ex/slider_crank.mech" --lu -o "$tmp/sc_note.c"
check "gen --lu on a mechanism that qualifies: no note" err_lacks note
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
