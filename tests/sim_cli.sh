#!/bin/sh
# tests/sim_cli.sh MECHC - `mechc sim` from the outside, against references no one here wrote.
#
#   sh tests/sim_cli.sh build/mechc
#
# Andrews' squeezer against the Test Set for IVP Solvers (angles, rates,
# consistent accelerations and multipliers); IFToMM benchmarks A01 (simple
# pendulum, 2000 s) and A02 (N four-bar, through its singular positions)
# against the exact solutions of their published definitions (the
# benchmark's own data files were not available); the free double
# pendulum's energy; a stiff spring's closed form with the implicit
# methods; the engines agreeing; a redundant parallelogram with masses
# through its flat positions; exit statuses and messages of bad use; motions
# that cannot go on (a rolling disk falling flat, dry friction that sticks:
# the step size collapses), --max-steps, and the note
# on moved initial values that run prints.
# The last line is "sim_cli: N passed, M failed".
set -u
# shellcheck source=tests/lib.sh
. "$(dirname "$0")/lib.sh"
suite_begin sim_cli "${1:-build/mechc}"

# run ARGS...: mechc sim ARGS (tests/lib.sh).
run() { run_mechc sim "$@"; }

# value_at T NAME FILE: column NAME of the CSV row whose t is T.
value_at() {
    awk -F, -v t="$1" -v name="$2" 'NR == 1 { for (i = 1; i <= NF; i++) if ($i == name) c = i; next }
                                    $1 == t && c { print $c }' "$3"
}

# close_rel A B TOL: |A - B| <= TOL |B| (A not empty); says the error on stderr when not.
close_rel() {
    awk -v a="$1" -v b="$2" -v tol="$3" 'BEGIN {
        d = a - b; if (d < 0) d = -d; s = b < 0 ? -b : b
        ok = a != "" && d <= tol * s
        if (!ok) printf "  got %s, want %s (relative error %.3g > %s)\n", a, b, s ? d / s : d, tol > "/dev/stderr"
        exit !ok }'
}

# close_abs A B TOL: |A - B| <= TOL.
close_abs() {
    awk -v a="$1" -v b="$2" -v tol="$3" 'BEGIN {
        d = a - b; if (d < 0) d = -d
        ok = a != "" && d <= tol
        if (!ok) printf "  got %s, want %s (error %.3g > %s)\n", a, b, d, tol > "/dev/stderr"
        exit !ok }'
}

# energy_drift_ratio: the relative drift `--stats` printed in $tmp/err.
energy_drift_ratio() {
    sed -n 's/.*energy balance T - W drifted by [^ ]* (\([^ ]*\) of the.*/\1/p' "$tmp/err"
}

# ---- Andrews' squeezing mechanism (Test Set for IVP Solvers, `andrews`) ----
# Reference at t = 0.03 (andrews.f, subroutine solut); the Test Set's own
# values are good to about 1e-10 relative in the angles and 3e-8 in the
# rates, so: angles 1e-7, rates 1e-6 relative.
run "$ex/andrews.mech" --t1 0.03 --steps 1 --rtol 1e-8 --atol 1e-8 --csv "$tmp/andrews.csv" --stats
check "andrews: exit 0" status_is 0
for pair in beta:0.1581077119629904e+2 Theta:-0.1575637105984298e+2 \
            gamma:0.4082224013073101e-1 Phi:-0.5347301163226948e+0 \
            delta:0.5244099658805304e+0 Omega:0.5347301163226948e+0 \
            epsilon:0.1048080741042263e+1; do
    name=${pair%%:*}
    check "andrews: $name(0.03) = Test Set to 1e-7" \
        close_rel "$(value_at 0.03 "$name" "$tmp/andrews.csv")" "${pair#*:}" 1e-7
done
for pair in beta:0.1139920302151208e+4 Theta:-0.1424379294994111e+4 \
            gamma:0.1103291221937134e+2 Phi:0.1929337464421385e+2 \
            delta:0.5735699284790808e+0 Omega:-0.1929337464421385e+2 \
            epsilon:0.3231791658026955e+0; do
    name=${pair%%:*}
    check "andrews: d($name)(0.03) = Test Set to 1e-6" \
        close_rel "$(value_at 0.03 "d($name)" "$tmp/andrews.csv")" "${pair#*:}" 1e-6
done
# E = T + V - mom beta is conserved: the energy balance's drift
check "andrews: energy balance within 1e-8" \
    close_abs "$(energy_drift_ratio)" 0 1e-8
# the consistent initial accelerations and multipliers (andrews.f, init)
check "andrews: dd(beta)(0) = Test Set" \
    close_rel "$(value_at 0 "dd(beta)" "$tmp/andrews.csv")" 14222.4439199541138705911625887 1e-10
check "andrews: dd(Theta)(0) = Test Set" \
    close_rel "$(value_at 0 "dd(Theta)" "$tmp/andrews.csv")" -10666.8329399655854029433719415 1e-10
for name in gamma Phi delta Omega epsilon; do
    check "andrews: dd($name)(0) = 0" close_abs "$(value_at 0 "dd($name)" "$tmp/andrews.csv")" 0 1e-8
done
run "$ex/andrews.mech" --t1 0.03 --steps 1 --rtol 1e-8 --atol 1e-8 --json
check "andrews --json: exit 0" status_is 0
check "andrews --json: the rows in the Test Set's order" \
    out_has '"rows": ["EB_x", "EB_y", "EA1_x", "EA1_y", "EA2_x", "EA2_y"]'
# the first "lambda" row: t = 0
sed -n 's/^ "lambda": \[\[\(.*\)\],$/\1/p' "$tmp/out" | tr -d ' ' | tr ',' '\n' > "$tmp/lambda0"
check "andrews: six multipliers at t = 0" test "$(wc -l < "$tmp/lambda0")" = 6
check "andrews: lambda1(0) = Test Set" \
    close_rel "$(sed -n 1p "$tmp/lambda0")" 98.5668703962410896057654982170 1e-10
check "andrews: lambda2(0) = Test Set" \
    close_rel "$(sed -n 2p "$tmp/lambda0")" -6.12268834425566265503114393122 1e-10
for i in 3 4 5 6; do
    check "andrews: lambda$i(0) = 0" close_abs "$(sed -n ${i}p "$tmp/lambda0")" 0 1e-10
done

# ---- IFToMM A01, simple pendulum: 2000 s, 4000 output steps ----------------
# exact solution (Jacobi elliptic; examples/a01_pendulum.mech)
run "$ex/a01_pendulum.mech" --t1 2000 --steps 4000 --csv "$tmp/a01.csv"
check "a01: exit 0" status_is 0
check "a01: 4001 states" test "$(wc -l < "$tmp/a01.csv")" = 4002
for row in "1 -0.9862917511318753 -0.1650108531255412 1e-8" \
           "10 0.2750874625761169 -0.9614192050991251 1e-8" \
           "20 -0.9969071739909918 -0.07858808080933375 1e-7" \
           "2000 -0.8146030685890322 -0.5800188278369355 1e-3"; do
    set -- $row
    check "a01: P1 at t = $1 within $4" \
        sh -c 'awk -v x="$1" -v y="$2" -v x0="$3" -v y0="$4" -v tol="$5" "BEGIN {
            dx = x - x0; dy = y - y0; if (dx < 0) dx = -dx; if (dy < 0) dy = -dy
            if (dx > tol || dy > tol) printf \"  error %.3g, %.3g\\n\", dx, dy > \"/dev/stderr\"
            exit !(x != \"\" && dx <= tol && dy <= tol) }"' - \
        "$(value_at "$1" P1.x "$tmp/a01.csv")" "$(value_at "$1" P1.y "$tmp/a01.csv")" "$2" "$3" "$4"
done
# the rod keeps its length and the energy (zero at the pivot) stays 0
check "a01: |P1| = 1 and E = 0 throughout" awk -F, '
    NR > 1 { r = sqrt($2 * $2 + $3 * $3) - 1; e = 0.5 * ($4 * $4 + $5 * $5) + 9.81 * $3
             if (r < 0) r = -r; if (e < 0) e = -e
             if (r > wr) wr = r; if (e > we) we = e }
    END { exit !(NR == 4002 && wr < 1e-12 && we < 1e-5) }' "$tmp/a01.csv"

# ---- IFToMM A02, N four-bar (examples/a02_four_bar.sh) ----------------------
# N = 4 over the benchmark's 20 s (about 20 flat positions, where the
# Jacobian loses 4 ranks), against the one-angle equation of the
# parallelogram branch I th'' = -K cos th (RK4, h = 1e-4, in awk): B0's
# position and velocity within the benchmark's 1e-3 (we see 3e-8); every
# rod keeps rod0's angle and every coupler stays level (the branch); the
# energy stays I/2 + K. (N = 40: bench/dynamics.sh; 6 s of CPU a second.)
sh "$ex/a02_four_bar.sh" 4 "$tmp/a02_4.mech"
run "$tmp/a02_4.mech" --t1 20 --steps 400 --rtol 1e-7 --atol 1e-7 \
    --qd "$(sh "$ex/a02_four_bar.sh" --qd 4)" --csv "$tmp/a02.csv" --stats
check "a02 N = 4: exit 0" status_is 0
check "a02 N = 4: came to singular positions (pivot ratio of Phi_q below 1e-3)" awk -v r="$(
    sed -n 's/.*smallest pivot ratio of Phi_q \([^ ]*\) .*/\1/p' "$tmp/err")" 'BEGIN { exit !(r != "" && r < 1e-3) }'
# a02_exact N CSV [STATES]: B0 within 1e-3 of the one-angle solution at all
# STATES (401) states
a02_exact() {
    worst=$(sh "$ex/a02_four_bar.sh" --error "$1" "$2")
    echo "  a02: largest error of B0 $worst" >&2
    [ "$(wc -l < "$2")" -eq "$((${3:-401} + 1))" ] && awk -v e="$worst" 'BEGIN { exit !(e <= 1e-3) }'
}
check "a02 N = 4: B0 and its velocity = the exact solution within 1e-3, 20 s" a02_exact 4 "$tmp/a02.csv"
# --error on a CSV without B0's columns or rows printed 0 (a perfect
# match) and exited 0 (the outside corpus)
: > "$tmp/a02_empty.csv"
printf 't,rod0.x\n0,0.5\n' > "$tmp/a02_other.csv"
for f in a02_empty a02_other; do
    sh "$ex/a02_four_bar.sh" --error 4 "$tmp/$f.csv" > "$tmp/out" 2> "$tmp/err"
    check "a02 --error on $f.csv: exit 2" test $? = 2
    check "a02 --error on $f.csv: nothing on stdout" out_empty
done
check "a02 --error on a CSV without B0: says which column" err_has "a02_other.csv: no column B0.x"
check "a02 N = 4: on the parallelogram branch throughout, energy I/2 + K" awk -F, '
    NR == 1 { for (i = 1; i <= NF; i++) c[$i] = i; next }
    { p = $(c["rod0.phi"]); e = 0
      for (i = 0; i <= 4; i++) { d = $(c["rod" i ".phi"]) - p; if (d < 0) d = -d; if (d > wb) wb = d }
      for (i = 0; i < 4; i++) { d = $(c["cpl" i ".phi"]); if (d < 0) d = -d; if (d > wb) wb = d }
      split("rod0 rod1 rod2 rod3 rod4 cpl0 cpl1 cpl2 cpl3", b, " ")
      for (j = 1; j <= 9; j++)
          e += 0.5 * ($(c["d(" b[j] ".x)"])^2 + $(c["d(" b[j] ".y)"])^2) \
               + 0.5 / 12 * $(c["d(" b[j] ".phi)"])^2 + 9.81 * $(c[b[j] ".y"])
      d = e - (5 / 3 + 4) / 2 - 9.81 * (2.5 + 4); if (d < 0) d = -d; if (d > we) we = d }
    END { exit !(NR == 402 && wb < 1e-6 && we < 1e-5) }' "$tmp/a02.csv"

# The same on the sparse augmented matrix (KLU; auto takes it above 100
# coordinates): every row kept by the pivots of [I Phi_q^T; Phi_q 0] away
# from the flat positions, the dense elimination near them.
run "$tmp/a02_4.mech" --linear sparse --t1 20 --steps 400 --rtol 1e-7 --atol 1e-7 \
    --qd "$(sh "$ex/a02_four_bar.sh" --qd 4)" --csv "$tmp/a02s.csv" --stats
check "a02 N = 4 --linear sparse: exit 0" status_is 0
check "a02 N = 4 --linear sparse: on KLU, near the flat positions, rows mostly chosen by its pivots" awk '
    /sparse augmented matrix/ { for (i = 1; i <= NF; i++) { if ($i == "pivots") s = $(i + 1)
                                                          if ($i == "elimination") d = $(i + 1) } }
    /largest pivot spread/ { for (i = 1; i <= NF; i++) if ($i == "row") p = $(i + 1) + 0 }
    END { exit !(s > 100 && d < s / 10 && p > 1e4) }' "$tmp/err"
check "a02 N = 4 --linear sparse: B0 = the exact solution within 1e-3, 20 s" a02_exact 4 "$tmp/a02s.csv"
# the dense and sparse runs agree where no flat position came between
check "a02 N = 4: sparse = dense at t = 0.5 to 1e-9" close_abs \
    "$(value_at 0.5 rod0.phi "$tmp/a02s.csv")" "$(value_at 0.5 rod0.phi "$tmp/a02.csv")" 1e-9
# N = 40 (243 coordinates: auto takes the sparse path) over the full 20 s
sh "$ex/a02_four_bar.sh" 40 "$tmp/a02_40.mech"
run "$tmp/a02_40.mech" --t1 20 --steps 400 --rtol 1e-6 --atol 1e-6 \
    --qd "$(sh "$ex/a02_four_bar.sh" --qd 40)" --csv "$tmp/a02_40.csv" --stats
check "a02 N = 40: exit 0" status_is 0
check "a02 N = 40: auto took the sparse path" err_has "sparse augmented matrix (KLU)"
check "a02 N = 40: B0 = the exact solution within 1e-3, 20 s" a02_exact 40 "$tmp/a02_40.csv"
# N = 1000 (6003 coordinates): assembled at t0 by sparse minimum-norm
# Newton (SuiteSparseQR), no dense array allocated, in 250 MB of address
# space where the dense Jacobian alone takes 288 MB and the mass matrix
# 288 MB (skipped where the build cannot start under that limit:
# sanitizers reserve terabytes)
sh "$ex/a02_four_bar.sh" 1000 "$tmp/a02_1000.mech"
if (ulimit -v 250000 && "$mechc" sim "$ex/andrews.mech" --t1 0.001 > /dev/null 2>&1); then
    (ulimit -v 250000 && "$mechc" sim "$tmp/a02_1000.mech" --t1 0.01 --steps 1 --stats \
        --qd "$(sh "$ex/a02_four_bar.sh" --qd 1000)" --csv "$tmp/a02_1000.csv") \
        > "$tmp/out" 2> "$tmp/err"
    rc=$?
    check "a02 N = 1000 within 250 MB of address space: exit 0" status_is 0
    check "a02 N = 1000: on the sparse path" err_has "sparse augmented matrix (KLU)"
    check "a02 N = 1000: B0 = the exact solution within 1e-3 at t = 0, 0.01" \
        a02_exact 1000 "$tmp/a02_1000.csv" 2
    # the subshell waits, so an abort's report goes to its stderr
    (ulimit -v 250000; "$mechc" sim "$tmp/a02_1000.mech" --linear dense --t1 0.01 --steps 1 \
        --qd "$(sh "$ex/a02_four_bar.sh" --qd 1000)" --csv /dev/null; echo $? > "$tmp/rc") \
        > "$tmp/out" 2> "$tmp/err"
    rc=$(cat "$tmp/rc")
    check "a02 N = 1000 dense within 250 MB: out of memory (the limit means something)" \
        test "$rc" != 0
else
    skip "the build does not start within 250 MB of address space"
fi
# a pivot 5 m off the line: no assembly; the sparse Newton says so at once
# (the dense restarts took 135 s of CPU at N = 100) and names a row
sed 's/^revolute g20: ground(20, 0)/revolute g20: ground(20, 5)/' "$tmp/a02_40.mech" \
    > "$tmp/a02_40bad.mech"
run "$tmp/a02_40bad.mech" --t1 0.01 --qd "$(sh "$ex/a02_four_bar.sh" --qd 40)"
check "a02 N = 40, a pivot moved: exit 1" status_is 1
check "a02 N = 40, a pivot moved: could not assemble, in which row" err_matches \
    "t = 0: could not assemble from these initial values: after [0-9]* iterations of minimum-norm Newton the largest residual at the best point found is [0-9.e+-]* in row [ab][0-9]*\.[xy]"
# --interpolate: rk8pd's own steps across the 400 output times, the states
# there from the steps' Hermite interpolant
run "$tmp/a02_40.mech" --t1 20 --steps 400 --rtol 1e-6 --atol 1e-6 --interpolate \
    --qd "$(sh "$ex/a02_four_bar.sh" --qd 40)" --csv "$tmp/a02_40i.csv" --stats
check "a02 N = 40 --interpolate: exit 0" status_is 0
check "a02 N = 40 --interpolate: fewer integrator steps than output intervals" awk '
    /integrator steps/ { n = $4 } END { exit !(n > 0 && n < 400) }' "$tmp/err"
check "a02 N = 40 --interpolate: B0 = the exact solution within 1e-3, 20 s" \
    a02_exact 40 "$tmp/a02_40i.csv"
run "$tmp/a02_4.mech" --linear sparse --engine generic --t1 0.1
check "--linear sparse with the generic engine: exit 2" status_is 2
check "--linear sparse with the generic engine: says why" err_has "needs the generated kernels"

# ---- the free double pendulum: energy over 10 s ----------------------------
run "$ex/double_pendulum.mech" --t1 10 --steps 1000 --csv "$tmp/dp.csv" --stats
check "double pendulum: exit 0" status_is 0
check "double pendulum: E from the states within 1e-8 of E0 = 0 over 10 s" awk -F, '
    NR == 1 { for (i = 1; i <= NF; i++) c[$i] = i; next }
    { e = 0
      for (j = 1; j <= 2; j++) { b = "rod" j
          e += 0.5 * ($(c["d(" b ".x)"])^2 + $(c["d(" b ".y)"])^2) + 0.5 / 12 * $(c["d(" b ".phi)"])^2 \
               + 9.81 * $(c[b ".y"]) }
      if (e < 0) e = -e; if (e > w) w = e }
    END { printf "  double pendulum: max |E - E0| %.3g\n", w > "/dev/stderr"; exit !(NR == 1002 && w <= 1e-8) }' "$tmp/dp.csv"
check "double pendulum: --stats energy balance within 1e-8" close_abs "$(energy_drift_ratio)" 0 1e-8
run "$ex/double_pendulum.mech" --t1 10 --steps 1000 --interpolate --csv "$tmp/dpi.csv"
check "double pendulum --interpolate: exit 0, 1001 states" awk 'END { exit !(NR == 1002) }' \
    "$tmp/dpi.csv"
# t = 1 falls inside a step: the interpolant against the reference below
check "double pendulum --interpolate: th1(1) between steps" close_abs \
    "$(value_at 1 rod1.phi "$tmp/dpi.csv")" -2.7785125649854966 1e-9
check "double pendulum --interpolate: th1'(1) between steps" close_abs \
    "$(value_at 1 "d(rod1.phi)" "$tmp/dpi.csv")" -3.406517532972 1e-8
# th = phi + pi/2 at t = 1 (the example's header; RK4 and mpmath agree to 1e-12)
check "double pendulum: th1(1)" close_abs "$(value_at 1 rod1.phi "$tmp/dp.csv")" \
    -2.7785125649854966 1e-9
check "double pendulum: th2(1)" close_abs "$(value_at 1 rod2.phi "$tmp/dp.csv")" \
    -2.3851873498861966 1e-9
check "double pendulum: th1'(1)" close_abs "$(value_at 1 "d(rod1.phi)" "$tmp/dp.csv")" \
    -3.406517532972 1e-8
check "double pendulum: th2'(1)" close_abs "$(value_at 1 "d(rod2.phi)" "$tmp/dp.csv")" \
    -0.51604547210521 1e-8

# ---- engines agree ---------------------------------------------------------
for e in jit generic aot; do
    run "$ex/double_pendulum.mech" --t1 2 --steps 4 --engine "$e" --csv "$tmp/dp_$e.csv"
    if [ "$e" = aot ] && ! status_is 0 && err_has "compiler"; then
        skip "no C compiler: aot engine"
        cp "$tmp/dp_jit.csv" "$tmp/dp_aot.csv"
        continue
    fi
    check "double pendulum --engine $e: exit 0" status_is 0
done
engines_agree() {
    paste -d, "$tmp/dp_jit.csv" "$tmp/dp_$1.csv" | awk -F, '
        NR > 1 { n = NF / 2; for (i = 1; i <= n; i++) { d = $i - $(i + n); if (d < 0) d = -d; if (d > w) w = d } }
        END { exit !(NR == 6 && w <= 1e-9) }'
}
check "jit and generic: the same states to 1e-9" engines_agree generic
check "jit and aot: the same states to 1e-9" engines_agree aot

# ---- designed masses: --design gives what the edited file gives ----------
# slider_crank_torque.mech with m1, m2 and g designed: sim and run --forces
# under --design m1=1.4,m2=2.5,g=5 against the file with those constants,
# every value to 1e-10 relative (the products m g are folded in one, not
# in the other).
sed 's/^param m1 .*/design m1 = 1/; s/^param m2 .*/design m2 = 2/; s/^param g .*/design g = 9.81/' \
    "$ex/slider_crank_torque.mech" > "$tmp/sct_design.mech"
sed 's/^param m1 .*/param m1 = 1.4/; s/^param m2 .*/param m2 = 2.5/; s/^param g .*/param g = 5/' \
    "$ex/slider_crank_torque.mech" > "$tmp/sct_edited.mech"
same_csv() {    # same_csv A.csv B.csv: same header and rows, values to 1e-10 relative
    head -1 "$1" > "$tmp/h1"; head -1 "$2" > "$tmp/h2"
    cmp -s "$tmp/h1" "$tmp/h2" && paste -d, "$1" "$2" | awk -F, '
        NR > 1 { n = NF / 2; for (i = 1; i <= n; i++) { d = $i - $(i + n); if (d < 0) d = -d
                 s = $(i + n) < 0 ? -$(i + n) : $(i + n); if (d > 1e-10 * (1 + s)) bad = 1 } }
        END { exit !(NR > 2 && !bad) }'
}
for cmd in sim "run --forces"; do
    tag=$(echo "$cmd" | tr -d ' -')
    # shellcheck disable=SC2086
    run_mechc $cmd "$tmp/sct_design.mech" --design m1=1.4,m2=2.5,g=5 --csv "$tmp/${tag}_d.csv"
    check "designed masses, $cmd --design: exit 0" status_is 0
    # shellcheck disable=SC2086
    run_mechc $cmd "$tmp/sct_edited.mech" --csv "$tmp/${tag}_e.csv"
    check "designed masses, $cmd --design: the edited file's values" \
        same_csv "$tmp/${tag}_d.csv" "$tmp/${tag}_e.csv"
done

# ---- a stiff spring: the implicit methods against the closed form ----------
# x = 0.25 + 0.05 cos(1000 t) (k = 1e6, m = 1)
cat > "$tmp/stiff.mech" <<'EOF'
body s x = 0.3
prismatic P: ground(0, 0) s(0, 0) axis(1, 0)
mass s m = 1 J = 0.01
spring K: ground(0, 0) s k = 1e6 length = 0.25
EOF
for mt in rk8pd:1e-9 rk4imp:1e-8 msbdf:1e-7; do
    m=${mt%%:*}
    run "$tmp/stiff.mech" --t1 0.01 --steps 10 --method "$m" --csv "$tmp/stiff_$m.csv"
    check "stiff spring --method $m: exit 0" status_is 0
    check "stiff spring --method $m: the closed form within ${mt#*:}" awk -F, -v tol="${mt#*:}" '
        NR > 1 { d = $2 - (0.25 + 0.05 * cos(1000 * $1)); if (d < 0) d = -d; if (d > w) w = d }
        END { exit !(NR == 12 && w <= tol) }' "$tmp/stiff_$m.csv"
done
check "stiff spring: msbdf and rk4imp end where rk8pd does (1e-7)" close_abs \
    "$(value_at 0.01 s.x "$tmp/stiff_msbdf.csv")" "$(value_at 0.01 s.x "$tmp/stiff_rk8pd.csv")" 1e-7
check "stiff spring: rk4imp ends where rk8pd does (1e-8)" close_abs \
    "$(value_at 0.01 s.x "$tmp/stiff_rk4imp.csv")" "$(value_at 0.01 s.x "$tmp/stiff_rk8pd.csv")" 1e-8

# ---- redundant rows and flat positions: parallelogram_redundant with masses --
# Released from pi/3 under gravity it swings through the two flat positions
# (phi = 0 and -pi: the rank drops) and back; the cranks keep one angle,
# the coupler stays level, and the energy is conserved.
{ grep -v '^#' "$ex/parallelogram_redundant.mech"
  printf 'gravity (0, -9.81)\nmass c1 m = 1 J = 1/12\nmass c2 m = 1 J = 1/12\n'
  printf 'mass c3 m = 1 J = 1/12\nmass coupler m = 2 J = 2*4/12\n'; } > "$tmp/pr.mech"
run "$tmp/pr.mech" --t1 3 --steps 300 --csv "$tmp/pr.csv" --stats
check "parallelogram with masses: exit 0" status_is 0
check "parallelogram with masses: a redundant row found" err_matches 'up to [12] dependent row'
check "parallelogram with masses: energy balance within 1e-9" close_abs "$(energy_drift_ratio)" 0 1e-9
check "parallelogram with masses: passes phi = 0 and -pi on its branch, energy kept" awk -F, '
    NR == 1 { for (i = 1; i <= NF; i++) c[$i] = i; next }
    { p = $(c["c1.phi"]); if (p < lo) lo = p; if (p > hi) hi = p
      for (k = 2; k <= 3; k++) { d = $(c["c" k ".phi"]) - p; if (d < 0) d = -d; if (d > wb) wb = d }
      d = $(c["coupler.phi"]); if (d < 0) d = -d; if (d > wb) wb = d
      e = 0
      split("c1 c2 c3 coupler", b, " ")
      for (j = 1; j <= 4; j++) { m = j == 4 ? 2 : 1
          e += 0.5 * m * ($(c["d(" b[j] ".x)"])^2 + $(c["d(" b[j] ".y)"])^2) \
               + 0.5 * m * (j == 4 ? 4 : 1) / 12 * $(c["d(" b[j] ".phi)"])^2 + 9.81 * m * $(c[b[j] ".y"]) }
      if (NR == 2) e0 = e
      d = e - e0; if (d < 0) d = -d; if (d > we) we = d }
    END { pi = atan2(0, -1); exit !(NR == 302 && lo < -pi && hi > 1 && wb < 1e-8 && we < 1e-7) }' "$tmp/pr.csv"

# ---- CSV and JSON shapes ---------------------------------------------------
run_mechc run "$ex/slider_crank_dynamics.mech" --steps 2 --csv "$tmp/run.csv"
check "slider_crank_dynamics: run exit 0" status_is 0
run "$ex/slider_crank_dynamics.mech" --t1 0.1 --steps 2 --csv "$tmp/sim.csv"
check "slider_crank_dynamics: sim exit 0" status_is 0
check "sim's CSV header is run's for the same file" \
    test "$(head -1 "$tmp/run.csv")" = "$(head -1 "$tmp/sim.csv")"
check "sim: steps + 1 CSV rows" test "$(wc -l < "$tmp/sim.csv")" = 4
run "$ex/slider_crank_dynamics.mech" --t1 0.1 --steps 2 --json
check "sim --json: exit 0" status_is 0
for key in '"coords": [' '"t": [0, 0.05, 0.1]' '"q": [[' '"qd": [[' '"qdd": [[' '"ok": true' \
           '"rows": ["O.x", "O.y"' '"lambda": [['; do
    check "sim --json has $key" out_has "$key"
done

# ---- bad use -----------------------------------------------------------------
run "$ex/four_bar.mech" --t1 1
check "no masses: exit 2" status_is 2
check "no masses: says so" err_has "the mechanism has no masses"
check "no masses: FILE:LINE:COL" err_matches 'four_bar.mech:[0-9]*:[0-9]*: error:'
check "no masses: with the caret" err_matches '^ *\^$'
run "$ex/double_pendulum.mech" --qd 1,2,3
check "--qd with 3 values for 6 coordinates: exit 2" status_is 2
run "$ex/double_pendulum.mech" --baumgarte 5
check "--baumgarte 5 (not A,B): exit 2" status_is 2
run "$ex/double_pendulum.mech" --baumgarte 5,x
check "--baumgarte 5,x: exit 2" status_is 2
run "$ex/double_pendulum.mech" --baumgarte -1,-1
check "--baumgarte -1,-1: exit 2" status_is 2
check "--baumgarte -1,-1: says why" err_has "must not be negative"
run "$ex/double_pendulum.mech" --rtol 10
check "--rtol 10: exit 2" status_is 2
check "--rtol 10: says why" err_has "is not below 1"
cat > "$tmp/over.mech" <<'EOF'
point p x = 1 y = 0
constraint a: p.x = 1
constraint b: p.y = 0
constraint c: p.x + p.y = 1
mass p m = 1
EOF
run "$tmp/over.mech" --steps 2
check "a redundant row: exit 0" status_is 0
check "a redundant row: named once" \
    err_has "over.mech: note: 3 holonomic rows for 2 coordinates: redundant row: c (joint c);"
check "a redundant row: its reaction said not unique" \
    err_has "over.mech: note: the reactions of the redundant rows and of the rows they repeat are not unique"
check "a redundant row: the states" out_lines 4
printf 'velocity v: der(p.x) = 0\n' >> "$tmp/over.mech"
run "$tmp/over.mech"
check "more holonomic rows than coordinates, and velocity-level rows: exit 2" status_is 2
check "more holonomic rows than coordinates, and velocity-level rows: FILE:LINE:COL" \
    err_matches "over\.mech:6:1: error: 3 holonomic rows for 2 coordinates"
check "more holonomic rows than coordinates, and velocity-level rows: nothing on stdout" out_lines 0
# --interpolate's degree, as generator/dyn/hermite.c has it (3 nodes: 9
# conditions, degree 8; 2 on the first step: the quintic), in --help and doc
run --help
check "sim --help: exit 0" status_is 0
check "sim --help: --interpolate's interpolant is of degree 8" \
    sh -c 'tr -s " \n" "  " < "$1" | grep -q "Hermite interpolant of q, qd, qdd at the ends of the last two steps, degree 8 (quintic within the first step;"' _ "$tmp/out"
check "sim --help: no longer calls it quintic alone" sh -c '! grep -q "quintic Hermite" "$1"' _ "$tmp/out"
check "doc/commands.md: --interpolate's interpolant is of degree 8" \
    sh -c 'tr -s " \n" "  " < "$1" | grep -q "and of the one before (degree 8; the quintic of the step alone on the first"' _ "$root/doc/commands.md"

# failing before its first state: the error, and no bare CSV header
printf 'mechanism stuck\nbody rod x = 0 y = 0 phi = 0\nrevolute O: ground rod\ndistance far: ground(5, 0) rod(1, 0) length = 1\nmass rod m = 1 J = 0.1 com(0.5, 0)\ngravity (0, -9.81)\n' \
    > "$tmp/stuck.mech"
run "$tmp/stuck.mech"
check "sim failing at t = 0: exit 1" status_is 1
check "sim failing at t = 0: the error on stderr" err_has "stuck.mech: error: t = 0: could not assemble"
check "sim failing at t = 0: nothing on stdout" out_empty

run "$ex/double_pendulum.mech" --t0 1 --t1 1
check "--t0 = --t1: exit 2" status_is 2
check "--t0 = --t1: says so" err_has "nothing to simulate"
run "$ex/double_pendulum.mech" --rtol 0 --atol 0
check "both tolerances 0: exit 2" status_is 2
run "$ex/double_pendulum.mech" --trace 'rod2(0.5, 0)'
check "--trace without --svg: exit 2" status_is 2
check "--trace without --svg: says so" err_has "--trace goes with --svg"
run "$ex/double_pendulum.mech" --method euler
check "--method euler: exit 2" status_is 2
cat > "$tmp/free.mech" <<'EOF'
body rod phi = -pi/3
revolute O: ground rod
mass rod m = 2 J = 2/12 com(0.5, 0)
coord z = 0
gravity (0, -9.81)
EOF
run "$tmp/free.mech" --t1 1
check "a massless free coordinate: exit 1" status_is 1
check "a massless free coordinate: t = 0 and singular" err_matches 't = 0: .*singular'

# ---- motions that cannot go on end with exit 1, the time and the rows ----
# A disk rolling on z = 0, leaning 0.3 rad, falls flat at t = 0.607: its
# contact's normal (the unit horizontal part of the axle) is 0/0 there, the
# rows roll.h and roll.x not defined. rk8pd and rkf45 crept on with steps
# of 5e-10 s for minutes, msbdf stepped through the flat state: every
# method and both linear-algebra paths now stop there.
cat > "$tmp/disk.mech" <<'EOF'
spatial
param R = 0.5
param a = 0.3
body disk x = 0  y = -R*sin(a)  z = R*cos(a)  orient = axis(1, 0, 0, a)
rolling roll: disk  radius = R  axis(0, 1, 0)
mass disk m = 1 J = (R^2/4, R^2/2, R^2/4)
gravity (0, 0, -9.81)
EOF
for m in rk8pd rkf45 rk4imp msbdf; do
    for l in dense sparse; do
        run "$tmp/disk.mech" --t1 2 --steps 20 --method "$m" --linear "$l"
        check "disk falling flat, $m $l: exit 1" status_is 1
        check "disk falling flat, $m $l: the time it lies flat" \
            err_matches 'error: t = 0\.6071[0-9]*: integration failed'
        check "disk falling flat, $m $l: its rows, not defined there" \
            err_matches 'turned abruptly (roll\.h and roll\.x): the rows are not smooth or not defined'
        check "disk falling flat, $m $l: the states before written" out_lines 8
    done
done
# A pendulum braked by dry friction (a torque -20 sign(w), written
# -20 w / sqrt(w^2 + 1e-200)) comes to rest at t = 0.0337 and sticks: the
# right side jumps at w = 0 and the steps collapse (watch.c) rather than
# underflow, with smooth rows.
cat > "$tmp/friction.mech" <<'EOF'
body rod x = 0.5 y = 0 phi = 0
revolute O: ground(0, 0) rod(-0.5, 0)
mass rod m = 1 J = 0.1
gravity (0, -9.81)
torque F: rod = -20*der(rod.phi)/sqrt(der(rod.phi)^2 + 1e-200)
EOF
for m in rk8pd msbdf; do
    run "$tmp/friction.mech" --t1 1 --qd 0,0,3 --method "$m" --linear dense
    check "dry friction sticking, $m: exit 1" status_is 1
    check "dry friction sticking, $m: the step size collapsed, and when" \
        err_matches 'friction.mech: error: t = 0\.03373[0-9]*: integration failed: the step size collapsed (1000 steps of [0-9.e-]* on average, [0-9]* attempts rejected; steps of [0-9.e-]* before): the motion reached a state the integrator cannot cross'
    check "dry friction sticking, $m: the 4 states before written" out_lines 5
done
# Smooth rows turn far in the long steps of loose tolerances: not a failure.
for f in a01_pendulum heavy_top; do
    run "$ex/$f.mech" --t1 5 --steps 2 --rtol 1e-2 --atol 1e-2
    check "$f at --rtol 1e-2, long steps turning its rows: exit 0" status_is 0
done

# ---- bounded work: --max-steps, and --steps beyond it ----
run "$ex/a01_pendulum.mech" --t1 200 --max-steps 2000
check "--t1 200 --max-steps 2000: exit 1" status_is 1
check "--t1 200 --max-steps 2000: the time reached and the option" \
    err_matches 'error: t = [0-9.]*: integration failed: more than 2000 integrator steps (--max-steps) at [0-9.e-]*% of the interval from t = 0 to 200'
# a span the budget cannot cover at this rate ends once a hundredth of it
# is spent (--t1 1e9 at the default budget: 2e10 steps needed, once a
# minute of CPU before the budget's end; the outside corpus)
for budget in "" "--max-steps 2000"; do
    # shellcheck disable=SC2086 # the option and its value are two words
    run "$ex/a01_pendulum.mech" --t1 1e9 $budget
    check "--t1 1e9 $budget: exit 1" status_is 1
    check "--t1 1e9 $budget: the forecast, the time reached and the option" \
        err_matches 'error: t = [0-9.]*: integration failed: [0-9]* integrator steps so far, at this rate about [0-9.e+]* for the whole interval: more than [0-9]* (--max-steps) at [0-9.e-]*% of the interval from t = 0 to 1000000000'
done
run "$ex/a01_pendulum.mech" --steps 20000 --max-steps 1000
check "--steps beyond --max-steps: exit 2" status_is 2
check "--steps beyond --max-steps: says so" \
    err_has "--steps 20000 output states need at least as many integrator steps, more than --max-steps 1000"
check "--steps beyond --max-steps: nothing on stdout" out_lines 0
run "$ex/a01_pendulum.mech" --max-steps 0
check "--max-steps 0: exit 2" status_is 2

# ---- the note run prints when assembly moves the file's values ----
cat > "$tmp/moved.mech" <<'EOF'
body rod x = 0.3 phi = -pi/3
revolute O: ground rod
driver D: rod.phi = -pi/3 + t
mass rod m = 2 J = 2/12 com(0.5, 0)
gravity (0, -9.81)
EOF
run_mechc run "$tmp/moved.mech" --steps 1
cp "$tmp/err" "$tmp/run_err"
run "$tmp/moved.mech" --t1 0.01 --steps 1
check "moved initial values: sim exit 0" status_is 0
check "moved initial values: sim notes the move" \
    err_has "note: assembly at t = 0 moved the initial values by up to 0.3 (rod.x: 0.3 -> 0)"
check "moved initial values: sim's note is run's" \
    test "$(grep note: "$tmp/err")" = "$(grep note: "$tmp/run_err")"

suite_end
