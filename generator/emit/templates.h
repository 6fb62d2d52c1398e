/* templates.h - the templates (templates/NAME.tmpl), embedded by the Makefile as C strings. */
#ifndef MECHC_TEMPLATES_H
#define MECHC_TEMPLATES_H

extern const char template_all[];
extern const char template_all_decl[];
extern const char template_all_nz[];
extern const char template_all_nz_decl[];
extern const char template_design[];
extern const char template_design_h[];
extern const char template_dynamics[];
extern const char template_dynamics_h[];
extern const char template_interface[];
extern const char template_jac_decl[];
extern const char template_jac_direct[];
extern const char template_jac_spread[];
extern const char template_mech_c[];
extern const char template_mech_h[];
extern const char template_sparse_only[];
extern const char template_sincos[];
extern const char template_sincos2[];
extern const char template_sincos_lane[];
extern const char template_trig[];

#endif
