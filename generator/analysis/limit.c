/* limit.c - a motion that ends at a limit position: a driver pushes the mechanism where it cannot go.
 *
 * A driver that asks for a position beyond the mechanism's reach (a
 * rocker driven past the angle where crank and coupler line up) makes the
 * Jacobian lose rank as the motion nears that position (sigma_min /
 * sigma_max falls as the square root of the time left): velocities and
 * accelerations grow without bound, and whatever gives up first (sim's
 * step size underflowing or the projection's Newton, run's Newton in a
 * step and its substeps) would otherwise headline the failure as a matter
 * of steps, at the time of the output step. The Jacobian at the last
 * state reached is decomposed (dense, up to LIMIT_MAX_NQ coordinates); a
 * near dependency of its rows in which a driver takes part is the cause,
 * said first with the time and the rows, and the failure's own words are
 * kept after it.
 */
#include "limit.h"

#include "common.h"

#include "../base/arena.h"
#include "../../runtime/host/mechrt_host.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* A row takes part in the dependency with at least this share of the
   largest |u_i| (as analysis_name_list names them). */
#define LIMIT_SHARE 0.2
/* Above this many coordinates the dense SVD is left out (O(n^3) on an error path). */
#define LIMIT_MAX_NQ 400

/* The drivers among the rows of the dependency (roww), "'D'" or "'D1',
   'D2'", into out; how many. */
static int driver_names(const Model *m, const double *roww, int nr, char *out, size_t size)
{
    double wmax = 0;
    for (int i = 0; i < nr; i++)
        wmax = roww[i] > wmax ? roww[i] : wmax;
    int n = 0;
    out[0] = '\0';
    for (int i = 0; i < nr; i++)
        if (m->rows[i].kind == JOINT_DRIVER && roww[i] >= LIMIT_SHARE * wmax)
            analysis_msgf(out, size, "%s'%s'", n++ ? ", " : "", m->rows[i].name);
    return n;
}

bool limit_explain(const Model *m, const MechrtKernels *k, const double *q, double t,
                   double ratio_max, char *message, size_t size)
{
    int nq = k->nq, nr = k->nh + k->nv;
    if (!k->jac || nr == 0 || nq > LIMIT_MAX_NQ)
        return false;
    double *jac = xcalloc((size_t)nr * (size_t)nq + 1, sizeof *jac);
    double *roww = xcalloc((size_t)nr + 1, sizeof *roww), *colw = xcalloc((size_t)nq, sizeof *colw);
    const char **row_names = xcalloc((size_t)nr + 1, sizeof *row_names);
    for (int i = 0; i < nr; i++)
        row_names[i] = m->rows[i].name;
    k->jac(k->ctx, q, t, jac);
    double ratio = mechrt_host_singular_direction(nr, nq, jac, roww, colw);
    char drivers[256];
    bool limit = ratio >= 0 && ratio < ratio_max
                 && driver_names(m, roww, nr, drivers, sizeof drivers) > 0;
    if (limit) {
        /* the failure's words after the cause, without their "t = T: " */
        char *was = xmalloc(size + 1);
        const char *tail = strncmp(message, "t = ", 4) == 0 && strstr(message, ": ")
                               ? strstr(message, ": ") + 2 : message;
        snprintf(was, size + 1, "%s", tail);
        message[0] = '\0';
        analysis_msgf(message, size, "t = %.10g: the mechanism cannot reach the driven position: "
                      "driver %s pushes it past a limit position, where the Jacobian loses "
                      "rank (smallest singular value %.2g of the largest, along rows ", t,
                      drivers, ratio);
        analysis_name_list(message, size, row_names, roww, nr);
        analysis_msgf(message, size, "); drive another coordinate, or end the motion before "
                      "it; where it stopped: %s", was);
        free(was);
    }
    free(jac), free(roww), free(colw), free(row_names);
    return limit;
}
