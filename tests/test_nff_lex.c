/* Tests for the NFF reader's lines (host/scene_nff_lex.c): the fast path for plain decimals
 * against strtod, bit for bit, on random strings and on every token of the scenes in the
 * repository; and reading a file in pieces against parsing its whole text, for every chunk
 * size from one byte up, messages and line numbers included. Runs from the repository
 * root. */
#include "testutil.h"

#include "scene.h"
#include "scene_nff.h"
#include "scene_nff_lex.h"
#include "sys.h"

#include <dirent.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

/* The folders whose .nff files (and fuzz inputs) the tests read; missing ones are skipped. */
static const char *const nff_dirs[] = {
    "scenes/spd",
    "tests/scenes/parse",
    "tests/scenes/pov",
    "tests/scenes/portability",
    "tests/fuzz/corpus/nff",
    "tests/fuzz/regressions/nff",
    "../shared/scenes/spd",
};

/* Calls fn on each regular file in the folders above; returns how many. */
static int each_file(void (*fn)(const char *path, void *ctx), void *ctx)
{
    size_t d;
    int n = 0;
    for (d = 0; d < sizeof nff_dirs / sizeof nff_dirs[0]; d++) {
        DIR *dir = opendir(nff_dirs[d]);
        struct dirent *e;
        if (!dir)
            continue;
        while ((e = readdir(dir)) != NULL) {
            char path[512];
            struct stat st;
            snprintf(path, sizeof path, "%s/%s", nff_dirs[d], e->d_name);
            if (e->d_name[0] == '.' || strcmp(e->d_name, "README") == 0 || stat(path, &st) != 0 ||
                !S_ISREG(st.st_mode))
                continue;
            fn(path, ctx);
            n++;
        }
        closedir(dir);
    }
    return n;
}

static char *read_text(const char *path, size_t *len)
{
    char *buf, err[512];
    if (sys_read_file(path, 1L << 30, 0, "a test file", &buf, len, err, sizeof err) != 0)
        fail_msg("%s", err);
    return buf;
}

/* ---- the fast path against strtod ---- */

static long fast_taken, fast_tried;

/* When the fast path takes t, strtod must take all of t and give the same bits. */
static void check_decimal(const char *t)
{
    double fast, slow;
    char *end;
    fast_tried++;
    if (!nff_lex_decimal(t, &fast))
        return;
    fast_taken++;
    slow = strtod(t, &end);
    if (*end != '\0' || memcmp(&fast, &slow, sizeof fast) != 0)
        fail_msg("'%s': fast path %.17g, strtod %.17g (stopped at '%s')", t, fast, slow, end);
}

static void test_decimal_cases(void **state)
{
    /* each with the answer of the fast path: 1 taken (and equal to strtod), 0 left to it */
    static const struct {
        const char *t;
        int fast;
    } cases[] = {
        {"0", 1},
        {"-0", 1},
        {"+0.0", 1},
        {"0.5", 1},
        {".5", 1},
        {"5.", 1},
        {"-0.166760", 1},
        {"1e22", 1},
        {"1e-22", 1},
        {"1e23", 0}, /* 10^23 is not exact */
        {"123e-25", 0},
        {"9007199254740992", 1},      /* 2^53 */
        {"9007199254740993", 0},      /* above: m inexact */
        {"0.1234567890123456789", 0}, /* 19 digits, m > 2^53 */
        {"12345678901234567890", 0},  /* 20 digits */
        {"0e99999999999", 1},
        {"00000000000000000000001", 0}, /* every digit counts */
        {"1E5", 1},
        {"1e+5", 1},
        {"1e", 0},
        {"1e+", 0},
        {"1.5x", 0},
        {".", 0},
        {"-", 0},
        {"+-1", 0},
        {"--1", 0},
        {"1..2", 0},
        {"0x10", 0},
        {"inf", 0},
        {"nan", 0},
        {"1e1e1", 0},
        {"", 0},
        {" 1", 0},
        {"1 ", 0},
        {"1#", 0},
    };
    size_t i;
    (void)state;
    for (i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        double v;
        int got = nff_lex_decimal(cases[i].t, &v);
        if (got != cases[i].fast)
            fail_msg("'%s': fast path %s, expected %s", cases[i].t, got ? "taken" : "not taken",
                     cases[i].fast ? "taken" : "not taken");
        check_decimal(cases[i].t);
    }
    {
        double v = 1;
        assert_true(nff_lex_decimal("-0", &v));
        assert_true(v == 0.0 && signbit(v)); /* the sign of zero is kept */
    }
}

/* A random decimal: sign, integer and fraction digits (leading zeros, long runs), an
 * exponent, and now and then a character that makes it no plain decimal. */
static void random_decimal(char *out, size_t cap)
{
    static const char junk[] = "+-.eEx0 #";
    size_t n = 0, k, len;
    uint64_t r = tu_rng_next();
    if (r % 4 == 0)
        out[n++] = r % 8 == 0 ? '-' : '+';
    r >>= 3;
    len = (size_t)(tu_rng_next() % (tu_rng_next() % 4 == 0 ? 24 : 10));
    for (k = 0; k < len && n < cap - 40; k++)
        out[n++] = (char)('0' + (r % 7 == 0 ? 0 : tu_rng_next() % 10));
    if (tu_rng_next() % 3 != 0) {
        out[n++] = '.';
        len = (size_t)(tu_rng_next() % (tu_rng_next() % 4 == 0 ? 24 : 9));
        for (k = 0; k < len && n < cap - 20; k++)
            out[n++] = (char)('0' + tu_rng_next() % 10);
    }
    if (tu_rng_next() % 4 == 0)
        n += (size_t)snprintf(out + n, cap - n, "%s%d", tu_rng_next() % 2 ? "e" : "E-",
                              (int)(tu_rng_next() % (tu_rng_next() % 2 ? 30 : 400)));
    if (tu_rng_next() % 50 == 0 && n > 0)
        out[tu_rng_next() % n] = junk[tu_rng_next() % (sizeof junk - 1)];
    out[n] = '\0';
}

static void test_decimal_random(void **state)
{
    char t[128];
    long i;
    (void)state;
    tu_rng_seed(13);
    fast_taken = fast_tried = 0;
    for (i = 0; i < 2000000; i++) {
        random_decimal(t, sizeof t);
        check_decimal(t);
    }
    /* mantissas near 2^53 and exponents at the edge of the fast range */
    for (i = 0; i < 200000; i++) {
        unsigned long long m = (1ULL << 53) - 1000 + tu_rng_next() % 2000;
        int e = (int)(tu_rng_next() % 51) - 25;
        snprintf(t, sizeof t, "%llue%d", m >> (tu_rng_next() % 54), e);
        check_decimal(t);
    }
    print_message("fast path: %ld of %ld random strings\n", fast_taken, fast_tried);
    assert_true(fast_taken > fast_tried / 4); /* the generator reaches the fast path */
}

/* Every token of a file (split as the reader splits lines). */
static void decimals_of_file(const char *path, void *ctx)
{
    size_t len, i = 0;
    char *buf = read_text(path, &len);
    (void)ctx;
    while (i < len) {
        size_t j = i;
        while (j < len && !strchr(" \t\r\f\v\n#", buf[j]) && buf[j] != '\0')
            j++;
        if (j > i) {
            char c = buf[j];
            buf[j] = '\0';
            check_decimal(buf + i);
            buf[j] = c;
        }
        i = j + 1;
    }
    free(buf);
}

static void test_decimal_corpora(void **state)
{
    int files;
    (void)state;
    fast_taken = fast_tried = 0;
    files = each_file(decimals_of_file, NULL);
    print_message("fast path: %ld of %ld tokens in %d files\n", fast_taken, fast_tried, files);
    assert_true(files > 0);
    assert_true(fast_taken > fast_tried / 2);
}

/* ---- reading in pieces against parsing the whole text ---- */

static int same_array(const scene_array *a, const scene_array *b, size_t size)
{
    return a->count == b->count &&
           (a->count == 0 || memcmp(a->data, b->data, a->count * size) == 0);
}

/* Lights and cones field by field: their structs end in padding. */
static int same_pos(vec3d a, vec3d b)
{
    return memcmp(&a, &b, sizeof a) == 0;
}

static int same_lights_cones(const scene *a, const scene *b)
{
    size_t i;
    if (a->lights.count != b->lights.count || a->cones.count != b->cones.count)
        return 0;
    for (i = 0; i < a->lights.count; i++) {
        const scene_light *p = &SCENE_AT(a->lights, scene_light, i);
        const scene_light *q = &SCENE_AT(b->lights, scene_light, i);
        if (!same_pos(p->position, q->position) ||
            memcmp(&p->intensity, &q->intensity, sizeof p->intensity) != 0)
            return 0;
    }
    for (i = 0; i < a->cones.count; i++) {
        const scene_cone *p = &SCENE_AT(a->cones, scene_cone, i);
        const scene_cone *q = &SCENE_AT(b->cones, scene_cone, i);
        if (!same_pos(p->base, q->base) || !same_pos(p->apex, q->apex) ||
            memcmp(&p->base_radius, &q->base_radius, sizeof(float)) != 0 ||
            memcmp(&p->apex_radius, &q->apex_radius, sizeof(float)) != 0 ||
            p->material != q->material)
            return 0;
    }
    return 1;
}

static int same_scene(const scene *a, const scene *b)
{
    return strcmp(a->name, b->name) == 0 && memcmp(&a->camera, &b->camera, sizeof a->camera) == 0 &&
           a->width == b->width && a->height == b->height && a->max_depth == b->max_depth &&
           memcmp(&a->background, &b->background, sizeof(vec3f)) == 0 &&
           memcmp(&a->ambient, &b->ambient, sizeof(vec3f)) == 0 &&
           same_array(&a->materials, &b->materials, sizeof(scene_material)) &&
           same_lights_cones(a, b) && same_array(&a->spheres, &b->spheres, sizeof(scene_sphere)) &&
           same_array(&a->triangles, &b->triangles, sizeof(scene_triangle)) &&
           same_array(&a->tri_normals, &b->tri_normals, sizeof(vec3f)) &&
           same_array(&a->polygons, &b->polygons, sizeof(scene_polygon)) &&
           same_array(&a->poly_verts, &b->poly_verts, sizeof(vec3d));
}

/* The file at path parsed whole (nff_parse of its text, named by the path) and read in
 * pieces of each chunk size: the same result, the same message. */
static void check_chunks(const char *path, const size_t *chunks, size_t nchunks)
{
    size_t len, c;
    char *text = read_text(path, &len), whole_err[1024] = "";
    scene whole;
    int whole_rc;
    scene_init(&whole);
    whole_rc = nff_parse(text, len, path, &whole, whole_err, sizeof whole_err);
    for (c = 0; c < nchunks; c++) {
        char err[1024] = "";
        scene s;
        int rc;
        scene_init(&s);
        rc = nff_load_chunked(path, chunks[c], &s, err, sizeof err);
        if (rc != whole_rc || strcmp(err, whole_err) != 0 || (rc == 0 && !same_scene(&s, &whole)))
            fail_msg("%s in pieces of %zu bytes: %d \"%s\"; whole: %d \"%s\"%s", path, chunks[c],
                     rc, err, whole_rc, whole_err,
                     rc == 0 && whole_rc == 0 ? " (different scenes)" : "");
        scene_free(&s);
    }
    scene_free(&whole);
    free(text);
}

static void chunks_of_file(const char *path, void *ctx)
{
    static const size_t small[] = {1, 2, 3, 7, 64, 4096, CW_NFF_READ_CHUNK};
    static const size_t large[] = {61, 4096, CW_NFF_READ_CHUNK};
    struct stat st;
    (void)ctx;
    if (stat(path, &st) == 0 && st.st_size > 100000)
        check_chunks(path, large, sizeof large / sizeof large[0]);
    else
        check_chunks(path, small, sizeof small / sizeof small[0]);
}

static void test_chunks_corpora(void **state)
{
    (void)state;
    assert_true(each_file(chunks_of_file, NULL) > 0);
}

/* Writes text (len bytes, NULs allowed) to a file under build/test-output. */
static void write_file(const char *path, const char *text, size_t len)
{
    FILE *f;
    mkdir("build", 0777);
    mkdir("build/test-output", 0777);
    f = fopen(path, "wb");
    assert_non_null(f);
    assert_int_equal(fwrite(text, 1, len, f), len);
    assert_int_equal(fclose(f), 0);
}

#define VIEW "v\nfrom 0 0 5\nat 0 0 0\nup 0 1 0\nangle 90\nhither 1\nresolution 3 3\n"

/* The cases where reading in pieces must keep the whole-text order of messages. */
static void test_chunks_cases(void **state)
{
    static const size_t chunks[] = {1, 2, 3, 5, 8, 13, 100, 4096};
    static const char nul_after_error[] = VIEW "s 0 0 0 zero\n\n\n# NUL: \0\n";
    static const char nul_first[] = "\0" VIEW;
    static const char nul_late_line[] = VIEW "s 0 0 0 1\ns 1 1 1 1 # \0\n";
    static const char bom_crlf[] = "\xEF\xBB\xBFv\r\nfrom 0 0 5\r\nat 0 0 0\r\nup 0 1 0\r\n"
                                   "angle 90\r\nhither 1\r\nresolution 3 3\r\ns 0 0 0 1";
    static const char truncated[] = VIEW "p 3\n0 0 0\n1 0 0\n";
    static const struct {
        const char *name, *text;
        size_t len;
        const char *expect; /* in the message; NULL: parses */
    } cases[] = {
        {"nul-after-error", nul_after_error, sizeof nul_after_error - 1, ":11: unexpected NUL"},
        {"nul-first", nul_first, sizeof nul_first - 1, ":1: unexpected NUL"},
        {"nul-late", nul_late_line, sizeof nul_late_line - 1, ":9: unexpected NUL"},
        {"bom-crlf", bom_crlf, sizeof bom_crlf - 1, NULL},
        {"truncated", truncated, sizeof truncated - 1, ":10: file ended inside 'p 3'"},
    };
    size_t i;
    (void)state;
    for (i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        char path[256], err[1024] = "";
        scene s;
        int rc;
        snprintf(path, sizeof path, "build/test-output/chunks-%s.nff", cases[i].name);
        write_file(path, cases[i].text, cases[i].len);
        check_chunks(path, chunks, sizeof chunks / sizeof chunks[0]);
        scene_init(&s);
        rc = nff_load(path, &s, err, sizeof err);
        scene_free(&s);
        if (cases[i].expect ? rc == 0 || !strstr(err, cases[i].expect) : rc != 0)
            fail_msg("%s: %d \"%s\", expected %s", cases[i].name, rc, err,
                     cases[i].expect ? cases[i].expect : "success");
        unlink(path);
    }
}

/* Lines far longer than a piece: a long comment, many tokens, a number of many digits. */
static void test_chunks_long_lines(void **state)
{
    static const size_t chunks[] = {1, 3, 64, 4096};
    size_t n = 300000, len = 0, k;
    char *text = malloc(n + 4096);
    const char path[] = "build/test-output/chunks-long.nff";
    (void)state;
    assert_non_null(text);
    len += (size_t)sprintf(text + len, "#");
    for (k = 0; k < n / 3; k++)
        text[len++] = (char)('a' + k % 26);
    len += (size_t)sprintf(text + len, "\n%ss 0 0 0 0.", VIEW);
    for (k = 0; k < n / 3; k++)
        text[len++] = (char)('1' + k % 9);
    len += (size_t)sprintf(text + len, "\nl 1 2 3");
    for (k = 0; k < n / 6; k++)
        len += (size_t)sprintf(text + len, " 1");
    text[len++] = '\n';
    write_file(path, text, len);
    check_chunks(path, chunks, sizeof chunks / sizeof chunks[0]);
    unlink(path);
    free(text);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_decimal_cases),   cmocka_unit_test(test_decimal_random),
        cmocka_unit_test(test_decimal_corpora), cmocka_unit_test(test_chunks_corpora),
        cmocka_unit_test(test_chunks_cases),    cmocka_unit_test(test_chunks_long_lines),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
