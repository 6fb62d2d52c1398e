#!/bin/sh
# tests/firmware_rules.sh MECHC - checks the promise of spec section 4 on the
# compiled objects, not only on the text: generated kernels and the runtime
# core build as freestanding C99 and need nothing but <math.h> (and, for
# the kernels, memset of <string.h>).
#
#   sh tests/firmware_rules.sh build/mechc
#
# For every examples/*.mech (and a synthetic mechanism that uses every
# function of the file format) in double and float:
#   - `mechc gen --lu` output (with --batch for the files whose batch
#     functions take every path of generator/emit/batch.c: lanes, the
#     plain loop, rolled, sparse-only, design parameters, every function
#     of the format; the others' batch code is the same text over other
#     chunks) compiles with cc -std=c99 -O2 -ffreestanding
#     -Wall -Wextra -Wpedantic -Wconversion -Wdouble-promotion -Wvla -Werror
#     (float code: float literals and sinf/cosf..., no promotion to double;
#     no variable-length arrays);
#   - the source includes only <math.h>, <string.h> (memset, the Jacobian's
#     zero fill) and its own header, and names no
#     allocation, stdio or other library call; `static` appears only as
#     `static const` data or in the PART macro of helper functions;
#   - nm: every undefined symbol is a <math.h> function of the right
#     precision, or memset/memcpy/memmove/memcmp, which GCC documents that
#     every freestanding environment must provide and may call for zeroing
#     or copying loops (GCC 12 emits none here under -ffreestanding; hosted
#     -O2 builds do call memset for the Jacobian's zero fill, and glibc
#     hosts merge sin/cos into sincos, which newlib also has);
#   - no writable data: no D/d/B/b/C/G/g/S/s symbols, empty .data and .bss
#     (objects built -fno-pie: position-independent code would move the
#     name tables' pointers to .data.rel.ro);
#   - every defined symbol starts with the prefix (several mechanisms link
#     into one image);
#   - call graph (objdump -dr): no indirect call, every call goes to the
#     object's own functions (the _partN helpers, fb_jac -> fb_jac_nz) or
#     to an allowed libm function, and the graph has no cycle: no recursion.
# The runtime core (runtime/*.c, not runtime/host/) in double and float:
# the same flags, no undefined symbol but mechrt's own and mem*, no writable
# data, an acyclic direct-call graph (its indirect calls are the kernels,
# by design), exported names mechrt_* (double) or mechrtf_* (float).
# Linking: slider_crank (prefix sc) + four_bar (prefix fb) + the runtime in
# one program, run and checked against known values; and the same two in
# double with four_bar as fbf in float and both runtime builds (mechrt_*,
# mechrtf_*) in one program; and the forward dynamics of the runtime
# (dynamics.c) on pendulum_distance with hand-written mass and force, in
# double and float, against the closed form.
# With arm-none-eabi-gcc installed (.ci/deps firmware), the kernels and the
# runtime are also compiled for a Cortex-M4F (float, hard-float ABI) and a
# Cortex-M3 (double, software floating point) and checked the same way;
# there the compiler's floating-point helpers (__aeabi_*) are allowed too.
#
# FIRMWARE_RULES=cross (make firmware-check) runs the Cortex-M builds only,
# FIRMWARE_RULES=host (make check) the host's only: each compile is done
# once over the two targets. MECHC_SKIP_GCC_ONLY=1 (make
# check-asan and check-valgrind, whose instruments cannot see inside the
# compiler) keeps mechc gen and the source rules and skips what only
# compiles and inspects the written C.
#
# The last line is "firmware_rules: N passed, M failed"; the exit status is
# non-zero on any failure. POSIX sh, awk, cc, nm, objdump.
# Flag lists ($FLAGS, $arch ...) are split into words on purpose.
# shellcheck disable=SC2086,SC2046
set -u
# shellcheck source=tests/lib.sh
. "$(dirname "$0")/lib.sh"
suite_begin firmware_rules "${1:-build/mechc}"

CC=${CC:-cc}
FLAGS="-std=c99 -O2 -ffreestanding -Wall -Wextra -Wpedantic -Wconversion -Wdouble-promotion -Wvla -Werror"
LIBM='sin|cos|tan|asin|acos|atan|atan2|sqrt|exp|log|sinh|cosh|tanh|pow|fabs'
MEM='memset|memcpy|memmove|memcmp'

# report DESCRIPTION LINES: says on stderr that DESCRIPTION failed, with
# the first LINES lines of $tmp/why.
report() {
    echo "FAIL: $1" >&2
    sed -n "1,${2}s/^/    /p" "$tmp/why" >&2
}

# try LINES DESCRIPTION COMMAND...: runs COMMAND with its output in $tmp/why
# and counts the outcome (tests/lib.sh); a failure is reported with LINES
# lines of that output, and try fails too.
try() {
    lines=$1 desc=$2
    shift 2
    if "$@" > "$tmp/why" 2>&1; then
        ok
    else
        fail=$((fail + 1))
        report "$desc" "$lines"
        return 1
    fi
}

for tool in "$CC" nm objdump; do
    if ! have "$tool"; then
        echo "firmware_rules: $tool is missing" >&2
        fail=1
        suite_end
        exit 1
    fi
done

# ---- helpers over objects ---------------------------------------------------

# The rules on one object OBJ read two listings that object_rules
# writes: OBJ.nm (nm: a defined symbol has three fields, an undefined one
# two) and OBJ.dis (objdump -h -dr --no-show-raw-insn: the sections, then
# the disassembly; one process, where size -A was a second). nm is given
# the object's format (the disassembly's header says it): guessing it, nm
# tries the linker plugins (LLVMgold among them), eight times slower. Then one awk (rules.awk, then
# callgraph.awk) judges every rule and writes what breaks rule R to OBJ.R:
#   undefined_only    every undefined symbol matches the regex ext;
#   no_writable_data  no data/bss symbols, empty .data and .bss;
#   defined_prefixed  every defined symbol matches the regex prefix (if set);
#   call_graph        below.
# One process per listing and one for the rules: this script runs them for
# some 120 objects, and starting a process costs more than a rule (5 to 8
# ms of CPU on this project's machine).
cat > "$tmp/rules.awk" <<'EOF'
function broken(rule, why) { print why > (obj "." rule) }
BEGIN {
    # every verdict file, new and empty: a rule that writes nothing is kept
    split("undefined_only no_writable_data defined_prefixed call_graph", rules)
    for (r in rules) printf "" > (obj "." rules[r])
}
FILENAME == obj ".nm" {
    if (NF == 2 && $2 !~ ext) broken("undefined_only", "undefined: " $2)
    if (NF == 3 && $2 ~ /^[DdBbCGgSs]$/) broken("no_writable_data", "writable: " $0)
    if (prefix != "" && NF == 3 && $2 ~ /^[TtRrDdBb]$/ && $3 !~ /^[.$]/ && $3 !~ prefix)
        broken("defined_prefixed", "foreign name: " $3)
    next
}
# objdump -h's table: index, name, size (hex), ...
FILENAME == obj ".dis" && /^ *[0-9]+ \./ && NF >= 7 {
    if ($2 ~ /^\.(data|bss)/ && $3 !~ /^0+$/) broken("no_writable_data", "section " $2 " has 0x" $3 " bytes")
    next
}
EOF

# object_rules OBJ NM OBJDUMP EXT PREFIX ALLOW_INDIRECT: OBJ's
# listings and verdicts; OBJ.judged when all were written.
object_rules() {
    "$3" -h -dr --no-show-raw-insn "$1" > "$1.dis" || return 1
    { read -r line; read -r line; } < "$1.dis"
    case $line in
        *" file format "*) format=${line##* file format } ;;
        *) format= ;;
    esac
    "$2" ${format:+--target="$format"} "$1" > "$1.nm" &&
    awk -v obj="$1" -v ext="$4" -v prefix="$5" -v allow_indirect="$6" \
        -f "$tmp/rules.awk" -f "$tmp/callgraph.awk" "$1.nm" "$1.dis" &&
    : > "$1.judged"
}

# kept OBJ RULE: object_rules found OBJ keeping RULE; else prints why not.
kept() {
    if [ ! -f "$1.judged" ]; then
        echo "not judged: objdump, nm or the rules failed on $1"
        return 1
    fi
    [ -s "$1.$2" ] || return 0
    while IFS= read -r line; do printf '%s\n' "$line"; done < "$1.$2"
    return 1
}

# The call graph of one object from `objdump -dr --no-show-raw-insn`, x86-64
# or Arm Thumb. A branch's target is the symbol of the relocation that
# follows it (calls to other objects and to libm), else the <name> that the
# assembler resolved (calls inside the section); a target inside the
# current function is a local jump. Checks: no indirect branch unless
# allow_indirect, every target a function of this object or matching the
# regex ext, no cycle (nodes are removed while they call no remaining node;
# what is left lies on a cycle).
cat > "$tmp/callgraph.awk" <<'EOF'
function base(s) { sub(/[+-]0x[0-9a-f]+$/, "", s); return s }
# A branch to another function, or a call (not a jump) to this one's entry.
function flush() {
    if (pending && target != "" && (target != fn || is_call)) edge(fn, target)
    pending = 0; target = ""
}
function edge(a, b) {
    if (!((a, b) in seen)) { seen[a, b] = 1; from[++ne] = a; to[ne] = b }
}
/^[0-9a-f]+ <[^>]+>:$/ {
    flush()
    fn = $2; gsub(/[<>:]/, "", fn); defined[fn] = 1
    next
}
/^[ \t]+[0-9a-f]+:[ \t]+R_/ {
    if (pending) { target = base($NF); flush() }
    next
}
/^[ \t]+[0-9a-f]+:\t/ {
    flush()
    insn = $0; sub(/^[^\t]*\t/, "", insn)
    mnem = insn; sub(/[ \t].*/, "", mnem)
    ops = insn; sub(/^[^ \t]+[ \t]*/, "", ops)
    if (mnem ~ /^(call|jmp|j[a-z]+)/ || (mnem ~ /^(b[a-z]*(\.[nw])?|cbn?z)$/ && mnem !~ /^(bic|bics|bfi|bfc|bkpt)/)) {
        if (ops ~ /^\*/ || mnem ~ /^(blx|bx)/ && ops ~ /^(r[0-9]+|ip|sl|fp)$/) {
            if (!allow_indirect) broken("call_graph", fn ": indirect branch: " insn)
            next
        }
        pending = 1
        is_call = mnem ~ /^(call|bl|blx)$/
        if (match(ops, /<[^>]+>/)) {
            target = substr(ops, RSTART + 1, RLENGTH - 2)
            # a jump or call into the middle of this function is local
            if (base(target) == fn && target != fn) target = ""
            else target = base(target)
        }
    } else if (mnem ~ /^(tbb|tbh)/ && !allow_indirect) {
        broken("call_graph", fn ": table branch: " insn)
    }
    next
}
END {
    flush()
    for (i = 1; i <= ne; i++) {
        if (to[i] in defined) { out[from[i]]++; continue }
        if (to[i] ~ /^\./) broken("call_graph", from[i] ": section-relative branch to " to[i])
        else if (to[i] !~ ext) broken("call_graph", from[i] ": calls " to[i])
    }
    do {
        changed = 0
        for (f in defined) if (!(f in gone) && !out[f]) {
            gone[f] = 1; changed = 1
            for (i = 1; i <= ne; i++) if (to[i] == f) out[from[i]]--
        }
    } while (changed)
    for (f in defined) if (!(f in gone)) broken("call_graph", "on a call cycle: " f)
}
EOF

# The source rules, one awk over the files named: each file's C text
# without comments and with every string and character literal emptied
# (names from the .mech file live in those), #include lines kept whole
# (they name their file in quotes); then on that text: every #include
# matches the regex includes, no forbidden name (allocation, stdio, exit
# and the like), and with statics=1 `static` only as `static const` data,
# in the PART or TRIG macro of helper functions or on the sincos2 helper.
# Prints what breaks a rule; fails then, and on an empty file.
cat > "$tmp/source_rules.awk" <<'EOF'
function has_word(s, w) { return s ~ ("(^|[^A-Za-z0-9_])(" w ")([^A-Za-z0-9_]|$)") }
BEGIN {
    forbidden = "malloc|calloc|realloc|free|alloca|printf|fprintf|sprintf|snprintf|puts|putchar|" \
                "fopen|FILE|stdio|stdlib|setjmp|longjmp|exit|abort|errno"
}
FNR == 1 { incomment = 0; lines[FILENAME] = 1 }
{
    out = ""; i = 1; n = length($0)
    while (i <= n) {
        c = substr($0, i, 1); d = substr($0, i, 2)
        if (incomment) {
            if (d == "*/") { incomment = 0; i += 2 } else i++
        } else if (d == "/*") { incomment = 1; i += 2; out = out " "
        } else if (d == "//") { break
        } else if (c == "\"" || c == "'") {
            # a literal: skip to its closing quote, past escapes
            for (j = i + 1; j <= n && substr($0, j, 1) != c; j++)
                if (substr($0, j, 1) == "\\") j++
            out = out c c; i = j + 1
        } else { out = out c; i++ }
    }
    if ($0 ~ /^[ \t]*#[ \t]*include/) {
        out = $0
        if (out !~ includes) { print FILENAME ": " out; bad = 1 }
    }
    if (has_word(out, forbidden)) { print FILENAME ":" FNR ": " out; bad = 1 }
    if (statics && has_word(out, "static") &&
        out !~ /static const|#define [A-Z0-9_]+_(PART|TRIG) static|static void [A-Za-z0-9_]+_sincos2_apart\(double/) {
        print FILENAME ":" FNR ": " out; bad = 1
    }
}
END {
    for (k = 1; k < ARGC; k++)
        if (!(ARGV[k] in lines)) { print ARGV[k] ": empty"; bad = 1 }
    exit bad
}
EOF

# source_rules C H: includes, forbidden names, static.
source_rules() {
    awk -v statics=1 -v includes='^#include (<math[.]h>|<string[.]h>|"[A-Za-z0-9_]+[.]h")$' \
        -f "$tmp/source_rules.awk" "$@"
}

# ---- the toolchains ---------------------------------------------------------
# name|compiler|arch flags|nm|objdump|reals|extra allowed symbols
toolchains=
host=0
if [ -n "${MECHC_SKIP_GCC_ONLY:-}" ]; then
    skip "MECHC_SKIP_GCC_ONLY: gen and the source rules only, no compile"
elif [ "${FIRMWARE_RULES:-}" = cross ]; then
    skip "FIRMWARE_RULES=cross: the host's builds (make check runs them)"
else
    toolchains="host|$CC|-fno-pie|nm|objdump|double float|"
    host=1
fi
if [ -n "${MECHC_SKIP_GCC_ONLY:-}" ]; then
    :
elif [ "${FIRMWARE_RULES:-}" = host ]; then
    skip "FIRMWARE_RULES=host: the Cortex-M builds (make firmware-check runs them)"
elif command -v arm-none-eabi-gcc > /dev/null 2>&1; then
    a=arm-none-eabi-
    toolchains="$toolchains
m4f|${a}gcc|-mcpu=cortex-m4 -mthumb -mfpu=fpv4-sp-d16 -mfloat-abi=hard|${a}nm|${a}objdump|float|__aeabi_[a-z0-9]+
m3|${a}gcc|-mcpu=cortex-m3 -mthumb -mfloat-abi=soft|${a}nm|${a}objdump|double|__aeabi_[a-z0-9]+"
else
    echo "skip: arm-none-eabi-gcc missing: Cortex-M builds (sh .ci/deps firmware installs it)" >&2
fi

# A mechanism using every function and operator of the file format, for
# the float spellings (sinf, atan2f, powf ...) and float literals. It need
# not assemble: only its code is compiled.
cat > "$tmp/every_function.mech" <<'EOF'
mechanism every_function
param a = 0.5
body b x = 0.3 y = 0.4 phi = 0.2
coord s = 0.7
point m x = 1 y = 1
constraint c1: sin(b.x) + cos(b.y) + tan(b.phi) + asin(b.x) + acos(b.y) + atan(b.phi) = 3*t + a
constraint c2: atan2(b.x, b.y) + sqrt(m.x) + exp(m.y) + log(m.x) + sinh(s) + cosh(s) + tanh(s) = t^2
constraint c3: m.x^3 + m.y^0.5 + m.x^m.y + (-s)^2 - 1e-3/s = 1/(1 + t)
driver d1: b.phi = 0.2 + t
distance L: b(0.1, 0) m length = 1 + 0.1*t
velocity v: der(m.x) + b.x*der(m.y) = sin(t)
EOF

# A chain written loop-rolled (gen --roll always): static const tables,
# loops, arrays of sin and cos on the stack; and one written sparse-only
# (gen --sparse-only, rolled: no dense jac and all, all_nz instead).
sh "$root/examples/chain.sh" 12 "$tmp/chain_rolled.mech"
sh "$root/examples/chain.sh" 12 "$tmp/chain_sparse_only.mech"

# ---- generated kernels --------------------------------------------------------
for mech in "$root"/examples/*.mech "$tmp/every_function.mech" "$tmp/chain_rolled.mech" \
            "$tmp/chain_sparse_only.mech"; do
    name=${mech##*/}
    name=${name%.mech}
    case $name in
        *[!A-Za-z0-9_]*) prefix=$(echo "$name" | tr -c 'A-Za-z0-9_\n' '_') ;;
        *) prefix=$name ;;
    esac
    roll=never
    only=
    batch=
    case $name in
        chain_rolled) roll=always ;;
        chain_sparse_only) roll=always only=--sparse-only ;;
    esac
    case $name in
        four_bar | stewart | freudenstein | every_function | chain_rolled | chain_sparse_only \
        | heavy_top) batch=--batch ;;
    esac
    mkdir -p "$tmp/$name-double" "$tmp/$name-float"     # one process for both
    for real in double float; do
        d=$tmp/$name-$real
        try 5 "$name ($real): mechc gen" "$mechc" gen "$mech" --prefix "$prefix" --real "$real" --lu $batch \
            --roll "$roll" $only -o "$d/$prefix.c" --header "$d/$prefix.h" || continue
        if [ -n "$only" ]; then
            try 5 "$name ($real): no dense jac or all, ${prefix}_all_nz" sh -c \
                "grep -q '^#define $(echo "$prefix" | tr a-z A-Z)_SPARSE_ONLY 1' '$d/$prefix.h' &&
                 grep -q '${prefix}_all_nz(' '$d/$prefix.c' &&
                 ! grep -E '${prefix}_(jac|all)\(' '$d/$prefix.c' '$d/$prefix.h'"
        fi
        try 12 "$name ($real): source rules" source_rules "$d/$prefix.c" "$d/$prefix.h"
        if [ "$real" = float ]; then f=f; else f=; fi
        while IFS='|' read -r tc cc arch nm_ objdump_ reals extra; do
            case " $reals " in *" $real "*) ;; *) continue ;; esac
            allowed="^(($LIBM)$f|$MEM${extra:+|$extra})\$"
            o=$d/$prefix-$tc.o
            try 10 "$name ($real, $tc): $cc $FLAGS $arch" \
                $cc $FLAGS $arch -I"$d" -c "$d/$prefix.c" -o "$o" || continue
            object_rules "$o" "$nm_" "$objdump_" "$allowed" "^${prefix}_" 0
            for rule in undefined_only no_writable_data defined_prefixed call_graph; do
                try 10 "$name ($real, $tc): $rule" kept "$o" $rule
            done
        done <<EOF
$toolchains
EOF
    done
done

# ---- the runtime core -----------------------------------------------------------
rt_sources=$(ls "$root"/runtime/*.c)
rt_src_rules() {
    awk -v statics=0 -v includes='^#include (<math[.]h>|<stddef[.]h>|<stdbool[.]h>|"mechrt[.]h")$' \
        -f "$tmp/source_rules.awk" "$@"
}
# exported_only OBJ NM REGEX: every global defined symbol matches REGEX.
exported_only() {
    "$2" -g --defined-only "$1" |
        awk -v re="$3" 'NF == 3 && $3 !~ re { print "exported: " $3; bad = 1 } END { exit bad }'
}
try 12 "runtime: includes and forbidden names" rt_src_rules $rt_sources "$root/runtime/mechrt.h"
while IFS='|' read -r tc cc arch nm_ objdump_ reals extra; do
    for real in $reals; do
        d=$tmp/runtime-$real-$tc
        mkdir -p "$d"
        def=""
        exported='^mechrt_'
        if [ "$real" = float ]; then def=-DMECHRT_REAL_FLOAT; exported='^mechrtf_'; fi
        built=1
        for src in $rt_sources; do
            if ! $cc $FLAGS $arch $def -I"$root/runtime" -c "$src" \
                    -o "$d/$(basename "$src" .c).o" > "$tmp/why" 2>&1; then
                report "runtime ($real, $tc): $cc $FLAGS $arch $def $(basename "$src")" 10
                built=0
            fi
        done
        # the build counts once: passed, or failed (a failed -r link silently)
        if [ $built = 0 ] || ! $cc $arch -r -nostdlib "$d"/*.o -o "$d/core.o" > "$tmp/why" 2>&1; then
            fail=$((fail + 1))
            continue
        fi
        ok
        allowed="^($MEM${extra:+|$extra})\$"
        object_rules "$d/core.o" "$nm_" "$objdump_" "$allowed" "" 1
        for rule in undefined_only no_writable_data call_graph; do
            try 10 "runtime ($real, $tc): $rule" kept "$d/core.o" $rule
        done
        try 10 "runtime ($real, $tc): exported names" exported_only "$d/core.o" "$nm_" "$exported"
    done
done <<EOF
$toolchains
EOF

if [ $host = 0 ]; then
    suite_end
    exit
fi

# ---- two mechanisms and the runtime in one program ---------------------------
# run_P.c steps mechanism P from t = 0 to t_end through the runtime, with
# static memory as firmware would, and returns one coordinate. Three units:
# slider_crank as sc and four_bar as fb in double, four_bar as fbf in float;
# the runtime is the host's core.o of each real, checked above (built
# -fno-pie, hence linked -no-pie).
link=$tmp/link
mkdir -p "$link"
LINKFLAGS="-std=c99 -O2 -Wall -Wextra -Wpedantic -Wdouble-promotion -Werror -I$link -I$root/runtime"
units="sc:SC:double:slider_crank:slider.x fb:FB:double:four_bar:rocker.phi fbf:FBF:float:four_bar:rocker.phi"
make_unit() {
    p=$1 P=$2 real=$3 mech=$4 coord=$5
    def=""
    [ "$real" = float ] && def="#define MECHRT_REAL_FLOAT"
    "$mechc" gen "$root/examples/$mech.mech" --prefix "$p" --real "$real" \
        -o "$link/$p.c" --header "$link/$p.h" || return 1
    cat > "$link/run_$p.c" <<EOF
$def
#include "$p.h"
#include "mechrt.h"
double run_$p(double t_end, int steps);
MECHRT_DEFINE_KERNELS($p, $P);
static mechrt_real ws[MECHRT_WORKSPACE_LEN(${P}_NQ, ${P}_NR)];
static int same(const char *a, const char *b)
{
    while (*a && *a == *b)
        a++, b++;
    return *a == *b;
}
double run_$p(double t_end, int steps)
{
    mechrt_real q[${P}_NQ], qd[${P}_NQ], qdd[${P}_NQ], t = 0;
    int i, c = -1;
    for (i = 0; i < ${P}_NQ; i++) {
        q[i] = ${p}_q0[i];
        qd[i] = qdd[i] = 0;
        if (same(${p}_coord_names[i], "$coord"))
            c = i;
    }
    for (i = 0; i <= steps; i++) {
        mechrt_real tn = (mechrt_real)t_end * (mechrt_real)i / (mechrt_real)steps;
        if (mechrt_step(&${p}_kernels, NULL, q, qd, qdd, t, tn - t, ws,
                        sizeof ws / sizeof ws[0], NULL) != MECHRT_OK)
            return -1000;
        t = tn;
    }
    return c < 0 ? -2000 : (double)q[c];
}
EOF
    $CC $LINKFLAGS -c "$link/run_$p.c" -o "$link/run_$p.o" &&
    $CC $LINKFLAGS -c "$link/$p.c" -o "$link/$p.o"
}
build_units() {
    for u in $units; do
        make_unit $(echo "$u" | tr ':' ' ') || return 1
    done
    cp "$tmp/runtime-double-host/core.o" "$link/rt_core.o" &&
    cp "$tmp/runtime-float-host/core.o" "$link/rtf_core.o"
}
try 12 "link: generate and compile sc, fb (double), fbf (float); both runtime builds" build_units
# link_run NAME EXPECTED UNITS...: main calls run_UNIT(0.25, 25) for each
# unit, links them with both runtime builds and compares with EXPECTED, a
# list of VALUE:TOLERANCE.
link_run() {
    name=$1 expected=$2
    shift 2
    {
        echo '#include <stdio.h>'
        for u in "$@"; do echo "double run_$u(double t_end, int steps);"; done
        echo 'int main(void)'
        echo '{'
        for u in "$@"; do printf '    printf("%%.12f\\n", run_%s(0.25, 25));\n' "$u"; done
        echo '    return 0;'
        echo '}'
    } > "$link/$name.c"
    objs=""
    for u in "$@"; do objs="$objs $link/run_$u.o $link/$u.o"; done
    $CC $LINKFLAGS -no-pie "$link/$name.c" $objs "$link"/rt_*.o "$link"/rtf_*.o -lm -o "$link/$name" &&
    "$link/$name" > "$link/$name.out" &&
    echo "got: $(tr '\n' ' ' < "$link/$name.out"), expected: $expected" &&
    echo "$expected" | tr ' :' '\n ' | paste -d ' ' - "$link/$name.out" |
        awk '{ d = $1 - $3; if (d < 0) d = -d; if (d > $2) bad = 1; n++ }
             END { exit bad || n == 0 }'
}
try 12 "link: slider_crank (sc) + four_bar (fb) + runtime in one program: slider.x(0.25) = sqrt(0.08), rocker.phi(0.25) = 1.725386" \
    link_run two "0.282842712475:1e-9 1.725386:1e-6" sc fb
try 12 "link: sc and fb in double, fbf in float, mechrt_* and mechrtf_* in one program" \
    link_run mixed "0.282842712475:1e-9 1.725386:1e-6 1.725386:1e-4" sc fb fbf

# ---- forward dynamics through the runtime (dynamics.c) ----------------------
# pendulum_distance (a particle on a circle of radius 2) as pd in double and
# pdf in float, with hand-written mass (unit) and force (gravity -9.81 along
# y), since generated kernels have no masses yet: at rest at its initial
# (1.732, 1) the particle accelerates by gravity's tangential part,
# qdd = g - (g.n) n = (4.247917, -7.357392), n = (1.732, 1) / |(1.732, 1)|.
make_dyn_unit() {
    p=$1 P=$2 real=$3
    def=""
    [ "$real" = float ] && def="#define MECHRT_REAL_FLOAT"
    "$mechc" gen "$root/examples/pendulum_distance.mech" --prefix "$p" --real "$real" \
        -o "$link/$p.c" --header "$link/$p.h" || return 1
    cat > "$link/dyn_$p.c" <<EOF
$def
#include "$p.h"
#include "mechrt.h"
double dyn_$p(int i);
MECHRT_DEFINE_KERNELS($p, $P);
static void ${p}_mass(void *ctx, const mechrt_real *q, mechrt_real *M)
{
    (void)ctx, (void)q;
    M[0] = 1, M[1] = 0, M[2] = 0, M[3] = 1;
}
static void ${p}_force(void *ctx, const mechrt_real *q, const mechrt_real *qd, mechrt_real t,
                       mechrt_real *Q)
{
    (void)ctx, (void)q, (void)qd, (void)t;
    Q[0] = 0, Q[1] = (mechrt_real)-9.81;
}
static mechrt_real dws[MECHRT_DYN_WORKSPACE_LEN(${P}_NQ, ${P}_NR)];
double dyn_$p(int i)
{
    MechrtKernels k = ${p}_kernels;
    mechrt_real q[${P}_NQ], qd[${P}_NQ], qdd[${P}_NQ], lam[${P}_NR];
    int j;
    k.mass = ${p}_mass;
    k.force = ${p}_force;
    for (j = 0; j < ${P}_NQ; j++)
        q[j] = ${p}_q0[j], qd[j] = 0;
    if (mechrt_forward_dynamics(&k, NULL, q, qd, 0, qdd, lam, dws, sizeof dws / sizeof dws[0],
                                NULL) != MECHRT_OK)
        return -1000;
    return (double)qdd[i];
}
EOF
    $CC $LINKFLAGS -c "$link/dyn_$p.c" -o "$link/dyn_$p.o" &&
    $CC $LINKFLAGS -c "$link/$p.c" -o "$link/$p.o"
}
dyn_run() {
    make_dyn_unit pd PD double && make_dyn_unit pdf PDF float || return 1
    {
        echo '#include <stdio.h>'
        echo 'double dyn_pd(int i);'
        echo 'double dyn_pdf(int i);'
        echo 'int main(void)'
        echo '{'
        printf '%s\n' '    printf("%.9f %.9f %.9f %.9f", dyn_pd(0), dyn_pd(1), dyn_pdf(0), dyn_pdf(1));'
        echo '    return 0;'
        echo '}'
    } > "$link/dyn.c"
    $CC $LINKFLAGS -no-pie "$link/dyn.c" "$link/dyn_pd.o" "$link/pd.o" "$link/dyn_pdf.o" "$link/pdf.o" \
        "$link"/rt_*.o "$link"/rtf_*.o -lm -o "$link/dyn" &&
    "$link/dyn" | tr ' ' '\n' > "$link/dyn.out" &&
    echo "got: $(cat "$link/dyn.out")" &&
    echo "4.247916908:1e-8 -7.357392085:1e-8 4.247916908:1e-4 -7.357392085:1e-4" |
        tr ' :' '\n ' | paste -d ' ' - "$link/dyn.out" |
        awk '{ d = $1 - $3; if (d < 0) d = -d; if (d > $2) bad = 1; n++ }
             END { exit bad || n != 4 }'
}
try 12 "link: forward dynamics (mechrt_forward_dynamics) of pendulum_distance, double and float, both runtime builds" \
    dyn_run

suite_end
