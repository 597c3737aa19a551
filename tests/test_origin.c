/* Scenes far from the origin render as they do at the origin (docs/model.md, "Far from the
 * origin"): the scene model keeps positions in double, and the kernel arrays are converted
 * to float relative to a local origin at the camera's eye (host/devscene.c).
 *
 * 1. tests/scenes/origin/far.nff (every primitive kind, mirrors, refraction, two lights
 *    with shadows, a triangle 0.01 above the floor) moved by 1e3, 1e5 and 1e6 along
 *    three directions that cover every axis both ways, and read back from a file written
 *    at 1e6 (the readers' path): each image must match the one at the origin — at most
 *    FAR_MAX_OVER of the pixels differ by more than FAR_TOL in a channel, and the mean
 *    difference is below FAR_MAX_MEAN. The same scenes with the float-only conversion (no
 *    local origin: renderer_debug_world_origin) must fail that check at 1e5 and 1e6.
 * 2. tests/scenes/origin/huge.nff: a ground polygon 1e7 across with small objects near the
 *    camera, at the origin and moved by 1e6, against the same scene with a floor 120
 *    across (which covers the whole view).
 * Each case prints the fraction of pixels off by more than 1e-3 and by more than 0.1; a
 * failing case writes its image and a diff image into build/test-output/. Runs from the
 * repository root. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "testutil.h"

#include "image.h"
#include "image_diff.h"
#include "render.h"
#include "render_debug.h"
#include "scene.h"
#include "scene_load.h"

#define FAR_SCENE "tests/scenes/origin/far.nff"
#define FAR_MOVED "tests/scenes/origin/far-moved.nff" /* far.nff moved by FAR_MOVED_BY */
#define FAR_MOVED_BY 1e6, -1e6, 1e6
#define HUGE_SCENE "tests/scenes/origin/huge.nff"
#define OUT_DIR "build/test-output"

#define FAR_TOL 0.1         /* a pixel differs when a channel moves by more than this */
#define FAR_MAX_OVER 0.002  /* at most 0.2% of the pixels (a handful of edge pixels) */
#define FAR_MAX_MEAN 2e-3   /* and the mean absolute difference below this */
#define HUGE_HALF_SMALL 60. /* the reference floor's half width */

TU_RENDERER_FIXTURE(1)
static char err[2048];

/* Moves every position of s by (dx, dy, dz), in double: camera, lights, geometry. */
static void move_scene(scene *s, double dx, double dy, double dz)
{
    size_t i;
    int k;
#define MOVE(p) ((p).x += dx, (p).y += dy, (p).z += dz)
    MOVE(s->camera.eye);
    for (i = 0; i < s->lights.count; i++)
        MOVE(SCENE_AT(s->lights, scene_light, i).position);
    for (i = 0; i < s->spheres.count; i++)
        MOVE(SCENE_AT(s->spheres, scene_sphere, i).center);
    for (i = 0; i < s->triangles.count; i++)
        for (k = 0; k < 3; k++)
            MOVE(SCENE_AT(s->triangles, scene_triangle, i).p[k]);
    for (i = 0; i < s->poly_verts.count; i++)
        MOVE(SCENE_AT(s->poly_verts, vec3d, i));
    for (i = 0; i < s->cones.count; i++) {
        MOVE(SCENE_AT(s->cones, scene_cone, i).base);
        MOVE(SCENE_AT(s->cones, scene_cone, i).apex);
    }
#undef MOVE
}

static void load(const char *path, scene *s)
{
    scene_init(s);
    if (scene_load(path, s, err, sizeof err) != 0)
        fail_msg("%s", err);
}

/* Renders s (finished here) with or without the local origin. */
static void render(scene *s, int world_origin, image *img)
{
    renderer_debug_world_origin(R, world_origin);
    if (scene_finish(s, 0, 0, 0, err, sizeof err) != 0 ||
        renderer_set_scene(R, s, err, sizeof err) != 0 ||
        renderer_render(R, img, err, sizeof err) != 0)
        fail_msg("%s", err);
    renderer_debug_world_origin(R, 0);
}

static void render_file(const char *path, double dx, double dy, double dz, int world_origin,
                        image *img)
{
    scene s;
    load(path, &s);
    move_scene(&s, dx, dy, dz);
    render(&s, world_origin, img);
    scene_free(&s);
}

typedef struct {
    double over3, over1; /* fractions of pixels off by more than 1e-3 and 0.1 */
    double over_tol, mean;
    int pass;
} cmp_result;

/* Compares img with ref under the check; on `expect_pass` and a failure, writes both. */
static cmp_result compare(const image *ref, const image *img, const char *name, int expect_pass)
{
    image_diff_stats st;
    cmp_result c;
    double npx = (double)ref->width * ref->height;
    assert_int_equal(image_compare(ref, img, NULL, 1e-3, &st), 0);
    c.over3 = st.over / npx;
    assert_int_equal(image_compare(ref, img, NULL, 0.1, &st), 0);
    c.over1 = st.over / npx;
    assert_int_equal(image_compare(ref, img, NULL, FAR_TOL, &st), 0);
    c.over_tol = st.over / npx;
    c.mean = st.mean_abs;
    c.pass = c.over_tol <= FAR_MAX_OVER && c.mean < FAR_MAX_MEAN;
    if (expect_pass && !c.pass) {
        char path[512];
        mkdir("build", 0777);
        mkdir(OUT_DIR, 0777);
        snprintf(path, sizeof path, OUT_DIR "/origin-%s.png", name);
        image_write(img, path, err, sizeof err);
        snprintf(path, sizeof path, OUT_DIR "/origin-%s-diff.png", name);
        image_write_diff(ref, img, NULL, FAR_TOL, 10, path, err, sizeof err);
        image_write(ref, OUT_DIR "/origin-ref.png", err, sizeof err);
        printf("    diff image: %s\n", path);
    }
    return c;
}

static void print_row(const char *what, const cmp_result *local, const cmp_result *flt)
{
    printf("  %-28s local origin: %6.2f%% > 1e-3, %5.2f%% > 0.1 (mean %.1e)%s", what,
           100 * local->over3, 100 * local->over1, local->mean, local->pass ? "" : "  FAIL");
    if (flt)
        printf(";  float only: %6.2f%% > 1e-3, %5.2f%% > 0.1 (mean %.1e)%s", 100 * flt->over3,
               100 * flt->over1, flt->mean, flt->pass ? "  (passes)" : "  (fails)");
    printf("\n");
}

/* 1. far.nff moved by 1e3, 1e5, 1e6 along three directions, and read at 1e6 from a file. */
static void test_far_offsets(void **state)
{
    static const double mags[] = {1e3, 1e5, 1e6};
    static const double dirs[3][3] = {{1, 1, 1}, {-1, -1, -1}, {1.2371, -0.7129, -1.0537}};
    image ref;
    int local_fails = 0, float_passes = 0;
    size_t im, id;
    (void)state;
    render_file(FAR_SCENE, 0, 0, 0, 0, &ref);
    {
        image flt;
        cmp_result c;
        render_file(FAR_SCENE, 0, 0, 0, 1, &flt);
        c = compare(&ref, &flt, "origin-float", 0);
        printf("  at the origin, float only against the local origin: %.2f%% > 1e-3, %.2f%% > "
               "0.1\n",
               100 * c.over3, 100 * c.over1);
        image_free(&flt);
    }
    for (im = 0; im < sizeof mags / sizeof mags[0]; im++) {
        for (id = 0; id < 3; id++) {
            double d[3];
            char name[96], what[96];
            image loc, flt;
            cmp_result cl, cf;
            int k;
            for (k = 0; k < 3; k++)
                d[k] = dirs[id][k] * mags[im];
            snprintf(what, sizeof what, "(%+.4g, %+.4g, %+.4g):", d[0], d[1], d[2]);
            snprintf(name, sizeof name, "%g_%g_%g", d[0], d[1], d[2]);
            render_file(FAR_SCENE, d[0], d[1], d[2], 0, &loc);
            render_file(FAR_SCENE, d[0], d[1], d[2], 1, &flt);
            cl = compare(&ref, &loc, name, 1);
            cf = compare(&ref, &flt, name, 0);
            print_row(what, &cl, &cf);
            local_fails += !cl.pass;
            /* float only: 1e5 and up must fail (at 1e3 it is near enough, a figure only) */
            if (mags[im] >= 1e5)
                float_passes += cf.pass;
            image_free(&loc);
            image_free(&flt);
        }
    }
    {
        /* the readers' path: the file written at (1e6, -1e6, 1e6) */
        image loc, flt;
        cmp_result cl, cf;
        scene s;
        load(FAR_MOVED, &s);
        render(&s, 0, &loc);
        scene_free(&s);
        load(FAR_MOVED, &s);
        render(&s, 1, &flt);
        scene_free(&s);
        cl = compare(&ref, &loc, "file", 1);
        cf = compare(&ref, &flt, "file", 0);
        print_row(FAR_MOVED ":", &cl, &cf);
        local_fails += !cl.pass;
        float_passes += cf.pass;
        image_free(&loc);
        image_free(&flt);
    }
    printf("  check: at most %.1f%% of the pixels over %g, mean below %g; local origin: %d "
           "fail; float only: %d of 10 at 1e5 and 1e6 pass\n",
           100 * FAR_MAX_OVER, FAR_TOL, FAR_MAX_MEAN, local_fails, float_passes);
    image_free(&ref);
    assert_int_equal(local_fails, 0);
    assert_int_equal(float_passes, 0);
}

/* 2. A ground polygon 1e7 across: the near objects as with a small floor. */
static void test_huge_ground(void **state)
{
    static const double offs[] = {0, 1e6, -1e6};
    image ref;
    scene s;
    size_t i, io;
    int fails = 0;
    (void)state;
    load(HUGE_SCENE, &s);
    /* the reference: the first polygon (the floor) cut down to HUGE_HALF_SMALL */
    for (i = 0; i < 4; i++) {
        vec3d *v = &SCENE_AT(s.poly_verts, vec3d, i);
        v->x = v->x < 0 ? -HUGE_HALF_SMALL : HUGE_HALF_SMALL;
        v->z = v->z < 0 ? -HUGE_HALF_SMALL : HUGE_HALF_SMALL;
    }
    render(&s, 0, &ref);
    scene_free(&s);
    for (io = 0; io < sizeof offs / sizeof offs[0]; io++) {
        image loc, flt;
        cmp_result cl, cf;
        char name[64], what[96];
        snprintf(name, sizeof name, "huge_%g", offs[io]);
        snprintf(what, sizeof what, "1e7 floor, moved by %g:", offs[io]);
        render_file(HUGE_SCENE, offs[io], offs[io], offs[io], 0, &loc);
        render_file(HUGE_SCENE, offs[io], offs[io], offs[io], 1, &flt);
        cl = compare(&ref, &loc, name, 1);
        cf = compare(&ref, &flt, name, 0);
        print_row(what, &cl, &cf);
        fails += !cl.pass;
        image_free(&loc);
        image_free(&flt);
    }
    image_free(&ref);
    assert_int_equal(fails, 0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_far_offsets),
        cmocka_unit_test(test_huge_ground),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
