"""bench/python.py - the Python module's costs against the library's targets (doc/python.md).

    PYTHONPATH=python /usr/bin/python3 bench/python.py     (part of `make bench`)

CPU time (time.process_time; loading also counts the children the JIT
starts, os.times), the best of several repeats, each figure printed with
the command that measured it and the target:
1. gamma of the four-bar over 10^6 states from NumPy, one batch call
   into a preallocated out= array (target < 50 ms), and the fused all(),
   with each engine (jit: tcc's code; aot: gcc -O2's; generic: interpreted);
2. one Python call at one state, m.gamma(q, qd, t, out=g): its whole
   cost, the library's kernel included (target < 2 us), beside a bare
   cffi call of mechc_gamma with the pointers made once;
3. mechc.load + the compile of the four-bar (target < 5 ms): jit (in
   libmechc.so the tcc program, a child process), aot (a cached library:
   the first load warms the cache) and generic;
4. whether the GIL is released: a Python thread counts while the main
   thread is inside a batch call.
"""

import os
import sys
import threading
import time

import numpy as np

import mechc
from mechc._ffi import ffi, lib

FOUR_BAR = "examples/four_bar.mech"
CMD = "PYTHONPATH=python /usr/bin/python3 bench/python.py"


def cpu():
    """This process's CPU time and its waited-for children's, s."""
    t = os.times()
    return time.process_time() + t.children_user + t.children_system


def best(fn, repeat):
    """The smallest CPU time of repeat runs of fn(), s."""
    times = []
    for _ in range(repeat):
        t0 = cpu()
        fn()
        times.append(cpu() - t0)
    return min(times)


def show(what, value, unit, target=None):
    line = "  %-66s %9.3f %s" % (what, value, unit)
    print(line + (" %s(target %s)" % (" " * (3 - len(unit)), target) if target else ""))


def batch_figures(n):
    rng = np.random.default_rng(1)
    for engine in ("jit", "aot", "generic"):
        m = mechc.load(FOUR_BAR, engine=engine)
        Q = m.q0 + 0.1 * rng.standard_normal((n, m.nq))
        QD = rng.standard_normal((n, m.nq))
        g = np.empty((n, m.nr))
        s = best(lambda: m.gamma(Q, QD, 0.25, out=g), 5)
        show("gamma, 10^6 states, one call, %s: m.gamma(Q, QD, t, out=g)" % engine, 1e3 * s,
             "ms", "< 50 ms")
        outs = (np.empty((n, m.nh)), np.empty((n, m.nr, m.nq)), np.empty((n, m.nr)), g)
        s = best(lambda: m.all(Q, QD, 0.25, out=outs), 3)
        show("  all (phi, jac, nu, gamma), 10^6 states, one call, %s" % engine, 1e3 * s, "ms")
        m.close()
    return Q, QD


def single_figures(m):
    q = m.q0
    qd = np.ones(m.nq)
    g = np.empty(m.nr)
    calls = 200000

    def loop():
        f = m.gamma
        for _ in range(calls):
            f(q, qd, 0.25, out=g)
    show("one call at one state (m.gamma(q, qd, t, out=g))", 1e6 * best(loop, 5) / calls,
         "us", "< 2 us")
    pq, pqd, pg = (ffi.from_buffer("double[]", a) for a in (q, qd, g))
    k = m._k

    def bare():
        f = lib.mechc_gamma
        for _ in range(calls):
            f(k, pq, pqd, 0.25, pg)
    show("  the bare cffi call of mechc_gamma, pointers made once", 1e6 * best(bare, 5) / calls,
         "us")


def load_figures():
    for engine in ("jit", "aot", "generic"):
        def one():
            mechc.load(FOUR_BAR, engine=engine).close()
        one()
        show("mechc.load + compile, four-bar, %s (children's CPU too)" % engine,
             1e3 * best(one, 20), "ms", "< 5 ms")
        m = mechc.load(FOUR_BAR, engine=engine)
        show("  its compile_seconds (wall, the library's own figure)", 1e3 * m.compile_seconds,
             "ms")
        m.close()


def gil_figure(m, Q, QD):
    count = [0]
    stop = [False]

    def counter():
        while not stop[0]:
            count[0] += 1
    th = threading.Thread(target=counter)
    th.start()
    time.sleep(0.05)
    before = count[0]
    t0 = time.perf_counter()
    for _ in range(5):
        m.gamma(Q, QD, 0.25)
    wall = time.perf_counter() - t0
    during = count[0] - before
    stop[0] = True
    th.join()
    print("  a Python thread counted %d times during %.0f ms of batch calls: the GIL is %s"
          % (during, 1e3 * wall, "released" if during > 1000 else "NOT released (or no CPU free)"))


def main():
    os.chdir(os.path.join(os.path.dirname(os.path.abspath(__file__)), os.pardir))
    print("Python module (%s, NumPy %s, mechc %s): %s"
          % (sys.executable, np.__version__, mechc.version(), CMD))
    Q, QD = batch_figures(1000000)
    m = mechc.load(FOUR_BAR, engine="jit")
    single_figures(m)
    load_figures()
    gil_figure(m, Q, QD)
    m.close()


if __name__ == "__main__":
    main()
