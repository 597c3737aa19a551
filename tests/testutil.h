/* Shared helpers for the cmocka suites. */
#ifndef CW_TESTUTIL_H
#define CW_TESTUTIL_H

#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "render.h"
#include "render_debug.h"
#include "scene.h"
#include "scene_geom.h"
#include "types.h"

/* splitmix64: the same random numbers on every machine. */
static uint64_t tu_rng_state;

static inline void tu_rng_seed(uint64_t seed)
{
    tu_rng_state = seed;
}

static inline uint64_t tu_rng_next(void)
{
    uint64_t z = (tu_rng_state += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
}

/* A float vector as a scene position (scene.h keeps positions in double). */
static inline vec3d tu_d(vec3f a)
{
    return vec3d_make(a.x, a.y, a.z);
}

/* Scenes built in code: one primitive appended to s. */
static inline void tu_add_sphere(scene *s, double x, double y, double z, double r, int mat)
{
    scene_sphere sp;
    sp.center = vec3d_make(x, y, z);
    sp.radius = (float)r;
    sp.material = mat;
    assert_true(scene_push(&s->spheres, &sp, sizeof sp) >= 0);
}

static inline void tu_add_triangle(scene *s, vec3f a, vec3f b, vec3f c, int mat)
{
    scene_triangle t;
    memset(&t, 0, sizeof t);
    t.p[0] = tu_d(a);
    t.p[1] = tu_d(b);
    t.p[2] = tu_d(c);
    t.material = mat;
    assert_true(scene_push(&s->triangles, &t, sizeof t) >= 0);
}

static inline void tu_add_polygon(scene *s, const vec3f *v, int n, int mat)
{
    scene_polygon p;
    int i;
    p.first = (int)s->poly_verts.count;
    p.count = n;
    p.material = mat;
    for (i = 0; i < n; i++) {
        vec3d q = tu_d(v[i]);
        assert_true(scene_push(&s->poly_verts, &q, sizeof q) >= 0);
    }
    assert_true(scene_push(&s->polygons, &p, sizeof p) >= 0);
}

/* An eye ray (depth 1, weight 1, no skip) from o along d (normalised here, in double). */
static inline cw_ray tu_make_ray(double ox, double oy, double oz, double dx, double dy, double dz)
{
    cw_ray r;
    double n = sqrt(dx * dx + dy * dy + dz * dz);
    memset(&r, 0, sizeof r);
    r.origin.x = (float)ox;
    r.origin.y = (float)oy;
    r.origin.z = (float)oz;
    r.dir.x = (float)(dx / n);
    r.dir.y = (float)(dy / n);
    r.dir.z = (float)(dz / n);
    r.weight.x = r.weight.y = r.weight.z = 1;
    r.depth = 1;
    return r;
}

/* The base scene of the kernel suites: a camera at (0, 0, eye_z) with basis x, y, z (w =
 * +z, looking down -z), window [-1,1]^2, d = 1; w x h pixels; nothing else. */
static inline void tu_base_scene(scene *s, enum scene_projection proj, float eye_z, int w, int h)
{
    scene_init(s);
    s->camera.projection = proj;
    s->camera.eye = vec3d_make(0, 0, eye_z);
    s->camera.u = vec3f_make(1, 0, 0);
    s->camera.v = vec3f_make(0, 1, 0);
    s->camera.w = vec3f_make(0, 0, 1);
    s->camera.l = -1;
    s->camera.r = 1;
    s->camera.b = -1;
    s->camera.t = 1;
    s->camera.d = 1;
    s->camera.dir = vec3f_make(0, 0, -1);
    s->width = w;
    s->height = h;
}

/* Appends a material; returns its index. */
static inline int tu_add_material(scene *s, vec3f ka, vec3f kd, vec3f ks, vec3f km, vec3f kt,
                                  float ior, float p)
{
    scene_material m;
    memset(&m, 0, sizeof m);
    m.ka = ka;
    m.kd = kd;
    m.ks = ks;
    m.km = km;
    m.kt = kt;
    m.ior = ior;
    m.p = p;
    return (int)scene_push(&s->materials, &m, sizeof m);
}

static inline void tu_add_light(scene *s, vec3f pos, vec3f intensity)
{
    scene_light l;
    l.position = tu_d(pos);
    l.intensity = intensity;
    assert_true(scene_push(&s->lights, &l, sizeof l) >= 0);
}

/* Finishes s at its own size and uploads it to r; a failure fails the test. */
static inline void tu_upload(renderer *r, scene *s)
{
    char e[2048];
    if (scene_finish(s, 0, 0, 0, e, sizeof e) != 0 || renderer_set_scene(r, s, e, sizeof e) != 0)
        fail_msg("%s", e);
}

/* The renderer fixture of the kernel suites: a renderer on the default device (PoCL),
 * made before the group (printing "device: NAME" when show_device is set) and destroyed
 * after it. Returns 0, or -1 with the reason on stderr (the group then fails). */
static inline int tu_renderer_open(renderer **r, int show_device)
{
    char e[2048];
    if (renderer_create(r, NULL, e, sizeof e) != 0) {
        fprintf(stderr, "renderer_create: %s\n", e);
        return -1;
    }
    if (show_device)
        printf("device: %s\n", renderer_device_name(*r));
    return 0;
}

static inline int tu_renderer_close(renderer **r)
{
    renderer_destroy(*r);
    *r = NULL;
    return 0;
}

/* A suite's group fixture: defines `static renderer *R` and the cmocka group functions
 * setup() and teardown() that open and close it (tu_renderer_open). With world_origin set,
 * the kernels see world coordinates (renderer_debug_world_origin): for the suites that give
 * the kernels rays in world coordinates through the test hooks, or expect them back. */
#define TU_RENDERER_FIXTURE_AT(show_device, world_origin)                                          \
    static renderer *R;                                                                            \
    static int setup(void **state)                                                                 \
    {                                                                                              \
        (void)state;                                                                               \
        if (tu_renderer_open(&R, show_device) != 0)                                                \
            return -1;                                                                             \
        renderer_debug_world_origin(R, world_origin);                                              \
        return 0;                                                                                  \
    }                                                                                              \
    static int teardown(void **state)                                                              \
    {                                                                                              \
        (void)state;                                                                               \
        return tu_renderer_close(&R);                                                              \
    }
#define TU_RENDERER_FIXTURE(show_device) TU_RENDERER_FIXTURE_AT(show_device, 0)

#endif
