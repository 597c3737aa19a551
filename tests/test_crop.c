/* --crop renders exactly the pixels of the full render in its window: several scenes
 * (perspective, refraction, SPD scenes), both execution strategies, one sample, four
 * samples and the SPD corners, windows at the corners, in the middle, one pixel and the
 * whole image. Tolerance: none, the values must be equal bit for bit (a cropped pixel's
 * eye ray is the full render's, computed with the same float operations: kernels/camera.h).
 * On failure the full render, the crop and a diff image (differing pixels in red) go to
 * build/test-output/. Also: windows outside the image are refused, and the renderer
 * renders the whole image again once the crop is lifted. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "testutil.h"

#include "image.h"
#include "image_diff.h"
#include "render.h"
#include "scene.h"
#include "scene_load.h"

#define OUT_DIR "build/test-output"
#define W 37
#define H 29

TU_RENDERER_FIXTURE(1)
static char err[2048];

static const char *const scenes[] = {
    "scenes/default.json",
    "tests/scenes/portability/spd-balls2.nff",
    "tests/scenes/portability/spd-tetra3.nff",
    "tests/scenes/portability/polygons.nff",
    "tests/scenes/pov/mirrors.nff",
};

/* x0, x1, y0, y1 */
static const int windows[][4] = {
    {0, W, 0, H}, {0, 5, 0, 4}, {W - 6, W, H - 3, H}, {11, 12, 17, 18}, {3, 30, 9, 21},
};

static void settings(int strategy, int spp, int spd, const int *crop)
{
    render_settings st;
    render_settings_default(&st);
    st.strategy = strategy;
    st.spp = spp;
    st.spd = spd;
    if (crop)
        memcpy(st.crop, crop, sizeof st.crop);
    if (renderer_set_settings(R, &st, err, sizeof err) != 0)
        fail_msg("%s", err);
}

/* The crop window of full as an image of its own. */
static void cut(const image *full, const int *c, image *out)
{
    int y;
    assert_int_equal(image_alloc(out, c[1] - c[0], c[3] - c[2]), 0);
    for (y = c[2]; y < c[3]; y++)
        memcpy(out->rgb + (size_t)(y - c[2]) * (size_t)out->width * 3,
               full->rgb + ((size_t)y * (size_t)full->width + (size_t)c[0]) * 3,
               (size_t)out->width * 3 * sizeof(float));
}

static void save_failure(const char *tag, const image *full, const image *want, const image *got)
{
    char path[512];
    mkdir("build", 0777);
    mkdir(OUT_DIR, 0777);
    snprintf(path, sizeof path, OUT_DIR "/crop-%s-full.exr", tag);
    image_write(full, path, err, sizeof err);
    snprintf(path, sizeof path, OUT_DIR "/crop-%s-got.exr", tag);
    image_write(got, path, err, sizeof err);
    snprintf(path, sizeof path, OUT_DIR "/crop-%s-diff.png", tag);
    image_write_diff(want, got, NULL, 0.0, 100.0, path, err, sizeof err);
    fprintf(stderr, "  wrote " OUT_DIR "/crop-%s-{full.exr,got.exr,diff.png}\n", tag);
}

static void test_crop_exact(void **state)
{
    static const int strategies[] = {RENDER_PIXEL, RENDER_WAVEFRONT};
    static const int modes[][2] = {{1, 0}, {4, 0}, {1, 1}}; /* spp, spd */
    size_t si, wi, k, m;
    int checked = 0;
    (void)state;
    for (si = 0; si < sizeof scenes / sizeof *scenes; si++) {
        scene s;
        scene_init(&s);
        if (scene_load(scenes[si], &s, err, sizeof err) != 0 ||
            scene_finish(&s, W, H, 0, err, sizeof err) != 0)
            fail_msg("%s: %s", scenes[si], err);
        for (k = 0; k < 2; k++)
            for (m = 0; m < 3; m++) {
                image full = {0, 0, NULL};
                settings(strategies[k], modes[m][0], modes[m][1], NULL);
                if (renderer_set_scene(R, &s, err, sizeof err) != 0 ||
                    renderer_render(R, &full, err, sizeof err) != 0)
                    fail_msg("%s: %s", scenes[si], err);
                assert_int_equal(full.width, W);
                for (wi = 0; wi < sizeof windows / sizeof *windows; wi++) {
                    const int *c = windows[wi];
                    image got = {0, 0, NULL}, want = {0, 0, NULL};
                    settings(strategies[k], modes[m][0], modes[m][1], c);
                    if (renderer_render(R, &got, err, sizeof err) != 0)
                        fail_msg("%s: %s", scenes[si], err);
                    cut(&full, c, &want);
                    assert_int_equal(got.width, c[1] - c[0]);
                    assert_int_equal(got.height, c[3] - c[2]);
                    if (memcmp(got.rgb, want.rgb,
                               (size_t)got.width * got.height * 3 * sizeof(float)) != 0) {
                        char tag[64];
                        snprintf(tag, sizeof tag, "%zu-%zu-%zu-%zu", si, k, m, wi);
                        save_failure(tag, &full, &want, &got);
                        fail_msg("%s, %s kernel, spp %d%s: crop %d,%d,%d,%d differs from the "
                                 "full render",
                                 scenes[si], render_strategy_name(strategies[k]), modes[m][0],
                                 modes[m][1] ? " spd" : "", c[0], c[1], c[2], c[3]);
                    }
                    image_free(&got);
                    image_free(&want);
                    checked++;
                }
                /* the crop lifted: the whole image again, the same as before */
                {
                    image again = {0, 0, NULL};
                    settings(strategies[k], modes[m][0], modes[m][1], NULL);
                    if (renderer_render(R, &again, err, sizeof err) != 0)
                        fail_msg("%s: %s", scenes[si], err);
                    assert_int_equal(again.width, W);
                    assert_int_equal(again.height, H);
                    assert_memory_equal(again.rgb, full.rgb, (size_t)W * H * 3 * sizeof(float));
                    image_free(&again);
                }
                image_free(&full);
            }
        scene_free(&s);
    }
    printf("%d crops equal to the full render\n", checked);
}

static void test_crop_outside(void **state)
{
    static const int bad[][4] = {{0, W + 1, 0, H}, {0, W, 0, H + 1}, {5, 5, 0, 1}, {0, 1, 3, 2}};
    scene s;
    size_t i;
    (void)state;
    scene_init(&s);
    if (scene_load("scenes/default.json", &s, err, sizeof err) != 0 ||
        scene_finish(&s, W, H, 0, err, sizeof err) != 0)
        fail_msg("%s", err);
    settings(RENDER_AUTO, 1, 0, NULL);
    assert_int_equal(renderer_set_scene(R, &s, err, sizeof err), 0);
    for (i = 0; i < sizeof bad / sizeof *bad; i++) {
        image img = {0, 0, NULL};
        render_settings st;
        render_settings_default(&st);
        memcpy(st.crop, bad[i], sizeof st.crop);
        assert_int_not_equal(render_check_crop(&st, W, H, err, sizeof err), 0);
        assert_non_null(strstr(err, "--crop"));
        assert_int_equal(renderer_set_settings(R, &st, err, sizeof err), 0);
        assert_int_not_equal(renderer_render(R, &img, err, sizeof err), 0);
        assert_null(img.rgb);
    }
    scene_free(&s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_crop_exact),
        cmocka_unit_test(test_crop_outside),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
