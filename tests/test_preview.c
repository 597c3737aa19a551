/* The preview window (clwhitted --preview), end to end under Xvfb with Mesa's software
 * OpenGL (xvfb-run -a, LIBGL_ALWAYS_SOFTWARE=1). A script (--preview-script) sends X input
 * events to the window through the X server: mouse drags (orbit, pan, shift-pan), wheel
 * notches, keys P (projection), - [ keypad- (depth down), = ] keypad+ (depth up), R (reset);
 * it also flies (W, E held for a simulated time) and resizes the window. After each step it
 * waits until every sample is done, grabs the window's pixels from the X server, and writes
 * the camera, size and depth it used as JSON (checked against what the keys should do).
 * Each grab must match a batch render (build/clwhitted --spp 16) of the same camera, and
 * each camera move must change the picture.
 *
 * Tolerance: the window shows 8-bit sRGB; a pixel matches when every channel is within
 * 2 codes of the batch PNG (the same encoding, so only rounding at a code boundary should
 * differ), and at least 99.9% of the pixels must match with a mean difference below
 * 0.25 codes. (Cameras go through JSON with 9 significant digits and the reader rebuilds
 * the basis, so a silhouette sample may flip: hence not 100%.) A "changed" picture has at
 * least 10% of its pixels more than 8 codes away.
 *
 * Also: without a display, --preview says so and exits 1; build/clwhitted links neither
 * GLFW nor OpenGL nor X11. Files go to build/test-output/preview/. Runs from the
 * repository root. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>

#include "testutil.h"

#include <cJSON.h>

#include "image.h"
#include "image_diff.h"
#include "image_read.h"
#include "scene.h"
#include "sys.h"

#define BIN "build/clwhitted"
#define OUT "build/test-output/preview"
#define CODE_TOL 2
#define MIN_MATCH 0.999
#define MAX_MEAN_CODES 0.25
#define CHANGED_CODES 8
#define MIN_CHANGED 0.10

static char err[2048];

/* Runs a shell command; returns its exit status (-1 if it did not exit). */
static int run(const char *cmd)
{
    int st = system(cmd);
    if (st == -1 || !WIFEXITED(st))
        return -1;
    return WEXITSTATUS(st);
}

static void out_dir(void)
{
    mkdir("build", 0777);
    mkdir("build/test-output", 0777);
    mkdir(OUT, 0777);
}

static char *slurp(const char *path)
{
    char *buf;
    size_t len;
    if (sys_read_file(path, CW_MAX_FILE_BYTES, 1, "a scene file", &buf, &len, err, sizeof err) != 0)
        fail_msg("%s", err);
    return buf;
}

static void print_file(const char *path)
{
    char *s;
    size_t len;
    if (sys_read_file(path, CW_MAX_FILE_BYTES, 1, "a scene file", &s, &len, err, sizeof err) == 0) {
        fputs(s, stdout);
        free(s);
    }
}

/* ---- without a display ------------------------------------------------------------ */

static void test_no_display(void **state)
{
    char *msg;
    (void)state;
    out_dir();
    assert_int_equal(run("env -u DISPLAY -u WAYLAND_DISPLAY " BIN " --preview scenes/default.json "
                         ">" OUT "/nodisplay.out 2>" OUT "/nodisplay.err"),
                     1);
    msg = slurp(OUT "/nodisplay.err");
    if (!strstr(msg, "clwhitted: --preview needs a display: DISPLAY is not set"))
        fail_msg("unexpected message: %s", msg);
    free(msg);
    /* a display that does not exist: GLFW itself fails to start */
    assert_int_equal(run("env -u WAYLAND_DISPLAY DISPLAY=:4093 " BIN
                         " --preview scenes/default.json >" OUT "/baddisplay.out 2>" OUT
                         "/baddisplay.err"),
                     1);
    msg = slurp(OUT "/baddisplay.err");
    if (!strstr(msg, "clwhitted: --preview needs a display: GLFW could not start"))
        fail_msg("unexpected message: %s", msg);
    free(msg);
}

static void test_no_gui_libraries_linked(void **state)
{
    char *s;
    (void)state;
    out_dir();
    assert_int_equal(run("ldd " BIN " >" OUT "/ldd.txt"), 0);
    s = slurp(OUT "/ldd.txt");
    if (strstr(s, "libglfw") || strstr(s, "libGL") || strstr(s, "libX11") || strstr(s, "libEGL"))
        fail_msg("build/clwhitted links a GUI library:\n%s", s);
    if (!strstr(s, "libOpenCL"))
        fail_msg("ldd output looks wrong:\n%s", s);
    free(s);
}

/* ---- under Xvfb ------------------------------------------------------------------- */

/* Reads a PNG's 8-bit values (not decoded), as fractions code/255. */
static void read_codes(const char *path, image *img)
{
    if (image_read_png(path, 0, img, err, sizeof err) != 0)
        fail_msg("%s", err);
}

/* Counts the pixels with a channel more than `codes` apart; mean difference in codes. */
static long count_over(const image *a, const image *b, int codes, double *mean)
{
    image_diff_stats st;
    if (image_compare(a, b, NULL, (codes + 0.5) / 255.0, &st) != 0)
        fail_msg("sizes differ: %dx%d and %dx%d", a->width, a->height, b->width, b->height);
    if (mean)
        *mean = st.mean_abs * 255.0;
    return st.over;
}

/* The grab must match the batch PNG within the tolerance. */
static void assert_matches(const char *grab, const char *batch)
{
    image a, b;
    double mean;
    long over, n, limit;
    read_codes(grab, &a);
    read_codes(batch, &b);
    over = count_over(&a, &b, CODE_TOL, &mean);
    n = (long)a.width * a.height;
    limit = (long)((1.0 - MIN_MATCH) * (double)n);
    printf("  %s vs %s: %ld of %ld pixels over %d codes (limit %ld), mean %.4f codes\n", grab,
           batch, over, n, CODE_TOL, limit, mean);
    if (over > limit || mean > MAX_MEAN_CODES) {
        char diff[512];
        snprintf(diff, sizeof diff, "%s-diff.png", grab);
        if (image_write_diff(&a, &b, NULL, (CODE_TOL + 0.5) / 255.0, 8.0, diff, err, sizeof err) ==
            0)
            printf("  diff image: %s\n", diff);
        fail_msg("%s does not match the batch render %s", grab, batch);
    }
    image_free(&a);
    image_free(&b);
}

static void assert_changed(const char *p1, const char *p2)
{
    image a, b;
    long over, n;
    read_codes(p1, &a);
    read_codes(p2, &b);
    if (a.width != b.width || a.height != b.height)
        return; /* a new size is a change */
    over = count_over(&a, &b, CHANGED_CODES, NULL);
    n = (long)a.width * a.height;
    printf("  %s vs %s: %.1f%% of the pixels changed by more than %d codes\n", p1, p2,
           100.0 * over / n, CHANGED_CODES);
    if (over < (long)(MIN_CHANGED * n))
        fail_msg("the camera move did not change the picture enough (%s, %s)", p1, p2);
    image_free(&a);
    image_free(&b);
}

/* Writes OUT/NAME-scene.json: scenes/default.json with the image, max_depth and camera
 * members of the preview's OUT/NAME.json, then renders it in batch to OUT/NAME-batch.png. */
static void batch_of_camera(const char *name, const char *want_projection, int want_w, int want_h,
                            int want_depth)
{
    char path[256], cmd[1024], *text, *cam_text;
    cJSON *scene_json, *cam_json, *proj, *img;
    const char *keys[] = {"image", "max_depth", "camera"};
    FILE *f;
    int i;

    text = slurp("scenes/default.json");
    snprintf(path, sizeof path, OUT "/%s.json", name);
    cam_text = slurp(path);
    scene_json = cJSON_Parse(text);
    cam_json = cJSON_Parse(cam_text);
    if (!scene_json || !cam_json)
        fail_msg("cannot parse scenes/default.json or %s:\n%s", path, cam_text);
    proj = cJSON_GetObjectItemCaseSensitive(cJSON_GetObjectItemCaseSensitive(cam_json, "camera"),
                                            "projection");
    img = cJSON_GetObjectItemCaseSensitive(cam_json, "image");
    if (!cJSON_IsString(proj) || strcmp(proj->valuestring, want_projection) != 0)
        fail_msg("%s: projection is not %s:\n%s", path, want_projection, cam_text);
    if (cJSON_GetObjectItemCaseSensitive(img, "width")->valueint != want_w ||
        cJSON_GetObjectItemCaseSensitive(img, "height")->valueint != want_h)
        fail_msg("%s: size is not %dx%d:\n%s", path, want_w, want_h, cam_text);
    if (cJSON_GetObjectItemCaseSensitive(cam_json, "max_depth")->valueint != want_depth)
        fail_msg("%s: depth is not %d:\n%s", path, want_depth, cam_text);
    for (i = 0; i < 3; i++) {
        cJSON *item = cJSON_DetachItemFromObjectCaseSensitive(cam_json, keys[i]);
        if (!item)
            fail_msg("%s has no \"%s\"", path, keys[i]);
        cJSON_ReplaceItemInObjectCaseSensitive(scene_json, keys[i], item);
    }
    free(text);
    text = cJSON_Print(scene_json);
    snprintf(path, sizeof path, OUT "/%s-scene.json", name);
    f = fopen(path, "w");
    if (!f || !text || fputs(text, f) == EOF || fclose(f) != 0)
        fail_msg("cannot write %s", path);
    free(text);
    free(cam_text);
    cJSON_Delete(scene_json);
    cJSON_Delete(cam_json);
    snprintf(cmd, sizeof cmd, BIN " -q --spp 16 -o " OUT "/%s-batch.png " OUT "/%s-scene.json",
             name, name);
    if (run(cmd) != 0)
        fail_msg("batch render failed: %s", cmd);
}

static const char script_text[] = "# a: the scene's camera\n"
                                  "wait\n"
                                  "grab " OUT "/a.png\n"
                                  "camera " OUT "/a.json\n"
                                  "save " OUT "/a-save\n"
                                  "# b: orbit, pan, zoom out, fly forward and up\n"
                                  "drag left 40 -15\n"
                                  "drag right 12 6\n"
                                  "scroll -1\n"
                                  "hold w 0.3\n"
                                  "hold e 0.1\n"
                                  "wait\n"
                                  "grab " OUT "/b.png\n"
                                  "camera " OUT "/b.json\n"
                                  "# c: orthographic, depth 6 -> 2 (two keys each)\n"
                                  "key p\n"
                                  "key minus\n"
                                  "key minus\n"
                                  "key left_bracket\n"
                                  "key kp_subtract\n"
                                  "wait\n"
                                  "grab " OUT "/c.png\n"
                                  "camera " OUT "/c.json\n"
                                  "# d: oblique, and a resized window\n"
                                  "key p\n"
                                  "drag shift-left -10 4\n"
                                  "size 200 100\n"
                                  "wait\n"
                                  "grab " OUT "/d.png\n"
                                  "camera " OUT "/d.json\n"
                                  "# e: reset (at the new size), depth back to 6\n"
                                  "key r\n"
                                  "key equal\n"
                                  "key equal\n"
                                  "key right_bracket\n"
                                  "key kp_add\n"
                                  "wait\n"
                                  "grab " OUT "/e.png\n"
                                  "camera " OUT "/e.json\n"
                                  "quit\n";

static void test_window_matches_batch(void **state)
{
    FILE *f;
    int rc;
    char *text;
    image saved, batch;
    image_diff_stats st;
    (void)state;
    out_dir();
    if (run("command -v xvfb-run >/dev/null") != 0)
        fail_msg("xvfb-run is missing: run tools/install-deps (Debian package xvfb)");
    f = fopen(OUT "/script", "w");
    if (!f || fputs(script_text, f) == EOF || fclose(f) != 0)
        fail_msg("cannot write " OUT "/script");
    remove(OUT "/e.png");
    rc = run("xvfb-run -a -s '-screen 0 640x480x24' env LIBGL_ALWAYS_SOFTWARE=1 " BIN
             " -W 160 -H 120 --preview-script " OUT "/script scenes/default.json >" OUT
             "/preview.out 2>" OUT "/preview.err");
    print_file(OUT "/preview.out");
    if (rc != 0) {
        print_file(OUT "/preview.err");
        fail_msg("the scripted preview exited with %d", rc);
    }
    text = slurp(OUT "/preview.out");
    if (!strstr(text, "input sent as X events"))
        fail_msg("the script's input did not go through the X server");
    free(text);

    /* a: the scene's own camera, against a plain batch render */
    assert_int_equal(
        run(BIN " -q -W 160 -H 120 --spp 16 -o " OUT "/a-batch.exr scenes/default.json"), 0);
    if (image_read_exr(OUT "/a-batch.exr", &batch, err, sizeof err) != 0 ||
        image_write(&batch, OUT "/a-batch.png", err, sizeof err) != 0 ||
        image_read_exr(OUT "/a-save.exr", &saved, err, sizeof err) != 0)
        fail_msg("%s", err);
    /* F5's images carry the batch images' metadata: title, software, device, settings */
    {
        static const char *const want[] = {"Title",
                                           "default.json",
                                           "Software",
                                           "clwhitted ",
                                           "Source",
                                           "160x120, depth 6, spp 16 (16 done), "
                                           "precision robust, exposure +0 EV, "
                                           "tonemap clamp, preview"};
        FILE *pf = fopen(OUT "/a-save.png", "rb");
        char buf[65536];
        size_t n, i;
        assert_non_null(pf);
        n = fread(buf, 1, sizeof buf, pf);
        fclose(pf);
        for (i = 0; i < sizeof want / sizeof *want; i++) {
            size_t k, len = strlen(want[i]);
            int found = 0;
            for (k = 0; k + len <= n && !found; k++)
                found = memcmp(buf + k, want[i], len) == 0;
            if (!found)
                fail_msg("a-save.png has no '%s' in its metadata", want[i]);
        }
    }
    /* the saved linear image is the renderer's, so it matches the batch EXR closely */
    assert_int_equal(image_compare(&saved, &batch, NULL, 1e-4, &st), 0);
    printf("  a-save.exr vs a-batch.exr: max |diff| %.3g, %ld pixels over 1e-4\n", st.max_abs,
           st.over);
    if (st.over > (long)((1.0 - MIN_MATCH) * 160 * 120))
        fail_msg("the saved EXR differs from the batch render");
    image_free(&saved);
    image_free(&batch);
    assert_matches(OUT "/a.png", OUT "/a-batch.png");

    batch_of_camera("b", "perspective", 160, 120, 6);
    assert_matches(OUT "/b.png", OUT "/b-batch.png");
    assert_changed(OUT "/a.png", OUT "/b.png");

    batch_of_camera("c", "orthographic", 160, 120, 2);
    assert_matches(OUT "/c.png", OUT "/c-batch.png");
    assert_changed(OUT "/b.png", OUT "/c.png");

    batch_of_camera("d", "oblique", 200, 100, 2);
    assert_matches(OUT "/d.png", OUT "/d-batch.png");

    /* e: reset at 200x100 is the scene's camera at that size, as the batch renderer makes
     * it from the scene file */
    batch_of_camera("e", "perspective", 200, 100, 6);
    assert_matches(OUT "/e.png", OUT "/e-batch.png");
    assert_int_equal(
        run(BIN " -q -W 200 -H 100 --spp 16 -o " OUT "/e-plain.png scenes/default.json"), 0);
    assert_matches(OUT "/e.png", OUT "/e-plain.png");
    assert_changed(OUT "/d.png", OUT "/e.png");
}

/* The C key: after a move, the printed batch command line (with the camera file written
 * beside a copy of the scene) renders the window's picture. The H key: the overlay covers
 * the picture (keys, samples, rate, camera) and the help is printed; H again removes it. */
static const char camera_script[] = "wait\n"
                                    "drag left 30 -12\n"
                                    "scroll 1\n"
                                    "wait\n"
                                    "grab " OUT "/f.png\n"
                                    "key h\n"
                                    "grab " OUT "/f-overlay.png\n"
                                    "key h\n"
                                    "grab " OUT "/f-after.png\n"
                                    "key c\n"
                                    "wait\n"
                                    "quit\n";

static void test_camera_key(void **state)
{
    char *text, *line, *end, cmd[4096];
    FILE *f;
    int rc;
    (void)state;
    out_dir();
    if (run("command -v xvfb-run >/dev/null") != 0)
        fail_msg("xvfb-run is missing: run tools/install-deps (Debian package xvfb)");
    f = fopen(OUT "/camera-script", "w");
    if (!f || fputs(camera_script, f) == EOF || fclose(f) != 0)
        fail_msg("cannot write " OUT "/camera-script");
    remove(OUT "/view-camera.json");
    assert_int_equal(run("cp scenes/default.json " OUT "/view.json"), 0);
    rc = run("xvfb-run -a -s '-screen 0 640x480x24' env LIBGL_ALWAYS_SOFTWARE=1 " BIN
             " -W 160 -H 120 --preview-script " OUT "/camera-script " OUT "/view.json >" OUT
             "/camera.out 2>" OUT "/camera.err");
    print_file(OUT "/camera.out");
    if (rc != 0) {
        print_file(OUT "/camera.err");
        fail_msg("the scripted preview exited with %d", rc);
    }
    text = slurp(OUT "/camera.out");
    if (!strstr(text, "clwhitted: camera written to " OUT "/view-camera.json"))
        fail_msg("the C key did not say where it wrote the camera");
    if (!strstr(text, "\"camera\": {"))
        fail_msg("the C key did not print the JSON camera block");
    line = strstr(text, "\n  clwhitted ");
    if (!line)
        fail_msg("the C key printed no batch command line");
    line += strlen("\n  clwhitted ");
    end = strchr(line, '\n');
    assert_non_null(end);
    *end = '\0';
    if (!strstr(line, "--camera " OUT "/view-camera.json " OUT "/view.json"))
        fail_msg("the command line does not name the camera file and the scene: %s", line);
    snprintf(cmd, sizeof cmd, BIN " -q -o " OUT "/f-batch.png %s", line);
    printf("  %s\n", cmd);
    free(text);
    if (run(cmd) != 0)
        fail_msg("the printed command failed: %s", cmd);
    assert_matches(OUT "/f.png", OUT "/f-batch.png");
    assert_int_equal(run(BIN " -q -W 160 -H 120 --spp 16 -o " OUT "/f-plain.png " OUT "/view.json"),
                     0);
    assert_changed(OUT "/f-plain.png", OUT "/f.png");
    assert_changed(OUT "/f.png", OUT "/f-overlay.png");
    assert_matches(OUT "/f.png", OUT "/f-after.png");
    text = slurp(OUT "/camera.out");
    if (!strstr(text, "preview keys:"))
        fail_msg("H printed no help");
    free(text);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_no_display),
        cmocka_unit_test(test_no_gui_libraries_linked),
        cmocka_unit_test(test_window_matches_batch),
        cmocka_unit_test(test_camera_key),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
