"""test_mechc.py - the Python module (python/mechc) against the mechc command and itself.

Run by tests/python.sh (make check) as
    MECHC=build/mechc PYTHONPATH=python /usr/bin/python3 -m pytest -q tests/python
The command prints every number with the fewest digits that read back
exactly, so its JSON and CSV give the very doubles it computed: the module,
calling the same library, must agree to the last bit where it computes the
same thing the same way (same engine).
"""

import csv
import io
import json
import os
import pydoc
import re
import subprocess
import threading

import numpy as np
import pytest

import mechc
import mechc._ffi as _ffi

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
EX = os.path.join(ROOT, "examples")
MECHC = os.path.abspath(os.environ.get("MECHC", os.path.join(ROOT, "build", "mechc")))


def ex(name):
    return os.path.join(EX, name)


def cli(*args, ok=True):
    """Runs the mechc command; its stdout (and the exit status unless ok)."""
    p = subprocess.run([MECHC] + [str(a) for a in args], capture_output=True, text=True)
    if ok:
        assert p.returncode == 0, p.stderr
        return p.stdout
    return p.returncode, p.stdout, p.stderr


def vec(a):
    """A vector as the command's comma-separated option, every bit kept."""
    return ",".join(repr(float(x)) for x in a)


def read_csv(text):
    rows = list(csv.reader(io.StringIO(text)))
    return rows[0], np.array([[float(x) for x in r] for r in rows[1:]])


@pytest.fixture(scope="module")
def four_bar():
    m = mechc.load(ex("four_bar.mech"), engine="jit")
    yield m
    m.close()


@pytest.fixture(scope="module")
def pendulum():
    m = mechc.load(ex("pendulum_dynamics.mech"))
    yield m
    m.close()


def a_state(m, seed=1):
    rng = np.random.default_rng(seed)
    return m.q0 + 0.1 * rng.standard_normal(m.nq), rng.standard_normal(m.nq)


# ---- the library's declarations -------------------------------------------

def header_declarations(text):
    """The header's declarations as cffi parses them (no preprocessor here)."""
    import cffi
    text = re.sub(r"/\*.*?\*/", " ", text, flags=re.S)
    text = re.sub(r"#ifdef __cplusplus.*?#endif", " ", text, flags=re.S)
    text = re.sub(r"^\s*#[^\n]*", " ", text, flags=re.M)
    f = cffi.FFI()
    f.cdef(text)
    return f._parser._declarations


def c_name(tp):
    s = tp._get_c_name()
    if getattr(tp, "fldtypes", None):
        s += str([(n, t._get_c_name()) for n, t in zip(tp.fldnames, tp.fldtypes)])
    return s


def test_cdef_matches_header():
    """Every function and struct the module declares is the header's, type for type."""
    header = os.path.join(ROOT, "generator", "lib", "mechc.h")
    theirs = header_declarations(open(header).read())
    ours = _ffi.ffi._parser._declarations
    checked = 0
    for key, (tp, _) in ours.items():
        if key.startswith(("function ", "struct ", "typedef ")):
            assert key in theirs, key + " is not in mechc.h"
            assert c_name(tp) == c_name(theirs[key][0]), key
            checked += 1
    assert checked > 80


# ---- names, sizes, values against `mechc eval --json` ---------------------------

def test_names_and_sizes(four_bar):
    m = four_bar
    j = json.loads(cli("eval", ex("four_bar.mech"), "--json"))
    assert list(m.coords) == j["coords"]
    assert list(m.rows) == [r["name"] for r in j["rows"]]
    assert (m.nq, m.nh, m.nv, m.nr, m.nout, m.np) == (9, 9, 0, 9, 0, 0)
    assert m.name == "four_bar" and m.engine == "jit" and not m.has_dynamics
    assert m.bodies == {"crank": slice(0, 3), "coupler": slice(3, 6), "rocker": slice(6, 9)}
    assert np.array_equal(m.q0, j["q"])
    assert np.array_equal(m.qd0, np.zeros(9))
    assert len(m.design) == 0


@pytest.mark.parametrize("engine", ["jit", "generic", "aot"])
@pytest.mark.parametrize("example", ["four_bar.mech", "pendulum_dynamics.mech",
                                     "slider_crank_spatial.mech", "knife_cart.mech"])
def test_values_equal_eval_json(example, engine):
    """phi, jac, nu, gamma (and M, Q) equal what `mechc eval --json` prints, bit for bit."""
    m = mechc.load(ex(example), engine=engine)
    q, qd = a_state(m)
    t = 0.3
    j = json.loads(cli("eval", ex(example), "--json", "--engine", engine, "--q", vec(q),
                       "--qd", vec(qd), "--t", repr(t)))
    assert np.array_equal(m.phi(q, t), np.array(j["phi"], float).reshape(m.nh))
    assert np.array_equal(m.jacobian(q, t), np.array(j["jac"], float).reshape(m.nr, m.nq))
    assert np.array_equal(m.nu(q, t), np.array(j["nu"], float).reshape(m.nr))
    assert np.array_equal(m.gamma(q, qd, t), np.array(j["gamma"], float).reshape(m.nr))
    if m.has_dynamics:
        assert np.array_equal(m.mass(q), np.array(j["M"]))
        assert np.array_equal(m.force(q, qd, t), np.array(j["Q"]))
        d = m.eom(q, qd, t)
        assert np.array_equal(d.M, np.array(j["M"])) and np.array_equal(d.Q, np.array(j["Q"]))
    else:
        with pytest.raises(mechc.NotAvailableError):
            m.mass(q)
    k = m.all(q, qd, t)
    assert np.array_equal(k.jac, m.jacobian(q, t)) and np.array_equal(k.gamma, m.gamma(q, qd, t))
    m.close()


def test_jacobian_is_the_derivative_of_phi(four_bar):
    """Phi_q against central differences of Phi, holonomic rows."""
    m = four_bar
    q, _ = a_state(m, 2)
    jac = m.jacobian(q, 0.2)
    h = 1e-6
    for i in range(m.nq):
        e = np.zeros(m.nq)
        e[i] = h
        fd = (m.phi(q + e, 0.2) - m.phi(q - e, 0.2)) / (2 * h)
        assert np.allclose(jac[:m.nh, i], fd, atol=1e-8, rtol=0), m.coords[i]


def test_sparse_jacobian_triplets(four_bar):
    m = four_bar
    q, _ = a_state(m, 3)
    vals, rows, cols = m.jacobian(q, 0.1, sparse=True)
    assert rows.dtype == np.intc and not rows.flags.writeable
    dense = np.zeros((m.nr, m.nq))
    np.add.at(dense, (rows, cols), vals)
    assert np.array_equal(dense, m.jacobian(q, 0.1))
    Q = np.stack([q, q + 0.01, q - 0.02])
    bvals, brows, _ = m.jacobian(Q, [0.1, 0.2, 0.3], sparse=True)
    assert brows is rows and bvals.shape == (3, len(rows))
    for i, t in enumerate([0.1, 0.2, 0.3]):
        assert np.array_equal(bvals[i], m.jacobian(Q[i], t, sparse=True)[0])


# ---- batches: one C call, the single calls' bits ----------------------------------

@pytest.mark.parametrize("example", ["four_bar.mech", "pendulum_dynamics.mech",
                                     "slider_crank_spatial.mech"])
def test_batch_equals_single_calls(example):
    m = mechc.load(ex(example))
    rng = np.random.default_rng(7)
    n = 17
    Q = m.q0 + 0.1 * rng.standard_normal((n, m.nq))
    QD = rng.standard_normal((n, m.nq))
    T = rng.uniform(0, 1, n)
    for t in (0.25, T):
        ti = (lambda i: 0.25) if np.ndim(t) == 0 else (lambda i: T[i])
        for name, batch, single in (
                ("phi", m.phi(Q, t), lambda i: m.phi(Q[i], ti(i))),
                ("jac", m.jacobian(Q, t), lambda i: m.jacobian(Q[i], ti(i))),
                ("nu", m.nu(Q, t), lambda i: m.nu(Q[i], ti(i))),
                ("gamma", m.gamma(Q, QD, t), lambda i: m.gamma(Q[i], QD[i], ti(i)))):
            for i in range(n):
                assert np.array_equal(batch[i], single(i)), (name, i)
        k = m.all(Q, QD, t)
        for i in range(n):
            one = m.all(Q[i], QD[i], ti(i))
            for a, b in zip(k, one):
                assert np.array_equal(a[i], b)
        if m.has_dynamics:
            M = m.mass(Q)
            F = m.force(Q, QD, t)
            for i in range(n):
                assert np.array_equal(M[i], m.mass(Q[i]))
                assert np.array_equal(F[i], m.force(Q[i], QD[i], ti(i)))
    m.close()


def test_out_arrays_and_conversions(four_bar):
    m = four_bar
    Q = np.tile(m.q0, (5, 1))
    out = np.empty((5, m.nr))
    assert m.gamma(Q, Q, 0.5, out=out) is out
    assert np.array_equal(out, m.gamma(Q, Q, 0.5))
    with pytest.raises(ValueError):
        m.gamma(Q, Q, out=np.empty((5, m.nr), np.float32))
    with pytest.raises(ValueError):
        m.gamma(Q, Q, out=np.empty((m.nr, 5)).T)
    with pytest.raises(ValueError):
        m.phi(np.zeros(m.nq + 1))
    with pytest.raises(ValueError):
        m.gamma(Q, Q[:4])
    with pytest.raises(ValueError):
        m.phi(Q, t=np.zeros(4))
    # lists, float32 and strided views are converted, with the same values
    F = np.asfortranarray(Q)
    assert np.array_equal(m.phi(F), m.phi(Q))
    assert np.array_equal(m.phi(list(m.q0)), m.phi(m.q0))
    assert m.phi(np.empty((0, m.nq))).shape == (0, m.nh)


# ---- analyses ---------------------------------------------------------------------

@pytest.mark.parametrize("example,steps", [("four_bar.mech", 36), ("slider_crank.mech", 24),
                                           ("coupler_synthesis.mech", 20),
                                           ("knife_cart.mech", 10)])
def test_run_equals_cli_csv(example, steps, tmp_path):
    m = mechc.load(ex(example))
    traj = m.run(steps=steps)
    cli("run", ex(example), "--steps", steps, "--csv", tmp_path / "r.csv")
    header, table = read_csv((tmp_path / "r.csv").read_text())
    assert list(traj.keys()) == header
    for j, name in enumerate(header):
        assert np.array_equal(traj[name], table[:, j]), name
    assert traj.q.shape == (steps + 1, m.nq) and traj.lam is None
    m.close()


def test_run_forces_lambda_columns(tmp_path):
    m = mechc.load(ex("slider_crank_torque.mech"))
    traj = m.run(steps=6, forces=True)
    cli("run", ex("slider_crank_torque.mech"), "--steps", 6, "--forces", "--csv",
        tmp_path / "f.csv")
    header, table = read_csv((tmp_path / "f.csv").read_text())
    for j, name in enumerate(header):
        if name in traj:
            assert np.array_equal(traj[name], table[:, j]), name
    assert traj.lam.shape == (7, m.nr)
    m.close()


def test_sim_equals_cli(pendulum, tmp_path):
    traj = pendulum.sim(t1=0.5, steps=10)
    cli("sim", ex("pendulum_dynamics.mech"), "--t1", 0.5, "--steps", 10, "--csv",
        tmp_path / "s.csv")
    header, table = read_csv((tmp_path / "s.csv").read_text())
    for j, name in enumerate(header):
        assert np.array_equal(traj[name], table[:, j]), name
    j = json.loads(cli("sim", ex("pendulum_dynamics.mech"), "--t1", 0.5, "--steps", 10, "--json"))
    assert np.array_equal(traj.lam, np.array(j["lambda"]))
    # the period of small swings is 1.6383 s: released at rest, phi'' < 0 at first
    assert traj["dd(rod.phi)"][0] < 0 and traj["rod.phi"][-1] < traj["rod.phi"][0]


def test_sim_needs_masses(four_bar):
    with pytest.raises(mechc.MechcError):
        four_bar.sim(t1=0.1)


def test_info_equals_cli_json(four_bar):
    assert four_bar.info() == json.loads(cli("info", ex("four_bar.mech"), "--json"))


def test_design_parameters(tmp_path):
    m = mechc.load(ex("coupler_synthesis.mech"))
    assert list(m.design) == ["xa", "ya", "xd", "yd", "a", "b", "c", "px", "py"]
    assert m.design["a"] == 1.1
    q = m.q0
    before = m.phi(q)
    m.design["a"] = 1.25
    m.design = {"b": 3.5}
    j = json.loads(cli("eval", ex("coupler_synthesis.mech"), "--json", "--design",
                       "a=1.25,b=3.5"))
    assert np.array_equal(m.phi(q), np.array(j["phi"]))
    assert not np.array_equal(m.phi(q), before)
    assert m.phi_p(q).shape == (m.nh, m.np)
    with pytest.raises(KeyError):
        m.design["nope"] = 1
    m.design.reset()
    assert np.array_equal(m.phi(q), before)
    m.close()


def test_outputs():
    """Outputs at the run's states: the run's own, bit for bit; n states in one call."""
    m = mechc.load(ex("rssr.mech"))
    traj = m.run(steps=12)
    y, yd, ydd = m.output_values(traj.q, traj.qd, traj.qdd, traj.t)
    assert m.nout > 0 and y.shape == (13, m.nout)
    assert np.array_equal(y, traj.y) and np.array_equal(yd, traj.yd)
    assert np.array_equal(ydd, traj.ydd)
    for i in range(13):
        assert np.array_equal(m.output_values(traj.q[i], t=traj.t[i]), y[i])
    m.close()
    m = mechc.load(ex("textbook_four_bar.mech"))
    assert m.outputs == ("D_pin.x", "D_pin.y") and m.output_values(m.q0).shape == (2,)
    m.close()


# ---- errors ---------------------------------------------------------------------

BROKEN = "mechanism broken\nbody a x = 0 y = 0 phi = 0\nrevolute O: ground(0, 0) b(0, 0)\n"


def test_error_has_file_line_column(tmp_path):
    path = tmp_path / "broken.mech"
    path.write_text(BROKEN)
    rc, _, err = cli("check", path, ok=False)
    place = re.match(r"[^:]*broken\.mech:(\d+):(\d+): error: (.*)", err)
    assert rc == 2 and place, err
    with pytest.raises(mechc.InputError) as e:
        mechc.loads(BROKEN, name="broken.mech")
    assert isinstance(e.value, ValueError) and isinstance(e.value, mechc.MechcError)
    assert (e.value.line, e.value.column) == (int(place.group(1)), int(place.group(2)))
    assert e.value.file == "broken.mech" and e.value.message == place.group(3)
    assert str(e.value) == "broken.mech:%s:%s: %s" % place.groups()
    with pytest.raises(mechc.MechcError) as e:
        mechc.load(path)
    assert e.value.file == str(path) and e.value.line == int(place.group(1))


def test_missing_file_and_bad_engine():
    with pytest.raises(mechc.MechcError):
        mechc.load(ex("no_such_file.mech"))
    with pytest.raises(ValueError):
        mechc.load(ex("four_bar.mech"), engine="fast")


def test_help_explains_itself():
    text = pydoc.render_doc(mechc)
    for word in ("load", "loads", "jacobian", "gamma", "batch", "MechcError", "Trajectory",
                 "GIL"):
        assert word in text, word
    for name in dir(mechc.Model):
        if not name.startswith("_"):
            assert getattr(mechc.Model, name).__doc__, name


def test_threads_share_nothing():
    """Two Models in two threads give the single-threaded values (the GIL is released)."""
    ms = [mechc.load(ex("four_bar.mech")) for _ in range(2)]
    Q = np.tile(ms[0].q0, (20000, 1))
    want = ms[0].gamma(Q, Q, 0.1)
    got = [None, None]

    def work(i):
        got[i] = ms[i].gamma(Q, Q, 0.1)
    threads = [threading.Thread(target=work, args=(i,)) for i in range(2)]
    for th in threads:
        th.start()
    for th in threads:
        th.join()
    assert all(np.array_equal(g, want) for g in got)
    for m in ms:
        m.close()


def test_sim_initial_velocities(pendulum, tmp_path):
    qd0 = np.array([0.0, 0.0, 1.5])
    traj = pendulum.sim(t1=0.2, steps=4, qd0=qd0)
    cli("sim", ex("pendulum_dynamics.mech"), "--t1", 0.2, "--steps", 4, "--qd", vec(qd0),
        "--csv", tmp_path / "s.csv")
    header, table = read_csv((tmp_path / "s.csv").read_text())
    for j, name in enumerate(header):
        assert np.array_equal(traj[name], table[:, j]), name
    assert traj["d(rod.phi)"][0] == 1.5


def test_installed_package_finds_installed_library(tmp_path):
    """make install-python: the package, with the installed library's path written in."""
    import shutil
    import sys
    prefix = tmp_path / "prefix"
    quiet = {k: v for k, v in os.environ.items() if k not in ("MAKEFLAGS", "MFLAGS", "MAKELEVEL")}
    p = subprocess.run(["make", "-s", "-C", ROOT, "install-python", "PREFIX=%s" % prefix,
                        "PYTHON=%s" % sys.executable], capture_output=True, text=True, env=quiet)
    assert p.returncode == 0, p.stderr
    (prefix / "lib").mkdir(exist_ok=True)
    shutil.copy(mechc.library_path, prefix / "lib" / "libmechc.so")
    site = next((prefix / "lib").glob("python3*/dist-packages"))
    env = {k: v for k, v in os.environ.items() if k not in ("MECHC_LIBRARY", "PYTHONPATH")}
    env["PYTHONPATH"] = str(site)
    code = ("import mechc; m = mechc.load(%r); print(mechc.library_path, m.nq, mechc.__file__)"
            % ex("four_bar.mech"))
    p = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env,
                       cwd=str(tmp_path))
    assert p.returncode == 0, p.stderr
    lib, nq, where = p.stdout.split()
    assert lib == str(prefix / "lib" / "libmechc.so") and nq == "9"
    assert where.startswith(str(site))


def test_failed_run_keeps_its_states():
    """A run that fails part-way: AnalysisError with the command's message and the states before."""
    rc, _, err = cli("run", ex("textbook_four_bar.mech"), "--steps", 2, "--csv", os.devnull,
                     ok=False)
    line = next(x for x in err.splitlines() if ": error: " in x)
    m = mechc.load(ex("textbook_four_bar.mech"))
    with pytest.raises(mechc.AnalysisError) as e:
        m.run(steps=2)
    assert rc == 1 and isinstance(e.value, RuntimeError)
    assert str(e.value) == line.replace(": error: ", ": ", 1)
    assert len(e.value.result.t) == 1 and e.value.t_fail == 0.0078125
    m.close()


def test_run_sensitivities_equal_cli(tmp_path):
    m = mechc.load(ex("coupler_synthesis.mech"))
    traj = m.run(steps=8, sens=True)
    cli("run", ex("coupler_synthesis.mech"), "--steps", 8, "--sens", "--csv", tmp_path / "s.csv")
    header, table = read_csv((tmp_path / "s.csv").read_text())
    assert list(traj.keys()) == header
    for j, name in enumerate(header):
        assert np.array_equal(traj[name], table[:, j]), name
    assert traj.sens.q_p.shape == (9, m.nq, m.np)
    with pytest.raises(mechc.NotAvailableError):
        fb = mechc.load(ex("four_bar.mech"))
        fb.sensitivities(fb.q0, fb.qd0, fb.qd0)
    m.close()


def test_all_leaves_parts_out(four_bar):
    m = four_bar
    q, qd = a_state(m, 4)
    k = m.all(q, qd, 0.3, out=(None, False, None, False))
    assert k.jac is None and k.gamma is None
    assert np.array_equal(k.phi, m.phi(q, 0.3)) and np.array_equal(k.nu, m.nu(q, 0.3))
    Q = np.stack([q, q])
    k = m.all(Q, Q, 0.3, out=(False, False, False, None))
    assert k.phi is None and np.array_equal(k.gamma, m.gamma(Q, Q, 0.3))


def test_closed_model_raises():
    # the outside corpus: a kernel called after close() passed
    # NULL kernels to the library, which crashed (SIGSEGV)
    m = mechc.loads("body b x = 1 y = 0 phi = 0\ndistance d: ground b length = 1\n")
    m.close()
    with pytest.raises(mechc.InputError):
        m.phi(np.zeros(3))
    with pytest.raises(mechc.InputError):
        m.gamma(np.zeros((2, 3)), np.zeros((2, 3)))
