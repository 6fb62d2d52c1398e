"""bench/sympy_rows.py - a mechanism's rows read from mechc and derived with SymPy (the yardstick's maths).

Shared by bench/sympy_ops.py (operation counts) and bench/sympy_kernels.py
(C kernels to time). read_rows runs `mechc gen FILE --dump rows`; derive
builds Phi, the Jacobian Phi_q (dq for position rows, dqd for velocity
rows), nu and gamma from the spec's formulas. Each row is differentiated
only by the coordinates it contains (the others give zero), so the N = 100
chain takes seconds, not minutes; the expressions are the same.
"""
import re
import subprocess

import sympy as sp


def read_rows(mechc, path):
    """[(name, level, text)] and the number of coordinates."""
    dump = subprocess.run([mechc, "gen", path, "--dump", "rows"], check=True,
                          capture_output=True, text=True).stdout
    rows, nq = [], 0
    for line in dump.splitlines():
        name, level, expr = line.split(" ", 2)
        for m in re.finditer(r"q\[(\d+)\]", expr):
            nq = max(nq, int(m.group(1)) + 1)
        rows.append((name, level, expr))
    return rows, nq


class Derived:
    """phi, nu, gamma: one expression per row; jac: per row, {column: entry} (nonzeros);
    q, qd, t: the symbols."""

    def __init__(self, rows, nq):
        q = self.q = sp.symbols("q0:%d" % nq)
        qd = self.qd = sp.symbols("qd0:%d" % nq)
        t = self.t = sp.Symbol("t")
        env = {"q%d" % i: q[i] for i in range(nq)}
        env.update({"qd%d" % i: qd[i] for i in range(nq)})
        env["t"] = t
        self.phi, self.jac, self.nu, self.gamma = [], [], [], []
        for _, level, text in rows:
            text = re.sub(r"qd\[(\d+)\]", r"qd\1", text)
            text = re.sub(r"q\[(\d+)\]", r"q\1", text).replace("^", "**")
            e = sp.sympify(text, locals=env)
            if level == "position":
                self._position(e)
            else:
                self._velocity(e)

    def _position(self, e):
        q, qd, t = self.q, self.qd, self.t
        js = sorted(j for j in range(len(q)) if q[j] in e.free_symbols)
        self.phi.append(e)
        row = {j: sp.diff(e, q[j]) for j in js}
        jv = sum(row[j] * qd[j] for j in js)
        et = sp.diff(e, t)
        g = -(sum(sp.diff(jv, q[j]) * qd[j] for j in js)
              + 2 * sum(sp.diff(et, q[j]) * qd[j] for j in js)
              + sp.diff(e, t, 2))
        self.nu.append(-et)
        self.jac.append({j: x for j, x in row.items() if x != 0})
        self.gamma.append(g)

    def _velocity(self, e):
        q, qd, t = self.q, self.qd, self.t
        fs = e.free_symbols
        row = {j: sp.diff(e, qd[j]) for j in range(len(qd)) if qd[j] in fs}
        self.nu.append(-e.subs({v: 0 for v in qd if v in fs}))
        g = -(sum(sp.diff(e, q[j]) * qd[j] for j in range(len(q)) if q[j] in fs)
              + sp.diff(e, t))
        self.jac.append({j: x for j, x in row.items() if x != 0})
        self.gamma.append(g)

    def jac_values(self):
        """The nonzeros row by row, columns ascending."""
        return [row[j] for row in self.jac for j in sorted(row)]
