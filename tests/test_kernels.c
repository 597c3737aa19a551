/* The real kernels on PoCL: camera rays for the three projections, ray-primitive
 * intersection (discriminant cases, parallel rays, non-convex polygons, closest hit),
 * and shading against hand-computed values of the model's formula. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "testutil.h"

#include "render.h"
#include "render_debug.h"
#include "scene.h"

TU_RENDERER_FIXTURE_AT(1, 1) /* rays in world coordinates */
static char err[2048];

/* A camera at eye with basis x, y, z (w = +z), window [-1,1]^2, d = 1. */
static void base_scene(scene *s, enum scene_projection proj, int w, int h)
{
    tu_base_scene(s, proj, 10, w, h);
}

/* No transmission, index 1. */
static int add_material(scene *s, vec3f ka, vec3f kd, vec3f ks, vec3f km, float p)
{
    return tu_add_material(s, ka, kd, ks, km, vec3f_make(0, 0, 0), 1, p);
}

#define add_light tu_add_light

static void upload(scene *s)
{
    tu_upload(R, s);
}

static void assert_near(double got, double want, double tol, const char *what)
{
    if (!(fabs(got - want) <= tol))
        fail_msg("%s: got %.9g, want %.9g (tolerance %g)", what, got, want, tol);
}

static void assert_vec(cw_float4 got, double x, double y, double z, double tol, const char *what)
{
    char buf[128];
    snprintf(buf, sizeof buf, "%s.x", what);
    assert_near(got.x, x, tol, buf);
    snprintf(buf, sizeof buf, "%s.y", what);
    assert_near(got.y, y, tol, buf);
    snprintf(buf, sizeof buf, "%s.z", what);
    assert_near(got.z, z, tol, buf);
}

/* ---- camera ----------------------------------------------------------------------- */

static cw_ray *gen_rays(scene *s)
{
    cw_ray *rays = calloc((size_t)s->width * s->height, sizeof *rays);
    assert_non_null(rays);
    upload(s);
    if (renderer_generate_rays(R, rays, err, sizeof err) != 0)
        fail_msg("%s", err);
    return rays;
}

/* 4x2 pixels, window l=-2 r=2 b=-1 t=1: pixel (i,j) centre at u = -2 + (i+0.5),
 * v = -1 + (j+0.5); image row 0 is j = 1. */
static void set_window_4x2(scene *s)
{
    s->camera.l = -2;
    s->camera.r = 2;
    s->camera.b = -1;
    s->camera.t = 1;
}

static void test_camera_perspective(void **state)
{
    scene s;
    cw_ray *rays;
    double n;
    (void)state;
    base_scene(&s, SCENE_PERSPECTIVE, 4, 2);
    set_window_4x2(&s);
    s.camera.d = 2;
    rays = gen_rays(&s);
    /* pixel (0,0), bottom-left, is image index 4 (second row): u=-1.5, v=-0.5, d=2 */
    n = sqrt(1.5 * 1.5 + 0.5 * 0.5 + 4);
    assert_vec(rays[4].origin, 0, 0, 10, 0, "origin");
    assert_vec(rays[4].dir, -1.5 / n, -0.5 / n, -2 / n, 1e-6, "dir(0,0)");
    assert_int_equal(rays[4].pixel, 4);
    assert_int_equal(rays[4].depth, 1);
    /* pixel (3,1), top-right, image index 3: u=1.5, v=0.5 */
    assert_vec(rays[3].dir, 1.5 / n, 0.5 / n, -2 / n, 1e-6, "dir(3,1)");
    assert_vec(rays[3].weight, 1, 1, 1, 0, "weight");
    free(rays);
    scene_free(&s);
}

static void test_camera_perspective_basis(void **state)
{
    scene s;
    cw_ray *rays;
    (void)state;
    /* looking from (1,2,3) along +x with up +z: w = -x, u = up x w = (0,-1,0), v = w x u =
     * (0,0,1). 1x1 image, window [-1,1]^2: the single ray goes straight ahead. */
    base_scene(&s, SCENE_PERSPECTIVE, 1, 1);
    s.camera.eye = vec3d_make(1, 2, 3);
    assert_int_equal(scene_camera_basis(&s.camera, vec3f_make(1, 0, 0), vec3f_make(0, 0, 1)), 0);
    rays = gen_rays(&s);
    assert_vec(rays[0].origin, 1, 2, 3, 0, "origin");
    assert_vec(rays[0].dir, 1, 0, 0, 1e-6, "dir");
    free(rays);
    /* 2x1 image: left pixel at u = -0.5, i.e. 0.5 along -u = +y */
    base_scene(&s, SCENE_PERSPECTIVE, 2, 1);
    s.camera.eye = vec3d_make(1, 2, 3);
    assert_int_equal(scene_camera_basis(&s.camera, vec3f_make(1, 0, 0), vec3f_make(0, 0, 1)), 0);
    rays = gen_rays(&s);
    assert_vec(rays[0].dir, 1 / sqrt(1.25), 0.5 / sqrt(1.25), 0, 1e-6, "dir left");
    free(rays);
    scene_free(&s);
}

static void test_camera_orthographic(void **state)
{
    scene s;
    cw_ray *rays;
    (void)state;
    base_scene(&s, SCENE_ORTHOGRAPHIC, 4, 2);
    set_window_4x2(&s);
    rays = gen_rays(&s);
    assert_vec(rays[4].origin, -1.5, -0.5, 10, 1e-6, "origin(0,0)");
    assert_vec(rays[4].dir, 0, 0, -1, 0, "dir(0,0)");
    assert_vec(rays[1].origin, -0.5, 0.5, 10, 1e-6, "origin(1,1)");
    assert_vec(rays[1].dir, 0, 0, -1, 0, "dir(1,1)");
    free(rays);
    scene_free(&s);
}

static void test_camera_oblique(void **state)
{
    scene s;
    cw_ray *rays;
    double n = sqrt(0.25 + 0.01 + 1);
    (void)state;
    base_scene(&s, SCENE_OBLIQUE, 4, 2);
    set_window_4x2(&s);
    s.camera.dir = vec3f_make(0.5f, 0.1f, -1); /* normalised by scene_finish */
    rays = gen_rays(&s);
    assert_vec(rays[6].origin, 0.5, -0.5, 10, 1e-6, "origin(2,0)");
    assert_vec(rays[6].dir, 0.5 / n, 0.1 / n, -1 / n, 1e-6, "dir(2,0)");
    assert_vec(rays[0].dir, 0.5 / n, 0.1 / n, -1 / n, 1e-6, "dir(0,1)");
    free(rays);
    scene_free(&s);
}

/* ---- intersection ----------------------------------------------------------------- */

#define make_ray tu_make_ray

static void trace(scene *s, cw_ray *rays, int n, cw_hit *hits)
{
    int i;
    for (i = 0; i < n; i++)
        rays[i].pixel = i;
    upload(s);
    if (renderer_intersect(R, rays, n, hits, err, sizeof err) != 0)
        fail_msg("%s", err);
}

static void test_sphere_cases(void **state)
{
    scene s;
    cw_ray rays[6];
    cw_hit hits[6];
    vec3f one = vec3f_make(1, 1, 1);
    (void)state;
    base_scene(&s, SCENE_PERSPECTIVE, 1, 1);
    tu_add_sphere(&s, 0, 0, -5, 1, add_material(&s, one, one, one, one, 1));
    rays[0] = make_ray(0, 0, 0, 0, 0, -1);     /* disc > 0: two roots, nearer is 4 */
    rays[1] = make_ray(1, 0, 0, 0, 0, -1);     /* disc = 0: tangent at t = 5 */
    rays[2] = make_ray(1.001, 0, 0, 0, 0, -1); /* disc < 0: miss */
    rays[3] = make_ray(0, 0, -5, 0, 1, 0);     /* from the centre: only the far root, 1 */
    rays[4] = make_ray(0, 0, 0, 0, 0, 1);      /* sphere behind the ray: both roots < 0 */
    rays[5] = make_ray(0, 3, 0, 0, -3, -5);    /* oblique through the centre: |(0,3,5)|-1 */
    trace(&s, rays, 6, hits);
    assert_int_equal(hits[0].kind, CW_PRIM_SPHERE);
    assert_near(hits[0].t, 4, 1e-5, "two roots");
    assert_int_equal(hits[1].kind, CW_PRIM_SPHERE);
    assert_near(hits[1].t, 5, 1e-5, "tangent");
    assert_int_equal(hits[2].kind, CW_PRIM_NONE);
    assert_int_equal(hits[3].kind, CW_PRIM_SPHERE);
    assert_near(hits[3].t, 1, 1e-5, "inside");
    assert_int_equal(hits[4].kind, CW_PRIM_NONE);
    assert_int_equal(hits[5].kind, CW_PRIM_SPHERE);
    assert_near(hits[5].t, sqrt(34.0) - 1, 1e-5, "oblique");
    scene_free(&s);
}

static void test_triangle_cases(void **state)
{
    scene s;
    cw_ray rays[6];
    cw_hit hits[6];
    vec3f one = vec3f_make(1, 1, 1);
    (void)state;
    base_scene(&s, SCENE_PERSPECTIVE, 1, 1);
    tu_add_triangle(&s, vec3f_make(0, 0, -2), vec3f_make(1, 0, -2), vec3f_make(0, 1, -2),
                    add_material(&s, one, one, one, one, 1));
    rays[0] = make_ray(0.25, 0.125, 0, 0, 0, -1); /* inside: t=2, beta=.25, gamma=.125 */
    rays[1] = make_ray(0.75, 0.75, 0, 0, 0, -1);  /* outside: beta + gamma > 1 */
    rays[2] = make_ray(-1, 0.25, -2, 1, 0, 0);    /* parallel, in the triangle's plane */
    rays[3] = make_ray(0.2, 0.2, -1, 1, 0, 0);    /* parallel, off the plane */
    rays[4] = make_ray(0.25, 0.25, -4, 0, 0, 1);  /* from behind: two-sided hit, t=2 */
    rays[5] = make_ray(0.25, 0.25, -3, 0, 0, -1); /* triangle behind the origin */
    trace(&s, rays, 6, hits);
    assert_int_equal(hits[0].kind, CW_PRIM_TRIANGLE);
    assert_near(hits[0].t, 2, 1e-6, "t");
    assert_near(hits[0].u, 0.25, 1e-6, "beta");
    assert_near(hits[0].v, 0.125, 1e-6, "gamma");
    assert_int_equal(hits[1].kind, CW_PRIM_NONE);
    assert_int_equal(hits[2].kind, CW_PRIM_NONE);
    assert_true(!isnan(hits[2].t));
    assert_int_equal(hits[3].kind, CW_PRIM_NONE);
    assert_int_equal(hits[4].kind, CW_PRIM_TRIANGLE);
    assert_near(hits[4].t, 2, 1e-6, "t from behind");
    assert_int_equal(hits[5].kind, CW_PRIM_NONE);
    scene_free(&s);
}

static void test_polygon_nonconvex(void **state)
{
    /* A "U" in the plane z = -3, seen from +z: arms at x in [0,1] and [2,3], the base at
     * y in [0,1], the notch x in (1,2), y in (1,3) is outside. */
    static const float u_shape[8][2] = {{0, 0}, {3, 0}, {3, 3}, {2, 3},
                                        {2, 1}, {1, 1}, {1, 3}, {0, 3}};
    vec3f v[8];
    scene s;
    cw_ray rays[5];
    cw_hit hits[5];
    vec3f one = vec3f_make(1, 1, 1);
    int i;
    (void)state;
    for (i = 0; i < 8; i++)
        v[i] = vec3f_make(u_shape[i][0], u_shape[i][1], -3);
    base_scene(&s, SCENE_PERSPECTIVE, 1, 1);
    tu_add_polygon(&s, v, 8, add_material(&s, one, one, one, one, 1));
    rays[0] = make_ray(0.5, 2.5, 0, 0, 0, -1); /* left arm */
    rays[1] = make_ray(2.5, 2.5, 0, 0, 0, -1); /* right arm */
    rays[2] = make_ray(1.5, 2.0, 0, 0, 0, -1); /* the notch: outside though inside the hull */
    rays[3] = make_ray(1.5, 0.5, 0, 0, 0, -1); /* the base */
    rays[4] = make_ray(3.5, 0.5, 0, 0, 0, -1); /* outside */
    trace(&s, rays, 5, hits);
    assert_int_equal(hits[0].kind, CW_PRIM_POLYGON);
    assert_near(hits[0].t, 3, 1e-6, "left arm t");
    assert_int_equal(hits[1].kind, CW_PRIM_POLYGON);
    assert_int_equal(hits[2].kind, CW_PRIM_NONE);
    assert_int_equal(hits[3].kind, CW_PRIM_POLYGON);
    assert_int_equal(hits[4].kind, CW_PRIM_NONE);
    scene_free(&s);
}

static void test_closest_hit(void **state)
{
    static const float sq[4][2] = {{-1, -1}, {1, -1}, {1, 1}, {-1, 1}};
    vec3f v[4];
    scene s;
    cw_ray rays[3];
    cw_hit hits[3];
    vec3f one = vec3f_make(1, 1, 1);
    int m, i;
    (void)state;
    base_scene(&s, SCENE_PERSPECTIVE, 1, 1);
    m = add_material(&s, one, one, one, one, 1);
    tu_add_sphere(&s, 0, 0, -10, 1, m); /* farthest */
    tu_add_sphere(&s, 0, 0, -6, 1, m);  /* nearest sphere */
    tu_add_triangle(&s, vec3f_make(-1, -1, -8), vec3f_make(1, -1, -8), vec3f_make(0, 1, -8), m);
    for (i = 0; i < 4; i++)
        v[i] = vec3f_make(sq[i][0] + 5, sq[i][1], -3);
    tu_add_polygon(&s, v, 4, m);
    rays[0] = make_ray(0, 0, 0, 0, 0, -1);    /* sphere 1 at t=5 before triangle and sphere 0 */
    rays[1] = make_ray(0, 0, -7.5, 0, 0, -1); /* past sphere 1: triangle at 0.5 */
    rays[2] = make_ray(5, 0, 0, 0, 0, -1);    /* only the polygon */
    trace(&s, rays, 3, hits);
    assert_int_equal(hits[0].kind, CW_PRIM_SPHERE);
    assert_int_equal(hits[0].index, 1);
    assert_near(hits[0].t, 5, 1e-5, "nearest sphere");
    assert_int_equal(hits[1].kind, CW_PRIM_TRIANGLE);
    assert_near(hits[1].t, 0.5, 1e-5, "triangle");
    assert_int_equal(hits[2].kind, CW_PRIM_POLYGON);
    assert_near(hits[2].t, 3, 1e-5, "polygon");
    scene_free(&s);
}

/* ---- shading ---------------------------------------------------------------------- */

/* An orthographic 1x1 camera looking down -z at the origin, over a large square floor in
 * the plane z = 0 (normal +z) with the given material. */
static void floor_scene(scene *s, int mat_from_caller)
{
    static const float sq[4][2] = {{-50, -50}, {50, -50}, {50, 50}, {-50, 50}};
    vec3f v[4];
    int i;
    for (i = 0; i < 4; i++)
        v[i] = vec3f_make(sq[i][0], sq[i][1], 0);
    tu_add_polygon(s, v, 4, mat_from_caller);
}

static void render_pixel(scene *s, int x, int y, double out[3])
{
    image img;
    size_t k;
    upload(s);
    if (renderer_render(R, &img, err, sizeof err) != 0)
        fail_msg("%s", err);
    k = 3 * ((size_t)y * img.width + x);
    out[0] = img.rgb[k];
    out[1] = img.rgb[k + 1];
    out[2] = img.rgb[k + 2];
    image_free(&img);
}

/* The model at point p with normal n seen from direction v (unit, towards the eye):
 * ka Ia + sum over unblocked lights facing the surface of kd I (n.l) + ks I (n.h)^p. */
static void blinn_phong(const double p[3], const double n[3], const double v[3], const scene *s,
                        const int *blocked, double out[3])
{
    const scene_material *m = &SCENE_AT(s->materials, scene_material, 0);
    double ka[3] = {m->ka.x, m->ka.y, m->ka.z}, kd[3] = {m->kd.x, m->kd.y, m->kd.z};
    double ks[3] = {m->ks.x, m->ks.y, m->ks.z}, ia[3] = {s->ambient.x, s->ambient.y, s->ambient.z};
    size_t k;
    int c;
    for (c = 0; c < 3; c++)
        out[c] = ka[c] * ia[c];
    for (k = 0; k < s->lights.count; k++) {
        const scene_light *L = &SCENE_AT(s->lights, scene_light, k);
        double l[3] = {L->position.x - p[0], L->position.y - p[1], L->position.z - p[2]};
        double I[3] = {L->intensity.x, L->intensity.y, L->intensity.z};
        double ll = sqrt(l[0] * l[0] + l[1] * l[1] + l[2] * l[2]), h[3], hl, ndl, ndh;
        for (c = 0; c < 3; c++)
            l[c] /= ll;
        ndl = n[0] * l[0] + n[1] * l[1] + n[2] * l[2];
        if (ndl <= 0 || (blocked && blocked[k]))
            continue;
        for (c = 0; c < 3; c++)
            h[c] = l[c] + v[c];
        hl = sqrt(h[0] * h[0] + h[1] * h[1] + h[2] * h[2]);
        ndh = (n[0] * h[0] + n[1] * h[1] + n[2] * h[2]) / hl;
        for (c = 0; c < 3; c++)
            out[c] += kd[c] * I[c] * ndl + ks[c] * I[c] * pow(ndh > 0 ? ndh : 0, m->p);
    }
}

static void shading_setup(scene *s)
{
    base_scene(s, SCENE_ORTHOGRAPHIC, 1, 1);
    s->camera.l = s->camera.b = -0.01f;
    s->camera.r = s->camera.t = 0.01f; /* the single ray hits (0,0,0) */
    s->ambient = vec3f_make(0.1f, 0.2f, 0.3f);
    add_material(s, vec3f_make(0.3f, 0.2f, 0.1f), vec3f_make(0.5f, 0.6f, 0.7f),
                 vec3f_make(0.4f, 0.3f, 0.2f), vec3f_make(0, 0, 0), 20);
    floor_scene(s, 0);
}

static void check_pixel(const double got[3], const double want[3], const char *what)
{
    int c;
    printf("  %s: got (%.6f %.6f %.6f), formula (%.6f %.6f %.6f)\n", what, got[0], got[1], got[2],
           want[0], want[1], want[2]);
    for (c = 0; c < 3; c++)
        assert_near(got[c], want[c], 2e-5, what);
}

static const double P0[3] = {0, 0, 0}, NZ[3] = {0, 0, 1}, VZ[3] = {0, 0, 1};

static void test_shade_one_light(void **state)
{
    scene s;
    double got[3], want[3];
    (void)state;
    shading_setup(&s);
    add_light(&s, vec3f_make(3, 1, 4), vec3f_make(0.9f, 0.8f, 0.7f));
    render_pixel(&s, 0, 0, got);
    blinn_phong(P0, NZ, VZ, &s, NULL, want);
    check_pixel(got, want, "one light");
    /* the specular term must matter in this set-up, or the test would not check it */
    assert_true(want[0] > 0.3 * 0.1 + 0.5 * 0.9 * 4 / sqrt(26.0) + 1e-3);
    scene_free(&s);
}

static void test_shade_two_lights(void **state)
{
    scene s;
    double got[3], want[3];
    (void)state;
    shading_setup(&s);
    add_light(&s, vec3f_make(3, 1, 4), vec3f_make(0.9f, 0.8f, 0.7f));
    add_light(&s, vec3f_make(-2, -2, 1), vec3f_make(0.2f, 0.5f, 1.0f));
    render_pixel(&s, 0, 0, got);
    blinn_phong(P0, NZ, VZ, &s, NULL, want);
    check_pixel(got, want, "two lights");
    scene_free(&s);
}

static void test_shade_shadow(void **state)
{
    scene s;
    double got[3], want[3];
    int blocked[2] = {1, 0};
    (void)state;
    shading_setup(&s);
    add_light(&s, vec3f_make(3, 1, 4), vec3f_make(0.9f, 0.8f, 0.7f));
    add_light(&s, vec3f_make(-2, -2, 1), vec3f_make(0.2f, 0.5f, 1.0f));
    /* a small sphere on the segment to light 0, away from the eye ray */
    tu_add_sphere(&s, 1.5f, 0.5f, 2.0f, 0.2f, 0);
    render_pixel(&s, 0, 0, got);
    blinn_phong(P0, NZ, VZ, &s, blocked, want);
    check_pixel(got, want, "light 0 in shadow");
    scene_free(&s);
}

static void test_shade_light_behind(void **state)
{
    scene s;
    double got[3], want[3];
    (void)state;
    shading_setup(&s);
    /* slightly below the floor's plane: n.l < 0 though n.h > 0, so a specular term would
     * show if the facing test were missing */
    add_light(&s, vec3f_make(10, 0, -0.5f), vec3f_make(1, 1, 1));
    render_pixel(&s, 0, 0, got);
    want[0] = 0.3 * 0.1;
    want[1] = 0.2 * 0.2;
    want[2] = 0.1 * 0.3;
    check_pixel(got, want, "light behind the surface");
    scene_free(&s);
}

/* Mirror A (normal (1,0,1)/sqrt2 at the origin) sends the eye ray to +x, mirror B at
 * x = 5 (normal (-1,0,1)/sqrt2) sends it up to +z, where a plate C at z = 5 (x in [4,6])
 * or the background waits. Ambient light only, so every local term is ka Ia exactly. */
static void mirror_scene(scene *s, int with_c)
{
    vec3f a[4], b[4], c[4];
    int ma, mb, mc;
    base_scene(s, SCENE_ORTHOGRAPHIC, 1, 1);
    s->camera.l = s->camera.b = -0.01f;
    s->camera.r = s->camera.t = 0.01f;
    s->ambient = vec3f_make(1, 1, 1);
    s->background = vec3f_make(0.05f, 0.1f, 0.2f);
    ma = add_material(s, vec3f_make(0.1f, 0.2f, 0.3f), vec3f_make(0, 0, 0), vec3f_make(0, 0, 0),
                      vec3f_make(0.5f, 0.6f, 0.7f), 1);
    mb = add_material(s, vec3f_make(0.3f, 0.1f, 0.2f), vec3f_make(0, 0, 0), vec3f_make(0, 0, 0),
                      vec3f_make(0.9f, 0.4f, 0.8f), 1);
    mc = add_material(s, vec3f_make(0.6f, 0.5f, 0.4f), vec3f_make(0, 0, 0), vec3f_make(0, 0, 0),
                      vec3f_make(0, 0, 0), 1);
    a[0] = vec3f_make(-1, -1, 1);
    a[1] = vec3f_make(1, -1, -1);
    a[2] = vec3f_make(1, 1, -1);
    a[3] = vec3f_make(-1, 1, 1);
    tu_add_polygon(s, a, 4, ma);
    b[0] = vec3f_make(4, -1, -1);
    b[1] = vec3f_make(6, -1, 1);
    b[2] = vec3f_make(6, 1, 1);
    b[3] = vec3f_make(4, 1, -1);
    tu_add_polygon(s, b, 4, mb);
    if (with_c) {
        c[0] = vec3f_make(4, -1, 5);
        c[1] = vec3f_make(6, -1, 5);
        c[2] = vec3f_make(6, 1, 5);
        c[3] = vec3f_make(4, 1, 5);
        tu_add_polygon(s, c, 4, mc);
    }
}

static void test_shade_mirror_of_mirror(void **state)
{
    static const double ka[3][3] = {{0.1, 0.2, 0.3}, {0.3, 0.1, 0.2}, {0.6, 0.5, 0.4}};
    static const double km[2][3] = {{0.5, 0.6, 0.7}, {0.9, 0.4, 0.8}};
    static const double bg[3] = {0.05, 0.1, 0.2};
    int depth, with_c, c;
    (void)state;
    for (with_c = 0; with_c <= 1; with_c++) {
        for (depth = 1; depth <= 4; depth++) {
            scene s;
            double got[3], want[3];
            char what[64];
            mirror_scene(&s, with_c);
            s.max_depth = depth;
            for (c = 0; c < 3; c++) {
                double third = with_c ? ka[2][c] : bg[c];
                want[c] = ka[0][c];
                if (depth >= 2)
                    want[c] += km[0][c] * ka[1][c];
                if (depth >= 3)
                    want[c] += km[0][c] * km[1][c] * third;
            }
            render_pixel(&s, 0, 0, got);
            snprintf(what, sizeof what, "mirror chain, depth %d, %s", depth,
                     with_c ? "plate" : "background");
            check_pixel(got, want, what);
            scene_free(&s);
        }
    }
}

static void test_shade_miss_is_background(void **state)
{
    scene s;
    double got[3], want[3] = {0.05, 0.1, 0.2};
    (void)state;
    base_scene(&s, SCENE_PERSPECTIVE, 1, 1);
    s.background = vec3f_make(0.05f, 0.1f, 0.2f);
    add_material(&s, vec3f_make(1, 1, 1), vec3f_make(1, 1, 1), vec3f_make(0, 0, 0),
                 vec3f_make(0, 0, 0), 1);
    tu_add_sphere(&s, 0, 0, -5, 1, 0);
    s.camera.eye = vec3d_make(0, 10, 10); /* looking along -z past the sphere */
    render_pixel(&s, 0, 0, got);
    check_pixel(got, want, "miss");
    scene_free(&s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_camera_perspective),
        cmocka_unit_test(test_camera_perspective_basis),
        cmocka_unit_test(test_camera_orthographic),
        cmocka_unit_test(test_camera_oblique),
        cmocka_unit_test(test_sphere_cases),
        cmocka_unit_test(test_triangle_cases),
        cmocka_unit_test(test_polygon_nonconvex),
        cmocka_unit_test(test_closest_hit),
        cmocka_unit_test(test_shade_one_light),
        cmocka_unit_test(test_shade_two_lights),
        cmocka_unit_test(test_shade_shadow),
        cmocka_unit_test(test_shade_light_behind),
        cmocka_unit_test(test_shade_mirror_of_mirror),
        cmocka_unit_test(test_shade_miss_is_background),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
