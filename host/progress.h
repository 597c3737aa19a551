/* A progress bar on a terminal: fraction done, rays, elapsed time, ETA and Mrays/s,
 * redrawn in place at most every 100 ms and cleared at the end. */
#ifndef CW_PROGRESS_H
#define CW_PROGRESS_H

#include <stddef.h>
#include <stdio.h>

typedef struct {
    FILE *out;
    int enabled;
    int columns;     /* terminal width */
    double t0;       /* start of the render (progress_begin) */
    double last;     /* time of the last redraw; < 0: none yet */
    double interval; /* least time between redraws in seconds (0.1) */
    size_t drawn;    /* characters now on the line (0: the line is clear) */
    int log;         /* log lines instead of a bar: never redrawn in place */
} progress_bar;

/* Progress modes (CLWHITTED_PROGRESS). */
#define PROGRESS_AUTO 0   /* unset or "auto": a bar when the output is a terminal */
#define PROGRESS_ALWAYS 1 /* "always" or "1": a bar even when it is not */
#define PROGRESS_NEVER 2  /* "never" or "0" */
#define PROGRESS_LOG 3    /* "log": a plain line every CW_PROGRESS_LOG_S seconds */
/* The mode of CLWHITTED_PROGRESS's value (NULL or "": auto), or -1 if it is none. */
int progress_mode_parse(const char *env);

/* What to show: 0 (nothing), 1 (the bar) or PROGRESS_LOG (lines): nothing with --quiet;
 * else by mode, auto showing the bar only when the output is a terminal. */
int progress_wanted(int quiet, int mode, int is_tty);

/* Prepares a bar on `out` (shown only when enabled; enabled == PROGRESS_LOG: log lines).
 * Nothing is drawn yet. */
void progress_init(progress_bar *p, FILE *out, int enabled);
/* Shows a one-line status message (e.g. while kernels compile) until the next draw. */
void progress_status(progress_bar *p, const char *msg);
/* Starts the clock of the render. */
void progress_begin(progress_bar *p);
/* A render_progress_fn (render.h): ctx is the progress_bar. Never cancels. */
int progress_update(void *ctx, double fraction, unsigned long long rays);
/* Clears the line (call before printing anything else and at the end). */
void progress_clear(progress_bar *p);

/* Formats the bar line, at most columns-1 characters:
 * "[#####-----]  45%  1.23 Mrays  0:03 elapsed  ETA 0:04  2.10 Mrays/s". */
void progress_format(char *buf, size_t n, int columns, double fraction, unsigned long long rays,
                     double elapsed);
/* A rate in Mrays/s: two decimals, four below 0.1 (slow renders are not all "0.00"). */
void progress_format_rate(char *buf, size_t n, double mrays_per_s);
/* "m:ss", or "h:mm:ss" from an hour on. */
void progress_format_time(char *buf, size_t n, double seconds);

#endif
