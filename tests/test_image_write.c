/* Tests for the fast paths of the image writers: the 8-bit sRGB table against its
 * definition (host/image.c), the ordered job pool (host/par.c), PNG pixels compressed in
 * pieces and EXR chunks compressed on several threads (host/image_png.c, image_exr.c). */
#include "testutil.h"

#include "image.h"
#include "image_internal.h"
#include "image_read.h"
#include "par.h"

#include <dirent.h>
#include <errno.h>
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#define PATHLEN 4096

static char g_dir[PATHLEN]; /* per-run temporary directory */

static void tpath(char *out, const char *name)
{
    int n = snprintf(out, PATHLEN, "%s/%s", g_dir, name);
    assert_true(n > 0 && n < PATHLEN);
}

static int group_setup(void **state)
{
    (void)state;
    snprintf(g_dir, sizeof g_dir, "/tmp/cw_test_image_write-XXXXXX");
    return mkdtemp(g_dir) ? 0 : -1;
}

static int group_teardown(void **state)
{
    DIR *d = opendir(g_dir);
    struct dirent *e;
    char sub[PATHLEN + 256];
    (void)state;
    if (!d)
        return -1;
    while ((e = readdir(d)) != NULL)
        if (strcmp(e->d_name, ".") != 0 && strcmp(e->d_name, "..") != 0) {
            snprintf(sub, sizeof sub, "%s/%s", g_dir, e->d_name);
            unlink(sub);
        }
    closedir(d);
    return rmdir(g_dir);
}

static float float_of_bits(uint32_t b)
{
    float f;
    memcpy(&f, &b, sizeof f);
    return f;
}

/* The float path of image_srgb8_encode (clamp at exposure 0) for one value. */
static int code_float_path(const image_srgb8_table *t, float f)
{
    unsigned char c;
    image_srgb8_encode(t, &f, 1, 1.0, IMAGE_TONEMAP_CLAMP, &c);
    return c;
}

/* The definition for a linear value, exposure scale and tone map. */
static int code_exact(double linear, double scale, int tonemap)
{
    return image_srgb8_exact(image_tonemap_value(linear * scale, tonemap));
}

/* ------------------------------------------------------------------------------------ */
/* The sRGB table                                                                        */

static void test_srgb8_bounds(void **state)
{
    static image_srgb8_table t;
    (void)state;
    image_srgb8_table_init(&t);
    assert_true(t.bound[0] == 0.0);
    for (int k = 1; k < 256; k++) {
        double b = t.bound[k], below = nextafter(b, 0.0);
        if (!(b > t.bound[k - 1]) || !(b < 1.0))
            fail_msg("bound %d = %.17g is not between bound %d and 1", k, b, k - 1);
        /* the least value of code k or more: its lower neighbour has code k - 1 */
        assert_int_equal(image_srgb8_exact(b), k);
        assert_int_equal(image_srgb8_exact(below), k - 1);
    }
}

/* Both paths against the definition for 512 doubles (floats) on each side of each bound,
 * where a non-monotonic pow would show. */
static void test_srgb8_near_bounds(void **state)
{
    static image_srgb8_table t;
    (void)state;
    image_srgb8_table_init(&t);
    for (int k = 1; k < 256; k++) {
        double d = t.bound[k];
        float f = float_of_bits(t.fbound[k]);
        for (int i = 0; i < 512; i++) {
            d = nextafter(d, 0.0);
            f = nextafterf(f, 0.0f);
        }
        for (int i = 0; i < 1024; i++) {
            if (image_srgb8(&t, d) != image_srgb8_exact(d))
                fail_msg("double %a: table %d, definition %d", d, image_srgb8(&t, d),
                         image_srgb8_exact(d));
            if (code_float_path(&t, f) != image_srgb8_exact(f))
                fail_msg("float %a: table %d, definition %d", (double)f, code_float_path(&t, f),
                         image_srgb8_exact(f));
            d = nextafter(d, 2.0);
            f = nextafterf(f, 2.0f);
        }
    }
}

/* The float path over every 257th bit pattern (both signs, NaNs and infinities) and the
 * special values; the double path over random values under every tone map and a few
 * exposures. (The whole float range and 2^31 patterns more were checked once by hand.) */
static void test_srgb8_sweep(void **state)
{
    static image_srgb8_table t;
    static const float special[] = {0.0f,     -0.0f,     1.0f,    2.0f, FLT_MAX, -FLT_MAX,
                                    FLT_MIN,  1e-45f,    -1e-45f, 0.5f, 0.999f,  1.0000001f,
                                    INFINITY, -INFINITY, NAN,     -NAN};
    static const double scales[] = {1.0, 2.0, 0.35355339059327373, 1e-3, 1e12};
    (void)state;
    image_srgb8_table_init(&t);
    for (size_t i = 0; i < sizeof special / sizeof special[0]; i++)
        assert_int_equal(code_float_path(&t, special[i]), code_exact(special[i], 1.0, 0));
    assert_int_equal(code_float_path(&t, nextafterf(1.0f, 0.0f)), 255);
    for (uint64_t b = 0; b <= 0xffffffffu; b += 257) {
        float f = float_of_bits((uint32_t)b);
        if (code_float_path(&t, f) != code_exact(f, 1.0, IMAGE_TONEMAP_CLAMP))
            fail_msg("bits %08x: table %d, definition %d", (unsigned)b, code_float_path(&t, f),
                     code_exact(f, 1.0, IMAGE_TONEMAP_CLAMP));
    }
    tu_rng_seed(7);
    for (int tm = IMAGE_TONEMAP_CLAMP; tm <= IMAGE_TONEMAP_ACES; tm++)
        for (size_t s = 0; s < sizeof scales / sizeof scales[0]; s++)
            for (int i = 0; i < 20000; i++) {
                /* linear values from 1e-6 to 1e3, and a few negatives */
                double u = (double)(tu_rng_next() >> 11) / 9007199254740992.0;
                float v = (float)(pow(10.0, -6.0 + 9.0 * u) * (i % 50 == 0 ? -1 : 1));
                unsigned char c;
                image_srgb8_encode(&t, &v, 1, scales[s], tm, &c);
                if (c != code_exact(v, scales[s], tm))
                    fail_msg("tone map %d, scale %g, value %a: table %d, definition %d", tm,
                             scales[s], (double)v, c, code_exact(v, scales[s], tm));
            }
}

/* ------------------------------------------------------------------------------------ */
/* The ordered pool                                                                      */

typedef struct {
    int window, njobs, fail_job, fail_emit;
    int slot[64];     /* the job held by each slot */
    int emitted;      /* jobs emitted so far, in order */
    int ran[4096];    /* times each job ran */
    int thread[4096]; /* the thread that ran each job */
    int bad;          /* an emit found the wrong job in its slot, or out of order */
} pool_case;

static int pool_job(void *ctx, int j, int thread)
{
    pool_case *c = ctx;
    volatile int spin = 0; /* work of varying length, so that jobs overlap */
    for (int i = 0; i < 2000 + (j * 7919) % 5000; i++)
        spin++;
    c->slot[j % c->window] = j;
    c->ran[j]++;
    c->thread[j] = thread;
    return j == c->fail_job ? 7 : 0;
}

static int pool_emit(void *ctx, int j)
{
    pool_case *c = ctx;
    if (c->slot[j % c->window] != j || j != c->emitted)
        c->bad = 1;
    c->emitted++;
    return j == c->fail_emit ? 9 : 0;
}

static void test_par_ordered(void **state)
{
    static const int cases[][3] = {/* jobs, threads, window */
                                   {1, 4, 8},   {5, 1, 4},  {100, 2, 4},   {1000, 4, 8},
                                   {333, 8, 3}, {64, 3, 1}, {4096, 8, 64}, {0, 4, 4}};
    static pool_case c;
    (void)state;
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        memset(&c, 0, sizeof c);
        c.njobs = cases[i][0];
        c.window = cases[i][2];
        c.fail_job = c.fail_emit = -1;
        assert_int_equal(par_ordered(c.njobs, cases[i][1], c.window, pool_job, pool_emit, &c), 0);
        assert_int_equal(c.emitted, c.njobs);
        assert_false(c.bad);
        for (int j = 0; j < c.njobs; j++) {
            assert_int_equal(c.ran[j], 1);
            assert_true(c.thread[j] >= 0 && c.thread[j] < cases[i][1]);
        }
    }
    /* a failed job: its code comes back, nothing from it on is emitted, no job twice */
    memset(&c, 0, sizeof c);
    c.njobs = 500;
    c.window = 8;
    c.fail_job = 123;
    c.fail_emit = -1;
    assert_int_equal(par_ordered(c.njobs, 4, c.window, pool_job, pool_emit, &c), 7);
    assert_true(c.emitted <= 123);
    assert_false(c.bad);
    for (int j = 0; j < c.njobs; j++)
        assert_true(c.ran[j] <= 1);
    assert_int_equal(c.ran[123], 1);
    /* a failed emit: its code comes back, no later job is emitted */
    memset(&c, 0, sizeof c);
    c.njobs = 500;
    c.window = 8;
    c.fail_job = -1;
    c.fail_emit = 40;
    assert_int_equal(par_ordered(c.njobs, 4, c.window, pool_job, pool_emit, &c), 9);
    assert_int_equal(c.emitted, 41);
    assert_false(c.bad);
}

/* ------------------------------------------------------------------------------------ */
/* The writers                                                                           */

/* A test picture: smooth ramps, noise, values above 1, negatives, NaN and infinities. */
static void fill_picture(image *img)
{
    tu_rng_seed(99);
    for (int y = 0; y < img->height; y++)
        for (int x = 0; x < img->width; x++) {
            float *p = img->rgb + ((size_t)y * img->width + x) * 3;
            p[0] = (float)x / (float)img->width;
            p[1] = (float)(tu_rng_next() >> 40) / (float)(1 << 24) * 1.5f;
            p[2] = (x + y) % 97 == 0   ? NAN
                   : (x * y) % 89 == 0 ? -INFINITY
                                       : (float)y * 0.01f - 0.5f;
        }
    img->rgb[0] = INFINITY;
}

/* Writes img as PNG with the options and checks every stored code against the
 * definition (the reader goes through libpng, which checks the chunk CRCs and the zlib
 * stream with its Adler-32). */
static void check_png(const image *img, const image_write_opts *o, const char *name)
{
    char path[PATHLEN], err[512] = "";
    image b;
    double scale = pow(2.0, o->exposure);
    tpath(path, name);
    assert_int_equal(image_write_ex(img, path, o, err, sizeof err), 0);
    assert_int_equal(image_read_png(path, 0, &b, err, sizeof err), 0);
    assert_int_equal(b.width, img->width);
    assert_int_equal(b.height, img->height);
    for (size_t i = 0; i < (size_t)img->width * img->height * 3; i++) {
        int want = code_exact(img->rgb[i], scale, o->tonemap), got = (int)lround(b.rgb[i] * 255.0);
        if (got != want)
            fail_msg("%s: value %zu (%g): stored %d, want %d", name, i, (double)img->rgb[i], got,
                     want);
    }
    image_free(&b);
}

static void test_png_pieces(void **state)
{
    /* many pieces of many rows; one row per piece (a row over CW_PNG_PIECE_BYTES); one
     * piece of a tall image; a single pixel */
    static const int sizes[][2] = {{700, 301}, {30000, 3}, {1, 5000}, {1, 1}, {129, 130}};
    image img;
    image_write_opts o;
    (void)state;
    for (size_t i = 0; i < sizeof sizes / sizeof sizes[0]; i++) {
        assert_int_equal(image_alloc(&img, sizes[i][0], sizes[i][1]), 0);
        fill_picture(&img);
        image_write_opts_default(&o);
        check_png(&img, &o, "pieces.png");
        o.exposure = 1.5;
        o.tonemap = IMAGE_TONEMAP_ACES;
        check_png(&img, &o, "pieces-aces.png");
        image_free(&img);
    }
}

/* The same image written twice gives the same bytes from the first IDAT chunk on (before
 * it, the creation time may differ). */
static const unsigned char *find_idat(const unsigned char *p, size_t n)
{
    for (size_t i = 4; i + 4 <= n; i++)
        if (memcmp(p + i, "IDAT", 4) == 0)
            return p + i - 4;
    fail_msg("no IDAT chunk");
    return NULL;
}

static void test_png_deterministic(void **state)
{
    char path[PATHLEN], err[512] = "";
    unsigned char *a, *b;
    size_t na, nb;
    image img;
    FILE *f;
    (void)state;
    assert_int_equal(image_alloc(&img, 333, 444), 0);
    fill_picture(&img);
    tpath(path, "det.png");
    a = malloc(1 << 22);
    b = malloc(1 << 22);
    assert_non_null(a);
    assert_non_null(b);
    assert_int_equal(image_write(&img, path, err, sizeof err), 0);
    assert_non_null(f = fopen(path, "rb"));
    na = fread(a, 1, 1 << 22, f);
    fclose(f);
    assert_int_equal(image_write(&img, path, err, sizeof err), 0);
    assert_non_null(f = fopen(path, "rb"));
    nb = fread(b, 1, 1 << 22, f);
    fclose(f);
    assert_int_equal(na, nb);
    assert_true(na < (1 << 22));
    assert_true(find_idat(a, na) - a == find_idat(b, nb) - b);
    assert_memory_equal(find_idat(a, na), find_idat(b, nb), na - (size_t)(find_idat(a, na) - a));
    free(a);
    free(b);
    image_free(&img);
}

static void test_exr_chunks(void **state)
{
    /* 63 chunks of 16 rows, the last one partial; and one chunk */
    static const int sizes[][2] = {{129, 1000}, {3, 5}, {1000, 17}};
    char path[PATHLEN], err[512] = "";
    image a, b;
    (void)state;
    for (size_t i = 0; i < sizeof sizes / sizeof sizes[0]; i++) {
        assert_int_equal(image_alloc(&a, sizes[i][0], sizes[i][1]), 0);
        tu_rng_seed(i + 1);
        for (size_t k = 0; k < (size_t)a.width * a.height * 3; k++) {
            uint32_t bits = (uint32_t)tu_rng_next();
            float f = float_of_bits(bits);
            /* every finite float and the infinities (the reader keeps NaN payloads but
             * memcmp would not care either way) */
            a.rgb[k] = isnan(f) ? INFINITY : k % 3 == 0 ? (float)k * 0.25f : f;
        }
        tpath(path, "chunks.exr");
        assert_int_equal(image_write(&a, path, err, sizeof err), 0);
        assert_int_equal(image_read_exr(path, &b, err, sizeof err), 0);
        assert_int_equal(b.width, a.width);
        assert_int_equal(b.height, a.height);
        assert_memory_equal(a.rgb, b.rgb, (size_t)a.width * a.height * 3 * sizeof(float));
        image_free(&b);
        image_free(&a);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_srgb8_bounds), cmocka_unit_test(test_srgb8_near_bounds),
        cmocka_unit_test(test_srgb8_sweep),  cmocka_unit_test(test_par_ordered),
        cmocka_unit_test(test_png_pieces),   cmocka_unit_test(test_png_deterministic),
        cmocka_unit_test(test_exr_chunks),
    };
    return cmocka_run_group_tests(tests, group_setup, group_teardown);
}
