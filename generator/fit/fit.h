/* fit.h - mechc fit as a library: design parameters identified from measurements by nonlinear least squares.
 *
 * The residuals are sqrt(w) (model - measured) for every measured value,
 * the model's values from the motion followed through the samples
 * (sample.h); the Jacobian is the sensitivities' (Phi_q q_p = -Phi_p, no
 * finite differences). GSL's trust-region solver (gsl_multifit_nlinear,
 * Levenberg-Marquardt) minimises their squares. Bounds are kept by a
 * change of variable, p = lo + (hi - lo) (1 + sin u) / 2. At the solution
 * the covariance (J^T J)^-1 of the varied parameters, scaled by the
 * residual variance chi^2 / (n - k), gives the standard errors and the
 * correlations.
 */
#ifndef MECHC_FIT_H
#define MECHC_FIT_H

#include "sample.h"

typedef struct FitOptions {
    bool *vary;             /* np: which design parameters are estimated (the rest stay) */
    double *lo, *hi;        /* np: bounds (-inf, +inf: none) */
    int max_iter;           /* solver iterations (default 200) */
    double xtol, gtol, ftol;/* GSL's tests (default 1e-15, 1e-15, 0): to round-off */
    int steps;              /* intervals over the data's span (default 20; run subdivides where it must) */
    double newton_tol;      /* the positions' Newton tolerances (default 1e-12) */
} FitOptions;

typedef enum FitStatus { FIT_OK, FIT_FAILED, FIT_BAD_INPUT } FitStatus;

typedef struct FitResult {
    FitStatus status;
    char message[600];      /* FIT_FAILED, FIT_BAD_INPUT: why */
    char warning[400];      /* FIT_OK: a parameter poorly identified ("" none) */
    int n, k;               /* residuals, parameters estimated */
    int *index;             /* k: the design parameter of each */
    double *p0, *p;         /* np: the starting and the final design */
    double *std_error;      /* k */
    double *corr;           /* k x k */
    double cost0, cost;     /* sum of the weighted squared residuals, at the start and the end */
    int iterations, nevalf, nevaldf;
    const char *reason;     /* the solver's stopping test */
    double cond;            /* J's condition number (2-norm) at the solution */
    double cpu_seconds;     /* the process's CPU time in fit_run (clock()) */
    double *model;          /* the data's shape: model values at the solution */
    bool solved;            /* the solver ran and the fields above are its end's;
                               false: FIT_BAD_INPUT, or FIT_FAILED before it
                               started or where the motion could not be followed */
} FitResult;

FitOptions fit_default_options(void);

/* Fits m's design to d: p starts from the model's design. The design at
   the end is left set in m (model_set_design). */
FitStatus fit_run(Model *m, const Kinematics *kin, const Engine *e, const FitData *d,
                  const FitOptions *o, FitResult *r);
void fit_result_free(FitResult *r);

#endif
