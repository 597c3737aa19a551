/* clwhitted against POV-Ray 3.7: every scene in tests/scenes/pov/NAME.nff (and a few
 * variants: other depths, orthographic and oblique cameras, per-channel materials) is
 * written with pov_write_scene, rendered by povray (linear 16-bit PNG, no
 * anti-aliasing) and by the renderer, and the two images are compared away from edges:
 * a pixel is left out when one of its 8 neighbours differs from it by more than
 * POV_EDGE in any channel in either image (geometric, shadow and reflected edges,
 * where one ray more or less on a side decides), grown by one pixel, and when POV-Ray's
 * value is clipped (>= 0.999). Over the rest the largest difference must be at most
 * POV_TOL, and at least half of the pixels must have been compared.
 * povray must be installed (tools/install-deps installs it); on a mismatch the images
 * and a diff go to build/test-output/pov-NAME-{pov,cw,diff}.png. With CW_POV_KEEP set
 * in the environment the temporary folder with the .pov files and POV-Ray's PNGs is
 * kept (its name is printed).
 *
 * Scenes for this test must keep their edges visible to the mask: a pixel whose ray
 * passes within float precision (or within the renderer's 1e-4 secondary-ray offset)
 * of an edge may land on the other side than POV-Ray's, which is harmless only where
 * the mask excludes it. So: mirrors strong (km >= 0.5) or absent, since a weak mirror
 * shows reflected edges with less contrast than POV_EDGE; no light in the plane of a
 * polygon or triangle (n.l ~ 0 there decides the specular term by rounding); objects
 * not touching (POV-Ray ignores occluders within 1e-3 of a shadow ray's ends); values
 * below about 0.95 (the PNG clips at 1). */
#include "testutil.h"

#include <dirent.h>
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "image.h"
#include "image_diff.h"
#include "image_read.h"
#include "render.h"
#include "scene.h"
#include "scene_geom.h"
#include "scene_load.h"
#include "scene_pov.h"

#define POV_W 160
#define POV_H 120
#define POV_TOL 1e-3
#define POV_EDGE 0.05
#define POV_CLIP 0.999
#define POV_MIN_COMPARED 0.5
#define SCENE_DIR "tests/scenes/pov"
#define OUT_DIR "build/test-output"

enum variant {
    VAR_NONE,
    VAR_ORTHO,   /* orthographic camera, window scaled to the scene */
    VAR_OBLIQUE, /* the same with a slanted direction */
    VAR_COLOUR,  /* per-channel ks, km and a kd channel at 0 under a non-zero ka */
    VAR_MATTE,   /* no ks, no km, a kd channel at 0 under a non-zero ka */
};

static const char *const variant_names[] = {"", "ortho", "oblique", "colour", "matte"};

/* Further cases for some scenes, besides each scene at its own depth. */
static const struct {
    const char *scene;
    int depth;
    enum variant var;
} extras[] = {
    {"mirrors", 1, VAR_NONE},    {"mirrors", 2, VAR_NONE},    {"mirrors", 0, VAR_COLOUR},
    {"shading", 0, VAR_ORTHO},   {"shading", 0, VAR_OBLIQUE}, {"shading", 0, VAR_COLOUR},
    {"patches", 0, VAR_OBLIQUE}, {"patches", 0, VAR_MATTE},
};

typedef struct {
    char name[160];
    char scene[128]; /* base name without .nff */
    int depth;       /* 0: the scene's own */
    enum variant var;
} pov_case;

static renderer *g_renderer;
static char g_tmpdir[64];

/* ------------------------------------------------------------------------ helpers */

static void make_dirs(void)
{
    if (mkdir("build", 0777) != 0 && errno != EEXIST)
        return;
    (void)mkdir(OUT_DIR, 0777);
}

static int povray_available(void)
{
    return system("command -v povray >/dev/null 2>&1") == 0;
}

static void print_file(const char *path)
{
    char line[512];
    FILE *f = fopen(path, "r");
    if (!f)
        return;
    while (fgets(line, sizeof line, f))
        fprintf(stderr, "    | %s", line);
    fclose(f);
}

/* The window of the finished NFF camera grown to the scene (about 10 units away), for
 * the parallel projections. */
static void apply_variant(scene *s, enum variant var)
{
    size_t i;
    scene_camera *c = &s->camera;
    if (var == VAR_ORTHO || var == VAR_OBLIQUE) {
        const float k = 10.0f;
        c->nff_angle_deg = 0.0f;
        c->l *= k;
        c->r *= k;
        c->b *= k;
        c->t *= k;
        c->projection = var == VAR_ORTHO ? SCENE_ORTHOGRAPHIC : SCENE_OBLIQUE;
        /* oblique: -w tilted towards +u and +v; scene_finish normalises it */
        c->dir = vec3f_make(-c->w.x + 0.25f * c->u.x + 0.1f * c->v.x,
                            -c->w.y + 0.25f * c->u.y + 0.1f * c->v.y,
                            -c->w.z + 0.25f * c->u.z + 0.1f * c->v.z);
    }
    if (var == VAR_MATTE) {
        for (i = 0; i < s->materials.count; i++) {
            scene_material *m = &SCENE_AT(s->materials, scene_material, i);
            m->kd.y = 0.0f;
            m->ks = m->km = vec3f_make(0, 0, 0);
        }
    }
    if (var == VAR_COLOUR) {
        for (i = 0; i < s->materials.count; i++) {
            scene_material *m = &SCENE_AT(s->materials, scene_material, i);
            m->kd.y = 0.0f; /* ka.y stays: ambient green without diffuse green */
            m->ks = vec3f_make(0.3f, 0.12f, 0.05f);
            /* mirrors stay strong (or absent): see the note on weak mirrors above */
            if (m->km.x > 0.0f || m->km.y > 0.0f || m->km.z > 0.0f)
                m->km = vec3f_make(0.7f, 0.5f, 0.6f);
            if (m->p < 2.0f)
                m->p = 30.0f; /* a high exponent keeps the specular step at the terminator small */
        }
    }
}

static int load_case(const pov_case *pc, scene *s, char *err, size_t errlen)
{
    char path[512];
    snprintf(path, sizeof path, "%s/%s.nff", SCENE_DIR, pc->scene);
    scene_init(s);
    if (scene_load(path, s, err, errlen) != 0 ||
        scene_finish(s, POV_W, POV_H, pc->depth, err, errlen) != 0)
        return -1;
    if (pc->var != VAR_NONE) {
        apply_variant(s, pc->var);
        if (scene_finish(s, POV_W, POV_H, pc->depth, err, errlen) != 0)
            return -1;
    }
    return 0;
}

/* Renders s with povray into *img. */
static int render_pov(const pov_case *pc, const scene *s, image *img, char *err, size_t errlen)
{
    char pov_path[256], png_path[256], log_path[256], cmd[2048];
    FILE *f;
    int rc, n;
    snprintf(pov_path, sizeof pov_path, "%s/%s.pov", g_tmpdir, pc->name);
    snprintf(png_path, sizeof png_path, "%s/%s.png", g_tmpdir, pc->name);
    snprintf(log_path, sizeof log_path, "%s/%s.log", g_tmpdir, pc->name);
    f = fopen(pov_path, "w");
    if (!f) {
        snprintf(err, errlen, "cannot write %s: %s", pov_path, strerror(errno));
        return -1;
    }
    if (pov_write_scene(s, f, err, errlen) != 0) {
        fclose(f);
        return -1;
    }
    if (fclose(f) != 0) {
        snprintf(err, errlen, "cannot write %s", pov_path);
        return -1;
    }
    n = pov_command_line(s, pov_path, png_path, cmd, sizeof cmd);
    if (n < 0 || (size_t)n + 64 >= sizeof cmd) {
        snprintf(err, errlen, "povray command line too long");
        return -1;
    }
    snprintf(cmd + n, sizeof cmd - (size_t)n, " +WT2 >'%s' 2>&1", log_path);
    rc = system(cmd);
    if (rc != 0) {
        fprintf(stderr, "  povray failed (status %d): %s\n  log:\n", rc, cmd);
        print_file(log_path);
        snprintf(err, errlen, "povray failed on %s (status %d; log above)", pov_path, rc);
        return -1;
    }
    return image_read_png(png_path, 0, img, err, errlen);
}

/* 1 where the pixel is compared; see the top of the file. */
static unsigned char *edge_mask(const image *a, const image *b)
{
    int w = a->width, h = a->height, x, y, dx, dy, c, k;
    size_t n = (size_t)w * (size_t)h;
    unsigned char *edge = calloc(n, 1), *mask = calloc(n, 1);
    const image *imgs[2];
    imgs[0] = a;
    imgs[1] = b;
    if (!edge || !mask) {
        free(edge);
        free(mask);
        return NULL;
    }
    for (y = 0; y < h; y++)
        for (x = 0; x < w; x++)
            for (k = 0; k < 2 && !edge[(size_t)y * w + x]; k++) {
                const float *p = imgs[k]->rgb + ((size_t)y * w + x) * 3;
                for (dy = -1; dy <= 1; dy++)
                    for (dx = -1; dx <= 1; dx++) {
                        const float *q;
                        if (x + dx < 0 || x + dx >= w || y + dy < 0 || y + dy >= h)
                            continue;
                        q = imgs[k]->rgb + ((size_t)(y + dy) * w + (x + dx)) * 3;
                        for (c = 0; c < 3; c++)
                            if (fabsf(p[c] - q[c]) > POV_EDGE)
                                edge[(size_t)y * w + x] = 1;
                    }
            }
    for (y = 0; y < h; y++)
        for (x = 0; x < w; x++) {
            const float *p = a->rgb + ((size_t)y * w + x) * 3;
            int keep = p[0] < POV_CLIP && p[1] < POV_CLIP && p[2] < POV_CLIP;
            for (dy = -1; dy <= 1 && keep; dy++)
                for (dx = -1; dx <= 1 && keep; dx++)
                    if (x + dx >= 0 && x + dx < w && y + dy >= 0 && y + dy < h &&
                        edge[(size_t)(y + dy) * w + (x + dx)])
                        keep = 0;
            mask[(size_t)y * w + x] = (unsigned char)keep;
        }
    free(edge);
    return mask;
}

static void write_failure_images(const pov_case *pc, const image *pov, const image *cw,
                                 const unsigned char *mask)
{
    char path[512], err[512];
    make_dirs();
    snprintf(path, sizeof path, "%s/pov-%s-diff.png", OUT_DIR, pc->name);
    if (image_write_diff(pov, cw, mask, POV_TOL, 100.0, path, err, sizeof err) != 0)
        fprintf(stderr, "  %s\n", err);
    else
        fprintf(stderr, "  diff (|pov - cw| x 100, red: over %g, grey: not compared): %s\n",
                POV_TOL, path);
    snprintf(path, sizeof path, "%s/pov-%s-pov.png", OUT_DIR, pc->name);
    if (image_write(pov, path, err, sizeof err) != 0)
        fprintf(stderr, "  %s\n", err);
    snprintf(path, sizeof path, "%s/pov-%s-cw.png", OUT_DIR, pc->name);
    if (image_write(cw, path, err, sizeof err) != 0)
        fprintf(stderr, "  %s\n", err);
    else
        fprintf(stderr, "  images: %s/pov-%s-{pov,cw}.png\n", OUT_DIR, pc->name);
}

/* -------------------------------------------------------------- the comparison */

static void test_compare(void **state)
{
    const pov_case *pc = *state;
    char err[2048];
    scene s;
    image pov = {0, 0, NULL}, cw = {0, 0, NULL};
    unsigned char *mask;
    image_diff_stats st;
    long total = (long)POV_W * POV_H;
    int ok_tol, ok_count;

    if (!povray_available())
        fail_msg("povray not found on PATH: this test needs POV-Ray 3.7 "
                 "(Debian/Ubuntu: apt-get install povray, or run tools/install-deps)");
    if (load_case(pc, &s, err, sizeof err) != 0) {
        scene_free(&s);
        fail_msg("%s: %s", pc->name, err);
    }
    if (render_pov(pc, &s, &pov, err, sizeof err) != 0) {
        scene_free(&s);
        fail_msg("%s: %s", pc->name, err);
    }
    if (renderer_set_scene(g_renderer, &s, err, sizeof err) != 0 ||
        renderer_render(g_renderer, &cw, err, sizeof err) != 0) {
        scene_free(&s);
        image_free(&pov);
        fail_msg("%s: renderer: %s", pc->name, err);
    }
    assert_int_equal(pov.width, cw.width);
    assert_int_equal(pov.height, cw.height);
    mask = edge_mask(&pov, &cw);
    assert_non_null(mask);
    assert_int_equal(image_compare(&pov, &cw, mask, POV_TOL, &st), 0);
    printf("  pov %-18s depth %d: compared %ld/%ld px (%.0f%%), max |diff| %.3g at (%d,%d), "
           "mean %.3g, %ld over %g\n",
           pc->name, s.max_depth, st.compared, total, 100.0 * st.compared / total, st.max_abs,
           st.worst_x, st.worst_y, st.mean_abs, st.over, POV_TOL);
    ok_tol = st.max_abs <= POV_TOL;
    ok_count = st.compared >= (long)(POV_MIN_COMPARED * total);
    if (!ok_tol || !ok_count) {
        if (st.worst_x >= 0) {
            size_t p = ((size_t)st.worst_y * POV_W + (size_t)st.worst_x) * 3;
            fprintf(stderr,
                    "  worst pixel (%d,%d): povray %.6f %.6f %.6f, clwhitted %.6f %.6f %.6f\n",
                    st.worst_x, st.worst_y, pov.rgb[p], pov.rgb[p + 1], pov.rgb[p + 2], cw.rgb[p],
                    cw.rgb[p + 1], cw.rgb[p + 2]);
        }
        write_failure_images(pc, &pov, &cw, mask);
    }
    free(mask);
    image_free(&pov);
    image_free(&cw);
    scene_free(&s);
    if (!ok_count)
        fail_msg("%s: only %ld of %ld pixels compared (need %.0f%%)", pc->name, st.compared, total,
                 100.0 * POV_MIN_COMPARED);
    if (!ok_tol)
        fail_msg("%s: max |povray - clwhitted| = %g > %g at (%d,%d) (%ld pixels over)", pc->name,
                 st.max_abs, POV_TOL, st.worst_x, st.worst_y, st.over);
}

/* ------------------------------------------------ pov_write_scene without povray */

static void one_sphere_scene(scene *s, scene_material m)
{
    scene_sphere sp;
    scene_light l;
    char err[256];
    scene_init(s);
    s->camera.eye = vec3d_make(0, 0, 5);
    assert_int_equal(scene_camera_basis(&s->camera, vec3f_make(0, 0, -1), vec3f_make(0, 1, 0)), 0);
    s->camera.l = -1;
    s->camera.r = 1;
    s->camera.b = -0.75f;
    s->camera.t = 0.75f;
    s->camera.d = 2;
    assert_true(scene_push(&s->materials, &m, sizeof m) == 0);
    sp.center = vec3d_make(0, 0, 0);
    sp.radius = -1.5f;
    sp.material = 0;
    assert_true(scene_push(&s->spheres, &sp, sizeof sp) == 0);
    l.position = vec3d_make(3, 4, 5);
    l.intensity = vec3f_make(0.5f, 0.6f, 0.7f);
    assert_true(scene_push(&s->lights, &l, sizeof l) == 0);
    assert_int_equal(scene_finish(s, 32, 24, 3, err, sizeof err), 0);
}

/* The scene written to memory; the caller frees it. */
static char *write_to_string(const scene *s, int *rc, char *err, size_t errlen)
{
    char *buf = NULL;
    size_t len = 0;
    FILE *f = open_memstream(&buf, &len);
    assert_non_null(f);
    *rc = pov_write_scene(s, f, err, errlen);
    fclose(f);
    return buf;
}

/* The vector after the first "\n  KEY <" in out (a camera line); 0 when found. */
static int camera_vec(const char *out, const char *key, double v[3])
{
    char pat[64];
    const char *p;
    snprintf(pat, sizeof pat, "\n  %s <", key);
    p = strstr(out, pat);
    if (!p)
        return -1;
    p = strchr(p, '<');
    return sscanf(p, "<%lf, %lf, %lf>", &v[0], &v[1], &v[2]) == 3 ? 0 : -1;
}

static void assert_camera_vec(const char *out, const char *key, double x, double y, double z)
{
    double v[3];
    assert_int_equal(camera_vec(out, key, v), 0);
    if (fabs(v[0] - x) > 1e-7 || fabs(v[1] - y) > 1e-7 || fabs(v[2] - z) > 1e-7)
        fail_msg("camera %s <%g, %g, %g>, expected <%g, %g, %g>", key, v[0], v[1], v[2], x, y, z);
}

static scene_material grey_material(void)
{
    scene_material m;
    memset(&m, 0, sizeof m);
    m.ka = m.kd = vec3f_make(0.5f, 0.4f, 0.3f);
    m.ks = m.km = vec3f_make(0.25f, 0.25f, 0.25f);
    m.p = 20;
    return m;
}

static void test_write_simple(void **state)
{
    scene s;
    char err[256];
    int rc;
    char *out;
    (void)state;
    one_sphere_scene(&s, grey_material());
    out = write_to_string(&s, &rc, err, sizeof err);
    assert_int_equal(rc, 0);
    assert_non_null(strstr(out, "#version 3.7;"));
    assert_non_null(strstr(out, "max_trace_level 3"));
    assert_non_null(strstr(out, "adc_bailout 0"));
    assert_non_null(strstr(out, "perspective"));
    assert_non_null(strstr(out, "specular 0.25 roughness 0.050000000000000003"));
    assert_non_null(strstr(out, "reflection { rgb <0.25, 0.25, 0.25> }"));
    assert_non_null(strstr(out, ", 1.5 texture { CW_M0 }")); /* |radius| */
    assert_null(strstr(out, "rgbf"));                        /* one layer */
    /* window: direction = -d w, right = (r-l) u, up = (t-b) v */
    assert_camera_vec(out, "location", 0, 0, 5);
    assert_camera_vec(out, "direction", 0, 0, -2);
    assert_camera_vec(out, "right", 2, 0, 0);
    assert_camera_vec(out, "up", 0, 1.5, 0);
    free(out);
    scene_free(&s);
}

static void test_write_layered(void **state)
{
    scene s;
    scene_material m = grey_material();
    char err[256];
    int rc;
    char *out;
    (void)state;
    m.ks = vec3f_make(0.4f, 0.2f, 0.0f); /* not grey: needs the filtered specular layer */
    m.kd.z = 0.0f;                       /* ka.z != 0 over kd.z == 0 */
    one_sphere_scene(&s, m);
    out = write_to_string(&s, &rc, err, sizeof err);
    assert_int_equal(rc, 0);
    assert_non_null(strstr(out, "rgbf <1, 0.5, 0, 1>"));
    assert_non_null(strstr(out, "specular 1.6000000238418579")); /* S / T^2 */
    assert_non_null(strstr(out, "diffuse 4 "));                  /* 1 / ((1-T) T) */
    assert_non_null(strstr(out, "ambient 2 "));                  /* 1 / (1-T) */
    free(out);
    scene_free(&s);
}

static void test_write_projections(void **state)
{
    scene s;
    char err[256];
    int rc;
    char *out;
    (void)state;
    one_sphere_scene(&s, grey_material());
    s.camera.projection = SCENE_ORTHOGRAPHIC;
    out = write_to_string(&s, &rc, err, sizeof err);
    assert_int_equal(rc, 0);
    assert_non_null(strstr(out, "orthographic"));
    assert_camera_vec(out, "location", 0, 0, 5);
    assert_camera_vec(out, "direction", 0, 0, -1);
    assert_camera_vec(out, "right", 2, 0, 0);
    assert_camera_vec(out, "up", 0, 1.5, 0);
    free(out);
    s.camera.projection = SCENE_OBLIQUE;
    s.camera.dir = vec3f_make(0.6f, 0.0f, -0.8f);
    out = write_to_string(&s, &rc, err, sizeof err);
    assert_int_equal(rc, 0);
    assert_non_null(strstr(out, "oblique"));
    assert_camera_vec(out, "direction", 0.6, 0, -0.8);
    free(out);
    scene_free(&s);
}

static void test_write_polygon_on_plane(void **state)
{
    /* a quad slightly off its plane comes out exactly on the renderer's plane */
    scene s;
    scene_polygon pg;
    vec3d v[4];
    char err[256], *out, *p;
    int rc, k;
    double pts[5][3];
    (void)state;
    one_sphere_scene(&s, grey_material());
    v[0] = vec3d_make(-1.03f, -0.97f, -3.0171f);
    v[1] = vec3d_make(1.01f, -1.02f, -3.2f);
    v[2] = vec3d_make(0.99f, 1.07f, -3.3f);
    v[3] = vec3d_make(-1.1f, 0.93f, -3.1f + 1e-3f);
    for (k = 0; k < 4; k++)
        assert_true(scene_push(&s.poly_verts, &v[k], sizeof v[k]) >= 0);
    pg.first = 0;
    pg.count = 4;
    pg.material = 0;
    assert_true(scene_push(&s.polygons, &pg, sizeof pg) == 0);
    out = write_to_string(&s, &rc, err, sizeof err);
    assert_int_equal(rc, 0);
    p = strstr(out, "polygon { 5");
    assert_non_null(p);
    for (k = 0; k < 5; k++) {
        p = strchr(p, '<');
        assert_non_null(p);
        assert_int_equal(sscanf(p, "<%lf, %lf, %lf>", &pts[k][0], &pts[k][1], &pts[k][2]), 3);
        p++;
    }
    /* closed, x and y (the dropped dominant axis is z) kept, all on one plane */
    assert_true(pts[4][0] == pts[0][0] && pts[4][1] == pts[0][1] && pts[4][2] == pts[0][2]);
    for (k = 0; k < 4; k++) {
        assert_true(pts[k][0] == (double)v[k].x && pts[k][1] == (double)v[k].y);
    }
    {
        double a[3], b[3], n[3], len, d0;
        for (k = 0; k < 3; k++) {
            a[k] = pts[1][k] - pts[0][k];
            b[k] = pts[2][k] - pts[0][k];
        }
        n[0] = a[1] * b[2] - a[2] * b[1];
        n[1] = a[2] * b[0] - a[0] * b[2];
        n[2] = a[0] * b[1] - a[1] * b[0];
        len = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        d0 = (n[0] * pts[0][0] + n[1] * pts[0][1] + n[2] * pts[0][2]) / len;
        assert_true(fabs((n[0] * pts[3][0] + n[1] * pts[3][1] + n[2] * pts[3][2]) / len - d0) <
                    1e-12);
    }
    free(out);
    scene_free(&s);
}

static void test_write_rejects(void **state)
{
    scene s;
    char err[256];
    int rc;
    char *out;
    (void)state;
    one_sphere_scene(&s, grey_material());
    SCENE_AT(s.spheres, scene_sphere, 0).material = 3;
    err[0] = '\0';
    out = write_to_string(&s, &rc, err, sizeof err);
    assert_int_equal(rc, -1);
    assert_non_null(strstr(err, "sphere 0 uses material 3"));
    free(out);
    scene_free(&s);
}

static void test_command_line(void **state)
{
    scene s;
    char buf[512];
    (void)state;
    one_sphere_scene(&s, grey_material());
    pov_command_line(&s, "/tmp/it's.pov", "out.png", buf, sizeof buf);
    assert_string_equal(buf, "povray '+I/tmp/it'\\''s.pov' '+Oout.png' +W32 +H24 -D -A +Q9 "
                             "+FN16 File_Gamma=1.0");
    scene_free(&s);
}

/* ---------------------------------------------------------------- the cases */

static int cmp_str(const void *a, const void *b)
{
    return strcmp(*(char *const *)a, *(char *const *)b);
}

/* The base names of tests/scenes/pov/NAME.nff, sorted. */
static char **list_scenes(size_t *count)
{
    DIR *d = opendir(SCENE_DIR);
    struct dirent *e;
    char **names = NULL;
    size_t n = 0, cap = 0;
    *count = 0;
    if (!d)
        return NULL;
    while ((e = readdir(d)) != NULL) {
        size_t len = strlen(e->d_name);
        char **grown;
        if (len <= 4 || strcmp(e->d_name + len - 4, ".nff") != 0 || len - 4 >= 128)
            continue;
        if (n == cap) {
            cap = cap ? 2 * cap : 8;
            grown = realloc(names, cap * sizeof *names);
            if (!grown)
                break;
            names = grown;
        }
        names[n] = malloc(len - 3);
        if (!names[n])
            break;
        memcpy(names[n], e->d_name, len - 4);
        names[n][len - 4] = '\0';
        n++;
    }
    closedir(d);
    if (n)
        qsort(names, n, sizeof *names, cmp_str);
    *count = n;
    return names;
}

static void set_case(pov_case *pc, const char *scene_name, int depth, enum variant var)
{
    memset(pc, 0, sizeof *pc);
    snprintf(pc->scene, sizeof pc->scene, "%s", scene_name);
    pc->depth = depth;
    pc->var = var;
    snprintf(pc->name, sizeof pc->name, "%s%s%s", scene_name, var ? "-" : "", variant_names[var]);
    if (depth > 0) {
        size_t n = strlen(pc->name);
        snprintf(pc->name + n, sizeof pc->name - n, "-d%d", depth);
    }
}

static int group_setup(void **state)
{
    (void)state;
    snprintf(g_tmpdir, sizeof g_tmpdir, "/tmp/cw-test-pov-XXXXXX");
    /* /tmp: POV-Ray's default I/O restrictions allow writing there */
    if (!mkdtemp(g_tmpdir)) {
        fprintf(stderr, "test_pov: cannot create a temporary folder: %s\n", strerror(errno));
        return -1;
    }
    return tu_renderer_open(&g_renderer, 0);
}

static int group_teardown(void **state)
{
    DIR *d;
    struct dirent *e;
    char path[512];
    (void)state;
    tu_renderer_close(&g_renderer);
    if (getenv("CW_POV_KEEP")) {
        printf("test_pov: CW_POV_KEEP set: the .pov files and POV-Ray images are in %s\n",
               g_tmpdir);
        return 0;
    }
    d = opendir(g_tmpdir);
    if (d) {
        while ((e = readdir(d)) != NULL) {
            if (strcmp(e->d_name, ".") == 0 || strcmp(e->d_name, "..") == 0)
                continue;
            snprintf(path, sizeof path, "%s/%s", g_tmpdir, e->d_name);
            remove(path);
        }
        closedir(d);
    }
    rmdir(g_tmpdir);
    return 0;
}

int main(void)
{
    static const struct CMUnitTest unit[] = {
        cmocka_unit_test(test_write_simple),      cmocka_unit_test(test_write_layered),
        cmocka_unit_test(test_write_projections), cmocka_unit_test(test_write_polygon_on_plane),
        cmocka_unit_test(test_write_rejects),     cmocka_unit_test(test_command_line),
    };
    size_t nscenes = 0, ncases = 0, i, k;
    char **names = list_scenes(&nscenes);
    pov_case *cases;
    struct CMUnitTest *tests;
    int failed;

    failed = cmocka_run_group_tests_name("pov_write", unit, NULL, NULL);
    if (nscenes < 2) {
        fprintf(stderr,
                "test_pov: expected the comparison scenes in %s/*.nff (run from the "
                "repository root); found %zu\n",
                SCENE_DIR, nscenes);
        return 1;
    }
    cases = calloc(nscenes + sizeof extras / sizeof extras[0], sizeof *cases);
    tests = calloc(nscenes + sizeof extras / sizeof extras[0], sizeof *tests);
    if (!cases || !tests)
        return 1;
    for (i = 0; i < nscenes; i++) {
        set_case(&cases[ncases++], names[i], 0, VAR_NONE);
        for (k = 0; k < sizeof extras / sizeof extras[0]; k++)
            if (strcmp(extras[k].scene, names[i]) == 0)
                set_case(&cases[ncases++], names[i], extras[k].depth, extras[k].var);
    }
    for (i = 0; i < ncases; i++) {
        tests[i].name = cases[i].name;
        tests[i].test_func = test_compare;
        tests[i].initial_state = &cases[i];
    }
    failed += _cmocka_run_group_tests("pov_compare", tests, ncases, group_setup, group_teardown);
    for (i = 0; i < nscenes; i++)
        free(names[i]);
    free(names);
    free(cases);
    free(tests);
    return failed ? 1 : 0;
}
