/* Replays the fuzzing corpora through the property the fuzz targets check (fuzz/fuzz_check.h,
 * fuzz/fuzz_mesh.h): every input that once broke a reader (tests/fuzz/regressions/TARGET/)
 * and every seed (tests/fuzz/corpus/TARGET/). Under `make asan` this runs with the
 * sanitizers, as the fuzzers do. Runs from the repository root. */
#include "testutil.h"

#include "fuzz/fuzz_check.h"
#include "fuzz/fuzz_mesh.h"

#include "config.h"
#include "scene_json.h"
#include "scene_nff.h"
#include "sys.h"

#include <dirent.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

/* Runs every regular file of dir through the reader (parse, or the mesh reader when parse
 * is NULL); returns how many, failing on the first input that breaks the property. */
static int replay_dir(const char *dir, fuzz_parser parse, const char *name)
{
    DIR *d = opendir(dir);
    struct dirent *e;
    int count = 0, failed = 0;
    if (!d)
        fail_msg("%s: cannot open the corpus folder", dir);
    while ((e = readdir(d)) != NULL) {
        char path[1024], why[1536], err[1280];
        struct stat st;
        char *data;
        size_t len = 0;
        snprintf(path, sizeof path, "%s/%s", dir, e->d_name);
        if (e->d_name[0] == '.' || stat(path, &st) != 0 || !S_ISREG(st.st_mode))
            continue;
        /* the bytes as they are, NUL bytes included */
        if (sys_read_file(path, CW_MAX_FILE_BYTES, 0, "a fuzz input", &data, &len, err,
                          sizeof err) != 0) {
            print_error("%s\n", err);
            failed++;
            continue;
        }
        if ((parse ? fuzz_check(parse, name, (const unsigned char *)data, len, why, sizeof why)
                   : fuzz_check_mesh((const unsigned char *)data, len, why, sizeof why)) != 0) {
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

/* Replays the seeds and the regression inputs of one fuzz target; returns the seeds. */
static int replay_target(const char *target, fuzz_parser parse, const char *name)
{
    char seeds_dir[256], regressions_dir[256];
    int seeds, regressions;
    snprintf(seeds_dir, sizeof seeds_dir, "tests/fuzz/corpus/%s", target);
    snprintf(regressions_dir, sizeof regressions_dir, "tests/fuzz/regressions/%s", target);
    seeds = replay_dir(seeds_dir, parse, name);
    regressions = replay_dir(regressions_dir, parse, name);
    print_message("%s: %d seeds, %d regression inputs\n", target, seeds, regressions);
    return seeds;
}

static void test_nff_corpus(void **state)
{
    (void)state;
    assert_true(replay_target("nff", nff_parse, "fuzz.nff") > 0);
}

static void test_json_corpus(void **state)
{
    (void)state;
    assert_true(replay_target("json", json_scene_parse, "fuzz.json") > 0);
}

static void test_mesh_corpus(void **state)
{
    (void)state;
    assert_true(replay_target("mesh", NULL, "fuzz.mesh") > 0);
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

/* A reader that fails with the message in `canned_msg`. */
static const char *canned_msg;

static int canned(const char *text, size_t len, const char *name, scene *s, char *err,
                  size_t errlen)
{
    (void)text, (void)len, (void)name, (void)s;
    snprintf(err, errlen, "%s", canned_msg);
    return -1;
}

static void test_property_fails(void **state)
{
    static const unsigned char two_lines[] = "a\nb";
    char why[1536];
    (void)state;
    assert_int_equal(fuzz_check(accept_anything, "x.nff", two_lines, 3, why, sizeof why), -1);
    assert_non_null(strstr(why, "scene_finish failed"));
    canned_msg = "x.nff: broken";
    assert_int_equal(fuzz_check(canned, "x.nff", two_lines, 3, why, sizeof why), -1);
    assert_non_null(strstr(why, "no line number"));
    canned_msg = "x.nff:3: broken";
    assert_int_equal(fuzz_check(canned, "x.nff", two_lines, 3, why, sizeof why), -1);
    assert_non_null(strstr(why, "1..2"));
    canned_msg = "x.nff:2: found '\x1b[31m'";
    assert_int_equal(fuzz_check(canned, "x.nff", two_lines, 3, why, sizeof why), -1);
    assert_non_null(strstr(why, "control character 0x1b"));
    canned_msg = "x.nff:2: expected a number, found '\\x1B'";
    assert_int_equal(fuzz_check(canned, "x.nff", two_lines, 3, why, sizeof why), 0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_nff_corpus),
        cmocka_unit_test(test_json_corpus),
        cmocka_unit_test(test_mesh_corpus),
        cmocka_unit_test(test_property_fails),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
