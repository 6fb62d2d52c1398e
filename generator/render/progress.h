/* progress.h - a progress bar on stderr for long runs and benches, only on a terminal. */
#ifndef MECHC_PROGRESS_H
#define MECHC_PROGRESS_H

#include <stdbool.h>
#include <stdio.h>

/* Shows nothing during the first second (short commands stay quiet), then
   redraws one line at most ten times a second, and clears it at the end.
   Silent when stderr is not a terminal, so logs and pipes stay clean.
   Updates are cheap: the clock is read only every `stride` calls, the
   stride growing while calls come faster than every millisecond. */
typedef struct Progress {
    FILE *out;              /* NULL: disabled */
    const char *label;      /* "run", "bench" */
    long total;             /* <= 0: unknown (a count, no bar) */
    double start;           /* monotonic seconds */
    double last_draw;
    double delay;           /* seconds before the first draw; default 1 */
    double interval;        /* seconds between draws; default 0.1 */
    long stride, countdown; /* clock reads every stride updates */
    double last_check;
    int width;              /* terminal columns */
    bool drawn;             /* something is on the line */
} Progress;

/* Starts a bar on stderr if it is a terminal (and TERM is not "dumb"). */
void progress_start(Progress *p, const char *label, long total);
/* The same on any stream, enabled or not: for tests and for callers that
   decide themselves (delay and interval may be changed after this call). */
void progress_start_on(Progress *p, FILE *out, bool enabled, const char *label, long total);
/* done of total units are finished. */
void progress_update(Progress *p, long done);
/* Clears the line if anything was drawn. */
void progress_finish(Progress *p);

#endif
