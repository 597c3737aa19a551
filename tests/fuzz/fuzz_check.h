/* The property every scene reader must have, whatever it is given, shared by the fuzz
 * targets (tests/fuzz/fuzz_*.c, which abort when it fails) and by test_fuzzcorpus (which
 * replays the seed and regression corpora in the normal and the sanitizer builds):
 *
 *   - the reader returns 0 or -1, and does not crash, hang, leak or read out of bounds
 *     (the sanitizers and libFuzzer see to those);
 *   - on -1 the message is "NAME:LINE: what was expected", LINE being a line of the input
 *     (1 .. newlines + 1), the text non-empty and printable (no control characters: bytes
 *     from the file are escaped);
 *   - on 0 the scene is usable: scene_finish at the scene's own size accepts it, so every
 *     problem was reported by the reader, with a line number, not later without one.
 */
#ifndef CW_FUZZ_CHECK_H
#define CW_FUZZ_CHECK_H

#include "scene.h"

#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef int (*fuzz_parser)(const char *text, size_t len, const char *name, scene *s, char *err,
                           size_t errlen);

/* 0 when err is "name:LINE: text" as described above, else -1 with the reason in why. */
static int fuzz_check_message(const char *name, const unsigned char *data, size_t size,
                              const char *err, char *why, size_t whylen)
{
    size_t n = strlen(name), i;
    long line = 0, lines = 1;
    const char *p;
    for (i = 0; i < size; i++)
        lines += data[i] == '\n';
    if (strncmp(err, name, n) != 0 || err[n] != ':') {
        snprintf(why, whylen, "the message does not start with \"%s:\": \"%.200s\"", name, err);
        return -1;
    }
    for (p = err + n + 1; *p >= '0' && *p <= '9' && line <= lines; p++)
        line = line * 10 + (*p - '0');
    if (p == err + n + 1 || line < 1 || line > lines) {
        snprintf(why, whylen, "no line number in 1..%ld after \"%s:\": \"%.200s\"", lines, name,
                 err);
        return -1;
    }
    if (p[0] != ':' || p[1] != ' ' || p[2] == '\0') {
        snprintf(why, whylen, "expected \": message\" after the line number: \"%.200s\"", err);
        return -1;
    }
    for (p = err; *p; p++)
        if ((unsigned char)*p < 0x20 || *p == 0x7f) {
            snprintf(why, whylen, "control character 0x%02x at offset %ld of the message",
                     (unsigned)(unsigned char)*p, (long)(p - err));
            return -1;
        }
    return 0;
}

/* Parses data[0..size) as file `name`; 0 when the reader behaved, else -1 with why. */
static int fuzz_check(fuzz_parser parse, const char *name, const unsigned char *data, size_t size,
                      char *why, size_t whylen)
{
    scene s;
    char err[1024];
    int rc, ok = 0;
    err[0] = '\0';
    scene_init(&s);
    rc = parse((const char *)data, size, name, &s, err, sizeof err);
    if (rc == 0) {
        if (scene_finish(&s, 0, 0, 0, err, sizeof err) != 0) {
            snprintf(why, whylen, "the reader accepted the scene, but scene_finish failed: %s",
                     err);
            ok = -1;
        }
    } else if (rc != -1) {
        snprintf(why, whylen, "the reader returned %d (expected 0 or -1)", rc);
        ok = -1;
    } else {
        ok = fuzz_check_message(name, data, size, err, why, whylen);
    }
    scene_free(&s);
    return ok;
}

/* The libFuzzer entry point of a target: runs the reader `parse` on each input as file
 * `name` and aborts (a crash to libFuzzer) when the property fails. */
#define FUZZ_TARGET(target, parse, name)                                                           \
    int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);                                  \
    int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)                                   \
    {                                                                                              \
        char why[1536];                                                                            \
        if (fuzz_check(parse, name, data, size, why, sizeof why) != 0) {                           \
            fprintf(stderr, "%s: %s\n", target, why);                                              \
            abort();                                                                               \
        }                                                                                          \
        return 0;                                                                                  \
    }

#endif
