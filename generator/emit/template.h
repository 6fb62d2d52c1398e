/* template.h - fills @NAME@ placeholders of an embedded template. */
#ifndef MECHC_TEMPLATE_H
#define MECHC_TEMPLATE_H

#include "../base/strbuf.h"

typedef struct TemplateVar {
    const char *name;       /* without the @ signs */
    const char *value;
} TemplateVar;

/* Appends tmpl to out with every @NAME@ replaced, without a first line
   that starts with "@@" (the template's own one-line header). A
   placeholder with no value is a bug in mechc: returns its name so the
   caller can report it. */
const char *template_render(StrBuf *out, const char *tmpl, const TemplateVar *vars, int nvars);

/* Gives the variable called name its value. A name not in vars is a bug
   in mechc: aborts. */
void template_set(TemplateVar *vars, int nvars, const char *name, const char *value);

/* Every placeholder of a template is given a value: one without (a name
   template_render returned) is a bug in mechc; says so and aborts. */
_Noreturn void template_placeholder_bug(const char *name);

#endif
