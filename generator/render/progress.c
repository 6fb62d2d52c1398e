/* progress.c - a one-line progress bar redrawn in place with '\r'.
 *
 * "run [##########..........]  50%  5000/10000  2.1 s left", cleared with
 * "\r\033[K" (erase to end of line: every terminal mechc meets knows it).
 * The remaining time is the elapsed time scaled by what is left, shown once
 * a tenth of the work is done.
 */
#include "progress.h"

#include <stdlib.h>
#include <string.h>
#include <sys/ioctl.h>
#include <time.h>
#include <unistd.h>

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

void progress_start_on(Progress *p, FILE *out, bool enabled, const char *label, long total)
{
    memset(p, 0, sizeof *p);
    p->out = enabled ? out : NULL;
    p->label = label ? label : "";
    p->total = total;
    p->start = now();
    p->last_check = p->start;
    p->delay = 1.0;
    p->interval = 0.1;
    p->stride = 1;
    p->countdown = 1;
    p->width = 80;
}

void progress_start(Progress *p, const char *label, long total)
{
    const char *term = getenv("TERM");
    bool tty = isatty(STDERR_FILENO) && !(term && strcmp(term, "dumb") == 0);
    progress_start_on(p, stderr, tty, label, total);
    if (tty) {
        struct winsize ws;
        if (ioctl(STDERR_FILENO, TIOCGWINSZ, &ws) == 0 && ws.ws_col >= 20)
            p->width = ws.ws_col;
    }
}

static void draw(Progress *p, long done, double t)
{
    char line[512];
    double elapsed = t - p->start;
    int n;
    if (p->total > 0) {
        double frac = (double)done / (double)p->total;
        if (frac < 0)
            frac = 0;
        if (frac > 1)
            frac = 1;
        char left[48] = "";
        if (frac >= 0.1 && frac < 1)
            snprintf(left, sizeof left, "  %.1f s left", elapsed * (1 - frac) / frac);
        char counts[64];
        snprintf(counts, sizeof counts, "%3d%%  %ld/%ld%s", (int)(100 * frac), done, p->total, left);
        /* the bar takes what the label and the counts leave, 10..50 columns */
        int bar = p->width - 1 - (int)strlen(p->label) - 4 - (int)strlen(counts);
        if (bar > 50)
            bar = 50;
        if (bar < 10)
            bar = 10;
        char cells[64];
        int full = (int)(frac * bar + 0.5);
        for (int i = 0; i < bar; i++)
            cells[i] = i < full ? '#' : '.';
        cells[bar] = '\0';
        n = snprintf(line, sizeof line, "%s [%s] %s", p->label, cells, counts);
    } else {
        n = snprintf(line, sizeof line, "%s: %ld done, %.1f s", p->label, done, elapsed);
    }
    if (n >= p->width)          /* never wrap: a wrapped line cannot be redrawn */
        line[p->width > 1 ? p->width - 1 : 0] = '\0';
    fprintf(p->out, "\r%s\033[K", line);
    fflush(p->out);
    p->drawn = true;
    p->last_draw = t;
}

void progress_update(Progress *p, long done)
{
    if (!p->out || --p->countdown > 0)
        return;
    double t = now();
    /* calls faster than a millisecond apart: read the clock less often */
    if (t - p->last_check < 1e-3 && p->stride < (1L << 20))
        p->stride *= 2;
    else if (t - p->last_check > 0.05 && p->stride > 1)     /* slower now */
        p->stride /= 2;
    p->countdown = p->stride;
    p->last_check = t;
    if (t - p->start < p->delay)
        return;
    if (p->drawn && t - p->last_draw < p->interval)
        return;
    draw(p, done, t);
}

void progress_finish(Progress *p)
{
    if (p->out && p->drawn) {
        fputs("\r\033[K", p->out);
        fflush(p->out);
    }
    p->drawn = false;
    p->out = NULL;
}
