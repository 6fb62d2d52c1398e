/* mujoco_sim.c - MuJoCo's C API on a benchmark model: integrates at fixed steps, writes a CSV like `mechc sim`'s, reports CPU time and peak memory. */
/*
 * mujoco_sim MODEL.xml --t1 T --steps S --dt H --csv FILE
 *            [--integrator rk4|euler|implicit] [--timeconst TC] [--dampratio DR]
 *            [--imp D] [--tolerance TOL]
 *
 * Loads MODEL.xml (mj_loadXML), starts from its first keyframe if it has
 * one, overrides the options given, steps T / H times (mj_step) and writes
 * S + 1 rows at t = i T / S: t, every hinge's angle under the joint's name,
 * then x, y, d(x), d(y) of every site under the site's name (mechc sim's
 * column names: P1.x, d(P1.x)). --timeconst and --dampratio set the solref
 * of every equality constraint (MuJoCo's stiffness of a soft constraint:
 * the time constant of its error's decay), --imp its impedance
 * (solimp d0 = dwidth; 0.9999 is MuJoCo's stiffest); any --timeconst turns
 * off MuJoCo's refsafe (which raises timeconst to 2 H). On stderr, one line:
 *   mujoco_sim: load L ms CPU, integration I ms CPU, N steps, peak RSS R kB
 * (CLOCK_PROCESS_CPUTIME_ID; getrusage's ru_maxrss of this process, so run
 * one case per process). Exit 0, 1 if MuJoCo warned (a diverging state, which it resets; a
 * full constraint buffer) or the state ends not finite, 2 on usage.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <time.h>

#include <mujoco/mujoco.h>

typedef struct {
    const char *model, *csv;
    double t1, dt, timeconst, dampratio, imp, tolerance;
    long steps;
    int integrator;
} SimArgs;

static double cpu_ms(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
    return 1e3 * (double)ts.tv_sec + 1e-6 * (double)ts.tv_nsec;
}

/* MuJoCo's own handler prints to stdout and appends to MUJOCO_LOG.TXT in
   the working directory: stderr instead. */
static void warn_stderr(const char *msg)
{
    fprintf(stderr, "mujoco_sim: MuJoCo: %s\n", msg);
}

static int usage(const char *why)
{
    fprintf(stderr, "mujoco_sim: %s\n"
            "usage: mujoco_sim MODEL.xml --t1 T --steps S --dt H --csv FILE [--integrator rk4|euler|implicit]\n"
            "       [--timeconst TC] [--dampratio DR] [--imp D] [--tolerance TOL]\n", why);
    return 2;
}

static int parse_integrator(const char *s)
{
    if (!strcmp(s, "rk4"))
        return mjINT_RK4;
    if (!strcmp(s, "euler"))
        return mjINT_EULER;
    if (!strcmp(s, "implicit"))
        return mjINT_IMPLICIT;
    return -1;
}

/* 0, or 2 after a usage message. */
static int parse_args(int argc, char **argv, SimArgs *a)
{
    *a = (SimArgs){.integrator = mjINT_RK4, .dampratio = 1};
    for (int i = 1; i < argc; i++) {
        const char *o = argv[i], *v = i + 1 < argc ? argv[i + 1] : NULL;
        if (o[0] != '-') {
            a->model = o;
            continue;
        }
        if (!v)
            return usage("an option without its value");
        i++;
        if (!strcmp(o, "--t1")) a->t1 = atof(v);
        else if (!strcmp(o, "--steps")) a->steps = atol(v);
        else if (!strcmp(o, "--dt")) a->dt = atof(v);
        else if (!strcmp(o, "--csv")) a->csv = v;
        else if (!strcmp(o, "--timeconst")) a->timeconst = atof(v);
        else if (!strcmp(o, "--dampratio")) a->dampratio = atof(v);
        else if (!strcmp(o, "--imp")) a->imp = atof(v);
        else if (!strcmp(o, "--tolerance")) a->tolerance = atof(v);
        else if (!strcmp(o, "--integrator")) {
            if ((a->integrator = parse_integrator(v)) < 0)
                return usage("--integrator takes rk4, euler or implicit");
        } else
            return usage("unknown option");
    }
    if (!a->model || !a->csv || a->t1 <= 0 || a->dt <= 0 || a->steps < 1)
        return usage("MODEL, --t1, --steps, --dt and --csv are required");
    return 0;
}

/* The options of the command line over the model's. */
static void apply_options(mjModel *m, const SimArgs *a)
{
    m->opt.timestep = a->dt;
    m->opt.integrator = a->integrator;
    if (a->tolerance > 0)
        m->opt.tolerance = a->tolerance;
    for (int i = 0; i < m->neq; i++) {
        if (a->timeconst > 0) {
            m->eq_solref[mjNREF * i] = a->timeconst;
            m->eq_solref[mjNREF * i + 1] = a->dampratio;
        }
        if (a->imp > 0) {
            m->eq_solimp[mjNIMP * i] = a->imp;
            m->eq_solimp[mjNIMP * i + 1] = a->imp;
        }
    }
    if (a->timeconst > 0)
        m->opt.disableflags |= mjDSBL_REFSAFE;
}

static void write_header(FILE *f, const mjModel *m)
{
    fprintf(f, "t");
    for (int j = 0; j < m->njnt; j++)
        if (m->jnt_type[j] == mjJNT_HINGE)
            fprintf(f, ",%s", mj_id2name(m, mjOBJ_JOINT, j));
    for (int s = 0; s < m->nsite; s++) {
        const char *n = mj_id2name(m, mjOBJ_SITE, s);
        fprintf(f, ",%s.x,%s.y,d(%s.x),d(%s.y)", n, n, n, n);
    }
    fputc('\n', f);
}

/* One row; mj_forward first, since mj_step leaves the positions of the
   state before its step in d. */
static void write_row(FILE *f, const mjModel *m, mjData *d)
{
    mj_forward(m, d);
    fprintf(f, "%.17g", d->time);
    for (int j = 0; j < m->njnt; j++)
        if (m->jnt_type[j] == mjJNT_HINGE)
            fprintf(f, ",%.17g", d->qpos[m->jnt_qposadr[j]]);
    for (int s = 0; s < m->nsite; s++) {
        mjtNum v[6];
        mj_objectVelocity(m, d, mjOBJ_SITE, s, v, 0);   /* world frame: angular, then linear */
        fprintf(f, ",%.17g,%.17g,%.17g,%.17g", d->site_xpos[3 * s], d->site_xpos[3 * s + 1], v[3], v[4]);
    }
    fputc('\n', f);
}

/* Steps to t1 with a row every t1 / steps; the state finite at the end. */
static int integrate(const mjModel *m, mjData *d, const SimArgs *a, FILE *f, long *nstep)
{
    long total = lround(a->t1 / a->dt), every = lround(a->t1 / a->steps / a->dt);
    if (every < 1 || every * a->steps != total) {
        fprintf(stderr, "mujoco_sim: --dt %g does not divide the output interval %g\n", a->dt, a->t1 / a->steps);
        return 2;
    }
    write_row(f, m, d);
    for (long i = 1; i <= total; i++) {
        mj_step(m, d);
        if (i % every == 0)
            write_row(f, m, d);
    }
    *nstep = total;
    /* MuJoCo resets the state where it diverges, drops constraints where
       its buffer is full, and counts a warning for each */
    for (int w = 0; w < mjNWARNING; w++)
        if (d->warning[w].number)
            return 1;
    for (int i = 0; i < m->nq; i++)
        if (!isfinite(d->qpos[i]))
            return 1;
    return 0;
}

int main(int argc, char **argv)
{
    SimArgs a;
    if (parse_args(argc, argv, &a))
        return 2;
    char err[1000] = "";
    mju_user_warning = warn_stderr;
    double t0 = cpu_ms();
    mjModel *m = mj_loadXML(a.model, NULL, err, sizeof err);
    if (!m) {
        fprintf(stderr, "mujoco_sim: %s: %s\n", a.model, err);
        return 2;
    }
    mjData *d = mj_makeData(m);
    apply_options(m, &a);
    if (m->nkey > 0)
        mj_resetDataKeyframe(m, d, 0);
    double t_load = cpu_ms() - t0;
    FILE *f = fopen(a.csv, "w");
    if (!f) {
        perror(a.csv);
        return 2;
    }
    write_header(f, m);
    long nstep = 0;
    t0 = cpu_ms();
    int rc = integrate(m, d, &a, f, &nstep);
    double t_int = cpu_ms() - t0;
    fclose(f);
    struct rusage ru;
    getrusage(RUSAGE_SELF, &ru);
    fprintf(stderr, "mujoco_sim: load %.3f ms CPU, integration %.3f ms CPU, %ld steps, peak RSS %ld kB\n",
            t_load, t_int, nstep, ru.ru_maxrss);
    if (rc == 1)
        fprintf(stderr, "mujoco_sim: MuJoCo warned (above: a diverging state it reset, a full buffer) or the state is not finite\n");
    mj_deleteData(d);
    mj_deleteModel(m);
    return rc;
}
