"""_result.py - Trajectory: the states of a run or a simulation as named NumPy columns."""

import numpy as np

from ._ffi import ffi, lib

_F64 = np.float64


class Trajectory(dict):
    """The states of Model.run or Model.sim.

    A dict of named columns, in the order of the CSV `mechc run --csv`
    writes: "t", every coordinate ("crank.phi"), every output
    ("D_pin.x"), then "d(NAME)" velocities and "dd(NAME)" accelerations of
    each of those, then "lambda(ROW)" when there are multipliers (sim,
    run with forces=True). Each column is a 1-D array of the states,
    a view into the arrays below (no copy):

      t     (states,)        times
      q     (states, nq)     coordinates; qd, qdd their rates
      y     (states, nout)   outputs; yd, ydd their rates
      lam   (states, nr) or None   multipliers (Phi_q^T lambda, signed as sim's)

    ``traj["rocker.phi"]`` or ``traj.q[:, m.coords.index("rocker.phi")]``;
    ``numpy.column_stack(list(traj.values()))`` is the CSV's table.
    """

    t = q = qd = qdd = y = yd = ydd = lam = sens = None

    def __repr__(self):
        return "<mechc.Trajectory: %d states, %d columns>" % (len(self.t), len(self))


def _copy(ptr, shape):
    """A NumPy copy of a library array (the result is freed after)."""
    n = int(np.prod(shape))
    if ptr == ffi.NULL or n == 0:
        return np.zeros(shape, _F64)
    return np.frombuffer(ffi.buffer(ptr, 8 * n), _F64).reshape(shape).copy()


def trajectory_from_result(model, r):
    """A Trajectory from a mechc_result (which the caller frees)."""
    n = lib.mechc_result_states(r)
    tr = Trajectory()
    tr.t = _copy(lib.mechc_result_time(r), (n,))
    tr.q = _copy(lib.mechc_result_q(r), (n, model.nq))
    tr.qd = _copy(lib.mechc_result_qd(r), (n, model.nq))
    tr.qdd = _copy(lib.mechc_result_qdd(r), (n, model.nq))
    tr.y = _copy(lib.mechc_result_y(r), (n, model.nout))
    tr.yd = _copy(lib.mechc_result_yd(r), (n, model.nout))
    tr.ydd = _copy(lib.mechc_result_ydd(r), (n, model.nout))
    lam = lib.mechc_result_lambda(r)
    tr.lam = None if lam == ffi.NULL else _copy(lam, (n, model.nr))
    tr["t"] = tr.t
    for prefix, qa, ya in (("", tr.q, tr.y), ("d(", tr.qd, tr.yd), ("dd(", tr.qdd, tr.ydd)):
        close = ")" if prefix else ""
        for j, name in enumerate(model.coords):
            tr[prefix + name + close] = qa[:, j]
        for j, name in enumerate(model.outputs):
            tr[prefix + name + close] = ya[:, j]
    if tr.lam is not None:
        for j, name in enumerate(model.rows):
            tr["lambda(" + name + ")"] = tr.lam[:, j]
    return tr


def add_sensitivities(tr, model):
    """The columns of run --sens, state by state (the library has one state per call)."""
    per_state = [model.sensitivities(tr.q[i], tr.qd[i], tr.qdd[i], tr.t[i])
                 for i in range(len(tr.t))]
    tr.sens = type(per_state[0])(*(np.array(a) for a in zip(*per_state))) if per_state else None
    if tr.sens is None:
        return
    params = list(model.design)
    for wrap, qa, ya in ((("d(", ")"), tr.sens.q_p, tr.sens.y_p),
                         (("d(d(", "))"), tr.sens.qd_p, tr.sens.yd_p),
                         (("d(dd(", "))"), tr.sens.qdd_p, tr.sens.ydd_p)):
        for names, a in ((model.coords, qa), (model.outputs, ya)):
            for i, name in enumerate(names):
                for j, p in enumerate(params):
                    tr[wrap[0] + name + wrap[1] + "/d(" + p + ")"] = a[:, i, j]
