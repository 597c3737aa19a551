/* The two execution strategies give the same image, on the real kernels on PoCL: every
 * scene of scenes/ and tests/scenes/ (and the SPD scenes in ../shared/scenes/spd when
 * present) rendered small with the wavefront and with the per-pixel kernel, plain, with
 * --spp 4, --spd, the fast path and --stats, plus renders large enough for several
 * per-pixel launches per band and the preview's progressive path. The images must be
 * identical bit for bit and every ray count and the passes equal.
 * Tolerance: only in scenes with refraction (a material with kt > 0 at depth > 1) may a
 * value differ (and on the fast path: FAST_REL_TOL), by at most REFRACTION_REL_TOL of its
 * size (about 8 ulps): the wavefront
 * adds a level's shading points to a pixel in the order its atomics take, which is the
 * per-pixel kernel's order except now and then (docs/model.md). Trees too wide for the
 * per-pixel queue (depth 7 or more; forced with a queue of 2 rays) are walked depth first,
 * which reorders up to a hundred terms of a pixel: DEPTH_FIRST_REL_TOL (about (n - 1) ulps
 * for n terms). On failure both images and a diff image (differing pixels in red) go to
 * build/test-output/.
 * Also: the strategy chosen per device, its build option, bad settings, --kernel, the test
 * hooks after a per-pixel render, and progress and cancelling with the per-pixel kernel. */
#include <dirent.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "testutil.h"

#include "cli.h"
#include "image.h"
#include "image_diff.h"
#include "render.h"
#include "render_debug.h"
#include "scene.h"
#include "scene_load.h"

#define OUT_DIR "build/test-output"
#define SPD_DIR "../shared/scenes/spd"
#define SMALL_W 40
#define SMALL_H 30
/* more than 65536 pixels: two launches of the per-pixel kernel in one band */
#define LARGE_W 256
#define LARGE_H 257
#define REFRACTION_REL_TOL 1e-6
/* The fast path is built with -cl-fast-relaxed-math, which lets the compiler reassociate
 * and contract each kernel's code its own way: the per-pixel kernel's loop over a run of
 * pixels and the wavefront's kernels come out with different float operations (measured:
 * up to 1.3e-4 relative on PoCL, on 17 of 22 scenes). There every value may differ by up
 * to FAST_REL_TOL, and where mirrors amplify such a difference into another reflected
 * object (balls, rings: about 1% of the values, up to 0.17) at most FAST_MAX_OVER of the
 * values may differ more and the ray counts by FAST_COUNT_TOL of their size. */
#define FAST_REL_TOL 1e-3
#define FAST_MAX_OVER 0.03
#define FAST_COUNT_TOL 0.01
#define DEPTH_FIRST_REL_TOL 2e-5
#define MAX_SCENES 256

TU_RENDERER_FIXTURE(1)
static char err[2048];

/* ======================================================================================== */
/* The scenes                                                                               */

static char *scene_paths[MAX_SCENES];
static int num_scenes;

static int has_ext(const char *name, const char *ext)
{
    size_t n = strlen(name), e = strlen(ext);
    return n > e && strcmp(name + n - e, ext) == 0;
}

/* Every .nff and .json file under dir (recursively), appended to scene_paths. */
static void find_scenes(const char *dir)
{
    DIR *d = opendir(dir);
    struct dirent *e;
    if (!d)
        return;
    while ((e = readdir(d)) != NULL) {
        char path[1024];
        struct stat st;
        if (e->d_name[0] == '.')
            continue;
        snprintf(path, sizeof path, "%s/%s", dir, e->d_name);
        if (stat(path, &st) != 0)
            continue;
        if (S_ISDIR(st.st_mode))
            find_scenes(path);
        else if ((has_ext(path, ".nff") || has_ext(path, ".json")) && num_scenes < MAX_SCENES) {
            scene_paths[num_scenes] = strdup(path);
            assert_non_null(scene_paths[num_scenes]);
            num_scenes++;
        }
    }
    closedir(d);
}

static int cmp_str(const void *a, const void *b)
{
    return strcmp(*(char *const *)a, *(char *const *)b);
}

static void list_scenes(void)
{
    if (num_scenes > 0)
        return;
    find_scenes("scenes");
    find_scenes("tests/scenes");
    find_scenes(SPD_DIR);
    qsort(scene_paths, (size_t)num_scenes, sizeof *scene_paths, cmp_str);
}

/* Loads and finishes a scene at the given size (0: its own); 0, or -1 with err. */
static int load(const char *path, int w, int h, scene *s)
{
    scene_init(s);
    if (scene_load(path, s, err, sizeof err) != 0 || scene_finish(s, w, h, 0, err, sizeof err)) {
        scene_free(s);
        return -1;
    }
    return 0;
}

static int has_refraction(const scene *s)
{
    size_t i;
    const scene_material *m = s->materials.data;
    if (s->max_depth < 2)
        return 0;
    for (i = 0; i < s->materials.count; i++)
        if (m[i].kt.x > 0 || m[i].kt.y > 0 || m[i].kt.z > 0)
            return 1;
    return 0;
}

/* ======================================================================================== */
/* Rendering both ways and comparing                                                        */

typedef struct {
    const char *name;
    int spp, spd, precision, stats;
} mode;

static const mode modes[] = {
    {"plain", 1, 0, RENDER_ROBUST, 0}, {"spp4", 4, 0, RENDER_ROBUST, 0},
    {"spd", 1, 1, RENDER_ROBUST, 0},   {"fast", 1, 0, RENDER_FAST, 0},
    {"stats", 1, 0, RENDER_ROBUST, 1},
};

static void set_mode(const mode *m, int strategy)
{
    render_settings st;
    render_settings_default(&st);
    st.spp = m->spp;
    st.spd = m->spd;
    st.precision = m->precision;
    st.stats = m->stats;
    st.strategy = strategy;
    if (renderer_set_settings(R, &st, err, sizeof err) != 0)
        fail_msg("%s", err);
}

static void render_with(const char *path, const scene *s, const mode *m, int strategy, image *img,
                        render_stats *st)
{
    set_mode(m, strategy);
    if (renderer_set_scene(R, s, err, sizeof err) != 0 ||
        renderer_render(R, img, err, sizeof err) != 0)
        fail_msg("%s (%s, %s): %s", path, m->name, render_strategy_name(strategy), err);
    assert_int_equal(renderer_strategy(R), strategy);
    renderer_get_stats(R, st);
}

/* path as one file name: leading dots and slashes dropped, the others made '-'. */
static void flat_name(const char *path, char *out, size_t n)
{
    size_t i;
    while (*path == '.' || *path == '/')
        path++;
    snprintf(out, n, "%s", path);
    for (i = 0; out[i]; i++)
        if (out[i] == '/' || out[i] == '.')
            out[i] = '-';
}

static void write_failure(const image *wf, const image *px, const char *path, const char *mname)
{
    char base[512], name[700], e2[2048];
    flat_name(path, base, sizeof base);
    mkdir("build", 0777);
    mkdir(OUT_DIR, 0777);
    snprintf(name, sizeof name, "%s/strategy-%s-%s-wavefront.exr", OUT_DIR, base, mname);
    if (image_write(wf, name, e2, sizeof e2) != 0)
        fprintf(stderr, "  %s\n", e2);
    snprintf(name, sizeof name, "%s/strategy-%s-%s-pixel.exr", OUT_DIR, base, mname);
    if (image_write(px, name, e2, sizeof e2) != 0)
        fprintf(stderr, "  %s\n", e2);
    snprintf(name, sizeof name, "%s/strategy-%s-%s-diff.png", OUT_DIR, base, mname);
    if (image_write_diff(wf, px, NULL, 0.0, 1e6, name, e2, sizeof e2) != 0)
        fprintf(stderr, "  %s\n", e2);
    else
        fprintf(stderr, "  images and diff: %s/strategy-%s-%s-*\n", OUT_DIR, base, mname);
}

/* Values of a and b that differ (*ndiff; *worst: the largest relative difference; *over:
 * how many differ by more than tol). Returns -1 when a value differs by more than tol
 * (tolerant: refraction, the fast path) or, otherwise, at all. */
static int compare_values(const image *a, const image *b, int tolerant, double tol, long *ndiff,
                          double *worst, long *over)
{
    size_t i, n = (size_t)a->width * (size_t)a->height * 3;
    int bad = 0;
    *ndiff = *over = 0;
    *worst = 0;
    for (i = 0; i < n; i++) {
        double x = a->rgb[i], y = b->rgb[i], rel;
        if (memcmp(&a->rgb[i], &b->rgb[i], sizeof(float)) == 0)
            continue;
        (*ndiff)++;
        rel = fabs(x - y) / fmax(fabs(x), fabs(y));
        if (!(rel <= *worst))
            *worst = rel;
        if (!(rel <= tol))
            (*over)++;
        if (!tolerant || !(rel <= tol))
            bad = 1;
    }
    return bad ? -1 : 0;
}

#define SAME_COUNT(field)                                                                          \
    if (fabs((double)a->field - (double)b->field) > tol * (double)a->field) {                      \
        fprintf(stderr, "  %s: wavefront %llu, pixel %llu\n", #field,                              \
                (unsigned long long)a->field, (unsigned long long)b->field);                       \
        same = 0;                                                                                  \
    }

/* The counts of a (the wavefront's) and b (the per-pixel kernel's) agree: equal, or within
 * tol of their size. Both walk the same tree for the same closest-hit rays; their shadow
 * rays too, but the per-pixel kernel skips the walk of a shadow ray its shadow cache
 * answers, so it visits no more nodes. */
static int same_counts(const render_stats *a, const render_stats *b, double tol)
{
    int same = 1;
    SAME_COUNT(closest_nodes)
    SAME_COUNT(closest_tests)
    if ((double)b->any_nodes > (1.0 + tol) * (double)a->any_nodes) {
        fprintf(stderr, "  any_nodes: wavefront %llu, pixel %llu (more)\n", a->any_nodes,
                b->any_nodes);
        same = 0;
    }
    SAME_COUNT(eye_rays)
    SAME_COUNT(eye_hits)
    SAME_COUNT(shadow_rays)
    SAME_COUNT(shadow_blocked)
    SAME_COUNT(secondary_rays)
    SAME_COUNT(secondary_hits)
    SAME_COUNT(passes)
    return same;
}

/* Renders path in mode m both ways at w x h; returns 0 when the images and counts agree
 * (printing what it compared), else -1 after writing the failure images. *loaded: 0 when
 * the scene does not load (a scene meant to fail). */
static int compare_scene(const char *path, const mode *m, int w, int h, int *loaded)
{
    scene s;
    image wf, px;
    render_stats swf, spx;
    long ndiff, over, n_values;
    double worst;
    int refraction, fast, bad, rc = 0;

    *loaded = load(path, w, h, &s) == 0;
    if (!*loaded)
        return 0;
    refraction = has_refraction(&s);
    render_with(path, &s, m, RENDER_WAVEFRONT, &wf, &swf);
    render_with(path, &s, m, RENDER_PIXEL, &px, &spx);
    scene_free(&s);
    assert_int_equal(wf.width, px.width);
    assert_int_equal(wf.height, px.height);
    fast = m->precision == RENDER_FAST;
    n_values = 3L * w * h;
    bad = compare_values(&wf, &px, refraction || fast, fast ? FAST_REL_TOL : REFRACTION_REL_TOL,
                         &ndiff, &worst, &over) != 0;
    if (fast) /* a few values moved further by mirrors (see FAST_REL_TOL) */
        bad = (double)over > FAST_MAX_OVER * (double)n_values;
    if (bad) {
        fprintf(stderr, "  %s (%s, %dx%d): %ld values differ, up to %.3g relative%s\n", path,
                m->name, w, h, ndiff, worst,
                fast         ? " (too many over the fast path's tolerance)"
                : refraction ? " (over the refraction tolerance)"
                             : " (no refraction: none may)");
        write_failure(&wf, &px, path, m->name);
        rc = -1;
    } else if (ndiff > 0)
        printf("    %-44s %-5s %s: %ld values differ, up to %.3g relative, %ld over %.0e\n", path,
               m->name, fast ? "fast maths" : "refraction", ndiff, worst, over,
               fast ? FAST_REL_TOL : REFRACTION_REL_TOL);
    if (!same_counts(&swf, &spx, fast ? FAST_COUNT_TOL : 0.0)) {
        fprintf(stderr, "  %s (%s): the ray counts differ\n", path, m->name);
        rc = -1;
    }
    image_free(&wf);
    image_free(&px);
    return rc;
}

/* Every scene in every mode; a scene that does not load is skipped (there are such scenes
 * in tests/scenes/parse/), but most must load. */
static void compare_all(const mode *m)
{
    int i, compared = 0, failed = 0;
    list_scenes();
    for (i = 0; i < num_scenes; i++) {
        int loaded;
        if (compare_scene(scene_paths[i], m, SMALL_W, SMALL_H, &loaded) != 0)
            failed++;
        compared += loaded;
    }
    printf("    %s: %d scenes compared (%d of %d files load), %d differ\n", m->name, compared,
           compared, num_scenes, failed);
    assert_true(compared >= 10);
    if (failed)
        fail_msg("%d scenes render differently with the two strategies (%s)", failed, m->name);
}

/* renderer_prepare_scene + renderer_set_prepared (the command line's upload, the first
 * half on the load thread) give renderer_set_scene's image bit for bit and the same counts,
 * on every scene; a prepared scene's primitive arrays are emptied; a renderer whose local
 * origin differs refuses it; one never used is freed (the sanitizer build checks leaks). */
static void test_prepared(void **state)
{
    int i, compared = 0, failed = 0;
    const mode *m = &modes[4]; /* stats: the counts too */
    (void)state;
    list_scenes();
    for (i = 0; i < num_scenes; i++) {
        scene a, b;
        image ia, ib;
        render_stats sa, sb;
        render_prep *p;
        long ndiff, over;
        double worst;
        if (load(scene_paths[i], SMALL_W, SMALL_H, &a) != 0)
            continue;
        if (load(scene_paths[i], SMALL_W, SMALL_H, &b) != 0)
            fail_msg("%s loads once but not twice: %s", scene_paths[i], err);
        render_with(scene_paths[i], &a, m, RENDER_PIXEL, &ia, &sa);
        p = renderer_prepare_scene(&b, err, sizeof err);
        if (!p)
            fail_msg("%s: renderer_prepare_scene: %s", scene_paths[i], err);
        assert_int_equal(b.triangles.count + b.spheres.count + b.polygons.count + b.cones.count, 0);
        if (renderer_set_prepared(R, p, &b, err, sizeof err) != 0 ||
            renderer_render(R, &ib, err, sizeof err) != 0)
            fail_msg("%s (prepared): %s", scene_paths[i], err);
        renderer_get_stats(R, &sb);
        /* the shadow cache's hits, and so the shadow walks' nodes, depend on which thread
         * takes which tile: not compared */
        sa.any_nodes = sb.any_nodes = 0;
        if (compare_values(&ia, &ib, 0, 0.0, &ndiff, &worst, &over) != 0 ||
            !same_counts(&sa, &sb, 0.0) || sa.nodes != sb.nodes || sa.triangles != sb.triangles ||
            sa.spheres != sb.spheres) {
            fprintf(stderr, "  %s: prepared and set_scene differ (%ld values)\n", scene_paths[i],
                    ndiff);
            write_failure(&ia, &ib, scene_paths[i], "prepared");
            failed++;
        }
        compared++;
        image_free(&ia);
        image_free(&ib);
        scene_free(&a);
        scene_free(&b);
    }
    printf("    prepared: %d scenes compared, %d differ\n", compared, failed);
    assert_true(compared >= 10);
    assert_int_equal(failed, 0);

    { /* another local origin: refused with a message; an unused prepared scene freed */
        scene s;
        render_prep *p;
        assert_int_equal(load("scenes/default.json", SMALL_W, SMALL_H, &s), 0);
        p = renderer_prepare_scene(&s, err, sizeof err);
        assert_non_null(p);
        renderer_debug_world_origin(R, 1);
        assert_int_not_equal(renderer_set_prepared(R, p, &s, err, sizeof err), 0);
        renderer_debug_world_origin(R, 0);
        assert_non_null(strstr(err, "another local origin"));
        renderer_prep_free(renderer_prepare_scene(&s, err, sizeof err));
        renderer_prep_free(NULL);
        scene_free(&s);
    }
}

static void test_plain(void **state)
{
    (void)state;
    compare_all(&modes[0]);
}

static void test_spp4(void **state)
{
    (void)state;
    compare_all(&modes[1]);
}

static void test_spd(void **state)
{
    (void)state;
    compare_all(&modes[2]);
}

static void test_fast(void **state)
{
    (void)state;
    compare_all(&modes[3]);
}

static void test_stats(void **state)
{
    (void)state;
    compare_all(&modes[4]);
}

/* Bands of more than one per-pixel launch: the default scene, and the SPD scenes with
 * mirrors and refraction when present. */
static void test_large(void **state)
{
    static const char *const paths[] = {"scenes/default.json", SPD_DIR "/balls.nff",
                                        SPD_DIR "/mount.nff"};
    int i, failed = 0;
    (void)state;
    for (i = 0; i < 3; i++) {
        int loaded;
        if (compare_scene(paths[i], &modes[4], LARGE_W, LARGE_H, &loaded) != 0)
            failed++;
        printf("    %s %dx%d: %s\n", paths[i], LARGE_W, LARGE_H,
               loaded ? "compared" : "not found, skipped");
        if (i == 0)
            assert_true(loaded);
    }
    if (failed)
        fail_msg("%d large renders differ", failed);
}

/* The preview's path: progressive samples in bands of a few rows (renderer_set_view,
 * renderer_trace, renderer_read). */
static void test_progressive(void **state)
{
    static const char *const path = "tests/scenes/pov/mirrors.nff";
    image img[2];
    scene s;
    int k, sample, row0;
    (void)state;
    if (load(path, 64, 48, &s) != 0)
        fail_msg("%s: %s", path, err);
    for (k = 0; k < 2; k++) {
        render_settings st;
        int strategy = k == 0 ? RENDER_WAVEFRONT : RENDER_PIXEL;
        render_settings_default(&st);
        st.spp = 4;
        st.strategy = strategy;
        if (renderer_set_settings(R, &st, err, sizeof err) != 0 ||
            renderer_set_scene(R, &s, err, sizeof err) != 0 ||
            renderer_set_view(R, &s, err, sizeof err) != 0)
            fail_msg("%s", err);
        for (sample = 0; sample < 3; sample++)
            for (row0 = 0; row0 < 48; row0 += 7)
                if (renderer_trace(R, sample, row0, row0 + 7 > 48 ? 48 - row0 : 7, err,
                                   sizeof err) != 0)
                    fail_msg("%s", err);
        if (renderer_read(R, &img[k], err, sizeof err) != 0)
            fail_msg("%s", err);
    }
    scene_free(&s);
    if (memcmp(img[0].rgb, img[1].rgb, sizeof(float) * 3 * 64 * 48) != 0) {
        write_failure(&img[0], &img[1], path, "progressive");
        fail_msg("the progressive renders differ");
    }
    printf("    %s: 3 samples in bands of 7 rows, identical\n", path);
    image_free(&img[0]);
    image_free(&img[1]);
}

/* Deep refraction: four overlapping glass spheres (km and kt > 0) at depth 10, where a
 * pixel's ray tree grows wider than the per-pixel queue, so that subtrees are walked depth
 * first; then again with a queue of 2 rays (CLWHITTED_BUILD_OPTIONS), where nearly every
 * tree overflows it. Within the refraction tolerance, with the same counts. */
static void test_deep_refraction(void **state)
{
    static const char *const extra[] = {NULL, "-w -DCW_PIX_QUEUE=2"};
    scene s;
    int q, glass;
    (void)state;
    tu_base_scene(&s, SCENE_PERSPECTIVE, 3, 32, 24);
    s.camera.l = s.camera.b = -0.4f; /* the spheres fill the view */
    s.camera.r = s.camera.t = 0.4f;
    s.max_depth = 10;
    s.background = vec3f_make(0.2f, 0.3f, 0.5f);
    s.ambient = vec3f_make(0.2f, 0.2f, 0.2f);
    glass = tu_add_material(&s, vec3f_make(0.1f, 0.1f, 0.1f), vec3f_make(0.1f, 0.2f, 0.1f),
                            vec3f_make(0.3f, 0.3f, 0.3f), vec3f_make(0.3f, 0.3f, 0.3f),
                            vec3f_make(0.7f, 0.7f, 0.7f), 1.5f, 20.0f);
    tu_add_sphere(&s, -0.5, -0.5, 0, 0.8, glass);
    tu_add_sphere(&s, 0.5, -0.5, -0.3, 0.8, glass);
    tu_add_sphere(&s, -0.5, 0.5, -0.6, 0.8, glass);
    tu_add_sphere(&s, 0.5, 0.5, 0.3, 0.8, glass);
    tu_add_light(&s, vec3f_make(3, 5, 6), vec3f_make(1, 1, 1));
    if (scene_finish(&s, 0, 0, 0, err, sizeof err) != 0)
        fail_msg("%s", err);
    assert_true(has_refraction(&s));
    for (q = 0; q < 2; q++) {
        image wf, px;
        render_stats swf, spx;
        long ndiff, over;
        double worst;
        int bad;
        if (extra[q])
            assert_int_equal(setenv("CLWHITTED_BUILD_OPTIONS", extra[q], 1), 0);
        render_with("deep refraction", &s, &modes[4], RENDER_WAVEFRONT, &wf, &swf);
        render_with("deep refraction", &s, &modes[4], RENDER_PIXEL, &px, &spx);
        unsetenv("CLWHITTED_BUILD_OPTIONS");
        bad = compare_values(&wf, &px, 1, DEPTH_FIRST_REL_TOL, &ndiff, &worst, &over);
        printf("    queue %s: %llu secondary rays for %d pixels, %d passes; %ld values differ, up "
               "to %.3g relative\n",
               q ? "2" : "32", spx.secondary_rays, 32 * 24, spx.passes, ndiff, worst);
        assert_true(spx.secondary_rays > 16 * 32 * 24);
        if (bad || !same_counts(&swf, &spx, 0.0)) {
            write_failure(&wf, &px, "deep-refraction", q ? "queue2" : "queue32");
            fail_msg("deep refraction (queue %s): the strategies differ", q ? "2" : "32");
        }
        image_free(&wf);
        image_free(&px);
    }
    scene_free(&s);
}

/* ======================================================================================== */
/* Choice, settings, hooks, progress                                                        */

static int contains(const char *s, const char *what)
{
    return strstr(s, what) != NULL;
}

/* PoCL is a CPU device: the default picks the per-pixel kernel; the setting overrides it,
 * and the program holds only the chosen strategy's kernels (-DCW_PIXEL). */
static void test_choice(void **state)
{
    render_settings st;
    scene s;
    image img;
    (void)state;
    render_settings_default(&st);
    assert_int_equal(st.strategy, RENDER_AUTO);
    if (renderer_set_settings(R, &st, err, sizeof err) != 0)
        fail_msg("%s", err);
    assert_int_equal(renderer_strategy(R), RENDER_PIXEL);
    assert_string_equal(render_strategy_name(RENDER_PIXEL), "pixel");
    assert_string_equal(render_strategy_name(RENDER_WAVEFRONT), "wavefront");
    assert_string_equal(render_strategy_name(RENDER_AUTO), "auto");
    if (load("scenes/default.json", 16, 12, &s) != 0)
        fail_msg("%s", err);
    if (renderer_set_scene(R, &s, err, sizeof err) != 0 ||
        renderer_render(R, &img, err, sizeof err) != 0)
        fail_msg("%s", err);
    image_free(&img);
    printf("    auto on %s: %s; options %s\n", renderer_device_name(R),
           render_strategy_name(renderer_strategy(R)), renderer_build_options(R));
    assert_true(contains(renderer_build_options(R), "-DCW_PIXEL=1"));

    st.strategy = RENDER_WAVEFRONT;
    if (renderer_set_settings(R, &st, err, sizeof err) != 0 ||
        renderer_render(R, &img, err, sizeof err) != 0)
        fail_msg("%s", err);
    image_free(&img);
    assert_int_equal(renderer_strategy(R), RENDER_WAVEFRONT);
    assert_true(contains(renderer_build_options(R), "-DCW_PIXEL=0"));
    scene_free(&s);
}

static void test_bad_setting(void **state)
{
    render_settings st;
    (void)state;
    render_settings_default(&st);
    st.strategy = 3;
    assert_int_equal(renderer_set_settings(R, &st, err, sizeof err), -1);
    printf("    strategy 3: %s\n", err);
    assert_true(contains(err, "strategy"));
    st.strategy = -1;
    assert_int_equal(renderer_set_settings(R, &st, err, sizeof err), -1);
}

/* --kernel auto|pixel|wavefront sets the strategy; anything else is a usage error. */
static int parse_kernel(const char *value, cli_options *o, int *status)
{
    char a0[] = "clwhitted", a1[] = "--kernel", a2[64], a3[] = "scene.nff";
    char *argv[] = {a0, a1, a2, a3, NULL};
    snprintf(a2, sizeof a2, "%s", value);
    optind = 0; /* glibc: start a new scan */
    return cli_parse(4, argv, o, status);
}

static void test_cli(void **state)
{
    static const char *const names[] = {"auto", "pixel", "wavefront"};
    static const int want[] = {RENDER_AUTO, RENDER_PIXEL, RENDER_WAVEFRONT};
    cli_options o;
    int i, status;
    (void)state;
    for (i = 0; i < 3; i++) {
        assert_int_equal(parse_kernel(names[i], &o, &status), CLI_RUN);
        assert_int_equal(o.settings.strategy, want[i]);
    }
    printf("    --kernel nope (a usage error, on stderr):\n");
    fflush(stdout);
    assert_int_equal(parse_kernel("nope", &o, &status), CLI_EXIT);
    assert_int_equal(status, 2);
}

/* The test hooks run the wavefront's kernels: they work between per-pixel renders, which
 * go on giving the same image. */
static void test_hooks_between(void **state)
{
    render_settings st;
    scene s;
    image a, b;
    cw_ray ray;
    cw_hit hit;
    (void)state;
    render_settings_default(&st);
    st.strategy = RENDER_PIXEL;
    if (renderer_set_settings(R, &st, err, sizeof err) != 0)
        fail_msg("%s", err);
    if (load("scenes/default.json", 24, 18, &s) != 0)
        fail_msg("%s", err);
    if (renderer_set_scene(R, &s, err, sizeof err) != 0 ||
        renderer_render(R, &a, err, sizeof err) != 0)
        fail_msg("%s", err);
    ray = tu_make_ray(s.camera.eye.x, s.camera.eye.y, s.camera.eye.z, -s.camera.w.x, -s.camera.w.y,
                      -s.camera.w.z);
    if (renderer_intersect(R, &ray, 1, &hit, err, sizeof err) != 0)
        fail_msg("%s", err);
    assert_true(contains(renderer_build_options(R), "-DCW_PIXEL=0"));
    if (renderer_render(R, &b, err, sizeof err) != 0)
        fail_msg("%s", err);
    assert_true(contains(renderer_build_options(R), "-DCW_PIXEL=1"));
    printf("    hook between renders: hit kind %d at t %g\n", hit.kind, hit.t);
    assert_memory_equal(a.rgb, b.rgb, sizeof(float) * 3 * 24 * 18);
    image_free(&a);
    image_free(&b);
    scene_free(&s);
}

typedef struct {
    int calls, cancel_at;
    double last;
    unsigned long long rays;
    int monotonic;
} progress_log;

static int on_progress(void *ctx, double fraction, unsigned long long rays)
{
    progress_log *p = ctx;
    p->calls++;
    if (fraction < p->last || rays < p->rays)
        p->monotonic = 0;
    p->last = fraction;
    p->rays = rays;
    return p->cancel_at > 0 && p->calls >= p->cancel_at;
}

/* A band of 257 rows at 256 pixels is two per-pixel launches: progress after each, up to
 * 1 with every ray counted; a callback that says stop cancels the render. */
static void test_progress(void **state)
{
    render_settings st;
    render_stats rs;
    progress_log log;
    scene s;
    image img;
    (void)state;
    render_settings_default(&st);
    st.strategy = RENDER_PIXEL;
    if (renderer_set_settings(R, &st, err, sizeof err) != 0)
        fail_msg("%s", err);
    if (load("scenes/default.json", LARGE_W, LARGE_H, &s) != 0)
        fail_msg("%s", err);
    if (renderer_set_scene(R, &s, err, sizeof err) != 0)
        fail_msg("%s", err);
    memset(&log, 0, sizeof log);
    log.monotonic = 1;
    renderer_set_progress(R, on_progress, &log);
    if (renderer_render(R, &img, err, sizeof err) != 0)
        fail_msg("%s", err);
    image_free(&img);
    renderer_get_stats(R, &rs);
    printf("    %d progress calls, last %g, %llu rays\n", log.calls, log.last, log.rays);
    assert_true(log.calls >= 2);
    assert_true(log.monotonic);
    assert_true(fabs(log.last - 1.0) < 1e-9);
    assert_true(log.rays == rs.eye_rays + rs.shadow_rays + rs.secondary_rays);

    memset(&log, 0, sizeof log);
    log.cancel_at = 1;
    assert_int_equal(renderer_render(R, &img, err, sizeof err), -1);
    assert_string_equal(err, "render cancelled");
    renderer_set_progress(R, NULL, NULL);
    scene_free(&s);
}

static int free_scenes(void **state)
{
    int i;
    for (i = 0; i < num_scenes; i++)
        free(scene_paths[i]);
    num_scenes = 0;
    return teardown(state);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_choice),        cmocka_unit_test(test_bad_setting),
        cmocka_unit_test(test_cli),           cmocka_unit_test(test_prepared),
        cmocka_unit_test(test_plain),         cmocka_unit_test(test_spp4),
        cmocka_unit_test(test_spd),           cmocka_unit_test(test_fast),
        cmocka_unit_test(test_stats),         cmocka_unit_test(test_large),
        cmocka_unit_test(test_progressive),   cmocka_unit_test(test_deep_refraction),
        cmocka_unit_test(test_hooks_between), cmocka_unit_test(test_progress),
    };
    return cmocka_run_group_tests(tests, setup, free_scenes);
}
