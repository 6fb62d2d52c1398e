#!/usr/bin/env python3
"""bench/sympy_kernels.py - SymPy cse's C kernels of a mechanism, to time beside mechc's.

usage: python3 bench/sympy_kernels.py MECHC FILE.mech WRITTEN.c OUT.c

Derives Phi, Phi_q and gamma with SymPy (bench/sympy_rows.py), runs
sympy.cse on each function's outputs and writes them with sympy.ccode into
m_phi, m_jac_nz and m_gamma, with the signatures of mechc's kernels (double
reals), so that bench/sympy_time.c calls both alike; also m_trig, sin and
cos of every angle of the mechanism (the trig floor). jac_nz follows the
nonzero order of WRITTEN.c (a file of `mechc gen --prefix m`): an entry
SymPy finds zero is stored as 0.0; one mechc leaves out is an error.
Optional: without SymPy it prints "skipped" and writes nothing.
"""
import re
import sys

try:
    import sympy as sp
    import sympy_rows
except ImportError:
    print("sympy_kernels: SymPy is not installed; skipped")
    sys.exit(0)


def int_list(written, name):
    """The values of `const int NAME[...] = { ... };` in a written file."""
    m = re.search(r"const int %s\[\w+\] = \{([^}]*)\}" % name, written)
    if not m:
        sys.exit("sympy_kernels: no %s in the written file" % name)
    return [int(x) for x in m.group(1).replace(",", " ").split()]


def c_of(expr):
    """expr in C over q[i], qd[i] and t."""
    text = sp.ccode(expr)
    text = re.sub(r"\bqd(\d+)\b", r"qd[\1]", text)
    return re.sub(r"\bq(\d+)\b", r"q[\1]", text)


def function(signature, array, exprs):
    """One C function: cse's replacements as constants, then the outputs."""
    repl, reduced = sp.cse(exprs)
    lines = ["void %s\n{" % signature]
    lines += ["    const double %s = %s;" % (s, c_of(v)) for s, v in repl]
    lines += ["    %s[%d] = %s;" % (array, i, c_of(e)) for i, e in enumerate(reduced)]
    lines.append("}\n\n")
    return "\n".join(lines)


def trig_floor(d):
    """m_trig: sin and cos of every angle of the mechanism, stored; the time
    that no kernel computing them all can go below (gcc makes each pair one
    sincos call, as in both sides' kernels)."""
    angles = sorted({f.args[0] for e in d.phi for f in e.atoms(sp.sin, sp.cos)},
                    key=sp.default_sort_key)
    lines = ["/* the trig floor: sin and cos of each of the %d angles */" % len(angles),
             "void m_trig(const double *q, double t, double *out)\n{", "    (void)t;"]
    for i, a in enumerate(angles):     # the argument read once: stores could alias q
        lines.append("    const double a%d = %s;" % (i, c_of(a)))
        lines.append("    out[%d] = sin(a%d);" % (2 * i, i))
        lines.append("    out[%d] = cos(a%d);" % (2 * i + 1, i))
    return "\n".join(lines) + "\n}\n"


def main():
    mechc, path, written_path, out_path = sys.argv[1:5]
    with open(written_path) as f:
        written = f.read()
    d = sympy_rows.Derived(*sympy_rows.read_rows(mechc, path))
    rows, cols = int_list(written, "m_jac_row"), int_list(written, "m_jac_col")
    ours = set(zip(rows, cols))
    for r, row in enumerate(d.jac):
        for c in row:
            if (r, c) not in ours:
                sys.exit("sympy_kernels: SymPy's entry (%d, %d) is not among mechc's nonzeros"
                         % (r, c))
    vals = [d.jac[r].get(c, sp.Integer(0)) for r, c in zip(rows, cols)]
    with open(out_path, "w") as f:
        f.write("/* SymPy cse's kernels of %s (bench/sympy_kernels.py) */\n" % path)
        f.write("#include <math.h>\n\n")
        f.write(function("m_phi(const double *q, double t, double *phi)", "phi", d.phi))
        f.write(function("m_jac_nz(const double *q, double t, double *vals)", "vals", vals))
        f.write(function("m_gamma(const double *q, const double *qd, double t, double *gamma)",
                         "gamma", d.gamma))
        f.write(trig_floor(d))


main()
