/* stewart.c - forward kinematics of the Stewart platform (examples/stewart.mech) on a microcontroller.
 *
 * The six leg lengths of stewart.mech are the closed-form inverse
 * kinematics of a known platform trajectory; this program recovers the
 * trajectory by forward kinematics over one period in STEPS equal time
 * steps. Each step is
 *   1. the forward-kinematics solve: Newton from the previous pose
 *      (mechrt_assemble, no predictor) with the position kernels only,
 *      st_phi and st_jac (the fused st_all would also compute nu and
 *      gamma, which a position solve does not need);
 *   2. the velocity and acceleration of the platform
 *      (mechrt_velocity_acceleration: one factorisation, nu, gamma).
 * Every PRINT_EVERY steps it prints step, t, the pose (x y z e0 e1 e2 e3)
 * and d(x), dd(z). It also checks every pose against the closed form (the
 * trajectory written in stewart.mech's header): the program fails when a
 * coordinate is off by more than POSE_TOL.
 *
 * Built with -DSTEP_COUNT (the Makefile's `count` target), SysTick times
 * the two parts of every step after the first (40 instructions a tick
 * under QEMU -icount shift=0, as in main.c) and the program prints the
 * means: instructions per forward-kinematics solve, and per velocity and
 * acceleration analysis. Built with -DSTEP_TRACE (the Makefile's `cycles`
 * target), it calls an empty marker function at the start of each part of
 * every step after the first; cycles.sh finds their addresses in QEMU's
 * trace of executed instructions and estimates the cycles of each part.
 * Kernels: `mechc gen examples/stewart.mech --prefix st [--real float]`,
 * the same real type as the runtime.
 */
#include <math.h>
#include <stdio.h>

#include "st.h"
#include "mechrt.h"

typedef char st_real_matches_mechrt_real[sizeof(st_real) == sizeof(mechrt_real) ? 1 : -1];

/* st_kernels (phi, jac, nu, gamma, all) and the wrappers used below. */
MECHRT_DEFINE_KERNELS(st, ST);

/* The position solve's kernels: without `all`, Newton calls phi and jac. */
static const MechrtKernels st_fk_kernels = {
    ST_NQ, ST_NH, ST_NV, NULL, st_mechrt_phi, st_mechrt_jac, st_mechrt_nu, st_mechrt_gamma, NULL,
    NULL, NULL
};

enum {
    STEPS = 200,      /* time steps over one period, t = 0 .. 1 */
    PRINT_EVERY = 20
};

#ifdef MECHRT_REAL_FLOAT
#define DIGITS 9
#define POSE_TOL 1e-5
#else
#define DIGITS 17
#define POSE_TOL 1e-12
#endif

#ifdef STEP_COUNT
#define SYST_CSR (*(volatile unsigned long *)0xE000E010UL)
#define SYST_RVR (*(volatile unsigned long *)0xE000E014UL)
#define SYST_CVR (*(volatile unsigned long *)0xE000E018UL)
#define SYST_MAX 0xFFFFFFUL
#define TICKS_SINCE(c0) (((c0) - SYST_CVR) & SYST_MAX)
#endif

#ifdef STEP_TRACE
/* Markers: cycles.awk opens a window at the entry of each (by name). */
void mark_fk_plain(void);
void mark_fk_pred(void);
void mark_va(void);
void mark_off(void);
__attribute__((noinline)) void mark_fk_plain(void) { __asm__ volatile(""); }
__attribute__((noinline)) void mark_fk_pred(void) { __asm__ volatile(""); }
__attribute__((noinline)) void mark_va(void) { __asm__ volatile(""); }
__attribute__((noinline)) void mark_off(void) { __asm__ volatile(""); }
#define MARK(step, f) do { if ((step) > 0) f(); } while (0)
#else
#define MARK(step, f) ((void)0)
#endif

static mechrt_real work[MECHRT_WORKSPACE_LEN(ST_NQ, ST_NR)];
static mechrt_real q[ST_NQ], qd[ST_NQ], qdd[ST_NQ];

/* The trajectory of stewart.mech's header at time t, in double:
   pose = (x, y, z, e0, e1, e2, e3). */
static void stewart_pose(double t, double pose[7])
{
    const double pi = 3.14159265358979323846, w = 2 * pi;
    const double g = 0.125 * sin(w * t), n = sqrt(1 + g * g);

    pose[0] = 0.1 * sin(w * t);
    pose[1] = 0.08 * sin(2 * w * t);
    pose[2] = 1 + 0.1 * (1 - cos(w * t));
    pose[3] = 1 / n;
    pose[4] = g / (3 * n);
    pose[5] = 2 * g / (3 * n);
    pose[6] = 2 * g / (3 * n);
}

/* The coordinates are x y z e0 e1 e2 e3 of the one body, in this order. */
static int names_as_expected(void)
{
    static const char *const want[7] = {
        "top.x", "top.y", "top.z", "top.e0", "top.e1", "top.e2", "top.e3"
    };
    int i, k;

    if (ST_NQ != 7)
        return 0;
    for (i = 0; i < 7; i++) {
        for (k = 0; want[i][k] != '\0' && st_coord_names[i][k] == want[i][k]; k++)
            ;
        if (want[i][k] != '\0' || st_coord_names[i][k] != '\0')
            return 0;
    }
    return 1;
}

/* The largest |x_i - pose_i| at t. */
static double pose_error(const mechrt_real *x, double t)
{
    double pose[7], worst = 0;
    int i;

    stewart_pose(t, pose);
    for (i = 0; i < 7; i++) {
        double d = fabs((double)x[i] - pose[i]);
        if (d > worst)
            worst = d;
    }
    return worst;
}

/* The forward-kinematics solve at t into pose (Newton on the position
   kernels), counting its iterations into *iterations. */
static MechrtStatus solve(mechrt_real *pose, mechrt_real t, long *iterations)
{
    MechrtReport report;
    MechrtStatus st = mechrt_assemble(&st_fk_kernels, NULL, pose, t, work,
                                      sizeof work / sizeof work[0], &report);
    *iterations += report.iterations;
    return st;
}

int main(void)
{
    static mechrt_real plain[ST_NQ];
    MechrtStatus st;
    long it_plain = 0, it_pred = 0;
    double worst = 0;
    mechrt_real t = 0;
    int i, k;

    if (!names_as_expected()) {
        printf("error: stewart.mech's coordinates are not top.x .. top.e3\n");
        return 1;
    }
    for (k = 0; k < ST_NQ; k++)
        q[k] = st_q0[k];
    printf("# mechc firmware example: stewart, %s, %d steps\n",
           sizeof(mechrt_real) == sizeof(float) ? "float" : "double", STEPS);
    printf("# step t x y z e0 e1 e2 e3 d(x) dd(z)\n");
#ifdef STEP_COUNT
    unsigned long plain_ticks = 0, pred_ticks = 0, va_ticks = 0;
    SYST_RVR = SYST_MAX;
    SYST_CVR = 0;
    SYST_CSR = 5;
#endif
    for (i = 0; i <= STEPS; i++) {
        mechrt_real tn = (mechrt_real)i / (mechrt_real)STEPS, h = tn - t;
        double err;
        /* 1. from the previous pose as it is (step 0: the initial values) */
        for (k = 0; k < ST_NQ; k++)
            plain[k] = q[k];
#ifdef STEP_COUNT
        unsigned long c0 = SYST_CVR;
#endif
        MARK(i, mark_fk_plain);
        st = solve(plain, tn, &it_plain);
        MARK(i, mark_fk_pred);
#ifdef STEP_COUNT
        unsigned long c1 = SYST_CVR;
#endif
        /* 2. from the previous pose moved by its velocity and acceleration */
        if (st == MECHRT_OK && i > 0) {
            for (k = 0; k < ST_NQ; k++)
                q[k] += h * qd[k] + MECHRT_R(0.5) * h * h * qdd[k];
            st = solve(q, tn, &it_pred);
        } else if (st == MECHRT_OK) {
            for (k = 0; k < ST_NQ; k++)
                q[k] = plain[k];
        }
        MARK(i, mark_va);
#ifdef STEP_COUNT
        unsigned long c2 = SYST_CVR;
#endif
        if (st != MECHRT_OK) {
            printf("error: t = %.*g: forward kinematics: %s\n", DIGITS, (double)tn,
                   mechrt_strerror(st));
            return 1;
        }
        st = mechrt_velocity_acceleration(&st_kernels, NULL, q, tn, qd, qdd, work,
                                          sizeof work / sizeof work[0], NULL);
        MARK(i, mark_off);
#ifdef STEP_COUNT
        if (i > 0) {
            plain_ticks += (c0 - c1) & SYST_MAX;
            pred_ticks += (c1 - c2) & SYST_MAX;
            va_ticks += TICKS_SINCE(c2);
        }
#endif
        if (st != MECHRT_OK) {
            printf("error: t = %.*g: velocity and acceleration: %s\n", DIGITS, (double)tn,
                   mechrt_strerror(st));
            return 1;
        }
        t = tn;
        err = pose_error(plain, (double)t);
        if (pose_error(q, (double)t) > err)
            err = pose_error(q, (double)t);
        if (err > worst)
            worst = err;
        if (i % PRINT_EVERY == 0)
            printf("%d %.*g %.*g %.*g %.*g %.*g %.*g %.*g %.*g %.*g %.*g\n", i,
                   DIGITS, (double)t, DIGITS, (double)q[0], DIGITS, (double)q[1],
                   DIGITS, (double)q[2], DIGITS, (double)q[3], DIGITS, (double)q[4],
                   DIGITS, (double)q[5], DIGITS, (double)q[6], DIGITS, (double)qd[0],
                   DIGITS, (double)qdd[2]);
    }
    if (worst > POSE_TOL) {
        printf("error: a pose is %g off the closed-form trajectory (more than %g)\n", worst,
               POSE_TOL);
        return 1;
    }
    printf("# done: %d steps; Newton iterations %ld from the previous pose, %ld with the "
           "predictor; every pose within %g of the trajectory\n",
           STEPS, it_plain, it_pred, POSE_TOL);
#ifdef STEP_COUNT
    printf("# step: about %lu instructions per forward-kinematics solve from the previous pose\n",
           40 * plain_ticks / STEPS);
    printf("# step: about %lu instructions per forward-kinematics solve with the predictor\n",
           40 * pred_ticks / STEPS);
    printf("# step: about %lu instructions per velocity and acceleration analysis\n",
           40 * va_ticks / STEPS);
#endif
    return 0;
}
