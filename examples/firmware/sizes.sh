#!/bin/sh
# sizes.sh MECHC [OUT] - the memory a firmware build spends on mechc's code:
# for every examples/*.mech, the generated kernels compiled for a Cortex-M4F
# (`--real float`, -mfpu=fpv4-sp-d16 -mfloat-abi=hard) and a Cortex-M3
# (`--real double`, software floating point), at -O2 and -Os, as
# arm-none-eabi-size reports them (text includes read-only data: the initial
# values, the name tables, the sparsity pattern); then the runtime core
# (runtime/lu.c, newton.c, analysis.c) built the same way; then the two
# images of this folder's Makefile, whole (newlib's printf and semihosting
# included). Prints Markdown tables (pasted into this folder's README.md). The workspace
# column is the static array a program reserves for mechrt_step:
# MECHRT_WORKSPACE_LEN(NQ, NR) reals, in bytes.
#
#   sh examples/firmware/sizes.sh build/mechc
#
# Needs arm-none-eabi-gcc and newlib (sh .ci/deps firmware). POSIX sh.
# Flag and file lists are split into words on purpose.
# shellcheck disable=SC2086,SC2046
set -eu

mechc=${1:?usage: sh sizes.sh MECHC [OUT]}
case $mechc in
    /*) ;;
    *) mechc=$(pwd)/$mechc ;;
esac
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../.." && pwd)
out=${2:-$root/build/firmware}
tmp=$(mktemp -d "${TMPDIR:-/tmp}/mechc_sizes.XXXXXX")
trap 'rm -rf "$tmp"' EXIT

gcc=arm-none-eabi-gcc
M4F="-mcpu=cortex-m4 -mthumb -mfpu=fpv4-sp-d16 -mfloat-abi=hard"
M3="-mcpu=cortex-m3 -mthumb -mfloat-abi=soft"
FLAGS="-std=c99 -ffreestanding -Wall -Wextra -Wpedantic -Wconversion -Wdouble-promotion -Wvla -Werror"

# size_of OBJ...: "text data bss" summed over the objects.
size_of() {
    arm-none-eabi-size -t "$@" | awk 'END { print $1, $2, $3 }'
}

# build ARCH DEF OPT OBJDIR SRC...: compiles each SRC, prints "text data bss".
build() {
    arch=$1 def=$2 opt=$3 dir=$4
    shift 4
    mkdir -p "$dir"
    for src in "$@"; do
        $gcc $arch $FLAGS $def $opt -I"$(dirname "$src")" -I"$root/runtime" \
            -c "$src" -o "$dir/$(basename "$src" .c).o"
    done
    size_of "$dir"/*.o
}

# row NAME NQ NR M4F-SOURCES... -- M3-SOURCES...: one table row.
row() {
    name=$1 nq=$2 nr=$3
    shift 3
    m4f="" m3=""
    while [ "$1" != -- ]; do m4f="$m4f $1"; shift; done
    shift
    m3="$*"
    set -- $(build "$M4F" -DMECHRT_REAL_FLOAT -O2 "$tmp/$name/m4f-O2" $m4f) \
           $(build "$M4F" -DMECHRT_REAL_FLOAT -Os "$tmp/$name/m4f-Os" $m4f) \
           $(build "$M3" "" -O2 "$tmp/$name/m3-O2" $m3) \
           $(build "$M3" "" -Os "$tmp/$name/m3-Os" $m3)
    if [ "$nq" = - ]; then ws4=- ws8=- nqnr="| - | -"; else
        len=$((nr * nq + 3 * nr + 5 * nq))
        ws4=$((4 * len)) ws8=$((8 * len)) nqnr="| $nq | $nr"
    fi
    echo "| $name $nqnr | $1 | $4 | $2 / $3 | $ws4 | $7 | ${10} | $8 / $9 | $ws8 |"
}

echo "Generated kernels (\`mechc gen\`, all functions of spec section 4) and the runtime core,"
echo "in bytes (arm-none-eabi-gcc $($gcc -dumpversion)):"
echo
echo "| mechanism | NQ | NR | M4F float text -O2 | text -Os | data / bss | workspace | M3 double text -O2 | text -Os | data / bss | workspace |"
echo "|---|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|"
for mech in "$root"/examples/*.mech; do
    name=$(basename "$mech" .mech)
    mkdir -p "$tmp/src/$name-float" "$tmp/src/$name-double"
    "$mechc" gen "$mech" --prefix k --real float -o "$tmp/src/$name-float/k.c" \
        --header "$tmp/src/$name-float/k.h"
    "$mechc" gen "$mech" --prefix k --real double -o "$tmp/src/$name-double/k.c" \
        --header "$tmp/src/$name-double/k.h"
    nq=$(awk '$2 == "K_NQ" { print $3 }' "$tmp/src/$name-double/k.h")
    nh=$(awk '$2 == "K_NH" { print $3 }' "$tmp/src/$name-double/k.h")
    nv=$(awk '$2 == "K_NV" { print $3 }' "$tmp/src/$name-double/k.h")
    row "$name" "$nq" $((nh + nv)) "$tmp/src/$name-float/k.c" -- "$tmp/src/$name-double/k.c"
done
rt=$(ls "$root"/runtime/*.c)
row "runtime core" - - $rt -- $rt

echo
echo "The firmware example's images (\`make -C examples/firmware\`, -O2, --gc-sections):"
echo
make --no-print-directory -s -C "$here" MECHC="$mechc" OUT="$out" target > /dev/null
echo "| image | board | text | data | bss |"
echo "|---|---|--:|--:|--:|"
set -- $(size_of "$out/m4f.elf")
echo "| m4f.elf (float) | mps2-an386, Cortex-M4F | $1 | $2 | $3 |"
set -- $(size_of "$out/m3.elf")
echo "| m3.elf (double) | mps2-an385, Cortex-M3 | $1 | $2 | $3 |"

# Where the bytes come from, from the linker maps: the Makefile compiles
# main.c startup.c sc.c and then runtime/*.c in that order, so the first
# objects loaded are those; the rest come from the libraries.
# Sizes are those of the input sections kept by --gc-sections (the runtime
# loses the functions the example does not call), before the linker merges
# duplicate strings: their sum exceeds the image's text by a few hundred
# bytes.
breakdown() {
    awk -v nrt="$(ls "$root"/runtime/*.c | wc -l)" '
    function hex(s,    i, c, n) {
        n = 0; s = tolower(substr(s, 3))
        for (i = 1; i <= length(s); i++) n = 16 * n + index("0123456789abcdef", substr(s, i, 1)) - 1
        return n
    }
    function group(f) {
        if (f in obj) return obj[f]
        if (f ~ /libm\.a/) return "libm"
        if (f ~ /libgcc\.a/) return "libgcc"
        if (f ~ /lib(c|rdimon)\.a/) return "newlib"
        return "other"
    }
    # counts what lands in the image: input sections of the loaded output
    # sections (not the debugging sections newlib carries)
    function add(size, f,    k) {
        if (out !~ /^\.(text|ARM\.extab|ARM\.exidx|init_array|data|bss)$/) return
        k = out == ".bss" ? "bss" : out == ".data" ? "data" : "text"
        sum[group(f), k] += size
    }
    BEGIN {
        split("example example kernels", role, " ")
        for (i = 1; i <= nrt; i++) role[3 + i] = "runtime"
    }
    /^Linker script and memory map/ { on = 1; next }
    on && /^LOAD / && $2 !~ /\.a$/ && nload < 3 + nrt { obj[$2] = role[++nload] }
    on && /^\./ { out = $1 }
    on && /^ [.A-Z]/ && $1 != "*fill*" {
        if (NF == 1) { getline; if (NF >= 3 && $1 ~ /^0x/) add(hex($2), $3); next }
        if (NF >= 4 && $2 ~ /^0x/ && $3 ~ /^0x/) add(hex($3), $4)
    }
    END {
        n = split("kernels runtime example libm newlib libgcc", g, " ")
        line = ""
        for (i = 1; i <= n; i++) line = line sprintf(" %d / %d / %d |", sum[g[i], "text"], sum[g[i], "data"], sum[g[i], "bss"])
        print line
    }' "$1"
}
echo
echo "The images by origin, text / data / bss (input sections kept by the linker, from its maps;"
echo "the example is main.c and startup.c):"
echo
echo "| image | kernels (sc.c) | runtime core | example | libm | newlib libc + rdimon | libgcc |"
echo "|---|--:|--:|--:|--:|--:|--:|"
echo "| m4f.elf |$(breakdown "$out/m4f.elf.map")"
echo "| m3.elf |$(breakdown "$out/m3.elf.map")"
