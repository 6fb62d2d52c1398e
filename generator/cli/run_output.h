/* run_output.h - where the states of `mechc run` and `mechc sim` go: CSV, JSON, the kept rows, pictures. */
#ifndef MECHC_RUN_OUTPUT_H
#define MECHC_RUN_OUTPUT_H

#include <stdbool.h>
#include <stdio.h>

#include "../kin/outputs.h"
#include "../model/model.h"
#include "../render/progress.h"
#include "../render/svg_anim.h"
#include "../render/svg_plot.h"
#include "../../runtime/host/mechrt_host.h"
#include "cli.h"

/* The animation draws the reactions of at most RUN_OUTPUT_MAX_FORCES joints. */
enum { RUN_OUTPUT_MAX_TRACES = CLI_LIST_MAX, RUN_OUTPUT_MAX_PLOT_VARS = 64,
       RUN_OUTPUT_MAX_FORCES = 256 };

/* What happens to the multipliers of the states (the last argument of
   run_output_state). */
typedef enum RunOutputLambda {
    RUN_OUTPUT_NO_LAMBDA,       /* run: there are none */
    RUN_OUTPUT_LAMBDA_JSON,     /* sim: kept for JSON's "rows" and "lambda" */
    RUN_OUTPUT_FORCES           /* run --forces: also CSV columns lambda(ROW) and
                                   effort(DRIVER), JSON "drivers" and "efforts",
                                   plottable, drawn as arrows */
} RunOutputLambda;

/* Where the states go. Fill the fields before the first, then
   run_output_open; run_output_close frees it. */
typedef struct RunOutput {
    const char *cmd;            /* "run", "sim": for messages */
    FILE *csv;                  /* NULL: no CSV */
    bool keep;                  /* keep the rows (JSON, pictures, the one-instant table) */
    RunOutputLambda lambda_use;
    int digits;
    double t0, t1;
    /* the rest is run_output_open's */
    const Model *m;
    MechrtTrace trace;          /* kept rows [t, v, vd, vdd] and angular velocities */
    bool full;                  /* out of memory keeping them */
    int nq, nv, nr;             /* coordinates; variables (coordinates, then outputs); rows */
    OutputEval outputs;
    double *v;                  /* a state's variables: v | vd | vdd, 3 nv */
    const char **names;         /* the variables' names, nv */
    double *w;                  /* a spatial state's angular velocities, outputs.nw */
    double *lambda;             /* kept multipliers, nr per kept row */
    double *efforts;            /* kept efforts (RUN_OUTPUT_FORCES), nd per kept row */
    size_t lcap;                /* kept rows' room in lambda and efforts */
    int nd;                     /* drivers */
    int *drivers;               /* their rows */
    const char **dnames;        /* their names */
    int nx;                     /* extra CSV columns: nr lambdas, nd efforts */
    char **xnames;
    double *x;                  /* a state's extra columns */
    Progress progress;
    bool warned;                /* an output was not finite (said once) */
    bool headed;                /* the CSV header is written: with the first state, so a
                                   run that fails before it prints nothing */
    /* extra columns a command computes itself (run --sens): called at each
       state to fill x (run_output_set_extra); NULL: none */
    void (*extra)(void *ctx, double t, const double *q, const double *qd, const double *qdd,
                  double *x);
    void *extra_ctx;
    double *xkept;              /* the extra columns of the kept rows (JSON) */
    size_t xcap;                /* kept rows' room in xkept */
} RunOutput;

/* Sets up out for m (out's first fields filled) and writes the CSV
   header when there is a CSV. */
void run_output_open(RunOutput *out, const Model *m);
void run_output_close(RunOutput *out);
/* Extra CSV columns (not with RUN_OUTPUT_FORCES), after run_output_open:
   n of them named names (taken: freed by run_output_close), filled by
   fill at each state. */
void run_output_set_extra(RunOutput *out, int n, char **names,
                          void (*fill)(void *ctx, double t, const double *q, const double *qd,
                                       const double *qdd, double *x), void *ctx);

/* A state: the CSV row, the kept row, the progress. lambda: nr values
   (NULL when lambda_use is RUN_OUTPUT_NO_LAMBDA). Shaped as RunForcesFn
   and SimStateFn; run_output_kinematic_state is RunStateFn's. */
void run_output_state(void *out, double t, const double *q, const double *qd,
                      const double *qdd, const double *lambda);
void run_output_kinematic_state(void *out, double t, const double *q, const double *qd,
                                const double *qdd);

/* The JSON of the kept rows to f: run's keys, then the multipliers' when
   kept. error_message NULL: "ok": true. */
void run_output_json(FILE *f, const RunOutput *out, const char *error_message, double error_t);

/* After the analysis: its failure (message, and how many states before
   t_fail were written) and a JSON store that ran out of memory, on stderr.
   True when either happened (exit status 1). */
bool run_output_report_failure(const RunOutput *out, const Model *m, const char *message,
                               int states, double t_fail);

/* The --trace points and --plot variables, resolved. */
typedef struct RunPictures {
    SvgTrace traces[RUN_OUTPUT_MAX_TRACES];
    int ntraces;                /* --trace points, then point outputs */
    SvgPlotVar vars[RUN_OUTPUT_MAX_PLOT_VARS];
    int nvars;
    const char *svg_path, *plot_path;
    int view;                   /* an SvgView; -1: the default */
    bool sens;                  /* run --sens: its columns can be plotted */
} RunPictures;

/* Resolves the --trace texts and the --plot-vars list (NULL: every
   variable) against m; lambda(ROW) and effort(DRIVER) are known when
   forces. false (reported on stderr) when one is unknown, or when
   p->view is set (>= 0) for a planar mechanism. */
bool run_output_resolve_pictures(const char *cmd, const Model *m, const CliList *traces,
                                 const char *plot_list, bool forces, RunPictures *p);

/* The animation and the chart of the kept rows; false (reported) when a
   file cannot be written. */
bool run_output_pictures(const RunOutput *out, const RunPictures *p);

#endif
