/* options.c - the default analysis options (documented in options.h). */
#include "options.h"

AnalysisOptions analysis_default_options(void)
{
    return (AnalysisOptions){
        .tol_phi = 1e-10,
        .tol_dq = 1e-10,
        .max_iter = 60,
        .rank_tol = -1.0,
        .samples = 8,
        .seed = 20240605u,
        .generic_samples = 3,
        .max_dense = 5e5,
    };
}
