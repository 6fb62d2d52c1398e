"""_ffi.py - libmechc's declarations for cffi (ABI mode), the library's loading, MechcError.

Nothing here is compiled: ``ffi.cdef`` declares the part of
generator/lib/mechc.h the module calls and ``ffi.dlopen`` opens
libmechc.so. The declarations must match the header; tests/python's
``test_cdef_matches_header`` compares them function by function.

cffi releases the GIL around every call into the library (ABI and API mode
alike), so other Python threads run while a kernel, a batch, a run or a
simulation computes.
"""

import ctypes.util
import os

import cffi

CDEF = """
typedef enum mechc_status {
    MECHC_OK = 0, MECHC_EINPUT = 1, MECHC_EARG = 2, MECHC_ENOTAVAIL = 3,
    MECHC_ECOMPILE = 4, MECHC_EANALYSIS = 5, MECHC_ENOTRUNNABLE = 6
} mechc_status;

typedef struct mechc_diag {
    mechc_status status;
    char file[256];
    int line, column;
    char message[1024];
} mechc_diag;

typedef struct mechc_model mechc_model;
typedef struct mechc_kernels mechc_kernels;
typedef struct mechc_result mechc_result;

const char *mechc_version(void);
const char *mechc_status_text(mechc_status status);
void mechc_free(void *p);

mechc_model *mechc_load_file(const char *path, mechc_diag *diag);
mechc_model *mechc_load_string(const char *text, const char *name, mechc_diag *diag);
void mechc_model_free(mechc_model *m);

typedef struct mechc_limits {
    int max_file_bytes;
    int max_line_length;
    int max_name_length;
    int max_depth;
    int max_expr_tokens;
    int max_coords;
    int max_rows;
    int max_jac_entries;
    int max_nodes;
    int max_code_ops;
    const char *jac_advice;
} mechc_limits;

mechc_limits mechc_default_limits(void);
mechc_model *mechc_load_file_with(const char *path, const mechc_limits *limits,
                                  mechc_diag *diag, char *source_line);

int mechc_nq(const mechc_model *m);
int mechc_nh(const mechc_model *m);
int mechc_nv(const mechc_model *m);
int mechc_nr(const mechc_model *m);
int mechc_nout(const mechc_model *m);
int mechc_nbodies(const mechc_model *m);
int mechc_np(const mechc_model *m);
int mechc_has_dynamics(const mechc_model *m);
int mechc_is_spatial(const mechc_model *m);
const char *mechc_model_name(const mechc_model *m);
const char *mechc_coord_name(const mechc_model *m, int i);
const char *mechc_row_name(const mechc_model *m, int i);
const char *mechc_output_name(const mechc_model *m, int i);
const char *mechc_body_name(const mechc_model *m, int i);
const char *mechc_design_name(const mechc_model *m, int i);
mechc_status mechc_body_coords(const mechc_model *m, int i, int *first, int *count);
const double *mechc_q0(const mechc_model *m);
mechc_status mechc_qd0(const mechc_model *m, double *qd0);

mechc_status mechc_design(const mechc_model *m, double *p);
mechc_status mechc_set_design(mechc_model *m, const char *name, double value);
mechc_status mechc_set_design_vector(mechc_model *m, const double *p);

mechc_kernels *mechc_compile(mechc_model *m, const char *engine, mechc_diag *diag);
void mechc_kernels_free(mechc_kernels *k);

typedef struct mechc_compile_options {
    int aot_fresh;
    int batch;
} mechc_compile_options;

mechc_compile_options mechc_compile_defaults(void);
mechc_kernels *mechc_compile_with(mechc_model *m, const char *engine,
                                  const mechc_compile_options *o, mechc_diag *diag);
const char *mechc_kernels_engine(const mechc_kernels *k);
double mechc_kernels_compile_seconds(const mechc_kernels *k);
const char *mechc_kernels_source(const mechc_kernels *k);

mechc_status mechc_phi(mechc_kernels *k, const double *q, double t, double *phi);
mechc_status mechc_jacobian(mechc_kernels *k, const double *q, double t, double *jac);
int mechc_jacobian_nz(const mechc_kernels *k);
mechc_status mechc_jacobian_pattern(const mechc_kernels *k, int *rows, int *cols);
mechc_status mechc_jacobian_values(mechc_kernels *k, const double *q, double t,
                                   double *vals);
mechc_status mechc_nu(mechc_kernels *k, const double *q, double t, double *nu);
mechc_status mechc_gamma(mechc_kernels *k, const double *q, const double *qd, double t,
                         double *gamma);
mechc_status mechc_all(mechc_kernels *k, const double *q, const double *qd, double t,
                       double *phi, double *jac, double *nu, double *gamma);
mechc_status mechc_mass(mechc_kernels *k, const double *q, double *M);
mechc_status mechc_force(mechc_kernels *k, const double *q, const double *qd, double t,
                         double *Q);
mechc_status mechc_eom(mechc_kernels *k, const double *q, const double *qd, double t,
                       double *M, double *Q, double *jac, double *gamma);
mechc_status mechc_phi_p(mechc_kernels *k, const double *q, double t, double *phi_p);
int mechc_phi_p_nz(const mechc_kernels *k);
mechc_status mechc_phi_p_pattern(const mechc_kernels *k, int *rows, int *params);
mechc_status mechc_phi_p_values(mechc_kernels *k, const double *q, double t, double *vals);
mechc_status mechc_sensitivities(mechc_kernels *k, const double *q, const double *qd,
                                 const double *qdd, double t, double *q_p, double *qd_p,
                                 double *qdd_p, double *y_p, double *yd_p, double *ydd_p);
mechc_status mechc_outputs(mechc_kernels *k, const double *q, const double *qd,
                           const double *qdd, double t, double *y, double *yd, double *ydd);

mechc_status mechc_phi_batch(mechc_kernels *k, size_t n, const double *q, const double *t,
                             size_t nt, double *phi);
mechc_status mechc_jacobian_batch(mechc_kernels *k, size_t n, const double *q, const double *t,
                                  size_t nt, double *jac);
mechc_status mechc_nu_batch(mechc_kernels *k, size_t n, const double *q, const double *t,
                            size_t nt, double *nu);
mechc_status mechc_gamma_batch(mechc_kernels *k, size_t n, const double *q, const double *qd,
                               const double *t, size_t nt, double *gamma);
mechc_status mechc_all_batch(mechc_kernels *k, size_t n, const double *q, const double *qd,
                             const double *t, size_t nt, double *phi, double *jac, double *nu,
                             double *gamma);
mechc_status mechc_mass_batch(mechc_kernels *k, size_t n, const double *q, double *M);
mechc_status mechc_force_batch(mechc_kernels *k, size_t n, const double *q, const double *qd,
                               const double *t, size_t nt, double *Q);
mechc_status mechc_outputs_batch(mechc_kernels *k, size_t n, const double *q, const double *qd,
                                 const double *qdd, const double *t, size_t nt, double *y,
                                 double *yd, double *ydd);

typedef void (*mechc_state_fn)(void *ctx, double t, const double *q, const double *qd,
                               const double *qdd, const double *lambda);
typedef struct mechc_run_options {
    double t0, t1;
    int steps;
    double tol;
    int max_iter;
    int forces;
    mechc_state_fn on_state;
    void *ctx;
} mechc_run_options;
mechc_run_options mechc_run_defaults(void);
mechc_result *mechc_run(mechc_kernels *k, const mechc_run_options *o, mechc_diag *diag);

typedef struct mechc_run_tuning {
    const char *linear;
    int max_substeps;
    int assembly_max_iter;
    double pivot_tol;
    double cond_warn;
    const char *ode;
    double ode_tol;
    long long max_dense_entries;
    int keep_states;
    FILE *notes;
} mechc_run_tuning;

mechc_run_tuning mechc_run_tuning_defaults(void);
mechc_result *mechc_run_with(mechc_kernels *k, const mechc_run_options *o,
                             const mechc_run_tuning *tuning, mechc_diag *diag);

typedef struct mechc_sim_options {
    double t0, t1;
    int steps;
    double rtol, atol;
    const char *method;
    const double *qd0;
    mechc_state_fn on_state;
    void *ctx;
} mechc_sim_options;
mechc_sim_options mechc_sim_defaults(void);
mechc_result *mechc_sim(mechc_kernels *k, const mechc_sim_options *o, mechc_diag *diag);

typedef struct mechc_sim_tuning {
    const char *linear;
    long max_steps;
    int interpolate;
    double baumgarte_alpha, baumgarte_beta;
    int keep_states;
    FILE *notes;
    void (*on_step)(void *ctx, double t);
    void *step_ctx;
} mechc_sim_tuning;

mechc_sim_tuning mechc_sim_tuning_defaults(void);
mechc_result *mechc_sim_with(mechc_kernels *k, const mechc_sim_options *o,
                             const mechc_sim_tuning *tuning, mechc_diag *diag);

int mechc_result_states(const mechc_result *r);
const double *mechc_result_time(const mechc_result *r);
const double *mechc_result_q(const mechc_result *r);
const double *mechc_result_qd(const mechc_result *r);
const double *mechc_result_qdd(const mechc_result *r);
const double *mechc_result_y(const mechc_result *r);
const double *mechc_result_yd(const mechc_result *r);
const double *mechc_result_ydd(const mechc_result *r);
const double *mechc_result_lambda(const mechc_result *r);
mechc_status mechc_result_status(const mechc_result *r);
const char *mechc_result_message(const mechc_result *r);
double mechc_result_t_fail(const mechc_result *r);
void mechc_result_free(mechc_result *r);

char *mechc_info_json(mechc_model *m, mechc_diag *diag);

typedef struct mechc_info_options {
    double t;
    double rank_tol;
    int samples;
    const char *linear;
    double max_dense;
    int follow;
    const double *q;
} mechc_info_options;

typedef struct mechc_info_report mechc_info_report;

mechc_info_options mechc_info_defaults(void);
mechc_info_report *mechc_info_with(mechc_model *m, const mechc_info_options *o,
                                   mechc_diag *diag);
char *mechc_info_report_json(const mechc_info_report *r);
void mechc_info_report_free(mechc_info_report *r);
"""

ffi = cffi.FFI()
ffi.cdef(CDEF)

_HERE = os.path.dirname(os.path.abspath(__file__))


def library_candidates():
    """The places libmechc.so is looked for, in order.

    $MECHC_LIBRARY when set; the path ``make install`` wrote into
    _libpath.py; build/libmechc.so of the source tree this package sits in
    (python/mechc/ -> ../../build/); then the system's search
    (ctypes.util.find_library("mechc")).
    """
    found = []
    env = os.environ.get("MECHC_LIBRARY")
    if env:
        found.append(env)
    try:
        from . import _libpath
        found.append(_libpath.LIBRARY)
    except ImportError:
        pass
    found.append(os.path.join(_HERE, os.pardir, os.pardir, "build", "libmechc.so"))
    system = ctypes.util.find_library("mechc")
    if system:
        found.append(system)
    return found


def _open():
    tried = []
    for path in library_candidates():
        if os.sep in path and not os.path.exists(path):
            tried.append(path + " (missing)")
            continue
        try:
            return ffi.dlopen(path), path
        except OSError as e:
            tried.append("%s (%s)" % (path, e))
    raise ImportError("mechc: libmechc.so not found; build it with `make` in the source tree, "
                      "install it with `make install`, or set MECHC_LIBRARY. Tried: "
                      + "; ".join(tried))


lib, library_path = _open()


class MechcError(Exception):
    """A failure reported by libmechc, with its place in the mechanism file.

    Attributes: ``status`` (the library's code, e.g. "input", "analysis"),
    ``file``, ``line``, ``column`` (1-based; 0 when the failure has no place
    in a file), ``message`` (the text alone). ``str(e)`` is
    ``file:line:col: message``, as the mechc command prints it. Loading
    errors are also ValueError (InputError), compile and analysis failures
    RuntimeError (AnalysisError).
    """

    def __init__(self, message, file="", line=0, column=0, status="error"):
        self.message = message
        self.file = file
        self.line = line
        self.column = column
        self.status = status
        super().__init__(self._text())

    def _text(self):
        place = self.file
        if self.line:
            place += ":%d" % self.line
            if self.column:
                place += ":%d" % self.column
        return "%s: %s" % (place, self.message) if place else self.message


class InputError(MechcError, ValueError):
    """The mechanism text is wrong, or an argument is (an unknown name, a bad size)."""


class NotAvailableError(MechcError, ValueError):
    """The model has no such thing: dynamics without masses, design without parameters."""


class AnalysisError(MechcError, RuntimeError):
    """Compiling, a run or a simulation failed (``result`` holds the states before it)."""

    result = None


_STATUS_NAMES = {1: "input", 2: "argument", 3: "not available", 4: "compile",
                 5: "analysis", 6: "not runnable"}
_STATUS_CLASSES = {1: InputError, 2: InputError, 3: NotAvailableError, 4: AnalysisError,
                   5: AnalysisError, 6: AnalysisError}


def _string(p):
    return ffi.string(p).decode("utf-8", "replace") if p != ffi.NULL else ""


def error_from(status, message="", file="", line=0, column=0):
    """The MechcError subclass for a status, with its text and place."""
    status = int(status)
    if not message:
        message = _string(lib.mechc_status_text(status))
    cls = _STATUS_CLASSES.get(status, MechcError)
    return cls(message, file, line, column, _STATUS_NAMES.get(status, "error"))


def error_from_diag(diag):
    """A MechcError from a filled mechc_diag."""
    return error_from(diag.status, _string(diag.message), _string(diag.file), diag.line,
                      diag.column)


def check(status):
    """Raises the MechcError of a status that is not MECHC_OK."""
    if status:
        raise error_from(status)
