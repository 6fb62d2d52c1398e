#!/bin/sh
# tests/diagnoses_cli.sh MECHC - failures whose diagnosis must name the
# real cause: a spatial loop that cannot close (the loop, then the rows
# violated at the best point Newton found, the Euler parameters'
# normalisation among them, never a diverged iterate; `info` shows that
# point as not assembled); a rail out of reach (the loop, the rail in it,
# before the rod's rows); a spring of length 0 (named, with its place in
# the file and why its force is NaN).
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
    err_has "rssr_short.mech: error: t = 0: could not assemble from these initial values: the loop of R1, R2, C and D cannot close (without any one of them the other rows assemble: a length, a pivot, a rail or a driven position out of reach); after 99 iterations of minimum-norm Newton the largest residual at the best point found is 3 in row C; rows left unsatisfied there: C and rocker.norm; rocker.norm is the normalisation of rocker's Euler parameters (e0^2 + e1^2 + e2^2 + e3^2 = 1), and there |p| = 1.0"
run_mechc info "$tmp/rssr_short.mech"
check "spatial loop too short: info exit 1" status_is 1
check "spatial loop too short: info names the rows violated at the best point" \
    err_has "the assembly did not converge (residual 3, worst row C): the loop of R1, R2, C and D cannot close (without any one of them the other rows assemble: a length, a pivot, a rail or a driven position out of reach); rows left unsatisfied at the best point found: C and rocker.norm"
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
    err_has "C cannot be met (without it the other rows assemble); after 254 iterations of minimum-norm Newton the largest residual at the best point found is 1.81e+03 in row C; rows left unsatisfied there: C, rocker.norm and crank.norm; crank.norm is the normalisation of crank's Euler parameters"
check "spatial loop too long: nothing on stdout" out_empty

# ---- a rail out of reach ----
# examples/slider_crank_spatial.mech with its rail (translational P) moved
# to y = 0.5: crank and rod reach 0.4. The best point keeps the slider on
# the rail and breaks the rod's joints, and the diagnosis was "worst row
# rod.norm", the rod's orientation. Now the loop comes first, P in it (and
# not the driver, which can stay).
sed 's/^translational P: ground(0, 0, 0)/translational P: ground(0, 0.5, 0)/' \
    "$ex/slider_crank_spatial.mech" > "$tmp/rail.mech"
grep -q 'ground(0, 0.5, 0)' "$tmp/rail.mech" || bad "rail.mech: the rail was not moved"
for cmd in run info; do
    run_mechc $cmd "$tmp/rail.mech"
    check "rail out of reach: $cmd exit 1" status_is 1
    check "rail out of reach: $cmd names the loop, the rail P in it, the driver not" \
        err_has "the loop of O, A, B and P cannot close (without any one of them the other rows assemble: a length, a pivot, a rail or a driven position out of reach)"
done
run_mechc run "$tmp/rail.mech"
check "rail out of reach: the loop before the rows left unsatisfied" \
    err_matches "error: t = 0: could not assemble from these initial values: the loop of O, A, B and P cannot close ([^)]*); after [0-9]* iterations .* in row rod.norm; rows left unsatisfied there: rod.norm, "
# the same in a plane, with masses, under sim
sed 's/^prismatic P: ground(0, 0)/prismatic P: ground(0, 0.5)/' \
    "$ex/slider_crank_dynamics.mech" > "$tmp/rail_planar.mech"
run_mechc sim "$tmp/rail_planar.mech"
check "planar rail out of reach: sim exit 1" status_is 1
check "planar rail out of reach: sim names the loop with P" \
    err_has "rail_planar.mech: error: t = 0: could not assemble from these initial values: the loop of O, A, B and P cannot close"

# ---- a spring of length 0 ----
# Its ends at one point: the direction of its force, (B - A)/|B - A|, is
# 0/0. sim and run --forces said "NaN or infinity in the mass matrix, the
# forces, ..." without naming it.
cat > "$tmp/zero_spring.mech" <<'EOF2'
body rod x = 0.5 y = 0 phi = 0
revolute O: ground(0, 0) rod(-0.5, 0)
mass rod m = 1 J = 0.1
gravity (0, -9.81)
spring S: ground(0, 0) rod(-0.5, 0)  k = 100  length = 0.2
EOF2
for l in dense sparse; do
    run_mechc sim "$tmp/zero_spring.mech" --linear $l
    check "spring of length 0, sim --linear $l: exit 1" status_is 1
    check "spring of length 0, sim --linear $l: names it, where, and why" \
        err_has "zero_spring.mech: error: t = 0: forward dynamics failed: spring 'S' ($tmp/zero_spring.mech:5:1) has length 0 here, its two ends at one point: the direction of its force, (B - A)/|B - A|, is undefined (0/0)"
done
run_mechc sim "$tmp/zero_spring.mech" --engine generic
check "spring of length 0, sim --engine generic: names it" err_has "spring 'S' ($tmp/zero_spring.mech:5:1) has length 0 here"
printf 'driver D: rod.phi = t\n' | cat "$tmp/zero_spring.mech" - | grep -v gravity > "$tmp/zero_spring_run.mech"
run_mechc run "$tmp/zero_spring_run.mech" --forces
check "spring of length 0, run --forces: exit 1" status_is 1
check "spring of length 0, run --forces: names it" \
    err_has "zero_spring_run.mech: error: t = 0: inverse dynamics failed: spring 'S' ($tmp/zero_spring_run.mech:4:1) has length 0 here"

# ---- a driver pushed past reach ----
# examples/four_bar.mech with its rocker driven at 2 rad/s: at t = 0.3614
# crank and coupler line up and the rocker can turn no further. sim said
# "step size underflow ... a stiff force?" (or, with rk4imp, "tighten
# --rtol/--atol"); run put it at t = 0.37, its output time.
sed 's/^driver drive: crank.phi = omega\*t$/driver drive: rocker.phi = 1.6961 + 2*t/' \
    "$ex/four_bar.mech" > "$tmp/past_reach.mech"
{ cat "$tmp/past_reach.mech"
  printf 'mass crank m = 1 J = 0.1\nmass coupler m = 1 J = 0.1\nmass rocker m = 1 J = 0.1\n'
  printf 'gravity (0, -9.81)\n'; } > "$tmp/past_reach_dyn.mech"
for m in rk8pd rk4imp msbdf; do
    run_mechc sim "$tmp/past_reach_dyn.mech" --method $m
    check "driver past reach, sim --method $m: exit 1" status_is 1
    check "driver past reach, sim --method $m: cannot reach, the time, the driver and the rows" \
        err_matches "past_reach_dyn.mech: error: t = 0\.361379[0-9]*: the mechanism cannot reach the driven position: driver 'drive' pushes it past a limit position, where the Jacobian loses rank (smallest singular value [0-9.e-]* of the largest, along rows drive, "
    check "driver past reach, sim --method $m: the integrator's words after" \
        err_matches "; where it stopped: [a-z ]* failed: "
    check "driver past reach, sim --method $m: the states before written" out_lines 38
done
run_mechc run "$tmp/past_reach.mech"
check "driver past reach, run: exit 1" status_is 1
check "driver past reach, run: the time it stopped (not the output time 0.37), the driver, the rows" \
    err_has "past_reach.mech: error: t = 0.36140625: the mechanism cannot reach the driven position: driver 'drive' pushes it past a limit position, where the Jacobian loses rank (smallest singular value 0.003 of the largest, along rows drive, O2.y, A.y, O4.y, B.y and O4.x)"
check "driver past reach, run: no headline at t = 0.37" sh -c '! grep -q "error: t = 0.37" "$1"' _ "$tmp/err"

# ---- a row not defined at the file's initial values ----
# sqrt of a negative number in a driver: NaN from the start, which the
# message blamed on the lengths ("minimum-norm Newton reached NaN or
# infinity ... the mechanism may not close with these lengths"); now the
# row is named (the outside corpus)
printf 'body b x = 1 y = 0 phi = 0\nrevolute O: ground b(-1, 0)\ndriver D: b.phi = sqrt(-1 - t)\n' > "$tmp/sqrt_neg.mech"
for cmd in run sim; do
    [ $cmd = sim ] && printf 'mass b m = 1 J = 1\n' >> "$tmp/sqrt_neg.mech"
    run_mechc $cmd "$tmp/sqrt_neg.mech"
    check "row NaN at the initial values, $cmd: exit 1" status_is 1
    check "row NaN at the initial values, $cmd: the row named" \
        err_has "sqrt_neg.mech: error: t = 0: could not assemble from these initial values: rows not a finite number at the file's initial values: D (an expression not defined there: the square root or log of a negative number, 0/0, asin or acos past 1, an overflow?)"
done

suite_end
