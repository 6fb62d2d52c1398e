#!/bin/sh
# tests/run_cli.sh MECHC - `mechc run` from the outside: exit statuses, the
# CSV header and rows, JSON keys (also after a failure), the failure
# messages with their times, every example running (or failing the way its
# header says), engines agreeing, and the firmware path: `mechc gen` output
# with MECHRT_DEFINE_KERNELS and the runtime built by cc -std=c99 -pedantic,
# double and float.
#
#   sh tests/run_cli.sh build/mechc
#
# The last line is "run_cli: N passed, M failed"; the exit status is
# non-zero on any failure. Checks needing cc or python3 are skipped (and say
# so) when those are missing.
set -u
# shellcheck source=tests/lib.sh
. "$(dirname "$0")/lib.sh"
suite_begin run_cli "${1:-build/mechc}"

# run ARGS...: mechc run ARGS (tests/lib.sh).
run() { run_mechc run "$@"; }

# value_at T NAME FILE: the value of column NAME in the row whose t is T
# (one awk, tests/lib.sh's; head, tr, grep and cut were four processes more).
value_at() { csv_value_at "$@"; }

# near A B TOL: |A - B| <= TOL
near() {
    awk -v a="$1" -v b="$2" -v tol="$3" 'BEGIN { d = a - b; if (d < 0) d = -d; exit !(a != "" && d <= tol) }'
}

# ---- spatial mechanisms (doc/spatial.md) ---------------------------------
# slider_crank_spatial.mech equals slider_crank.mech: x, y of every body,
# phi = 2 atan2(e3, e0) (mod 2 pi), d(phi) = 2 (e0 e3' - e3 e0') = wz and
# dd(phi) = 2 (e0 e3'' - e3 e0''), every step, to 1e-12
run "$ex/slider_crank.mech" --csv "$tmp/sc2.csv"
run "$ex/slider_crank_spatial.mech" --csv "$tmp/sc3.csv"
check "spatial slider-crank: exit 0" status_is 0
check "spatial slider-crank: as many rows as the planar run" \
    test "$(wc -l < "$tmp/sc2.csv")" = "$(wc -l < "$tmp/sc3.csv")"
check "spatial slider-crank: the wz columns follow the d() columns" \
    sh -c "head -1 '$tmp/sc3.csv' | grep -q ',d(slider.e3),crank.wx,crank.wy,crank.wz,rod.wx,'"
# spatial_vs_planar: the largest difference over every body, quantity and step
spatial_vs_planar() {
    paste -d, "$tmp/sc2.csv" "$tmp/sc3.csv" | awk -F, '
    NR == 1 { for (i = 1; i <= NF; i++) if (!($i in c)) c[$i] = i; else c2[$i] = i; next }
    function col(name) { return (name in c2) ? c2[name] : c[name] }
    function v(name) { return $(col(name)) }
    function wrap(a) { while (a > pi) a -= 2 * pi; while (a < -pi) a += 2 * pi; return a }
    function put(d) { if (d < 0) d = -d; if (d > worst) worst = d }
    BEGIN { pi = atan2(0, -1); worst = 0 }
    {
        split("crank rod slider", b, " ")
        for (k = 1; k <= 3; k++) {
            n = b[k]
            put(v(n ".x") - $(c[n ".x"])); put(v(n ".y") - $(c[n ".y"]))
            put(v("d(" n ".x)") - $(c["d(" n ".x)"])); put(v("d(" n ".y)") - $(c["d(" n ".y)"]))
            put(v("dd(" n ".x)") - $(c["dd(" n ".x)"])); put(v("dd(" n ".y)") - $(c["dd(" n ".y)"]))
            e0 = v(n ".e0"); e3 = v(n ".e3")
            put(wrap(2 * atan2(e3, e0) - $(c[n ".phi"])))
            put(2 * (e0 * v("d(" n ".e3)") - e3 * v("d(" n ".e0)")) - $(c["d(" n ".phi)"]))
            put(v(n ".wz") - $(c["d(" n ".phi)"]))
            put(2 * (e0 * v("dd(" n ".e3)") - e3 * v("dd(" n ".e0)")) - $(c["dd(" n ".phi)"]))
            put(v(n ".z")); put(v(n ".e1")); put(v(n ".e2"))
        }
    }
    END { printf "largest difference %.3g\n", worst > "/dev/stderr"; exit !(NR > 100 && worst <= 1e-12) }'
}
check "spatial slider-crank: x, y, phi and their rates equal the planar file's to 1e-12" spatial_vs_planar
# the RSSR's output angle against its closed form (examples/rssr.mech)
run "$ex/rssr.mech" --steps 8 --csv "$tmp/rssr.csv"
check "rssr: exit 0" status_is 0
rssr_closed_form() {
    awk -F, '
    NR == 1 { for (i = 1; i <= NF; i++) c[$i] = i; next }
    function acos(x) { return atan2(sqrt(1 - x * x), x) }
    BEGIN { pi = atan2(0, -1); worst = 0 }
    {
        th = 2 * pi * $1
        P = 6 * (2 - cos(th)); Q = -3 * sqrt(2) * sin(th); R = 4 * cos(th) - 4
        psi = atan2(Q, P) + acos(R / sqrt(P * P + Q * Q))
        d = $(c["psi"]) - psi
        while (d > pi) d -= 2 * pi; while (d < -pi) d += 2 * pi
        if (d < 0) d = -d; if (d > worst) worst = d
    }
    END { exit !(NR == 10 && worst <= 1e-9) }' "$tmp/rssr.csv"
}
check "rssr: psi = atan2(Q, P) + acos(R / sqrt(P^2 + Q^2)) at 9 crank angles, to 1e-9" rssr_closed_form
check "rssr: psi(0.25) = 1.5506466765" near "$(value_at 0.25 psi "$tmp/rssr.csv")" 1.5506466764710545 1e-9
# the Stewart platform: forward kinematics (Newton from the previous pose)
# gives back the trajectory whose inverse kinematics drives the legs
# (examples/stewart.mech): pose, rates and accelerations at every step
run "$ex/stewart.mech" --steps 40 --csv "$tmp/stewart.csv"
check "stewart: exit 0" status_is 0
stewart_closed_form() {
    awk -F, '
    NR == 1 { for (i = 1; i <= NF; i++) c[$i] = i; next }
    function put(name, want, level,   d) {
        if (!(name in c)) { missing = name; return }
        d = $(c[name]) - want; if (d < 0) d = -d
        if (d > worst[level]) worst[level] = d
    }
    BEGIN { pi = atan2(0, -1); w = 2 * pi; k = 0.125; u[1] = 1 / 3; u[2] = u[3] = 2 / 3 }
    {
        t = $1; s = sin(w * t); co = cos(w * t)
        put("top.x", 0.1 * s, 0); put("d(top.x)", 0.1 * w * co, 1); put("dd(top.x)", -0.1 * w * w * s, 2)
        put("top.y", 0.08 * sin(2 * w * t), 0); put("d(top.y)", 0.16 * w * cos(2 * w * t), 1)
        put("dd(top.y)", -0.32 * w * w * sin(2 * w * t), 2)
        put("top.z", 1 + 0.1 * (1 - co), 0); put("d(top.z)", 0.1 * w * s, 1); put("dd(top.z)", 0.1 * w * w * co, 2)
        # e0 = (1 + g^2)^(-1/2), e = u g e0, g = k sin wt
        g = k * s; gd = k * w * co; gdd = -k * w * w * s; m = 1 + g * g
        e0 = m ^ -0.5; e0d = -g * gd * m ^ -1.5
        e0dd = -(gd * gd + g * gdd) * m ^ -1.5 + 3 * g * g * gd * gd * m ^ -2.5
        put("top.e0", e0, 0); put("d(top.e0)", e0d, 1); put("dd(top.e0)", e0dd, 2)
        for (j = 1; j <= 3; j++) {
            put("top.e" j, u[j] * g * e0, 0); put("d(top.e" j ")", u[j] * (gd * e0 + g * e0d), 1)
            put("dd(top.e" j ")", u[j] * (gdd * e0 + 2 * gd * e0d + g * e0dd), 2)
        }
        n++
    }
    END {
        printf "stewart: worst position %.3g, velocity %.3g, acceleration %.3g\n", worst[0], worst[1], worst[2] > "/dev/stderr"
        exit !(n == 41 && missing == "" && worst[0] <= 1e-9 && worst[1] <= 1e-9 && worst[2] <= 1e-9)
    }' "$tmp/stewart.csv"
}
check "stewart: pose, rates and accelerations equal the closed-form trajectory at 41 instants, to 1e-9" stewart_closed_form
check "stewart: e1(0.25) = 0.125/(3 sqrt(1 + 0.125^2))" near "$(value_at 0.25 top.e1 "$tmp/stewart.csv")" 0.041344911529736156 1e-12
# the double-wishbone suspension: camber and toe against an independent
# computation of the same geometry (tests/suspension_reference.awk)
run "$ex/suspension.mech" --steps 20 --csv "$tmp/suspension.csv"
check "suspension: exit 0" status_is 0
check "suspension: camber and toe at 21 travels equal the step-by-step geometry to 1e-9 deg" \
    awk -F, -v tol=1e-9 -f "$(dirname "$0")/suspension_reference.awk" "$tmp/suspension.csv"
check "suspension: camber 0 at zero travel" near "$(value_at 0.5 camber_deg "$tmp/suspension.csv")" 0 1e-9
check "suspension: toe 0 at zero travel" near "$(value_at 0.5 toe_deg "$tmp/suspension.csv")" 0 1e-9
check "suspension: camber -2.641 deg at 80 mm of bump" near "$(value_at 1 camber_deg "$tmp/suspension.csv")" -2.641433191371 1e-9
check "suspension: toe -0.187 deg at 80 mm of rebound" near "$(value_at 0 toe_deg "$tmp/suspension.csv")" -0.187234746379 1e-9
# examples/chain_spatial.sh: N bodies, 7N coordinates; every rod turns with
# the first by a = 0.5 sin(2 pi t) about y, so e2 = sin(a/2), e0 = cos(a/2)
sh "$ex/chain_spatial.sh" 4 "$tmp/chain_spatial_4.mech"
run "$tmp/chain_spatial_4.mech" --steps 8 --csv "$tmp/chain_spatial.csv"
check "chain_spatial.sh 4: runs (exit 0)" status_is 0
check "chain_spatial.sh 4: 28 coordinates" sh -c "head -1 '$tmp/chain_spatial.csv' | grep -q ',rod3.e3,' && ! grep -q rod4 '$tmp/chain_spatial.csv'"
check "chain_spatial.sh 4: every rod at the first rod's angle, to 1e-12" awk -F, '
    NR == 1 { for (i = 1; i <= NF; i++) c[$i] = i; next }
    {
        a = 0.5 * sin(2 * atan2(0, -1) * $1)
        for (k = 0; k < 4; k++) {
            d = $(c["rod" k ".e2"]) - sin(a / 2); if (d < 0) d = -d; if (d > w) w = d
            d = $(c["rod" k ".e0"]) - cos(a / 2); if (d < 0) d = -d; if (d > w) w = d
        }
        n++
    }
    END { exit !(n == 9 && w <= 1e-12) }' "$tmp/chain_spatial.csv"
run_mechc gen "$tmp/chain_spatial_4.mech" --stats -o /dev/null
check "chain_spatial.sh 4: 28 rows" err_has "28 coordinates, 28 rows"
sh "$ex/chain_spatial.sh" 0 > /dev/null 2>&1
check "chain_spatial.sh 0: refused (exit 2)" test $? = 2
# omega in JSON, beside the Euler-parameter rates
run "$ex/rolling_disk.mech" --steps 2 --json
check "rolling disk: runs (integrated, projected)" status_is 0
check "rolling disk JSON: omega_names" out_has '"omega_names": ["disk.wx", "disk.wy", "disk.wz"]'
check "rolling disk JSON: wz = 0.4 at t = 0 (its Turn driver), wy = V/R = 1" out_has '"omega": [[0, 1, 0.4]'
run "$ex/slider_crank.mech" --steps 2 --json
check "planar JSON: no omega key" sh -c "! grep -q omega '$tmp/out'"
# pictures: the animation in an orthographic view (--view, default iso), and --plot
run "$ex/rssr.mech" --svg "$tmp/rssr.svg" --trace 'rocker(3, 0, 0)'
check "spatial --svg: exit 0" status_is 0
check "spatial --svg: the iso view by default" grep -q "(the iso view, orthographic" "$tmp/rssr.svg"
check "spatial --svg: two links that move" \
    sh -c '[ "$(grep -c "<polyline class=\"link\".*<title>" "$1")" = 2 ] && grep -q "<animate attributeName=\"points\"" "$1"' _ "$tmp/rssr.svg"
check "spatial --svg: the ground pivots marked" sh -c '[ "$(grep -c "class=\"pivot\"" "$1")" = 2 ]' _ "$tmp/rssr.svg"
check "spatial --trace BODY(sx, sy, sz): its path" grep -q "path of rocker(3, 0, 0)" "$tmp/rssr.svg"
run "$ex/all_spatial.mech" --t1 1 --svg "$tmp/all_spatial.svg"
check "spatial --svg: a point output's path is drawn" grep -q "path of wtip" "$tmp/all_spatial.svg"
# the crank of slider_crank_spatial at t = 0.25 points along +y from the
# origin: the top view shows it upright (one pixel column, r tall), the front
# view as a point, the side view lying (one pixel row)
crank_px() {   # crank_px VIEW: the crank link's first-frame points, "X0 Y0 X1 Y1"
    "$mechc" run "$ex/slider_crank_spatial.mech" --t0 0.25 --svg "$tmp/v_$1.svg" --view "$1" 2>/dev/null &&
        sed -n 's/.*<polyline class="link" points="\([^"]*\)".*<title>crank<\/title>.*/\1/p' "$tmp/v_$1.svg" | tr ', ' '  '
}
crank_is() {   # crank_is VIEW AWK-CONDITION on x0 y0 x1 y1
    set -- "$(crank_px "$1")" "$2"
    [ -n "$1" ] && echo "$1" | awk "{ x0 = \$1; y0 = \$2; x1 = \$3; y1 = \$4; exit !($2) }"
}
check "--view top: the crank upright (x right, y up)" crank_is top 'x0 == x1 && y1 < y0 - 50'
check "--view front: the crank end-on (x right, z up)" crank_is front 'x0 == x1 && y0 == y1'
check "--view side: the crank lying (y right, z up)" crank_is side 'y0 == y1 && x1 > x0 + 50'
check "--view front: said in the picture" grep -q "(the front view, orthographic" "$tmp/v_front.svg"
run "$ex/rssr.mech" --svg "$tmp/bad.svg" --view back
check "--view back: exit 2" status_is 2
check "--view back: names the choices" err_has "--view takes front, top, side or iso, not 'back'"
run "$ex/slider_crank.mech" --svg "$tmp/bad.svg" --view iso
check "--view on a planar file: exit 2" status_is 2
check "--view on a planar file: says why" err_has "--view chooses how a spatial mechanism is seen, and this one is planar"
run "$ex/rssr.mech" --view top
check "--view without --svg: exit 2" status_is 2
check "--view without --svg: says so" err_has "--view goes with --svg FILE"
run "$ex/rssr.mech" --svg "$tmp/bad.svg" --trace 'rocker(3, 0)'
check "spatial --trace B(sx, sy): exit 2, sz missing" \
    sh -c '[ "$1" = 2 ] && grep -q "expected .,. between sy and sz" "$2"' _ "$rc" "$tmp/err"
run "$ex/rssr.mech" --plot "$tmp/rssr_plot.svg" --plot-vars 'psi,d(psi)'
check "spatial --plot: exit 0" status_is 0
check "spatial --plot: a chart" grep -q "d(psi)" "$tmp/rssr_plot.svg"
# bad spatial input: FILE:LINE:COL, the line and a caret, exit 2
printf 'spatial\nbody b\nrevolute R: ground b axis(0, 0, 0)\n' > "$tmp/zero_axis.mech"
run "$tmp/zero_axis.mech"
check "zero axis: exit 2" status_is 2
check "zero axis: FILE:LINE:COL" err_has "zero_axis.mech:3:22: error: the axis of revolute 'R' is zero"
check "zero axis: the caret under the axis" err_matches '^ *\^'
printf 'body b\nspherical S: ground b\n' > "$tmp/not_spatial.mech"
run "$tmp/not_spatial.mech"
check "spatial joint in a planar file: exit 2" status_is 2
check "spatial joint in a planar file: says to write spatial" err_has "not_spatial.mech:2:1: error: 'spherical' is a spatial joint"
printf 'spatial\nbody b\npointline L: ground b axis(1, 0)\n' > "$tmp/planar_in_spatial.mech"
run "$tmp/planar_in_spatial.mech"
check "planar joint in a spatial file: exit 2" status_is 2
check "planar joint in a spatial file: names it" err_has "planar_in_spatial.mech:3:1: error: 'pointline' is a planar joint"

# ---- help and usage ------------------------------------------------------
run --help
check "run --help exits 0" status_is 0
check "run --help documents the CSV columns" grep -q "d(crank.x)" "$tmp/out"
run "$ex/slider_crank.mech" --svg "$tmp/anim.svg" --trace 'rod(0, 0)' --plot "$tmp/plot.svg" --plot-vars 'slider.x,d(slider.x)'
check "--svg: exit 0" status_is 0
check "--svg: no CSV on stdout when only pictures are asked for" out_empty
check "--svg: an animated SVG" grep -q "<animate" "$tmp/anim.svg"
check "--svg --trace: the path is drawn" grep -q "path of rod(0, 0)" "$tmp/anim.svg"
check "--plot: a chart with the legend entry" grep -q "d(slider.x)" "$tmp/plot.svg"
run "$ex/slider_crank.mech" --trace 'rod(0, 0)'
check "--trace without --svg: exit 2" status_is 2
run "$ex/slider_crank.mech" --plot "$tmp/p2.svg" --plot-vars 'nothing.x'
check "--plot-vars with an unknown name: exit 2" status_is 2
check "--plot-vars with an unknown name: names it" err_has "nothing"
# every name there is, outputs included (once only the first 8 of 24)
run "$ex/suspension.mech" --plot "$tmp/p2.svg" --plot-vars 'nothing.x'
check "--plot-vars unknown on suspension: exit 2" status_is 2
check "--plot-vars unknown on suspension: counts the names" \
    err_has "mechc run: error: --plot-vars: unknown coordinate or output 'nothing.x'; the 21 coordinates and 3 outputs are lca.x, lca.y,"
check "--plot-vars unknown on suspension: lists the last coordinate and the outputs" \
    err_has "upright.e2, upright.e3, camber_deg, toe_deg, travel"
check "--plot-vars unknown: no plot written" [ ! -e "$tmp/p2.svg" ]
run "$ex/slider_crank.mech" --svg "$tmp/a2.svg" --trace 'ghost(0,0)'
check "--trace of an unknown body: exit 2" status_is 2
run "$ex/slider_crank.mech" --steps -1
check "--steps -1: exit 2" status_is 2
run "$ex/slider_crank.mech" --engine warp
check "--engine warp: exit 2" status_is 2
run "$ex/slider_crank.mech" --t0 1 --t1 1
check "empty interval: exit 2" status_is 2
run "$ex/slider_crank.mech" --ode euler
check "--ode euler: exit 2" status_is 2
run "$ex/slider_crank.mech" --tol -1
check "--tol -1: exit 2" status_is 2
run "$ex/slider_crank.mech" --csv - --json
check "--csv - with --json: exit 2" status_is 2
run "$tmp/missing.mech"
check "missing file: exit 2" status_is 2

# ---- the slider-crank: CSV -----------------------------------------------
run "$ex/slider_crank.mech" --steps 8
check "slider_crank: exit 0" status_is 0
check "slider_crank: header + 9 rows" out_lines 10
check "slider_crank: header starts with t and the coordinates" \
    grep -q '^t,crank\.x,crank\.y,crank\.phi,rod\.x' "$tmp/out"
check "slider_crank: velocity and acceleration columns" \
    grep -q ',d(crank\.x),.*,dd(slider\.phi)$' "$tmp/out"
check "slider_crank: 28 columns" \
    awk -F, '{ if (NF != 28) exit 1 }' "$tmp/out"
cp "$tmp/out" "$tmp/sc.csv"
check "slider_crank: slider.x(0.25) = sqrt(0.08)" \
    near "$(value_at 0.25 slider.x "$tmp/sc.csv")" 0.28284271247461906 1e-12
check "slider_crank: slider.x(0.5) = 0.2" \
    near "$(value_at 0.5 slider.x "$tmp/sc.csv")" 0.2 1e-12
check "slider_crank: d(slider.x)(0.25) = -omega r" \
    near "$(value_at 0.25 'd(slider.x)' "$tmp/sc.csv")" -0.62831853071795865 1e-12
check "slider_crank: last t is exactly 1" \
    near "$(tail -1 "$tmp/sc.csv" | cut -d, -f1)" 1 0
check "slider_crank: nothing on stderr" [ ! -s "$tmp/err" ]

# ---- coarse steps: redone in substeps, not a jump to another branch -------
run "$ex/slider_crank.mech" --steps 4 --stats
check "--steps 4: exit 0" status_is 0
check "--steps 4: slider.x(0.25) = sqrt(0.08) on the right branch" \
    near "$(value_at 0.25 slider.x "$tmp/out")" 0.282842712474619 1e-9
check "--steps 4: slider.x(0.5) = 0.2 on the right branch" \
    near "$(value_at 0.5 slider.x "$tmp/out")" 0.2 1e-9
check "--steps 4 --stats: the steps redone are counted" err_has "redone in substeps"
run "$ex/slider_crank.mech" --steps 3 --max-substeps 1
check "--steps 3 --max-substeps 1: exit 1" status_is 1
check "--steps 3 --max-substeps 1: says the motion is too fast, at t = 0.333" \
    err_matches "t = 0\.3333333333: .*too fast for the step"
check "--steps 3 --max-substeps 1: the state at t = 0 is written" out_lines 2
run "$ex/slider_crank.mech" --max-substeps 0
check "--max-substeps 0: exit 2" status_is 2

run "$ex/slider_crank.mech" --steps 8 --csv "$tmp/file.csv"
check "--csv FILE: exit 0, stdout empty" out_empty
check "--csv FILE: same content as stdout" cmp -s "$tmp/file.csv" "$tmp/sc.csv"

run "$ex/slider_crank.mech" --steps 8 --digits 6
check "--digits 6: 0.282843" [ "$(value_at 0.25 slider.x "$tmp/out")" = "0.282843" ]

run "$ex/slider_crank.mech" --steps 1000 --stats --csv /dev/null
check "--stats: exit 0" status_is 0
check "--stats: Newton iterations per step" err_has "Newton iterations per step"
check "--stats: ns per step" err_has "ns per step"
check "--stats: cost in all-kernel calls" err_has "a step costs"
check "--stats: the kernels' unrolled LU factored" err_has "unrolled LU (the kernels' lu_factor): "
check "--stats: ... every time (the pattern LU never needed)" sh -c '! grep -q "pattern LU:" "$1"' sh "$tmp/err"

# ---- JSON ------------------------------------------------------------------
run "$ex/slider_crank.mech" --steps 4 --json
check "--json: exit 0" status_is 0
if have python3; then
    check "--json: keys and sizes" py -c '
import json, sys
d = json.load(open(sys.argv[1]))
assert list(d)[:5] == ["coords", "t", "q", "qd", "qdd"], list(d)
assert len(d["coords"]) == 9 and d["coords"][6] == "slider.x"
assert d["t"] == [0, 0.25, 0.5, 0.75, 1]
assert all(len(d[k]) == 5 and all(len(r) == 9 for r in d[k]) for k in ("q", "qd", "qdd"))
assert abs(d["q"][2][6] - 0.2) < 1e-12 and d["ok"] is True and "error" not in d
' "$tmp/out"
else
    skip "python3 missing: JSON checks"
fi

# ---- through singular positions (doc/singular.md) -------------------------
# The toggle slider-crank (r = l) meets the branch x = 0 at t = 0.25 and
# 0.75 and goes on along the smooth one it came on, x = 2 r cos(2 pi t).
run "$ex/slider_crank_toggle.mech" --stats
check "toggle: exit 0, through t = 0.25 and 0.75" status_is 0
check "toggle: 101 states (header + 101)" out_lines 102
check "toggle: slider.x = 0 at t = 0.25" near "$(value_at 0.25 slider.x "$tmp/out")" 0 1e-9
check "toggle: slider.x = -2 r at t = 0.5" near "$(value_at 0.5 slider.x "$tmp/out")" -0.4 1e-12
check "toggle: d(slider.x) = -2 r omega at t = 0.25" \
    near "$(value_at 0.25 'd(slider.x)' "$tmp/out")" -2.5132741228718345 1e-6
check "toggle --stats: the two steps by the rank-revealing corrector" \
    err_has "2 steps through singular positions by the rank-revealing corrector"

# IFToMM A02, the reproduction of the singular-position failure: a chain of 40 parallelograms
# turned through a full turn, flat at t = 0.25 and 0.75 (on the grid).
sh "$ex/chain.sh" 40 "$tmp/c40.mech"
sed -e 's/^driver drive: rod0.phi = .*/driver drive: rod0.phi = pi\/2 - 2*pi*t/' "$tmp/c40.mech" \
    > "$tmp/a02.mech"
run "$tmp/a02.mech" --steps 400 --stats
check "A02: exit 0" status_is 0
check "A02: 401 states" out_lines 402
check "A02 --stats: sparse, with the dense fallback at the two flat states" \
    err_has "2 steps through singular positions by the rank-revealing corrector (dense QR, where KLU found the Jacobian singular or too ill-conditioned"
check "A02 --stats: rank-deficient by 40 there" err_has "rank-deficient (by up to 40)"
# every rod at rod0's angle pi/2 - 2 pi t, every coupler horizontal; rates
# -2 pi and 0, accelerations 0: to 1e-8, 1e-6, 1e-4 in every state
check "A02: every angle, rate and acceleration on the parallelogram branch" awk -F, '
    function abs(x) { return x < 0 ? -x : x }
    NR == 1 { for (i = 2; i <= NF; i++) {
                  if ($i ~ /^rod[0-9]*\.phi$/) rod[i] = 1
                  if ($i ~ /^cpl[0-9]*\.phi$/) cpl[i] = 1 }
              nq = (NF - 1) / 3; next }
    { pi = 3.141592653589793; t = $1
      for (i in rod) { if (!(abs($i - (pi / 2 - 2 * pi * t)) <= 1e-8)) bad = bad " " t
                       if (!(abs($(i + nq) + 2 * pi) <= 1e-6)) bad = bad " d" t
                       if (!(abs($(i + 2 * nq)) <= 1e-4)) bad = bad " dd" t }
      for (i in cpl) { if (!(abs($i) <= 1e-8) || !(abs($(i + nq)) <= 1e-6) \
                           || !(abs($(i + 2 * nq)) <= 1e-4)) bad = bad " c" t }
      n++ }
    END { if (bad != "") print "off the branch at" bad > "/dev/stderr"; exit bad != "" || n != 401 }
' "$tmp/out"
cp "$tmp/out" "$tmp/a02.csv"
run "$ex/a02_chain.mech" --steps 400
check "examples/a02_chain.mech: the same run" cmp -s "$tmp/out" "$tmp/a02.csv"

# ---- failures ------------------------------------------------------------
# A slider pushed to its dead centre (crank 0.1, rod 0.3: x <= 0.4 at t = 1)
# and past it: no motion continues; the message says so, with the time.
cat > "$tmp/limit.mech" <<'EOF'
param r = 0.1
param l = 0.3
body crank  x = 0.05 y = 0 phi = 0
body rod    x = 0.25 y = 0 phi = 0
body slider x = 0.4  y = 0 phi = 0
revolute O: ground(0, 0) crank(-r/2, 0)
revolute A: crank(r/2, 0) rod(-l/2, 0)
revolute B: rod(l/2, 0) slider(0, 0)
prismatic P: ground(0, 0) slider(0, 0) axis(1, 0)
driver D: slider.x = 0.3 + 0.1*t
EOF
run "$tmp/limit.mech" --t1 2 --steps 20
check "dead centre passed: exit 1" status_is 1
check "dead centre passed: the message names t = 1" err_matches "error: t = 1: "
check "dead centre passed: names crank.phi" err_matches "crank\.phi"
check "dead centre passed: the corrector's verdict" \
    err_has "the rank-revealing corrector found no motion that continues the branch either (at t = 1: "
check "dead centre passed: the 10 states before are written (header + 10)" out_lines 11
run "$tmp/limit.mech" --t1 2 --steps 20 --linear sparse
check "dead centre passed, sparse: exit 1" status_is 1
check "dead centre passed, sparse: the dependent rows and the free direction named" \
    err_matches "singular along rows .* and coordinates crank\.phi and rod\.phi"
check "dead centre passed: the last row written is t = 0.9" \
    [ "$(tail -1 "$tmp/out" | cut -d, -f1)" = "0.9" ]
run "$tmp/limit.mech" --t1 2 --steps 20 --json
check "dead centre passed --json: exit 1" status_is 1
if have python3; then
    check "dead centre passed --json: valid, 10 states, ok false, the error's time" py -c '
import json, sys
d = json.load(open(sys.argv[1]))
assert len(d["t"]) == 10 and len(d["q"]) == 10 and d["t"][-1] == 0.9
assert d["ok"] is False and d["error"]["t"] == 1
assert d["error"]["message"].startswith("t = 1: ")
' "$tmp/out"
fi
run "$tmp/limit.mech" --t1 0.9 --steps 9
check "dead centre, t1 = 0.9: exit 0" status_is 0

cat > "$tmp/reach.mech" <<'EOF'
# a point on the unit circle pulled along x past its reach (x = 1 at t = 0.45)
point p x = 0.55 y = 0.8
constraint circle: p.x^2 + p.y^2 = 1
driver pull: p.x = 0.55 + t
EOF
run "$tmp/reach.mech" --steps 10
check "out of reach: exit 1" status_is 1
check "out of reach: the time it stopped, the driver, then no convergence" \
    err_matches "error: t = 0\.4515625: the mechanism cannot reach the driven position: driver 'pull' pushes it past a limit position.*no convergence"
check "out of reach: names the row" err_has "row circle"
check "out of reach: assembly moved the rough initial values: a note" \
    err_has "note: assembly at t = 0 moved"
check "out of reach: 5 states written" out_lines 6

run "$ex/parallelogram_redundant.mech"
check "redundant parallelogram: exit 1 at t = 0, singular" \
    sh -c '[ "$1" = 1 ] && grep -q "t = 0: .*singular" "$2"' - "$rc" "$tmp/err"
check "redundant parallelogram: failing at t = 0, nothing on stdout (no bare header)" out_empty
run "$ex/parallelogram_redundant.mech" --csv - --steps 4
check "redundant parallelogram --csv -: exit 1" status_is 1
check "redundant parallelogram --csv -: the error on stderr" \
    err_has "parallelogram_redundant.mech: error: t = 0: assembly from the file's initial values failed: singular Jacobian"
check "redundant parallelogram --csv -: no bare CSV header on stdout" out_empty
printf 'mechanism stuck\nbody rod x = 0 y = 0 phi = 0\nrevolute O: ground rod\ndistance far: ground(5, 0) rod(1, 0) length = 1\nmass rod m = 1 J = 0.1 com(0.5, 0)\ngravity (0, -9.81)\n' \
    > "$tmp/stuck.mech"
run "$tmp/stuck.mech" --forces --csv -
check "--forces failing at t = 0: exit 1" status_is 1
check "--forces failing at t = 0: the error on stderr" err_has "stuck.mech: error: t = 0: could not assemble"
check "--forces failing at t = 0: nothing on stdout" out_empty

for f in pendulum_distance pendulum_constraint; do
    run "$ex/$f.mech"
    check "$f: exit 2" status_is 2
    check "$f: 1 degree of freedom is not driven" err_matches "$f.mech:[0-9]*:1: error: 1 degree of freedom is not driven"
    check "$f: the last statement, with a caret" err_matches '^    \^$'
    check "$f: no output" out_empty
    run "$ex/$f.mech" --csv "$tmp/$f.csv" --svg "$tmp/$f.svg"
    check "$f --csv FILE --svg FILE: exit 2" status_is 2
    check "$f --csv FILE --svg FILE: no file written" \
        sh -c '[ ! -e "$1" ] && [ ! -e "$2" ]' _ "$tmp/$f.csv" "$tmp/$f.svg"
done
cat > "$tmp/over.mech" <<'EOF'
point p x = 0 y = 0
constraint a: p.x = 0
constraint b: p.y = 0
driver c: p.x = t
EOF
run "$tmp/over.mech"
check "a redundant driver that contradicts: exit 1" status_is 1
check "a redundant driver that contradicts: named once" \
    err_has "over.mech: note: 3 holonomic rows for 2 coordinates: redundant row: c (joint c);"
check "a redundant driver that contradicts: says where, when and why" \
    err_has "over.mech: error: t = 0: the redundant rows contradict the others: row c (joint c) is violated at the velocity level"
printf 'velocity v: der(p.y) = 0\n' >> "$tmp/over.mech"
run "$tmp/over.mech"
check "one row too many with a velocity-level row: exit 2" status_is 2
check "one row too many with a velocity-level row: says so" err_has "2 more rows than coordinates"
check "one row too many with a velocity-level row: points at the last statement" \
    err_has "over.mech:5:1: error:"

# ---- every example runs, or fails as its header says -----------------------
for f in "$ex"/*.mech; do
    name=${f##*/}; name=${name%.mech}
    case $name in
        pendulum_distance|pendulum_constraint|pendulum_dynamics) want=2 ;;
        andrews|a01_pendulum|double_pendulum|heavy_top|spherical_pendulum) want=2 ;;   # not driven: mechc sim
        parallelogram_redundant|bricard) want=1 ;;
        *) want=0 ;;
    esac
    run "$f" --csv /dev/null
    check "example $name: exit $want" status_is "$want"
    if [ "$name" = pendulum_dynamics ]; then check "pendulum_dynamics: exit 2 because undriven" err_has "is not driven"; fi
done

# ---- one instant, outputs, rough guesses (textbook problems) ---------------
# The value of CSV column NAME in the first data row of $tmp/out.
col() {
    awk -F, -v name="$1" 'NR == 1 { for (i = 1; i <= NF; i++) if ($i == name) c = i }
                          NR == 2 { print $c }' "$tmp/out"
}
run "$ex/textbook_slider_crank.mech" --steps 0 --csv -
check "textbook slider-crank --steps 0 --csv: exit 0" status_is 0
check "textbook slider-crank: one row" out_lines 2
check "textbook slider-crank: omega_BD = 62.0 rad/s ccw" near "$(col 'd(rod.phi)')" 61.99292234 1e-6
check "textbook slider-crank: v_P = 523.4 in./s" near "$(col 'd(piston.x)')" 523.4202136 1e-6
check "textbook slider-crank: alpha_BD = 9940 rad/s^2" near "$(col 'dd(rod.phi)')" 9940.162671 1e-6
check "textbook slider-crank: a_P = -9290 ft/s^2" near "$(col 'dd(piston.x)')" -111477.5962 1e-3
check "textbook slider-crank: v_B = 628.3 in./s (output B_pin)" \
    near "$(awk -v x="$(col 'd(B_pin.x)')" -v y="$(col 'd(B_pin.y)')" 'BEGIN { printf "%.12g\n", sqrt(x * x + y * y) }')" 628.3185307 1e-6
check "textbook slider-crank: beta = 13.95 deg (output)" near "$(col beta_deg)" 13.94824618 1e-6
run "$ex/textbook_four_bar.mech" --steps 0
check "textbook four-bar --steps 0: exit 0" status_is 0
check "textbook four-bar: a table, not CSV" out_has "coordinate             position           velocity       acceleration"
check "textbook four-bar: omega_BD = -88/3" out_has "coupler.phi        0.2449786631       -29.33333333       -645.3960784"
check "textbook four-bar: omega_DE = 192/17, alpha_DE = 809" out_has "11.29411765         809.271511   (135 deg)"
check "textbook four-bar: v_D = (-192, -192) (output D_pin)" out_has "D_pin.y                      17               -192       -15926.08627"
check "textbook four-bar: placed by construction from angle guesses 0" out_has "textbook_four_bar at t = 0 (9 of 9 coordinates placed by construction, then 1 Newton iteration)"
run "$ex/slider_crank_spatial.mech" --at 0.1
check "spatial slider-crank at one instant: exit 0" status_is 0
check "spatial slider-crank: the rod's omega_z and alpha_z are the planar rod.phi's rates" \
    out_has "rod.wz                              -1.727890865        7.291297119"
check "spatial slider-crank: the angular block's heading" \
    out_has "angular                                 velocity       acceleration"
run "$ex/textbook_geneva.mech" --at 0 --json
check "textbook geneva --at 0 --json: exit 0" status_is 0
check "textbook geneva: outputs listed" out_has '"outputs": ["slot_r", "pin.x", "pin.y"]'
check "textbook geneva: r = 37.1 mm, sliding 476.5 mm/s toward C" \
    out_has '"y": [[37.0981892'
check "textbook geneva: omega_S = -4.08 rad/s" out_has ', -4.082482904638'
check "textbook geneva: alpha_S = -233 rad/s^2" out_has ', -233.32118403'
printf 'param a = 1\nbody crank\nbody coupler\nbody rocker\nrevolute O2: ground(0, 0) crank(-0.5, 0)\nrevolute A: crank(0.5, 0) coupler(-1.5, 0)\nrevolute B: coupler(1.5, 0) rocker(1.25, 0)\nrevolute O4: ground(3, 0) rocker(-1.25, 0)\ndriver d: crank.phi = 30*deg + 60*rpm*t\n' > "$tmp/zero.mech"
run "$tmp/zero.mech" --steps 8 --csv "$tmp/zero.csv"
check "four-bar with every guess 0: runs (exit 0)" status_is 0
check "four-bar with every guess 0: the note says how it assembled" err_has "9 of the 9 coordinates were placed by construction"
check "four-bar with every guess 0: the note says how far it moved" err_has "moved the initial values by up to"
printf 'body crank\nbody coupler\nbody rocker\nrevolute O2: ground(0, 0) crank(-0.5, 0)\nrevolute A: crank(0.5, 0) coupler(-1.5, 0)\nrevolute B: coupler(1.5, 0) rocker(1.25, 0)\nrevolute O4: ground(9, 0) rocker(-1.25, 0)\ndriver d: crank.phi = 0\n' > "$tmp/open.mech"
run "$tmp/open.mech" --steps 0
check "lengths that cannot close: exit 1" status_is 1
check "lengths that cannot close: 'could not assemble', no toggle" sh -c "grep -q 'could not assemble from these initial values' '$tmp/err' && ! grep -q toggle '$tmp/err'"
printf 'body c\nrevolute O: ground c\ndriver d: c.phi = t\noutput tip: c(1, 0)\noutput deg_angle = c.phi/deg\n' > "$tmp/out.mech"
run "$tmp/out.mech" --steps 2 --t1 0.5
check "outputs in the CSV header, beside the coordinates" out_has "t,c.x,c.y,c.phi,tip.x,tip.y,deg_angle,d(c.x),d(c.y),d(c.phi),d(tip.x),d(tip.y),d(deg_angle),dd(c.x)"
run "$tmp/out.mech" --steps 2 --t1 0.5 --plot "$tmp/o.svg" --plot-vars 'tip.y,d(deg_angle)'
check "--plot-vars takes output names" status_is 0
run "$tmp/out.mech" --steps 2 --t1 0.5 --svg "$tmp/o2.svg"
check "--svg: a point output's path is drawn" sh -c "grep -q 'tip' '$tmp/o2.svg'"

run "$ex/slider_crank_toggle.mech" --at 0.25
check "a driven toggle reached from rough guesses: exit 1" status_is 1
check "a driven toggle reached from rough guesses: said to be a toggle" err_has "assembly from the file's initial values failed: singular Jacobian: a toggle"
run "$ex/four_bar.mech" --at 0.1 --t0 0.5
check "--at with --t0: refused (exit 2)" status_is 2
check "--at with --t0: says why" err_has "--at T is --t0 T --steps 0"
run "$ex/four_bar.mech" --steps 0 --svg "$tmp/one.svg"
check "--steps 0 with --svg: refused (exit 2)" status_is 2
printf 'param a = 30*deg\nparam deg = 2\nbody c\nrevolute O: ground c\ndriver d: c.phi = a\n' > "$tmp/unit.mech"
run "$tmp/unit.mech" --steps 0
check "deg declared after its use as a unit: exit 2" status_is 2
check "deg declared after its use as a unit: says so" err_has "unit.mech:2:7: error: 'deg' was used as the unit deg on line 1"
printf 'body c\nrevolute O: ground c\ndriver d: c.phi = t\noutput w = der(c.phi)\n' > "$tmp/derout.mech"
run "$tmp/derout.mech" --steps 0
check "der() in an output: exit 2" status_is 2
check "der() in an output: says so" err_has "output 'w' contains der()"
printf 'body c\nrevolute O: ground c\ndriver d: c.phi = t\noutput s = sqrt(c.phi - 0.5)\n' > "$tmp/nan.mech"
run "$tmp/nan.mech" --steps 2 --csv /dev/null
check "an output that is NaN: warned once" err_has "warning: output 's' is not finite at t = 0"

# every example that assembles as written also assembles with every angle
# guess 0, and with every initial value left out
for f in "$ex"/*.mech; do
    name=${f##*/}; name=${name%.mech}
    run "$f" --steps 0 --csv /dev/null
    [ "$rc" = 0 ] || continue
    sed -E '/^body/ s/phi *= *[^ ]+/phi = 0/' "$f" > "$tmp/angles0.mech"
    sed -E 's/^(body +[A-Za-z_0-9]+).*/\1/; s/^(point +[A-Za-z_0-9]+).*/\1/' "$f" > "$tmp/all0.mech"
    run "$tmp/angles0.mech" --steps 0 --csv /dev/null
    check "$name with angle guesses 0 assembles" status_is 0
    # (a02_chain: with no values at all the construction does not place
    # chains of 30 or more loops, chain.sh's as well: Newton then starts
    # from a singular guess; its angle guesses 0 are enough, above)
    [ "$name" = a02_chain ] && continue
    run "$tmp/all0.mech" --steps 0 --csv /dev/null
    check "$name with every guess 0 assembles" status_is 0
done

# ---- velocity-level rows: integrated positions ----------------------------
run "$ex/knife_cart.mech" --steps 20
check "knife_cart: exit 0" status_is 0
check "knife_cart: (x, y)(0.5) = (0, 1)" sh -c '
    x=$(awk -F, "NR > 1 && \$1 == 0.5 { print \$2 }" "$1")
    y=$(awk -F, "NR > 1 && \$1 == 0.5 { print \$3 }" "$1")
    awk -v x="$x" -v y="$y" "BEGIN { exit !(x*x < 1e-16 && (y-1)*(y-1) < 1e-16) }"' - "$tmp/out"
check "knife_cart: ends at (-1, 0)" \
    near "$(value_at 1 cart.x "$tmp/out")" -1 1e-8
run "$ex/rolling_wheel.mech" --steps 4 --ode rkf45 --ode-tol 1e-9
check "rolling_wheel (rkf45): x(1) = 1 + pi" \
    near "$(value_at 1 wheel.x "$tmp/out")" 4.14159265358979 1e-8

# ---- engines agree ---------------------------------------------------------
"$mechc" run "$ex/four_bar.mech" --steps 20 > "$tmp/jit.csv" 2> "$tmp/err"
for engine in generic aot; do
    "$mechc" run "$ex/four_bar.mech" --steps 20 --engine $engine > "$tmp/$engine.csv" 2> "$tmp/err"
    rc=$?
    if [ $rc = 2 ] && grep -q "error: .*not available\|error: .*compiler" "$tmp/err"; then
        skip "--engine $engine not available: $(head -1 "$tmp/err")"
        continue
    fi
    check "four_bar --engine $engine: exit 0" status_is 0
    check "four_bar: $engine agrees with jit (1e-9)" awk -F, '
        NR == FNR { for (i = 1; i <= NF; i++) a[FNR, i] = $i; next }
        FNR == 1 { next }
        { for (i = 1; i <= NF; i++) { d = $i - a[FNR, i]; if (d < 0) d = -d; if (d > 1e-9) exit 1 } }
        END { if (FNR != 22) exit 1 }
    ' "$tmp/jit.csv" "$tmp/$engine.csv"
done

# ---- firmware: generated C + MECHRT_DEFINE_KERNELS + the runtime ----------
# (at -O0: tests/firmware_rules.sh builds the runtime and the kernels at -O2
# with stricter flags)
if have cc; then
    cat > "$tmp/fw.c" <<'EOF'
/* what firmware writes: the generated kernels and the runtime, no heap */
#include <stdio.h>
#include "fb.h"
#include "mechrt.h"

MECHRT_DEFINE_KERNELS(fb, FB);

int main(void)
{
    static mechrt_real ws[MECHRT_WORKSPACE_LEN(FB_NQ, FB_NR)];
    mechrt_real q[FB_NQ], qd[FB_NQ] = {0}, qdd[FB_NQ] = {0}, t = 0;
    MechrtOptions o = mechrt_default_options();
    MechrtReport r;
    int i;
    for (i = 0; i < FB_NQ; i++)
        q[i] = fb_q0[i];
    for (i = 0; i <= 100; i++) {
        mechrt_real tn = (mechrt_real)i / 100;
        MechrtStatus st = mechrt_step(&fb_kernels, &o, q, qd, qdd, t, i ? tn - t : 0, ws,
                                      sizeof ws / sizeof *ws, &r);
        if (st != MECHRT_OK) {
            printf("t = %g: %s\n", (double)tn, mechrt_strerror(st));
            return 1;
        }
        t = tn;
        if (i == 25)
            printf("%.9f %.9f\n", (double)q[6], (double)qd[6]);
    }
    return 0;
}
EOF
    for real in double float; do
        def=""
        [ $real = float ] && def="-DMECHRT_REAL_FLOAT"
        if "$mechc" gen "$ex/slider_crank.mech" --prefix fb --real $real \
                -o "$tmp/fb.c" --header "$tmp/fb.h" 2> "$tmp/err" \
           && cc -std=c99 -pedantic -Wall -Wextra -Werror -O0 $def -I"$tmp" -I"$root/runtime" \
                "$tmp/fw.c" "$tmp/fb.c" "$root"/runtime/*.c -lm -o "$tmp/fw_$real" 2> "$tmp/err"; then
            ok
            "$tmp/fw_$real" > "$tmp/fw.out" 2> "$tmp/err"
            set -- $(cat "$tmp/fw.out") "" ""
            tol=1e-12
            [ $real = float ] && tol=1e-4
            check "firmware ($real): slider.x(0.25) = sqrt(0.08)" near "$1" 0.282842712 $tol
            check "firmware ($real): d(slider.x)(0.25) = -0.2 pi" near "$2" -0.628318531 $tol
        else
            fail=$((fail + 1))
            echo "FAIL: firmware ($real): gen + cc -std=c99 -pedantic -Werror" >&2
            sed -n '1,10s/^/    /p' "$tmp/err" >&2
        fi
    done
else
    skip "cc missing: firmware build"
fi

# ---- inverse dynamics: run --forces (doc/dynamics.md) ----------------------
# slider_crank_torque.mech: effort(D) = -lambda(D) at theta = 30 k degrees
# (t = k/12) is the crank torque of its header's reference table (REFS.md
# section 3), with gravity and, with g set to 0, without; to 1e-9 relative
# (1e-12 absolute at the zeros).
torque_table() {   # FILE.csv COLUMN "v0 v30 ... v330": the worst mismatch, or FAIL
    awk -F, -v col="$2" -v want="$3" '
    NR == 1 { for (i = 1; i <= NF; i++) if ($i == col) c = i; n = split(want, w, " "); next }
    NR >= 2 && NR <= 13 { k = NR - 1; d = $c - w[k]; if (d < 0) d = -d
                           tol = 1e-9 * (w[k] < 0 ? -w[k] : w[k]) + 1e-12
                           if (!(d <= tol)) bad = bad " t=" $1 ":" $c "!=" w[k]; rows++ }
    END { if (!c || rows != 12 || bad != "") { print "FAIL" bad; exit 1 } }' "$1"
}
tau_g="1.4715 1.99288516501141 1.13103964241246 -0.348943209981944 -1.26630317393169 -1.56866853899195 -1.4715 -0.980044224345654 -0.205196826068313 0.348943209981944 0.340460357587543 0.555827598326197"
tau_0="0 0.718528783342604 0.395289642412457 -0.348943209981944 -0.530553173931687 -0.294312157323148 0 0.294312157323148 0.530553173931687 0.348943209981944 -0.395289642412457 -0.718528783342604"
run "$ex/slider_crank_torque.mech" --forces --steps 12 --csv "$tmp/sct.csv"
check "run --forces: exit 0" status_is 0
check "run --forces: the crank torque table with gravity to 1e-9" \
    torque_table "$tmp/sct.csv" "effort(D)" "$tau_g"
sed 's/^param g .*/param g     = 0/' "$ex/slider_crank_torque.mech" > "$tmp/sct0.mech"
run "$tmp/sct0.mech" --forces --steps 12 --csv "$tmp/sct0.csv"
check "run --forces: the crank torque table without gravity to 1e-9" \
    torque_table "$tmp/sct0.csv" "effort(D)" "$tau_0"
check "run --forces: the reference values are the example's header's" \
    sh -c "grep -q '^#    30            0.718528783342604       1.99288516501141' '$ex/slider_crank_torque.mech'"
check "run --forces: lambda(ROW) and effort(DRIVER) columns after the dd() ones" \
    sh -c "head -1 '$tmp/sct.csv' | grep -q ',dd(slider.phi),lambda(O.x),lambda(O.y),lambda(A.x),lambda(A.y),lambda(B.x),lambda(B.y),lambda(P.n),lambda(P.phi),lambda(D),effort(D)\$'"
check "run --forces: effort(D) = -lambda(D) in every row" \
    awk -F, 'NR == 1 { for (i = 1; i <= NF; i++) { if ($i == "lambda(D)") l = i; if ($i == "effort(D)") e = i }; next }
             { if ($e != -$l) exit 1 }' "$tmp/sct.csv"
# the pin O's force on the crank plus the guide's on the slider carry the
# weights (1 + 2 + 1.5) 9.81 at the dead centres, where no body's
# centre of mass accelerates vertically
check "run --forces: lambda(O.y) - lambda(P.n) = 44.145 at theta = 0 and 180 deg" \
    awk -F, 'NR == 1 { for (i = 1; i <= NF; i++) { if ($i == "lambda(O.y)") a = i; if ($i == "lambda(P.n)") b = i }; next }
             NR == 2 || NR == 8 { d = $a - $b - 44.145; if (d < 0) d = -d; if (d > 1e-9) exit 1; n++ }
             END { exit n != 2 }' "$tmp/sct.csv"
run "$ex/slider_crank_torque.mech" --forces --steps 4 --json
check "run --forces --json: rows, lambda, drivers and efforts" \
    sh -c "grep -q -F '\"rows\": [\"O.x\", \"O.y\", \"A.x\"' '$tmp/out' && grep -q -F '\"lambda\": [[-19.08123517543' '$tmp/out' && grep -q -F '\"drivers\": [\"D\"]' '$tmp/out' && grep -q -F '\"efforts\": [[1.47150000000' '$tmp/out'"
if have python3; then
    check "run --forces --json: valid JSON, one lambda per row and state" py -c '
import json, sys
d = json.load(open(sys.argv[1]))
assert d["ok"] and len(d["rows"]) == 9 and len(d["lambda"]) == 5 == len(d["efforts"])
assert all(len(l) == 9 for l in d["lambda"]) and d["drivers"] == ["D"]
assert all(abs(e[0] + l[8]) == 0 for e, l in zip(d["efforts"], d["lambda"]))' "$tmp/out"
fi
run "$ex/slider_crank_torque.mech" --steps 4 --json
check "run without --forces: no lambda keys" sh -c "! grep -q '\"lambda\"' '$tmp/out'"
run "$ex/slider_crank_torque.mech" --forces --at 0.25
check "run --forces --at: the table with lambda and effort" \
    sh -c "grep -q '^D  *-0.34894321\$' '$tmp/out' && grep -q '^P.n  *-24.27825989\$' '$tmp/out'"
run "$ex/slider_crank.mech" --forces
check "run --forces without masses: exit 2" status_is 2
check "run --forces without masses: says so at the file's last statement" \
    err_matches 'slider_crank.mech:[0-9]*:1: error: the mechanism has no masses: `run --forces`'
run "$ex/slider_crank_torque.mech" --forces --plot "$tmp/eff.svg" --plot-vars 'effort(D), lambda(O.x)'
check "run --forces --plot-vars effort(D), lambda(O.x): exit 0" status_is 0
check "run --forces --plot: the curves named" \
    sh -c "grep -q 'effort(D)' '$tmp/eff.svg' && grep -q 'lambda(O.x)' '$tmp/eff.svg'"
run "$ex/slider_crank_torque.mech" --plot "$tmp/eff.svg" --plot-vars 'effort(D)'
check "run --plot-vars effort(D) without --forces: exit 2" status_is 2
run "$ex/slider_crank_torque.mech" --forces --plot "$tmp/eff.svg" --plot-vars 'effort(O.x)'
check "run --forces --plot-vars effort(NOT A DRIVER): exit 2, named" \
    sh -c "[ $rc = 2 ] && grep -q \"unknown driver 'O.x'\" '$tmp/err'"
for e in generic aot; do
    [ "$e" = aot ] && ! have cc && continue
    run "$ex/slider_crank_torque.mech" --forces --steps 12 --engine $e --csv "$tmp/sct_$e.csv"
    check "run --forces --engine $e: the torque table" torque_table "$tmp/sct_$e.csv" "effort(D)" "$tau_g"
done
run "$ex/slider_crank_torque.mech" --forces --steps 12 --linear sparse --csv "$tmp/sct_sp.csv"
check "run --forces --linear sparse: the torque table" torque_table "$tmp/sct_sp.csv" "effort(D)" "$tau_g"

run "$ex/slider_crank_torque.mech" --forces --svg "$tmp/sct.svg"
check "run --forces --svg: an arrow at each of O, A, B and P, and the scale's legend" \
    sh -c "[ \$(grep -c '<polyline class=\"force\" marker-end=\"url(#force)\" points=\"[0-9.,]* [0-9.,]*\"><title>reaction at' '$tmp/sct.svg') = 4 ] && grep -q 'this arrow is 27.37 (the largest)' '$tmp/sct.svg'"
# the first frame's arrow at O points along the pin's force on the crank,
# (lambda(O.x), lambda(O.y)) = (-19.08, 19.62) at t = 0 (pixels: y down)
check "run --forces --svg: the arrow at O along (lambda(O.x), lambda(O.y))" \
    awk '/<title>reaction at O</ { split($0, a, "points=\""); split(a[2], b, "\""); split(b[1], p, "[ ,]")
         dx = p[3] - p[1]; dy = p[2] - p[4]; r = dx / dy - (-19.081235175439428 / 19.62)
         found = 1; exit !(dx < 0 && dy > 0 && r < 0.01 && r > -0.01) } END { if (!found) exit 1 }' "$tmp/sct.svg"
run "$ex/slider_crank_torque.mech" --svg "$tmp/sct_nf.svg"
check "run --svg without --forces: no arrows" sh -c "! grep -q 'force' '$tmp/sct_nf.svg'"
if have xmllint; then
    check "run --forces --svg: well-formed XML" xmllint --noout "$tmp/sct.svg"
fi

# velocity-level rows (positions integrated): knife_cart with a mass runs a
# circle of radius v/w = 1 at speed pi; the blade carries the centripetal
# force m v^2 / R = 2 pi^2 (lambda(blade) = -2 pi^2: the force -lambda n_A
# on the cart points to the centre), the drivers nothing
{ cat "$ex/knife_cart.mech"; echo 'mass cart m = 2 J = 0.1'; } > "$tmp/kcm.mech"
run "$tmp/kcm.mech" --forces --steps 8 --csv "$tmp/kcm.csv"
check "run --forces, velocity-level rows: lambda(blade) = -2 pi^2, efforts 0" \
    awk -F, 'NR == 1 { for (i = 1; i <= NF; i++) c[$i] = i; next }
             { d = $(c["lambda(blade)"]) + 2 * atan2(0, -1)^2; if (d < 0) d = -d
               e = $(c["effort(fwd)"]); if (e < 0) e = -e; f = $(c["effort(turn)"]); if (f < 0) f = -f
               if (d > 1e-9 || e > 1e-9 || f > 1e-9) exit 1; n++ }
             END { exit n != 9 }' "$tmp/kcm.csv"

suite_end
