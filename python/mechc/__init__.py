"""Mechanisms from .mech files, compiled to C kernels, called with NumPy arrays.

A thin layer over libmechc (the mechanism compiler as a C library, opened
with cffi in ABI mode: nothing to compile, no network). Load a mechanism,
compile its kernels (engine "jit": generated C compiled by tcc, "aot":
by the system compiler, cached; "generic": interpreted), then evaluate
them at one state or at many states in one call:

    import numpy as np, mechc
    m = mechc.load("examples/four_bar.mech", engine="jit")
    m.coords[:3], m.nq, m.nr          # ('crank.x', 'crank.y', 'crank.phi'), 9, 9
    q = m.q0                          # the file's initial values, (9,)
    m.phi(q, t=0.0)                   # Phi(q, t), (nh,)
    m.jacobian(q)                     # Phi_q, dense (nr, nq)
    vals, rows, cols = m.jacobian(q, sparse=True)   # scipy.sparse.coo_matrix-ready
    Q = np.tile(q, (1000000, 1))      # 10^6 states, (n, nq)
    G = m.gamma(Q, np.ones_like(Q), t=0.0)          # (10^6, nr) in one C call
    traj = m.run(steps=360)           # kinematic analysis: a dict of named columns
    traj["rocker.phi"].max(), traj.q.shape          # 2.4189, (361, 9)
    m.info()["dof"]                   # mechc info --json as a dict: 0

Kernels: phi, jacobian, nu, gamma, all (fused), and with masses in the
file mass, force, eom; phi_p and sensitivities with design parameters;
output_values.
Each takes q of shape (nq,) (and qd) or (n, nq) for n states, t a number
or (for n states) an array of n times, and out= a preallocated result.
The GIL is released during every library call (cffi does that for every
foreign call), so threads with one Model each compute in parallel.

Analyses: Model.run (mechc run), Model.sim (mechc sim, with masses),
Model.info (mechc info). They return a Trajectory, a dict whose keys are
the columns of `mechc run --csv` ("t", "crank.phi", "d(crank.phi)",
"dd(crank.phi)", ...), and a dict of info's JSON.

Names: m.coords, m.rows, m.outputs (tuples of str), m.bodies (dict name
-> slice of q), m.design (mapping name -> value of the file's `design`
parameters: set one and every kernel sees it without recompiling).

Errors: every failure raises MechcError, with .file, .line, .column,
.message and str(e) == "file:line:col: message"; InputError (also a
ValueError) for a wrong mechanism text or argument, NotAvailableError
(ValueError) for what the model lacks, AnalysisError (RuntimeError) for a
failed compile, run or simulation (.result: the states before it).

The library: $MECHC_LIBRARY, else the one `make install` recorded, else
build/libmechc.so of the source tree (PYTHONPATH=python after `make`),
else the system's; mechc.library_path says which was opened.
doc/python.md has the whole guide and the figures.
"""

from ._ffi import (ffi as _cffi, lib as _lib, library_path, MechcError, InputError,
                   NotAvailableError, AnalysisError, error_from_diag as _error_from_diag)
from ._model import Model, Design, Kinematics, Dynamics, Sensitivities
from ._result import Trajectory

__all__ = ["load", "loads", "version", "library_path", "Model", "Design", "Trajectory",
           "Kinematics", "Dynamics", "Sensitivities", "MechcError", "InputError",
           "NotAvailableError", "AnalysisError"]


def version():
    """The version of the mechc that libmechc was built from, e.g. "0.1.0"."""
    return _cffi.string(_lib.mechc_version()).decode()


def load(path, engine="jit"):
    """Loads a .mech file and compiles its kernels: a Model.

    engine: "jit" (default), "aot" or "generic". Raises InputError
    (a MechcError) with the file, line and column of a mistake in the file.
    """
    path = str(path)
    diag = _cffi.new("mechc_diag *")
    m = _lib.mechc_load_file(path.encode(), diag)
    if m == _cffi.NULL:
        raise _error_from_diag(diag)
    return Model(m, engine, path)


def loads(text, name=None, engine="jit"):
    """Loads a mechanism from its text (a str) and compiles it: a Model.

    name is what error messages call the file (default "<string>"); it
    also gives the mechanism's name when the text has no `mechanism`
    statement.
    """
    diag = _cffi.new("mechc_diag *")
    cname = _cffi.NULL if name is None else str(name).encode()
    m = _lib.mechc_load_string(text.encode(), cname, diag)
    if m == _cffi.NULL:
        raise _error_from_diag(diag)
    return Model(m, engine, "<string>" if name is None else str(name))
