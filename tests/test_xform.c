/* Affine transforms (host/xform.c), the JSON transform reader (host/scene_json_xform.c)
 * and the placement of meshes (host/scene_mesh.c), on the host:
 * - xform: rotations (exact quarter turns, lengths and the axis kept, det 1, a turn and
 *   its reverse), composition order and aliasing, inverses of random transforms, singular
 *   and non-finite ones refused, normals under non-uniform scales, matrices;
 * - jx_transform: steps applied in order, the same transform as a matrix and as one step;
 *   every error with its line (singular matrix, bad last row, zero axis, zero scale, a step
 *   with two keys, a composition that underflows);
 * - scene_mesh: a mesh placed once flattened into world triangles (a mirror reverses the
 *   vertex order; normals by the inverse transpose), one placed twice kept as instances,
 *   the bounds of an instance. */
#include "testutil.h"

#include <cJSON.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "scene.h"
#include "scene_io.h"
#include "scene_json_value.h"
#include "scene_json_xform.h"
#include "scene_mesh.h"
#include "xform.h"

#define PI_D 3.14159265358979323846

static double rnd(double lo, double hi)
{
    return lo + (hi - lo) * (double)(tu_rng_next() >> 11) / 9007199254740992.0;
}

/* A random transform: rotation, non-uniform scale (factors 0.2..5, signs random),
 * translation, composed. */
static void random_xform(scene_xform *x)
{
    scene_xform r, s, t;
    assert_int_equal(xform_rotate(&r, rnd(-1, 1), rnd(-1, 1), rnd(-1, 1) + 1e-3, rnd(-720, 720)),
                     0);
    xform_scale(&s, rnd(0.2, 5) * (rnd(0, 1) < 0.3 ? -1 : 1), rnd(0.2, 5), rnd(0.2, 5));
    xform_translate(&t, rnd(-100, 100), rnd(-100, 100), rnd(-100, 100));
    xform_compose(x, &r, &s);
    xform_compose(x, &t, x);
}

static double max_diff(const scene_xform *a, const scene_xform *b)
{
    double d = 0;
    for (int i = 0; i < 12; i++)
        d = fmax(d, fabs(a->m[i] - b->m[i]));
    return d;
}

static void assert_close(double got, double want, double tol, const char *what)
{
    if (!(fabs(got - want) <= tol))
        fail_msg("%s: got %.17g, want %.17g (tolerance %g)", what, got, want, tol);
}

static void assert_point(vec3d p, double x, double y, double z, double tol, const char *what)
{
    assert_close(p.x, x, tol, what);
    assert_close(p.y, y, tol, what);
    assert_close(p.z, z, tol, what);
}

/* ---- xform ---------------------------------------------------------------------------- */

static void test_rotate(void **state)
{
    scene_xform x, y, z;
    vec3d p;
    int i;
    (void)state;
    /* quarter turns are exact; right-handed: +90 about z takes x to y */
    assert_int_equal(xform_rotate(&x, 0, 0, 5, 90), 0);
    p = xform_point(&x, vec3d_make(1, 0, 0));
    assert_true(p.x == 0 && p.y == 1 && p.z == 0);
    assert_int_equal(xform_rotate(&x, 0, 1, 0, -270), 0); /* = +90 about y: z to x */
    p = xform_point(&x, vec3d_make(0, 0, 1));
    assert_true(p.x == 1 && p.y == 0 && p.z == 0);
    assert_int_equal(xform_rotate(&x, 1, 0, 0, 180), 0);
    p = xform_point(&x, vec3d_make(0, 1, 1));
    assert_true(p.x == 0 && p.y == -1 && p.z == -1);
    /* 30 degrees about y against the closed form */
    assert_int_equal(xform_rotate(&x, 0, 1, 0, 30), 0);
    p = xform_point(&x, vec3d_make(1, 0, 0));
    assert_point(p, cos(PI_D / 6), 0, -sin(PI_D / 6), 1e-15, "30 degrees about y");
    /* random axes: the axis stays, lengths stay, det 1, and the reverse turn undoes it */
    tu_rng_seed(7);
    for (i = 0; i < 1000; i++) {
        double a[3] = {rnd(-1, 1), rnd(-1, 1), rnd(-1, 1)}, deg = rnd(-1000, 1000);
        double len = sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
        vec3d q = vec3d_make(rnd(-10, 10), rnd(-10, 10), rnd(-10, 10)), r;
        if (len < 1e-3)
            continue;
        assert_int_equal(xform_rotate(&x, a[0], a[1], a[2], deg), 0);
        assert_int_equal(xform_rotate(&y, a[0], a[1], a[2], -deg), 0);
        p = xform_point(&x, vec3d_make(a[0], a[1], a[2]));
        assert_point(p, a[0], a[1], a[2], 1e-14, "the axis stays");
        r = xform_point(&x, q);
        assert_close(sqrt(r.x * r.x + r.y * r.y + r.z * r.z),
                     sqrt(q.x * q.x + q.y * q.y + q.z * q.z), 1e-13, "lengths stay");
        assert_close(xform_det(&x), 1, 1e-14, "a rotation has det 1");
        xform_compose(&z, &y, &x);
        assert_true(max_diff(&z, &(scene_xform){{1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0}}) < 1e-14);
    }
    /* a zero or non-finite axis, a non-finite angle */
    assert_int_equal(xform_rotate(&x, 0, 0, 0, 30), -1);
    assert_int_equal(xform_rotate(&x, NAN, 0, 1, 30), -1);
    assert_int_equal(xform_rotate(&x, 0, 0, 1, INFINITY), -1);
}

static void test_compose_invert(void **state)
{
    scene_xform a, b, c, ab, abc1, abc2, inv, id, tmp;
    int i;
    double worst = 0;
    (void)state;
    xform_identity(&id);
    /* a after b: translate after scale */
    xform_translate(&a, 1, 2, 3);
    xform_scale(&b, 2, 3, 4);
    xform_compose(&ab, &a, &b);
    assert_point(xform_point(&ab, vec3d_make(1, 1, 1)), 3, 5, 7, 0, "a after b");
    xform_compose(&ab, &b, &a);
    assert_point(xform_point(&ab, vec3d_make(1, 1, 1)), 4, 9, 16, 0, "b after a");
    /* aliasing: out may be a or b */
    tmp = a;
    xform_compose(&tmp, &tmp, &b);
    xform_compose(&ab, &a, &b);
    assert_memory_equal(&tmp, &ab, sizeof ab);
    tmp = b;
    xform_compose(&tmp, &a, &tmp);
    assert_memory_equal(&tmp, &ab, sizeof ab);
    assert_true(xform_is_identity(&id) && !xform_is_identity(&a));

    tu_rng_seed(11);
    for (i = 0; i < 1000; i++) {
        random_xform(&a);
        random_xform(&b);
        random_xform(&c);
        /* associativity */
        xform_compose(&abc1, &a, &b);
        xform_compose(&abc1, &abc1, &c);
        xform_compose(&abc2, &b, &c);
        xform_compose(&abc2, &a, &abc2);
        assert_true(max_diff(&abc1, &abc2) < 1e-9);
        /* the inverse, both ways; its determinant */
        assert_int_equal(xform_invert(&a, &inv), 0);
        xform_compose(&tmp, &inv, &a);
        worst = fmax(worst, max_diff(&tmp, &id));
        xform_compose(&tmp, &a, &inv);
        worst = fmax(worst, max_diff(&tmp, &id));
        assert_close(xform_det(&inv) * xform_det(&a), 1, 1e-12, "det of the inverse");
    }
    printf("  1000 random transforms: |x^-1 x - I| at most %.3g\n", worst);
    assert_true(worst < 1e-11);

    /* singular and non-finite transforms have no inverse */
    xform_scale(&a, 1, 0, 1);
    assert_int_equal(xform_invert(&a, &inv), -1);
    xform_scale(&a, 1e-200, 1e-200, 1e-200); /* the determinant underflows */
    assert_int_equal(xform_invert(&a, &inv), -1);
    xform_translate(&a, NAN, 0, 0);
    assert_int_equal(xform_invert(&a, &inv), -1);
    xform_scale(&a, -1, 1, 1);
    assert_true(xform_det(&a) < 0); /* a mirror */
}

static void test_normal_matrix(void **state)
{
    scene_xform x, y;
    vec3f n;
    double m[16] = {1, 2, 3, 4, 0, 1, 5, 6, 0, 0, 1, 7, 0, 0, 0, 1};
    int i;
    (void)state;
    /* a non-uniform scale: the normal of the plane x + y = 1 stays perpendicular to it */
    xform_scale(&x, 4, 1, 1);
    assert_int_equal(xform_normal(&x, vec3f_make(0.70710678f, 0.70710678f, 0), &n), 0);
    /* the plane's direction (1, -1, 0) becomes (4, -1, 0) */
    assert_close(n.x * 4.0 - n.y * 1.0, 0, 1e-6, "normal perpendicular to the surface");
    assert_close(sqrt(n.x * n.x + n.y * n.y + n.z * n.z), 1, 1e-6, "unit normal");
    tu_rng_seed(5);
    for (i = 0; i < 1000; i++) {
        double t[3] = {rnd(-1, 1), rnd(-1, 1), rnd(-1, 1)}, tt[3], nn[3];
        vec3f n0;
        random_xform(&x);
        /* a normal perpendicular to t, transformed, stays perpendicular to x's t */
        nn[0] = t[1];
        nn[1] = -t[0];
        nn[2] = 0;
        n0 = vec3f_make((float)nn[0], (float)nn[1], (float)nn[2]);
        if (fabs(nn[0]) + fabs(nn[1]) < 1e-3)
            continue;
        assert_int_equal(xform_normal(&x, n0, &n), 0);
        xform_vector(&x, t, tt);
        assert_close((n.x * tt[0] + n.y * tt[1] + n.z * tt[2]) /
                         sqrt(tt[0] * tt[0] + tt[1] * tt[1] + tt[2] * tt[2]),
                     0, 1e-5, "normals stay perpendicular");
    }
    xform_scale(&x, 1, 1, 0);
    assert_int_equal(xform_normal(&x, vec3f_make(0, 0, 1), &n), -1);
    /* matrices: copied as given; a last row other than 0 0 0 1 refused */
    assert_int_equal(xform_from_matrix(&x, m), 0);
    assert_point(xform_point(&x, vec3d_make(1, 1, 1)), 10, 12, 8, 0, "matrix");
    m[14] = 1e-9;
    assert_int_equal(xform_from_matrix(&y, m), -1);
    m[14] = 0;
    m[15] = 2;
    assert_int_equal(xform_from_matrix(&y, m), -1);
}

/* ---- jx_transform --------------------------------------------------------------------- */

/* Reads {"transform": ...} from text; returns jx_transform's result, err its message. */
static int read_json_xform(const char *text, scene_xform *x, char *err, size_t errlen)
{
    scene_msg msg;
    jv_doc doc;
    cJSON *root = cJSON_ParseWithLength(text, strlen(text) + 1);
    int rc;
    if (!root)
        fail_msg("test JSON does not parse: %s", text);
    msg.name = "t.json";
    msg.err = err;
    msg.errlen = errlen;
    doc.text = text;
    doc.len = strlen(text);
    doc.root = root;
    doc.msg = &msg;
    err[0] = '\0';
    rc = jx_transform(&doc, cJSON_GetObjectItemCaseSensitive(root, "transform"), "transform", x);
    cJSON_Delete(root);
    return rc;
}

static void xform_ok(const char *text, scene_xform *x)
{
    char err[512];
    if (read_json_xform(text, x, err, sizeof err) != 0)
        fail_msg("%s: %s", text, err);
}

/* Fails unless text is refused with a message starting with prefix and holding want. */
static void xform_bad(const char *text, const char *prefix, const char *want)
{
    char err[512];
    scene_xform x;
    if (read_json_xform(text, &x, err, sizeof err) == 0)
        fail_msg("accepted: %s", text);
    if (strncmp(err, prefix, strlen(prefix)) != 0 || !strstr(err, want))
        fail_msg("message \"%s\": want \"%s...%s\"", err, prefix, want);
    printf("  %s\n", err);
}

static void test_json_xform(void **state)
{
    scene_xform x, y, z;
    vec3d p;
    (void)state;
    /* scale 2, then 90 degrees about y (x to -z), then translate: (1, 0, 0) -> (2, 0, 0)
     * -> (0, 0, -2) -> (1, 0, 0) */
    xform_ok("{\"transform\": [{\"scale\": 2}, {\"rotate\": {\"axis\": [0, 1, 0], \"degrees\": "
             "90}},\n {\"translate\": [1, 0, 2]}]}",
             &x);
    p = xform_point(&x, vec3d_make(1, 0, 0));
    assert_point(p, 1, 0, 0, 0, "steps in order");
    p = xform_point(&x, vec3d_make(0, 1, 0));
    assert_point(p, 1, 2, 2, 0, "steps in order");
    /* the same as a matrix, and as one step */
    xform_ok("{\"transform\": {\"matrix\": [[0, 0, 2, 1], [0, 2, 0, 0], [-2, 0, 0, 2], "
             "[0, 0, 0, 1]]}}",
             &y);
    assert_memory_equal(&x, &y, sizeof x);
    xform_ok("{\"transform\": [{\"matrix\": [[0, 0, 2, 1], [0, 2, 0, 0], [-2, 0, 0, 2], "
             "[0, 0, 0, 1]]}]}",
             &z);
    assert_memory_equal(&x, &z, sizeof x);
    /* non-uniform scale; an empty list is the identity */
    xform_ok("{\"transform\": {\"scale\": [1, -2, 3]}}", &x);
    assert_point(xform_point(&x, vec3d_make(1, 1, 1)), 1, -2, 3, 0, "scale");
    xform_ok("{\"transform\": []}", &x);
    assert_true(xform_is_identity(&x));

    xform_bad("{\n\"transform\": {\"matrix\": [[1, 2, 3, 0],\n [2, 4, 6, 0],\n [0, 0, 1, 0], "
              "[0, 0, 0, 1]]}}",
              "t.json:2: ", "transform.matrix: the matrix is singular");
    xform_bad("{\"transform\": {\"matrix\": [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0],\n"
              "[0, 0, 1, 1]]}}",
              "t.json:2: ", "transform.matrix[3]: the last row must be [0, 0, 0, 1]");
    xform_bad("{\"transform\": {\"matrix\": [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0]]}}",
              "t.json:1: ", "expected 4 rows of 4 numbers, found 3 rows");
    xform_bad("{\"transform\": {\"matrix\": [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1],\n"
              "[0, 0, 0, 1]]}}",
              "t.json:1: ", "transform.matrix[2]: expected");
    xform_bad("{\"transform\": [{\"scale\": 2},\n {\"rotate\": {\"axis\":\n [0, 0, 0], "
              "\"degrees\": 30}}]}",
              "t.json:2: ", "transform[1].rotate.axis: the axis is zero"); /* the key's line */
    xform_bad("{\"transform\": [{\"rotate\": {\"axis\": [0, 0, 1]}}]}",
              "t.json:1: ", "transform[0].rotate: missing \"degrees\"");
    xform_bad("{\"transform\": [{\"translate\": [1, 0, 0]},\n{\"scale\": [1, 0, 1]}]}",
              "t.json:2: ", "transform[1].scale: a scale factor of zero");
    xform_bad("{\"transform\": [{\"translate\": [1, 0, 0],\n \"scale\": 2}]}",
              "t.json:1: ", "transform[0]: a step has exactly one of");
    xform_bad("{\"transform\": [{\"shear\": 2}]}", "t.json:1: ", "transform[0]");
    xform_bad("{\"transform\": [{}]}", "t.json:1: ", "found 0 keys");
    xform_bad("{\"transform\": 3}", "t.json:1: ", "transform: expected an array of steps");
    xform_bad("{\"transform\": [{\"translate\": [1, 0, \"2\"]}]}",
              "t.json:1: ", "transform[0].translate[2]");
    /* each step invertible, the composition not: the determinant underflows */
    xform_bad("{\"transform\": [{\"scale\": 1e-18}, {\"scale\": 1e-18}, {\"scale\": 1e-18},\n"
              "{\"scale\": 1e-18}, {\"scale\": 1e-18}, {\"scale\": 1e-18}]}",
              "t.json:1: ", "compose into a transform that is not invertible");
}

/* ---- scene_mesh ----------------------------------------------------------------------- */

/* A mesh of one smooth triangle (normals (0, 0, 1)) and one flat one; returns its index. */
static int add_mesh(scene *s)
{
    scene_mesh m;
    vec3d p[3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
    vec3f n[3] = {{0, 0, 1}, {0, 0, 1}, {0, 0, 1}};
    m.first = s->mesh_tris.count;
    m.source = NULL;
    assert_true(scene_push_mesh_triangle(s, p, n, 0) >= 0);
    p[2] = vec3d_make(0, 0, 1);
    assert_true(scene_push_mesh_triangle(s, p, NULL, 0) >= 0);
    m.count = 2;
    return (int)scene_push(&s->meshes, &m, sizeof m);
}

static void test_mesh_placement(void **state)
{
    scene s;
    scene_xform x, mirror;
    scene_material mat;
    char err[256];
    double lo[3], hi[3];
    const scene_triangle *t;
    const vec3f *n;
    int m0, m1;
    (void)state;
    scene_init(&s);
    memset(&mat, 0, sizeof mat);
    assert_true(scene_push(&s.materials, &mat, sizeof mat) >= 0);
    assert_true(scene_push(&s.materials, &mat, sizeof mat) >= 0);
    m0 = add_mesh(&s);
    m1 = add_mesh(&s);
    /* m0 once: mirrored in x, then moved by (10, 0, 0), with material 1 */
    xform_scale(&mirror, -1, 1, 1);
    xform_translate(&x, 10, 0, 0);
    xform_compose(&x, &x, &mirror);
    assert_true(scene_place_mesh(&s, m0, &x, 1) >= 0);
    /* m1 twice */
    assert_true(scene_place_mesh(&s, m1, NULL, -1) >= 0);
    xform_scale(&x, 2, 2, 2);
    assert_true(scene_place_mesh(&s, m1, &x, -1) >= 0);
    assert_int_equal(scene_instance_bounds(&s, 2, lo, hi), 0);
    assert_true(lo[0] == 0 && lo[1] == 0 && lo[2] == 0 && hi[0] == 2 && hi[1] == 2 && hi[2] == 2);
    assert_int_equal(scene_instance_bounds(&s, 0, lo, hi), 0);
    assert_true(lo[0] == 9 && hi[0] == 10);

    /* only the mesh placed once is flattened */
    assert_int_equal(scene_flatten_instances(&s, 0, err, sizeof err), 0);
    assert_int_equal(s.instances.count, 2);
    assert_int_equal(SCENE_AT(s.instances, scene_instance, 0).mesh, m1);
    assert_int_equal(s.triangles.count, 2);
    /* the mirror reverses the vertex order: (0,1,0), (1,0,0), (0,0,0) mirrored and moved */
    t = &SCENE_AT(s.triangles, scene_triangle, 0);
    assert_point(t->p[0], 10, 1, 0, 0, "mirrored");
    assert_point(t->p[1], 9, 0, 0, 0, "mirrored");
    assert_point(t->p[2], 10, 0, 0, 0, "mirrored");
    assert_int_equal(t->material, 1);
    n = scene_triangle_normals(&s, t);
    assert_non_null(n);
    assert_true(n[0].x == 0 && n[0].y == 0 && n[0].z == 1);
    assert_null(scene_triangle_normals(&s, &SCENE_AT(s.triangles, scene_triangle, 1)));
    /* then all */
    assert_int_equal(scene_flatten_instances(&s, 1, err, sizeof err), 0);
    assert_int_equal(s.instances.count, 0);
    assert_int_equal(s.triangles.count, 6);
    assert_point(SCENE_AT(s.triangles, scene_triangle, 5).p[2], 0, 0, 2, 0, "scaled by 2");
    scene_free(&s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_rotate),         cmocka_unit_test(test_compose_invert),
        cmocka_unit_test(test_normal_matrix),  cmocka_unit_test(test_json_xform),
        cmocka_unit_test(test_mesh_placement),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
