"""_model.py - Model: a loaded mechanism and its compiled kernels, called with NumPy arrays."""

import collections
import collections.abc
import json

import numpy as np

from ._ffi import ffi, lib, check, error_from, error_from_diag, InputError
from ._result import trajectory_from_result, add_sensitivities

_F64 = np.float64
_ENGINES = ("jit", "aot", "generic")
# states per C call when the sparse Jacobian of many states goes through the
# dense batch (the library has no batch of the nonzeros): 8 MB of dense
# Jacobians at most for a 32 x 32 one
_SPARSE_CHUNK = 1024

Kinematics = collections.namedtuple("Kinematics", "phi jac nu gamma")
Kinematics.__doc__ = """What Model.all returns: Phi (nh), Phi_q (nr x nq), nu (nr), gamma (nr)
(each with a leading n for n states)."""
Sensitivities = collections.namedtuple("Sensitivities", "q_p qd_p qdd_p y_p yd_p ydd_p")
Sensitivities.__doc__ = """What Model.sensitivities returns: d(q)/d(p), d(qd)/d(p), d(qdd)/d(p)
(nq x np each) and the outputs' d(y)/d(p), d(yd)/d(p), d(ydd)/d(p) (nout x np)."""
Dynamics = collections.namedtuple("Dynamics", "M Q jac gamma")
Dynamics.__doc__ = """What Model.eom returns: M (nq x nq), Q (nq), Phi_q (nr x nq), gamma (nr)."""


_DOUBLES = ffi.typeof("double[]")
_from_buffer = ffi.from_buffer
_contiguous = np.ascontiguousarray


def _buf(a):
    """A double * over a float64 C-contiguous array, without a copy."""
    return _from_buffer(_DOUBLES, a)


def _out(out, shape, name):
    """out when it fits (float64, C-contiguous, shape), a new array when None."""
    if out is None:
        return np.empty(shape, _F64)
    if not isinstance(out, np.ndarray) or out.dtype != _F64 or out.shape != shape:
        flags = None
    else:
        flags = out.flags
    if flags is None or not (flags.c_contiguous and flags.writeable):
        raise ValueError("mechc: %s: out must be a writable C-contiguous float64 array of "
                         "shape %s" % (name, shape))
    return out


class Design(collections.abc.MutableMapping):
    """A model's design parameters, name -> value, read and set in place.

    ``m.design["a"] = 1.2`` changes the parameter for every kernel already
    compiled (no recompiling), for run, sim and info; ``m.design = {...}``
    sets several; ``m.design.reset()`` goes back to the file's values.
    Only the parameters of ``design NAME = value`` statements are here
    (``param`` values are compiled in); deleting one is not possible.
    """

    def __init__(self, model):
        self._model = model
        n = lib.mechc_np(model._m)
        self._names = tuple(ffi.string(lib.mechc_design_name(model._m, i)).decode()
                            for i in range(n))

    def _vector(self):
        p = np.empty(len(self._names), _F64)
        if len(self._names):
            check(lib.mechc_design(self._model._m, _buf(p)))
        return p

    def __getitem__(self, name):
        try:
            i = self._names.index(name)
        except ValueError:
            raise KeyError(name) from None
        return float(self._vector()[i])

    def __setitem__(self, name, value):
        if name not in self._names:
            raise KeyError(name)
        check(lib.mechc_set_design(self._model._m, name.encode(), float(value)))

    def __delitem__(self, name):
        raise TypeError("mechc: a design parameter cannot be deleted (reset() restores the file's)")

    def __iter__(self):
        return iter(self._names)

    def __len__(self):
        return len(self._names)

    def __repr__(self):
        return "Design(%r)" % dict(zip(self._names, self._vector().tolist()))

    def array(self):
        """The values as an array, in the file's order (the keys' order)."""
        return self._vector()

    def reset(self):
        """Back to the file's values."""
        if self._names:
            check(lib.mechc_set_design_vector(self._model._m, ffi.NULL))


class Model:
    """A mechanism loaded and compiled: its names, sizes and kernels.

    Made by mechc.load(path) or mechc.loads(text). Every kernel takes one
    state, q of shape (nq,) (and qd), or n states at once, q of shape
    (n, nq), and then returns arrays with a leading n, computed in one call
    of the library's batch function; t is a number, or for n states also an
    array of n times. Arrays are float64: what already is float64 and
    C-contiguous is passed as it is, anything else is converted once.
    ``out=`` takes a preallocated result (float64, C-contiguous, the exact
    shape), which is filled and returned: nothing is allocated then.
    The GIL is released while the library computes.

    One Model serves one thread at a time (the library's rule: the generic
    engine keeps scratch memory in the handle); use one Model per thread.
    """

    def __init__(self, handle, engine="jit", file="<string>"):
        if engine not in _ENGINES:
            lib.mechc_model_free(handle)
            raise InputError("mechc: unknown engine %r (jit, aot, generic)" % (engine,),
                             status="argument")
        self._m = handle
        self._k = ffi.NULL
        self.file = file
        diag = ffi.new("mechc_diag *")
        k = lib.mechc_compile(handle, engine.encode(), diag)
        if k == ffi.NULL:
            lib.mechc_model_free(handle)
            self._m = ffi.NULL
            raise error_from_diag(diag)
        self._k = k
        m = handle
        self.nq = lib.mechc_nq(m)
        self._one = (self.nq,)
        self.nh = lib.mechc_nh(m)
        self.nv = lib.mechc_nv(m)
        self.nr = lib.mechc_nr(m)
        self.nout = lib.mechc_nout(m)
        self.np = lib.mechc_np(m)
        self.name = ffi.string(lib.mechc_model_name(m)).decode()
        self.engine = ffi.string(lib.mechc_kernels_engine(k)).decode()
        self.has_dynamics = bool(lib.mechc_has_dynamics(m))
        self.spatial = bool(lib.mechc_is_spatial(m))
        self.compile_seconds = lib.mechc_kernels_compile_seconds(k)
        self.coords = self._names(lib.mechc_coord_name, self.nq)
        self.rows = self._names(lib.mechc_row_name, self.nr)
        self.outputs = self._names(lib.mechc_output_name, self.nout)
        self.bodies = self._bodies()
        self._design = Design(self)
        self._pattern = None

    def _names(self, fn, n):
        return tuple(ffi.string(fn(self._m, i)).decode() for i in range(n))

    def _bodies(self):
        first = ffi.new("int *")
        count = ffi.new("int *")
        bodies = {}
        for i in range(lib.mechc_nbodies(self._m)):
            check(lib.mechc_body_coords(self._m, i, first, count))
            name = ffi.string(lib.mechc_body_name(self._m, i)).decode()
            bodies[name] = slice(first[0], first[0] + count[0])
        return bodies

    def close(self):
        """Frees the library's handles now (otherwise when the Model is collected)."""
        if self._k != ffi.NULL:
            lib.mechc_kernels_free(self._k)
            self._k = ffi.NULL
        if self._m != ffi.NULL:
            lib.mechc_model_free(self._m)
            self._m = ffi.NULL

    def __del__(self):
        if lib is not None and getattr(self, "_m", None) is not None:
            self.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def __repr__(self):
        return "<mechc.Model %s: %d coordinates, %d rows, engine %s>" % (
            self.name, self.nq, self.nr, self.engine)

    # ---- what the file gives -------------------------------------------

    @property
    def q0(self):
        """The file's initial coordinates, a new (nq,) array."""
        return np.frombuffer(ffi.buffer(lib.mechc_q0(self._m), 8 * self.nq), _F64).copy()

    @property
    def qd0(self):
        """The initial velocities sim starts from by default (zero), a new (nq,) array."""
        qd = np.empty(self.nq, _F64)
        check(lib.mechc_qd0(self._m, _buf(qd)))
        return qd

    @property
    def design(self):
        """The design parameters, a mutable mapping name -> value (Design)."""
        return self._design

    @design.setter
    def design(self, values):
        for name, value in dict(values).items():
            self._design[name] = value

    @property
    def source(self):
        """The generated C the kernels were compiled from (None for the generic engine)."""
        s = lib.mechc_kernels_source(self._k)
        return None if s == ffi.NULL else ffi.string(s).decode()

    def info(self):
        """The structure analysis of `mechc info --json` as a dict (rank, DOF, redundant rows)."""
        diag = ffi.new("mechc_diag *")
        s = lib.mechc_info_json(self._m, diag)
        if s == ffi.NULL:
            raise error_from_diag(diag)
        try:
            return json.loads(ffi.string(s).decode())
        finally:
            lib.mechc_free(s)

    # ---- arguments -------------------------------------------------------

    def _states(self, q, name="q"):
        """q as float64 C-contiguous, and n: None for one state, else the count."""
        a = _contiguous(q, dtype=_F64)
        shape = a.shape
        if len(shape) == 1:
            if shape[0] == self.nq:
                return a, None
        elif len(shape) == 2 and shape[1] == self.nq:
            return a, shape[0]
        raise ValueError("mechc: %s must have shape (%d,) or (n, %d), not %s"
                         % (name, self.nq, self.nq, a.shape))

    def _pair(self, q, qd):
        q, n = self._states(q)
        qd, nd = self._states(qd, "qd")
        if n != nd:
            raise ValueError("mechc: q and qd hold different numbers of states (%s, %s)"
                             % (q.shape, qd.shape))
        return q, qd, n

    @staticmethod
    def _times(t, n):
        """t for n states: a (1,) or (n,) float64 array."""
        a = np.ascontiguousarray(t, dtype=_F64).reshape(-1)
        if a.shape[0] not in (1, n):
            raise ValueError("mechc: t must be a number or hold one time per state (%d), not %d"
                             % (n, a.shape[0]))
        return a

    # ---- kinematic kernels --------------------------------------------------

    # One state takes the short path first: the fewest Python operations
    # between the caller and the library (doc/python.md has its cost).

    def phi(self, q, t=0.0, out=None):
        """Phi(q, t), the holonomic rows' residuals: (nh,), or (n, nh) for (n, nq) states."""
        q = _contiguous(q, dtype=_F64)
        if q.shape == self._one:
            out = _out(out, (self.nh,), "phi")
            status = lib.mechc_phi(self._k, _from_buffer(_DOUBLES, q), t,
                                   _from_buffer(_DOUBLES, out))
        else:
            q, n = self._states(q)
            t = self._times(t, n)
            out = _out(out, (n, self.nh), "phi")
            status = lib.mechc_phi_batch(self._k, n, _buf(q), _buf(t), t.shape[0], _buf(out))
        if status:
            check(status)
        return out

    def jacobian(self, q, t=0.0, sparse=False, out=None):
        """Phi_q of every row (velocity-level rows: their coefficients), at q and t.

        Dense: an (nr, nq) array, or (n, nr, nq) for n states. sparse=True:
        (vals, rows, cols) with nnz values (or (n, nnz) for n states) and the
        pattern's row and column indices, so that for one state
        ``scipy.sparse.coo_matrix((vals, (rows, cols)), shape=(nr, nq))`` is
        the Jacobian (mechc itself does not import SciPy). rows and cols are
        the same read-only arrays at every call (jacobian_pattern()).
        """
        q, n = self._states(q)
        if sparse:
            return self._jacobian_sparse(q, n, t, out)
        if n is None:
            out = _out(out, (self.nr, self.nq), "jacobian")
            status = lib.mechc_jacobian(self._k, _from_buffer(_DOUBLES, q), t,
                                        _from_buffer(_DOUBLES, out))
        else:
            t = self._times(t, n)
            out = _out(out, (n, self.nr, self.nq), "jacobian")
            status = lib.mechc_jacobian_batch(self._k, n, _buf(q), _buf(t), t.shape[0],
                                              _buf(out))
        if status:
            check(status)
        return out

    def jacobian_pattern(self):
        """The Jacobian's nonzeros: (rows, cols), two read-only int32 arrays of nnz."""
        if self._pattern is None:
            nnz = lib.mechc_jacobian_nz(self._k)
            rows = np.empty(nnz, np.intc)
            cols = np.empty(nnz, np.intc)
            check(lib.mechc_jacobian_pattern(self._k, ffi.from_buffer("int[]", rows),
                                              ffi.from_buffer("int[]", cols)))
            rows.flags.writeable = False
            cols.flags.writeable = False
            self._pattern = (rows, cols)
        return self._pattern

    def _jacobian_sparse(self, q, n, t, out):
        rows, cols = self.jacobian_pattern()
        nnz = rows.shape[0]
        if n is None:
            out = _out(out, (nnz,), "jacobian")
            check(lib.mechc_jacobian_values(self._k, _buf(q), t, _buf(out)))
            return out, rows, cols
        t = self._times(t, n)
        out = _out(out, (n, nnz), "jacobian")
        # the library has no batch of the nonzeros: dense batches, gathered
        for s in range(0, n, _SPARSE_CHUNK):
            e = min(n, s + _SPARSE_CHUNK)
            ts = t if t.shape[0] == 1 else t[s:e]
            dense = self.jacobian(q[s:e], ts)
            out[s:e] = dense[:, rows, cols]
        return out, rows, cols

    def nu(self, q, t=0.0, out=None):
        """nu(q, t), the right side of Phi_q qd = nu: (nr,), or (n, nr) for n states."""
        q = _contiguous(q, dtype=_F64)
        if q.shape == self._one:
            out = _out(out, (self.nr,), "nu")
            status = lib.mechc_nu(self._k, _from_buffer(_DOUBLES, q), t,
                                  _from_buffer(_DOUBLES, out))
        else:
            q, n = self._states(q)
            t = self._times(t, n)
            out = _out(out, (n, self.nr), "nu")
            status = lib.mechc_nu_batch(self._k, n, _buf(q), _buf(t), t.shape[0], _buf(out))
        if status:
            check(status)
        return out

    def gamma(self, q, qd, t=0.0, out=None):
        """gamma(q, qd, t), the right side of Phi_q qdd = gamma: (nr,), or (n, nr)."""
        q = _contiguous(q, dtype=_F64)
        qd = _contiguous(qd, dtype=_F64)
        if q.shape == self._one and qd.shape == self._one:
            out = _out(out, (self.nr,), "gamma")
            status = lib.mechc_gamma(self._k, _from_buffer(_DOUBLES, q),
                                     _from_buffer(_DOUBLES, qd), t, _from_buffer(_DOUBLES, out))
        else:
            q, qd, n = self._pair(q, qd)
            t = self._times(t, n)
            out = _out(out, (n, self.nr), "gamma")
            status = lib.mechc_gamma_batch(self._k, n, _buf(q), _buf(qd), _buf(t), t.shape[0],
                                           _buf(out))
        if status:
            check(status)
        return out

    def all(self, q, qd, t=0.0, out=None):
        """Phi, Phi_q, nu and gamma in one fused call: a Kinematics(phi, jac, nu, gamma).

        out, when given, is a sequence of four: an array to fill in place,
        None for one to allocate, or False for a part not to compute (it is
        None in the result: ``m.all(q, qd, out=(None, False, None, None))``
        leaves the Jacobian out, which a sparse-only model has not).
        """
        q, qd, n = self._pair(q, qd)
        lead = () if n is None else (n,)
        shapes = (lead + (self.nh,), lead + (self.nr, self.nq), lead + (self.nr,),
                  lead + (self.nr,))
        out = (None,) * 4 if out is None else tuple(out)
        if len(out) != 4:
            raise ValueError("mechc: all: out holds four arrays (phi, jac, nu, gamma)")
        parts = [None if o is False else _out(o, s, "all") for o, s in zip(out, shapes)]
        ptrs = [ffi.NULL if a is None else _buf(a) for a in parts]
        if n is None:
            check(lib.mechc_all(self._k, _buf(q), _buf(qd), t, *ptrs))
        else:
            t = self._times(t, n)
            check(lib.mechc_all_batch(self._k, n, _buf(q), _buf(qd), _buf(t), t.shape[0], *ptrs))
        return Kinematics(*parts)

    # ---- dynamics (files with masses) ----------------------------------------

    def mass(self, q, out=None):
        """M(q), the mass matrix: (nq, nq), or (n, nq, nq). NotAvailableError without masses."""
        q, n = self._states(q)
        if n is None:
            out = _out(out, (self.nq, self.nq), "mass")
            check(lib.mechc_mass(self._k, _buf(q), _buf(out)))
            return out
        out = _out(out, (n, self.nq, self.nq), "mass")
        check(lib.mechc_mass_batch(self._k, n, _buf(q), _buf(out)))
        return out

    def force(self, q, qd, t=0.0, out=None):
        """Q(q, qd, t) of M qdd + Phi_q^T lambda = Q, the forces: (nq,), or (n, nq) for n states."""
        q, qd, n = self._pair(q, qd)
        if n is None:
            out = _out(out, (self.nq,), "force")
            check(lib.mechc_force(self._k, _buf(q), _buf(qd), t, _buf(out)))
            return out
        t = self._times(t, n)
        out = _out(out, (n, self.nq), "force")
        check(lib.mechc_force_batch(self._k, n, _buf(q), _buf(qd), _buf(t), t.shape[0],
                                    _buf(out)))
        return out

    def eom(self, q, qd, t=0.0):
        """M, Q, Phi_q and gamma at one state in one call: a Dynamics(M, Q, jac, gamma)."""
        q, qd, n = self._pair(q, qd)
        if n is not None:
            raise ValueError("mechc: eom takes one state (the library has no batch of it); "
                             "mass() and force() take many")
        M = np.empty((self.nq, self.nq), _F64)
        Q = np.empty(self.nq, _F64)
        jac = np.empty((self.nr, self.nq), _F64)
        gamma = np.empty(self.nr, _F64)
        check(lib.mechc_eom(self._k, _buf(q), _buf(qd), t, _buf(M), _buf(Q), _buf(jac),
                            _buf(gamma)))
        return Dynamics(M, Q, jac, gamma)

    # ---- design sensitivities and outputs (one state) ----------------------------

    def phi_p(self, q, t=0.0):
        """dPhi/dp at the current design, (nh, np). NotAvailableError without design parameters."""
        q, n = self._states(q)
        if n is not None:
            raise ValueError("mechc: phi_p takes one state")
        out = np.empty((self.nh, self.np), _F64)
        check(lib.mechc_phi_p(self._k, _buf(q), t, _buf(out)))
        return out

    def sensitivities(self, q, qd, qdd, t=0.0):
        """The sensitivities of a state of the motion to the design parameters (run --sens).

        q, qd, qdd at t as a run gives them (traj.q[i], ...): a
        Sensitivities(q_p, qd_p, qdd_p, y_p, yd_p, ydd_p), [i, j] =
        d(variable i)/d(p_j), p in the order of m.design. NotAvailableError
        without design parameters, with velocity-level rows or when not
        driven; AnalysisError where Phi_q is singular.
        """
        arrays = []
        for a, name in ((q, "q"), (qd, "qd"), (qdd, "qdd")):
            a, n = self._states(a, name)
            if n is not None:
                raise ValueError("mechc: sensitivities take one state")
            arrays.append(a)
        res = Sensitivities(*(np.empty((rows, self.np), _F64)
                              for rows in (self.nq,) * 3 + (self.nout,) * 3))
        status = lib.mechc_sensitivities(self._k, *(_buf(a) for a in arrays), t,
                                         *(_buf(r) for r in res))
        if status:
            check(status)
        return res

    def output_values(self, q, qd=None, qdd=None, t=0.0):
        """The `output` statements' values: y, (nout,) or (n, nout) for n states.

        With qd (and qdd, zero when not given) (y, yd, ydd), the outputs'
        velocities and accelerations too. The names are m.outputs; n
        states are one call (mechc_outputs_batch).
        """
        q, n = self._states(q)
        y = np.empty(q.shape[:-1] + (self.nout,), _F64)
        rates = qd is not None
        if rates:
            qd, nd = self._states(qd, "qd")
            qdd, ndd = self._states(np.zeros(q.shape) if qdd is None else qdd, "qdd")
            if nd != n or ndd != n:
                raise ValueError("mechc: q, qd and qdd hold different numbers of states")
            yd = np.empty_like(y)
            ydd = np.empty_like(y)
            ptrs = (_buf(qd), _buf(qdd), _buf(yd), _buf(ydd))
        else:
            ptrs = (ffi.NULL,) * 4
        if n is None:
            status = lib.mechc_outputs(self._k, _buf(q), ptrs[0], ptrs[1], t, _buf(y), ptrs[2],
                                       ptrs[3])
        else:
            t = self._times(t, n)
            status = lib.mechc_outputs_batch(self._k, n, _buf(q), ptrs[0], ptrs[1], _buf(t),
                                             t.shape[0], _buf(y), ptrs[2], ptrs[3])
        if status:
            check(status)
        return (y, yd, ydd) if rates else y

    # ---- analyses ---------------------------------------------------------------------

    def run(self, steps=100, t0=0.0, t1=1.0, tol=None, max_iter=None, forces=False,
            sens=False):
        """Kinematic analysis (mechc run): assembles at t0, then steps+1 states to t1.

        Returns a Trajectory: a dict of named columns as `mechc run --csv`
        writes them ("t", the coordinates, the outputs, "d(NAME)",
        "dd(NAME)", with forces=True "lambda(ROW)", with sens=True the
        sensitivities "d(NAME)/d(P)", "d(d(NAME))/d(P)", "d(dd(NAME))/d(P)"
        as run --sens), each an (steps+1,) array, plus the arrays .t, .q,
        .qd, .qdd, .y, .yd, .ydd, .lam (and .sens, a Sensitivities of
        (steps+1, ...) arrays).
        A failure part-way raises AnalysisError, whose .result holds the
        states before it. tol and max_iter default to the command's.
        """
        o = ffi.new("mechc_run_options *", lib.mechc_run_defaults())
        o.t0, o.t1, o.steps, o.forces = t0, t1, int(steps), int(bool(forces))
        if tol is not None:
            o.tol = tol
        if max_iter is not None:
            o.max_iter = int(max_iter)
        diag = ffi.new("mechc_diag *")
        traj = self._result(lib.mechc_run(self._k, o, diag), diag)
        if sens:
            add_sensitivities(traj, self)
        return traj

    def sim(self, t1=1.0, steps=100, t0=0.0, qd0=None, method="rk8pd", rtol=None, atol=None):
        """Forward dynamics (mechc sim) of a file with masses, steps+1 states from t0 to t1.

        qd0: initial velocities (made consistent with the rows), default
        zero. method: "rk8pd", "rkf45", "rk4imp" or "msbdf"; rtol, atol
        default to the command's 5e-11. Returns a Trajectory as run does,
        with the multipliers in .lam and "lambda(ROW)" columns.
        """
        o = ffi.new("mechc_sim_options *", lib.mechc_sim_defaults())
        o.t0, o.t1, o.steps = t0, t1, int(steps)
        method_c = ffi.new("char[]", method.encode())
        o.method = method_c
        if rtol is not None:
            o.rtol = rtol
        if atol is not None:
            o.atol = atol
        if qd0 is not None:
            qd0_a, n = self._states(qd0, "qd0")
            if n is not None:
                raise ValueError("mechc: sim: qd0 is one state")
            o.qd0 = _buf(qd0_a)
        diag = ffi.new("mechc_diag *")
        return self._result(lib.mechc_sim(self._k, o, diag), diag)

    def _result(self, r, diag):
        if r == ffi.NULL:
            raise error_from_diag(diag)
        try:
            traj = trajectory_from_result(self, r)
            status = lib.mechc_result_status(r)
            if status:
                e = error_from(status, ffi.string(lib.mechc_result_message(r)).decode(),
                               self.file)
                e.result = traj
                e.t_fail = lib.mechc_result_t_fail(r)
                raise e
            return traj
        finally:
            lib.mechc_result_free(r)
