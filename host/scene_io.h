/* What the scene readers share: messages "name:line: text" with text from the file made
 * printable, and getting the text (a copy of a string, a whole file, or a file in pieces)
 * with the checks every reader makes before its own: the scene's name and no NUL byte. */
#ifndef CW_SCENE_IO_H
#define CW_SCENE_IO_H

#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>

#include "scene.h"

#if defined(__GNUC__)
#define SCENE_PRINTF(fmt, args) __attribute__((format(printf, fmt, args)))
#else
#define SCENE_PRINTF(fmt, args)
#endif

/* A macro's value as a string, for limits in messages: SCENE_STR(CW_MAX_ABS) is "1e30". */
#define SCENE_STR(x) SCENE_STR_(x)
#define SCENE_STR_(x) #x

/* Where a reader reports: the text's name (a path) and the caller's buffer. */
typedef struct {
    const char *name;
    char *err;
    size_t errlen;
} scene_msg;

/* Writes "name:line: " and the formatted text into m->err (line 1 when line < 1).
 * Returns -1, so that a reader can `return scene_fail(...)`. */
int scene_fail(const scene_msg *m, long line, const char *fmt, ...) SCENE_PRINTF(3, 4);
int scene_vfail(const scene_msg *m, long line, const char *fmt, va_list ap) SCENE_PRINTF(3, 0);

/* The line (1-based) that the byte at `at` lies on in text. */
long scene_line_at(const char *text, const char *at);

/* 3 when buf[0..len) starts with a UTF-8 byte order mark (which the readers skip), else 0. */
size_t scene_bom_len(const char *buf, size_t len);

/* Copies text from a file into out for an error message: at most max bytes of the
 * NUL-terminated string s, with control characters and bytes that are not UTF-8 written as
 * \xNN, and "..." when cut short. out is always NUL-terminated. Returns out. */
const char *scene_printable(const char *s, size_t max, char *out, size_t outlen);

/* A word or key from the file as messages show it: scene_printable of its first 40 bytes
 * (NULL shows as "") into buf, which has SCENE_SHOWN_LEN bytes. Returns buf. */
#define SCENE_SHOWN_LEN 176
const char *scene_shown(const char *text, char *buf);

/* For a message about a number stored as a float: when rounding to single precision
 * changes x into 0 or +-180 (bounds the readers check), " (V in single precision)" in buf;
 * otherwise "". Returns buf. */
const char *scene_single_note(double x, char *buf, size_t len);

/* A reader's parser: text in buf[0..len), writable, with buf[len] == '\0' and no other
 * NUL byte; s->name is set. Returns 0, or -1 with scene_fail. */
typedef int (*scene_text_parser)(char *buf, size_t len, const scene_msg *m, scene *s);

/* Runs a parser on a NUL-terminated copy of text, naming it `name` in messages, or on the
 * contents of the file at path (read with sys_read_file, at most CW_MAX_FILE_BYTES),
 * naming it by its path. Sets the scene's name and rejects a NUL byte with its line
 * first. Return 0, or -1 with "name:line: message" in err. */
int scene_parse_copy(scene_text_parser parse, const char *text, size_t len, const char *name,
                     scene *s, char *err, size_t errlen);
int scene_parse_file(scene_text_parser parse, const char *path, scene *s, char *err, size_t errlen);

/* The message for a NUL byte in the text at line (the same from every path). Returns -1. */
int scene_fail_nul(const scene_msg *m, long line);

#endif
