/* Whole-image regressions: scenes rendered on PoCL against reference images in
 * tests/ref/. Tolerance: at most 0.1% of the pixels may differ by more than 1e-3 in
 * any channel (hit/miss flips on silhouettes between CPUs with different floating-point
 * contraction), and the mean absolute difference must stay below 1e-4.
 * On failure the rendered image and a diff image go to build/test-output/.
 * CW_UPDATE_REFS=1 rewrites the references instead (review them before committing).
 * Also: the batch CLI's renderer_set_scene_dropping renders the same image bit for bit. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "testutil.h"

#include "image.h"
#include "image_diff.h"
#include "image_read.h"
#include "render.h"
#include "scene.h"
#include "scene_load.h"

#define REF_DIR "tests/ref"
#define OUT_DIR "build/test-output"
#define PIXEL_TOL 1e-3
#define MAX_OVER_FRACTION 0.001
#define MAX_MEAN 1e-4

TU_RENDERER_FIXTURE(0)
static char err[2048];

static void regress(const char *scene_path, const char *name, int w, int h, int depth)
{
    scene s;
    image img, ref;
    image_diff_stats st;
    char ref_path[256], out_path[256], diff_path[256];
    long limit;

    snprintf(ref_path, sizeof ref_path, "%s/%s.exr", REF_DIR, name);
    snprintf(out_path, sizeof out_path, "%s/%s.exr", OUT_DIR, name);
    snprintf(diff_path, sizeof diff_path, "%s/%s-diff.png", OUT_DIR, name);
    scene_init(&s);
    if (scene_load(scene_path, &s, err, sizeof err) != 0 ||
        scene_finish(&s, w, h, depth, err, sizeof err) != 0 ||
        renderer_set_scene(R, &s, err, sizeof err) != 0 ||
        renderer_render(R, &img, err, sizeof err) != 0)
        fail_msg("%s: %s", scene_path, err);
    scene_free(&s);

    if (getenv("CW_UPDATE_REFS")) {
        if (image_write(&img, ref_path, err, sizeof err) != 0)
            fail_msg("%s", err);
        printf("  updated %s\n", ref_path);
        image_free(&img);
        return;
    }
    if (image_read_exr(ref_path, &ref, err, sizeof err) != 0)
        fail_msg("reference: %s", err);
    assert_int_equal(image_compare(&img, &ref, NULL, PIXEL_TOL, &st), 0);
    limit = (long)(MAX_OVER_FRACTION * (double)img.width * img.height);
    printf("  %s %dx%d: max |diff| %.3g at (%d,%d), mean %.3g, %ld pixels over %g (limit %ld)\n",
           name, img.width, img.height, st.max_abs, st.worst_x, st.worst_y, st.mean_abs, st.over,
           PIXEL_TOL, limit);
    if (st.over > limit || st.mean_abs > MAX_MEAN) {
        mkdir("build", 0777);
        mkdir(OUT_DIR, 0777);
        if (image_write(&img, out_path, err, sizeof err) != 0 ||
            image_write_diff(&img, &ref, NULL, PIXEL_TOL, 10.0, diff_path, err, sizeof err) != 0)
            fprintf(stderr, "  could not write the failure images: %s\n", err);
        else
            fprintf(stderr, "  rendered image: %s, diff image: %s\n", out_path, diff_path);
        image_free(&img);
        image_free(&ref);
        fail_msg("%s differs from %s beyond the tolerance", name, ref_path);
    }
    image_free(&img);
    image_free(&ref);
}

static void test_default_scene(void **state)
{
    (void)state;
    regress("scenes/default.json", "default-160x120", 160, 120, 0);
}

static void test_tetra(void **state)
{
    (void)state;
    regress("scenes/spd/tetra.nff", "tetra-128", 128, 128, 0);
}

static void test_projections(void **state)
{
    (void)state;
    regress("scenes/orthographic.json", "orthographic-96x72", 96, 72, 0);
    regress("scenes/oblique.json", "oblique-96x72", 96, 72, 0);
}

/* renderer_set_scene_dropping (what the batch CLI uses) renders what renderer_set_scene
 * renders, bit for bit, and leaves the scene without its primitives but with its lights
 * and materials. The scene has spheres, polygons, a triangle and a cone. */
static void load_at(const char *path, int w, int h, scene *s)
{
    scene_init(s);
    if (scene_load(path, s, err, sizeof err) != 0 || scene_finish(s, w, h, 0, err, sizeof err))
        fail_msg("%s: %s", path, err);
}

static void test_dropping(void **state)
{
    const char *path = "tests/scenes/regress/pixel-lanes.nff";
    scene kept, dropped;
    image a, b;
    size_t lights, materials;
    (void)state;
    load_at(path, 96, 72, &kept);
    load_at(path, 96, 72, &dropped);
    lights = dropped.lights.count;
    materials = dropped.materials.count;
    assert_true(dropped.spheres.count > 0 && dropped.cones.count > 0 &&
                dropped.polygons.count + dropped.triangles.count > 0);
    if (renderer_set_scene(R, &kept, err, sizeof err) != 0 ||
        renderer_render(R, &a, err, sizeof err) != 0 ||
        renderer_set_scene_dropping(R, &dropped, err, sizeof err) != 0 ||
        renderer_render(R, &b, err, sizeof err) != 0)
        fail_msg("%s: %s", path, err);
    assert_true(dropped.spheres.count == 0 && dropped.spheres.data == NULL);
    assert_true(dropped.triangles.count == 0 && dropped.triangles.data == NULL);
    assert_true(dropped.tri_normals.count == 0 && dropped.polygons.count == 0);
    assert_true(dropped.poly_verts.count == 0 && dropped.cones.count == 0);
    assert_true(dropped.lights.count == lights && dropped.materials.count == materials);
    assert_int_equal(a.width, b.width);
    assert_int_equal(a.height, b.height);
    assert_memory_equal(a.rgb, b.rgb, (size_t)a.width * a.height * 3 * sizeof *a.rgb);
    printf("  dropping: %dx%d identical, the scene's primitive arrays emptied\n", a.width,
           a.height);
    image_free(&a);
    image_free(&b);
    scene_free(&kept);
    scene_free(&dropped);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_default_scene),
        cmocka_unit_test(test_tetra),
        cmocka_unit_test(test_projections),
        cmocka_unit_test(test_dropping),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
