/* What the scene readers share: messages, printable text, the text to parse. See
 * scene_io.h. */
#include "scene_io.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "config.h"
#include "sys.h"

int scene_vfail(const scene_msg *m, long line, const char *fmt, va_list ap)
{
    int n;
    if (!m->err || m->errlen == 0)
        return -1;
    n = snprintf(m->err, m->errlen, "%s:%ld: ", m->name, line > 0 ? line : 1);
    if (n >= 0 && (size_t)n < m->errlen)
        vsnprintf(m->err + n, m->errlen - (size_t)n, fmt, ap);
    return -1;
}

int scene_fail(const scene_msg *m, long line, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    scene_vfail(m, line, fmt, ap);
    va_end(ap);
    return -1;
}

long scene_line_at(const char *text, const char *at)
{
    long line = 1;
    for (; text < at; text++)
        line += *text == '\n';
    return line;
}

size_t scene_bom_len(const char *buf, size_t len)
{
    return len >= 3 && memcmp(buf, "\xEF\xBB\xBF", 3) == 0 ? 3 : 0;
}

/* The length of the UTF-8 sequence at u (at most avail bytes), or 0 when it is not one or
 * encodes a C1 control character. */
static size_t utf8_sequence(const unsigned char *u, size_t avail)
{
    unsigned char lo = 0x80, hi = 0xBF;
    size_t n, k;
    if (u[0] >= 0xC2 && u[0] <= 0xDF)
        n = 2;
    else if (u[0] >= 0xE0 && u[0] <= 0xEF)
        n = 3;
    else if (u[0] >= 0xF0 && u[0] <= 0xF4)
        n = 4;
    else
        return 0;
    if (u[0] == 0xC2)
        lo = 0xA0; /* U+0080..U+009F: C1 controls */
    else if (u[0] == 0xE0)
        lo = 0xA0; /* overlong */
    else if (u[0] == 0xED)
        hi = 0x9F; /* surrogates */
    else if (u[0] == 0xF0)
        lo = 0x90; /* overlong */
    else if (u[0] == 0xF4)
        hi = 0x8F; /* above U+10FFFF */
    if (n > avail)
        return 0;
    for (k = 1; k < n; k++) {
        if (u[k] < lo || u[k] > hi)
            return 0;
        lo = 0x80;
        hi = 0xBF;
    }
    return n;
}

const char *scene_printable(const char *s, size_t max, char *out, size_t outlen)
{
    size_t i = 0, o = 0;
    if (outlen == 0)
        return out;
    while (i < max && s[i] != '\0') {
        const unsigned char *u = (const unsigned char *)s + i;
        char esc[8];
        const char *piece = (const char *)u;
        size_t take = 1, n;
        if (u[0] < 0x20 || u[0] == 0x7f) {
            snprintf(esc, sizeof esc, "\\x%02X", u[0]);
            piece = esc;
        } else if (u[0] >= 0x80) {
            n = utf8_sequence(u, max - i);
            if (n == 0) {
                snprintf(esc, sizeof esc, "\\x%02X", u[0]);
                piece = esc;
            } else {
                take = n;
            }
        }
        n = piece == esc ? strlen(esc) : take;
        if (o + n + 4 > outlen) /* keep room for "..." and the NUL */
            break;
        memcpy(out + o, piece, n);
        o += n;
        i += take;
    }
    if (s[i] != '\0' && o + 4 <= outlen) { /* cut short */
        memcpy(out + o, "...", 3);
        o += 3;
    }
    out[o < outlen ? o : outlen - 1] = '\0';
    return out;
}

const char *scene_shown(const char *text, char *buf)
{
    return scene_printable(text ? text : "", 40, buf, SCENE_SHOWN_LEN);
}

const char *scene_single_note(double x, char *buf, size_t len)
{
    float f = (float)x;
    if (len == 0)
        return buf;
    buf[0] = '\0';
    if ((double)f != x && (f == 0.0f || fabsf(f) == 180.0f))
        snprintf(buf, len, " (%g in single precision)", (double)f);
    return buf;
}

int scene_fail_nul(const scene_msg *m, long line)
{
    return scene_fail(m, line, "unexpected NUL byte (not a text file?)");
}

/* The checks before any parser: the scene's name, no NUL byte. Then the parser. */
static int parse_text(scene_text_parser parse, char *buf, size_t len, const char *name, scene *s,
                      char *err, size_t errlen)
{
    scene_msg m;
    const char *nul;
    m.name = name;
    m.err = err;
    m.errlen = errlen;
    if (scene_set_name(s, name) != 0)
        return scene_fail(&m, 1, "out of memory");
    if ((nul = memchr(buf, '\0', len)))
        return scene_fail_nul(&m, scene_line_at(buf, nul));
    return parse(buf, len, &m, s);
}

int scene_parse_copy(scene_text_parser parse, const char *text, size_t len, const char *name,
                     scene *s, char *err, size_t errlen)
{
    char *buf = malloc(len + 1);
    int rc;
    if (!buf) {
        snprintf(err, errlen, "%s:1: out of memory", name);
        return -1;
    }
    memcpy(buf, text, len);
    buf[len] = '\0';
    rc = parse_text(parse, buf, len, name, s, err, errlen);
    free(buf);
    return rc;
}

int scene_parse_file(scene_text_parser parse, const char *path, scene *s, char *err, size_t errlen)
{
    char *buf;
    size_t len;
    int rc;
    if (sys_read_file(path, CW_MAX_FILE_BYTES, 1, "a scene file", &buf, &len, err, errlen) != 0)
        return -1;
    rc = parse_text(parse, buf, len, path, s, err, errlen);
    free(buf);
    return rc;
}
