/* integrability.h - is one velocity-level row a position constraint in disguise, and which? */
#ifndef MECHC_INTEGRABILITY_H
#define MECHC_INTEGRABILITY_H

#include "../model/model.h"
#include "../analysis/options.h"

#include <stdbool.h>

typedef struct Integrability {
    bool integrable;        /* the verdict */
    bool symbolic;          /* proved by simplification, not by sampling */
    bool decided;           /* false: no sample state could be evaluated */
    int ncoords;            /* coordinates (t included) the form involves */
    int triples;            /* components of omega ^ d omega tested */
    int samples;            /* sample states evaluated */
    char *law;              /* "h(q, t) = const", or NULL (malloc'd) */
    char *note;             /* how the verdict was reached (malloc'd) */
} Integrability;

/* Tests the velocity-level row `row` of the model: Psi = a(q,t)^T qd + b(q,t),
   omega = a^T dq + b dt on (q, t) space, integrable iff omega ^ d omega = 0,
   i.e. for every triple i < j < k of (q, t) coordinates
     a_i (d_j a_k - d_k a_j) + a_j (d_k a_i - d_i a_k) + a_k (d_i a_j - d_j a_i) = 0.
   Symbolic first (every triple simplifies to 0: proof); otherwise sampled
   at opt->samples random states around q_center. When integrable, looks
   for h with mu omega = dh (mu = 1, then 1/a_p) by symbolic integration.
   Adds nodes to the model's graph. Returns false with diag filled only when
   the graph's node limit is passed. */
bool integrability_analyse(Model *m, int row, const double *q_center,
                           const AnalysisOptions *opt, Integrability *out, Diag *diag);
void integrability_free(Integrability *it);

#endif
