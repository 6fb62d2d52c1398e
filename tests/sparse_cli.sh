#!/bin/sh
# tests/sparse_cli.sh MECHC - `mechc run --linear`: every example run dense
# and sparse (KLU) gives the same states to 1e-10 (relative, at least
# absolute) and the same exit status, including the states written before a
# failure; a chain of 50 four-bar loops goes sparse under auto and matches
# the dense run; bad values, velocity-level rows and the generic engine are
# refused with exit 2; a singular sparse failure names its time, row and
# coordinate.
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

suite_end
