#!/usr/bin/env python3
"""bench/sympy_ops.py - the yardstick: SymPy's cse on the same rows, op counts beside mechc's.

usage: python3 bench/sympy_ops.py build/mechc FILE.mech

Reads the rows with `mechc gen --dump rows` and derives Phi_q, nu and gamma
with SymPy from the spec's formulas (bench/sympy_rows.py), runs sympy.cse
on each function's outputs and counts operations (sympy.count_ops) over the
replacements and the reduced expressions. Prints them beside `mechc gen --stats`. Optional: it needs
SymPy and only measures; nothing in mechc depends on it.
"""
import re
import subprocess
import sys

try:
    import sympy as sp
    import sympy_rows
except ImportError:
    print("sympy_ops: SymPy is not installed; skipped")
    sys.exit(0)


def main():
    mechc, path = sys.argv[1], sys.argv[2]
    stats = subprocess.run([mechc, "gen", path, "--stats", "-o", "/dev/null"], check=True,
                           capture_output=True, text=True).stderr
    d = sympy_rows.Derived(*sympy_rows.read_rows(mechc, path))
    phi, jac, nu, gamma = d.phi, d.jac_values(), d.nu, d.gamma

    def cost(exprs):
        repl, reduced = sp.cse(exprs)
        return sum(sp.count_ops(v) for _, v in repl) + sum(sp.count_ops(e) for e in reduced)

    counts = {"phi": cost(phi), "jac": cost(jac), "nu": cost(nu), "gamma": cost(gamma),
              "all": cost(phi + jac + nu + gamma)}
    ours = dict(re.findall(r"(\w+) (\d+)", stats.split("sharing:")[1].splitlines()[0]))
    print("%-8s %8s %8s" % ("function", "mechc", "sympy"))
    for k in ("phi", "jac", "nu", "gamma", "all"):
        print("%-8s %8s %8d" % (k, ours.get(k, "?"), counts[k]))
    # the yardstick: the Jacobian's nonzeros and gamma together
    if "jac" in ours and "gamma" in ours:
        mine = int(ours["jac"]) + int(ours["gamma"])
        theirs = counts["jac"] + counts["gamma"]
        print("%-8s %8d %8d   %.2fx SymPy's" % ("jac+gam", mine, theirs, mine / max(theirs, 1)))


main()
