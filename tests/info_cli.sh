#!/bin/sh
# tests/info_cli.sh MECHC - `mechc info` from the outside: exit statuses, the
# JSON keys of spec section 3, and the verdicts on the examples (redundant
# row, nonholonomic knife, integrable rolling disk, singular toggle).
#
#   sh tests/info_cli.sh build/mechc
#
# The last line is "info_cli: N passed, M failed"; the exit status is
# non-zero on any failure. The JSON parse checks need python3 and are
# skipped (and say so) without it.
set -u
# shellcheck source=tests/lib.sh
. "$(dirname "$0")/lib.sh"
suite_begin info_cli "${1:-build/mechc}"

# ---- usage and bad input: exit 2 ----

run info --help
check "info --help exits 0" status_is 0
check "info --help shows the usage" out_has "usage: mechc info"
run info
check "info without a file exits 2" status_is 2
check "info without a file says so" err_has "no input file"
run info "$ex/four_bar.mech" --frobnicate
check "info with an unknown option exits 2" status_is 2
run info "$ex/four_bar.mech" --rank-tol
check "info --rank-tol without a value exits 2" status_is 2
run info "$ex/four_bar.mech" --rank-tol -1
check "info --rank-tol -1 exits 2" status_is 2
run info "$ex/four_bar.mech" --rank-tol abc
check "info --rank-tol abc exits 2" status_is 2
run info "$tmp/does_not_exist.mech"
check "info on a missing file exits 2" status_is 2
# a named pipe with no writer once blocked open() forever: only regular
# files are read (stdin is '-'), whatever command reads them
if have mkfifo && mkfifo "$tmp/pipe.mech"; then
    mechc_timeout=20
    for cmd in info run; do
        run $cmd "$tmp/pipe.mech"
        check "$cmd on a named pipe exits 2 (does not block)" status_is 2
        check "$cmd on a named pipe says it is one" \
            err_has "pipe.mech: error: cannot read '$tmp/pipe.mech': a named pipe; give a regular file, or '-' for stdin"
    done
    mechc_timeout=
else
    skip "mkfifo: the named-pipe cases"
fi
run info /dev/null
check "info on a device exits 2" status_is 2
check "info on a device says it is one" err_has "'/dev/null': a device"
run info "$tmp"
check "info on a folder exits 2" status_is 2
check "info on a folder says it is one" err_has "': a directory"
printf 'body b x = 0\nrevolute J: ground crnk\n' > "$tmp/bad.mech"
run info "$tmp/bad.mech"
check "info on bad input exits 2" status_is 2
check "info on bad input reports FILE:LINE:COL: error:" err_has "bad.mech:2:20: error:"

# ---- the analysis cannot assemble: exit 1, the report still printed ----

printf 'point m x = 0.5 y = 0.1\ndistance a: ground(0, 0) m length = 1\ndistance b: ground(5, 0) m length = 1\n' \
    > "$tmp/impossible.mech"
run info "$tmp/impossible.mech"
check "info on an impossible mechanism exits 1" status_is 1
check "info on an impossible mechanism names t = 0" err_has "t = 0"
check "info on an impossible mechanism says the assembly failed" err_has "did not converge"
check "info on an impossible mechanism still prints the report" out_has "verdict:"

# ---- every example runs ----

for f in "$ex"/*.mech; do
    run info "$f"
    check "info ${f##*/} exits 0" status_is 0
    run info "$f" --json
    check "info --json ${f##*/} exits 0" status_is 0
done

# ---- parallelogram: rank 11 of 12, A2.y redundant ----

run info "$ex/parallelogram_redundant.mech"
check "parallelogram: text verdict" \
    out_has "the count says 0 DOF; the Jacobian has rank 11 of 12: the mechanism moves with 1 DOF, row A2.y is redundant"
check "parallelogram: nothing on stderr" err_empty
run info "$ex/parallelogram_redundant.mech" --json
for key in '"coords": [' '"rows": [' '"nq": 12' '"nh": 12' '"nv": 0' '"dof": 0' '"rank": 11' \
           '"redundant": ["A2.y"]' '"joint": "A2"' '"level": "position"' '"kind": "revolute"'; do
    check "parallelogram --json has $key" out_has "$key"
done
cp "$tmp/out" "$tmp/parallelogram.json"
run info "$ex/parallelogram_redundant.mech" --json --rank-tol 1e-30
check "parallelogram --rank-tol 1e-30: rank 12" out_has '"rank": 12'
run info "$ex/parallelogram_redundant.mech" --json --rank-tol=10
check "parallelogram --rank-tol=10: rank 0" out_has '"rank": 0'

# ---- knife: nonholonomic; rolling disk: integrable with its law ----

run info "$ex/knife_cart.mech" --json
cp "$tmp/out" "$tmp/knife.json"
check "knife_cart --json: blade not integrable" \
    grep -q '"name": "blade".*"integrable": false' "$tmp/knife.json"
run info "$ex/knife_cart.mech"
check "knife_cart text: nonholonomic" out_has "not integrable (nonholonomic)"
check "knife_cart text: says the verdicts are per row" out_has "the verdicts above are per row"
check "knife_cart text: nonholonomic as a system too" out_has "nonholonomic: d omega of row blade"
run info "$ex/knife_cart.mech" --json
check "knife_cart --json: system_integrable false" out_has '"system_integrable": false'
run info "$ex/rolling_wheel.mech" --json
check "rolling_wheel --json: system_integrable true" out_has '"system_integrable": true'
run info "$ex/four_bar.mech" --json
check "four_bar --json: system_integrable null (no velocity rows)" out_has '"system_integrable": null'

run info "$ex/rolling_disk_velocity.mech" --json
cp "$tmp/out" "$tmp/disk.json"
check "rolling_disk_velocity --json: roll integrable with its law" \
    grep -q '"name": "roll".*"integrable": true, "law": "disk.x + 0.5\*disk.phi = const"' "$tmp/disk.json"
run info "$ex/rolling_wheel.mech"
check "rolling_wheel text: law" out_has "wheel.x + 0.5*wheel.phi = const"
run info "$ex/skate_velocity.mech" --json
check "skate_velocity --json: side not integrable" \
    grep -q '"name": "side".*"integrable": false' "$tmp/out"

# ---- the toggle position of slider_crank_toggle.mech ----

run info "$ex/slider_crank_toggle.mech" --t 0.25
check "slider_crank_toggle --t 0.25 exits 0" status_is 0
check "slider_crank_toggle --t 0.25: near-singular" out_has "near-singular"
run info "$ex/slider_crank_toggle.mech"
check "slider_crank_toggle at t = 0: regular" out_has "configuration: regular"

# ---- the JSON parses and has the spec's shape ----

if have python3; then
    check "info --json parses with the spec's keys (parallelogram)" py - "$tmp/parallelogram.json" <<'EOF'
import json, sys
d = json.load(open(sys.argv[1]))
for k in ("coords", "rows", "nq", "nh", "nv", "dof", "rank", "redundant"):
    assert k in d, k
assert d["dof"] == d["nq"] - d["nh"] - d["nv"]
assert len(d["coords"]) == d["nq"] and len(d["rows"]) == d["nh"] + d["nv"]
for r in d["rows"]:
    assert set(("name", "kind", "level", "joint")) <= set(r), r
    assert r["level"] in ("position", "velocity")
assert d["redundant"] == ["A2.y"] and d["rank"] == 11
assert d["cond"] is None or d["cond"] > 1e14
EOF
    check "info --json parses: velocity rows carry integrable and law (rolling disk)" \
        py - "$tmp/disk.json" <<'EOF'
import json, sys
d = json.load(open(sys.argv[1]))
vel = [r for r in d["rows"] if r["level"] == "velocity"]
assert len(vel) == d["nv"] == 2
for r in vel:
    assert isinstance(r["integrable"], bool)
    if r["integrable"]:
        assert isinstance(r["law"], str) and r["law"]
roll = [r for r in vel if r["name"] == "roll"][0]
assert roll["integrable"] and "disk.x + 0.5*disk.phi" in roll["law"]
for r in d["rows"]:
    if r["level"] == "position":
        assert "integrable" not in r
EOF
    check "info --json parses: knife blade nonholonomic, no law" py - "$tmp/knife.json" <<'EOF'
import json, sys
d = json.load(open(sys.argv[1]))
blade = [r for r in d["rows"] if r["name"] == "blade"][0]
assert blade["integrable"] is False and "law" not in blade
EOF
else
    skip "python3 not found: JSON parse checks"
fi

# ---- spatial mechanisms (doc/spatial.md) ---------------------------------
# Bricard: the count says it cannot move, the rank finds one redundant row
# and 1 DOF (examples/bricard.mech's header)
run info "$ex/bricard.mech"
check "bricard: exit 0" status_is 0
check "bricard: the count says 0 DOF" out_has "35 coordinates - 35 holonomic - 0 velocity-level rows = 0 DOF"
check "bricard: rank deficiency 34 of 35" out_has "holonomic rows: rank 34 of 35"
check "bricard: permanent, not a singular pose" out_has "a permanent redundancy"
check "bricard: names the redundant row" out_has "redundant rows: J6.g (joint J6)"
check "bricard: 1 DOF by the rank" out_has "DOF by the rank: 1 with drivers, 1 without"
check "bricard: the verdict" out_has "the mechanism moves with 1 DOF, row J6.g is redundant"
# the rolling disk: its no-slip rows are nonholonomic (Frobenius test)
run info "$ex/rolling_disk.mech"
check "rolling disk: exit 0" status_is 0
check "rolling disk: roll.x not integrable" grep -q "^  roll.x  *not integrable (nonholonomic)" "$tmp/out"
check "rolling disk: roll.y not integrable" grep -q "^  roll.y  *not integrable (nonholonomic)" "$tmp/out"
check "rolling disk: the rows together, drivers left out: nonholonomic" \
    grep -A1 -q "drivers left out" "$tmp/out"
check "rolling disk: ... and the verdict there is nonholonomic" \
    sh -c "grep -A1 'drivers left out' '$tmp/out' | grep -q '^  nonholonomic'"
check "rolling disk: the contact row is holonomic" out_has "roll.h"
check "rolling disk: 3 DOF without the drivers" out_has "without its 3 drivers: 3 DOF by the count, 3 by the rank"
# every spatial body's normalisation row is a row like any other
run info "$ex/rssr.mech"
check "rssr: counts the .norm rows" out_has "14 coordinates, 14 rows (14 holonomic, 0 velocity level)"
check "rssr: crank.norm listed" grep -q "^  crank.norm  *crank  *body  *position" "$tmp/out"
check "rssr: 1 DOF without its driver" out_has "without its 1 driver: 1 DOF by the count, 1 by the rank"

# rough initial values (every guess 0): info assembles them as run does
sed -E 's/^(body +[A-Za-z_0-9]+).*/\1/' "$ex/four_bar.mech" > "$tmp/fb0.mech"
run info "$tmp/fb0.mech" --json
check "info from every guess 0: assembled" out_has '"assembled": true'
# ---- info at a given state: --at T, --state FILE.csv ----------------------
# The A02 chain of 40 parallelograms driven flat at t = 0.25: every loop
# folds at once, the holonomic rows lose 40 ranks and 40 rows turn
# dependent (beyond 100 coordinates: SuiteSparseQR).
sh "$ex/chain.sh" 40 "$tmp/c40.mech"
sed -e 's/^driver drive: rod0.phi = .*/driver drive: rod0.phi = pi\/2 - 2*pi*t/' "$tmp/c40.mech" \
    > "$tmp/a02.mech"
run info "$tmp/a02.mech" --at 0.25
check "A02 --at 0.25: exit 0" status_is 0
check "A02 --at 0.25: the motion followed from t = 0" out_has "the motion followed from t = 0"
check "A02 --at 0.25: rank 203 against 243" \
    out_has "rank 203 of the holonomic rows (drivers included) against 243 generically"
check "A02 --at 0.25: a drop of 40 (sparse QR: pivots, not singular values)" \
    out_has "(at t = 0 or just before): a drop of 40 (sparse QR pivots above 3.27e-08 count)"
check "A02 --at 0.25: 40 rows became dependent, b0.x first" out_has "rows that became dependent (40): b0.x, b1.x"
check "A02 --at 0.25: ... and b39.x last" grep -q "dependent (40): .*b38.x, b39.x$" "$tmp/out"
check "A02 --at 0.25: 40 free directions" out_has "directions the rows leave free (40;"
check "A02 --at 0.25: the first one folds loop 0 (rod1 with cpl0)" \
    out_has "cpl1.phi: cpl0.phi -1 rod1.phi -1 cpl1.phi 1 cpl0.y -0.5 rod1.y -0.5 cpl1.y -0.5"
run info "$tmp/a02.mech" --at 0.25 --json
check "A02 --at 0.25 --json: state.drop 40" out_has '"drop": 40'
check "A02 --at 0.25 --json: generic_rank 243" out_has '"generic_rank": 243'
# at an ordinary time of the same chain nothing drops
run info "$tmp/a02.mech" --at 0.1
check "A02 --at 0.1: a drop of 0" out_has "against 243 generically"
check "A02 --at 0.1: ... a drop of 0" out_has ": a drop of 0 "
check "A02 --at 0.1: no dependent rows" out_has "rows that became dependent (0): none"
# one parallelogram four-bar, folded flat: a drop of 1
sh "$ex/chain.sh" 1 "$tmp/c1.mech"
sed -e 's/^driver drive: rod0.phi = .*/driver drive: rod0.phi = pi\/2 - 2*pi*t/' "$tmp/c1.mech" \
    > "$tmp/pg.mech"
run info "$tmp/pg.mech" --at 0.25
check "parallelogram four-bar folded: rank 8 against 9" \
    out_has "rank 8 of the holonomic rows (drivers included) against 9 generically"
check "parallelogram four-bar folded: b0.x dependent" out_has "rows that became dependent (1): b0.x"
check "parallelogram four-bar folded: rod1 and cpl0 free to fold" \
    out_has "rod1.phi: cpl0.phi 1 rod1.phi 1"
run info "$tmp/pg.mech" --at 0.25 --linear sparse
check "parallelogram four-bar folded, sparse: the same drop" out_has "rows that became dependent (1): b0.x"
# an ordinary example at an ordinary time
run info "$ex/four_bar.mech" --at 0.3
check "four_bar --at 0.3: a drop of 0" out_has "rank 9 of the holonomic rows (drivers included) against 9"
check "four_bar --at 0.3: no free direction" out_has "directions the rows leave free: none"
check "four_bar --at 0.3: dense, so singular values" out_has "a drop of 0 (singular values above"
# --state: the row run writes, read back
"$mechc" run "$tmp/pg.mech" --t0 0 --t1 0.2 --steps 8 --csv "$tmp/pg.csv" > /dev/null 2>&1
"$mechc" run "$ex/four_bar.mech" --at 0.3 --csv "$tmp/fb.csv" > /dev/null 2>&1
run info "$ex/four_bar.mech" --state "$tmp/fb.csv" --json
check "--state: exit 0" status_is 0
check "--state: the state's t" out_has '"t": 0.3'
check "--state: read from the CSV" out_has '"source": "csv"'
run info "$ex/four_bar.mech" --state "$tmp/pg.csv"
check "--state with another mechanism's CSV: exit 2" status_is 2
check "--state with another mechanism's CSV: names the column" err_has "no column named crank.x"
run info "$tmp/pg.mech" --state "$tmp/pg.csv"
check "--state with several rows and no --at: exit 2" status_is 2
check "--state with several rows: asks for --at" err_has "rows: give --at T"
run info "$tmp/pg.mech" --state "$tmp/pg.csv" --at 0.125
check "--state --at 0.125: that row" out_has "at this state (t = 0.125, read from the CSV"
run info "$tmp/pg.mech" --state "$tmp/pg.csv" --at 0.21
check "--state --at 0.2: no such row, exit 2" status_is 2
run info "$ex/four_bar.mech" --state "$tmp/nothing.csv"
check "--state on a missing file: exit 2" status_is 2
run info "$ex/four_bar.mech" --state "$tmp"
check "--state on a folder: exit 2" status_is 2
check "--state on a folder: says why" \
    err_has "$tmp: error: cannot read '$tmp': a directory; give a regular file, or '-' for stdin"
# the state CSV is read as a .mech file is: a named pipe with no writer
# does not block (it once did, in fopen), and '-' is stdin
if have mkfifo && mkfifo "$tmp/pipe.csv"; then
    mechc_timeout=20
    run info "$ex/four_bar.mech" --state "$tmp/pipe.csv"
    check "--state on a named pipe: exit 2 (does not block)" status_is 2
    check "--state on a named pipe: says it is one" \
        err_has "pipe.csv: error: cannot read '$tmp/pipe.csv': a named pipe; give a regular file, or '-' for stdin"
    mechc_timeout=
else
    skip "mkfifo: --state on a named pipe"
fi
"$mechc" run "$ex/four_bar.mech" --steps 2 > "$tmp/fb2.csv"
"$mechc" info "$ex/four_bar.mech" --state - --at 0.5 < "$tmp/fb2.csv" > "$tmp/out" 2> "$tmp/err"
rc=$?
check "--state - (stdin): exit 0" status_is 0
check "--state - (stdin): the state at t = 0.5" out_has "read from the CSV"
# a number that is not finite, where it is read: FILE:LINE:COL and a caret
sed '2s/^[^,]*/inf/' "$tmp/fb.csv" > "$tmp/fb_inf.csv"
run info "$ex/four_bar.mech" --state "$tmp/fb_inf.csv"
check "--state with t = inf: exit 2" status_is 2
check "--state with t = inf: at line 2, column 1" \
    err_has "fb_inf.csv:2:1: error: field 1 ('inf') is not a finite number"
check "--state with t = inf: nothing printed" out_empty
# nan as the third field (the CSV's second coordinate): its byte column
awk -F, -v OFS=, 'NR == 2 { $3 = "nan" } { print }' "$tmp/fb.csv" > "$tmp/fb_nan.csv"
col=$(awk -F, 'NR == 2 { print length($1) + length($2) + 3 }' "$tmp/fb_nan.csv")
name=$(awk -F, 'NR == 1 { print $3 }' "$tmp/fb_nan.csv")
run info "$ex/four_bar.mech" --state "$tmp/fb_nan.csv"
check "--state with $name = nan: exit 2" status_is 2
check "--state with $name = nan: at line 2, column $col" \
    err_has "fb_nan.csv:2:$col: error: field 3 ('nan') is not a finite number"
check "--state with $name = nan: the caret under it" \
    err_matches "^    $(printf "%${col}s" "^")\$"
# a field short, and a bad number
sed '2s/,[^,]*$//' "$tmp/fb.csv" > "$tmp/fb_short.csv"
run info "$ex/four_bar.mech" --state "$tmp/fb_short.csv"
check "--state with a field short: exit 2" status_is 2
col=$(awk 'NR == 2 { print length($0) + 1 }' "$tmp/fb_short.csv")
check "--state with a field short: counts the fields, at the line's end" \
    err_matches "fb_short.csv:2:$col: error: [0-9]* fields where the header has"
awk -F, -v OFS=, 'NR == 2 { $2 = "1.5x" } { print }' "$tmp/fb.csv" > "$tmp/fb_bad.csv"
run info "$ex/four_bar.mech" --state "$tmp/fb_bad.csv"
check "--state with a bad number: names it" err_matches "fb_bad.csv:2:[0-9]*: error: field 2 ('1.5x') is not a number"
# velocity-level rows: run integrates the positions, --at does not follow them
run info "$ex/knife_cart.mech" --at 0.5
check "--at with velocity-level rows: exit 2" status_is 2
check "--at with velocity-level rows: points to --state" err_has "give it with --state"
# run --at T would put the initial positions at T: the advice integrates to T
check "--at with velocity-level rows: the advice integrates to T" \
    err_has "mechc run FILE --t1 T --csv STATE.csv"
"$mechc" run "$ex/knife_cart.mech" --t1 0.5 --csv "$tmp/knife.csv" > /dev/null 2>&1
run info "$ex/knife_cart.mech" --state "$tmp/knife.csv" --at 0.5
check "--state with velocity-level rows: exit 0" status_is 0
check "--state with velocity-level rows: the integrated state (cart.y = 1, not 0)" \
    grep -q "^  cart.y  *0  *1$" "$tmp/out"
check "--state with velocity-level rows: the knife is free in 3 directions" \
    out_has "directions the rows leave free (3;"

# ---- --linear: SuiteSparseQR gives the dense SVD's verdicts (doc/large.md) --
for f in "$ex"/*.mech; do
    n=${f##*/}; n=${n%.mech}
    "$mechc" info "$f" --json --linear dense > "$tmp/$n.dense.json" 2>/dev/null
    "$mechc" info "$f" --json --linear sparse > "$tmp/$n.sparse.json" 2>/dev/null
done
if have python3; then
    check "--linear sparse and dense: the same rank, redundant rows and mobility on every example" \
        py - "$tmp" "$ex" <<'EOF'
import glob, json, os, sys
tmp, ex = sys.argv[1], sys.argv[2]
keys = ("rank", "rank_all", "redundant", "redundant_velocity", "dof_rank", "mobility_rank")
n = 0
for f in sorted(glob.glob(os.path.join(ex, "*.mech"))):
    name = os.path.basename(f)[:-5]
    d = json.load(open(os.path.join(tmp, name + ".dense.json")))
    s = json.load(open(os.path.join(tmp, name + ".sparse.json")))
    assert d["dense"] is True and s["dense"] is False, name
    for k in keys:
        assert d[k] == s[k], (name, k, d[k], s[k])
    n += 1
assert n >= 20, n
EOF
else
    skip "python3 not found: --linear comparison"
fi
run info "$ex/parallelogram_redundant.mech" --linear sparse
check "parallelogram --linear sparse: A2.y redundant" out_has "row A2.y is redundant"
check "parallelogram --linear sparse: says sparse QR" out_has "rank (sparse QR at the assembled configuration)"
run info "$ex/four_bar.mech" --linear nope
check "--linear nope: exit 2" status_is 2
# chain N = 1000 (6003 x 6003): auto goes sparse and is quick; dense is refused
sh "$ex/chain.sh" 1000 "$tmp/c1000.mech"
run info "$tmp/c1000.mech"
check "chain 1000: exit 0" status_is 0
check "chain 1000: full rank by sparse QR" out_has "holonomic rows: rank 6003 of 6003"
check "chain 1000: 1 DOF without the driver" out_has "DOF by the rank: 0 with drivers, 1 without"
run info "$tmp/c1000.mech" --linear dense
check "chain 1000 --linear dense: refused, exit 2" status_is 2
check "chain 1000 --linear dense: says why" err_has "beyond --max-dense"
# chain N = 1200 (7203 x 7203 = 51.9 million entries, past the default
# dense-Jacobian limit of 50 million): the sparse rank forms no dense
# matrix, so auto loads it; --linear dense is refused at the limit
sh "$ex/chain.sh" 1200 "$tmp/c1200.mech"
run info "$tmp/c1200.mech"
check "chain 1200 (past the dense limit): exit 0" status_is 0
check "chain 1200: full rank by sparse QR" out_has "holonomic rows: rank 7203 of 7203"
run info "$tmp/c1200.mech" --linear dense
check "chain 1200 --linear dense: exit 2" status_is 2
check "chain 1200 --linear dense: the dense limit named, with the line" \
    err_matches "c1200.mech:[0-9]*:[0-9]*: error: the dense Jacobian would have .* more than the limit of 50000000"
suite_end
