/* common.h - what the analyses over time (run, sim, check) share: the linear-algebra choice, the failure message. */
#ifndef MECHC_ANALYSIS_COMMON_H
#define MECHC_ANALYSIS_COMMON_H

#include <stddef.h>

/* Appends printf-style text to the message msg (size bytes, NUL-terminated),
   truncating quietly at its size: a failure's message is built in parts. */
void analysis_msgf(char *msg, size_t size, const char *fmt, ...) __attribute__((format(printf, 3, 4)));

#endif
