/* options.h - the tunable constants of `mechc info`'s analyses (assembly, rank, sampling). */
#ifndef MECHC_ANALYSIS_OPTIONS_H
#define MECHC_ANALYSIS_OPTIONS_H

/* Fill with analysis_default_options(). */
typedef struct AnalysisOptions {
    /* Assembly converged when ||Phi||_inf <= tol_phi (row units) and the last
       step ||dq||_inf <= tol_dq (coordinate units). default 1e-10, 1e-10 */
    double tol_phi, tol_dq;
    /* Newton iterations allowed; a singular root converges only linearly,
       so this is generous. default 60 */
    int max_iter;
    /* Give up early when the residual's 2-norm has not fallen by 1 % in
       this many iterations (a stationary point that is no solution, e.g.
       a guess symmetric about a line the mechanism cannot lie on); 0:
       never. default 0 */
    int stall_iter;
    /* Absolute tolerance on singular values: sigma > rank_tol counts toward
       the rank. Negative: the default max(m, n) * eps * sigma_max (the rule
       of LAPACK's and Matlab's rank). default -1 */
    double rank_tol;
    /* Random states for the numerical integrability check and the law
       verification. default 8 */
    int samples;
    /* Seed of the (deterministic) sample generator. default 20240605 */
    unsigned seed;
    /* Assembled configurations sampled to find the generic rank of the
       undriven mechanism (telling a singular position from a permanent
       redundancy); 0 skips. default 3 */
    int generic_samples;
    /* Dense SVD limit: rank and condition are computed only when
       rows * coordinates <= max_dense (the cost is cubic: about 1 s for
       600 x 600, 20 s for 1200 x 1200 with GSL). default 5e5 */
    double max_dense;
} AnalysisOptions;

AnalysisOptions analysis_default_options(void);

#endif
