#!/bin/sh
# tests/diagnoses_cli.sh MECHC - failures whose diagnosis must name the
# real cause: a spatial loop that cannot close (the rows violated at the
# best point Newton found, the Euler parameters' normalisation among them,
# never a diverged iterate; `info` shows that point as not assembled).
#
#   sh tests/diagnoses_cli.sh build/mechc
#
# The last line is "diagnoses_cli: N passed, M failed".
set -u
# shellcheck source=tests/lib.sh
. "$(dirname "$0")/lib.sh"
suite_begin diagnoses_cli "${1:-build/mechc}"

# ---- a spatial loop that cannot close ----
# examples/rssr.mech with a coupler of length 1 where the pivots are 2 apart
# and the crank and rocker 1 and 3 long: the loop opens by 3 at least.
# Newton's full steps once carried it to a residual of 1.8e10 (the Euler
# parameters grown without bound), and that iterate was the diagnosis.
sed 's/^param L     = sqrt(10)$/param L     = 1/' "$ex/rssr.mech" > "$tmp/rssr_short.mech"
run_mechc run "$tmp/rssr_short.mech"
check "spatial loop too short: run exit 1" status_is 1
check "spatial loop too short: the best point's residual, not a diverged one" \
    err_has "rssr_short.mech: error: t = 0: could not assemble from these initial values: after 99 iterations of minimum-norm Newton the largest residual at the best point found is 3 in row C; rows left unsatisfied there: C and rocker.norm; rocker.norm is the normalisation of rocker's Euler parameters (e0^2 + e1^2 + e2^2 + e3^2 = 1), and there |p| = 1.0"
run_mechc info "$tmp/rssr_short.mech"
check "spatial loop too short: info exit 1" status_is 1
check "spatial loop too short: info names the rows violated at the best point" \
    err_has "the assembly did not converge (residual 3, worst row C); rows left unsatisfied at the best point found: C and rocker.norm"
check "spatial loop too short: info does not call the point assembled" \
    out_has "coordinates (initial value, best point found, NOT assembled, at t = 0):"
check "spatial loop too short: nor the configuration of its rank" \
    out_has "rank (SVD at the best point found, not assembled):"
check "spatial loop too short: no 'assembled at'" sh -c '! grep -q "assembled at" "$1"' _ "$tmp/out"

# The same with masses under sim, a coupler far too long (1000): the best
# point stretches both bodies (|p| of 12 and 13), which the message once
# left out ("rows left unsatisfied: C").
cat > "$tmp/rssr_long.mech" <<'EOF2'
spatial
body crank  x = 0  y = 0  z = 0
body rocker x = 2  y = 0  z = 0  orient = axis(0, 1, 1, pi/2)
revolute R1: ground(0, 0, 0)  crank(0, 0, 0)   axis(0, 0, 1)
revolute R2: ground(2, 0, 0)  rocker(0, 0, 0)  axis(0, 1, 1)
distance C:  crank(1, 0, 0)   rocker(3, 0, 0)  length = 1000
mass crank m = 1 J = (0.1, 0.1, 0.1)
mass rocker m = 1 J = (0.1, 0.1, 0.1)
gravity (0, 0, -9.81)
EOF2
run_mechc sim "$tmp/rssr_long.mech"
check "spatial loop too long: sim exit 1" status_is 1
check "spatial loop too long: every violated row, the normalisations too" \
    err_has "the largest residual at the best point found is 1.81e+03 in row C; rows left unsatisfied there: C, rocker.norm and crank.norm; crank.norm is the normalisation of crank's Euler parameters"
check "spatial loop too long: nothing on stdout" out_empty

suite_end
