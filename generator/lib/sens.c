/* sens.c - libmechc's sensitivities of a state of the motion to the design parameters (run --sens's). */
#include "lib.h"

#include <string.h>

mechc_status mechc_sensitivities(mechc_kernels *k, const double *q, const double *qd,
                                 const double *qdd, double t, double *q_p, double *qd_p,
                                 double *qdd_p, double *y_p, double *yd_p, double *ydd_p)
{
    if (!k || !q || !qd || !qdd || !q_p || !qd_p || !qdd_p)
        return MECHC_EARG;
    if (k->sens_state == 0) {
        char why[200];
        Mech *mech = k->model->mech;
        k->sens_state = sens_init(&k->sens, mech->model, &mech->kin, &k->engine, why, sizeof why)
                            ? 1 : -1;
    }
    if (k->sens_state < 0)
        return MECHC_ENOTAVAIL;
    if (sens_eval(&k->sens, t, q, qd, qdd) != MECHRT_OK)
        return MECHC_EANALYSIS;
    const Sens *s = &k->sens;
    size_t nq = (size_t)s->nq * (size_t)s->np * sizeof(double);
    size_t no = (size_t)s->nout * (size_t)s->np * sizeof(double);
    memcpy(q_p, s->q_p, nq), memcpy(qd_p, s->qd_p, nq), memcpy(qdd_p, s->qdd_p, nq);
    if (y_p && no)
        memcpy(y_p, s->y_p, no);
    if (yd_p && no)
        memcpy(yd_p, s->yd_p, no);
    if (ydd_p && no)
        memcpy(ydd_p, s->ydd_p, no);
    return MECHC_OK;
}
