#!/bin/sh
# tests/lib_install.sh MECHC - libmechc from the outside: `make install`
# into a temporary DESTDIR and PREFIX puts the header, libmechc.a,
# libmechc.so and mechc.pc in place (and `make uninstall` takes them
# away), and examples/embed/design_loop.c, built with
# `pkg-config --cflags --libs mechc` against the installed .so, runs and
# prints the four-bar's rocker swings.
#
#   sh tests/lib_install.sh build/mechc
#
# Installs what BUILD (MECHC's folder) holds without rebuilding it (make
# -o), so it can run beside the other suites. Skipped, and says so,
# without pkg-config or a C compiler. The last line is
# "lib_install: N passed, M failed".
set -u
# shellcheck source=tests/lib.sh
. "$(dirname "$0")/lib.sh"
build=$(dirname "${1:-build/mechc}")
suite_begin lib_install "${1:-build/mechc}"
cd "$root" || exit 2

# the installed files, relative to the prefix
files="bin/mechc include/mechc/mechc.h include/mechc/mechrt.h lib/libmechc.a lib/libmechc.so
       lib/pkgconfig/mechc.pc share/mechc/runtime/mechrt.h"

# make VARIABLES... TARGET, quietly, never rebuilding what BUILD has
install_make() {
    env -u MAKEFLAGS -u MAKELEVEL make -s --no-print-directory BUILD="$build" \
        -o "$build/mechc" -o "$build/libmechc.a" -o "$build/libmechc.so" "$@" \
        > "$tmp/make.log" 2>&1
}

all_present() { for f in $files; do [ -f "$1/$f" ] || return 1; done; }
none_present() { for f in $files; do [ ! -e "$1/$f" ] || return 1; done; }

if ! have make || [ ! -f "$build/libmechc.so" ]; then
    skip "no make or no $build/libmechc.so: nothing to install"
    suite_end
    exit
fi

# ---- DESTDIR: the files under it, the prefix in mechc.pc without it ----
dest=$tmp/dest
check "make install DESTDIR=... succeeds" install_make DESTDIR="$dest" PREFIX=/opt/mechc install
check "make install puts every file in place" all_present "$dest/opt/mechc"
check "mechc.pc names the prefix, not DESTDIR" \
    grep -q '^prefix=/opt/mechc$' "$dest/opt/mechc/lib/pkgconfig/mechc.pc"
check "mechc.pc has Libs.private for libmechc.a" \
    grep -q '^Libs.private: .*-ltcc' "$dest/opt/mechc/lib/pkgconfig/mechc.pc"
check "make uninstall succeeds" install_make DESTDIR="$dest" PREFIX=/opt/mechc uninstall
check "make uninstall removes what install added" none_present "$dest/opt/mechc"

# ---- PREFIX: a program built with pkg-config against the installed .so ----
if ! have pkg-config; then
    skip "pkg-config is missing: the example is not built against mechc.pc"
    suite_end
    exit
fi
cc=${CC:-cc}
prefix=$tmp/prefix
check "make install PREFIX=... succeeds" install_make PREFIX="$prefix" install
export PKG_CONFIG_PATH="$prefix/lib/pkgconfig"
check "pkg-config knows mechc" pkg-config --exists mechc
check "pkg-config --modversion mechc is the version" \
    test "$(pkg-config --modversion mechc)" = "$("$mechc" --version | awk '{print $NF}')"
# a sanitizer build's library needs its runtime in the program too: gcc's
# ASan build (check-asan) names it; clang's UBSan build (check-ubsan)
# leaves it to the program, built here by cc: the plain build checks that
san=
if grep -q __asan_init "$build/libmechc.so"; then
    san="-fsanitize=address,undefined"
elif grep -q __ubsan_handle "$build/libmechc.so"; then
    skip "$build/libmechc.so is clang's UBSan build: design_loop is built against the plain build's"
    suite_end
    exit
fi
# shellcheck disable=SC2046 # pkg-config's words
if $cc -std=c11 -Wall -Werror $san examples/embed/design_loop.c \
        $(pkg-config --cflags --libs mechc) -o "$tmp/design_loop" 2> "$tmp/err"; then
    ok
    LD_LIBRARY_PATH=$prefix/lib "$tmp/design_loop" examples/four_bar.mech > "$tmp/out" 2> "$tmp/err"
    rc=$?
    check "design_loop exits 0" status_is 0
    check "design_loop prints the file's swing (51.46 deg at b = 3)" \
        out_has "b = 3.0  rocker swing 51.46 deg"
    check "design_loop's recompiled lengths move the swing" out_has "b = 2.6  rocker swing 49.00 deg"
    check "design_loop's design parameter gives the same swing" \
        out_has "design b = 3.4  rocker swing 55.15 deg"
    check "design_loop times the recompiles" out_has "mean load + recompile: "
    check "design_loop prints nothing on stderr" err_empty
else
    bad "examples/embed/design_loop.c builds with pkg-config --cflags --libs mechc"
fi
suite_end
