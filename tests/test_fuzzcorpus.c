/* Replays the fuzzing corpora through the property the fuzz targets check (fuzz/fuzz_check.h):
 * every input that once broke a reader (tests/fuzz/regressions/TARGET/) and every seed
 * (tests/fuzz/corpus/TARGET/). Under `make asan` this runs with the sanitizers, as the
 * fuzzers do. Runs from the repository root. */
#include "testutil.h"

#include "fuzz/fuzz_check.h"

#include <dirent.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

/* Reads a whole file, bytes as they are (NUL bytes included). */
static unsigned char *read_bytes(const char *path, size_t *len)
{
    FILE *f = fopen(path, "rb");
    unsigned char *buf = NULL;
    size_t cap = 0, n = 0, got;
    if (!f)
        return NULL;
    do {
        if (n == cap) {
            unsigned char *nb = realloc(buf, cap ? cap * 2 : 4096);
            if (!nb) {
                free(buf);
                fclose(f);
                return NULL;
            }
            buf = nb;
            cap = cap ? cap * 2 : 4096;
        }
        got = fread(buf + n, 1, cap - n, f);
        n += got;
    } while (got > 0);
    fclose(f);
    *len = n;
    return buf;
}

/* Runs every regular file of dir through the reader; returns how many, failing on the first
 * input that breaks the property. */
static int replay_dir(const char *dir, fuzz_parser parse, const char *name)
{
    DIR *d = opendir(dir);
    struct dirent *e;
    int count = 0, failed = 0;
    if (!d)
        fail_msg("%s: cannot open the corpus folder", dir);
    while ((e = readdir(d)) != NULL) {
        char path[1024], why[1536];
        struct stat st;
        unsigned char *data;
        size_t len = 0;
        snprintf(path, sizeof path, "%s/%s", dir, e->d_name);
        if (e->d_name[0] == '.' || stat(path, &st) != 0 || !S_ISREG(st.st_mode))
            continue;
        data = read_bytes(path, &len);
        if (!data) {
            print_error("%s: cannot read\n", path);
            failed++;
            continue;
        }
        if (fuzz_check(parse, name, data, len, why, sizeof why) != 0) {
            print_error("%s: %s\n", path, why);
            failed++;
        }
        free(data);
        count++;
    }
    closedir(d);
    if (failed)
        fail_msg("%s: %d of %d inputs break the reader", dir, failed, count);
    return count;
}

static void test_nff_corpus(void **state)
{
    int seeds, regressions;
    (void)state;
    seeds = replay_dir("tests/fuzz/corpus/nff", nff_parse, "fuzz.nff");
    regressions = replay_dir("tests/fuzz/regressions/nff", nff_parse, "fuzz.nff");
    print_message("nff: %d seeds, %d regression inputs\n", seeds, regressions);
    assert_true(seeds > 0);
}

static void test_json_corpus(void **state)
{
    int seeds, regressions;
    (void)state;
    seeds = replay_dir("tests/fuzz/corpus/json", json_scene_parse, "fuzz.json");
    regressions = replay_dir("tests/fuzz/regressions/json", json_scene_parse, "fuzz.json");
    print_message("json: %d seeds, %d regression inputs\n", seeds, regressions);
    assert_true(seeds > 0);
}

/* The property itself must be able to fail. */
static int accept_anything(const char *text, size_t len, const char *name, scene *s, char *err,
                           size_t errlen)
{
    (void)text;
    (void)len;
    (void)name;
    (void)err;
    (void)errlen;
    s->width = 0; /* scene_finish rejects this */
    return 0;
}

static int fail_with(const char *msg, char *err, size_t errlen)
{
    snprintf(err, errlen, "%s", msg);
    return -1;
}

static int no_line(const char *text, size_t len, const char *name, scene *s, char *err,
                   size_t errlen)
{
    (void)text, (void)len, (void)name, (void)s;
    return fail_with("x.nff: broken", err, errlen);
}

static int line_too_far(const char *text, size_t len, const char *name, scene *s, char *err,
                        size_t errlen)
{
    (void)text, (void)len, (void)name, (void)s;
    return fail_with("x.nff:3: broken", err, errlen);
}

static int control_char(const char *text, size_t len, const char *name, scene *s, char *err,
                        size_t errlen)
{
    (void)text, (void)len, (void)name, (void)s;
    return fail_with("x.nff:2: found '\x1b[31m'", err, errlen);
}

static int good_message(const char *text, size_t len, const char *name, scene *s, char *err,
                        size_t errlen)
{
    (void)text, (void)len, (void)name, (void)s;
    return fail_with("x.nff:2: expected a number, found '\\x1B'", err, errlen);
}

static void test_property_fails(void **state)
{
    static const unsigned char two_lines[] = "a\nb";
    char why[1536];
    (void)state;
    assert_int_equal(fuzz_check(accept_anything, "x.nff", two_lines, 3, why, sizeof why), -1);
    assert_non_null(strstr(why, "scene_finish failed"));
    assert_int_equal(fuzz_check(no_line, "x.nff", two_lines, 3, why, sizeof why), -1);
    assert_non_null(strstr(why, "no line number"));
    assert_int_equal(fuzz_check(line_too_far, "x.nff", two_lines, 3, why, sizeof why), -1);
    assert_non_null(strstr(why, "1..2"));
    assert_int_equal(fuzz_check(control_char, "x.nff", two_lines, 3, why, sizeof why), -1);
    assert_non_null(strstr(why, "control character 0x1b"));
    assert_int_equal(fuzz_check(good_message, "x.nff", two_lines, 3, why, sizeof why), 0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_nff_corpus),
        cmocka_unit_test(test_json_corpus),
        cmocka_unit_test(test_property_fails),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
