/* dynamics.c - the check of M and Q: symmetry, definiteness, velocity terms against the kinetic energy. */
#include "dynamics.h"

#include "../eval/generic.h"

#include <math.h>
#include <string.h>

/* The smallest eigenvalue of the jit's M, made relative: the error is
   max(0, -lambda_min) / (1 + max |lambda|). */
static void check_definite(Checker *c)
{
    size_t nq = (size_t)c->nq;
    memcpy(c->mw, c->mass[ENGINE_JIT], nq * nq * sizeof *c->mw);
    gsl_matrix_view a = gsl_matrix_view_array(c->mw, nq, nq);
    gsl_vector_view ev = gsl_vector_view_array(c->qv, nq);
    gsl_eigen_symm(&a.matrix, &ev.vector, c->eigen);
    double lo = c->qv[0], big = 0.0;
    for (size_t i = 0; i < nq; i++) {
        lo = fmin(lo, c->qv[i]);
        big = fmax(big, fabs(c->qv[i]));
    }
    check_record(c, CHECK_M_PSD, -1, -1, fmax(0.0, -lo) / (1.0 + big), 0.0, 0.0);
}

/* The jit's M at q + x dir (dir a unit column j >= 0, or qd) into out. */
static void mass_at(Checker *c, int j, double x, double *out)
{
    for (int i = 0; i < c->nq; i++)
        c->qw[i] = c->q[i] + x * (j >= 0 ? (i == j) : c->qd[i]);
    const MechrtKernels *k = &c->eng[ENGINE_JIT].k;
    k->mass(k->ctx, c->qw, out);
}

/* Lagrange: the velocity terms are -(d/dt(M qd) - dT/dq) with qdd = 0,
   -(M_dot qd)_i + 1/2 qd^T M_{q_i} qd, by central differences of the jit's
   M, against the generic evaluator's own velocity terms. */
static void check_velocity_terms(Checker *c)
{
    int nq = c->nq;
    double h = c->opt->fd_step;
    for (int i = 0; i < nq; i++)
        c->qv_fd[i] = 0.0;
    mass_at(c, -1, h, c->mw);
    mass_at(c, -1, -h, c->mw2);
    for (int i = 0; i < nq; i++)
        for (int k = 0; k < nq; k++)
            c->qv_fd[i] -= (c->mw[(size_t)i * nq + k] - c->mw2[(size_t)i * nq + k]) / (2 * h) * c->qd[k];
    for (int j = 0; j < nq; j++) {
        double hj = h * fmax(1.0, fabs(c->q[j]));
        mass_at(c, j, hj, c->mw);
        mass_at(c, j, -hj, c->mw2);
        double quad = 0.0;
        for (int i = 0; i < nq; i++)
            for (int k = 0; k < nq; k++)
                quad += c->qd[i] * (c->mw[(size_t)i * nq + k] - c->mw2[(size_t)i * nq + k]) * c->qd[k];
        c->qv_fd[j] += 0.5 * quad / (2 * hj);
    }
    generic_velocity_terms(c->eng[ENGINE_GENERIC].generic, c->q, c->qd, c->qv);
    for (int i = 0; i < nq; i++)
        check_record(c, CHECK_QV_FD, -1, i, c->qv[i], c->qv_fd[i], h);
}

void check_dynamics(Checker *c)
{
    int nq = c->nq;
    const double *m = c->mass[ENGINE_JIT];
    for (int i = 0; i < nq; i++)
        for (int j = 0; j < i; j++)
            check_record(c, CHECK_M_SYMMETRIC, -1, j, m[(size_t)i * nq + j], m[(size_t)j * nq + i], 0.0);
    if (nq == 1)
        c->rep->items[CHECK_M_SYMMETRIC].checked = true;
    check_definite(c);
    check_velocity_terms(c);
}
