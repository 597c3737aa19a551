/* The NFF reader's lines (see scene_nff_lex.h): one pass over each line that finds the
 * tokens, NUL-terminates them in place and converts the plain decimals among them.
 *
 * Numbers are most of an NFF file, and strtod was most of the reading time. A token such
 * as "-0.166760" or "2.5e3" is converted here while it is scanned: its digits form an
 * integer m (at most 19 significant digits) and a power of ten e. When m <= 2^53 and
 * |e| <= 22, both m and 10^|e| are exact doubles, so one IEEE multiplication or division
 * gives the correctly rounded value of the decimal: the value strtod (correctly rounded,
 * glibc) gives (Clinger's fast path). Anything else (more digits, larger exponents, hex,
 * inf, nan, words, malformed numbers) is left to strtod and its messages in scene_nff.c.
 *
 * A file is read in pieces into a window (CW_NFF_READ_CHUNK bytes at a time), not whole:
 * each piece is parsed while it is in the cache, and a large scene never has its whole text
 * in memory. The lines that start before `whole` are complete in the window; the next line
 * from there makes the window move on. The messages stay those of reading the whole file
 * first (nff_lex_finish): a NUL byte anywhere is reported with its line even when a parse
 * error comes before it. */
#include "scene_nff_lex.h"

#include <float.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

/* The fast path needs double arithmetic evaluated in double (not x87 extended). */
#if defined(FLT_EVAL_METHOD) && FLT_EVAL_METHOD == 0
#define LEX_FAST 1
#else
#define LEX_FAST 0
#endif

enum { C_TOKEN = 0, C_BLANK, C_END, C_HASH };

/* The class of each byte: blank, end of line ('\n', or the '\0' at the end of the text),
 * '#', or part of a token. */
static const unsigned char char_class[256] = {
    ['\0'] = C_END,   ['\n'] = C_END,   [' '] = C_BLANK,  ['\t'] = C_BLANK,
    ['\r'] = C_BLANK, ['\f'] = C_BLANK, ['\v'] = C_BLANK, ['#'] = C_HASH,
};

static const double pow10_exact[23] = {1e0,  1e1,  1e2,  1e3,  1e4,  1e5,  1e6,  1e7,
                                       1e8,  1e9,  1e10, 1e11, 1e12, 1e13, 1e14, 1e15,
                                       1e16, 1e17, 1e18, 1e19, 1e20, 1e21, 1e22};

#define LEX_MAX_DIGITS 19  /* digits an uint64_t always holds */
#define LEX_MAX_EXP 100000 /* exponent digits stop counting here (far beyond any fast case) */

#if defined(__GNUC__)
#define LEX_INLINE static inline __attribute__((always_inline))
#else
#define LEX_INLINE static inline
#endif

LEX_INLINE int is_token(unsigned char c)
{
    return char_class[c] == C_TOKEN;
}

LEX_INLINE unsigned digit(char c)
{
    return (unsigned)((unsigned char)c - '0'); /* 10 or more: not a digit */
}

/* The run of digits at *pp appended to m (m * 10^k + run, wrapping around past 19 digits);
 * *pp moves past the run. (Eight digits at a time with SWAR arithmetic measured slower.) */
LEX_INLINE uint64_t digit_run(char **pp, uint64_t m)
{
    char *p = *pp;
    unsigned d;
    for (; (d = digit(*p)) < 10; p++)
        m = m * 10 + d;
    *pp = p;
    return m;
}

/* Scans the token at p (a token byte) to its end: the first blank, end of line or '#'.
 * Sets *fast (and *val) when the token is a plain decimal the fast path converts. Every
 * digit goes into m (leading zeros too); more than LEX_MAX_DIGITS digits in all may have
 * wrapped m around, and leave the token to strtod. */
LEX_INLINE char *scan_token(char *p, double *val, int *fast)
{
    uint64_t m = 0;
    long ndig, frac = 0, e10;
    int neg = 0, ex = 0, eneg = 0;
    unsigned d;
    char *start;
    double v;

    *fast = 0;
    *val = 0.0;
    if (*p == '-' || *p == '+')
        neg = *p++ == '-';
    start = p;
    m = digit_run(&p, m);
    ndig = p - start;
    if (*p == '.') {
        start = ++p;
        m = digit_run(&p, m);
        frac = p - start;
        ndig += frac;
    }
    if (ndig == 0)
        goto slow;
    if (*p == 'e' || *p == 'E') {
        char *q = p + 1;
        if (*q == '-' || *q == '+')
            eneg = *q++ == '-';
        if (digit(*q) >= 10)
            goto slow;
        for (; (d = digit(*q)) < 10; q++)
            if (ex < LEX_MAX_EXP)
                ex = ex * 10 + (int)d;
        p = q;
    }
    if (is_token((unsigned char)*p))
        goto slow;
    if (!LEX_FAST || ndig > LEX_MAX_DIGITS)
        return p;
    e10 = (eneg ? -(long)ex : (long)ex) - frac;
    if (m == 0) {
        v = 0.0;
    } else {
        if (m > (uint64_t)1 << 53 || e10 < -22 || e10 > 22)
            return p;
        v = (double)m;
        v = e10 < 0 ? v / pow10_exact[-e10] : v * pow10_exact[e10];
    }
    *val = neg ? -v : v;
    *fast = 1;
    return p;
slow:
    while (is_token((unsigned char)*p))
        p++;
    return p;
}

static long newlines(const char *p, const char *end)
{
    long n = 0;
    for (; p < end; p++)
        n += *p == '\n';
    return n;
}

void nff_lex_init(nff_lex *lx, char *text, size_t len)
{
    memset(lx, 0, sizeof *lx);
    lx->cur = text;
    lx->end = lx->whole = text + len;
}

/* Moves the window on: keeps the unread text from cur, then reads until a line is whole
 * (a newline in what was read) or the file ends. Returns 0, or -1 when the text ends early
 * (lx->stop). */
static int refill(nff_lex *lx)
{
    size_t keep = (size_t)(lx->end - lx->cur);
    memmove(lx->buf, lx->cur, keep);
    lx->cur = lx->whole = lx->buf;
    lx->end = lx->buf + keep;
    for (;;) {
        size_t n, used = keep;
        char *fresh, *q;
        if (lx->cap - used - 1 < lx->chunk) { /* a line longer than the window */
            size_t cap = used + lx->chunk + 1 > 2 * lx->cap ? used + lx->chunk + 1 : 2 * lx->cap;
            char *nb = realloc(lx->buf, cap);
            if (!nb) {
                lx->stop = NFF_LEX_FAILED;
                return sys_file_oom(lx->file);
            }
            lx->buf = lx->cur = lx->whole = nb;
            lx->end = nb + used;
            lx->cap = cap;
        }
        fresh = lx->end;
        n = sys_file_read(lx->file, fresh, lx->chunk);
        if (n == 0) {
            if (lx->file->failed) {
                lx->stop = NFF_LEX_FAILED;
                return -1;
            }
            lx->eof = 1;
            lx->whole = lx->end;
            *lx->end = '\0';
            return 0;
        }
        lx->end += n;
        *lx->end = '\0';
        keep += n;
        if ((q = memchr(fresh, '\0', n))) {
            lx->stop = NFF_LEX_NUL;
            lx->nul_line = lx->line + 1 + newlines(lx->cur, q);
            return -1;
        }
        for (q = lx->end; q > fresh && q[-1] != '\n'; q--)
            ;
        if (q > fresh) {
            lx->whole = q;
            return 0;
        }
    }
}

int nff_lex_open(nff_lex *lx, sys_file *f, size_t chunk)
{
    memset(lx, 0, sizeof *lx);
    lx->file = f;
    lx->chunk = chunk > 0 ? chunk : 1;
    lx->cap = 2 * lx->chunk + 1;
    lx->buf = malloc(lx->cap);
    if (!lx->buf)
        return sys_file_oom(f);
    lx->cur = lx->end = lx->whole = lx->buf;
    *lx->end = '\0';
    if (refill(lx) == 0) /* the first line is whole: skip a byte order mark */
        lx->cur += scene_bom_len(lx->cur, (size_t)(lx->end - lx->cur));
    return 0;
}

/* After a parse error: reads the rest of the file for a NUL byte, which the whole-file
 * reader would have reported instead. */
static int drain(nff_lex *lx, const scene_msg *m, int rc)
{
    long lines = lx->line + 1; /* the line that starts at cur */
    if (lx->cur < lx->end)
        lines += newlines(lx->cur, lx->end);
    while (!lx->eof) {
        size_t n = sys_file_read(lx->file, lx->buf, lx->cap - 1);
        char *q;
        if (n == 0)
            return lx->file->failed ? -1 : rc;
        if ((q = memchr(lx->buf, '\0', n)))
            return scene_fail_nul(m, lines + newlines(lx->buf, q));
        lines += newlines(lx->buf, lx->buf + n);
    }
    return rc;
}

int nff_lex_finish(nff_lex *lx, int rc, const scene_msg *m)
{
    if (!lx->file)
        return rc;
    if (lx->stop == NFF_LEX_FAILED)
        rc = -1; /* the message is in err */
    else if (lx->stop == NFF_LEX_NUL)
        rc = scene_fail_nul(m, lx->nul_line);
    else if (rc != 0)
        rc = drain(lx, m, rc);
    free(lx->buf);
    lx->buf = NULL;
    return rc;
}

int nff_lex_next_line(nff_lex *lx)
{
    char *p = lx->cur;
    int n = 0;
    if (p >= lx->whole) {
        if (lx->stop || (lx->file && !lx->eof && refill(lx) != 0))
            return 0;
        p = lx->cur;
        if (p >= lx->end)
            return 0;
    }
    lx->line++;
    for (;;) {
        unsigned char c;
        while (char_class[c = (unsigned char)*p] == C_BLANK)
            p++;
        if (char_class[c] != C_TOKEN)
            break; /* end of line, or a comment */
        {
            char *t = p;
            double v;
            int fast;
            p = scan_token(p, &v, &fast);
            if (n < NFF_MAX_TOKENS) {
                lx->tok[n] = t;
                lx->val[n] = v;
                lx->fast[n] = (unsigned char)fast;
            }
            n++;
        }
        if (char_class[(unsigned char)*p] != C_BLANK)
            break;
        *p++ = '\0';
    }
    lx->ntok = n;
    if (*p == '#') { /* a comment: the line ends at the next newline */
        char *eol;
        *p = '\0';
        eol = memchr(p + 1, '\n', (size_t)(lx->end - (p + 1)));
        p = eol ? eol : lx->end;
    }
    *p = '\0'; /* at the newline, or the end of the text (already '\0') */
    lx->cur = p + 1;
    return 1;
}

int nff_lex_decimal(const char *s, double *out)
{
    double v;
    int fast;
    const char *end;
    if (!is_token((unsigned char)*s))
        return 0;
    end = scan_token((char *)s, &v, &fast); /* scan_token only reads */
    if (!fast || *end != '\0')
        return 0;
    *out = v;
    return 1;
}
