/* The preview's camera controls (host/viewcam.c), without a display: start-up (pivot,
 * world up), orbit, pan, zoom, fly, reset, resize (square pixels), projection toggle, and
 * the JSON the preview's script writes (read back by the JSON reader). Runs from the
 * repository root. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "testutil.h"

#include "scene.h"
#include "scene_json.h"
#include "scene_load.h"
#include "viewcam.h"

#define EPS 1e-4f
#define PI 3.14159265358979323846

static char err[2048];

static void load(const char *path, int w, int h, scene *s)
{
    scene_init(s);
    if (scene_load(path, s, err, sizeof err) != 0 || scene_finish(s, w, h, 0, err, sizeof err) != 0)
        fail_msg("%s: %s", path, err);
}

static void parse_json(const char *text, scene *s)
{
    scene_init(s);
    if (json_scene_parse(text, strlen(text), "test.json", s, err, sizeof err) != 0 ||
        scene_finish(s, 0, 0, 0, err, sizeof err) != 0)
        fail_msg("%s", err);
}

static void assert_vec_near(vec3f a, vec3f b, float eps)
{
    if (!(fabsf(a.x - b.x) <= eps && fabsf(a.y - b.y) <= eps && fabsf(a.z - b.z) <= eps))
        fail_msg("vector (%.7g, %.7g, %.7g), expected (%.7g, %.7g, %.7g)", a.x, a.y, a.z, b.x, b.y,
                 b.z);
}

static void assert_near(double a, double b, double eps)
{
    if (!(fabs(a - b) <= eps))
        fail_msg("value %.9g, expected %.9g (eps %g)", a, b, eps);
}

/* A position as float, to compare with the float vectors of the camera. */
static vec3f fp(vec3d a)
{
    return vec3f_make((float)a.x, (float)a.y, (float)a.z);
}

static vec3f add(vec3f a, vec3f b)
{
    return vec3f_make(a.x + b.x, a.y + b.y, a.z + b.z);
}

static vec3f mul(vec3f a, float k)
{
    return vec3f_make(a.x * k, a.y * k, a.z * k);
}

/* An orthonormal right-handed basis, u level (perpendicular to world up), the pivot on
 * the view axis at dist. */
static void assert_consistent(const viewcam *vc)
{
    const scene_camera *c = &vc->cam;
    vec3f x = vec3f_cross(c->u, c->v);
    assert_near(vec3f_length(c->u), 1, 1e-5);
    assert_near(vec3f_length(c->v), 1, 1e-5);
    assert_near(vec3f_dot(c->u, c->v), 0, 1e-5);
    assert_vec_near(x, c->w, 1e-5f);
    assert_near(vec3f_dot(c->u, vc->up), 0, 1e-5);
    assert_vec_near(add(fp(c->eye), mul(c->w, -vc->dist)), fp(vc->pivot), 1e-4f * (1 + vc->dist));
    /* square pixels */
    assert_near((c->r - c->l) / vc->width, (c->t - c->b) / vc->height, 1e-5 * (c->t - c->b));
}

static void test_init_default(void **state)
{
    scene s;
    viewcam vc;
    (void)state;
    load("scenes/default.json", 160, 120, &s);
    viewcam_init(&vc, &s);
    /* up [0,1,0] in the file: the orbit axis is Y */
    assert_vec_near(vc.up, vec3f_make(0, 1, 0), 0);
    /* the pivot is on the view axis, near the file's look_at [0, 1.1, 0] (9.12 away): the
     * bounding box centre (0, 1.45, 0) projected on the axis */
    assert_near(vc.dist, 9.07, 0.01);
    assert_vec_near(fp(vc.pivot), vec3f_make(0, 1.1f, 0), 0.06f);
    assert_int_equal(vc.width, 160);
    assert_int_equal(vc.height, 120);
    assert_true(memcmp(&vc.cam.eye, &s.camera.eye, sizeof(vec3d)) == 0);
    assert_true(vc.cam.l == s.camera.l && vc.cam.r == s.camera.r && vc.cam.b == s.camera.b &&
                vc.cam.t == s.camera.t);
    assert_consistent(&vc);
    scene_free(&s);
}

static void test_world_up(void **state)
{
    scene s;
    viewcam vc;
    (void)state;
    /* Z up, looking along +y and down */
    parse_json("{\"camera\": {\"eye\": [0, -10, 3], \"look_at\": [0, 0, 0], \"up\": [0, 0, 1], "
               "\"fov\": 40}, \"objects\": [{\"type\": \"triangle\", \"vertices\": [[-1, 0, 0], "
               "[1, 0, 0], [0, 0, 1]], \"material\": \"m\"}], \"materials\": {\"m\": {}}}",
               &s);
    viewcam_init(&vc, &s);
    assert_vec_near(vc.up, vec3f_make(0, 0, 1), 0);
    scene_free(&s);
    /* looking straight down with up = -z: Y is perpendicular to the view's vertical, so Z
     * (signed towards v) is the axis */
    parse_json("{\"camera\": {\"eye\": [0, 10, 0], \"view\": [0, -1, 0], \"up\": [0, 0, -1], "
               "\"window\": [-1, 1, -1, 1]}}",
               &s);
    viewcam_init(&vc, &s);
    assert_vec_near(vc.up, vec3f_make(0, 0, -1), 0);
    assert_near(vc.dist, 1.0, 0); /* empty scene: one unit */
    scene_free(&s);
    /* tetra.nff: up (-1,-1,1) is no axis, and no axis is perpendicular to u: v itself */
    load("scenes/spd/tetra.nff", 64, 64, &s);
    viewcam_init(&vc, &s);
    assert_vec_near(vc.up, s.camera.v, 0);
    assert_consistent(&vc);
    scene_free(&s);
}

static void test_orbit(void **state)
{
    scene s;
    viewcam vc;
    vec3f off0, off1, h0, h1, up = {0, 1, 0};
    double e0, e1, ang;
    (void)state;
    load("scenes/default.json", 160, 120, &s);
    viewcam_init(&vc, &s);
    off0 = vec3f_sub(fp(vc.cam.eye), fp(vc.pivot));
    e0 = asin(vec3f_dot(vc.cam.w, up));

    /* yaw 30 degrees: same distance and height, eye moved towards +u, horizontal angle 30 */
    viewcam_orbit(&vc, (float)(30 * PI / 180), 0);
    assert_consistent(&vc);
    off1 = vec3f_sub(fp(vc.cam.eye), fp(vc.pivot));
    assert_near(vec3f_length(off1), vec3f_length(off0), 1e-4);
    assert_near(off1.y, off0.y, 1e-4);
    h0 = vec3f_make(off0.x, 0, off0.z);
    h1 = vec3f_make(off1.x, 0, off1.z);
    ang = acos(vec3f_dot(h0, h1) / (vec3f_length(h0) * vec3f_length(h1)));
    assert_near(ang, 30 * PI / 180, 1e-4);
    assert_true(vec3f_dot(vec3f_sub(off1, off0), s.camera.u) > 0);
    /* the rest of the turn brings it back */
    viewcam_orbit(&vc, (float)(330 * PI / 180), 0);
    assert_vec_near(fp(vc.cam.eye), fp(s.camera.eye), 1e-3f);
    assert_vec_near(vc.cam.w, s.camera.w, 1e-5f);

    /* pitch: the elevation changes by the angle, the eye moves up */
    viewcam_orbit(&vc, 0, 0.2f);
    assert_consistent(&vc);
    e1 = asin(vec3f_dot(vc.cam.w, up));
    assert_near(e1, e0 + 0.2, 1e-4);
    assert_true(vc.cam.eye.y > s.camera.eye.y);
    /* clamped at 89.5 degrees either way, never flipping over */
    viewcam_orbit(&vc, 0, 3.0f);
    assert_near(asin(vec3f_dot(vc.cam.w, up)), 89.5 * PI / 180, 1e-3);
    assert_consistent(&vc);
    viewcam_orbit(&vc, 0, -6.0f);
    assert_near(asin(vec3f_dot(vc.cam.w, up)), -89.5 * PI / 180, 1e-3);
    assert_consistent(&vc);
    assert_near(vec3f_length(vec3f_sub(fp(vc.cam.eye), fp(vc.pivot))), vc.dist, 1e-3);
    scene_free(&s);
}

static void test_orbit_oblique_keeps_direction(void **state)
{
    scene s;
    viewcam vc;
    vec3f dc;
    (void)state;
    load("scenes/oblique.json", 96, 72, &s);
    viewcam_init(&vc, &s);
    viewcam_orbit(&vc, 0.7f, 0.1f);
    assert_consistent(&vc);
    /* the ray direction turns with the camera: the same in camera coordinates */
    dc = vec3f_make(vec3f_dot(vc.cam.dir, vc.cam.u), vec3f_dot(vc.cam.dir, vc.cam.v),
                    vec3f_dot(vc.cam.dir, vc.cam.w));
    assert_vec_near(dc,
                    vec3f_make(vec3f_dot(s.camera.dir, s.camera.u),
                               vec3f_dot(s.camera.dir, s.camera.v),
                               vec3f_dot(s.camera.dir, s.camera.w)),
                    1e-5f);
    assert_near(vec3f_length(vc.cam.dir), 1, 1e-5);
    scene_free(&s);
}

static void test_pan(void **state)
{
    scene s;
    viewcam vc;
    vec3f eye0, piv0, d;
    float px;
    (void)state;
    load("scenes/default.json", 160, 120, &s);
    viewcam_init(&vc, &s);
    eye0 = fp(vc.cam.eye);
    piv0 = fp(vc.pivot);
    px = viewcam_pixel_size(&vc);
    /* perspective: the window's height over the image rows, scaled to the pivot's depth */
    assert_near(px, (s.camera.t - s.camera.b) / 120.0 * vc.dist / s.camera.d, 1e-6);
    viewcam_pan(&vc, 10, -4); /* pointer 10 right, 4 up: the scene follows, the eye goes
                               * left and down */
    d = vec3f_sub(fp(vc.cam.eye), eye0);
    assert_vec_near(d, add(mul(s.camera.u, -10 * px), mul(s.camera.v, -4 * px)), 1e-5f);
    assert_vec_near(vec3f_sub(fp(vc.pivot), piv0), d, 1e-5f);
    assert_vec_near(vc.cam.w, s.camera.w, 0);
    /* the old pivot now projects 10 pixels right and 4 up of the centre */
    {
        vec3f rel = vec3f_sub(piv0, fp(vc.cam.eye));
        double x = vec3f_dot(rel, vc.cam.u) / vc.dist, y = vec3f_dot(rel, vc.cam.v) / vc.dist;
        double pitch = (vc.cam.t - vc.cam.b) / 120.0 / vc.cam.d;
        assert_near(x / pitch, 10, 1e-3);
        assert_near(y / pitch, 4, 1e-3);
    }
    scene_free(&s);
}

static void test_zoom(void **state)
{
    scene s;
    viewcam vc;
    float d0;
    scene_camera c0;
    (void)state;
    load("scenes/default.json", 160, 120, &s);
    viewcam_init(&vc, &s);
    d0 = vc.dist;
    viewcam_zoom(&vc, 2);
    assert_near(vc.dist, d0 * 0.85 * 0.85, 1e-4);
    assert_consistent(&vc);
    assert_true(vc.cam.l == s.camera.l && vc.cam.t == s.camera.t); /* window unchanged */
    viewcam_zoom(&vc, -2);
    assert_vec_near(fp(vc.cam.eye), fp(s.camera.eye), 1e-4f);
    /* never through the pivot */
    viewcam_zoom(&vc, 1000);
    assert_true(vc.dist >= vc.min_dist && vc.dist > 0);
    assert_consistent(&vc);
    scene_free(&s);

    /* orthographic: the window shrinks about its centre, the eye stays */
    load("scenes/orthographic.json", 96, 72, &s);
    viewcam_init(&vc, &s);
    c0 = vc.cam;
    viewcam_zoom(&vc, 1);
    assert_near(vc.cam.t - vc.cam.b, 0.85 * (c0.t - c0.b), 1e-5);
    assert_near(vc.cam.r - vc.cam.l, 0.85 * (c0.r - c0.l), 1e-5);
    assert_near(vc.cam.l + vc.cam.r, c0.l + c0.r, 1e-5);
    assert_vec_near(fp(vc.cam.eye), fp(c0.eye), 0);
    assert_near(viewcam_pixel_size(&vc), (vc.cam.t - vc.cam.b) / 72.0, 1e-7);
    scene_free(&s);
}

static void test_fly(void **state)
{
    scene s;
    viewcam vc;
    (void)state;
    load("scenes/default.json", 160, 120, &s);
    viewcam_init(&vc, &s);
    viewcam_fly(&vc, 2, 1, 0.5f);
    assert_vec_near(fp(vc.cam.eye),
                    add(add(add(fp(s.camera.eye), mul(s.camera.w, -2)), mul(s.camera.u, 1)),
                        vec3f_make(0, 0.5f, 0)),
                    1e-5f);
    assert_consistent(&vc);
    assert_vec_near(vc.cam.w, s.camera.w, 0);
    scene_free(&s);
}

static void test_resize_and_reset(void **state)
{
    scene s, s2;
    viewcam vc;
    (void)state;
    load("scenes/default.json", 160, 120, &s);
    viewcam_init(&vc, &s);
    viewcam_set_size(&vc, 300, 100);
    assert_consistent(&vc);
    assert_true(vc.cam.t == s.camera.t && vc.cam.b == s.camera.b); /* vertical extent kept */
    assert_near(vc.cam.r, s.camera.t * 3.0, 1e-6);
    /* a fov scene at a new size is exactly what scene_finish makes for that size */
    load("scenes/default.json", 300, 100, &s2);
    assert_near(vc.cam.l, s2.camera.l, 1e-6);
    assert_near(vc.cam.r, s2.camera.r, 1e-6);
    scene_free(&s2);

    viewcam_orbit(&vc, 1, 0.3f);
    viewcam_pan(&vc, 5, 7);
    viewcam_zoom(&vc, 3);
    viewcam_fly(&vc, 1, 1, 1);
    viewcam_set_projection(&vc, SCENE_OBLIQUE);
    viewcam_reset(&vc);
    assert_int_equal(vc.width, 300);
    assert_int_equal(vc.height, 100);
    assert_int_equal(vc.cam.projection, SCENE_PERSPECTIVE);
    assert_vec_near(fp(vc.cam.eye), fp(s.camera.eye), 0);
    assert_vec_near(vc.cam.w, s.camera.w, 0);
    assert_vec_near(fp(vc.pivot), fp(vc.home_pivot), 0);
    assert_near(vc.cam.r, s.camera.t * 3.0, 1e-6);
    viewcam_set_size(&vc, 160, 120);
    viewcam_reset(&vc);
    assert_true(memcmp(&vc.cam, &vc.home, sizeof vc.cam) == 0);
    scene_free(&s);
}

static void test_projection_toggle(void **state)
{
    scene s;
    viewcam vc;
    scene_camera c0;
    float px;
    (void)state;
    assert_int_equal(viewcam_next_projection(SCENE_PERSPECTIVE), SCENE_ORTHOGRAPHIC);
    assert_int_equal(viewcam_next_projection(SCENE_ORTHOGRAPHIC), SCENE_OBLIQUE);
    assert_int_equal(viewcam_next_projection(SCENE_OBLIQUE), SCENE_PERSPECTIVE);
    load("scenes/default.json", 160, 120, &s);
    viewcam_init(&vc, &s);
    c0 = vc.cam;
    px = viewcam_pixel_size(&vc);
    /* orthographic: the same pixel size at the pivot's depth */
    viewcam_set_projection(&vc, SCENE_ORTHOGRAPHIC);
    assert_int_equal(vc.cam.projection, SCENE_ORTHOGRAPHIC);
    assert_near(viewcam_pixel_size(&vc), px, 1e-6);
    assert_near(vc.cam.t, c0.t * vc.dist / c0.d, 1e-5);
    assert_consistent(&vc);
    /* oblique: the default direction, into the view; the pivot stays at the centre */
    viewcam_set_projection(&vc, SCENE_OBLIQUE);
    assert_int_equal(vc.cam.projection, SCENE_OBLIQUE);
    assert_near(vec3f_length(vc.cam.dir), 1, 1e-6);
    assert_true(vec3f_dot(vc.cam.dir, vc.cam.w) < 0);
    {
        /* the ray through the window centre passes through the pivot */
        float cx = 0.5f * (vc.cam.l + vc.cam.r), cy = 0.5f * (vc.cam.b + vc.cam.t);
        vec3f o = add(add(fp(vc.cam.eye), mul(vc.cam.u, cx)), mul(vc.cam.v, cy));
        float t = -vc.dist / vec3f_dot(vc.cam.dir, vc.cam.w);
        assert_vec_near(add(o, mul(vc.cam.dir, t)), fp(vc.pivot), 1e-4f);
    }
    assert_near(viewcam_pixel_size(&vc), px, 1e-6);
    /* and back to perspective: the original window */
    viewcam_set_projection(&vc, SCENE_PERSPECTIVE);
    assert_near(vc.cam.l, c0.l, 1e-5);
    assert_near(vc.cam.r, c0.r, 1e-5);
    assert_near(vc.cam.b, c0.b, 1e-5);
    assert_near(vc.cam.t, c0.t, 1e-5);
    assert_near(vc.cam.d, c0.d, 0);
    scene_free(&s);

    /* an oblique scene keeps its own direction */
    load("scenes/oblique.json", 96, 72, &s);
    viewcam_init(&vc, &s);
    viewcam_set_projection(&vc, SCENE_PERSPECTIVE);
    assert_near(vc.cam.d, 1, 0);
    viewcam_set_projection(&vc, SCENE_ORTHOGRAPHIC);
    viewcam_set_projection(&vc, SCENE_OBLIQUE);
    assert_vec_near(vc.cam.dir, s.camera.dir, 1e-5f);
    assert_near(vc.cam.l, s.camera.l, 1e-4);
    assert_near(vc.cam.t, s.camera.t, 1e-4);
    scene_free(&s);
}

/* The JSON written for the test script reads back as the same camera. */
static void test_json_round_trip(void **state)
{
    static const enum scene_projection proj[3] = {SCENE_PERSPECTIVE, SCENE_ORTHOGRAPHIC,
                                                  SCENE_OBLIQUE};
    scene s, r;
    viewcam vc;
    char buf[2048];
    int i;
    (void)state;
    load("scenes/default.json", 160, 120, &s);
    viewcam_init(&vc, &s);
    viewcam_orbit(&vc, 0.4f, -0.1f);
    viewcam_set_size(&vc, 200, 100);
    for (i = 0; i < 3; i++) {
        viewcam_set_projection(&vc, proj[i]);
        assert_int_equal(viewcam_to_json(&vc, 3, buf, sizeof buf), 0);
        parse_json(buf, &r);
        assert_int_equal(r.camera.projection, proj[i]);
        assert_int_equal(r.width, 200);
        assert_int_equal(r.height, 100);
        assert_int_equal(r.max_depth, 3);
        assert_vec_near(fp(r.camera.eye), fp(vc.cam.eye), 0);
        assert_vec_near(r.camera.u, vc.cam.u, 1e-6f);
        assert_vec_near(r.camera.v, vc.cam.v, 1e-6f);
        assert_vec_near(r.camera.w, vc.cam.w, 1e-6f);
        assert_true(r.camera.l == vc.cam.l && r.camera.r == vc.cam.r && r.camera.b == vc.cam.b &&
                    r.camera.t == vc.cam.t);
        if (proj[i] == SCENE_PERSPECTIVE)
            assert_true(r.camera.d == vc.cam.d);
        if (proj[i] == SCENE_OBLIQUE)
            assert_vec_near(r.camera.dir, vc.cam.dir, 1e-6f);
        scene_free(&r);
    }
    assert_int_equal(viewcam_to_json(&vc, 3, buf, 40), -1);
    scene_free(&s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_init_default),
        cmocka_unit_test(test_world_up),
        cmocka_unit_test(test_orbit),
        cmocka_unit_test(test_orbit_oblique_keeps_direction),
        cmocka_unit_test(test_pan),
        cmocka_unit_test(test_zoom),
        cmocka_unit_test(test_fly),
        cmocka_unit_test(test_resize_and_reset),
        cmocka_unit_test(test_projection_toggle),
        cmocka_unit_test(test_json_round_trip),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
