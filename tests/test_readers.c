/* Tests for the scene readers: host/scene_nff.c (NFF, the SPD scenes) and host/scene_json.c
 * (the native JSON format). Good input is checked value by value; every class of bad input
 * must fail with "name:line: message". Runs from the repository root. */
#include "testutil.h"

#include "config.h"
#include "scene.h"
#include "scene_geom.h"
#include "scene_json.h"
#include "scene_load.h"
#include "scene_nff.h"
#include "sys.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <unistd.h>

#define EPS 1e-5f

static void assert_vec(vec3f a, float x, float y, float z)
{
    if (fabsf(a.x - x) > EPS || fabsf(a.y - y) > EPS || fabsf(a.z - z) > EPS)
        fail_msg("vector (%g, %g, %g), expected (%g, %g, %g)", a.x, a.y, a.z, x, y, z);
}

/* A position (double), as stored. */
static void assert_pos(vec3d a, double x, double y, double z)
{
    if (fabs(a.x - x) > EPS || fabs(a.y - y) > EPS || fabs(a.z - z) > EPS)
        fail_msg("position (%g, %g, %g), expected (%g, %g, %g)", a.x, a.y, a.z, x, y, z);
}

static void assert_near(float a, float b)
{
    if (fabsf(a - b) > EPS * (1.0f + fabsf(b)))
        fail_msg("value %.8g, expected %.8g", a, b);
}

typedef int (*parse_fn)(const char *, size_t, const char *, scene *, char *, size_t);

static void parse_ok(parse_fn fn, const char *text, const char *name, scene *s)
{
    char err[512] = "";
    scene_init(s);
    if (fn(text, strlen(text), name, s, err, sizeof err) != 0)
        fail_msg("%s: parse failed: %s", name, err);
}

/* Parsing must fail with a message starting with `prefix` ("name:line: ") and holding
 * every key word given (up to three, NULL for none). */
static void parse_bad(parse_fn fn, const char *name, const char *text, const char *prefix,
                      const char *k1, const char *k2, const char *k3)
{
    char err[512] = "";
    scene s;
    int rc;
    scene_init(&s);
    rc = fn(text, strlen(text), name, &s, err, sizeof err);
    scene_free(&s);
    if (rc != -1)
        fail_msg("expected failure with \"%s...\", but parsing succeeded on:\n%s", prefix, text);
    if (strncmp(err, prefix, strlen(prefix)) != 0 || (k1 && !strstr(err, k1)) ||
        (k2 && !strstr(err, k2)) || (k3 && !strstr(err, k3)))
        fail_msg("message \"%s\"\nexpected prefix \"%s\" and words \"%s\" \"%s\" \"%s\"", err,
                 prefix, k1 ? k1 : "", k2 ? k2 : "", k3 ? k3 : "");
}

static void nff_bad(const char *text, const char *prefix, const char *k1, const char *k2,
                    const char *k3)
{
    parse_bad(nff_parse, "x.nff", text, prefix, k1, k2, k3);
}

static void json_bad(const char *text, const char *prefix, const char *k1, const char *k2,
                     const char *k3)
{
    parse_bad(json_scene_parse, "x.json", text, prefix, k1, k2, k3);
}

/* ======================================================================================== */
/* NFF: good input                                                                          */

/* A viewpoint block: 7 lines, so that entities after it start at line 8. */
#define VIEW "v\nfrom 0 0 5\nat 0 0 0\nup 0 1 0\nangle 90\nhither 1\nresolution 3 3\n"

static const char *const nff_all =
    "# every NFF entity\n"                                       /* 1 */
    "b 0.1 0.2 0.3   # background\n"                             /* 2 */
    "v\n"                                                        /* 3 */
    "from 0 0 5\n"                                               /* 4 */
    "at 0 0 0  # look at the origin\n"                           /* 5 */
    "up 0 1 0\n"                                                 /* 6 */
    "angle 90\n"                                                 /* 7 */
    "hither 0.5\n"                                               /* 8 */
    "resolution 3 3\n"                                           /* 9 */
    "\n"                                                         /* 10 */
    "l 1 2 3\n"                                                  /* 11: no colour */
    "l 4 5 6 0.5 0.25 1#coloured\n"                              /* 12 */
    "s 0 0 -1 0.5\n"                                             /* 13: default material */
    "f 1 0.5 0.25 0.8 0.3 20 0.1 1.5\n"                          /* 14 */
    "s 1 2 3 -2\n"                                               /* 15: negative radius kept */
    "p 3\n0 0 0\n1 0 0\n0 1 0\n"                                 /* 16-19: triangle */
    "p 5\n0 0 0\n2 0 0\n2 1 0\n1 2 0\n0 1 0\n"                   /* 20-25: polygon */
    "pp 3\n0 0 0 0 0 2\n1 0 0 0 0 1\n0 1 0 1 0 0\n"              /* 26-29: smooth triangle */
    "pp 4\n0 0 1 0 0 1\n1 0 1 0 0 1\n1 1 1 0 0 1\n0 1 1 0 0 1\n" /* 30-34: fan */
    "\t# a comment line\n"
    "c\n0 0 0 1\n0 0 2 0.5\n" /* two-line cone */
    "c 1 1 1 0.25 1 1 3 0\n"; /* SPD one-line cone */

static void test_nff_entities(void **state)
{
    scene s;
    const scene_material *m;
    const scene_triangle *t;
    const scene_polygon *pg;
    const scene_cone *c;
    const float g = 0.35355339f; /* sqrt(2)/(2*2): two lights */
    (void)state;
    parse_ok(nff_parse, nff_all, "some/dir/all.nff", &s);

    assert_string_equal(s.name, "all");
    assert_vec(s.background, 0.1f, 0.2f, 0.3f);
    assert_int_equal(s.width, 3);
    assert_int_equal(s.height, 3);
    assert_int_equal(s.max_depth, CW_DEFAULT_DEPTH);

    /* lights: the colourless one gets sqrt(L)/(2L), the coloured one keeps its colour */
    assert_int_equal(s.lights.count, 2);
    assert_pos(SCENE_AT(s.lights, scene_light, 0).position, 1, 2, 3);
    assert_vec(SCENE_AT(s.lights, scene_light, 0).intensity, g, g, g);
    assert_pos(SCENE_AT(s.lights, scene_light, 1).position, 4, 5, 6);
    assert_vec(SCENE_AT(s.lights, scene_light, 1).intensity, 0.5f, 0.25f, 1);
    assert_vec(s.ambient, g, g, g);

    /* materials: the default one, then the `f` */
    assert_int_equal(s.materials.count, 2);
    m = &SCENE_AT(s.materials, scene_material, 0);
    assert_vec(m->kd, 1, 1, 1);
    assert_vec(m->ka, 1, 1, 1);
    assert_vec(m->ks, 0, 0, 0);
    assert_vec(m->km, 0, 0, 0);
    assert_vec(m->kt, 0, 0, 0);
    assert_near(m->p, 1);
    assert_near(m->ior, 1);
    m = &SCENE_AT(s.materials, scene_material, 1);
    assert_vec(m->kd, 0.8f, 0.4f, 0.2f); /* Kd * colour */
    assert_vec(m->ka, 0.8f, 0.4f, 0.2f);
    assert_vec(m->ks, 0.3f, 0.3f, 0.3f);
    assert_vec(m->km, 0.3f, 0.3f, 0.3f);
    assert_near(m->p, 20);
    assert_vec(m->kt, 0.1f, 0.1f, 0.1f);
    assert_near(m->ior, 1.5f);

    assert_int_equal(s.spheres.count, 2);
    assert_pos(SCENE_AT(s.spheres, scene_sphere, 0).center, 0, 0, -1);
    assert_near(SCENE_AT(s.spheres, scene_sphere, 0).radius, 0.5f);
    assert_int_equal(SCENE_AT(s.spheres, scene_sphere, 0).material, 0);
    assert_pos(SCENE_AT(s.spheres, scene_sphere, 1).center, 1, 2, 3);
    assert_near(SCENE_AT(s.spheres, scene_sphere, 1).radius, -2);
    assert_int_equal(SCENE_AT(s.spheres, scene_sphere, 1).material, 1);

    /* p 3 -> flat triangle; pp 3 -> smooth; pp 4 -> two fan triangles */
    assert_int_equal(s.triangles.count, 4);
    t = &SCENE_AT(s.triangles, scene_triangle, 0);
    assert_null(scene_triangle_normals(&s, t));
    assert_int_equal(t->material, 1);
    assert_pos(t->p[0], 0, 0, 0);
    assert_pos(t->p[1], 1, 0, 0);
    assert_pos(t->p[2], 0, 1, 0);
    t = &SCENE_AT(s.triangles, scene_triangle, 1);
    assert_non_null(scene_triangle_normals(&s, t));
    assert_pos(t->p[2], 0, 1, 0);
    assert_vec(scene_triangle_normals(&s, t)[0], 0, 0, 1); /* normalised from (0 0 2) */
    assert_vec(scene_triangle_normals(&s, t)[1], 0, 0, 1);
    assert_vec(scene_triangle_normals(&s, t)[2], 1, 0, 0);
    t = &SCENE_AT(s.triangles, scene_triangle, 2);
    assert_non_null(scene_triangle_normals(&s, t));
    assert_pos(t->p[0], 0, 0, 1);
    assert_pos(t->p[1], 1, 0, 1);
    assert_pos(t->p[2], 1, 1, 1);
    t = &SCENE_AT(s.triangles, scene_triangle, 3);
    assert_pos(t->p[0], 0, 0, 1); /* (v0, v2, v3) */
    assert_pos(t->p[1], 1, 1, 1);
    assert_pos(t->p[2], 0, 1, 1);
    assert_vec(scene_triangle_normals(&s, t)[2], 0, 0, 1);

    /* p 5 -> polygon */
    assert_int_equal(s.polygons.count, 1);
    pg = &SCENE_AT(s.polygons, scene_polygon, 0);
    assert_int_equal(pg->first, 0);
    assert_int_equal(pg->count, 5);
    assert_int_equal(pg->material, 1);
    assert_int_equal(s.poly_verts.count, 5);
    assert_pos(SCENE_AT(s.poly_verts, vec3d, 3), 1, 2, 0);

    /* cones, in both layouts */
    assert_int_equal(s.cones.count, 2);
    c = &SCENE_AT(s.cones, scene_cone, 0);
    assert_pos(c->base, 0, 0, 0);
    assert_near(c->base_radius, 1);
    assert_pos(c->apex, 0, 0, 2);
    assert_near(c->apex_radius, 0.5f);
    c = &SCENE_AT(s.cones, scene_cone, 1);
    assert_pos(c->base, 1, 1, 1);
    assert_near(c->base_radius, 0.25f);
    assert_pos(c->apex, 1, 1, 3);
    assert_near(c->apex_radius, 0);
    assert_int_equal(c->material, 1);
    scene_free(&s);
}

static void test_nff_camera(void **state)
{
    scene s;
    char err[256];
    const scene_camera *c = &s.camera;
    (void)state;
    parse_ok(nff_parse, VIEW, "cam.nff", &s);
    assert_int_equal(c->projection, SCENE_PERSPECTIVE);
    assert_pos(c->eye, 0, 0, 5);
    assert_vec(c->w, 0, 0, 1);
    assert_vec(c->u, 1, 0, 0);
    assert_vec(c->v, 0, 1, 0);
    assert_near(c->nff_angle_deg, 90);
    assert_near(c->d, 1);
    /* no lights: ambient 0.5 */
    assert_vec(s.ambient, 0.5f, 0.5f, 0.5f);
    assert_vec(s.background, 0, 0, 0);
    /* angle 90 over 3 pixel centres: pitch 2 tan(45)/2 = 1, so the window is +-1.5 */
    assert_int_equal(scene_finish(&s, 0, 0, 0, err, sizeof err), 0);
    assert_near(c->r, 1.5f);
    assert_near(c->l, -1.5f);
    assert_near(c->t, 1.5f);
    assert_near(c->b, -1.5f);
    scene_free(&s);

    /* a skewed up vector and an oblique view still give an orthonormal basis */
    parse_ok(nff_parse, "v\nresolution 4 2\nfrom 1 1 1\nup 0 0.5 3\nat 0 0 0\nhither 0\nangle 45\n",
             "cam2.nff", &s);
    assert_near(vec3f_length(c->w), 1);
    assert_near(vec3f_dot(c->u, c->v), 0);
    assert_near(c->w.x, 0.57735027f);
    assert_int_equal(s.width, 4);
    assert_int_equal(s.height, 2);
    assert_int_equal(scene_finish(&s, 0, 0, 0, err, sizeof err), 0);
    scene_free(&s);
}

static void test_nff_lights(void **state)
{
    scene s;
    const float g = 0.35355339f;
    (void)state;
    parse_ok(nff_parse, VIEW "l 0 0 9\nl 1 1 1\n", "l.nff", &s);
    assert_vec(SCENE_AT(s.lights, scene_light, 0).intensity, g, g, g);
    assert_vec(SCENE_AT(s.lights, scene_light, 1).intensity, g, g, g);
    assert_vec(s.ambient, g, g, g);
    scene_free(&s);
    /* three lights, one coloured: sqrt(3)/6 for the others and the ambient */
    parse_ok(nff_parse, "l 0 0 9\n" VIEW "l 1 1 1 2 2 2\nl 3 3 3\n", "l3.nff", &s);
    assert_vec(SCENE_AT(s.lights, scene_light, 0).intensity, 0.28867513f, 0.28867513f, 0.28867513f);
    assert_vec(SCENE_AT(s.lights, scene_light, 1).intensity, 2, 2, 2);
    assert_vec(s.ambient, 0.28867513f, 0.28867513f, 0.28867513f);
    scene_free(&s);
}

static void test_nff_whitespace(void **state)
{
    scene s;
    (void)state;
    /* CRLF line ends, tabs, a comment glued to a number, no newline at the end */
    parse_ok(nff_parse,
             "v\r\nfrom 0 0 5\r\nat\t0 0 0\r\nup 0 1 0\r\nangle 90\r\nhither 1\r\n"
             "resolution 3 3\r\ns 0 0 0 1#c\r\n#\r\n\r\ns 1 1 1 +1e-1",
             "crlf.nff", &s);
    assert_int_equal(s.spheres.count, 2);
    assert_near(SCENE_AT(s.spheres, scene_sphere, 1).radius, 0.1f);
    scene_free(&s);
}

static void test_nff_load_files(void **state)
{
    scene s;
    char err[512];
    (void)state;
    scene_init(&s);
    assert_int_equal(nff_load("tests/no/such/file.nff", &s, err, sizeof err), -1);
    assert_non_null(strstr(err, "tests/no/such/file.nff: "));
    assert_non_null(strstr(err, "No such file"));
    scene_free(&s);
    scene_init(&s);
    assert_int_equal(nff_load("tests", &s, err, sizeof err), -1);
    assert_non_null(strstr(err, "tests: "));
    assert_non_null(strstr(err, "directory"));
    scene_free(&s);
    scene_init(&s);
    assert_int_equal(json_scene_load("tests", &s, err, sizeof err), -1);
    assert_non_null(strstr(err, "directory"));
    scene_free(&s);
    scene_init(&s);
    assert_int_equal(json_scene_load("tests/none.json", &s, err, sizeof err), -1);
    assert_non_null(strstr(err, "No such file"));
    scene_free(&s);
}

/* ---- the SPD scenes ---- */

static void load_and_finish(const char *path, scene *s, double *secs)
{
    char err[512];
    double t0;
    scene_init(s);
    t0 = sys_now();
    if (scene_load(path, s, err, sizeof err) != 0)
        fail_msg("%s", err);
    *secs = sys_now() - t0;
    if (scene_finish(s, 0, 0, 0, err, sizeof err) != 0)
        fail_msg("%s", err);
}

static void test_spd_tetra(void **state)
{
    scene s;
    double secs;
    (void)state;
    load_and_finish("scenes/spd/tetra.nff", &s, &secs);
    assert_string_equal(s.name, "tetra");
    assert_int_equal(s.triangles.count, 4096);
    assert_int_equal(s.lights.count, 1);
    assert_int_equal(s.materials.count, 1);
    assert_int_equal(s.spheres.count + s.polygons.count + s.cones.count, 0);
    assert_int_equal(s.width, 512);
    assert_int_equal(s.height, 512);
    assert_vec(s.background, 0.078f, 0.361f, 0.753f);
    assert_vec(SCENE_AT(s.lights, scene_light, 0).intensity, 0.5f, 0.5f, 0.5f);
    assert_vec(s.ambient, 0.5f, 0.5f, 0.5f);
    assert_near(s.camera.nff_angle_deg, 45);
    /* f 1 0.2 0.2 1 0 100000 0 0 */
    assert_vec(SCENE_AT(s.materials, scene_material, 0).kd, 1, 0.2f, 0.2f);
    assert_near(SCENE_AT(s.materials, scene_material, 0).p, 100000);
    assert_near(SCENE_AT(s.materials, scene_material, 0).ior, 0);
    scene_free(&s);
}

static void test_spd_all(void **state)
{
    /* name, spheres, triangles, polygons, cones, lights: as in the files */
    static const struct {
        const char *name;
        size_t sph, tri, poly, cone, light;
    } spd[] = {
        {"balls", 7381, 0, 1, 0, 3},    {"gears", 0, 0, 9345, 0, 5},   {"mount", 4, 8192, 0, 0, 1},
        {"rings", 4200, 0, 1, 4200, 3}, {"teapot", 0, 2256, 36, 0, 2}, {"tetra", 0, 4096, 0, 0, 1},
        {"tree", 4095, 0, 1, 4095, 7},
    };
    size_t i;
    int found = 0;
    (void)state;
    for (i = 0; i < sizeof spd / sizeof spd[0]; i++) {
        char path[256];
        struct stat st;
        scene s;
        double secs;
        snprintf(path, sizeof path, "../shared/scenes/spd/%s.nff", spd[i].name);
        if (stat(path, &st) != 0)
            continue;
        found++;
        load_and_finish(path, &s, &secs);
        print_message("%-7s %6.1f ms: %zu spheres, %zu triangles, %zu polygons (%zu vertices), "
                      "%zu cones, %zu lights, %zu materials\n",
                      spd[i].name, secs * 1e3, s.spheres.count, s.triangles.count, s.polygons.count,
                      s.poly_verts.count, s.cones.count, s.lights.count, s.materials.count);
        assert_int_equal(s.spheres.count, spd[i].sph);
        assert_int_equal(s.triangles.count, spd[i].tri);
        assert_int_equal(s.polygons.count, spd[i].poly);
        assert_int_equal(s.cones.count, spd[i].cone);
        assert_int_equal(s.lights.count, spd[i].light);
        scene_free(&s);
    }
    if (!found)
        print_message("../shared/scenes/spd not present: only tetra was checked\n");
}

/* ======================================================================================== */
/* NFF: bad input, one test per class                                                       */

/* Text with a NUL byte in it: not a text file. */
static void test_nul_byte(void **state)
{
    static const char nff[] = VIEW "s 0\0 0 0 1\n";
    static const char json[] = "{\n\"ambient\": [1, 2,\0 3]}\n";
    char err[256];
    scene s;
    (void)state;
    scene_init(&s);
    assert_int_equal(nff_parse(nff, sizeof nff - 1, "x.nff", &s, err, sizeof err), -1);
    assert_non_null(strstr(err, "x.nff:8: "));
    assert_non_null(strstr(err, "NUL byte"));
    scene_free(&s);
    scene_init(&s);
    assert_int_equal(json_scene_parse(json, sizeof json - 1, "x.json", &s, err, sizeof err), -1);
    assert_non_null(strstr(err, "x.json:2: "));
    assert_non_null(strstr(err, "NUL byte"));
    scene_free(&s);
}

static void test_nff_bad_entity(void **state)
{
    (void)state;
    nff_bad(VIEW "q 1 2 3\n", "x.nff:8: ", "unknown entity 'q'", "v b l f s p pp c #", NULL);
    nff_bad("# c\nfrom 0 0 0\n", "x.nff:2: ", "unknown entity 'from'", "inside a 'v' block", NULL);
    nff_bad("", "x.nff:1: ", "empty file", NULL, NULL);
    nff_bad("# only a comment\n\n", "x.nff:2: ", "empty file", NULL, NULL);
    nff_bad("s 0 0 0 1\n", "x.nff:1: ", "no 'v' viewpoint block", NULL, NULL);
    nff_bad("b 0 0 0\n\n# end\n", "x.nff:3: ", "no 'v' viewpoint block", NULL, NULL);
    nff_bad(VIEW "s 0 0 0 1\n" VIEW, "x.nff:9: ", "second 'v'", "line 1", NULL);
}

static void test_nff_bad_counts(void **state)
{
    (void)state;
    nff_bad(VIEW "l 1 2\n",
            "x.nff:8: ", "expected 3 numbers after 'l' (x y z) or 6 (x y z r g b), found 2", NULL,
            NULL);
    nff_bad(VIEW "l 1 2 3 4\n", "x.nff:8: ", "found 4", NULL, NULL);
    nff_bad(VIEW "s 0 0 0 1 2\n", "x.nff:8: ", "expected 4 numbers", "after 's'", "found 5");
    nff_bad(VIEW "b 0 0\n", "x.nff:8: ", "expected 3 numbers", "after 'b'", "found 2");
    nff_bad(VIEW "f 1 1 1 1 0 1 0\n", "x.nff:8: ", "expected 8 numbers", "after 'f'", "found 7");
    nff_bad(VIEW "p 3\n0 0 0\n1 0 0 7\n0 1 0\n", "x.nff:10: ", "expected 3 numbers",
            "vertex 2 of 'p 3' (line 8)", "found 4");
    nff_bad(VIEW "pp 3\n0 0 0 0 0 1\n1 0 0\n", "x.nff:10: ", "expected 6 numbers",
            "vertex 2 of 'pp 3'", "found 3");
    nff_bad(VIEW "c 0 0 0 1 0 0 1\n", "x.nff:8: ", "8 numbers", "found 7", NULL);
    nff_bad(VIEW "c\n0 0 0 1\n0 0 1\n", "x.nff:10: ", "expected 4 numbers", "apex of 'c'",
            "found 3");
    nff_bad("v extra\n", "x.nff:1: ", "expected nothing after 'v'", NULL, NULL);
    nff_bad("v\nfrom 0 0\n", "x.nff:2: ", "expected 3 numbers", "after 'from'", "found 2");
    nff_bad("v\nresolution 3 3 3\n", "x.nff:2: ", "after 'resolution'", "found 3", NULL);
    nff_bad(VIEW "p 3 4\n", "x.nff:8: ", "vertex count after 'p'", NULL, NULL);
}

static void test_nff_bad_numbers(void **state)
{
    (void)state;
    nff_bad(VIEW "s 0 0 abc 1\n", "x.nff:8: ", "expected a number after 's'", "'abc'", NULL);
    nff_bad(VIEW "s 0 0 1x 1\n", "x.nff:8: ", "expected a number", "'1x'", NULL);
    nff_bad(VIEW "s 0 0 nan 1\n", "x.nff:8: ", "'nan'", "not finite", NULL);
    nff_bad(VIEW "l 0 0 1 inf 1 1\n", "x.nff:8: ", "'inf'", "not finite", NULL);
    nff_bad(VIEW "s 0 0 1e999 1\n", "x.nff:8: ", "'1e999'", "not finite", NULL);
    nff_bad(VIEW "s 0 0 -2e30 1\n", "x.nff:8: ", "'-2e30'", "out of range", "1e18");
    nff_bad(VIEW "s 0 0 -2e18 1\n", "x.nff:8: ", "'-2e18'", "out of range", "1e18");
    nff_bad(VIEW "p 3\n0 0 0\n1 zero 0\n", "x.nff:10: ", "expected a number", "vertex 2 of 'p 3'",
            "'zero'");
    nff_bad("v\nangle wide\n", "x.nff:2: ", "expected a number after 'angle'", NULL, NULL);
    nff_bad("v\nhither near\n", "x.nff:2: ", "after 'hither'", "'near'", NULL);
}

static void test_nff_bad_polygons(void **state)
{
    (void)state;
    nff_bad(VIEW "p 5\n0 0 0\n1 0 0\n", "x.nff:10: ", "file ended inside 'p 5'",
            "expected 5 vertex lines, found 2", NULL);
    nff_bad(VIEW "pp 3\n", "x.nff:8: ", "file ended inside 'pp 3'", "found 0", NULL);
    nff_bad(VIEW "p 2\n0 0 0\n1 1 1\n", "x.nff:8: ", "at least 3", NULL, NULL);
    nff_bad(VIEW "p 0\n", "x.nff:8: ", "at least 3", NULL, NULL);
    nff_bad(VIEW "p -4\n", "x.nff:8: ", "at least 3", NULL, NULL);
    nff_bad(VIEW "p 20000000\n", "x.nff:8: ", "10000000", NULL, NULL);
    nff_bad(VIEW "p 3.5\n", "x.nff:8: ", "integer", NULL, NULL);
    nff_bad(VIEW "p\n", "x.nff:8: ", "vertex count after 'p'", "found 0", NULL);
    /* a polygon one line short runs into the next entity */
    nff_bad(VIEW "p 4\n0 0 0\n1 0 0\n1 1 0\ns 0 0 0 1\n", "x.nff:12: ", "expected a number",
            "vertex 4 of 'p 4' (line 8)", "found 's'");
    nff_bad(VIEW "pp 3\n0 0 0 0 0 1\n1 0 0 0 0 0\n0 1 0 0 0 1\n", "x.nff:10: ", "zero normal",
            "vertex 2 of 'pp 3'", NULL);
    nff_bad(VIEW "c\n0 0 0 1\n", "x.nff:9: ", "file ended inside 'c'", "found 1", NULL);
    nff_bad(VIEW "c 1 1 1 1 1 1 1 2\n", "x.nff:8: ", "base and apex coincide", NULL, NULL);
    nff_bad(VIEW "s 0 0 0 0\n", "x.nff:8: ", "radius", "zero", NULL);
}

static void test_nff_bad_view(void **state)
{
    (void)state;
    nff_bad("v\nfrom 0 0 5\nat 0 0 0\nup 0 1 0\nangle 90\nresolution 3 3\ns 0 0 0 1\n",
            "x.nff:7: ", "'v' block (line 1)", "no 'hither' line", "found 's'");
    nff_bad("v\nfrom 0 0 5\nat 0 0 0\n", "x.nff:3: ", "file ended inside the 'v' block", "'up'",
            NULL);
    nff_bad("v\nfrom 0 0 5\nfrom 0 0 5\n", "x.nff:3: ", "second 'from'", "line 2", NULL);
    nff_bad("v\nfrom 0 0 5\nat 0 0 0\nup 0 1 0\nangle 180\nhither 1\nresolution 3 3\n",
            "x.nff:5: ", "'angle'", "between 0 and 180", NULL);
    nff_bad("v\nfrom 0 0 5\nat 0 0 0\nup 0 1 0\nangle 0\nhither 1\nresolution 3 3\n",
            "x.nff:5: ", "'angle'", NULL, NULL);
    nff_bad("v\nfrom 0 0 5\nat 0 0 5\nup 0 1 0\nangle 45\nhither 1\nresolution 3 3\n",
            "x.nff:3: ", "'at' equals 'from'", NULL, NULL);
    nff_bad("v\nfrom 0 0 5\nat 0 0 0\nup 0 0 2\nangle 45\nhither 1\nresolution 3 3\n",
            "x.nff:4: ", "'up'", "parallel", NULL);
    nff_bad("v\nfrom 0 0 5\nat 0 0 0\nup 0 1 0\nangle 45\nhither 1\nresolution 0 3\n",
            "x.nff:7: ", "'resolution' width", "integer", NULL);
    nff_bad("v\nfrom 0 0 5\nat 0 0 0\nup 0 1 0\nangle 45\nhither 1\nresolution 3 2.5\n",
            "x.nff:7: ", "'resolution' height", NULL, NULL);
}

/* ======================================================================================== */
/* JSON: good input                                                                         */

static const char *const json_all =
    "{\n"
    "  \"image\": {\"width\": 200, \"height\": 100},\n"
    "  \"max_depth\": 7,\n"
    "  \"background\": [0.1, 0.2, 0.3],\n"
    "  \"ambient\": 0.25,\n"
    "  \"camera\": {\"projection\": \"perspective\", \"eye\": [0, 0, 5], \"look_at\": [0, 0, 0],\n"
    "             \"up\": [0, 2, 0], \"fov\": 90, \"distance\": 2},\n"
    "  \"materials\": {\n"
    "    \"plain\": {},\n"
    "    \"shiny\": {\"ka\": [0.1, 0.2, 0.3], \"kd\": 0.5, \"ks\": [1, 1, 1], \"km\": 0.25,\n"
    "              \"p\": 50, \"kt\": 0.5, \"ior\": 1.33}\n"
    "  },\n"
    "  \"lights\": [{\"position\": [1, 2, 3], \"intensity\": [0.5, 0.6, 0.7]},\n"
    "             {\"position\": [-1, 2, 3], \"intensity\": 0.2}],\n"
    "  \"objects\": [\n"
    "    {\"type\": \"sphere\", \"center\": [0, 1, 0], \"radius\": 0.5, \"material\": \"shiny\"},\n"
    "    {\"type\": \"triangle\", \"vertices\": [[0, 0, 0], [1, 0, 0], [0, 1, 0]],\n"
    "     \"material\": \"plain\"},\n"
    "    {\"type\": \"triangle\", \"vertices\": [[0, 0, 0], [1, 0, 0], [0, 1, 0]],\n"
    "     \"normals\": [[0, 0, 3], [0, 1, 0], [1, 0, 0]], \"material\": \"shiny\"},\n"
    "    {\"type\": \"polygon\", \"material\": \"plain\",\n"
    "     \"vertices\": [[0, 0, 0], [2, 0, 0], [2, 1, 0], [1, 2, 0], [0, 1, 0]]}\n"
    "  ]\n"
    "}\n";

static void test_json_all(void **state)
{
    scene s;
    char err[256];
    const scene_camera *c = &s.camera;
    const scene_material *m;
    const scene_triangle *t;
    (void)state;
    parse_ok(json_scene_parse, json_all, "dir/all.json", &s);
    assert_string_equal(s.name, "all");
    assert_int_equal(s.width, 200);
    assert_int_equal(s.height, 100);
    assert_int_equal(s.max_depth, 7);
    assert_vec(s.background, 0.1f, 0.2f, 0.3f);
    assert_vec(s.ambient, 0.25f, 0.25f, 0.25f);

    assert_int_equal(c->projection, SCENE_PERSPECTIVE);
    assert_pos(c->eye, 0, 0, 5);
    assert_vec(c->u, 1, 0, 0);
    assert_vec(c->v, 0, 1, 0);
    assert_vec(c->w, 0, 0, 1);
    assert_near(c->nff_angle_deg, 0);
    assert_near(c->d, 2);
    assert_near(c->fov_deg, 90);
    if (scene_finish(&s, 0, 0, 0, err, sizeof err) != 0)
        fail_msg("%s", err);
    assert_near(c->t, 2); /* d tan(45 degrees) */
    assert_near(c->b, -2);
    assert_near(c->r, 4); /* t * 200/100 */
    assert_near(c->l, -4);
    /* a size override keeps the vertical field of view and square pixels */
    if (scene_finish(&s, 50, 100, 0, err, sizeof err) != 0)
        fail_msg("%s", err);
    assert_near(c->t, 2);
    assert_near(c->r, 1); /* t * 50/100 */
    s.width = 200;
    s.height = 100;

    assert_int_equal(s.materials.count, 2);
    m = &SCENE_AT(s.materials, scene_material, 0);
    assert_vec(m->ka, 0, 0, 0);
    assert_vec(m->kd, 0, 0, 0);
    assert_vec(m->ks, 0, 0, 0);
    assert_vec(m->km, 0, 0, 0);
    assert_vec(m->kt, 0, 0, 0);
    assert_near(m->p, 1);
    assert_near(m->ior, 1);
    m = &SCENE_AT(s.materials, scene_material, 1);
    assert_vec(m->ka, 0.1f, 0.2f, 0.3f);
    assert_vec(m->kd, 0.5f, 0.5f, 0.5f);
    assert_vec(m->ks, 1, 1, 1);
    assert_vec(m->km, 0.25f, 0.25f, 0.25f);
    assert_vec(m->kt, 0.5f, 0.5f, 0.5f);
    assert_near(m->p, 50);
    assert_near(m->ior, 1.33f);

    assert_int_equal(s.lights.count, 2);
    assert_pos(SCENE_AT(s.lights, scene_light, 0).position, 1, 2, 3);
    assert_vec(SCENE_AT(s.lights, scene_light, 0).intensity, 0.5f, 0.6f, 0.7f);
    assert_vec(SCENE_AT(s.lights, scene_light, 1).intensity, 0.2f, 0.2f, 0.2f);

    assert_int_equal(s.spheres.count, 1);
    assert_pos(SCENE_AT(s.spheres, scene_sphere, 0).center, 0, 1, 0);
    assert_near(SCENE_AT(s.spheres, scene_sphere, 0).radius, 0.5f);
    assert_int_equal(SCENE_AT(s.spheres, scene_sphere, 0).material, 1);

    assert_int_equal(s.triangles.count, 2);
    t = &SCENE_AT(s.triangles, scene_triangle, 0);
    assert_null(scene_triangle_normals(&s, t));
    assert_int_equal(t->material, 0);
    assert_pos(t->p[1], 1, 0, 0);
    t = &SCENE_AT(s.triangles, scene_triangle, 1);
    assert_non_null(scene_triangle_normals(&s, t));
    assert_int_equal(t->material, 1);
    assert_vec(scene_triangle_normals(&s, t)[0], 0, 0, 1);
    assert_vec(scene_triangle_normals(&s, t)[2], 1, 0, 0);

    assert_int_equal(s.polygons.count, 1);
    assert_int_equal(SCENE_AT(s.polygons, scene_polygon, 0).count, 5);
    assert_int_equal(SCENE_AT(s.polygons, scene_polygon, 0).first, 0);
    assert_int_equal(SCENE_AT(s.polygons, scene_polygon, 0).material, 0);
    assert_pos(SCENE_AT(s.poly_verts, vec3d, 3), 1, 2, 0);
    assert_int_equal(s.cones.count, 0);

    assert_int_equal(scene_finish(&s, 0, 0, 0, err, sizeof err), 0);
    scene_free(&s);
}

static void test_json_projections(void **state)
{
    scene s;
    char err[256];
    const scene_camera *c = &s.camera;
    (void)state;
    /* orthographic with a view direction and a window; defaults for everything else */
    parse_ok(json_scene_parse,
             "{\"camera\": {\"projection\": \"orthographic\", \"eye\": [1, 2, 3],\n"
             "  \"view\": [0, 0, -2], \"up\": [0, 1, 0], \"window\": [-2, 2, -1, 1.5]}}",
             "ortho.json", &s);
    assert_int_equal(c->projection, SCENE_ORTHOGRAPHIC);
    assert_pos(c->eye, 1, 2, 3);
    assert_vec(c->w, 0, 0, 1);
    assert_vec(c->u, 1, 0, 0);
    assert_near(c->l, -2);
    assert_near(c->r, 2);
    assert_near(c->b, -1);
    assert_near(c->t, 1.5f);
    assert_int_equal(s.width, 640);
    assert_int_equal(s.height, 480);
    assert_int_equal(s.max_depth, 5);
    assert_vec(s.background, 0, 0, 0);
    assert_vec(s.ambient, 0, 0, 0);
    assert_int_equal(s.materials.count + s.lights.count + s.spheres.count, 0);
    assert_int_equal(scene_finish(&s, 0, 0, 0, err, sizeof err), 0);
    scene_free(&s);

    /* oblique: the direction is stored and normalised */
    parse_ok(json_scene_parse,
             "{\"camera\": {\"projection\": \"oblique\", \"eye\": [0, 0, 0],\n"
             "  \"look_at\": [0, 0, -1], \"up\": [0, 1, 0], \"window\": [-1, 1, -1, 1],\n"
             "  \"direction\": [1, 0, -1]}, \"image\": {\"width\": 8}}",
             "obl.json", &s);
    assert_int_equal(c->projection, SCENE_OBLIQUE);
    assert_vec(c->dir, 0.70710678f, 0, -0.70710678f);
    assert_int_equal(s.width, 8);
    assert_int_equal(s.height, 480);
    assert_int_equal(scene_finish(&s, 0, 0, 0, err, sizeof err), 0);
    scene_free(&s);

    /* perspective is the default; a window instead of fov */
    parse_ok(json_scene_parse,
             "{\"camera\": {\"eye\": [0, 0, 0], \"look_at\": [0, 0, -1], \"up\": [0, 1, 0],\n"
             "  \"window\": [-1, 1, -0.5, 0.5]}, \"objects\": [], \"lights\": [],\n"
             "  \"materials\": {}}",
             "persp.json", &s);
    assert_int_equal(c->projection, SCENE_PERSPECTIVE);
    assert_near(c->d, 1);
    assert_near(c->t, 0.5f);
    assert_int_equal(scene_finish(&s, 0, 0, 0, err, sizeof err), 0);
    scene_free(&s);
}

/* the example scenes the project ships, when present */
static void test_json_shipped(void **state)
{
    static const char *const files[] = {"scenes/default.json", "scenes/orthographic.json",
                                        "scenes/oblique.json"};
    size_t i;
    (void)state;
    for (i = 0; i < sizeof files / sizeof files[0]; i++) {
        struct stat st;
        scene s;
        double secs;
        if (stat(files[i], &st) != 0)
            continue;
        load_and_finish(files[i], &s, &secs);
        scene_free(&s);
    }
}

/* Fixture files: the loaders name the path in messages and the scene after the file. */
static void test_fixture_files(void **state)
{
    scene s;
    char err[512];
    double secs;
    (void)state;
    load_and_finish("tests/scenes/parse/good.json", &s, &secs);
    assert_string_equal(s.name, "good");
    assert_int_equal(s.width, 64);
    assert_int_equal(s.max_depth, 4);
    assert_int_equal(s.materials.count, 2);
    assert_int_equal(s.lights.count, 1);
    assert_int_equal(s.spheres.count, 1);
    assert_int_equal(s.triangles.count, 1);
    assert_int_equal(s.polygons.count, 1);
    assert_near(SCENE_AT(s.materials, scene_material, 1).ior, 1.5f);
    scene_free(&s);

    scene_init(&s);
    assert_int_equal(scene_load("tests/scenes/parse/bad.json", &s, err, sizeof err), -1);
    assert_non_null(strstr(err, "tests/scenes/parse/bad.json:12: "));
    assert_non_null(strstr(err, "no material named \"flor\""));
    scene_free(&s);

    scene_init(&s);
    assert_int_equal(scene_load("tests/scenes/parse/bad.nff", &s, err, sizeof err), -1);
    assert_non_null(strstr(err, "tests/scenes/parse/bad.nff:13: "));
    assert_non_null(strstr(err, "file ended inside 'p 3' (line 11)"));
    scene_free(&s);
}

/* ======================================================================================== */
/* JSON: bad input                                                                          */

#define JCAM                                                                                       \
    "\"camera\": {\"eye\": [0, 0, 5], \"look_at\": [0, 0, 0], \"up\": [0, 1, 0], \"fov\": 60}"

static void test_json_bad_syntax(void **state)
{
    (void)state;
    json_bad("{\n  \"max_depth\": 5\n  \"ambient\": 1\n}\n", "x.json:3: ", "syntax error",
             "\"ambient\"", NULL);
    json_bad("{\n" JCAM "\n}\n}\n", "x.json:4: ", "syntax error", NULL, NULL);
    json_bad("{\n" JCAM ",\n\"lights\": [\n", "x.json:", "syntax error", NULL, NULL);
    json_bad("", "x.json:1: ", "empty file", NULL, NULL);
    json_bad("\n  \n", "x.json:", "empty file", NULL, NULL);
    json_bad("[1, 2]", "x.json:1: ", "JSON object at the top level", "an array", NULL);
    json_bad("{\n\"ambient\": [1, 2, 3 4]}\n", "x.json:2: ", "syntax error", NULL, NULL);
}

static void test_json_bad_keys(void **state)
{
    (void)state;
    json_bad("{\n" JCAM ",\n  \"objcts\": []\n}", "x.json:3: ", "unknown key \"objcts\"",
             "expected one of", "objects");
    json_bad("{\n\"camera\": {\"eye\": [0, 0, 5], \"look_at\": [0, 0, 0],\n"
             "  \"eyes\": [1, 1, 1], \"up\": [0, 1, 0], \"fov\": 60}}",
             "x.json:3: ", "camera: unknown key \"eyes\"", NULL, NULL);
    json_bad("{\n" JCAM ",\n\"max_depth\": 3,\n\n\"max_depth\": 4}",
             "x.json:5: ", "duplicate key \"max_depth\"", "first at line 3", NULL);
    json_bad("{\n" JCAM ",\n\"materials\": {\"a\": {},\n \"a\": {}}}",
             "x.json:4: ", "materials: duplicate key \"a\"", NULL, NULL);
    json_bad("{\n" JCAM ",\n\"materials\": {\"a\": {\"kd\": 1,\n \"shine\": 3}}}",
             "x.json:4: ", "materials.a: unknown key \"shine\"", NULL, NULL);
    json_bad("{\n" JCAM ",\n\"lights\": [{\"position\": [0, 0, 0],\n \"colour\": 1}]}",
             "x.json:4: ", "lights[0]: unknown key \"colour\"", NULL, NULL);
    json_bad("{\n" JCAM ",\n\"materials\": {\"m\": {}},\n\"objects\": [\n"
             "{\"type\": \"sphere\", \"center\": [0, 0, 0], \"radius\": 1, \"material\": \"m\",\n"
             " \"vertices\": []}]}",
             "x.json:6: ", "objects[0]: unknown key \"vertices\"", NULL, NULL);
    json_bad("{\n\"image\": {\"width\": 10, \"heigth\": 10},\n" JCAM "}",
             "x.json:2: ", "image: unknown key \"heigth\"", NULL, NULL);
}

static void test_json_bad_values(void **state)
{
    (void)state;
    json_bad("{\n\"camera\": {\"eye\": \"here\", \"look_at\": [0, 0, 0], \"up\": [0, 1, 0], "
             "\"fov\": 60}}",
             "x.json:2: ", "camera.eye: expected [x, y, z]", "found a string", NULL);
    json_bad("{\n\"camera\": {\"eye\": [0, 0], \"look_at\": [0, 0, 0], \"up\": [0, 1, 0], "
             "\"fov\": 60}}",
             "x.json:2: ", "camera.eye", "found an array of 2", NULL);
    json_bad("{\n\"camera\": {\"eye\": [0, 0, \n\"5\"], \"look_at\": [0, 0, 0], \"up\": [0, 1, 0], "
             "\"fov\": 60}}",
             "x.json:3: ", "camera.eye[2]: expected a number", "found a string", NULL);
    json_bad("{\n" JCAM ",\n\"ambient\": [1, 1e999, 1]}", "x.json:3: ", "ambient[1]", "not finite",
             NULL);
    json_bad("{\n" JCAM ",\n\"ambient\": -3e30}", "x.json:3: ", "ambient", "out of range", NULL);
    json_bad("{\n" JCAM ",\n\"background\": \"black\"}",
             "x.json:3: ", "background: expected a colour", "found a string", NULL);
    json_bad("{\n" JCAM ",\n\"image\": {\"width\": 0}}", "x.json:3: ", "image.width",
             "integer in 1..65536", NULL);
    json_bad("{\n" JCAM ",\n\"image\": {\"height\": 10.5}}", "x.json:3: ", "image.height",
             "integer", NULL);
    json_bad("{\n" JCAM ",\n\"max_depth\": 65}", "x.json:3: ", "max_depth", "1..64", NULL);
    json_bad("{\n" JCAM ",\n\"image\": [640, 480]}", "x.json:3: ", "image: expected an object",
             NULL, NULL);
    json_bad("{\n" JCAM ",\n\"lights\": {}}", "x.json:3: ", "lights: expected an array", NULL,
             NULL);
    json_bad("{\n" JCAM ",\n\"lights\": [{\"position\": [0, 0, 0]}]}",
             "x.json:3: ", "lights[0]: missing \"intensity\"", NULL, NULL);
    json_bad("{\n" JCAM ",\n\"materials\": {\"a\": {\n\"p\": -1}}}", "x.json:4: ", "materials.a.p",
             ">= 0", NULL);
    json_bad("{\n" JCAM ",\n\"materials\": {\"a\": {\n\"ior\": 0}}}",
             "x.json:4: ", "materials.a.ior", "> 0", NULL);
    json_bad("{\n" JCAM ",\n\"materials\": {\"a\": {\"ks\": [1, 2]}}}",
             "x.json:3: ", "materials.a.ks", "[r, g, b]", NULL);
}

static void test_json_bad_camera(void **state)
{
    (void)state;
    json_bad("{\n\"max_depth\": 3\n}", "x.json:1: ", "missing \"camera\"", NULL, NULL);
    json_bad("{\n\"camera\": {\"look_at\": [0, 0, 0], \"up\": [0, 1, 0], \"fov\": 60}}",
             "x.json:2: ", "camera: missing \"eye\"", NULL, NULL);
    json_bad("{\n\"camera\": {\"eye\": [0, 0, 5], \"look_at\": [0, 0, 0],\n"
             "\"view\": [0, 0, -1], \"up\": [0, 1, 0], \"fov\": 60}}",
             "x.json:3: ", "\"look_at\" or \"view\", not both", NULL, NULL);
    json_bad("{\n\"camera\": {\"eye\": [0, 0, 5], \"up\": [0, 1, 0], \"fov\": 60}}",
             "x.json:2: ", "missing \"look_at\"", "\"view\"", NULL);
    json_bad("{\n\"camera\": {\"eye\": [0, 0, 5], \"look_at\": [0, 0, 5], \"up\": [0, 1, 0], "
             "\"fov\": 60}}",
             "x.json:2: ", "camera.look_at", "equals the eye", NULL);
    json_bad("{\n\"camera\": {\"eye\": [0, 0, 5], \"look_at\": [0, 0, 0],\n"
             "\"up\": [0, 0, 1], \"fov\": 60}}",
             "x.json:3: ", "camera.up", "parallel", NULL);
    json_bad("{\n\"camera\": {\"projection\": \"fisheye\", \"eye\": [0, 0, 5]}}",
             "x.json:2: ", "camera.projection", "\"fisheye\"", "\"orthographic\"");
    json_bad("{\n\"camera\": {\"projection\": \"orthographic\", \"eye\": [0, 0, 5],\n"
             "\"look_at\": [0, 0, 0], \"up\": [0, 1, 0],\n\"fov\": 60}}",
             "x.json:4: ", "camera.fov", "only a perspective camera", NULL);
    json_bad("{\n\"camera\": {\"eye\": [0, 0, 5], \"look_at\": [0, 0, 0], \"up\": [0, 1, 0],\n"
             "\"fov\": 60, \"window\": [-1, 1, -1, 1]}}",
             "x.json:3: ", "\"window\" or \"fov\", not both", NULL, NULL);
    json_bad("{\n\"camera\": {\"eye\": [0, 0, 5], \"look_at\": [0, 0, 0], \"up\": [0, 1, 0]}}",
             "x.json:2: ", "missing \"window\"", "\"fov\"", NULL);
    /* NFF's angle */
    json_bad("{\n\"camera\": {\"eye\": [0, 0, 5], \"look_at\": [0, 0, 0], \"up\": [0, 1, 0],\n"
             "\"angle\": 0}}",
             "x.json:3: ", "camera.angle", "between 0 and 180", NULL);
    json_bad("{\n\"camera\": {\"eye\": [0, 0, 5], \"look_at\": [0, 0, 0], \"up\": [0, 1, 0],\n"
             "\"fov\": 60,\n\"angle\": 60}}",
             "x.json:4: ", "camera.angle", "one of \"angle\", \"fov\" and \"window\"", NULL);
    json_bad("{\n\"camera\": {\"eye\": [0, 0, 5], \"look_at\": [0, 0, 0], \"up\": [0, 1, 0],\n"
             "\"distance\": 2, \"angle\": 60}}",
             "x.json:3: ", "camera.angle", "no \"distance\"", NULL);
    json_bad("{\n\"camera\": {\"projection\": \"orthographic\", \"eye\": [0, 0, 5],\n"
             "\"look_at\": [0, 0, 0], \"up\": [0, 1, 0], \"angle\": 60}}",
             "x.json:3: ", "camera.angle", "only a perspective camera", NULL);
    json_bad("{\n\"camera\": {\"eye\": [0, 0, 5], \"look_at\": [0, 0, 0], \"up\": [0, 1, 0],\n"
             "\"fov\": 180}}",
             "x.json:3: ", "camera.fov", "between 0 and 180", NULL);
    json_bad("{\n\"camera\": {\"eye\": [0, 0, 5], \"look_at\": [0, 0, 0], \"up\": [0, 1, 0],\n"
             "\"window\": [1, -1, -1, 1]}}",
             "x.json:3: ", "camera.window", "l < r", NULL);
    json_bad("{\n\"camera\": {\"eye\": [0, 0, 5], \"look_at\": [0, 0, 0], \"up\": [0, 1, 0],\n"
             "\"fov\": 60, \"distance\": 0}}",
             "x.json:3: ", "camera.distance", "> 0", NULL);
    json_bad("{\n\"camera\": {\"projection\": \"oblique\", \"eye\": [0, 0, 5],\n"
             "\"look_at\": [0, 0, 0], \"up\": [0, 1, 0], \"window\": [-1, 1, -1, 1]}}",
             "x.json:2: ", "oblique camera needs \"direction\"", NULL, NULL);
    json_bad("{\n\"camera\": {\"projection\": \"oblique\", \"eye\": [0, 0, 5],\n"
             "\"look_at\": [0, 0, 0], \"up\": [0, 1, 0], \"window\": [-1, 1, -1, 1],\n"
             "\"direction\": [0, 0, 1]}}",
             "x.json:4: ", "camera.direction", "into the view", NULL);
    json_bad("{\n\"camera\": {\"eye\": [0, 0, 5], \"look_at\": [0, 0, 0], \"up\": [0, 1, 0],\n"
             "\"fov\": 60,\n\"direction\": [0, 0, -1]}}",
             "x.json:4: ", "camera.direction", "only an oblique camera", NULL);
    json_bad("{\n\"camera\": {\"projection\": \"orthographic\", \"eye\": [0, 0, 5],\n"
             "\"look_at\": [0, 0, 0], \"up\": [0, 1, 0], \"window\": [-1, 1, -1, 1],\n"
             "\"distance\": 2}}",
             "x.json:4: ", "camera.distance", "only a perspective camera", NULL);
}

#define JMAT ",\n\"materials\": {\"m\": {}}, \"objects\": [\n" /* objects start at line 4 */

static void test_json_bad_objects(void **state)
{
    (void)state;
    json_bad("{\n" JCAM JMAT "{\"type\": \"cube\", \"material\": \"m\"}]}",
             "x.json:4: ", "objects[0].type", "unknown object type \"cube\"", "\"polygon\"");
    json_bad("{\n" JCAM JMAT "{\"center\": [0, 0, 0]}]}",
             "x.json:4: ", "objects[0]: missing \"type\"", NULL, NULL);
    json_bad("{\n" JCAM JMAT "[]]}", "x.json:4: ", "objects[0]: expected an object", NULL, NULL);
    json_bad("{\n" JCAM JMAT
             "{\"type\": \"sphere\", \"center\": [0, 0, 0], \"radius\": 1, \"material\": \"m\"},\n"
             "{\"type\": \"sphere\", \"center\": [0, 0, 0], \"radius\": 0, \"material\": \"m\"}]}",
             "x.json:5: ", "objects[1].radius", "> 0", NULL);
    json_bad("{\n" JCAM JMAT
             "{\"type\": \"sphere\", \"center\": [0, 0, 0], \"radius\": -1, \"material\": \"m\"}]}",
             "x.json:4: ", "objects[0].radius", "> 0", NULL);
    json_bad("{\n" JCAM JMAT "{\"type\": \"sphere\", \"center\": [0, 0, 0], \"radius\": 1,\n"
             " \"material\": \"gold\"}]}",
             "x.json:5: ", "objects[0].material", "no material named \"gold\"", NULL);
    json_bad("{\n" JCAM JMAT "{\"type\": \"sphere\", \"center\": [0, 0, 0], \"radius\": 1}]}",
             "x.json:4: ", "objects[0]: missing \"material\"", NULL, NULL);
    json_bad("{\n" JCAM JMAT "{\"type\": \"polygon\", \"material\": \"m\",\n"
             " \"vertices\": [[0, 0, 0], [1, 0, 0]]}]}",
             "x.json:5: ", "objects[0].vertices", "expected 3..", "found 2");
    json_bad("{\n" JCAM JMAT "{\"type\": \"triangle\", \"material\": \"m\",\n"
             " \"vertices\": [[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]]}]}",
             "x.json:5: ", "objects[0].vertices", "expected 3 points", "found 4");
    json_bad("{\n" JCAM JMAT "{\"type\": \"polygon\", \"material\": \"m\", \"vertices\": [\n"
             " [0, 0, 0], [10, 0, 0],\n [10, 10, 0],\n [5, 15, 0.005],\n [0, 10, 0]]}]}",
             "x.json:7: ", "objects[0].vertices[3]", "not planar", NULL);
    json_bad("{\n" JCAM JMAT "{\"type\": \"polygon\", \"material\": \"m\",\n"
             " \"vertices\": [[0, 0, 0], [1, 1, 1], [2, 2, 2], [3, 3, 3]]}]}",
             "x.json:5: ", "objects[0].vertices", "zero area", NULL);
    json_bad("{\n" JCAM JMAT "{\"type\": \"triangle\", \"material\": \"m\",\n"
             " \"vertices\": [[0, 0, 0], [1, 0, 0], [2, 0, 0]]}]}",
             "x.json:5: ", "triangle has zero area", NULL, NULL);
    json_bad("{\n" JCAM JMAT "{\"type\": \"triangle\", \"material\": \"m\",\n"
             " \"vertices\": [[0, 0, 0], [1, 0, 0], [0, 1, 0]],\n"
             " \"normals\": [[0, 0, 1],\n [0, 0, 0], [0, 0, 1]]}]}",
             "x.json:7: ", "objects[0].normals[1]", "zero", NULL);
    json_bad("{\n" JCAM JMAT "{\"type\": \"triangle\", \"material\": \"m\",\n"
             " \"vertices\": [[0, 0, 0], [1, 0, 0], [0, \"1\", 0]]}]}",
             "x.json:5: ", "objects[0].vertices[2][1]", "expected a number", NULL);
    json_bad("{\n" JCAM ",\n\"objects\": {}}", "x.json:3: ", "objects: expected an array", NULL,
             NULL);
    /* spheres seen from inside, cones, cylinders, smooth polygons */
    json_bad("{\n" JCAM JMAT "{\"type\": \"sphere\", \"center\": [0, 0, 0], \"radius\": 1,\n"
             " \"inside\": 1, \"material\": \"m\"}]}",
             "x.json:5: ", "objects[0].inside", "expected true or false", "a number");
    json_bad("{\n" JCAM JMAT "{\"type\": \"cone\", \"base\": [0, 0, 0], \"base_radius\": 0,\n"
             " \"apex\": [0, 1, 0], \"apex_radius\": 0, \"material\": \"m\"}]}",
             "x.json:4: ", "objects[0]: base_radius and apex_radius are both zero", NULL, NULL);
    json_bad("{\n" JCAM JMAT "{\"type\": \"cone\", \"base\": [0, 0, 0], \"base_radius\": 1,\n"
             " \"apex\": [0, 1, 0], \"apex_radius\": -0.5, \"material\": \"m\"}]}",
             "x.json:5: ", "objects[0].apex_radius", ">= 0", "-0.5");
    json_bad("{\n" JCAM JMAT "{\"type\": \"cone\", \"base\": [0, 0, 0], \"base_radius\": 1,\n"
             " \"apex\": [0, 1, 0], \"material\": \"m\"}]}",
             "x.json:4: ", "objects[0]: missing \"apex_radius\"", NULL, NULL);
    json_bad("{\n" JCAM JMAT "{\"type\": \"cone\", \"base\": [0, 0, 0], \"base_radius\": 1,\n"
             " \"apex\": [0, 1, 0], \"apex_radius\": 1, \"radius\": 1, \"material\": \"m\"}]}",
             "x.json:5: ", "radius", NULL, NULL);
    json_bad("{\n" JCAM JMAT "{\"type\": \"cylinder\", \"base\": [1, 2, 3],\n"
             " \"apex\": [1, 2, 3], \"radius\": 1, \"material\": \"m\"}]}",
             "x.json:5: ", "objects[0].apex: equals the base", NULL, NULL);
    json_bad("{\n" JCAM JMAT "{\"type\": \"cylinder\", \"base\": [0, 0, 0],\n"
             " \"apex\": [0, 1, 0], \"radius\": 0, \"material\": \"m\"}]}",
             "x.json:5: ", "objects[0].radius", "> 0", NULL);
    json_bad("{\n" JCAM JMAT "{\"type\": \"polygon\", \"material\": \"m\",\n"
             " \"vertices\": [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]],\n"
             " \"normals\": [[0, 0, 1], [0, 0, 1], [0, 0, 1]]}]}",
             "x.json:6: ", "objects[0].normals", "expected 4 points", "found 3");
}

/* The objects NFF has and JSON gained: an inside-only sphere (stored with a negative
 * radius, as NFF's), a cone, a cylinder, a polygon with vertex normals (a fan of smooth
 * triangles, as NFF's pp). */
static void test_json_more_objects(void **state)
{
    scene s, n;
    const scene_cone *c;
    const scene_triangle *t;
    size_t i;
    (void)state;
    parse_ok(
        json_scene_parse,
        "{" JCAM ", \"materials\": {\"m\": {}}, \"objects\": [\n"
        "{\"type\": \"sphere\", \"center\": [1, 2, 3], \"radius\": 4, \"inside\": true,\n"
        " \"material\": \"m\"},\n"
        "{\"type\": \"sphere\", \"center\": [1, 2, 3], \"radius\": 0.5, \"inside\": false,\n"
        " \"material\": \"m\"},\n"
        "{\"type\": \"cone\", \"base\": [0, 0, 0], \"base_radius\": 1, \"apex\": [0, 2, 0],\n"
        " \"apex_radius\": 0, \"material\": \"m\"},\n"
        "{\"type\": \"cylinder\", \"base\": [1, 0, 0], \"apex\": [1, 0, 3], \"radius\": 0.25,\n"
        " \"material\": \"m\"},\n"
        "{\"type\": \"polygon\", \"material\": \"m\",\n"
        " \"vertices\": [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]],\n"
        " \"normals\": [[0, 0, 2], [0, 1, 1], [1, 1, 1], [1, 0, 1]]}]}\n",
        "more.json", &s);
    assert_int_equal(s.spheres.count, 2);
    assert_near(SCENE_AT(s.spheres, scene_sphere, 0).radius, -4);
    assert_pos(SCENE_AT(s.spheres, scene_sphere, 0).center, 1, 2, 3);
    assert_near(SCENE_AT(s.spheres, scene_sphere, 1).radius, 0.5f);
    assert_int_equal(s.cones.count, 2);
    c = &SCENE_AT(s.cones, scene_cone, 0);
    assert_pos(c->base, 0, 0, 0);
    assert_pos(c->apex, 0, 2, 0);
    assert_near(c->base_radius, 1);
    assert_near(c->apex_radius, 0);
    c = &SCENE_AT(s.cones, scene_cone, 1);
    assert_pos(c->apex, 1, 0, 3);
    assert_near(c->base_radius, 0.25f);
    assert_near(c->apex_radius, 0.25f);
    /* the smooth polygon: triangles (v0, v1, v2) and (v0, v2, v3), normals normalised */
    assert_int_equal(s.polygons.count, 0);
    assert_int_equal(s.triangles.count, 2);
    t = &SCENE_AT(s.triangles, scene_triangle, 1);
    assert_pos(t->p[0], 0, 0, 0);
    assert_pos(t->p[1], 1, 1, 0);
    assert_pos(t->p[2], 0, 1, 0);
    assert_non_null(scene_triangle_normals(&s, t));
    assert_vec(scene_triangle_normals(&s, t)[0], 0, 0, 1);
    assert_vec(scene_triangle_normals(&s, t)[2], 0.70710678f, 0, 0.70710678f);

    /* the same objects as NFF gives the same model (but the materials) */
    parse_ok(nff_parse,
             "v\nfrom 0 0 5\nat 0 0 0\nup 0 1 0\nangle 60\nhither 1\nresolution 64 48\n"
             "s 1 2 3 -4\ns 1 2 3 0.5\nc 0 0 0 1 0 2 0 0\nc 1 0 0 0.25 1 0 3 0.25\n"
             "pp 4\n0 0 0 0 0 2\n1 0 0 0 1 1\n1 1 0 1 1 1\n0 1 0 1 0 1\n",
             "more.nff", &n);
    assert_int_equal(n.spheres.count, 2);
    for (i = 0; i < 2; i++) {
        assert_memory_equal(&SCENE_AT(n.spheres, scene_sphere, i).center,
                            &SCENE_AT(s.spheres, scene_sphere, i).center, sizeof(vec3d));
        assert_true(SCENE_AT(n.spheres, scene_sphere, i).radius ==
                    SCENE_AT(s.spheres, scene_sphere, i).radius);
    }
    assert_int_equal(n.cones.count, 2);
    for (i = 0; i < 2; i++) {
        const scene_cone *a = &SCENE_AT(n.cones, scene_cone, i),
                         *b = &SCENE_AT(s.cones, scene_cone, i);
        assert_memory_equal(&a->base, &b->base, sizeof a->base);
        assert_memory_equal(&a->apex, &b->apex, sizeof a->apex);
        assert_true(a->base_radius == b->base_radius && a->apex_radius == b->apex_radius);
    }
    assert_int_equal(n.triangles.count, 2);
    assert_int_equal(n.tri_normals.count, s.tri_normals.count);
    assert_memory_equal(n.tri_normals.data, s.tri_normals.data,
                        s.tri_normals.count * sizeof(vec3f));
    for (i = 0; i < 2; i++)
        assert_memory_equal(SCENE_AT(n.triangles, scene_triangle, i).p,
                            SCENE_AT(s.triangles, scene_triangle, i).p, 3 * sizeof(vec3d));
    scene_free(&n);
    scene_free(&s);
}

/* The line finder must step over strings with escapes and brackets, nested arrays and
 * multi-line values. */
static void test_json_lines(void **state)
{
    (void)state;
    json_bad("{\n"
             "  \"materials\": {\"we\\\"ird{[\": {\"kd\": [1,\n 1, 1]},\n"
             "                \"x\\\\\": {}},\n"
             "  \"camera\": {\"eye\": [0, 0, 5], \"look_at\": [[0][0]] },\n",
             "x.json:5: ", "syntax error", NULL, NULL);
    json_bad("{\n"
             "  \"materials\": {\"we\\\"ird{[\": {\"kd\": [1,\n 1, 1]},\n"  /* 2-3 */
             "                \"x\\\\\": {}},\n"                            /* 4 */
             "  \"camera\": {\"eye\": [0, 0, 5], \"look_at\": [0, 0, 0],\n" /* 5 */
             "     \"up\": [0, 1, 0], \"fov\": 60},\n"                      /* 6 */
             "  \"objects\": [{\"type\": \"sphere\", \"center\": [[],\n"    /* 7 */
             "  {}], \"radius\": 1, \"material\": \"x\\\\\"},\n"            /* 8 */
             "     {\"type\": \"sphere\", \"center\": [0, 0, 0],\n"         /* 9 */
             "      \"radius\":\n -1, \"material\": \"we\\\"ird{[\"}]\n"    /* 10-11 */
             "}\n",
             "x.json:7: ", "objects[0].center", NULL, NULL);
    json_bad("{\n"
             "  \"materials\": {\"we\\\"ird{[\": {\"kd\": [1,\n 1, 1]},\n"     /* 2-3 */
             "                \"x\\\\\": {}},\n"                               /* 4 */
             "  \"camera\": {\"eye\": [0, 0, 5], \"look_at\": [0, 0, 0],\n"    /* 5 */
             "     \"up\": [0, 1, 0], \"fov\": 60},\n"                         /* 6 */
             "  \"objects\": [{\"type\": \"sphere\", \"center\": [0, 0, 0],\n" /* 7 */
             "  \"radius\": 1, \"material\": \"x\\\\\"},\n"                    /* 8 */
             "     {\"type\": \"sphere\", \"center\": [0, 0, 0],\n"            /* 9 */
             "      \"radius\":\n -1, \"material\": \"we\\\"ird{[\"}]\n"       /* 10-11 */
             "}\n",
             "x.json:10: ", "objects[1].radius", "> 0", NULL);
    json_bad("{\n"
             "  \"materials\": {\"we\\\"ird{[\": {\"kd\": [1,\n 1, 1]},\n"
             "                \"x\\\\\": {}},\n"
             "  \"camera\": {\"eye\": [0, 0, 5], \"look_at\": [0, 0, 0],\n"
             "     \"up\": [0, 1, 0], \"fov\": 60},\n"
             "  \"objects\": [{\"type\": \"sphere\", \"center\": [0, 0, 0],\n"
             "  \"radius\": 1, \"material\": \"x\\\\\"},\n"
             "     {\"type\": \"sphere\", \"center\": [0, 0, 0],\n"
             "      \"radius\": 1, \"material\":\n\n \"we\\\"ird{[x\"}]\n"
             "}\n",
             "x.json:10: ", "no material named", NULL, NULL);
}

/* ======================================================================================== */
/* Robustness: every class of bad input, in every field                                     */

/* text with [pos, pos + len) replaced by repl; malloc'd */
static char *replaced(const char *text, size_t pos, size_t len, const char *repl)
{
    size_t n = strlen(text), m = strlen(repl);
    char *out = malloc(n - len + m + 1);
    assert_non_null(out);
    memcpy(out, text, pos);
    memcpy(out + pos, repl, m);
    memcpy(out + pos + m, text + pos + len, n - pos - len + 1);
    return out;
}

static long line_at(const char *text, size_t pos)
{
    long line = 1;
    size_t i;
    for (i = 0; i < pos; i++)
        line += text[i] == '\n';
    return line;
}

/* NaN, infinities and out-of-range magnitudes in every numeric field of the NFF scene that
 * holds every entity: each must fail at its own line. */
static void test_nff_bad_nonfinite(void **state)
{
    static const char *const bad[] = {"nan", "-nan", "inf", "-inf", "infinity", "1e999", "1e31"};
    const char *t = nff_all;
    size_t pos = 0, fields = 0;
    (void)state;
    while (t[pos]) {
        size_t end = pos, k;
        char tok[64], *stop;
        if (t[pos] == '#') { /* a comment: to the end of the line */
            while (t[pos] && t[pos] != '\n')
                pos++;
            continue;
        }
        if (strchr(" \t\r\n", t[pos])) {
            pos++;
            continue;
        }
        while (t[end] && !strchr(" \t\r\n#", t[end]))
            end++;
        assert_true(end - pos < sizeof tok);
        memcpy(tok, t + pos, end - pos);
        tok[end - pos] = '\0';
        strtod(tok, &stop);
        if (*stop == '\0') { /* a number */
            fields++;
            for (k = 0; k < sizeof bad / sizeof bad[0]; k++) {
                char *text = replaced(t, pos, end - pos, bad[k]), prefix[32];
                snprintf(prefix, sizeof prefix, "x.nff:%ld: ", line_at(t, pos));
                nff_bad(text, prefix, bad[k], k == 6 ? "out of range" : "not finite", NULL);
                free(text);
            }
        }
        pos = end;
    }
    print_message("NFF: %zu numeric fields, each NaN, infinite and out of range\n", fields);
    assert_true(fields > 60);
}

/* The same in JSON, which has no NaN or infinity literals (syntax errors, at their line) but
 * overflows 1e999 to infinity. */
static void test_json_bad_nonfinite(void **state)
{
    static const char *const bad[] = {"1e999", "-1e999", "1e31", "NaN", "Infinity", "-inf"};
    const char *t = json_all;
    size_t pos = 0, fields = 0;
    (void)state;
    while (t[pos]) {
        size_t end = pos + 1, k;
        if (t[pos] == '"') { /* a string */
            while (t[end] && t[end] != '"')
                end += t[end] == '\\' ? 2 : 1;
            pos = end + 1;
            continue;
        }
        if (!strchr("-0123456789", t[pos])) {
            pos++;
            continue;
        }
        while (t[end] && strchr("0123456789.eE+-", t[end]))
            end++;
        fields++;
        for (k = 0; k < sizeof bad / sizeof bad[0]; k++) {
            char *text = replaced(t, pos, end - pos, bad[k]), prefix[32];
            snprintf(prefix, sizeof prefix, "x.json:%ld: ", line_at(t, pos));
            json_bad(text, prefix,
                     k < 2   ? "not finite"
                     : k < 3 ? "out of range"
                             : "syntax error",
                     NULL, NULL);
            free(text);
        }
        pos = end;
    }
    print_message("JSON: %zu numeric fields, each NaN, infinite and out of range\n", fields);
    assert_true(fields > 70);
}

/* Numbers that are finite and non-zero as read, but zero or equal once stored as floats. */
static void test_tiny_numbers(void **state)
{
    (void)state;
    nff_bad(VIEW "s 0 0 0 1e-300\n", "x.nff:8: ", "radius must not be zero", NULL, NULL);
    nff_bad("v\nfrom 0 0 5\nat 0 0 0\nup 0 1 0\nangle 1e-300\nhither 1\nresolution 3 3\n",
            "x.nff:5: ", "'angle'", NULL, NULL);
    nff_bad("v\nfrom 0 0 5\nat 0 0 0\nup 0 1 0\nangle 179.999999999\nhither 1\nresolution 3 3\n",
            "x.nff:5: ", "'angle'", NULL, NULL);
    /* an angle that is fine for a few pixels, but not for 65536 rows */
    nff_bad("v\nfrom 0 0 5\nat 0 0 0\nup 0 1 0\nangle 1e-40\nhither 1\nresolution 1 65536\n",
            "x.nff:5: ", "no usable view", "too small", NULL);
    nff_bad(VIEW "f 1e18 1 1 1e18 0 1 0 1\n", "x.nff:8: ", "Kd * (r g b)", "out of range", NULL);
    json_bad(
        "{\n" JCAM ",\n\"materials\": {\"m\": {}}, \"objects\": [\n"
        "{\"type\": \"sphere\", \"center\": [0, 0, 0], \"radius\": 1e-300, \"material\": \"m\"}]}",
        "x.json:4: ", "objects[0].radius", "> 0", NULL);
    json_bad("{\n\"camera\": {\"eye\": [0, 0, 5], \"look_at\": [0, 0, 0], \"up\": [0, 1, 0],\n"
             "\"fov\": 60, \"distance\": 1e-300}}",
             "x.json:3: ", "camera.distance", "> 0", NULL);
    json_bad("{\n\"camera\": {\"eye\": [0, 0, 5], \"look_at\": [0, 0, 0], \"up\": [0, 1, 0],\n"
             "\"fov\": 1e-300}}",
             "x.json:3: ", "camera.fov", NULL, NULL);
    json_bad("{\n\"camera\": {\"eye\": [0, 0, 5], \"look_at\": [0, 0, 0], \"up\": [0, 1, 0],\n"
             "\"window\": [0, 1e-300, -1, 1]}}",
             "x.json:3: ", "camera.window", "l < r", NULL);
    json_bad("{\n" JCAM ",\n\"materials\": {\"a\": {\n\"ior\": 1e-300}}}",
             "x.json:4: ", "materials.a.ior", "> 0", NULL);
    /* a distance whose window would overflow a float at this size is out of range (CW_MAX_ABS
     * keeps every coordinate and its square within float range) */
    json_bad("{\"image\": {\"width\": 65536, \"height\": 1},\n\"camera\": {\"eye\": [0, 0, 0],\n"
             "\"view\": [0, 0, -1], \"up\": [0, 1, 0],\n\"fov\": 179.99999, \"distance\": 1e30}}",
             "x.json:4: ", "camera.distance", "out of range", "1e18");
    json_bad("{\"image\": {\"width\": 1, \"height\": 65536},\n\"camera\": {\"eye\": [0, 0, 0],\n"
             "\"view\": [0, 0, -1], \"up\": [0, 1, 0],\n\"fov\": 1e-40, \"distance\": 1e-30}}",
             "x.json:4: ", "camera: gives no usable view", "too small", NULL);
}

/* Image sizes: per side, in all, in files and in scene_finish (whose caller may override
 * the size), so that width * height * bytes per pixel cannot overflow. */
static void test_bad_image_size(void **state)
{
    scene s;
    char err[256];
    (void)state;
    nff_bad("v\nfrom 0 0 5\nat 0 0 0\nup 0 1 0\nangle 45\nhither 1\nresolution 65536 65536\n",
            "x.nff:7: ", "65536x65536", "2^28 pixels", NULL);
    nff_bad("v\nfrom 0 0 5\nat 0 0 0\nup 0 1 0\nangle 45\nhither 1\nresolution 65537 1\n",
            "x.nff:7: ", "'resolution' width", "1..65536", NULL);
    nff_bad("v\nfrom 0 0 5\nat 0 0 0\nup 0 1 0\nangle 45\nhither 1\nresolution 8 4294967304\n",
            "x.nff:7: ", "'resolution' height", "1..65536", NULL);
    nff_bad("v\nfrom 0 0 5\nat 0 0 0\nup 0 1 0\nangle 45\nhither 1\nresolution -8 8\n",
            "x.nff:7: ", "'resolution' width", NULL, NULL);
    json_bad("{\n" JCAM ",\n\"image\": {\"width\": 65536,\n \"height\": 65536}}",
             "x.json:3: ", "image: 65536x65536", "2^28 pixels", NULL);
    json_bad("{\n" JCAM ",\n\"image\": {\"width\": 4294967296}}", "x.json:3: ", "image.width",
             "1..65536", NULL);
    json_bad("{\n" JCAM ",\n\"image\": {\"height\": -1}}", "x.json:3: ", "image.height", "1..65536",
             NULL);
    json_bad("{\n" JCAM ",\n\"max_depth\": 2147483648}", "x.json:3: ", "max_depth", "1..64", NULL);

    /* scene_finish: 2^28 pixels pass, one row more does not; so does a side over 65536 */
    parse_ok(json_scene_parse, "{" JCAM "}", "size.json", &s);
    assert_int_equal(scene_finish(&s, 65536, 4096, 0, err, sizeof err), 0);
    assert_int_equal(scene_finish(&s, 65536, 4097, 0, err, sizeof err), -1);
    assert_non_null(strstr(err, "size: image size 65536x4097 out of range"));
    assert_int_equal(scene_finish(&s, 65537, 1, 0, err, sizeof err), -1);
    assert_non_null(strstr(err, "65537x"));
    assert_int_equal(scene_finish(&s, 2147483647, 2147483647, 0, err, sizeof err), -1);
    assert_non_null(strstr(err, "out of range"));
    assert_int_equal(scene_finish(&s, 8, 6, 65, err, sizeof err), -1);
    assert_non_null(strstr(err, "maximum depth 65"));
    scene_free(&s);
}

/* Vertex counts far beyond the file: an error, found before anything is allocated for them,
 * or (within the limit) when the file ends. */
static void test_nff_bad_absurd_counts(void **state)
{
    struct rusage before, after;
    double t0;
    (void)state;
    nff_bad(VIEW "p 2147483648\n0 0 0\n", "x.nff:8: ", "'p' vertex count", "3..10000000",
            "'2147483648'");
    nff_bad(VIEW "pp 4294967299\n", "x.nff:8: ", "'pp' vertex count", NULL, NULL);
    nff_bad(VIEW "p 1e18\n", "x.nff:8: ", "'p' vertex count", NULL, NULL);
    nff_bad(VIEW "p -2147483648\n", "x.nff:8: ", "at least 3", NULL, NULL);
    nff_bad(VIEW "p 0x10\n", "x.nff:8: ", NULL, NULL, NULL); /* hexadecimal: 16, then EOF */
    getrusage(RUSAGE_SELF, &before);
    t0 = sys_now();
    nff_bad(VIEW "p 10000000\n0 0 0\n1 0 0\n", "x.nff:10: ", "file ended inside 'p 10000000'",
            "found 2", NULL);
    nff_bad(VIEW "pp 10000000\n0 0 0 0 0 1\n", "x.nff:9: ", "file ended inside 'pp 10000000'", NULL,
            NULL);
    getrusage(RUSAGE_SELF, &after);
    print_message("two 10^7-vertex headers: %.1f ms, peak memory +%ld KiB\n",
                  (sys_now() - t0) * 1e3, after.ru_maxrss - before.ru_maxrss);
    assert_true(after.ru_maxrss - before.ru_maxrss < 32 * 1024);
    assert_true(sys_now() - t0 < 1.0);
}

/* Zero-length and parallel camera vectors. */
static void test_bad_camera_vectors(void **state)
{
    (void)state;
    nff_bad("v\nfrom 0 0 5\nat 0 0 0\nup 0 0 0\nangle 45\nhither 1\nresolution 3 3\n",
            "x.nff:4: ", "'up' is zero", NULL, NULL);
    nff_bad("v\nfrom 0 0 5\nat 0 0 0\nup 0 0 -3\nangle 45\nhither 1\nresolution 3 3\n",
            "x.nff:4: ", "parallel", NULL, NULL);
    nff_bad("v\nfrom 1 2 3\nat 1 2 3\nup 0 1 0\nangle 45\nhither 1\nresolution 3 3\n",
            "x.nff:3: ", "'at' equals 'from'", NULL, NULL);
    json_bad("{\n\"camera\": {\"eye\": [0, 0, 5], \"view\": [0, 0, 0], \"up\": [0, 1, 0], "
             "\"fov\": 60}}",
             "x.json:2: ", "camera.view", "zero", NULL);
    json_bad("{\n\"camera\": {\"eye\": [0, 0, 5], \"view\": [0, 0, -1],\n\"up\": [0, 0, 0], "
             "\"fov\": 60}}",
             "x.json:3: ", "camera.up", "zero or parallel", NULL);
    json_bad("{\n\"camera\": {\"eye\": [0, 0, 5], \"view\": [0, 2, 0],\n\"up\": [0, -1, 0], "
             "\"fov\": 60}}",
             "x.json:3: ", "camera.up", "parallel", NULL);
    json_bad("{\n\"camera\": {\"projection\": \"oblique\", \"eye\": [0, 0, 5],\n"
             "\"look_at\": [0, 0, 0], \"up\": [0, 1, 0], \"window\": [-1, 1, -1, 1],\n"
             "\"direction\": [0, 0, 0]}}",
             "x.json:4: ", "camera.direction", "zero", NULL);
}

/* Polygons without area are rejected (as in JSON); a polygon with some collinear vertices
 * but an area is accepted. */
static void test_nff_bad_degenerate(void **state)
{
    scene s;
    (void)state;
    nff_bad(VIEW "p 3\n0 0 0\n1 1 1\n2 2 2\n", "x.nff:8: ", "'p 3' has zero area", "collinear",
            "line 11");
    nff_bad(VIEW "p 4\n1 1 1\n1 1 1\n1 1 1\n1 1 1\n", "x.nff:8: ", "'p 4' has zero area", NULL,
            NULL);
    nff_bad(VIEW "pp 3\n0 0 0 0 0 1\n1 0 0 0 0 1\n3 0 0 0 0 1\n",
            "x.nff:8: ", "'pp 3' has zero area", NULL, NULL);
    nff_bad(VIEW "s 0 0 0 1\npp 5\n0 0 0 0 0 1\n1 0 0 0 0 1\n2 0 0 0 0 1\n3 0 0 0 0 1\n"
                 "4 0 0 0 0 1\n",
            "x.nff:9: ", "'pp 5' has zero area", NULL, NULL);
    /* a sliver is not zero: 1e-6 high over 1e3 long */
    parse_ok(nff_parse, VIEW "p 3\n0 0 0\n1000 0 0\n500 1e-6 0\n", "sliver.nff", &s);
    assert_int_equal(s.triangles.count, 1);
    scene_free(&s);
    /* a vertex in the middle of an edge, and a repeated vertex */
    parse_ok(nff_parse, VIEW "p 5\n0 0 0\n1 0 0\n2 0 0\n2 2 0\n2 2 0\n", "mid.nff", &s);
    assert_int_equal(s.polygons.count, 1);
    scene_free(&s);
}

/* Bytes that are not a scene: binary with and without NUL bytes, control characters (shown
 * escaped in the message), a UTF-8 byte order mark (accepted). */
static void test_binary_garbage(void **state)
{
    static const unsigned char png[] = {0x89, 'P', 'N',  'G', '\r', '\n', 0x1a, '\n', 0,
                                        0,    0,   0x0d, 'I', 'H',  'D',  'R',  0,    0};
    unsigned char junk[4096];
    unsigned long x = 12345;
    char err[512];
    scene s;
    int round;
    size_t i;
    (void)state;
    scene_init(&s);
    assert_int_equal(nff_parse((const char *)png, sizeof png, "x.nff", &s, err, sizeof err), -1);
    assert_non_null(strstr(err, "x.nff:3: unexpected NUL byte"));
    scene_free(&s);
    scene_init(&s);
    assert_int_equal(json_scene_parse((const char *)png, sizeof png, "x.json", &s, err, sizeof err),
                     -1);
    assert_non_null(strstr(err, "x.json:3: unexpected NUL byte"));
    scene_free(&s);
    /* pseudo-random bytes without NUL: an error with a line and a printable message */
    for (round = 0; round < 50; round++) {
        for (i = 0; i < sizeof junk; i++) {
            x = x * 1103515245UL + 12345UL;
            junk[i] = (unsigned char)(1 + (x >> 16) % 255);
        }
        scene_init(&s);
        assert_int_equal(nff_parse((const char *)junk, sizeof junk, "x.nff", &s, err, sizeof err),
                         -1);
        scene_free(&s);
        assert_true(strncmp(err, "x.nff:", 6) == 0 && err[6] >= '1' && err[6] <= '9');
        for (i = 0; err[i]; i++)
            if ((unsigned char)err[i] < 0x20 || err[i] == 0x7f)
                fail_msg("control character in \"%s\"", err);
        scene_init(&s);
        assert_int_equal(
            json_scene_parse((const char *)junk, sizeof junk, "x.json", &s, err, sizeof err), -1);
        scene_free(&s);
        assert_true(strncmp(err, "x.json:", 7) == 0 && err[7] >= '1' && err[7] <= '9');
        for (i = 0; err[i]; i++)
            if ((unsigned char)err[i] < 0x20 || err[i] == 0x7f)
                fail_msg("control character in \"%s\"", err);
    }
    /* control characters and bytes that are not UTF-8 are escaped; UTF-8 is kept */
    nff_bad(VIEW "\x1b[2J\xff\xfe\n", "x.nff:8: ", "unknown entity '\\x1B[2J\\xFF\\xFE'", NULL,
            NULL);
    nff_bad(VIEW "s 0 0 \xc3\xa9\x07 1\n", "x.nff:8: ", "found '\xc3\xa9\\x07'", NULL, NULL);
    nff_bad(VIEW "q0123456789012345678901234567890123456789xyz\n",
            "x.nff:8: ", "'q012345678901234567890123456789012345678...'", NULL, NULL);
    json_bad("{\n" JCAM ",\n\"\\u001b[2J\": 1}", "x.json:3: ", "unknown key \"\\x1B[2J\"", NULL,
             NULL);
    json_bad("{\n" JCAM ",\n\"materials\": {\"\xe2\x98\x83\\u0007\": {\"p\": -1}}}",
             "x.json:3: ", "materials.\xe2\x98\x83\\x07.p", NULL, NULL);
    json_bad("{\n\x7f\x02}", "x.json:2: ", "syntax error near '", "\\x02}'", NULL);
    /* a byte order mark is not an entity */
    parse_ok(nff_parse, "\xef\xbb\xbf" VIEW, "bom.nff", &s);
    scene_free(&s);
    parse_ok(json_scene_parse, "\xef\xbb\xbf{" JCAM "}", "bom.json", &s);
    scene_free(&s);
    nff_bad("  \n\t\r\n", "x.nff:", "empty file", NULL, NULL);
}

/* Materials under thousands of keys: duplicates found in O(n log n), at the right line. */
static void test_json_many_keys(void **state)
{
    const int n = 50000;
    size_t cap = (size_t)n * 32 + 256, len = 0;
    char *text = malloc(cap);
    double t0;
    int i;
    (void)state;
    assert_non_null(text);
    len += (size_t)snprintf(text + len, cap - len, "{" JCAM ",\n\"materials\": {");
    for (i = 0; i < n; i++)
        len += (size_t)snprintf(text + len, cap - len, "%s\"m%d\": {}", i ? ",\n" : "", i);
    snprintf(text + len, cap - len, ",\n\"m17\": {}}}");
    t0 = sys_now();
    json_bad(text, "x.json:50002: ", "materials: duplicate key \"m17\"", "first at line 19", NULL);
    print_message("%d materials, one duplicate: %.1f ms\n", n, (sys_now() - t0) * 1e3);
    assert_true(sys_now() - t0 < 2.0);
    /* the same in an object's own keys */
    json_bad("{\n" JCAM ",\n\"materials\": {\"m\": {}}, \"objects\": [\n"
             "{\"type\": \"sphere\", \"center\": [0, 0, 0], \"radius\": 1, \"material\": \"m\",\n"
             "\"radius\": 2}]}",
             "x.json:5: ", "objects[0]: duplicate key \"radius\"", "first at line 4", NULL);
    free(text);
}

/* Files: directories, unreadable files, devices, files too large to be a scene. */
static void test_bad_files(void **state)
{
    scene s;
    char err[512], path[64];
    int fd;
    (void)state;
    /* a directory, even one named like a scene */
    mkdir("build", 0777);
    mkdir("build/test-output", 0777);
    mkdir("build/test-output/dir.nff", 0777);
    scene_init(&s);
    assert_int_equal(scene_load("build/test-output/dir.nff", &s, err, sizeof err), -1);
    assert_non_null(strstr(err, "build/test-output/dir.nff: cannot read: Is a directory"));
    scene_free(&s);
    /* a path through a file */
    scene_init(&s);
    assert_int_equal(scene_load("scenes/default.json/x.nff", &s, err, sizeof err), -1);
    assert_non_null(strstr(err, "scenes/default.json/x.nff: cannot open: Not a directory"));
    scene_free(&s);
    /* an empty device; a device of NUL bytes, which is not read to its (missing) end */
    scene_init(&s);
    assert_int_equal(nff_load("/dev/null", &s, err, sizeof err), -1);
    assert_non_null(strstr(err, "/dev/null:1: empty file"));
    scene_free(&s);
    scene_init(&s);
    assert_int_equal(json_scene_load("/dev/zero", &s, err, sizeof err), -1);
    assert_non_null(strstr(err, "/dev/zero:1: unexpected NUL byte"));
    scene_free(&s);
    /* a read error after a successful open (as root too): /proc/self/mem at address 0 */
    scene_init(&s);
    if (access("/proc/self/mem", F_OK) != 0)
        print_message("no /proc/self/mem: the read error is not tested\n");
    else if (nff_load("/proc/self/mem", &s, err, sizeof err) == -1)
        assert_non_null(strstr(err, "/proc/self/mem: cannot read: "));
    else
        fail_msg("/proc/self/mem was read");
    scene_free(&s);
    /* no permission: root reads anything, so there only the read error above is tested */
    snprintf(path, sizeof path, "build/test-output/unreadable-XXXXXX");
    fd = mkstemp(path);
    assert_true(fd >= 0);
    assert_int_equal(write(fd, VIEW, strlen(VIEW)), (long)strlen(VIEW));
    close(fd);
    chmod(path, 0);
    scene_init(&s);
    if (geteuid() == 0) {
        print_message("running as root: mode 000 does not make a file unreadable; skipped\n");
    } else {
        assert_int_equal(nff_load(path, &s, err, sizeof err), -1);
        assert_non_null(strstr(err, "cannot open: Permission denied"));
    }
    scene_free(&s);
    unlink(path);
    /* larger than a scene may be: refused before reading (a sparse file: no disk used) */
    snprintf(path, sizeof path, "build/test-output/huge-XXXXXX");
    fd = mkstemp(path);
    assert_true(fd >= 0);
    assert_int_equal(ftruncate(fd, (off_t)CW_MAX_FILE_BYTES + 1), 0);
    close(fd);
    scene_init(&s);
    assert_int_equal(nff_load(path, &s, err, sizeof err), -1);
    assert_non_null(strstr(err, "file too large"));
    scene_free(&s);
    unlink(path);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_nff_entities),
        cmocka_unit_test(test_nff_camera),
        cmocka_unit_test(test_nff_lights),
        cmocka_unit_test(test_nff_whitespace),
        cmocka_unit_test(test_nff_load_files),
        cmocka_unit_test(test_spd_tetra),
        cmocka_unit_test(test_spd_all),
        cmocka_unit_test(test_nff_bad_entity),
        cmocka_unit_test(test_nff_bad_counts),
        cmocka_unit_test(test_nff_bad_numbers),
        cmocka_unit_test(test_nff_bad_polygons),
        cmocka_unit_test(test_nff_bad_view),
        cmocka_unit_test(test_json_all),
        cmocka_unit_test(test_json_projections),
        cmocka_unit_test(test_json_shipped),
        cmocka_unit_test(test_json_bad_syntax),
        cmocka_unit_test(test_json_bad_keys),
        cmocka_unit_test(test_json_bad_values),
        cmocka_unit_test(test_json_bad_camera),
        cmocka_unit_test(test_json_bad_objects),
        cmocka_unit_test(test_json_more_objects),
        cmocka_unit_test(test_json_lines),
        cmocka_unit_test(test_nul_byte),
        cmocka_unit_test(test_fixture_files),
        cmocka_unit_test(test_nff_bad_nonfinite),
        cmocka_unit_test(test_json_bad_nonfinite),
        cmocka_unit_test(test_tiny_numbers),
        cmocka_unit_test(test_bad_image_size),
        cmocka_unit_test(test_nff_bad_absurd_counts),
        cmocka_unit_test(test_bad_camera_vectors),
        cmocka_unit_test(test_nff_bad_degenerate),
        cmocka_unit_test(test_binary_garbage),
        cmocka_unit_test(test_json_many_keys),
        cmocka_unit_test(test_bad_files),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
