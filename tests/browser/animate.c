/* animate.c - writes the animated SVG of a fully driven, holonomic mechanism for the browser test.
 *
 * usage: animate FILE.mech OUT.svg [--t1 T] [--steps N] [--trace SPEC]...
 *
 * A stand-in for `mechc run --svg` until the run command exists: assembles
 * the mechanism at every step with plain Newton-Raphson on the JIT kernels
 * (Phi and Phi_q, dense Gaussian elimination with partial pivoting), each
 * step starting from the last two solutions extrapolated, and hands the
 * trajectory to svg_write_animation. Only NH = NQ and NV = 0 mechanisms.
 */
#include "../../generator/engine/engine.h"
#include "../../generator/pipeline/pipeline.h"
#include "../../generator/render/svg_anim.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Solves a x = b in place (a: n*n row-major, destroyed); false when singular. */
static bool solve(double *a, double *b, int n)
{
    for (int k = 0; k < n; k++) {
        int p = k;
        for (int i = k + 1; i < n; i++)
            if (fabs(a[i * n + k]) > fabs(a[p * n + k]))
                p = i;
        if (!(fabs(a[p * n + k]) > 1e-14))
            return false;
        if (p != k) {
            for (int j = 0; j < n; j++) {
                double s = a[k * n + j];
                a[k * n + j] = a[p * n + j];
                a[p * n + j] = s;
            }
            double s = b[k];
            b[k] = b[p];
            b[p] = s;
        }
        for (int i = k + 1; i < n; i++) {
            double f = a[i * n + k] / a[k * n + k];
            if (f == 0)
                continue;
            for (int j = k; j < n; j++)
                a[i * n + j] -= f * a[k * n + j];
            b[i] -= f * b[k];
        }
    }
    for (int k = n - 1; k >= 0; k--) {
        double s = b[k];
        for (int j = k + 1; j < n; j++)
            s -= a[k * n + j] * b[j];
        b[k] = s / a[k * n + k];
    }
    return true;
}

/* Newton on Phi(q, t) = 0 from q; false when it does not converge. */
static bool assemble(const Engine *e, double *q, double t, double *jac, double *phi)
{
    int n = e->nq;
    for (int it = 0; it < 50; it++) {
        engine_phi(e, q, t, phi);
        double worst = 0;
        for (int i = 0; i < n; i++)
            worst = fmax(worst, fabs(phi[i]));
        if (worst < 1e-12)
            return true;
        engine_jac(e, q, t, jac);
        for (int i = 0; i < n; i++)
            phi[i] = -phi[i];
        if (!solve(jac, phi, n))
            return false;
        double step = 0;
        for (int i = 0; i < n; i++) {
            q[i] += phi[i];
            step = fmax(step, fabs(phi[i]));
        }
        if (step < 1e-13)
            return true;
    }
    return false;
}

int main(int argc, char **argv)
{
    if (argc < 3) {
        fprintf(stderr, "usage: animate FILE.mech OUT.svg [--t1 T] [--steps N] [--trace SPEC]...\n");
        return 2;
    }
    double t1 = 1;
    int steps = 100, ntr = 0;
    const char *trace_text[8];
    for (int i = 3; i < argc; i++) {
        if (strcmp(argv[i], "--t1") == 0 && i + 1 < argc)
            t1 = atof(argv[++i]);
        else if (strcmp(argv[i], "--steps") == 0 && i + 1 < argc)
            steps = atoi(argv[++i]);
        else if (strcmp(argv[i], "--trace") == 0 && i + 1 < argc && ntr < 8)
            trace_text[ntr++] = argv[++i];
        else {
            fprintf(stderr, "animate: bad argument '%s'\n", argv[i]);
            return 2;
        }
    }
    if (steps < 1 || !(t1 > 0)) {
        fprintf(stderr, "animate: need --steps >= 1 and --t1 > 0\n");
        return 2;
    }
    MechLimits limits = mech_default_limits();
    Diag diag;
    Mech *mech = pipeline_load(argv[1], &limits, &diag);
    if (!mech) {
        diag_print(&diag, stderr);
        return 2;
    }
    const Model *m = mech->model;
    if (m->nv != 0 || m->nh != m->nq) {
        fprintf(stderr, "animate: %s: needs NH = NQ and no velocity rows (NQ %d, NH %d, NV %d)\n",
                argv[1], m->nq, m->nh, m->nv);
        pipeline_free(mech);
        return 2;
    }
    SvgTrace tr[8];
    for (int i = 0; i < ntr; i++) {
        char err[256];
        if (!svg_parse_trace(m, trace_text[i], &tr[i], err, sizeof err)) {
            fprintf(stderr, "animate: %s\n", err);
            pipeline_free(mech);
            return 2;
        }
    }
    Engine e;
    if (!engine_open(&e, ENGINE_JIT, mech, &diag)) {
        diag_print(&diag, stderr);
        pipeline_free(mech);
        return 1;
    }
    int n = m->nq, frames = steps + 1, status = 0;
    double *t = malloc((size_t)frames * sizeof *t);
    double *q = malloc((size_t)frames * (size_t)n * sizeof *q);
    double *jac = malloc((size_t)n * (size_t)n * sizeof *jac);
    double *phi = malloc((size_t)n * sizeof *phi);
    for (int k = 0; k < frames; k++) {
        double *qk = q + (size_t)k * n;
        t[k] = t1 * k / steps;
        for (int i = 0; i < n; i++)     /* start: q0, then extrapolate the last two */
            qk[i] = k == 0 ? m->q0[i] : k == 1 ? qk[i - n] : 2 * qk[i - n] - qk[i - 2 * n];
        if (!assemble(&e, qk, t[k], jac, phi)) {
            fprintf(stderr, "animate: t = %g: Newton did not converge\n", t[k]);
            status = 1;
            break;
        }
    }
    if (status == 0) {
        FILE *out = fopen(argv[2], "w");
        if (!out || !svg_write_animation(out, m, t, q, frames, tr, ntr, NULL)) {
            perror(argv[2]);
            status = 1;
        }
        if (out && fclose(out) != 0)
            status = 1;
    }
    free(t);
    free(q);
    free(jac);
    free(phi);
    engine_close(&e);
    pipeline_free(mech);
    return status;
}
