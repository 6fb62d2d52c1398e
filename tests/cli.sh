#!/bin/sh
# tests/cli.sh MECHC - the command line's contract (spec section 3): exit
# statuses, help texts, the compiler-style error format on bad input, the
# JSON keys of `eval`, and that `gen` writes C that gcc compiles.
#
#   sh tests/cli.sh build/mechc
#
# Each check counts as passed or failed; the last line is
# "cli: N passed, M failed" and the exit status is non-zero on any failure.
# Checks that need gcc or python3 are skipped (and say so) when those are
# missing.
set -u
# shellcheck source=tests/lib.sh
. "$(dirname "$0")/lib.sh"
suite_begin cli "${1:-build/mechc}"

# ---- help and version ----

run --help
check "--help exits 0" status_is 0
check "--help prints the usage on stdout" out_has "usage: mechc COMMAND"
run --version
check "--version exits 0" status_is 0
check "--version prints 'mechc X.Y.Z'" sh -c "grep -E -q '^mechc [0-9]+\.[0-9]+\.[0-9]+$' '$tmp/out'"

for c in gen run eval check info bench; do
    run "$c" --help
    if [ "$rc" != 0 ] && err_has "not implemented yet"; then
        skip "$c --help: the command is not implemented yet"
        continue
    fi
    check "$c --help exits 0" status_is 0
    check "$c --help prints its usage" out_has "usage: mechc $c"
    # every option the help names (synopsis, list, limits) is one the command reads
    opts=$(grep -o -e '--[a-z][a-z0-9-]*' -e '^  -[a-z] ' "$tmp/out" | tr -d ' ' | sort -u)
    check "$c --help names options" [ -n "$opts" ]
    for o in $opts; do
        run "$c" "$o"
        check "$c reads $o, which its --help names" err_lacks 'unknown option'
    done
done

# ---- usage errors ----

run
check "no arguments exits 2" status_is 2
run frobnicate "$ex/pendulum_distance.mech"
check "unknown command exits 2" status_is 2
check "unknown command is named" err_has "unknown command 'frobnicate'"
run --bogus
check "unknown top-level option exits 2" status_is 2
run eval "$ex/pendulum_distance.mech" --bogus
check "unknown eval option exits 2" status_is 2
check "unknown eval option is named" err_has "--bogus"
check "unknown eval option: nothing on stdout" out_empty
run gen "$ex/pendulum_distance.mech" --real long
check "gen --real long exits 2" status_is 2
run eval
check "eval without a file exits 2" status_is 2
run eval "$ex/pendulum_distance.mech" --t abc
check "eval --t abc exits 2" status_is 2
check "eval --t abc says why" err_has "error:"

run eval "$ex/pendulum_distance.mech" --q 1,2,3
check "eval --q with 3 values for 2 coordinates exits 2" status_is 2
check "eval --q count message" err_has "--q needs 2"
check "eval --q count: nothing on stdout" out_empty
run eval "$ex/pendulum_distance.mech" --q 1
check "eval --q with 1 value exits 2" status_is 2
run eval "$ex/pendulum_distance.mech" --qd 1,2,3,4
check "eval --qd with 4 values exits 2" status_is 2
check "eval --qd count message" err_has "--qd"
run eval "$ex/pendulum_distance.mech" --q 1,x
check "eval --q with a non-number exits 2" status_is 2

run eval "$tmp/does_not_exist.mech"
check "missing file exits 2" status_is 2
check "missing file: error:" err_has "error:"
check "missing file is named" err_has "does_not_exist.mech"
check "missing file: nothing on stdout" out_empty

# ---- eval ----

run eval "$ex/pendulum_distance.mech"
check "eval pendulum exits 0" status_is 0
check "eval pendulum prints the row" out_has "rod"

run eval "$ex/pendulum_distance.mech" --json
check "eval --json exits 0" status_is 0
for key in '"coords"' '"rows"' '"name"' '"kind"' '"level"' '"phi"' '"jac"' '"nu"' '"gamma"' \
           '"m.x"' '"m.y"' '"distance"' '"position"'; do
    check "eval --json has $key" out_has "$key"
done
cp "$tmp/out" "$tmp/pendulum.json"

if have python3; then
    # strict parse and values: Phi = 1.732^2 + 1 - 4, Jacobian (3.464, 2)
    check "eval --json parses and has the spec's shape and values" py - "$tmp/pendulum.json" <<'EOF'
import json, sys
d = json.load(open(sys.argv[1]))
assert d["coords"] == ["m.x", "m.y"], d["coords"]
assert len(d["rows"]) == 1
r = d["rows"][0]
assert (r["name"], r["kind"], r["level"]) == ("rod", "distance", "position"), r
assert len(d["phi"]) == 1 and abs(d["phi"][0] + 0.000176) < 1e-12, d["phi"]
assert len(d["jac"]) == 1 and len(d["jac"][0]) == 2, d["jac"]
assert abs(d["jac"][0][0] - 3.464) < 1e-12 and abs(d["jac"][0][1] - 2.0) < 1e-12, d["jac"]
assert d["nu"] == [0] and len(d["gamma"]) == 1 and d["gamma"][0] == 0, (d["nu"], d["gamma"])
EOF
    # gamma = -18 on the circle of radius 2 at 3 m/s
    run eval "$ex/pendulum_distance.mech" --q 1.7320508075688772,1 --qd -1.5,2.598076211353316 --json
    check "eval --q --qd exits 0" status_is 0
    cp "$tmp/out" "$tmp/pendulum18.json"
    check "eval --q --qd: gamma = -18, phi = 0" py - "$tmp/pendulum18.json" <<'EOF'
import json, sys
d = json.load(open(sys.argv[1]))
assert abs(d["gamma"][0] + 18) < 1e-9, d["gamma"]
assert abs(d["phi"][0]) < 1e-12, d["phi"]
EOF
    # velocity-level rows: level "velocity", phi has NH = 0 entries, NR x NQ jac
    run eval "$ex/knife_cart.mech" --json --t 0.25
    check "eval knife_cart --json exits 0" status_is 0
    cp "$tmp/out" "$tmp/knife.json"
    check "eval knife_cart --json: velocity rows" py - "$tmp/knife.json" <<'EOF'
import json, sys, math
d = json.load(open(sys.argv[1]))
assert d["coords"] == ["cart.x", "cart.y", "cart.phi"], d["coords"]
assert [r["name"] for r in d["rows"]] == ["blade", "fwd", "turn"], d["rows"]
assert all(r["level"] == "velocity" for r in d["rows"]), d["rows"]
assert d["phi"] == [] and len(d["jac"]) == 3 and all(len(r) == 3 for r in d["jac"])
assert abs(d["nu"][1] - math.pi) < 1e-12 and abs(d["nu"][2] - math.pi) < 1e-12, d["nu"]
EOF
else
    skip "python3 not found: the strict JSON checks"
fi

# ---- bad input: FILE:LINE:COL: error:, the source line, a caret, exit 2 ----

# bad_input NAME LINE COL TEXT [MESSAGE]: TEXT (printf %b escapes) must be
# rejected at LINE:COL, with MESSAGE in the error if given. The lines are
# read by the shell, not by head, sed and grep: 30 cases, and a process
# costs 5 to 8 ms of CPU here.
cr=$(printf '\r') blanks=$(printf ' \t')
bad_input() {
    name=$1 line=$2 col=$3 text=$4 msg=${5:-}
    f=$tmp/$name.mech
    printf '%b' "$text" > "$f"
    run eval "$f"
    check "$name: exit 2" status_is 2
    check "$name: nothing on stdout" out_empty
    err1= err2= caret=
    { IFS= read -r err1; IFS= read -r err2; IFS= read -r caret; } < "$tmp/err"
    check "$name: '$f:$line:$col: error: ' first" has_text "$err1" "$f:$line:$col: error: "
    if [ -n "$msg" ]; then
        check "$name: message has '$msg'" has_text "$err1" "$msg"
    fi
    # line LINE of the file, its carriage returns removed
    i=0 src=
    while IFS= read -r src || [ -n "$src" ]; do
        i=$((i + 1))
        [ "$i" = "$line" ] && break
        src=
    done < "$f"
    while :; do
        case $src in *"$cr"*) src=${src%%"$cr"*}${src#*"$cr"} ;; *) break ;; esac
    done
    check "$name: the source line second" [ "$err2" = "    $src" ]
    check "$name: a caret line third" is_caret "$caret"
    check "$name: the caret under column $col" [ "${#caret}" = "$((col + 4))" ]
}
# has_text STRING TEXT: STRING holds TEXT; is_caret LINE: blanks, then ^.
has_text() { case $1 in *"$2"*) return 0 ;; esac; return 1; }
is_caret() {
    case $1 in *^) ;; *) return 1 ;; esac
    case ${1%^} in *[!"$blanks"]*) return 1 ;; esac
}

bad_input unknown_name      2 22 'point m x = 1\ndistance rod: ground mm length = 2\n' "unknown name 'mm'"
bad_input duplicate_name    2 7  'point m x = 1\npoint m x = 2\ndistance rod: ground m length = 2\n' "duplicate name 'm'"
bad_input reserved_name     1 7  'point pi x = 1\n' "reserved"
bad_input reserved_fn       1 6  'body sin x = 1\n' "reserved"
bad_input particle_offset   2 22 'point m x = 1\ndistance rod: ground m(1, 0) length = 2\n' "point"
bad_input prismatic_point   2 21 'point m x = 1\nprismatic P: ground m axis(1, 0)\n' "prismatic"
bad_input zero_axis         2 23 'body b x = 1\nprismatic P: ground b axis(0, 0)\n' "zero"
bad_input der_constraint    2 15 'point m x = 1\nconstraint c: der(m.x) = 0\n' "der()"
bad_input param_t           1 13 'param p = 2*t\npoint m x = 1\ndistance rod: ground m length = 2\n' "'t'"
bad_input param_div0        1 12 'param p = 1/0\npoint m x = 1\nconstraint c: m.x = p\n' "finite"
bad_input component_z       2 17 'point m x = 1\nconstraint c: m.z = 0\n' "'z'"
bad_input unbalanced_paren  2 24 'point m x = 1\nconstraint c: (m.x + 1 = 0\n' "')'"
bad_input non_ascii         2 19 'point m x = 1 # ok \0303\0251\nconstraint c: m.x \0303\0251= 0\n' "non-ASCII"
bad_input empty_file        1 1  '' "no statements"
bad_input not_affine        2 1  'point m x = 1\nvelocity v: der(m.x)^2 = 1\n' "not affine"
bad_input velocity_no_der   2 1  'point m x = 1\nvelocity v: m.x = 1\n' "der()"
bad_input unknown_statement 2 1  'point m x = 1\nhinge h: ground m\n' "unknown statement"
bad_input malformed_number  1 13 'point m x = 1.2.3\n' "malformed number"
bad_input unknown_function  2 15 'point m x = 1\nconstraint c: foo(m.x) = 0\n' "foo"
bad_input missing_colon     2 14 'point m x = 1\ndistance rod ground m length = 2\n' "':'"
bad_input no_coordinates    1 1  'param a = 1\n' "no coordinates"
bad_input tab_indent        2 22 'point m x = 1\n\tconstraint c: m.x = q\n' "unknown name 'q'"
# masses and forces (doc/dynamics.md)
pin='body a x = 1\npoint p\nrevolute O: ground a\n'
bad_input negative_mass     4 8  "${pin}mass a m = -2\n" "the mass m of mass 'a' is negative"
bad_input negative_inertia  4 14 "${pin}mass a m = 1 J = -1\n" "moment of inertia J of mass 'a' is negative"
bad_input negative_length   5 21 "${pin}mass a m = 1\nspring S: a p k = 1 length = -1\n" "free length of spring 'S' is negative"
bad_input mass_unknown      4 6  "${pin}mass b m = 1\n" "unknown name 'b'"
bad_input point_torque      5 11 "${pin}mass p m = 1\ntorque T: p = 1\n" "'p' is a point (it has no angle)"
bad_input point_inertia     4 14 "${pin}mass p m = 1 J = 1\n" "it has no angle, so no moment of inertia J"
bad_input force_no_mass     4 1  "${pin}gravity (0, -9.81)\n" "gravity without masses"

# the same error from gen: nothing on stdout, no output file
printf 'point m x = 1\nconstraint c: m.x = nope\n' > "$tmp/genbad.mech"
run gen "$tmp/genbad.mech" -o "$tmp/genbad.c"
check "gen on bad input exits 2" status_is 2
check "gen on bad input: FILE:LINE:COL" err_has "$tmp/genbad.mech:2:21: error: "
check "gen on bad input writes no file" [ ! -e "$tmp/genbad.c" ]
run gen "$tmp/genbad.mech"
check "gen on bad input: nothing on stdout" out_empty

# ---- dynamics (doc/dynamics.md): eval's M and Q, gen's kernels only with masses ----
run eval examples/pendulum_dynamics.mech --qd 0,0,2 --json
check "eval dynamics: exit 0" status_is 0
check "eval dynamics: M's last row" grep -q '\[0.8660254037844386, 0.5000000000000001, 0.6666666666666666\]' "$tmp/out"
check "eval dynamics: Q" grep -q '"Q": \[2.0000000000000004, -23.084101615137754, -4.905000000000001\]' "$tmp/out"
run eval examples/pendulum_dynamics.mech --engine generic
check "eval dynamics text: M shown" grep -q '^Mass matrix M' "$tmp/out"
run eval examples/pendulum_distance.mech --json
check "eval without masses: no M" sh -c "! grep -q '\"M\"' '$tmp/out'"
run gen examples/pendulum_dynamics.mech --prefix fb
check "gen dynamics: FB_HAS_DYNAMICS" grep -q '^#define FB_HAS_DYNAMICS 1' "$tmp/out"
check "gen dynamics: fb_eom" grep -q '^void fb_eom(' "$tmp/out"
run gen examples/pendulum_distance.mech --prefix fb
check "gen without masses: no dynamics" sh -c "! grep -q 'DYNAMICS\|fb_mass' '$tmp/out'"
run check examples/slider_crank_dynamics.mech --samples 3
check "check dynamics: exit 0" status_is 0
check "check dynamics: M compared" grep -q 'M jit/generic' "$tmp/out"
check "check dynamics: velocity terms" grep -q '^ok   Q velocity fd' "$tmp/out"

# ---- gen ----

run gen "$ex/four_bar.mech"
check "gen to stdout exits 0" status_is 0
check "gen: the banner is the first line" \
    sh -c "head -n 1 '$tmp/out' | grep -q '^/\*.*four_bar\.mech.*DO NOT EDIT'"

run gen "$ex/four_bar.mech" -o "$tmp/fb.c" --prefix fb
check "gen -o exits 0" status_is 0
check "gen -o: nothing on stdout" out_empty
check "gen -o writes the file" [ -s "$tmp/fb.c" ]
check "gen --prefix fb names the functions" grep -q 'void fb_all(' "$tmp/fb.c"
check "gen --prefix fb names the macros" grep -q '#define FB_NQ' "$tmp/fb.c"

run gen "$ex/slider_crank.mech" -o "$tmp/sc.c" --header "$tmp/sc.h" --prefix sc
check "gen --header exits 0" status_is 0
check "gen --header writes the header" [ -s "$tmp/sc.h" ]
check "gen --header: the source includes it" grep -q '#include "sc.h"' "$tmp/sc.c"

run gen "$ex/all_statements.mech" -o "$tmp/af.c" --real float
check "gen --real float exits 0" status_is 0
check "gen --real float uses float" grep -q 'typedef float all_statements_real;' "$tmp/af.c"

check "gen: sin and cos of two angles through one call of the file's own sincos2" grep -q 'sc_sincos2(q\[2\], q\[5\], &' "$tmp/sc.c"
run gen "$ex/slider_crank.mech" -o "$tmp/sl.c" --prefix sl --trig libm
check "gen --trig libm exits 0" status_is 0
check "gen --trig libm: no sincos of its own" sh -c '! grep -q sincos "$1"' _ "$tmp/sl.c"
check "gen --trig libm: sin of <math.h>" grep -q '= sin(q\[2\]);' "$tmp/sl.c"
run gen "$ex/slider_crank.mech" --trig fast
check "gen --trig fast exits 2" status_is 2
check "gen --trig fast names the choices" err_has "own or libm"

# The written files compile: test_emit (one file, a header, float) and
# tests/firmware_rules.sh (every example, strict flags) build what gen
# writes by default; --trig libm is compiled here.
if [ -n "${MECHC_SKIP_GCC_ONLY:-}" ]; then
    skip "MECHC_SKIP_GCC_ONLY: compiling the generated C"
elif have gcc; then
    check "gcc compiles gen --trig libm output" \
        gcc -std=c99 -Wall -Wextra -Wpedantic -Werror -c "$tmp/sl.c" -o "$tmp/sl.o"
else
    skip "gcc not found: compiling the generated C"
fi

run gen --help
check "gen --help documents --jac" out_has "--jac HOW"
run gen "$ex/four_bar.mech" --jac direct --prefix fbd -o "$tmp/fbd.c"
check "gen --jac direct exits 0" status_is 0
check "gen --jac direct: the dense Jacobian stores its own entries" \
    sh -c 'grep -q "Zero-filled, then every nonzero stored in place" "$1" && ! grep -q "fbd_jac_nz(q, t, packed);" "$1"' _ "$tmp/fbd.c"
check "gen default (--jac auto), small: the dense Jacobian stores in place" \
    sh -c 'grep -q "Zero-filled, then every nonzero stored in place" "$1" && ! grep -q "fb_jac_nz(q, t, packed);" "$1"' _ "$tmp/fb.c"
run gen "$ex/four_bar.mech" --jac spread --prefix fbs -o "$tmp/fbs.c"
check "gen --jac spread: the dense Jacobian is spread from jac_nz" grep -q "fbs_jac_nz(q, t, packed);" "$tmp/fbs.c"
# 4005 nonzeros (chain of 200 loops): straight-line, over EMIT_DIRECT_JAC_NNZ, spread;
# rolled (the default for its 1206 rows), direct
sh "$ex/chain.sh" 200 "$tmp/chain200.mech"
run gen "$tmp/chain200.mech" --roll never --prefix cs -o "$tmp/cs.c"
check "gen --jac auto, over 4000 nonzeros straight-line: spread" grep -q "cs_jac_nz(q, t, packed);" "$tmp/cs.c"
run gen "$tmp/chain200.mech" --prefix cr -o "$tmp/cr.c"
check "gen --jac auto, over 4000 nonzeros rolled: direct" \
    sh -c 'grep -q "Zero-filled, then every nonzero stored in place" "$1" && ! grep -q "cr_jac_nz(q, t, packed);" "$1"' _ "$tmp/cr.c"
# fbd.c is fb.c with another prefix (direct is four-bar's default): compiled
# by test_emit
check "gen --jac direct: the default's text" \
    sh -c 'sed s/fbd_/fb_/g "$1" | sed s/FBD_/FB_/g | cmp -s - "$2"' _ "$tmp/fbd.c" "$tmp/fb.c"
printf 'point p x = 0 y = 0\nconstraint a: p.x = 1e-50*p.y\ndriver d: p.y = t\n' > "$tmp/tiny.mech"
run gen "$tmp/tiny.mech" --real float
check "gen --real float with a constant float rounds to 0: exit 2" status_is 2
check "gen --real float with a constant float rounds to 0: the file and why" \
    err_has "tiny.mech:2:21: error: this constant is 1e-50, which a float (--real float) cannot hold: it would become 0"
run gen "$ex/four_bar.mech" --jac sideways
check "gen --jac sideways exits 2" status_is 2
check "gen --jac sideways names the choices" err_has "auto, spread or direct"
run gen "$ex/four_bar.mech" --prefix 1bad -o "$tmp/bad_prefix.c"
check "gen --prefix 1bad exits 2" status_is 2
check "gen --prefix 1bad says why" err_has "error:"
check "gen --prefix 1bad writes no file" [ ! -e "$tmp/bad_prefix.c" ]
run gen "$ex/four_bar.mech" --prefix int
check "gen --prefix int (a C keyword) exits 2" status_is 2
# mechrt_real, MECHRT_OK, mechrtf_*: the runtime's names are not a prefix's
for p in mechrt MECHRT mechrtf mechrt_x; do
    run gen "$ex/four_bar.mech" --prefix $p -o "$tmp/rt_prefix.c"
    check "gen --prefix $p (the runtime's) exits 2" status_is 2
    check "gen --prefix $p says it clashes with the runtime" \
        err_has "mechc gen: error: --prefix '$p' cannot be used: the runtime's names start with mechrt_, mechrtf_ and MECHRT_, which this prefix would clash with"
    check "gen --prefix $p writes no file" [ ! -e "$tmp/rt_prefix.c" ]
done
run gen "$ex/four_bar.mech" --prefix mechrt2
check "gen --prefix mechrt2 (no clash) exits 0" status_is 0

# ---- gen --roll: loops for joints of one shape (doc/figures.md, "Loop-rolled code")
sh "$ex/chain.sh" 90 "$tmp/chain90.mech"
run gen "$tmp/chain90.mech" -o "$tmp/ch_auto.c"
check "gen --roll auto (default) rolls a chain of 543 rows" grep -q "one shape: one loop" "$tmp/ch_auto.c"
run gen "$tmp/chain90.mech" --roll never -o "$tmp/ch_never.c"
check "gen --roll never writes no loop" sh -c '! grep -q "one shape: one loop" "$1"' _ "$tmp/ch_never.c"
run gen "$ex/four_bar.mech" --roll always -o "$tmp/fb_always.c"
check "gen --roll always exits 0 on the four-bar" status_is 0
run gen "$ex/four_bar.mech" --roll sometimes
check "gen --roll sometimes exits 2" status_is 2
check "gen --roll sometimes names the choices" err_has "auto, never or always"
run gen --help
check "gen --help documents --roll" out_has "--roll WHEN"
if [ -z "${MECHC_SKIP_GCC_ONLY:-}" ] && have gcc; then
    check "gcc compiles gen --roll auto output" \
        gcc -std=c99 -Wall -Wextra -Wpedantic -Werror -c "$tmp/ch_auto.c" -o "$tmp/ch_auto.o"
fi

# ---- spatial mechanisms (doc/spatial.md): gen, eval, check and bench work on them
for f in rssr all_spatial slider_crank_spatial rolling_disk; do
    run check "$ex/$f.mech" --samples 4
    check "check $f (spatial): derivatives, engines agree (exit 0)" status_is 0
    check "check $f (spatial): the last line says so" out_has "ok: every comparison is within its tolerance"
done
run eval "$ex/rssr.mech" --engine generic --json
check "eval --engine generic on a spatial file: exit 0" status_is 0
check "eval: the .norm rows are rows like any other" out_has '{"name": "crank.norm", "kind": "body", "level": "position", "joint": "crank"}'
run eval "$ex/rssr.mech" --json
cp "$tmp/out" "$tmp/rssr_jit.json"
run eval "$ex/rssr.mech" --json --engine generic
# Hand formulas (generator/eval/generic_spatial.c) and generated code
# associate sums differently: the same text, every number within 1e-12.
same_to_roundoff() {
    num='[-]\{0,1\}[0-9][0-9.eE+-]*'
    sed "s/$num/N/g" "$1" > "$tmp/shape1" && sed "s/$num/N/g" "$2" > "$tmp/shape2" \
        && cmp -s "$tmp/shape1" "$tmp/shape2" || return 1
    grep -o "$num" "$1" > "$tmp/num1" && grep -o "$num" "$2" > "$tmp/num2" || return 1
    paste -d ' ' "$tmp/num1" "$tmp/num2" | awk '{ d = $1 - $2; m = $2 < 0 ? -$2 : $2
        if (d > 1e-12 * (1 + m) || -d > 1e-12 * (1 + m)) bad = 1 } END { exit bad }'
}
check "eval: generic (spatial formulas) prints what jit prints, to round-off" same_to_roundoff "$tmp/out" "$tmp/rssr_jit.json"
differs_beyond_roundoff() { ! same_to_roundoff "$@"; }
awk '!done && match($0, /[0-9]+\.[0-9]+/) { v = substr($0, RSTART, RLENGTH)
    $0 = substr($0, 1, RSTART - 1) sprintf("%.17g", v * (1 + 1e-10)) substr($0, RSTART + RLENGTH); done = 1 }
    { print }' "$tmp/rssr_jit.json" > "$tmp/rssr_off.json"
check "eval: ... and the comparison sees a change of 1e-10" differs_beyond_roundoff "$tmp/rssr_off.json" "$tmp/rssr_jit.json"
run gen "$ex/rssr.mech" --real float -o "$tmp/rssr_float.c"
check "gen --real float on a spatial file: exit 0" status_is 0
check "gen: the driven angle's row needs sin and cos of t only" grep -q "sinf\|P_sincos" "$tmp/rssr_float.c"
run info "$ex/all_spatial.mech" --json
check "info --json: rolling's contact row is kind contact" out_has '"name": "roll.h", "kind": "contact"'

suite_end
