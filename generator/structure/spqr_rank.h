/* spqr_rank.h - rank, dependent rows and a null-space basis of a sparse Jacobian, by SuiteSparseQR. */
#ifndef MECHC_ANALYSIS_SPQR_RANK_H
#define MECHC_ANALYSIS_SPQR_RANK_H

#include <stdbool.h>

/* A sparse matrix by rows (CSR): row i's entries are cols[start[i] ..
   start[i + 1]) with their values, columns ascending within a row. */
typedef struct SpqrRows {
    int m, n;
    const int *start;
    const int *cols;
    const double *vals;
} SpqrRows;

/* Rank of the rows and which rows depend on the rows before them: a QR of
   A^T with its columns (A's rows) kept in order, a column whose remaining
   2-norm is at or below tol counted as dependent (Heath's rank detection).
   dependent[i] for i < m; returns the rank, -1 when NaN or Inf is met or
   SuiteSparseQR fails. Rows before `upto` decide rank_upto (the rank of
   rows 0 .. upto - 1) when rank_upto is not NULL. */
int spqr_dependent_rows(const SpqrRows *a, double tol, bool *dependent, int upto, int *rank_upto);

/* A basis of the null space of A, one vector per coordinate that depends
   on the coordinates before it (A's columns kept in order): vector k is 1
   at free[k], 0 at the other free coordinates, and the rest solves
   A x = 0 (a QR of A with the same rank rule). At most max_vectors are
   written to basis (max_vectors x n, row-major) and free; returns the
   null space's dimension n - rank, -1 on failure. */
int spqr_null_basis(const SpqrRows *a, double tol, int max_vectors, double *basis, int *free_coords);

#endif
