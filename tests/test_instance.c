/* Instances (a mesh placed many times: the two-level BVH of host/devscene_inst.c and
 * kernels/instance.h) render like the same meshes flattened into world triangles
 * (scene_flatten_instances), and do not copy the mesh's triangles.
 *
 * The scene: a floor, and a smooth lat-long sphere mesh with a flat box beside it (one
 * mesh), placed PLACEMENTS times with rotations, non-uniform scales, a mirroring scale,
 * shears (a 4x4 matrix), material overrides (matte, mirror, glass) and the mesh's own
 * materials, lit by two lights with shadows, depth 6. Rendered instanced and flattened on
 * each strategy (per pixel and wavefront) and on the fast path: at most INST_MAX_OVER of
 * the pixels may differ by more than INST_TOL in a channel (sub-pixel decisions: the
 * instanced rays meet the mesh in mesh coordinates, the flattened ones in world
 * coordinates, and round differently), and the mean difference must stay below
 * INST_MAX_MEAN. A failing case writes both images and a diff image into
 * build/test-output/. The same scene far from the origin (1e6) and the flattened one at
 * the origin are compared too. Then 1000 placements of a 5k-triangle mesh: the device
 * arrays hold its triangles once, and the image is compared with the flattened copy. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "testutil.h"

#include "devscene.h"
#include "image.h"
#include "image_diff.h"
#include "render.h"
#include "scene.h"
#include "scene_geom.h"
#include "scene_mesh.h"
#include "xform.h"

#define OUT_DIR "build/test-output"
#define INST_TOL 0.1
#define INST_MAX_OVER 0.003
#define INST_MAX_MEAN 2e-3
#define PLACEMENTS 9

TU_RENDERER_FIXTURE(1)
static char err[2048];

static void push_tri(scene *s, vec3d a, vec3d b, vec3d c, const vec3f *n, int mat)
{
    vec3d p[3] = {a, b, c};
    assert_true(scene_push_mesh_triangle(s, p, n, mat) >= 0);
}

/* A mesh: a smooth sphere of radius 1 at the mesh origin (nlat x nlon quads as triangles,
 * material m0) and a flat box beside it (material m1). Returns its index. */
static int add_mesh(scene *s, int nlat, int nlon, int m0, int m1)
{
    scene_mesh m;
    const double pi = 3.14159265358979323846;
    m.first = s->mesh_tris.count;
    m.source = NULL;
    for (int i = 0; i < nlat; i++)
        for (int j = 0; j < nlon; j++) {
            double t0 = pi * i / nlat, t1 = pi * (i + 1) / nlat;
            double p0 = 2 * pi * j / nlon, p1 = 2 * pi * (j + 1) / nlon;
            vec3d v[4];
            vec3f n[4];
            double th[4] = {t0, t1, t1, t0}, ph[4] = {p0, p0, p1, p1};
            for (int k = 0; k < 4; k++) {
                v[k] = vec3d_make(sin(th[k]) * cos(ph[k]), cos(th[k]), sin(th[k]) * sin(ph[k]));
                n[k] = vec3f_make((float)v[k].x, (float)v[k].y, (float)v[k].z);
            }
            if (i > 0) {
                vec3f nn[3] = {n[0], n[1], n[2]};
                push_tri(s, v[0], v[1], v[2], nn, m0);
            }
            if (i < nlat - 1) {
                vec3f nn[3] = {n[0], n[2], n[3]};
                push_tri(s, v[0], v[2], v[3], nn, m0);
            }
        }
    { /* a box [1.2, 2] x [-1, 0.2] x [-0.4, 0.4], flat */
        double lo[3] = {1.2, -1, -0.4}, hi[3] = {2, 0.2, 0.4};
        static const int faces[6][4] = {{0, 1, 3, 2}, {4, 6, 7, 5}, {0, 4, 5, 1},
                                        {2, 3, 7, 6}, {0, 2, 6, 4}, {1, 5, 7, 3}};
        vec3d c[8];
        for (int k = 0; k < 8; k++)
            c[k] = vec3d_make(k & 4 ? hi[0] : lo[0], k & 2 ? hi[1] : lo[1], k & 1 ? hi[2] : lo[2]);
        for (int f = 0; f < 6; f++) {
            push_tri(s, c[faces[f][0]], c[faces[f][1]], c[faces[f][2]], NULL, m1);
            push_tri(s, c[faces[f][0]], c[faces[f][2]], c[faces[f][3]], NULL, m1);
        }
    }
    m.count = s->mesh_tris.count - m.first;
    return (int)scene_push(&s->meshes, &m, sizeof m);
}

/* The test scene, every position moved by off. */
static void make_scene(scene *s, double off, int w, int h)
{
    int matte, mirror, glass, red, blue, mesh;
    scene_xform x, t;
    tu_base_scene(s, SCENE_PERSPECTIVE, 0, w, h);
    s->camera.eye = vec3d_make(off, off + 4.0, off + 12.0);
    assert_int_equal(scene_camera_basis(&s->camera, vec3f_make(0, -0.33f, -1), vec3f_make(0, 1, 0)),
                     0);
    s->camera.fov_deg = 45;
    s->max_depth = 6;
    s->ambient = vec3f_make(0.1f, 0.1f, 0.1f);
    s->background = vec3f_make(0.05f, 0.07f, 0.1f);
    matte = tu_add_material(s, vec3f_make(.6f, .6f, .55f), vec3f_make(.6f, .6f, .55f),
                            vec3f_make(0, 0, 0), vec3f_make(0.1f, 0.1f, 0.1f), vec3f_make(0, 0, 0),
                            1, 1);
    mirror = tu_add_material(s, vec3f_make(.05f, .05f, .05f), vec3f_make(.05f, .05f, .05f),
                             vec3f_make(.5f, .5f, .5f), vec3f_make(.8f, .8f, .85f),
                             vec3f_make(0, 0, 0), 1, 120);
    glass = tu_add_material(s, vec3f_make(0, 0, 0), vec3f_make(.05f, .05f, .05f),
                            vec3f_make(.4f, .4f, .4f), vec3f_make(.1f, .1f, .1f),
                            vec3f_make(.85f, .85f, .85f), 1.5f, 80);
    red =
        tu_add_material(s, vec3f_make(.7f, .1f, .1f), vec3f_make(.7f, .1f, .1f),
                        vec3f_make(.3f, .3f, .3f), vec3f_make(0, 0, 0), vec3f_make(0, 0, 0), 1, 30);
    blue = tu_add_material(s, vec3f_make(.1f, .2f, .7f), vec3f_make(.1f, .2f, .7f),
                           vec3f_make(0, 0, 0), vec3f_make(0.2f, 0.2f, 0.3f), vec3f_make(0, 0, 0),
                           1, 1);
    tu_add_light(s, vec3f_make((float)off - 6, (float)off + 9, (float)off + 6),
                 vec3f_make(.7f, .7f, .7f));
    tu_add_light(s, vec3f_make((float)off + 7, (float)off + 5, (float)off + 3),
                 vec3f_make(.35f, .35f, .45f));
    { /* the floor */
        scene_polygon pg;
        vec3d v[4] = {
            vec3d_make(off - 20, off - 1, off - 20), vec3d_make(off + 20, off - 1, off - 20),
            vec3d_make(off + 20, off - 1, off + 20), vec3d_make(off - 20, off - 1, off + 20)};
        pg.first = (int)s->poly_verts.count;
        pg.count = 4;
        pg.material = matte;
        for (int k = 0; k < 4; k++)
            assert_true(scene_push(&s->poly_verts, &v[k], sizeof v[k]) >= 0);
        assert_true(scene_push(&s->polygons, &pg, sizeof pg) >= 0);
    }
    mesh = add_mesh(s, 10, 16, red, blue);
    for (int i = 0; i < PLACEMENTS; i++) {
        int col = i % 3, row = i / 3, material = -1;
        scene_xform a;
        xform_identity(&x);
        switch (i) {
        case 1:
            xform_rotate(&x, 0, 1, 0, 40);
            break;
        case 2:
            xform_scale(&x, 1.3, 0.7, 1.0);
            break;
        case 3:
            xform_scale(&x, -1, 1, 1);
            material = mirror;
            break; /* mirrored */
        case 4:
            xform_rotate(&x, 1, 1, 0, 75);
            material = glass;
            break;
        case 5: { /* a shear, as a matrix */
            const double m[16] = {1, 0.4, 0, 0, 0, 1, 0, 0, 0.2, 0, 0.8, 0, 0, 0, 0, 1};
            assert_int_equal(xform_from_matrix(&x, m), 0);
            break;
        }
        case 6:
            xform_scale(&x, 0.5, 0.5, 0.5);
            material = matte;
            break;
        case 7:
            xform_rotate(&x, 0, 0, 1, 180);
            break;
        default:
            break;
        }
        xform_translate(&t, off + (col - 1) * 4.2, off + (row == 2 ? 0.5 : 0.0), off - row * 3.5);
        xform_compose(&a, &t, &x);
        assert_true(scene_place_mesh(s, mesh, &a, material) >= 0);
    }
}

static void render(scene *s, int flatten, const render_settings *st, image *img)
{
    if (flatten)
        assert_int_equal(scene_flatten_instances(s, 1, err, sizeof err), 0);
    if (scene_finish(s, 0, 0, 0, err, sizeof err) != 0 ||
        renderer_set_settings(R, st, err, sizeof err) != 0 ||
        renderer_set_scene(R, s, err, sizeof err) != 0 ||
        renderer_render(R, img, err, sizeof err) != 0)
        fail_msg("%s", err);
}

/* The comparison; on failure, both images and a diff image. */
static int compare(const image *ref, const image *img, const char *name)
{
    image_diff_stats st;
    double npx = (double)ref->width * ref->height, over;
    int pass;
    assert_int_equal(image_compare(ref, img, NULL, INST_TOL, &st), 0);
    over = st.over / npx;
    pass = over <= INST_MAX_OVER && st.mean_abs < INST_MAX_MEAN;
    printf("  %-34s %5.2f%% of the pixels > %g, mean %.1e%s\n", name, 100 * over, INST_TOL,
           st.mean_abs, pass ? "" : "  FAIL");
    if (!pass || getenv("INST_WRITE")) {
        char path[512];
        mkdir("build", 0777);
        mkdir(OUT_DIR, 0777);
        snprintf(path, sizeof path, OUT_DIR "/instance-%s.png", name);
        image_write(img, path, err, sizeof err);
        snprintf(path, sizeof path, OUT_DIR "/instance-%s-ref.png", name);
        image_write(ref, path, err, sizeof err);
        snprintf(path, sizeof path, OUT_DIR "/instance-%s-diff.png", name);
        image_write_diff(ref, img, NULL, INST_TOL, 10, path, err, sizeof err);
        printf("    diff image: %s\n", path);
    }
    return pass;
}

/* Instanced against flattened, on each strategy and both precisions. */
static void test_instanced_like_flattened(void **state)
{
    static const struct {
        const char *name;
        int strategy, precision;
    } cases[] = {{"pixel-robust", RENDER_PIXEL, RENDER_ROBUST},
                 {"wavefront-robust", RENDER_WAVEFRONT, RENDER_ROBUST},
                 {"pixel-fast", RENDER_PIXEL, RENDER_FAST}};
    int fails = 0;
    (void)state;
    for (size_t c = 0; c < sizeof cases / sizeof cases[0]; c++) {
        render_settings st;
        scene a, b;
        image ia, ib;
        render_settings_default(&st);
        st.strategy = cases[c].strategy;
        st.precision = cases[c].precision;
        make_scene(&a, 0, 160, 120);
        make_scene(&b, 0, 160, 120);
        render(&a, 0, &st, &ia);
        assert_int_equal((int)a.instances.count, PLACEMENTS); /* still instances */
        render(&b, 1, &st, &ib);
        assert_int_equal((int)b.instances.count, 0);
        fails += !compare(&ib, &ia, cases[c].name);
        scene_free(&a);
        scene_free(&b);
        image_free(&ia);
        image_free(&ib);
    }
    assert_int_equal(fails, 0);
}

/* The instanced scene moved by 1e6 renders like the flattened one at the origin. */
static void test_instanced_far(void **state)
{
    render_settings st;
    scene a, b;
    image ia, ib;
    (void)state;
    render_settings_default(&st);
    make_scene(&a, 1e6, 160, 120);
    make_scene(&b, 0, 160, 120);
    render(&a, 0, &st, &ia);
    render(&b, 1, &st, &ib);
    assert_true(compare(&ib, &ia, "far-1e6"));
    scene_free(&a);
    scene_free(&b);
    image_free(&ia);
    image_free(&ib);
}

/* 1000 placements of one 5k-triangle mesh: one copy of its triangles on the device. */
static void test_many_placements(void **state)
{
    scene s, f;
    devscene ds;
    image ia, ib;
    render_settings st;
    int mesh, mat, i, ntri;
    (void)state;
    for (int pass = 0; pass < 2; pass++) {
        scene *sc = pass == 0 ? &s : &f;
        tu_base_scene(sc, SCENE_PERSPECTIVE, 0, 96, 72);
        sc->camera.eye = vec3d_make(0, 30, 60);
        assert_int_equal(
            scene_camera_basis(&sc->camera, vec3f_make(0, -0.5f, -1), vec3f_make(0, 1, 0)), 0);
        sc->camera.fov_deg = 50;
        sc->ambient = vec3f_make(0.2f, 0.2f, 0.2f);
        mat = tu_add_material(sc, vec3f_make(.5f, .5f, .5f), vec3f_make(.6f, .5f, .4f),
                              vec3f_make(.3f, .3f, .3f), vec3f_make(0, 0, 0), vec3f_make(0, 0, 0),
                              1, 20);
        tu_add_light(sc, vec3f_make(-20, 40, 30), vec3f_make(.8f, .8f, .8f));
        mesh = add_mesh(sc, 50, 50, mat, mat);
        for (i = 0; i < 1000; i++) {
            scene_xform x, r, a;
            xform_rotate(&r, 0, 1, 0, i * 7.0);
            xform_translate(&x, (i % 40) * 2.5 - 50, 0, (i / 40) * -2.5 + 20);
            xform_compose(&a, &x, &r);
            assert_true(scene_place_mesh(sc, mesh, &a, -1) >= 0);
        }
    }
    ntri = (int)SCENE_AT(s.meshes, scene_mesh, 0).count;
    assert_int_equal(scene_finish(&s, 0, 0, 0, err, sizeof err), 0);
    assert_int_equal(devscene_convert(&s, &s.camera.eye, &ds, err, sizeof err), 0);
    assert_int_equal(devscene_build_bvh(&ds, err, sizeof err), 0);
    printf("  1000 placements of a %d-triangle mesh: %d triangles, %d instances on the device\n",
           ntri, ds.ntri, ds.ninst);
    assert_int_equal(ds.ninst, 1000);
    assert_true(ds.ntri <= ntri); /* one copy (degenerate pole triangles dropped) */
    devscene_free(&ds);
    render_settings_default(&st);
    render(&s, 0, &st, &ia);
    render(&f, 1, &st, &ib);
    assert_true(compare(&ib, &ia, "1000-placements"));
    scene_free(&s);
    scene_free(&f);
    image_free(&ia);
    image_free(&ib);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_instanced_like_flattened),
        cmocka_unit_test(test_instanced_far),
        cmocka_unit_test(test_many_placements),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
