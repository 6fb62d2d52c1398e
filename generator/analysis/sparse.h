/* sparse.h - rank and redundant rows of a large sparse Jacobian (row-wise Givens QR). */
#ifndef MECHC_ANALYSIS_SPARSE_H
#define MECHC_ANALYSIS_SPARSE_H

#include "../diff/kinematics.h"

#include <stddef.h>

/* Rank and redundant rows beyond the dense limit: rows are added one at a
   time to a row-wise Givens QR; a row eliminated down to entries at or
   below tol is redundant. fill_max bounds the stored R entries. */
typedef struct SparseRank SparseRank;

SparseRank *sparse_rank_new(int nq, double tol, size_t fill_max);
void sparse_rank_free(SparseRank *s);
/* Adds a row given by its nonzeros: 1 it raised the rank, 0 it is
   redundant, -1 NaN or Inf, -2 the fill limit was reached. */
int sparse_rank_add(SparseRank *s, const int *cols, const double *vals, int n);
int sparse_rank_of(const SparseRank *s);
/* Solves R^T R y = b in place with the factor of the rows added so far
   (m of them; a redundant row gets y = 0): the seminormal equations of the
   sparse minimum-norm step. */
void sparse_rank_seminormal_solve(const SparseRank *s, int m, double *b);
/* Largest singular value of the listed rows (power iteration), for the
   rank tolerance; vals[e] is the value of kin->jac[e]. */
double sparse_rank_sigma_max(const Kinematics *kin, const double *vals, const int *rows, int nrows,
                             unsigned seed);

#endif
