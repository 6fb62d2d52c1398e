/* sample.h - the motion at the data's times, and its sensitivities to the design parameters. */
#ifndef MECHC_FIT_SAMPLE_H
#define MECHC_FIT_SAMPLE_H

#include "../kin/outputs.h"
#include "../kin/run.h"
#include "../kin/sens.h"
#include "data.h"

/* The model's motion followed through the samples in time order: assembled
   at the first sample's time from the file's initial values, then carried
   from each sample to the next by `run`'s analysis (steps equal intervals
   per span of the data; substeps where it needs them), so that every
   sample lies on the branch the file's initial values choose. */
typedef struct FitSampler {
    const Model *m;
    const Engine *e;
    const FitData *d;
    Sens sens;
    OutputEval outputs;
    RunOptions ro;
    double step;            /* the longest interval between states */
    double *q, *y;          /* the state at the sample: nq, and the outputs' values */
    double *start;          /* the state to start the next span from */
} FitSampler;

/* false with why when the mechanism has no sensitivities (sens_init).
   newton_tol: both Newton tolerances of the positions. */
bool fit_sampler_init(FitSampler *s, Model *m, const Kinematics *kin, const Engine *e,
                      const FitData *d, int steps, double newton_tol, char *why, size_t size);
void fit_sampler_free(FitSampler *s);

/* At the model's design: the measured variables' model values (d's shape,
   every entry), and with dvalue also their derivatives in every design
   parameter ((nsamples x ncols) x np, row-major). false with why (the time
   and the cause) when the motion cannot be followed. */
bool fit_sample(FitSampler *s, double *value, double *dvalue, char *why, size_t size);

#endif
