#!/bin/sh
# tests/sparse_only_cli.sh MECHC - `mechc gen --sparse-only`: a chain past
# --max-jac-entries, which gen writes sparse-only by itself with a note
# naming the option, is written with it: PREFIX_SPARSE_ONLY 1, PREFIX_all_nz, no dense
# PREFIX_jac or PREFIX_all, C99 that gcc -Wall -Wextra -Werror compiles,
# and whose kernels compute the bytes of the ordinary file's (a small
# driver calls both); ordinary files have no mark. A file with masses keeps
# its dense M and the limit. A chain whose dense Jacobian passes INT_MAX
# entries (N = 7800, 46 803 coordinates) runs in process: the engines write
# it sparse-only.
#
#   sh tests/sparse_only_cli.sh build/mechc
set -u
# shellcheck source=tests/lib.sh
. "$(dirname "$0")/lib.sh"
suite_begin sparse_only_cli "${1:-build/mechc}"

gen() { run_mechc gen "$@"; }

sh "$ex/chain.sh" 50 "$tmp/chain50.mech"    # 303 rows x 303 coordinates = 91809 entries

# ---- past the limit a file is written sparse-only by itself, with a note ----
gen "$tmp/chain50.mech" --max-jac-entries 1000 --prefix e -o "$tmp/e.c" --header "$tmp/e.h"
check "chain 50, --max-jac-entries 1000: written, exit 0" status_is 0
check "... a note counting the whole Jacobian and naming the option" err_has \
    "the dense Jacobian would have 303 rows x 303 coordinates = 91809 entries, more than the limit of 1000 (--max-jac-entries): written --sparse-only"
check "... at no line of the file" sh -c "! grep -q 'chain50.mech:[0-9]' '$tmp/err'"
check "... its header defines E_SPARSE_ONLY 1" grep -q '^#define E_SPARSE_ONLY 1$' "$tmp/e.h"
gen "$tmp/chain50.mech" --max-jac-entries 1000 --sparse-only --prefix c -o "$tmp/c.c" --header "$tmp/c.h"
check "chain 50, --max-jac-entries 1000 --sparse-only: written" status_is 0
check "... its header defines C_SPARSE_ONLY 1" grep -q '^#define C_SPARSE_ONLY 1$' "$tmp/c.h"
check "... declares c_all_nz" grep -q 'void c_all_nz(' "$tmp/c.h"
check "... and no dense c_jac or c_all" sh -c "! grep -E 'c_(jac|all)\(' '$tmp/c.h' '$tmp/c.c'"
gen "$tmp/chain50.mech" --sparse --prefix d -o "$tmp/d.c" --header "$tmp/d.h"
check "the ordinary file has no mark" sh -c "! grep -q SPARSE_ONLY '$tmp/d.h' '$tmp/d.c'"
check "... and has d_jac and d_all" sh -c "grep -q 'void d_jac(' '$tmp/d.h' && grep -q 'void d_all(' '$tmp/d.h'"

# ---- compiled: the same bytes as the ordinary file's kernels ----------------
if have gcc; then
    cat > "$tmp/main.c" <<'EOF2'
/* c (sparse-only) against d (ordinary) at a few states: the same bytes. */
#include "c.h"
#include "d.h"
#include <stdio.h>
#include <string.h>

#if !C_SPARSE_ONLY || defined(D_SPARSE_ONLY)
#error "the mark: 1 in c, absent in d"
#endif

static int same(const char *what, const double *a, const double *b, int n)
{
    if (memcmp(a, b, (size_t)n * sizeof *a) == 0)
        return 1;
    printf("%s differs\n", what);
    return 0;
}

int main(void)
{
    static double q[C_NQ], qd[C_NQ], o[2][5][C_NH + C_NNZ + 2 * C_NR];
    int good = C_NQ == D_NQ && C_NR == D_NR && C_NNZ == D_NNZ;
    for (int s = 0; s < 4; s++) {
        for (int i = 0; i < C_NQ; i++) {
            q[i] = c_q0[i] + 0.01 * s * ((i * 37 + s) % 11 - 5);
            qd[i] = 0.1 * ((i * 13 + s) % 7 - 3);
        }
        double t = 0.3 * s;
        memset(o, 0x5a, sizeof o);
        c_phi(q, t, o[0][0]);
        c_jac_nz(q, t, o[0][1]);
        c_nu(q, t, o[0][2]);
        c_gamma(q, qd, t, o[0][3]);
        c_all_nz(q, qd, t, o[0][4], o[0][4] + C_NH, o[0][4] + C_NH + C_NNZ,
                 o[0][4] + C_NH + C_NNZ + C_NR);
        d_phi(q, t, o[1][0]);
        d_jac_nz(q, t, o[1][1]);
        d_nu(q, t, o[1][2]);
        d_gamma(q, qd, t, o[1][3]);
        d_all_nz(q, qd, t, o[1][4], o[1][4] + D_NH, o[1][4] + D_NH + D_NNZ,
                 o[1][4] + D_NH + D_NNZ + D_NR);
        good &= same("phi", o[0][0], o[1][0], C_NH) & same("jac_nz", o[0][1], o[1][1], C_NNZ)
                & same("nu", o[0][2], o[1][2], C_NR) & same("gamma", o[0][3], o[1][3], C_NR)
                & same("all_nz", o[0][4], o[1][4], C_NH + C_NNZ + 2 * C_NR);
        good &= o[0][1][7] != 0 && o[0][4][C_NH + 7] == o[0][1][7];   /* values, not fill */
    }
    printf("%s\n", good ? "same" : "different");
    return !good;
}
EOF2
    for opt in "-O2" "-O0"; do
        check "gcc -std=c99 $opt -Wall -Wextra -Werror: both files and the driver" \
            gcc -std=c99 $opt -Wall -Wextra -Werror -I"$tmp" "$tmp/main.c" "$tmp/c.c" "$tmp/d.c" \
            -lm -o "$tmp/main"
        check "... the sparse-only kernels give the ordinary file's bytes ($opt)" \
            sh -c "'$tmp/main' > '$tmp/main.out'"
    done
else
    skip "gcc missing: the compiled comparison"
fi

# ---- a file with masses: M stays dense, so the limit stays ------------------
gen "$ex/slider_crank_dynamics.mech" --sparse-only --max-jac-entries 10
check "masses, --sparse-only past the limit: refused, exit 2" status_is 2
check "... saying M and eom stay dense" err_has "_mass and _eom stay dense with --sparse-only"
gen "$ex/slider_crank_dynamics.mech" --sparse-only -o "$tmp/scd.c"
check "masses, --sparse-only within the limit: written" status_is 0
check "... with its _mass_nz" grep -q 'slider_crank_dynamics_mass_nz(' "$tmp/scd.c"

# ---- past INT_MAX entries: the engines write sparse-only ---------------------
sh "$ex/chain.sh" 7800 "$tmp/chain7800.mech"
run_mechc run "$tmp/chain7800.mech" --steps 2 --csv "$tmp/big.csv"
check "chain 7800 (46803 x 46803 > INT_MAX entries): run in process, exit 0" status_is 0
check "... 3 states written" test "$(wc -l < "$tmp/big.csv")" = 4
run_mechc gen "$tmp/chain7800.mech" --max-jac-entries 2147483647 -o "$tmp/c7800.c"
check "... gen past INT_MAX entries: written sparse-only, exit 0" status_is 0
check "... with the note" err_has "written --sparse-only"

suite_end
