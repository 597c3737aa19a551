/* Progress bar on stderr. See progress.h. */
#include "progress.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include <sys/ioctl.h>
#include <unistd.h>

#include "config.h"
#include "sys.h"

#define REDRAW_S 0.1 /* at most ten redraws a second */
#define BAR_MIN 10
#define BAR_MAX 40

int progress_mode_parse(const char *env)
{
    if (!env || !*env || strcmp(env, "auto") == 0)
        return PROGRESS_AUTO;
    if (strcmp(env, "always") == 0 || strcmp(env, "1") == 0)
        return PROGRESS_ALWAYS;
    if (strcmp(env, "never") == 0 || strcmp(env, "0") == 0)
        return PROGRESS_NEVER;
    if (strcmp(env, "log") == 0)
        return PROGRESS_LOG;
    return -1;
}

int progress_wanted(int quiet, int mode, int is_tty)
{
    if (quiet || mode == PROGRESS_NEVER)
        return 0;
    if (mode == PROGRESS_LOG)
        return PROGRESS_LOG;
    return mode == PROGRESS_ALWAYS || is_tty != 0;
}

static int terminal_columns(FILE *out)
{
    struct winsize ws;
    const char *env = getenv("COLUMNS");
    if (ioctl(fileno(out), TIOCGWINSZ, &ws) == 0 && ws.ws_col >= 20)
        return ws.ws_col;
    if (env && atoi(env) >= 20)
        return atoi(env);
    return 80;
}

void progress_init(progress_bar *p, FILE *out, int enabled)
{
    memset(p, 0, sizeof *p);
    p->out = out;
    p->enabled = enabled && out;
    p->log = p->enabled && enabled == PROGRESS_LOG;
    p->columns = p->enabled && !p->log ? terminal_columns(out) : 80;
    p->t0 = sys_now();
    p->last = -1.0;
    p->interval = p->log ? CW_PROGRESS_LOG_S : REDRAW_S;
}

/* Replaces the line with `text`, padding over what was there. */
static void draw(progress_bar *p, const char *text)
{
    size_t len = strlen(text);
    fprintf(p->out, "\r%s", text);
    if (p->drawn > len)
        fprintf(p->out, "%*s\r%s", (int)(p->drawn - len), "", text);
    fflush(p->out);
    p->drawn = len;
    sys_signal_line(fileno(p->out), len);
}

void progress_status(progress_bar *p, const char *msg)
{
    char line[512];
    size_t max;
    if (!p->enabled || p->log)
        return;
    max = (size_t)p->columns - 1 < sizeof line ? (size_t)p->columns - 1 : sizeof line - 1;
    snprintf(line, max + 1, "%s", msg);
    draw(p, line);
}

void progress_begin(progress_bar *p)
{
    p->t0 = sys_now();
    p->last = -1.0;
}

void progress_format_rate(char *buf, size_t n, double mrays_per_s)
{
    if (!(mrays_per_s > 0)) /* also NaN */
        mrays_per_s = 0;
    snprintf(buf, n, mrays_per_s > 0 && mrays_per_s < 0.1 ? "%.4f" : "%.2f", mrays_per_s);
}

void progress_format_time(char *buf, size_t n, double seconds)
{
    long s = seconds > 0 ? (long)floor(seconds + 0.5) : 0;
    if (s >= 3600)
        snprintf(buf, n, "%ld:%02ld:%02ld", s / 3600, s / 60 % 60, s % 60);
    else
        snprintf(buf, n, "%ld:%02ld", s / 60, s % 60);
}

/* Copies as much of s as fits into buf[*used..n-1], keeping buf NUL-terminated. */
static void append(char *buf, size_t n, size_t *used, const char *s, size_t max)
{
    while (*s && max-- > 0 && *used + 1 < n)
        buf[(*used)++] = *s++;
    buf[*used] = '\0';
}

void progress_format(char *buf, size_t n, int columns, double fraction, unsigned long long rays,
                     double elapsed)
{
    char text[160], el[32], eta[32], rate[32];
    int bar, filled, i;
    size_t used = 0, width = columns > 1 ? (size_t)columns - 1 : 0;

    if (n == 0)
        return;
    buf[0] = '\0';
    if (!(fraction > 0)) /* also NaN */
        fraction = 0;
    if (fraction > 1)
        fraction = 1;
    if (!(elapsed > 0))
        elapsed = 0;
    progress_format_time(el, sizeof el, elapsed);
    if (fraction > 0)
        progress_format_time(eta, sizeof eta, elapsed * (1 - fraction) / fraction);
    else
        snprintf(eta, sizeof eta, "--:--");
    if (elapsed > 0)
        progress_format_rate(rate, sizeof rate, (double)rays / elapsed * 1e-6);
    else
        snprintf(rate, sizeof rate, "--");
    snprintf(text, sizeof text, "%3d%%  %.2f Mrays  %s elapsed  ETA %s  %s Mrays/s",
             (int)floor(fraction * 100), (double)rays * 1e-6, el, eta, rate);

    /* "[bar] text" when there is room for a bar of BAR_MIN, else the text alone; never
     * more than `width` characters. */
    bar = (int)width - (int)strlen(text) - 3;
    if (bar > BAR_MAX)
        bar = BAR_MAX;
    if (bar >= BAR_MIN) {
        filled = (int)floor(fraction * bar);
        append(buf, n, &used, "[", 1);
        for (i = 0; i < bar; i++)
            append(buf, n, &used, i < filled ? "#" : "-", 1);
        append(buf, n, &used, "] ", 2);
    }
    append(buf, n, &used, text, width - used);
}

int progress_update(void *ctx, double fraction, unsigned long long rays)
{
    progress_bar *p = ctx;
    char line[512];
    double t;
    if (!p || !p->enabled)
        return 0;
    t = sys_now();
    if (p->last >= 0 && t - p->last < p->interval)
        return 0;
    if (p->log && p->last < 0) { /* the first line after CW_PROGRESS_LOG_S, not at 0 % */
        p->last = t;
        return 0;
    }
    p->last = t;
    if (p->log) {
        char text[160];
        progress_format(text, sizeof text, 1 << 20, fraction, rays, t - p->t0);
        fprintf(p->out, "clwhitted: %s\n", strchr(text, ']') ? strchr(text, ']') + 2 : text);
        fflush(p->out);
        return 0;
    }
    progress_format(line, sizeof line, p->columns, fraction, rays, t - p->t0);
    draw(p, line);
    return 0;
}

void progress_clear(progress_bar *p)
{
    if (!p->enabled || p->drawn == 0)
        return;
    fprintf(p->out, "\r%*s\r", (int)p->drawn, "");
    fflush(p->out);
    p->drawn = 0;
    sys_signal_line(-1, 0);
}
