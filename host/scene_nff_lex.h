/* The NFF reader's lines: the text (in memory, or read from the file in pieces), split into
 * lines of tokens, with the fast path that converts a plain decimal token while its line is
 * split (see scene_nff_lex.c). */
#ifndef CW_SCENE_NFF_LEX_H
#define CW_SCENE_NFF_LEX_H

#include <stddef.h>

#include "scene_io.h"
#include "sys.h"

#define NFF_MAX_TOKENS 16 /* tokens kept per line; more are only counted */

/* Why the text ended early (a file read in pieces). */
enum { NFF_LEX_OK = 0, NFF_LEX_NUL, NFF_LEX_FAILED };

typedef struct {
    char *cur, *end; /* unread part of the writable text in memory (*end == '\0') */
    char *whole;     /* lines that start before it are whole in memory (end: all of them) */
    long line;       /* number of the current line (1-based; 0 before the first) */
    char *tok[NFF_MAX_TOKENS];          /* the tokens of the current line, NUL-terminated */
    double val[NFF_MAX_TOKENS];         /* token i's value when fast[i] */
    unsigned char fast[NFF_MAX_TOKENS]; /* token i is a plain decimal whose value is val[i] */
    int ntok;                           /* tokens on the current line (can exceed NFF_MAX_TOKENS) */
    /* a file read in pieces: the window buf[0..cap) holds cur..end */
    sys_file *file; /* NULL: the whole text is in memory */
    char *buf;
    size_t cap, chunk; /* window size; bytes read at a time */
    int eof;           /* the file is all read */
    int stop;          /* NFF_LEX_NUL or NFF_LEX_FAILED: the text ended there */
    long nul_line;     /* the line of the first NUL byte (NFF_LEX_NUL) */
} nff_lex;

/* Starts at text[0..len), which is writable with text[len] == '\0' and no other NUL. */
void nff_lex_init(nff_lex *lx, char *text, size_t len);

/* Starts on an open file, read chunk bytes at a time (chunk >= 1), a UTF-8 byte order mark
 * at its start skipped. Returns 0, or -1 when out of memory (the message is in f's err). */
int nff_lex_open(nff_lex *lx, sys_file *f, size_t chunk);

/* The result of a reader that parsed lines from nff_lex_open: rc, unless the whole-file
 * reader would have failed first. A read failure wins, then a NUL byte (with its line, even
 * after the parse error: the rest of the file is read to find one), then rc. Frees the
 * window. */
int nff_lex_finish(nff_lex *lx, int rc, const scene_msg *m);

/* Splits the next line into NUL-terminated tokens (blanks are space, tab, CR, FF and VT;
 * `#` starts a comment anywhere on a line, even inside a token) and converts each plain
 * decimal token on the way. Returns 0 at the end of the text, or when it ended early
 * (lx->stop: a NUL byte, a read failure, no memory for a long line). */
int nff_lex_next_line(nff_lex *lx);

/* The fast path on its own, for tests: when the NUL-terminated s is a plain decimal
 * ([+-] digits [. digits] [e [+-] digits], at least one digit, at most 19 significant
 * digits) whose value one correctly rounded multiplication or division by a power of ten
 * gives exactly, sets *out to that value, which is the value strtod gives, and returns 1.
 * Returns 0 for anything else (strtod decides it then). */
int nff_lex_decimal(const char *s, double *out);

#endif
