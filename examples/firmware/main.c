/* main.c - a firmware-style kinematic loop over mechc-generated kernels.
 *
 * Turns the slider-crank of examples/slider_crank.mech through one crank
 * revolution in STEPS equal time steps (assembly at t = 0, then predictor,
 * Newton corrector, velocity and acceleration per step, all in
 * mechrt_step_lup, whose LU is the kernels' own: sc_lu_factor and
 * sc_lu_solve of `mechc gen --lu`, unrolled for the Jacobian's pattern,
 * with the runtime's pattern LU where their pivot checks decline; built
 * with -DPATTERN_LU_ONLY, the pattern LU alone) and prints, every
 * PRINT_EVERY steps, the step number, t and
 * the slider's position, velocity and acceleration along the guide.
 *
 * What makes it firmware-like: the kernels (sc.c, sc.h) come from
 * `mechc gen examples/slider_crank.mech --prefix sc --lu [--real float]` at build
 * time, the runtime core (the .c files of runtime/) is compiled
 * next to them, and every array lives in static storage sized at compile
 * time: no heap, no recursion, no library call in the numerical code. The
 * only I/O is printf, which newlib sends through semihosting on the target
 * (--specs=rdimon.specs) and the C library to stdout on a host, so the same
 * file builds both ways and the outputs can be compared line by line
 * (compare.awk).
 *
 * Build the kernels and this file with the same real type: `--real float`
 * goes with -DMECHRT_REAL_FLOAT (checked below at compile time).
 */
#include <stdio.h>

#include "sc.h"
#include "mechrt.h"

/* The generated real type and the runtime's must agree. */
typedef char sc_real_matches_mechrt_real[sizeof(sc_real) == sizeof(mechrt_real) ? 1 : -1];

/* Defines `static const MechrtKernels sc_kernels` over sc_phi, sc_jac, ...
   and `static const MechrtJacNz sc_jac_nz_kernel` over sc_jac_nz. */
MECHRT_DEFINE_KERNELS(sc, SC);
MECHRT_DEFINE_JAC_NZ(sc, SC);
/* `static const MechrtLuGen sc_lu` over sc_lu_factor and sc_lu_solve. */
MECHRT_DEFINE_LU(sc, SC);

enum {
    STEPS = 200,      /* time steps over one revolution, t = 0 .. PERIOD */
    PRINT_EVERY = 20  /* print every PRINT_EVERY-th step */
};
#define PERIOD MECHRT_R(1.0) /* s: omega = 2 pi rad/s in slider_crank.mech */

/* Digits that read back exactly: 17 for double, 9 for float. */
#ifdef MECHRT_REAL_FLOAT
#define DIGITS 9
#else
#define DIGITS 17
#endif

/* Built with -DSTEP_COUNT (the `count` target of the Makefile, Cortex-M
   only): SysTick, clocked by the core, times every mechrt_step_lup call after
   the first, and the program prints the mean at the end. Under QEMU with
   -icount shift=0 every instruction takes 1 ns of virtual time and the
   MPS2 core clock is 25 MHz, so one tick is 40 instructions, exactly and
   on every run: an instruction count of the step on the emulated core. */
#ifdef STEP_COUNT
#define SYST_CSR (*(volatile unsigned long *)0xE000E010UL)
#define SYST_RVR (*(volatile unsigned long *)0xE000E014UL)
#define SYST_CVR (*(volatile unsigned long *)0xE000E018UL)
#define SYST_MAX 0xFFFFFFUL /* a 24-bit down counter */
#endif

/* All the memory the loop uses, reserved at link time (.bss): the step's
   workspace, and the pattern LU's state and workspaces (its pivot order,
   recorded at the first step, is replayed by the others). */
static mechrt_real work[MECHRT_WORKSPACE_LEN(SC_NQ, SC_NR)];
static MechrtLup lup;
static mechrt_real lup_work[MECHRT_LUP_WORK_LEN(SC_NQ)];
static int lup_iwork[MECHRT_LUP_IWORK_LEN(SC_NQ)];
static mechrt_real q[SC_NQ], qd[SC_NQ], qdd[SC_NQ];

/* Index of the coordinate called name, or -1: the program looks the
   slider's coordinate up by name so it survives a reordered .mech file. */
static int coord_index(const char *name)
{
    int i, k;

    for (i = 0; i < SC_NQ; i++) {
        const char *s = sc_coord_names[i];
        for (k = 0; s[k] != '\0' && s[k] == name[k]; k++)
            ;
        if (s[k] == '\0' && name[k] == '\0')
            return i;
    }
    return -1;
}

int main(void)
{
    MechrtOptions opts = mechrt_default_options();
    MechrtReport report;
    MechrtStatus st;
    mechrt_real t = 0;
    long newton_iterations = 0;
    int i, x = coord_index("slider.x");

    if (x < 0) {
        printf("error: no coordinate slider.x\n");
        return 1;
    }
    st = mechrt_lup_init(&lup, SC_NQ, SC_NNZ, sc_jac_row, sc_jac_col, lup_work,
                         sizeof lup_work / sizeof lup_work[0], lup_iwork,
                         sizeof lup_iwork / sizeof lup_iwork[0]);
#ifndef PATTERN_LU_ONLY
    if (st == MECHRT_OK)
        st = mechrt_lup_use(&lup, &sc_lu);
#else
    (void)sc_lu;
#endif
    if (st != MECHRT_OK) {
        printf("error: %s\n", mechrt_strerror(st));
        return 1;
    }
    for (i = 0; i < SC_NQ; i++) {
        q[i] = sc_q0[i];
        qd[i] = 0;
        qdd[i] = 0;
    }
    printf("# mechc firmware example: slider_crank, %s, %d steps\n",
           sizeof(mechrt_real) == sizeof(float) ? "float" : "double", STEPS);
    printf("# step t slider.x d(slider.x) dd(slider.x)\n");
#ifdef STEP_COUNT
    unsigned long ticks = 0;
    SYST_RVR = SYST_MAX;
    SYST_CVR = 0;
    SYST_CSR = 5;   /* enable, core clock, no interrupt */
#endif
    for (i = 0; i <= STEPS; i++) {
        /* Step 0 (h = 0) assembles and analyses at t = 0. */
        mechrt_real tn = PERIOD * (mechrt_real)i / (mechrt_real)STEPS;
#ifdef STEP_COUNT
        unsigned long c0 = SYST_CVR;
#endif
        st = mechrt_step_lup(&sc_kernels, &sc_jac_nz_kernel, &lup, &opts, q, qd, qdd, t,
                             tn - t, work, sizeof work / sizeof work[0], &report);
#ifdef STEP_COUNT
        if (i > 0)
            ticks += (c0 - SYST_CVR) & SYST_MAX;
#endif
        if (st != MECHRT_OK) {
            printf("error: t = %.*g: %s\n", DIGITS, (double)tn, mechrt_strerror(st));
            return 1;
        }
        t = tn;
        newton_iterations += report.iterations;
        if (i % PRINT_EVERY == 0)
            printf("%d %.*g %.*g %.*g %.*g\n", i, DIGITS, (double)t, DIGITS, (double)q[x],
                   DIGITS, (double)qd[x], DIGITS, (double)qdd[x]);
    }
    printf("# done: %d steps, %ld Newton iterations\n", STEPS, newton_iterations);
#ifdef STEP_COUNT
    printf("# step: %lu SysTick ticks per step (40 instructions each under -icount shift=0)\n",
           ticks / STEPS);
    printf("# step: about %lu instructions per step\n", 40 * ticks / STEPS);
#endif
    return 0;
}
