#!/usr/bin/env python3
"""bench/sympy_ops.py - the yardstick: SymPy's cse on the same rows, op counts beside mechc's.

usage: python3 bench/sympy_ops.py build/mechc FILE.mech

Reads the rows with `mechc gen --dump rows`, derives Phi_q, nu and gamma with
SymPy from the spec's formulas, runs sympy.cse on each function's outputs and
counts operations (sympy.count_ops) over the replacements and the reduced
expressions. Prints them beside `mechc gen --stats`. Optional: it needs
SymPy and only measures; nothing in mechc depends on it.
"""
import re
import subprocess
import sys

try:
    import sympy as sp
except ImportError:
    print("sympy_ops: SymPy is not installed; skipped")
    sys.exit(0)


def main():
    mechc, path = sys.argv[1], sys.argv[2]
    dump = subprocess.run([mechc, "gen", path, "--dump", "rows"], check=True,
                          capture_output=True, text=True).stdout
    stats = subprocess.run([mechc, "gen", path, "--stats", "-o", "/dev/null"], check=True,
                           capture_output=True, text=True).stderr
    rows = []
    nq = 0
    for line in dump.splitlines():
        name, level, expr = line.split(" ", 2)
        for m in re.finditer(r"q\[(\d+)\]", expr):
            nq = max(nq, int(m.group(1)) + 1)
        rows.append((name, level, expr))
    q = sp.symbols("q0:%d" % nq)
    qd = sp.symbols("qd0:%d" % nq)
    t = sp.Symbol("t")
    env = {"q%d" % i: q[i] for i in range(nq)}
    env.update({"qd%d" % i: qd[i] for i in range(nq)})
    env["t"] = t

    def parse(text):
        text = re.sub(r"qd\[(\d+)\]", r"qd\1", text)
        text = re.sub(r"q\[(\d+)\]", r"q\1", text).replace("^", "**")
        return sp.sympify(text, locals=env)

    phi, jac, nu, gamma = [], [], [], []
    for name, level, text in rows:
        e = parse(text)
        if level == "position":
            phi.append(e)
            row = [sp.diff(e, qi) for qi in q]
            jv = sum(row[j] * qd[j] for j in range(nq))
            g = -(sum(sp.diff(jv, q[j]) * qd[j] for j in range(nq))
                  + 2 * sum(sp.diff(sp.diff(e, t), q[j]) * qd[j] for j in range(nq))
                  + sp.diff(e, t, 2))
            nu.append(-sp.diff(e, t))
        else:
            row = [sp.diff(e, v) for v in qd]
            nu.append(-e.subs({v: 0 for v in qd}))
            g = -(sum(sp.diff(e, q[j]) * qd[j] for j in range(nq)) + sp.diff(e, t))
        jac.extend(x for x in row if x != 0)
        gamma.append(g)

    def cost(exprs):
        repl, reduced = sp.cse(exprs)
        return sum(sp.count_ops(v) for _, v in repl) + sum(sp.count_ops(e) for e in reduced)

    counts = {"phi": cost(phi), "jac": cost(jac), "nu": cost(nu), "gamma": cost(gamma),
              "all": cost(phi + jac + nu + gamma)}
    ours = dict(re.findall(r"(\w+) (\d+)", stats.split("sharing:")[1].splitlines()[0]))
    print("%-8s %8s %8s" % ("function", "mechc", "sympy"))
    for k in ("phi", "jac", "nu", "gamma", "all"):
        print("%-8s %8s %8d" % (k, ours.get(k, "?"), counts[k]))
    # issue 17's yardstick: the Jacobian's nonzeros and gamma together
    if "jac" in ours and "gamma" in ours:
        mine = int(ours["jac"]) + int(ours["gamma"])
        theirs = counts["jac"] + counts["gamma"]
        print("%-8s %8d %8d   %.2fx SymPy's" % ("jac+gam", mine, theirs, mine / max(theirs, 1)))


main()
