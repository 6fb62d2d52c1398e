/* sincos.h - the generated code's sin-and-cos (templates/sincos.tmpl), built into the tool. */
#ifndef MECHC_SINCOS_H
#define MECHC_SINCOS_H

/* sin x and cos x, within 2.5 ulp of the exact values. The JIT's kernels call
   it (symbol "mechc_sincos") and the generic evaluator uses it, so that
   every engine computes the same trigonometry. */
void mechc_sincos(double x, double *s, double *c);

/* Two angles at once, with the results of two mechc_sincos calls. */
void mechc_sincos2(double x0, double x1, double *s0, double *c0, double *s1, double *c1);

#endif
