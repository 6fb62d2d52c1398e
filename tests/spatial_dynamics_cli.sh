#!/bin/sh
# tests/spatial_dynamics_cli.sh MECHC - dynamics of spatial (Euler-parameter) bodies, against references no one here wrote.
#
#   sh tests/spatial_dynamics_cli.sh build/mechc
#
# The spatial slider-crank's motor torque (run --forces) against the
# planar closed-form table and the planar file's; a heavy symmetric top's
# steady precession against Goldstein's exact relation; a compound
# spherical pendulum's period against 2 pi sqrt(I / (m g a)) with the
# amplitude correction, and its energy (computed here from the CSV)
# over a conical motion; check, eval, gen and bad input on spatial masses.
# The last line is "spatial_dynamics_cli: N passed, M failed".
set -u
# shellcheck source=tests/lib.sh
. "$(dirname "$0")/lib.sh"
suite_begin spatial_dynamics_cli "${1:-build/mechc}"

# run ARGS..., sim ARGS...: mechc run / mechc sim (tests/lib.sh).
run() { run_mechc run "$@"; }
sim() { run_mechc sim "$@"; }

# column NAME FILE: the CSV column NAME, one value a line.
column() {
    awk -F, -v name="$1" 'NR == 1 { for (i = 1; i <= NF; i++) if ($i == name) c = i; next }
                          c { print $c }' "$2"
}

# close_rel A B TOL: |A - B| <= TOL max(|B|, 1) (A not empty).
close_rel() {
    awk -v a="$1" -v b="$2" -v tol="$3" 'BEGIN {
        d = a - b; if (d < 0) d = -d; s = b < 0 ? -b : b; if (s < 1) s = 1
        ok = a != "" && d <= tol * s
        if (!ok) printf "  got %s, want %s (error %.3g > %s)\n", a, b, d / s, tol > "/dev/stderr"
        exit !ok }'
}

# ---- the spatial slider-crank's motor torque = the planar closed form ----
sc=$ex/slider_crank_spatial_torque.mech
run "$sc" --forces --steps 12 --csv "$tmp/sc3.csv"
check "spatial slider-crank torque: exit 0" status_is 0
column 'effort(D)' "$tmp/sc3.csv" > "$tmp/sc3.effort"
# the table of slider_crank_torque.mech (g = 9.81), theta = 0, 30, ..., 360 deg
printf '%s\n' 1.4715 1.99288516501141 1.13103964241246 -0.348943209981944 -1.26630317393169 \
    -1.56866853899195 -1.4715 -0.980044224345654 -0.205196826068313 0.348943209981944 \
    0.340460357587543 0.555827598326197 1.4715 > "$tmp/table"
table_error() {
    paste -d, "$tmp/sc3.effort" "$tmp/table" | awk -F, '
        { d = $1 - $2; if (d < 0) d = -d; if (d > m) m = d; n++ }
        END { if (n != 13 || m > 1e-9) { printf "  %d rows, largest error %.3g\n", n, m > "/dev/stderr"; exit 1 } }'
}
check "spatial slider-crank torque: effort(D) = the closed-form table to 1e-9 N m" table_error
run "$ex/slider_crank_torque.mech" --forces --steps 360 --csv "$tmp/sc2.csv"
run "$sc" --forces --steps 360 --csv "$tmp/sc3.csv"
planar_error() {
    paste -d, "$tmp/a" "$tmp/b" | awk -F, '
        { d = $1 - $2; if (d < 0) d = -d; if (d > m) m = d; n++ }
        END { if (n != 361 || m > 1e-9) { printf "  %d rows, largest difference %.3g\n", n, m > "/dev/stderr"; exit 1 } }'
}
column 'effort(D)' "$tmp/sc2.csv" > "$tmp/a"
column 'effort(D)' "$tmp/sc3.csv" > "$tmp/b"
check "spatial slider-crank torque: effort(D) = the planar file's at 361 steps to 1e-9" planar_error
run "$sc" --forces --steps 360 --engine generic --csv "$tmp/sc3g.csv"
column 'effort(D)' "$tmp/sc3g.csv" > "$tmp/b"
check "spatial slider-crank torque: the generic engine's effort(D) too" planar_error

# ---- the heavy symmetric top: steady precession ----
top_qd=0.078444083484950244,0,0,0,0,-7.0840904187543625,49.497166583500075
# the reference, computed from heavy_top.mech's parameters
omega=$(awk 'BEGIN { m = 1; l = 0.1; J1 = 0.002; J3 = 0.004; g = 9.81; th = 0.3; w3 = 100
    I1 = J1 + m * l * l; A = I1 * cos(th); B = J3 * w3; C = m * g * l
    printf "%.17g", (B - sqrt(B * B - 4 * A * C)) / (2 * A) }')
for engine in jit generic; do
    sim "$ex/heavy_top.mech" --t1 1 --steps 10 --qd "$top_qd" --engine "$engine" --csv "$tmp/top.csv"
    check "heavy top ($engine): exit 0" status_is 0
    az=$(awk -F, 'NR > 1 && $1 == 1 { printf "%.17g", atan2($3, $2) + atan2(1, 0) }' "$tmp/top.csv")
    check "heavy top ($engine): azimuth at t = 1 is Omega t (Goldstein's steady precession) to 1e-7" \
        close_rel "$az" "$omega" 1e-7
    height() {
        awk -F, 'NR > 1 { d = $4 - 0.1 * cos(0.3); if (d < 0) d = -d; if (d > m) m = d }
                 END { if (m > 1e-9) { printf "  height off by %.3g\n", m > "/dev/stderr"; exit 1 } }' "$tmp/top.csv"
    }
    check "heavy top ($engine): the tilt stays theta (height l cos theta to 1e-9 m)" height
done
# the same start as an angular velocity (--w, global frame): w = Omega z + psi' k,
# k = (0, -sin theta, cos theta), psi' = w3 - Omega cos theta
top_w=$(awk -v O="$omega" 'BEGIN { th = 0.3; p = 100 - O * cos(th)
    printf "%.17g,%.17g,%.17g", 0, -p * sin(th), O + p * cos(th) }')
sim "$ex/heavy_top.mech" --t1 1 --steps 10 --qd 0.078444083484950244,0,0,0,0,0,0 --w "top=$top_w" \
    --csv "$tmp/topw.csv"
check "heavy top, --w top=...: exit 0" status_is 0
az=$(awk -F, 'NR > 1 && $1 == 1 { printf "%.17g", atan2($3, $2) + atan2(1, 0) }' "$tmp/topw.csv")
check "heavy top, --w: azimuth at t = 1 is Omega t to 1e-7 (the rates from w)" close_rel "$az" "$omega" 1e-7
sim "$ex/heavy_top.mech" --w "ground=1,2,3"
check "--w of ground: exit 2 naming what it takes" err_has "--w takes B=WX,WY,WZ with B a spatial body"
sim "$ex/heavy_top.mech" --w "top=1,2"
check "--w with two numbers: exit 2" status_is 2
# a body given twice took its last value, silently (the outside corpus)
sim "$ex/heavy_top.mech" --w "top=1,2,3" --w "top=0,0,0"
check "--w twice for one body: exit 2" status_is 2
check "--w twice for one body: said" err_has "mechc sim: error: --w: body 'top' is given more than once"
# the gyroscopic approximation m g l / (I3 w3) = 2.4525 is not it (the test can tell them apart)
check "heavy top: the exact rate differs from the gyroscopic approximation" \
    awk -v w="$omega" 'BEGIN { exit !(w - 2.4525 > 0.1) }'

# ---- the compound spherical pendulum ----
sim "$ex/spherical_pendulum.mech" --t1 7 --steps 7000 --csv "$tmp/sp.csv"
check "spherical pendulum: exit 0" status_is 0
period=$(awk -F, 'NR > 1 { t = $1; y = $3; if (NR > 2 && py > 0 && y <= 0) { n++; c[n] = pt + (t - pt) * py / (py - y) }
                          pt = t; py = y }
                  END { if (n >= 2) printf "%.17g", (c[n] - c[1]) / (n - 1) }' "$tmp/sp.csv")
want=$(awk 'BEGIN { L = 1; rho = 0.02; m = 2; g = 9.81; a = L / 2; th0 = 0.01
    I = m * (3 * rho * rho + 4 * L * L) / 12
    printf "%.17g", 2 * 3.14159265358979324 * sqrt(I / (m * g * a)) * (1 + th0 * th0 / 16) }')
check "spherical pendulum: period = 2 pi sqrt(I / (m g a)) (1 + th0^2/16) to 1e-6" \
    close_rel "$period" "$want" 1e-6
plane() { awk -F, 'NR > 1 { x = $2 < 0 ? -$2 : $2; if (x > m) m = x } END { exit !(m < 1e-12) }' "$tmp/sp.csv"; }
check "spherical pendulum: a swing in the y-z plane stays there (x < 1e-12)" plane

# a conical motion from 0.6 rad, turning at 3 rad/s about the vertical:
# xd = w x r, ed = E^T w / 2
sed 's/^param th0 = 0.01/param th0 = 0.6/' "$ex/spherical_pendulum.mech" > "$tmp/cone.mech"
cone_qd=$(awk 'BEGIN { W = 3; th = 0.6
    printf "%.17g,0,0,0,0,%.17g,%.17g", -W * 0.5 * sin(th), 0.5 * W * sin(th / 2), 0.5 * W * cos(th / 2) }')
sim "$tmp/cone.mech" --t1 10 --steps 1000 --qd "$cone_qd" --csv "$tmp/cone.csv"
check "spherical pendulum, conical: exit 0" status_is 0
# E = m |v|^2 / 2 + (J1 |w|^2 + (J3 - J1) (w.k)^2) / 2 + m g z, k = A(e) z_body
energy() {
    awk -F, 'NR == 1 { for (i = 1; i <= NF; i++) c[$i] = i; next }
        { m = 2; L = 1; rho = 0.02; g = 9.81; J1 = m * (3 * rho^2 + L^2) / 12; J3 = m * rho^2 / 2
          e0 = $c["rod.e0"]; e1 = $c["rod.e1"]; e2 = $c["rod.e2"]; e3 = $c["rod.e3"]
          kx = 2 * (e1 * e3 + e0 * e2); ky = 2 * (e2 * e3 - e0 * e1); kz = 2 * e0^2 - 1 + 2 * e3^2
          wx = $c["rod.wx"]; wy = $c["rod.wy"]; wz = $c["rod.wz"]; wk = wx * kx + wy * ky + wz * kz
          v2 = $c["d(rod.x)"]^2 + $c["d(rod.y)"]^2 + $c["d(rod.z)"]^2
          T = m * v2 / 2 + (J1 * (wx^2 + wy^2 + wz^2) + (J3 - J1) * wk^2) / 2
          E = T + m * g * $c["rod.z"]
          if (NR == 2) E0 = E; d = E - E0; if (d < 0) d = -d; if (d > dmax) dmax = d
          if (T > tmax) tmax = T }
        END { if (!(dmax <= 1e-9 * tmax)) { printf "  energy drift %.3g of %.3g\n", dmax, tmax > "/dev/stderr"; exit 1 } }' "$tmp/cone.csv"
}
check "spherical pendulum, conical: energy (from the CSV) conserved to 1e-9 of T over 10 s" energy

# ---- check, eval, gen on spatial masses ----
for f in slider_crank_spatial_torque heavy_top spherical_pendulum; do
    run_mechc check "$ex/$f.mech" --samples 10
    check "$f: check exits 0" status_is 0
    check "$f: check compares M and Q between engines and Q's velocity terms with M's" \
        sh -c "grep -q '^ok   M jit/generic' '$tmp/out' && grep -q '^ok   Q velocity fd' '$tmp/out' && ! grep -q FAIL '$tmp/out'"
done
run_mechc eval "$ex/heavy_top.mech" --qd 0,0,0,0.1,0.2,-0.3,0.4
check "heavy top: eval prints M and Q" sh -c "grep -q 'Mass matrix M' '$tmp/out' && grep -q 'top.e3' '$tmp/out'"
if have cc; then
    for real in double float; do
        run_mechc gen "$ex/heavy_top.mech" -o "$tmp/top_$real.c" --header "$tmp/top_$real.h" \
            --prefix top --real "$real"
        check "heavy top: gen --real $real" status_is 0
        check "heavy top: the written $real file compiles as C99 with -Wall -Werror" \
            cc -std=c99 -Wall -Wextra -Werror -c "$tmp/top_$real.c" -o "$tmp/top_$real.o"
        check "heavy top: the written $real file has the dynamics kernels" grep -q 'top_eom' "$tmp/top_$real.c"
    done
else
    skip "no cc: the written files are not compiled"
fi

# ---- pictures: sim draws a spatial mechanism as run does ----
sim "$ex/heavy_top.mech" --t1 0.2 --steps 10 --qd "$top_qd" --svg "$tmp/top.svg" --view front \
    --trace 'top(0, 0, 0.1)' --csv "$tmp/top.csv"
check "heavy top: sim --svg --view front exits 0" status_is 0
check "heavy top: the animation has the top's path" grep -q '<svg' "$tmp/top.svg"
sim "$ex/pendulum_dynamics.mech" --svg "$tmp/p.svg" --view top --csv "$tmp/p.csv"
check "sim --view on a planar file: exit 2" status_is 2
check "sim --view on a planar file: says why" err_has "--view chooses how a spatial mechanism is seen"

# ---- bad input ----
printf 'spatial\nbody a z = -1\nspherical O: ground(0, 0, 0) a(0, 0, 1)\nmass a m = 1 J = (1, 1, 1) Jxz = 1.5\n' > "$tmp/bad.mech"
run_mechc sim "$tmp/bad.mech"
check "a tensor that is not positive definite: exit 2" status_is 2
check "a tensor that is not positive definite: FILE:LINE:COL" err_has "bad.mech:4:14: error: the inertia tensor of 'a' is not positive definite"
check "a tensor that is not positive definite: the caret" err_matches '^ *\^'
printf 'spatial\nbody a z = -1\nspherical O: ground(0, 0, 0) a(0, 0, 1)\nmass a m = 1 J = (1, -1, 1)\n' > "$tmp/bad.mech"
run_mechc run "$tmp/bad.mech" --forces
check "a negative moment of inertia: exit 2" status_is 2
check "a negative moment of inertia: FILE:LINE:COL" err_has "bad.mech:4:22: error: the moment of inertia Jyy of mass 'a' is negative"

suite_end
