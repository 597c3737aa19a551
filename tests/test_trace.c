/* The tracing features of the renderer, on the real kernels on PoCL:
 * - the BVH: closest hit (renderer_intersect) and any hit (renderer_occluded) on random
 *   scenes of spheres, triangles, polygons and cones equal a brute-force loop over every
 *   primitive, run on the host with the kernels' own intersection functions
 *   (kernels/prim.h compiles as C99);
 * - refraction: a glass slab seen by an orthographic camera shifts a sharp edge by
 *   t sin(theta - theta_r) / cos(theta_r), the same at any distance (the rays leave
 *   parallel); total internal reflection in a prism sends the (km + kt)-weighted ray on;
 * - cones: closed-form cases (cylinder, cone, open ends, negative radii, a ray parallel
 *   to the side, degenerate cones) and random rays against a double-precision solver;
 * - spheres visible from inside only (a negative radius): seen from outside and from
 *   inside, and a light inside one (shadow rays);
 * - specialised builds: the feature flags follow the scene, forced flags really remove
 *   code, bad flags fail with the build log;
 * - ray statistics and the SPD corner mode against counts and images made on the host.
 * Every test prints the figures it measures. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "testutil.h"

#include "devscene.h"
#include "image.h"
#include "prim.h"
#include "render.h"
#include "render_debug.h"
#include "scene.h"
#include "scene_load.h"

#define PI 3.14159265358979323846

TU_RENDERER_FIXTURE_AT(1, 1) /* rays in world coordinates */
static char err[2048];

/* ======================================================================================== */
/* Helpers                                                                                  */

/* uniform in [0, 1) */
static double rnd(void)
{
    return (double)(tu_rng_next() >> 11) * (1.0 / 9007199254740992.0);
}

static double rnd_range(double a, double b)
{
    return a + (b - a) * rnd();
}

static int rnd_int(int n)
{
    return (int)(tu_rng_next() % (uint64_t)n);
}

/* A uniformly distributed unit vector. */
static void rnd_unit(double d[3])
{
    double len;
    do {
        d[0] = rnd_range(-1, 1);
        d[1] = rnd_range(-1, 1);
        d[2] = rnd_range(-1, 1);
        len = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    } while (len < 0.1 || len > 1.0);
    d[0] /= len;
    d[1] /= len;
    d[2] /= len;
}

/* Every test starts here: the settings, and no extra build options. */
static void settings(int spd, int stats, int precision)
{
    render_settings st;
    unsetenv("CLWHITTED_BUILD_OPTIONS");
    render_settings_default(&st);
    st.spd = spd;
    st.stats = stats;
    st.precision = precision;
    if (renderer_set_settings(R, &st, err, sizeof err) != 0)
        fail_msg("%s", err);
}

/* An orthographic camera at (0, 0, 20) looking down -z, window [-1,1]^2. */
static void base_scene(scene *s, int w, int h)
{
    tu_base_scene(s, SCENE_ORTHOGRAPHIC, 20, w, h);
}

static vec3f grey(float g)
{
    return vec3f_make(g, g, g);
}

#define add_material tu_add_material

/* ka only: with ambient light 1 and no lights a surface shows exactly its ka. */
static int add_flat(scene *s, vec3f ka)
{
    return add_material(s, ka, grey(0), grey(0), grey(0), grey(0), 1, 1);
}

/* A quadrilateral face whose polygon normal points to the `outward` side (the vertex
 * order is reversed when needed): refraction decides inside/outside from it. */
static void add_face(scene *s, const vec3f q[4], vec3f outward, int mat)
{
    double n[3], off;
    int axis;
    vec3d v[4];
    vec3f vf[4];
    int i;
    for (i = 0; i < 4; i++)
        v[i] = tu_d(q[i]);
    assert_int_equal(scene_polygon_plane(v, 4, NULL, n, &off, &axis), 0);
    if (n[0] * outward.x + n[1] * outward.y + n[2] * outward.z < 0)
        for (i = 0; i < 4; i++)
            v[i] = tu_d(q[3 - i]);
    assert_int_equal(scene_polygon_plane(v, 4, NULL, n, &off, &axis), 0);
    assert_true(n[0] * outward.x + n[1] * outward.y + n[2] * outward.z > 0);
    for (i = 0; i < 4; i++)
        vf[i] = vec3f_make((float)v[i].x, (float)v[i].y, (float)v[i].z);
    tu_add_polygon(s, vf, 4, mat);
}

static void add_cone(scene *s, vec3f base, float r0, vec3f apex, float r1, int mat)
{
    scene_cone c;
    c.base = tu_d(base);
    c.apex = tu_d(apex);
    c.base_radius = r0;
    c.apex_radius = r1;
    c.material = mat;
    assert_true(scene_push(&s->cones, &c, sizeof c) >= 0);
}

#define add_light tu_add_light

static void upload(scene *s)
{
    tu_upload(R, s);
}

static void render(image *img)
{
    if (renderer_render(R, img, err, sizeof err) != 0)
        fail_msg("%s", err);
}

static void assert_near(double got, double want, double tol, const char *what)
{
    if (!(fabs(got - want) <= tol))
        fail_msg("%s: got %.9g, want %.9g (tolerance %g)", what, got, want, tol);
}

#define make_ray tu_make_ray

static void intersect(cw_ray *rays, int n, cw_hit *hits)
{
    int i;
    for (i = 0; i < n; i++)
        rays[i].pixel = i;
    if (renderer_intersect(R, rays, n, hits, err, sizeof err) != 0)
        fail_msg("%s", err);
}

/* The options of the program built last must contain each of the words. */
static void expect_options(const char *const *words, int n, const char *what)
{
    const char *opt = renderer_build_options(R);
    int i;
    printf("  %s: %s\n", what, opt);
    for (i = 0; i < n; i++) {
        /* whole words: "-DCW_HAS_CONES=1" must not match "-DCW_HAS_CONES=10" */
        const char *p = opt;
        size_t len = strlen(words[i]);
        int found = 0;
        while ((p = strstr(p, words[i])) != NULL) {
            if ((p == opt || p[-1] == ' ') && (p[len] == ' ' || p[len] == '\0')) {
                found = 1;
                break;
            }
            p += len;
        }
        if (!found)
            fail_msg("%s: build options \"%s\" lack \"%s\"", what, opt, words[i]);
    }
}

/* ======================================================================================== */
/* Host copies of the device primitives, and brute force                                   */

/* The device arrays as the renderer builds them (host/devscene.c): the same indices. */
static void host_convert(const scene *s, devscene *h)
{
    if (devscene_convert(s, NULL, h, err, sizeof err) != 0)
        fail_msg("%s", err);
}

/* One primitive, with the kernels' own function: 1 and *t on a hit in (tmin, tmax). */
static int host_hit(const devscene *h, int kind, int i, const cw_rayinfo *ri, float tmax, float *t)
{
    float u, v;
    switch (kind) {
    case CW_PRIM_SPHERE:
        return isect_sphere(&h->sph[i], ri->o, ri->d, 0.0f, tmax, t);
    case CW_PRIM_TRIANGLE:
        return isect_triangle(&h->tri[i], ri, 0.0f, tmax, t, &u, &v);
    case CW_PRIM_POLYGON: {
        /* every edge, not the kernel's edge bands: the brute force checks those too */
        cw_polygon pg = h->pg[i];
        pg.band_count = 0;
        return isect_polygon(&pg, h->verts, NULL, ri->o, ri->d, 0.0f, tmax, t);
    }
    default:
        return isect_cone(&h->cones[i], ri->o, ri->d, 0.0f, tmax, t);
    }
}

static int host_count(const devscene *h, int kind)
{
    return kind == CW_PRIM_SPHERE     ? h->nsph
           : kind == CW_PRIM_TRIANGLE ? h->ntri
           : kind == CW_PRIM_POLYGON  ? h->npg
                                      : h->ncone;
}

/* Closest hit over every primitive (never skip - 1), in (0, CW_FAR) as the kernel. */
static cw_hit brute_closest(const devscene *h, const cw_ray *ray)
{
    cw_rayinfo ri = isect_rayinfo(v3_from4(ray->origin), v3_from4(ray->dir));
    cw_hit best;
    float tmax = CW_FAR, t;
    int kind, i;
    memset(&best, 0, sizeof best);
    best.kind = CW_PRIM_NONE;
    best.index = -1;
    best.t = CW_FAR;
    for (kind = CW_PRIM_SPHERE; kind <= CW_PRIM_CONE; kind++)
        for (i = 0; i < host_count(h, kind); i++)
            if (CW_REF(kind, i) + 1 != ray->skip && host_hit(h, kind, i, &ri, tmax, &t)) {
                tmax = t;
                best.t = t;
                best.kind = kind;
                best.index = i;
            }
    return best;
}

/* Any hit in (0, tmax) (never skip - 1). */
static int brute_any(const devscene *h, const cw_shadow_ray *sr)
{
    cw_rayinfo ri = isect_rayinfo(v3_from4(sr->origin), v3_from4(sr->dir));
    float t;
    int kind, i;
    for (kind = CW_PRIM_SPHERE; kind <= CW_PRIM_CONE; kind++)
        for (i = 0; i < host_count(h, kind); i++)
            if (CW_REF(kind, i) + 1 != sr->skip && host_hit(h, kind, i, &ri, sr->origin.w, &t))
                return 1;
    return 0;
}

/* ======================================================================================== */
/* 1. BVH traversal against brute force                                                    */

static vec3f vd(const double c[3], const double e1[3], const double e2[3], double a, double b)
{
    return vec3f_make((float)(c[0] + a * e1[0] + b * e2[0]), (float)(c[1] + a * e1[1] + b * e2[1]),
                      (float)(c[2] + a * e1[2] + b * e2[2]));
}

/* An orthonormal pair perpendicular to the unit n. */
static void perp_basis(const double n[3], double e1[3], double e2[3])
{
    double len;
    if (fabs(n[0]) < 0.6) {
        e1[0] = 0;
        e1[1] = n[2];
        e1[2] = -n[1];
    } else {
        e1[0] = -n[2];
        e1[1] = 0;
        e1[2] = n[0];
    }
    len = sqrt(e1[0] * e1[0] + e1[1] * e1[1] + e1[2] * e1[2]);
    e1[0] /= len;
    e1[1] /= len;
    e1[2] /= len;
    e2[0] = n[1] * e1[2] - n[2] * e1[1];
    e2[1] = n[2] * e1[0] - n[0] * e1[2];
    e2[2] = n[0] * e1[1] - n[1] * e1[0];
}

/* The polygon kinds of random scenes. */
enum { POLY_CONVEX, POLY_STAR, POLY_L, POLY_POINT, POLY_LINE };

static void random_polygon(scene *s, const double c[3], double size, int mat, int type)
{
    vec3f v[160];
    double n[3], e1[3], e2[3], ang[16];
    int k, i;
    rnd_unit(n);
    perp_basis(n, e1, e2);
    if (type == POLY_CONVEX) {
        /* points on an ellipse at sorted random angles */
        double ra = size * rnd_range(0.4, 1.0), rb = size * rnd_range(0.4, 1.0);
        k = 3 + rnd_int(6);
        for (i = 0; i < k; i++)
            ang[i] = rnd_range(0, 2 * PI);
        for (i = 1; i < k; i++) { /* insertion sort */
            double a = ang[i];
            int j = i - 1;
            while (j >= 0 && ang[j] > a) {
                ang[j + 1] = ang[j];
                j--;
            }
            ang[j + 1] = a;
        }
        for (i = 0; i < k; i++)
            v[i] = vd(c, e1, e2, ra * cos(ang[i]), rb * sin(ang[i]));
    } else if (type == POLY_STAR) {
        /* half of them gear-like, 32 to 142 vertices: the kernels test those through
         * edge bands, the brute force edge by edge */
        k = rnd_int(2) ? 2 * (16 + rnd_int(56)) : 2 * (3 + rnd_int(4));
        for (i = 0; i < k; i++) {
            double r = (i % 2 ? 0.35 : 1.0) * size;
            double a = 2 * PI * (i + rnd_range(-0.2, 0.2)) / k;
            v[i] = vd(c, e1, e2, r * cos(a), r * sin(a));
        }
    } else if (type == POLY_L) {
        static const double L[6][2] = {{0, 0}, {1, 0}, {1, 0.35}, {0.35, 0.35}, {0.35, 1}, {0, 1}};
        k = 6;
        for (i = 0; i < k; i++)
            v[i] = vd(c, e1, e2, size * (L[i][0] - 0.5), size * (L[i][1] - 0.5));
    } else if (type == POLY_POINT) { /* every vertex the same point: no area, dropped */
        k = 4;
        for (i = 0; i < k; i++)
            v[i] = vd(c, e1, e2, 0, 0);
    } else { /* collinear in float: dropped or a sliver, the same on both sides */
        k = 4;
        for (i = 0; i < k; i++)
            v[i] = vd(c, e1, e2, size * (i - 1.5), 0);
    }
    tu_add_polygon(s, v, k, mat);
}

/* n random primitives (about a quarter of each kind, a few degenerate ones and exact
 * duplicates) in [-E, E]^3, sized so that they overlap at every n. */
static void random_scene(scene *s, int n, uint64_t seed, double E)
{
    double size = 2.5 * E / cbrt((double)n);
    int i, mat;
    base_scene(s, 1, 1);
    mat = add_flat(s, grey(1));
    tu_rng_seed(seed);
    for (i = 0; i < n; i++) {
        double c[3], sz = size * rnd_range(0.2, 1.0), d[3];
        int kind = i < 4 ? i : rnd_int(4), degenerate = i >= 4 && rnd_int(100) == 0;
        c[0] = rnd_range(-E, E);
        c[1] = rnd_range(-E, E);
        c[2] = rnd_range(-E, E);
        if (i >= 4 && rnd_int(100) == 0) { /* an exact duplicate of the previous primitive */
            if (s->spheres.count && kind == 0) {
                scene_sphere sp = SCENE_AT(s->spheres, scene_sphere, s->spheres.count - 1);
                assert_true(scene_push(&s->spheres, &sp, sizeof sp) >= 0);
                continue;
            }
            if (s->triangles.count && kind == 1) {
                scene_triangle t = SCENE_AT(s->triangles, scene_triangle, s->triangles.count - 1);
                assert_true(scene_push(&s->triangles, &t, sizeof t) >= 0);
                continue;
            }
        }
        if (kind == 0) {
            tu_add_sphere(s, c[0], c[1], c[2],
                          degenerate ? 0.0 : (rnd_int(10) == 0 ? -0.5 : 0.5) * sz, mat);
        } else if (kind == 1) {
            vec3f p[3];
            int k;
            for (k = 0; k < 3; k++) {
                rnd_unit(d);
                p[k] = vec3f_make((float)(c[0] + sz * d[0]), (float)(c[1] + sz * d[1]),
                                  (float)(c[2] + sz * d[2]));
            }
            if (degenerate) /* collinear: kept, never hit */
                p[2] = vec3f_make(2 * p[1].x - p[0].x, 2 * p[1].y - p[0].y, 2 * p[1].z - p[0].z);
            tu_add_triangle(s, p[0], p[1], p[2], mat);
        } else if (kind == 2) {
            int type = degenerate ? (rnd_int(2) ? POLY_POINT : POLY_LINE) : rnd_int(3);
            random_polygon(s, c, 0.7 * sz, mat, type);
        } else {
            double h = sz * rnd_range(0.3, 1.5), r0, r1;
            vec3f base = vec3f_make((float)c[0], (float)c[1], (float)c[2]), apex;
            int shape = rnd_int(4);
            rnd_unit(d);
            apex = vec3f_make((float)(c[0] + h * d[0]), (float)(c[1] + h * d[1]),
                              (float)(c[2] + h * d[2]));
            r0 = 0.4 * sz * rnd_range(0.2, 1.0);
            r1 = shape == 0 ? r0 : shape == 1 ? 0.0 : 0.4 * sz * rnd_range(0.0, 1.0);
            if (rnd_int(10) == 0) { /* NFF: negative radii */
                r0 = -r0;
                r1 = -r1;
            }
            if (degenerate) {
                if (rnd_int(2))
                    apex = base; /* zero height */
                else
                    r0 = r1 = 0; /* no radius */
            }
            add_cone(s, base, (float)r0, apex, (float)r1, mat);
        }
    }
}

/* A random ray: from inside the scene's box, or from outside towards a point of it, with
 * a few axis-aligned directions and directions with a zero component; 1 in 10 skips a
 * random primitive. */
static void random_ray(const devscene *h, double E, double o[3], double d[3], int *skip)
{
    int how = rnd_int(20), k;
    if (rnd_int(2)) {
        for (k = 0; k < 3; k++)
            o[k] = rnd_range(-E, E);
        rnd_unit(d);
    } else {
        double u[3], len = 0;
        rnd_unit(u);
        for (k = 0; k < 3; k++) {
            o[k] = 2.5 * E * u[k];
            d[k] = rnd_range(-E, E) - o[k];
            len += d[k] * d[k];
        }
        for (k = 0; k < 3; k++)
            d[k] /= sqrt(len);
    }
    if (how == 0) { /* along an axis */
        k = rnd_int(3);
        d[0] = d[1] = d[2] = 0;
        d[k] = rnd_int(2) ? 1 : -1;
    } else if (how == 1) { /* one zero component */
        double len;
        d[rnd_int(3)] = 0;
        len = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
        for (k = 0; k < 3; k++)
            d[k] /= len;
    }
    *skip = 0;
    if (rnd_int(10) == 0) {
        int kind = 1 + rnd_int(4), cnt = host_count(h, kind);
        if (cnt > 0)
            *skip = CW_REF(kind, rnd_int(cnt)) + 1;
    }
}

static const char *kind_name(int kind)
{
    static const char *const names[] = {"none", "sphere", "triangle", "polygon", "cone"};
    return kind >= 0 && kind <= 4 ? names[kind] : "?";
}

static void bvh_case(int nprim, uint64_t seed, int nrays)
{
    const double E = 10;
    scene s;
    devscene h;
    cw_ray *rays = calloc((size_t)nrays, sizeof *rays);
    cw_hit *hits = calloc((size_t)nrays, sizeof *hits);
    cw_shadow_ray *sr = calloc((size_t)nrays, sizeof *sr);
    int *blocked = calloc((size_t)nrays, sizeof *blocked);
    int i, nhit = 0, ties = 0, bad = 0, nblocked = 0, bad_any = 0, nskip = 0;
    int by_kind[5] = {0, 0, 0, 0, 0};
    assert_true(rays && hits && sr && blocked);

    random_scene(&s, nprim, seed, E);
    host_convert(&s, &h);
    upload(&s);
    if (nprim == 10) {
        static const char *const want[] = {"-DCW_HAS_SPHERES=1",  "-DCW_HAS_TRIANGLES=1",
                                           "-DCW_HAS_POLYGONS=1", "-DCW_HAS_CONES=1",
                                           "-DCW_HAS_MIRRORS=0",  "-DCW_HAS_REFRACTION=0"};
        expect_options(want, 6, "every primitive kind, no mirrors");
    }
    tu_rng_seed(seed * 7919 + 1);
    for (i = 0; i < nrays; i++) {
        double o[3], d[3];
        int skip;
        random_ray(&h, E, o, d, &skip);
        rays[i] = make_ray(o[0], o[1], o[2], d[0], d[1], d[2]);
        rays[i].skip = skip;
        nskip += skip != 0;
        /* shadow rays: the same lines, a random length (some end inside objects) */
        memset(&sr[i], 0, sizeof sr[i]);
        sr[i].origin = rays[i].origin;
        sr[i].origin.w = (float)(rnd_int(4) == 0 ? rnd_range(0, 1) : rnd_range(0, 5 * E));
        sr[i].dir = rays[i].dir;
        sr[i].skip = skip;
    }
    intersect(rays, nrays, hits);
    if (renderer_occluded(R, sr, nrays, blocked, err, sizeof err) != 0)
        fail_msg("%s", err);

    for (i = 0; i < nrays; i++) {
        cw_hit b = brute_closest(&h, &rays[i]);
        int any = brute_any(&h, &sr[i]);
        if (hits[i].kind != b.kind || hits[i].index != b.index || hits[i].t != b.t) {
            /* a tie: the kernel's primitive is hit at exactly the same t */
            cw_rayinfo ri = isect_rayinfo(v3_from4(rays[i].origin), v3_from4(rays[i].dir));
            float t = 0;
            int tie = hits[i].kind != CW_PRIM_NONE && b.kind != CW_PRIM_NONE && hits[i].t == b.t &&
                      hits[i].index >= 0 && hits[i].index < host_count(&h, hits[i].kind) &&
                      CW_REF(hits[i].kind, hits[i].index) + 1 != rays[i].skip &&
                      host_hit(&h, hits[i].kind, hits[i].index, &ri, CW_FAR, &t) && t == b.t;
            if (tie) {
                ties++;
            } else {
                if (bad < 5)
                    printf("    closest MISMATCH ray %d o (%.9g %.9g %.9g) d (%.9g %.9g %.9g) "
                           "skip %d: kernel %s %d t %.9g, brute force %s %d t %.9g\n",
                           i, rays[i].origin.x, rays[i].origin.y, rays[i].origin.z, rays[i].dir.x,
                           rays[i].dir.y, rays[i].dir.z, rays[i].skip, kind_name(hits[i].kind),
                           hits[i].index, hits[i].t, kind_name(b.kind), b.index, b.t);
                bad++;
            }
        }
        if (b.kind != CW_PRIM_NONE) {
            nhit++;
            by_kind[b.kind]++;
        }
        if (blocked[i] != any) {
            if (bad_any < 5)
                printf("    any-hit MISMATCH ray %d o (%.9g %.9g %.9g) d (%.9g %.9g %.9g) tmax "
                       "%.9g skip %d: kernel %d, brute force %d\n",
                       i, sr[i].origin.x, sr[i].origin.y, sr[i].origin.z, sr[i].dir.x, sr[i].dir.y,
                       sr[i].dir.z, sr[i].origin.w, sr[i].skip, blocked[i], any);
            bad_any++;
        }
        nblocked += any;
    }
    printf("  %6d primitives (%d sph, %d tri, %d poly, %d cone; %d degenerate dropped), seed "
           "%d:\n    closest: %d rays (%d with skip), %d hits (%d sph, %d tri, %d poly, %d "
           "cone), %d ties, %d mismatches\n    any hit: %d shadow rays, %d blocked, %d "
           "mismatches\n",
           nprim, h.nsph, h.ntri, h.npg, h.ncone, h.dropped, (int)seed, nrays, nskip, nhit,
           by_kind[1], by_kind[2], by_kind[3], by_kind[4], ties, bad, nrays, nblocked, bad_any);
    if (bad || bad_any)
        fail_msg("%d primitives: %d closest-hit and %d any-hit mismatches", nprim, bad, bad_any);
    /* the test must test something: hits of every kind, misses, and both answers of any */
    assert_true(by_kind[1] > 0 && by_kind[2] > 0 && by_kind[3] > 0 && by_kind[4] > 0);
    assert_true(nhit < nrays);
    assert_true(nblocked > 0 && nblocked < nrays);
    devscene_free(&h);
    scene_free(&s);
    free(rays);
    free(hits);
    free(sr);
    free(blocked);
}

static void test_bvh_brute_force(void **state)
{
    (void)state;
    settings(0, 0, RENDER_ROBUST);
    bvh_case(10, 1, 4000);
    bvh_case(150, 2, 4000);
    bvh_case(1500, 3, 3000);
    bvh_case(6000, 4, 2000);
    bvh_case(20000, 5, 1000);
}

/* ======================================================================================== */
/* 2. Refraction                                                                            */

/* A slab of glass (kt 1, ior 1.5, nothing else) between two parallel square faces,
 * tilted by theta about the y axis (front normal n = (sin theta, 0, cos theta)), covering
 * y > 0 only; behind it, at z = -Z, a target plane white (ka 1) for x < 0 and nothing
 * (black background) for x > 0. An orthographic camera looks down -z with ambient light 1:
 * rows with y < 0 see the edge at x = 0, rows with y > 0 see it through the slab. */
#define SLAB_NX 3200
#define SLAB_HALF 1.6

static void slab_scene(scene *s, double theta_deg, double thick, double Z)
{
    double th = theta_deg * PI / 180, n[3] = {sin(th), 0, cos(th)};
    double e1[3] = {cos(th), 0, -sin(th)}, e2[3] = {0, 1, 0};
    double c0[3] = {0, 0, 0}, c1[3];
    const double a = 8, top = 6;
    vec3f q[4], t[4];
    int glass, white, k;
    for (k = 0; k < 3; k++)
        c1[k] = c0[k] - thick * n[k];
    base_scene(s, SLAB_NX, 4);
    s->camera.l = (float)-SLAB_HALF;
    s->camera.r = (float)SLAB_HALF;
    s->ambient = grey(1);
    s->max_depth = 5;
    glass = add_material(s, grey(0), grey(0), grey(0), grey(0), grey(1), 1.5f, 1);
    white = add_flat(s, grey(1));
    q[0] = vd(c0, e1, e2, -a, 0);
    q[1] = vd(c0, e1, e2, a, 0);
    q[2] = vd(c0, e1, e2, a, top);
    q[3] = vd(c0, e1, e2, -a, top);
    add_face(s, q, vec3f_make((float)n[0], (float)n[1], (float)n[2]), glass);
    q[0] = vd(c1, e1, e2, -a, 0);
    q[1] = vd(c1, e1, e2, a, 0);
    q[2] = vd(c1, e1, e2, a, top);
    q[3] = vd(c1, e1, e2, -a, top);
    add_face(s, q, vec3f_make((float)-n[0], (float)-n[1], (float)-n[2]), glass);
    t[0] = vec3f_make(-30, -30, (float)-Z);
    t[1] = vec3f_make(0, -30, (float)-Z);
    t[2] = vec3f_make(0, 30, (float)-Z);
    t[3] = vec3f_make(-30, 30, (float)-Z);
    add_face(s, t, vec3f_make(0, 0, 1), white);
}

/* The edge of a row: white (1) pixels from the left, then black (0) ones; returns the x
 * of the boundary, l + pitch * (number of white pixels), within half a pixel. */
static double row_edge(const image *img, int row, const char *what)
{
    int i, nwhite = 0;
    double pitch = 2 * SLAB_HALF / SLAB_NX;
    for (i = 0; i < img->width; i++) {
        const float *p = &img->rgb[3 * ((size_t)row * img->width + i)];
        int white = p[0] > 0.5f;
        if (white && i != nwhite)
            fail_msg("%s: row %d is not a clean edge (white pixel %d after black)", what, row, i);
        /* kt = 1 on every face: nothing is lost through the glass */
        assert_near(p[0], white ? 1 : 0, 1e-6, what);
        assert_near(p[1], p[0], 0, what);
        nwhite += white;
    }
    if (nwhite == 0 || nwhite == img->width)
        fail_msg("%s: row %d has no edge in the window", what, row);
    return -SLAB_HALF + pitch * nwhite;
}

/* The shift of the edge, predicted: d = t sin(theta - theta_r) / cos(theta_r), towards
 * +x for theta > 0 (the ray bends towards -n inside: what it sees lies at smaller x).
 * Also computed by following the ray on the host with vector Snell, in double. */
static double slab_shift_formula(double theta_deg, double thick)
{
    double th = theta_deg * PI / 180, thr = asin(sin(th) / 1.5);
    return thick * sin(th - thr) / cos(thr);
}

static double slab_shift_traced(double theta_deg, double thick)
{
    double th = theta_deg * PI / 180, n[3] = {sin(th), 0, cos(th)}, d[3] = {0, 0, -1};
    double eta = 1 / 1.5, cosi = -(d[0] * n[0] + d[2] * n[2]);
    double k2 = 1 - eta * eta * (1 - cosi * cosi), td[3], t, p[3], q[3], e;
    int k;
    for (k = 0; k < 3; k++) /* transmitted direction, through the front face at the origin */
        td[k] = eta * d[k] + (eta * cosi - sqrt(k2)) * n[k];
    /* to the back face: n.(p - (-thick n)) = 0 */
    t = thick / -(td[0] * n[0] + td[1] * n[1] + td[2] * n[2]);
    for (k = 0; k < 3; k++)
        p[k] = t * td[k];
    /* leaving through the back face (outward normal -n): eta = 1.5, the normal facing
     * the ray is +n */
    cosi = -(td[0] * n[0] + td[1] * n[1] + td[2] * n[2]);
    k2 = 1 - 1.5 * 1.5 * (1 - cosi * cosi);
    for (k = 0; k < 3; k++)
        q[k] = 1.5 * td[k] + (1.5 * cosi - sqrt(k2)) * n[k];
    e = fabs(q[0] - d[0]) + fabs(q[1] - d[1]) + fabs(q[2] - d[2]);
    assert_true(e < 1e-12); /* parallel to the incoming ray */
    /* the ray entered at x = 0 and leaves at p.x: what it sees is at x = p.x, so the
     * picture of an edge at x = 0 moves to -p.x */
    return -p[0];
}

static void test_refraction_slab(void **state)
{
    static const double cases[][2] = {{0, 1},    {20, 1},   {45, 1},
                                      {60, 1.5}, {30, 0.5}, {-35, 1.25}}; /* theta, thickness */
    const double pitch = 2 * SLAB_HALF / SLAB_NX;
    size_t c;
    (void)state;
    settings(0, 0, RENDER_ROBUST);
    printf("  pixel pitch %.6g; edge positions within half a pixel\n", pitch);
    for (c = 0; c < sizeof cases / sizeof cases[0]; c++) {
        double theta = cases[c][0], thick = cases[c][1];
        double want = slab_shift_formula(theta, thick), traced = slab_shift_traced(theta, thick);
        double shifts[2];
        int zi;
        assert_near(traced, want, 1e-12, "the formula and the traced ray agree");
        for (zi = 0; zi < 2; zi++) {
            double Z = zi == 0 ? 10 : 40, open, through;
            char what[96];
            scene s;
            image img;
            slab_scene(&s, theta, thick, Z);
            upload(&s);
            if (c == 0 && zi == 0) {
                static const char *const opts[] = {"-DCW_HAS_SPHERES=0", "-DCW_HAS_POLYGONS=1",
                                                   "-DCW_HAS_MIRRORS=0", "-DCW_HAS_REFRACTION=1"};
                expect_options(opts, 4, "glass polygons");
            }
            render(&img);
            snprintf(what, sizeof what, "slab theta %g, thickness %g, target at z = -%g", theta,
                     thick, Z);
            /* rows 0 and 1 (y > 0) look through the slab, rows 2 and 3 do not */
            through = row_edge(&img, 0, what);
            assert_near(row_edge(&img, 1, what), through, 1e-9, what);
            open = row_edge(&img, 2, what);
            assert_near(row_edge(&img, 3, what), open, 1e-9, what);
            shifts[zi] = through - open;
            printf("  theta %6.1f, thickness %.2f, target z = -%2.0f: edge %+.6f without the "
                   "slab, %+.6f through it: shift %+.6f, predicted %+.6f (%.2f pixel off)\n",
                   theta, thick, Z, open, through, shifts[zi], want,
                   fabs(shifts[zi] - want) / pitch);
            /* the true edges are at 0 and at the predicted shift: a row's boundary is at
             * most half a pixel off (plus float rounding when an edge falls on a centre) */
            assert_near(open, 0, 0.5 * pitch + 2e-5, what);
            assert_near(through, want, 0.5 * pitch + 2e-5, what);
            image_free(&img);
            scene_free(&s);
        }
        /* leaving parallel: the shift does not depend on the distance to the target */
        assert_near(shifts[1], shifts[0], pitch, "the shift at 10 and at 40");
    }
}

/* A right prism of glass, its cross-section in the xz plane the triangle P (-1, 0),
 * Q (1, 0), S (-1, -2), extruded along y. A ray down -z enters PQ head-on, meets the
 * hypotenuse QS at 45 degrees (beyond the critical angle asin(1/1.5) = 41.8): total
 * internal reflection turns it to -x, and it leaves PS head-on towards a target at
 * x = -3. The target shows through kt (in) (km + kt) (reflection) kt (out). */
static void test_total_internal_reflection(void **state)
{
    static const float kt[3] = {0.5f, 0.6f, 0.7f}, km[3] = {0.2f, 0.1f, 0.05f};
    static const float kat[3] = {0.9f, 0.7f, 0.5f};
    static const int depths[] = {3, 4, 6};
    size_t di;
    (void)state;
    settings(0, 0, RENDER_ROBUST);
    for (di = 0; di < sizeof depths / sizeof depths[0]; di++) {
        scene s;
        image img;
        vec3f q[4];
        int glass, target, i, c;
        const float Y = 5;
        double want[3];
        base_scene(&s, 6, 3);
        s.camera.l = -0.9f;
        s.camera.r = 0.9f;
        s.camera.b = -0.5f;
        s.camera.t = 0.5f;
        s.ambient = grey(1);
        s.max_depth = depths[di];
        glass = add_material(&s, grey(0), grey(0), grey(0), vec3f_make(km[0], km[1], km[2]),
                             vec3f_make(kt[0], kt[1], kt[2]), 1.5f, 1);
        target = add_flat(&s, vec3f_make(kat[0], kat[1], kat[2]));
        q[0] = vec3f_make(-1, -Y, 0); /* PQ, outward +z */
        q[1] = vec3f_make(1, -Y, 0);
        q[2] = vec3f_make(1, Y, 0);
        q[3] = vec3f_make(-1, Y, 0);
        add_face(&s, q, vec3f_make(0, 0, 1), glass);
        q[0] = vec3f_make(1, -Y, 0); /* QS, outward (1, 0, -1) */
        q[1] = vec3f_make(-1, -Y, -2);
        q[2] = vec3f_make(-1, Y, -2);
        q[3] = vec3f_make(1, Y, 0);
        add_face(&s, q, vec3f_make(1, 0, -1), glass);
        q[0] = vec3f_make(-1, -Y, -2); /* SP, outward -x */
        q[1] = vec3f_make(-1, -Y, 0);
        q[2] = vec3f_make(-1, Y, 0);
        q[3] = vec3f_make(-1, Y, -2);
        add_face(&s, q, vec3f_make(-1, 0, 0), glass);
        q[0] = vec3f_make(-3, -Y, -4); /* the target, facing +x */
        q[1] = vec3f_make(-3, -Y, 2);
        q[2] = vec3f_make(-3, Y, 2);
        q[3] = vec3f_make(-3, Y, -4);
        add_face(&s, q, vec3f_make(1, 0, 0), target);
        upload(&s);
        render(&img);
        for (c = 0; c < 3; c++) /* depth 3 ends inside the glass (ka 0, black background) */
            want[c] = depths[di] < 4 ? 0 : (double)kat[c] * kt[c] * (km[c] + kt[c]) * kt[c];
        printf("  depth %d: pixel (%.6f %.6f %.6f), want (%.6f %.6f %.6f) [kt^3 would be "
               "%.6f, kt km kt %.6f]\n",
               depths[di], img.rgb[0], img.rgb[1], img.rgb[2], want[0], want[1], want[2],
               (double)kat[0] * kt[0] * kt[0] * kt[0], (double)kat[0] * kt[0] * km[0] * kt[0]);
        for (i = 0; i < img.width * img.height; i++)
            for (c = 0; c < 3; c++)
                assert_near(img.rgb[3 * i + c], want[c], 1e-6, "total internal reflection");
        image_free(&img);
        scene_free(&s);
    }
}

/* ======================================================================================== */
/* 3. Cones                                                                                 */

/* Double-precision reference for an open cone: the smallest t in (0, inf) with the point
 * on the surface and 0 <= h <= H; *margin: how far that decision is from flipping (the
 * distance of the roots from the ends, relative discriminant). Returns 0 for a miss. */
static int ref_cone(const double b[3], const double a[3], double H, double r0, double r1,
                    const double o[3], const double d[3], double *t_out, double *margin)
{
    double k = (r1 - r0) / H, ob[3], ho, dh, op[3], dp[3], rr, A, B, C, disc, roots[2];
    int i, n = 0;
    for (i = 0; i < 3; i++)
        ob[i] = o[i] - b[i];
    ho = ob[0] * a[0] + ob[1] * a[1] + ob[2] * a[2];
    dh = d[0] * a[0] + d[1] * a[1] + d[2] * a[2];
    for (i = 0; i < 3; i++) {
        op[i] = ob[i] - ho * a[i];
        dp[i] = d[i] - dh * a[i];
    }
    rr = r0 + k * ho;
    A = dp[0] * dp[0] + dp[1] * dp[1] + dp[2] * dp[2] - k * k * dh * dh;
    B = op[0] * dp[0] + op[1] * dp[1] + op[2] * dp[2] - k * dh * rr;
    C = op[0] * op[0] + op[1] * op[1] + op[2] * op[2] - rr * rr;
    *margin = 1e30;
    if (fabs(A) < 1e-9) {
        if (B == 0)
            return 0;
        roots[n++] = -C / (2 * B);
        *margin = fabs(A) * 1e3;
    } else {
        disc = B * B - A * C;
        *margin = fabs(disc) / (B * B + fabs(A * C) + 1e-300);
        if (disc < 0)
            return 0;
        roots[n++] = (-B - sqrt(disc)) / A;
        roots[n++] = (-B + sqrt(disc)) / A;
        if (roots[0] > roots[1]) {
            double tmp = roots[0];
            roots[0] = roots[1];
            roots[1] = tmp;
        }
    }
    for (i = 0; i < n; i++) {
        double t = roots[i], h = ho + t * dh, m = fmin(fabs(h), fabs(h - H));
        *margin = fmin(*margin, fmin(m, fabs(t)));
        if (t <= 0 || h < 0 || h > H || r0 + k * h < 0)
            continue;
        *t_out = t;
        return 1;
    }
    return 0;
}

static void test_cone_cases(void **state)
{
    scene s;
    cw_ray rays[12];
    cw_hit hits[12], neg[12];
    int m, i;
    const double r5 = sqrt(5.0), r2 = sqrt(2.0);
    (void)state;
    settings(0, 0, RENDER_ROBUST);

    /* a cylinder of radius 1 around the y axis, y in [-2, 2], open at both ends */
    base_scene(&s, 1, 1);
    m = add_flat(&s, grey(1));
    add_cone(&s, vec3f_make(0, -2, 0), 1, vec3f_make(0, 2, 0), 1, m);
    upload(&s);
    {
        static const char *const want[] = {"-DCW_HAS_SPHERES=0", "-DCW_HAS_TRIANGLES=0",
                                           "-DCW_HAS_POLYGONS=0", "-DCW_HAS_CONES=1"};
        expect_options(want, 4, "cones only");
    }
    rays[0] = make_ray(5, 0.5, 0, -1, 0, 0);   /* across the axis: t = 5 - 1 */
    rays[1] = make_ray(5, 0.5, 0.6, -1, 0, 0); /* off-centre: t = 5 - sqrt(1 - 0.36) */
    rays[2] = make_ray(0.3, -5, 0, 0, 1, 0);   /* along the axis, inside: no caps, no hit */
    rays[3] = make_ray(0, 3, 0, 1, -2, 0);     /* in through the open top: wall at (1, 1, 0) */
    rays[4] = make_ray(5, 2.1, 0, -1, 0, 0);   /* just past the top end: miss */
    rays[5] = make_ray(5, -2.1, 0, -1, 0, 0);  /* just past the bottom end: miss */
    rays[6] = make_ray(5, 1.9, 0, -1, 0, 0);   /* just inside the top end: t = 4 */
    rays[7] = make_ray(0.5, 0, 0, 1, 0, 0);    /* from inside: the wall at t = 0.5 */
    rays[8] = make_ray(1.5, -5, 0, 0, 1, 0);   /* parallel to the axis, outside: miss */
    rays[9] = make_ray(1, -5, 0, 0, 1, 0);     /* along the wall itself: miss (no area) */
    intersect(rays, 10, hits);
    {
        static const double want_t[10] = {4, 4.2, -1, 0, -1, -1, 4, 0.5, -1, -1};
        double wt[10];
        memcpy(wt, want_t, sizeof wt);
        wt[3] = r5;
        for (i = 0; i < 10; i++) {
            char what[64];
            printf("  cylinder ray %d: %s t %.7g, want %s %.7g\n", i, kind_name(hits[i].kind),
                   hits[i].t, wt[i] < 0 ? "miss" : "cone", wt[i] < 0 ? 0 : wt[i]);
            snprintf(what, sizeof what, "cylinder ray %d", i);
            assert_false(isnan(hits[i].t));
            if (wt[i] < 0) {
                assert_int_equal(hits[i].kind, CW_PRIM_NONE);
            } else {
                assert_int_equal(hits[i].kind, CW_PRIM_CONE);
                assert_int_equal(hits[i].index, 0);
                assert_near(hits[i].t, wt[i], 2e-6 * wt[i], what);
            }
        }
    }
    scene_free(&s);

    /* NFF: negative radii (inside visible) make the same surface */
    base_scene(&s, 1, 1);
    m = add_flat(&s, grey(1));
    add_cone(&s, vec3f_make(0, -2, 0), -1, vec3f_make(0, 2, 0), -1, m);
    upload(&s);
    intersect(rays, 10, neg);
    for (i = 0; i < 10; i++) {
        assert_int_equal(neg[i].kind, hits[i].kind);
        if (hits[i].kind != CW_PRIM_NONE)
            assert_true(neg[i].t == hits[i].t);
    }
    printf("  negative radii: the same 10 answers, bit for bit\n");
    scene_free(&s);

    /* a cone of base radius 1 at y = 0 and apex (0, 1, 0): radius 1 - y, its side at 45
     * degrees; first a degenerate cone of each kind, dropped: the real one is index 0 */
    base_scene(&s, 1, 1);
    m = add_flat(&s, grey(1));
    add_cone(&s, vec3f_make(0, 0, 3), 1, vec3f_make(0, 0, 3), 1, m); /* zero height */
    add_cone(&s, vec3f_make(0, 0, 3), 0, vec3f_make(0, 1, 3), 0, m); /* zero radii */
    add_cone(&s, vec3f_make(0, 0, 0), 1, vec3f_make(0, 1, 0), 0, m);
    upload(&s);
    rays[0] = make_ray(5, 0.5, 0, -1, 0, 0);    /* radius 0.5 at y = 0.5: t = 4.5 */
    rays[1] = make_ray(0.5, -0.5, 0, -1, 1, 0); /* parallel to the side x + y = 1: in through
                                                 * the open base, wall at (-0.5, 0.5, 0) */
    rays[2] = make_ray(5, 1.2, 0, -1, 0, 0);    /* above the apex: miss */
    rays[3] = make_ray(3, 0, 3.5, -1, 0, 0);    /* through the zero-height cone's place */
    rays[4] = make_ray(0, 0.5, 8, 0, 0, -1);    /* through the zero-radius cone, then the
                                                 * real one at z = 0.5: t = 7.5 */
    rays[5] = make_ray(-5, 0.25, 0.3, 1, 0, 0); /* radius 0.75: t = 5 - sqrt(0.75^2 - 0.09) */
    rays[6] = make_ray(0, 5, 3, 0, -1, 0);      /* along the zero-radius cone's axis */
    intersect(rays, 7, hits);
    {
        double want_t[7];
        want_t[0] = 4.5;
        want_t[1] = r2;
        want_t[2] = -1;
        want_t[3] = -1;
        want_t[4] = 7.5;
        want_t[5] = 5 - sqrt(0.75 * 0.75 - 0.09);
        want_t[6] = -1;
        for (i = 0; i < 7; i++) {
            char what[64];
            printf("  cone ray %d: %s %d t %.7g, want %s %.7g\n", i, kind_name(hits[i].kind),
                   hits[i].index, hits[i].t, want_t[i] < 0 ? "miss" : "cone 0",
                   want_t[i] < 0 ? 0 : want_t[i]);
            snprintf(what, sizeof what, "cone ray %d", i);
            assert_false(isnan(hits[i].t));
            if (want_t[i] < 0) {
                assert_int_equal(hits[i].kind, CW_PRIM_NONE);
            } else {
                assert_int_equal(hits[i].kind, CW_PRIM_CONE);
                assert_int_equal(hits[i].index, 0);
                assert_near(hits[i].t, want_t[i], 2e-6 * want_t[i], what);
            }
        }
    }
    scene_free(&s);

    /* only degenerate cones: nothing is uploaded, nothing is hit, no NaN */
    base_scene(&s, 1, 1);
    m = add_flat(&s, grey(1));
    add_cone(&s, vec3f_make(0, 0, 0), 1, vec3f_make(0, 0, 0), 2, m);
    add_cone(&s, vec3f_make(0, -1, 0), 0, vec3f_make(0, 1, 0), -0.0f, m);
    upload(&s);
    rays[0] = make_ray(5, 0, 0, -1, 0, 0);
    rays[1] = make_ray(0, 5, 0, 0, -1, 0);
    rays[2] = make_ray(0, 0, 5, 0, 0, -1);
    {
        static const char *const none[] = {"-DCW_HAS_SPHERES=0", "-DCW_HAS_TRIANGLES=0",
                                           "-DCW_HAS_POLYGONS=0", "-DCW_HAS_CONES=0"};
        expect_options(none, 4, "degenerate cones only (no primitive kind left)");
    }
    intersect(rays, 3, hits);
    for (i = 0; i < 3; i++) {
        assert_int_equal(hits[i].kind, CW_PRIM_NONE);
        assert_false(isnan(hits[i].t));
    }
    printf("  degenerate cones only: 3 rays, 3 misses, t %.3g (finite)\n", hits[0].t);
    scene_free(&s);
}

/* A flat cone (a washer: radii 1 and 2, a small height H, slope k = 1/H) seen along its
 * axis from a distance D: the ray at radius 1.5 crosses the surface at h = H/2, t = D - H/2.
 * The quadratic's discriminant B^2 - AC is k^2 |op|^2 = 2.25 k^2 while B^2 and AC are each
 * about (k (r0 + k D))^2: in float the difference is lost once k D reaches a few thousand
 * (relative size (1.5 / (k D))^2 below the float epsilon), and the cone is missed.
 * isect_cone solves from an origin moved near the cone, which keeps it. */
static void test_cone_flat_far(void **state)
{
    static const double cases[][2] = {{0.1, 50}, {1e-2, 10}, {1e-2, 100}, {1e-3, 5}, {1e-3, 20}};
    enum { N = sizeof cases / sizeof cases[0] };
    int i, bad = 0;
    (void)state;
    settings(0, 0, RENDER_ROBUST);
    for (i = 0; i < N; i++) {
        double H = cases[i][0], D = cases[i][1], want = D - H / 2;
        scene s;
        cw_ray ray;
        cw_hit hit;
        base_scene(&s, 1, 1);
        add_cone(&s, vec3f_make(0, 0, 0), 1, vec3f_make(0, (float)H, 0), 2, add_flat(&s, grey(1)));
        upload(&s);
        ray = make_ray(1.5, D, 0, 0, -1, 0);
        intersect(&ray, 1, &hit);
        printf("  washer H %g seen from D %g (k D = %g): %s t %.7g, want cone t %.7g\n", H, D,
               D / H, kind_name(hit.kind), hit.t, want);
        /* within 1% of the cone's height, or float rounding of t */
        if (hit.kind != CW_PRIM_CONE || !(fabs(hit.t - want) <= fmax(1e-2 * H, 2e-6 * want)))
            bad++;
        scene_free(&s);
    }
    printf("  %d of %d flat-cone rays wrong\n", bad, N);
    assert_int_equal(bad, 0);
}

/* A general cone (tilted axis, both radii, a ray perpendicular to the axis at a known
 * height) and random rays against random cones, compared with the double-precision
 * solution where the decision is clear. */
static void test_cone_random(void **state)
{
    enum { NCONES = 6, NRAYS = 4000 };
    static cw_ray rays[NRAYS];
    static cw_hit hits[NRAYS];
    double cb[NCONES][3], ca[NCONES][3], ch[NCONES], cr0[NCONES], cr1[NCONES];
    int i, j, checked = 0, hit = 0, unclear = 0, bad = 0;
    double worst = 0;
    scene s;
    int m;
    (void)state;
    settings(0, 0, RENDER_ROBUST);

    /* base (1, 2, 3), axis (1, 2, -2)/3, height 3, radii 2 and 0.5: at h = 1.5 the radius
     * is 1.25; p = (2, -1, 0)/sqrt5 and q = a x p are perpendicular to the axis */
    {
        double a[3] = {1.0 / 3, 2.0 / 3, -2.0 / 3}, p[3], q[3], c[3], o[3], t0, t1;
        double sp = sqrt(5.0);
        p[0] = 2 / sp;
        p[1] = -1 / sp;
        p[2] = 0;
        q[0] = a[1] * p[2] - a[2] * p[1];
        q[1] = a[2] * p[0] - a[0] * p[2];
        q[2] = a[0] * p[1] - a[1] * p[0];
        for (i = 0; i < 3; i++)
            c[i] = (i == 0 ? 1 : i == 1 ? 2 : 3) + 1.5 * a[i];
        base_scene(&s, 1, 1);
        m = add_flat(&s, grey(1));
        add_cone(&s, vec3f_make(1, 2, 3), 2, vec3f_make(2, 4, 1), 0.5f, m);
        upload(&s);
        for (i = 0; i < 3; i++)
            o[i] = c[i] + 10 * p[i];
        rays[0] = make_ray(o[0], o[1], o[2], -p[0], -p[1], -p[2]);
        for (i = 0; i < 3; i++)
            o[i] = c[i] + 10 * p[i] + 0.6 * q[i];
        rays[1] = make_ray(o[0], o[1], o[2], -p[0], -p[1], -p[2]);
        intersect(rays, 2, hits);
        t0 = 10 - 1.25;
        t1 = 10 - sqrt(1.25 * 1.25 - 0.36);
        printf("  tilted cone, perpendicular rays at h = 1.5: t %.7g and %.7g, want %.7g and "
               "%.7g\n",
               hits[0].t, hits[1].t, t0, t1);
        assert_int_equal(hits[0].kind, CW_PRIM_CONE);
        assert_int_equal(hits[1].kind, CW_PRIM_CONE);
        assert_near(hits[0].t, t0, 2e-5, "tilted cone, through the axis");
        assert_near(hits[1].t, t1, 2e-5, "tilted cone, off the axis");
        scene_free(&s);
    }

    base_scene(&s, 1, 1);
    m = add_flat(&s, grey(1));
    tu_rng_seed(77);
    for (j = 0; j < NCONES; j++) {
        double dd[3];
        for (i = 0; i < 3; i++)
            cb[j][i] = (float)rnd_range(-20, 20);
        rnd_unit(dd);
        ch[j] = rnd_range(0.5, 4);
        cr0[j] = (float)(j == 0 ? 1.5 : rnd_range(0, 2));
        cr1[j] = (float)(j == 0 ? 1.5 : j == 1 ? 0 : rnd_range(0, 2));
        {
            vec3f base = vec3f_make((float)cb[j][0], (float)cb[j][1], (float)cb[j][2]);
            vec3f apex =
                vec3f_make((float)(cb[j][0] + ch[j] * dd[0]), (float)(cb[j][1] + ch[j] * dd[1]),
                           (float)(cb[j][2] + ch[j] * dd[2]));
            double ax = (double)apex.x - base.x, ay = (double)apex.y - base.y,
                   az = (double)apex.z - base.z;
            /* the reference uses the cone as stored (float apex) */
            ch[j] = sqrt(ax * ax + ay * ay + az * az);
            ca[j][0] = ax / ch[j];
            ca[j][1] = ay / ch[j];
            ca[j][2] = az / ch[j];
            add_cone(&s, base, (float)cr0[j], apex, (float)cr1[j], m);
        }
    }
    /* cones far apart (|base| up to 20, size up to 6): each ray aims at one cone */
    for (i = 0; i < NRAYS; i++) {
        double o[3], d[3], target[3], u[3], len = 0;
        j = i % NCONES;
        rnd_unit(u);
        for (int k = 0; k < 3; k++) {
            target[k] = cb[j][k] + ca[j][k] * rnd_range(-0.3, 1.3) * ch[j] + rnd_range(-2, 2);
            o[k] = target[k] + 8 * u[k];
            d[k] = target[k] - o[k];
            len += d[k] * d[k];
        }
        for (int k = 0; k < 3; k++)
            d[k] /= sqrt(len);
        rays[i] = make_ray(o[0], o[1], o[2], d[0], d[1], d[2]);
    }
    upload(&s);
    intersect(rays, NRAYS, hits);
    for (i = 0; i < NRAYS; i++) {
        double o[3] = {rays[i].origin.x, rays[i].origin.y, rays[i].origin.z};
        double d[3] = {rays[i].dir.x, rays[i].dir.y, rays[i].dir.z};
        double best = 1e300, t, margin, min_margin = 1e300;
        int best_j = -1;
        for (j = 0; j < NCONES; j++) {
            int got = ref_cone(cb[j], ca[j], ch[j], cr0[j], cr1[j], o, d, &t, &margin);
            min_margin = fmin(min_margin, margin);
            if (got && t < best) {
                best = t;
                best_j = j;
            }
        }
        if (min_margin < 1e-3) { /* grazing or at an end: float may decide either way */
            unclear++;
            continue;
        }
        checked++;
        if (best_j < 0) {
            if (hits[i].kind != CW_PRIM_NONE) {
                if (bad < 5)
                    printf("    ray %d: kernel hits cone %d at %.9g, reference misses\n", i,
                           hits[i].index, hits[i].t);
                bad++;
            }
            continue;
        }
        hit++;
        if (hits[i].kind != CW_PRIM_CONE || hits[i].index != best_j ||
            fabs(hits[i].t - best) > 1e-5 * (1 + best)) {
            if (bad < 5)
                printf("    ray %d: kernel %s %d at %.9g, reference cone %d at %.9g\n", i,
                       kind_name(hits[i].kind), hits[i].index, hits[i].t, best_j, best);
            bad++;
        } else {
            worst = fmax(worst, fabs(hits[i].t - best) / (1 + best));
        }
    }
    printf("  random cones: %d rays, %d checked (%d near an end or grazing skipped), %d hits, "
           "%d mismatches, largest relative t error %.3g\n",
           NRAYS, checked, unclear, hit, bad, worst);
    assert_int_equal(bad, 0);
    assert_true(checked > NRAYS * 8 / 10 && hit > checked / 4 && hit < checked);
    scene_free(&s);
}

/* ======================================================================================== */
/* 3b. Spheres visible from inside only (a negative radius, NFF)                            */

/* The image of one render of s (finished and uploaded here). */
static void render_scene(scene *s, image *img)
{
    upload(s);
    render(img);
}

/* Checks pixel (i, j) of an 8 x 8 image against a grey. */
static void expect_grey(const image *img, int i, int j, double want, const char *what)
{
    int c;
    for (c = 0; c < 3; c++)
        assert_near(img->rgb[3 * (j * img->width + i) + c], want, 1e-6, what);
}

static void test_inside_spheres(void **state)
{
    static const int precisions[] = {RENDER_ROBUST, RENDER_FAST};
    int ip;
    (void)state;
    for (ip = 0; ip < 2; ip++) {
        scene s;
        image img, ref;
        int i, j, n[3] = {0, 0, 0}, lit_differs = 0;
        settings(0, 0, precisions[ip]);
        printf("  %s path:\n", ip ? "fast" : "robust");

        /* From outside (orthographic, 8 x 8 over [-1, 1]^2): an inside-only sphere of radius
         * 0.8 (ka 0.25) around an ordinary one of radius 0.3 (ka 0.75). The near side is
         * not hit: the inner ball shows, and around it the inside of the far side. */
        base_scene(&s, 8, 8);
        s.ambient = grey(1);
        s.background = grey(0.5f);
        tu_add_sphere(&s, 0, 0, 0, -0.8, add_flat(&s, grey(0.25f)));
        tu_add_sphere(&s, 0, 0, 0, 0.3, add_flat(&s, grey(0.75f)));
        render_scene(&s, &img);
        for (j = 0; j < 8; j++)
            for (i = 0; i < 8; i++) {
                double x = -1 + (i + 0.5) / 4, y = 1 - (j + 0.5) / 4, r2 = x * x + y * y;
                int k = r2 < 0.09 ? 0 : r2 < 0.64 ? 1 : 2;
                expect_grey(&img, i, j, k == 0 ? 0.75 : k == 1 ? 0.25 : 0.5, "from outside");
                n[k]++;
            }
        printf("    from outside: %d pixels see the inner ball, %d the far side, %d the "
               "background\n",
               n[0], n[1], n[2]);
        assert_true(n[0] == 4 && n[1] == 28 && n[2] == 32);
        image_free(&img);
        scene_free(&s);

        /* From inside (perspective, 90 degrees, eye at the centre of an inside-only sphere of
         * radius 5): every pixel sees its wall, not the ball of radius 2 beyond it. */
        tu_base_scene(&s, SCENE_PERSPECTIVE, 0, 8, 8);
        s.ambient = grey(1);
        s.background = grey(0.5f);
        tu_add_sphere(&s, 0, 0, 0, -5, add_flat(&s, grey(0.25f)));
        tu_add_sphere(&s, 0, 0, -10, 2, add_flat(&s, grey(0.75f)));
        render_scene(&s, &img);
        for (j = 0; j < 8; j++)
            for (i = 0; i < 8; i++)
                expect_grey(&img, i, j, 0.25, "from inside");
        printf("    from inside: every pixel sees the wall\n");
        image_free(&img);
        scene_free(&s);

        /* Shadow rays: a light inside an inside-only sphere (a lantern) above a floor lights
         * the floor as if the sphere were not there; an ordinary sphere would shadow it. */
        for (i = 0; i < 3; i++) { /* 0: inside-only sphere, 1: none, 2: ordinary */
            static const vec3f q[4] = {{-2, -2, 0}, {2, -2, 0}, {2, 2, 0}, {-2, 2, 0}};
            int mat;
            base_scene(&s, 8, 8);
            mat = add_material(&s, grey(0), grey(0.5f), grey(0), grey(0), grey(0), 1, 1);
            add_face(&s, q, vec3f_make(0, 0, 1), mat);
            add_light(&s, vec3f_make(0, 0, 1), grey(1));
            if (i != 1)
                tu_add_sphere(&s, 0, 0, 1, i == 0 ? -0.4 : 0.4, mat);
            render_scene(&s, i == 0 ? &img : &ref);
            scene_free(&s);
            if (i == 0)
                continue;
            for (j = 0; j < 8; j++) {
                int col;
                for (col = 0; col < 8; col++) {
                    double x = -1 + (col + 0.5) / 4, y = 1 - (j + 0.5) / 4;
                    size_t at = 3 * (size_t)(j * 8 + col);
                    if (x * x + y * y < 0.16 + 0.05)
                        continue; /* under the sphere (or near its silhouette) */
                    if (i == 1)
                        expect_grey(&img, col, j, ref.rgb[at], "lantern: the floor");
                    else
                        lit_differs += fabs(img.rgb[at] - ref.rgb[at]) > 1e-3;
                }
            }
            image_free(&ref);
        }
        printf("    lantern: the floor lit as without the sphere; %d of its pixels differ from "
               "an ordinary sphere's shadow\n",
               lit_differs);
        assert_true(lit_differs > 0);
        image_free(&img);
    }
}

/* ======================================================================================== */
/* 4. Specialised builds                                                                    */

/* A sphere of radius 0.5 at the origin, ka 0.25 (ka 0.25 + km x background with a
 * mirror), in front of an orthographic camera: 8 x 8 pixels over [-1, 1]^2. */
static void sphere_scene(scene *s, int depth, int mirror, int glass)
{
    int m;
    base_scene(s, 8, 8);
    s->ambient = grey(1);
    s->background = vec3f_make(0.1f, 0.2f, 0.4f);
    s->max_depth = depth;
    m = add_material(s, grey(0.25f), grey(0), grey(0), grey(mirror ? 0.5f : 0),
                     grey(glass ? 0.5f : 0), 1.5f, 1);
    tu_add_sphere(s, 0, 0, 0, 0.5, m);
}

/* The image of sphere_scene: centres within 0.5 of the axis see the sphere (12 of them). */
static void check_sphere_image(const image *img, double on_sphere[3], const char *what)
{
    int i, j, c, n = 0;
    for (j = 0; j < 8; j++)
        for (i = 0; i < 8; i++) {
            double x = -1 + (i + 0.5) / 4, y = 1 - (j + 0.5) / 4;
            int in = x * x + y * y < 0.25;
            const float *p = &img->rgb[3 * (j * 8 + i)];
            static const double bg[3] = {0.1, 0.2, 0.4};
            for (c = 0; c < 3; c++)
                assert_near(p[c], in ? on_sphere[c] : bg[c], 1e-6, what);
            n += in;
        }
    assert_int_equal(n, 12);
}

/* Runs fn with stderr going to a temporary file; returns the text written (malloc'd). */
static char *stderr_of(int (*fn)(image *), image *img, int *rc)
{
    FILE *tmp = tmpfile();
    int saved;
    long len;
    char *text;
    assert_non_null(tmp);
    fflush(stderr);
    saved = dup(2);
    assert_true(saved >= 0);
    assert_true(dup2(fileno(tmp), 2) >= 0);
    *rc = fn(img);
    fflush(stderr);
    assert_true(dup2(saved, 2) >= 0);
    close(saved);
    fseek(tmp, 0, SEEK_END);
    len = ftell(tmp);
    if (len < 0)
        len = 0;
    rewind(tmp);
    text = calloc((size_t)len + 1, 1);
    assert_non_null(text);
    if (len > 0 && fread(text, 1, (size_t)len, tmp) != (size_t)len)
        fail_msg("reading the captured stderr");
    fclose(tmp);
    return text;
}

#define FORCE_MIRRORS_OFF "-w -DCW_HAS_MIRRORS=0"
#define FORCE_SPHERES_OFF "-w -DCW_HAS_SPHERES=0"

static int try_render(image *img)
{
    int rc = renderer_render(R, img, err, sizeof err);
    if (rc == 0)
        image_free(img);
    return rc;
}

static void test_specialised_builds(void **state)
{
    scene s;
    image img;
    render_stats st;
    double v[3];
    (void)state;
    settings(0, 0, RENDER_ROBUST);

    /* spheres only, no mirrors, depth 5: one pass, no secondary rays */
    {
        static const char *const want[] = {
            "-DCW_HAS_SPHERES=1", "-DCW_HAS_TRIANGLES=0", "-DCW_HAS_POLYGONS=0",
            "-DCW_HAS_CONES=0",   "-DCW_HAS_MIRRORS=0",   "-DCW_HAS_REFRACTION=0",
            "-DCW_FAST=0",        "-DCW_STATS=0",         "-Werror"};
        sphere_scene(&s, 5, 0, 0);
        upload(&s);
        expect_options(want, 9, "spheres only, depth 5");
        render(&img);
        renderer_get_stats(R, &st);
        v[0] = v[1] = v[2] = 0.25;
        check_sphere_image(&img, v, "spheres only");
        printf("    passes %d, secondary rays %llu, shadow rays %llu\n", st.passes,
               st.secondary_rays, st.shadow_rays);
        assert_int_equal(st.passes, 1);
        assert_true(st.secondary_rays == 0);
        image_free(&img);
        scene_free(&s);
    }
    /* mirrors at depth 1: compiled without mirrors, local shading only */
    {
        static const char *const want[] = {"-DCW_HAS_MIRRORS=0", "-DCW_HAS_REFRACTION=0"};
        sphere_scene(&s, 1, 1, 0);
        upload(&s);
        expect_options(want, 2, "mirrors at depth 1");
        render(&img);
        renderer_get_stats(R, &st);
        v[0] = v[1] = v[2] = 0.25;
        check_sphere_image(&img, v, "mirror at depth 1");
        printf("    passes %d, secondary rays %llu\n", st.passes, st.secondary_rays);
        assert_int_equal(st.passes, 1);
        assert_true(st.secondary_rays == 0);
        image_free(&img);
        scene_free(&s);
    }
    /* mirrors at depth 2: compiled with mirrors; the mirror ray of every sphere pixel
     * goes back up to the background */
    {
        static const char *const want[] = {"-DCW_HAS_MIRRORS=1", "-DCW_HAS_REFRACTION=0"};
        sphere_scene(&s, 2, 1, 0);
        upload(&s);
        expect_options(want, 2, "mirrors at depth 2");
        render(&img);
        renderer_get_stats(R, &st);
        v[0] = 0.25 + 0.5 * 0.1;
        v[1] = 0.25 + 0.5 * 0.2;
        v[2] = 0.25 + 0.5 * 0.4;
        check_sphere_image(&img, v, "mirror at depth 2");
        printf("    passes %d, secondary rays %llu\n", st.passes, st.secondary_rays);
        assert_int_equal(st.passes, 2);
        assert_true(st.secondary_rays == 12); /* one per sphere pixel */
        image_free(&img);

        /* forced off through CLWHITTED_BUILD_OPTIONS (appended last: the later -D wins;
         * PoCL rejects -U, and -w keeps -Werror from failing on the redefinition): the
         * reflection disappears */
        assert_int_equal(setenv("CLWHITTED_BUILD_OPTIONS", FORCE_MIRRORS_OFF, 1), 0);
        render(&img);
        renderer_get_stats(R, &st);
        {
            static const char *const forced[] = {"-w", "-DCW_HAS_MIRRORS=0"};
            expect_options(forced, 1, "mirrors forced off");
        }
        v[0] = v[1] = v[2] = 0.25;
        check_sphere_image(&img, v, "mirrors forced off");
        printf("    passes %d, secondary rays %llu\n", st.passes, st.secondary_rays);
        assert_int_equal(st.passes, 1);
        image_free(&img);
        scene_free(&s);
    }
    /* spheres forced off: the spheres-only scene shows only the background */
    {
        assert_int_equal(setenv("CLWHITTED_BUILD_OPTIONS", FORCE_SPHERES_OFF, 1), 0);
        sphere_scene(&s, 1, 0, 0);
        upload(&s);
        {
            static const char *const forced[] = {"-w", "-DCW_HAS_SPHERES=0"};
            expect_options(forced, 2, "spheres forced off");
        }
        render(&img);
        v[0] = 0.1;
        v[1] = 0.2;
        v[2] = 0.4;
        check_sphere_image(&img, v, "spheres forced off: background where the sphere was");
        printf("    the sphere's 12 pixels show the background\n");
        image_free(&img);

        /* a flag that is not 0 or 1: the build fails and prints its log */
        assert_int_equal(setenv("CLWHITTED_BUILD_OPTIONS", "-w -DCW_HAS_SPHERES=2", 1), 0);
        {
            int rc;
            char *log = stderr_of(try_render, &img, &rc);
            printf("    CW_HAS_SPHERES=2: render returns %d, \"%s\"; %zu bytes on stderr\n", rc,
                   err, strlen(log));
            assert_int_not_equal(rc, 0);
            assert_non_null(strstr(err, "clBuildProgram"));
            assert_non_null(strstr(log, "kernel build log"));
            assert_non_null(strstr(log, "must be 0 or 1"));
            free(log);
        }
        assert_int_equal(unsetenv("CLWHITTED_BUILD_OPTIONS"), 0);
        /* and back to normal without the variable */
        render(&img);
        v[0] = v[1] = v[2] = 0.25;
        check_sphere_image(&img, v, "spheres after the variable is gone");
        image_free(&img);
        scene_free(&s);
    }
    /* transmitters: refraction compiled in at depth > 1 only; no mirrors unless SPD */
    {
        static const char *const deep[] = {"-DCW_HAS_MIRRORS=0", "-DCW_HAS_REFRACTION=1"};
        static const char *const flat[] = {"-DCW_HAS_MIRRORS=0", "-DCW_HAS_REFRACTION=0"};
        static const char *const spd[] = {"-DCW_HAS_MIRRORS=1", "-DCW_HAS_REFRACTION=1"};
        sphere_scene(&s, 5, 0, 1);
        upload(&s);
        expect_options(deep, 2, "transmitters at depth 5");
        scene_free(&s);
        sphere_scene(&s, 1, 0, 1);
        upload(&s);
        expect_options(flat, 2, "transmitters at depth 1");
        scene_free(&s);
        settings(1, 0, RENDER_ROBUST);
        sphere_scene(&s, 5, 0, 1);
        upload(&s);
        expect_options(spd, 2, "transmitters at depth 5, SPD");
        scene_free(&s);
        settings(0, 0, RENDER_ROBUST);
    }
    /* the fast path */
    {
        static const char *const want[] = {"-DCW_FAST=1", "-cl-fast-relaxed-math"};
        settings(0, 0, RENDER_FAST);
        sphere_scene(&s, 5, 0, 0);
        upload(&s);
        expect_options(want, 2, "fast");
        render(&img);
        v[0] = v[1] = v[2] = 0.25;
        check_sphere_image(&img, v, "fast path");
        image_free(&img);
        scene_free(&s);
        settings(0, 0, RENDER_ROBUST);
    }
}

/* ======================================================================================== */
/* 5. Statistics and SPD                                                                    */

/* A big sphere (lit from the upper right, the terminator visible) and a small one between
 * it and the light, out of the picture, casting a shadow on it. */
#define STATS_NX 64
#define STATS_NY 48
static const double BIG[4] = {0.1, -0.05, 0, 1.23}, SMALL[4] = {1.15, 1.55, 1.8, 0.3};
static const double LIGHT[3] = {3, 4, 5};

static void stats_scene(scene *s, int occluder)
{
    int m;
    base_scene(s, STATS_NX, STATS_NY);
    s->camera.l = -2;
    s->camera.r = 2;
    s->camera.b = -1.5f;
    s->camera.t = 1.5f;
    s->ambient = grey(0.1f);
    s->max_depth = 1;
    m = add_material(s, vec3f_make(0.3f, 0.2f, 0.1f), vec3f_make(0.6f, 0.5f, 0.4f), grey(0.3f),
                     grey(0), grey(0), 1, 10);
    add_light(s, vec3f_make((float)LIGHT[0], (float)LIGHT[1], (float)LIGHT[2]), grey(0.8f));
    tu_add_sphere(s, BIG[0], BIG[1], BIG[2], BIG[3], m);
    if (occluder)
        tu_add_sphere(s, SMALL[0], SMALL[1], SMALL[2], SMALL[3], m);
}

/* Line o + t d (unit d) against sphere c: the nearest t > 0 or -1; *margin: how far the
 * line passes from grazing. */
static double sphere_t(const double c[4], const double o[3], const double d[3], double *margin)
{
    double f[3] = {o[0] - c[0], o[1] - c[1], o[2] - c[2]};
    double b = f[0] * d[0] + f[1] * d[1] + f[2] * d[2];
    double cc = f[0] * f[0] + f[1] * f[1] + f[2] * f[2] - c[3] * c[3], disc = b * b - cc, t;
    *margin = fabs(disc);
    if (disc < 0)
        return -1;
    t = -b - sqrt(disc);
    if (t > 0)
        return t;
    t = -b + sqrt(disc);
    return t > 0 ? t : -1;
}

typedef struct {
    long eye, hits, shadow, blocked;
    double margin; /* the smallest distance of any decision from flipping */
} counts;

/* The counts for an nx x ny orthographic image over window (l, r, b, t), in double. */
static counts expected_counts(int occluder, int nx, int ny, double l, double r, double b, double t)
{
    counts k;
    int i, j, q;
    const double *sph[2] = {BIG, SMALL};
    memset(&k, 0, sizeof k);
    k.margin = 1e30;
    for (j = 0; j < ny; j++)
        for (i = 0; i < nx; i++) {
            double o[3] = {l + (r - l) * (i + 0.5) / nx, b + (t - b) * (j + 0.5) / ny, 20};
            double d[3] = {0, 0, -1}, best = 1e30, m, p[3], n[3], L[3], dist, ndl;
            int which = -1;
            k.eye++;
            for (q = 0; q < 1 + occluder; q++) {
                double th = sphere_t(sph[q], o, d, &m);
                k.margin = fmin(k.margin, m);
                if (th > 0 && th < best) {
                    best = th;
                    which = q;
                }
            }
            if (which < 0)
                continue;
            k.hits++;
            for (q = 0; q < 3; q++) {
                p[q] = o[q] + best * d[q];
                n[q] = (p[q] - sph[which][q]) / sph[which][3];
                L[q] = LIGHT[q] - p[q];
            }
            dist = sqrt(L[0] * L[0] + L[1] * L[1] + L[2] * L[2]);
            for (q = 0; q < 3; q++)
                L[q] /= dist;
            ndl = n[0] * L[0] + n[1] * L[1] + n[2] * L[2];
            k.margin = fmin(k.margin, fabs(ndl));
            if (ndl <= 0)
                continue;
            k.shadow++;
            for (q = 0; q < 1 + occluder; q++) {
                double th;
                if (q == which)
                    continue; /* a sphere does not shadow its own lit side */
                th = sphere_t(sph[q], p, L, &m);
                k.margin = fmin(k.margin, m);
                if (th > 0 && th < dist) {
                    k.blocked++;
                    break;
                }
            }
        }
    return k;
}

static void check_counts(const render_stats *st, const counts *k, const char *what)
{
    printf("  %s: eye rays %llu (want %ld), eye hits %llu (%ld), shadow rays %llu (%ld), "
           "blocked %llu (%ld), secondary %llu, passes %d; decision margin %.2g\n",
           what, st->eye_rays, k->eye, st->eye_hits, k->hits, st->shadow_rays, k->shadow,
           st->shadow_blocked, k->blocked, st->secondary_rays, st->passes, k->margin);
    /* the set-up must keep every decision clear of rounding */
    assert_true(k->margin > 1e-4);
    assert_true(st->eye_rays == (unsigned long long)k->eye);
    assert_true(st->eye_hits == (unsigned long long)k->hits);
    assert_true(st->shadow_rays == (unsigned long long)k->shadow);
    assert_true(st->shadow_blocked == (unsigned long long)k->blocked);
    assert_true(st->secondary_rays == 0 && st->secondary_hits == 0);
}

static void test_stats(void **state)
{
    scene s;
    image img;
    render_stats st;
    counts k;
    (void)state;
    settings(0, 1, RENDER_ROBUST);

    stats_scene(&s, 0);
    upload(&s);
    {
        static const char *const want[] = {"-DCW_STATS=1"};
        expect_options(want, 1, "stats");
    }
    render(&img);
    renderer_get_stats(R, &st);
    k = expected_counts(0, STATS_NX, STATS_NY, -2, 2, -1.5, 1.5);
    check_counts(&st, &k, "one sphere");
    assert_true(k.hits > 0 && k.shadow > 0 && k.shadow < k.hits && k.blocked == 0);
    assert_int_equal(st.passes, 1);
    /* the walks' work in a tree of one node: every ray visits it; a ray that hits the
     * sphere has tested it, and no ray tests it more than once; no shadow ray is blocked,
     * so no shadow cache entry spares a walk */
    printf("  walk: closest %llu nodes, %llu tests; shadow %llu nodes, %llu tests\n",
           st.closest_nodes, st.closest_tests, st.any_nodes, st.any_tests);
    assert_int_equal(st.nodes, 1);
    assert_true(st.closest_nodes == st.eye_rays);
    assert_true(st.closest_tests >= st.eye_hits && st.closest_tests <= st.eye_rays);
    assert_true(st.any_nodes == st.shadow_rays);
    assert_true(st.any_tests <= st.shadow_rays);
    image_free(&img);
    scene_free(&s);

    stats_scene(&s, 1);
    upload(&s);
    render(&img);
    renderer_get_stats(R, &st);
    k = expected_counts(1, STATS_NX, STATS_NY, -2, 2, -1.5, 1.5);
    check_counts(&st, &k, "with an occluder");
    assert_true(k.blocked > 0);
    /* a blocked shadow ray has tested its occluder; a walk the shadow cache spares visits
     * no node, and only a blocked ray's can be spared */
    printf("  walk: closest %llu nodes, %llu tests; shadow %llu nodes, %llu tests\n",
           st.closest_nodes, st.closest_tests, st.any_nodes, st.any_tests);
    assert_true(st.closest_nodes >= st.eye_rays && st.closest_tests >= st.eye_hits);
    assert_true(st.any_tests >= st.shadow_blocked);
    assert_true(st.any_nodes <= st.shadow_rays &&
                st.any_nodes >= st.shadow_rays - st.shadow_blocked);
    image_free(&img);
    scene_free(&s);
}

/* SPD mode: (nx+1) x (ny+1) corner rays, each pixel the mean of its four corners, which
 * is a centre render of an (nx+1) x (ny+1) image over a window half a pixel wider on each
 * side, averaged 2 x 2. */
static void test_spd(void **state)
{
    scene s;
    image spd, ref;
    render_stats st;
    counts k;
    float l = -2, r = 2, b = -1.5f, t = 1.5f, pu, pv;
    int i, j, c;
    double maxdiff = 0;
    (void)state;

    settings(1, 1, RENDER_ROBUST);
    stats_scene(&s, 1);
    upload(&s);
    render(&spd);
    renderer_get_stats(R, &st);
    pu = (r - l) / (float)STATS_NX;
    pv = (t - b) / (float)STATS_NY;
    k = expected_counts(1, STATS_NX + 1, STATS_NY + 1, l - 0.5 * pu, r + 0.5 * pu, b - 0.5 * pv,
                        t + 0.5 * pv);
    check_counts(&st, &k, "SPD corners");
    assert_true(st.eye_rays == (unsigned long long)(STATS_NX + 1) * (STATS_NY + 1));
    assert_int_equal(spd.width, STATS_NX);
    assert_int_equal(spd.height, STATS_NY);
    scene_free(&s);

    settings(0, 1, RENDER_ROBUST);
    stats_scene(&s, 1);
    s.width = STATS_NX + 1;
    s.height = STATS_NY + 1;
    s.camera.l = l - 0.5f * pu;
    s.camera.r = r + 0.5f * pu;
    s.camera.b = b - 0.5f * pv;
    s.camera.t = t + 0.5f * pv;
    upload(&s);
    render(&ref);
    renderer_get_stats(R, &st);
    assert_true(st.eye_rays == (unsigned long long)(STATS_NX + 1) * (STATS_NY + 1));
    assert_true(st.eye_hits == (unsigned long long)k.hits);
    for (j = 0; j < STATS_NY; j++)
        for (i = 0; i < STATS_NX; i++)
            for (c = 0; c < 3; c++) {
                const float *p = ref.rgb;
                int w = STATS_NX + 1;
                float avg =
                    0.25f * (p[3 * (j * w + i) + c] + p[3 * (j * w + i + 1) + c] +
                             p[3 * ((j + 1) * w + i) + c] + p[3 * ((j + 1) * w + i + 1) + c]);
                double dd = fabs(avg - spd.rgb[3 * (j * STATS_NX + i) + c]);
                maxdiff = fmax(maxdiff, dd);
            }
    printf("  SPD image vs the 2x2 mean of a %dx%d centre render over the widened window: "
           "largest difference %.3g\n",
           STATS_NX + 1, STATS_NY + 1, maxdiff);
    assert_true(maxdiff <= 1e-6);
    image_free(&spd);
    image_free(&ref);
    scene_free(&s);
    settings(0, 0, RENDER_ROBUST);
}

/* ---- the upload in pieces ------------------------------------------------------------ */

/* Scenes whose arrays are uploaded in pieces of 100 bytes, of a page and a bit, and of
 * 64 KiB and a bit (each piece's memory given back once uploaded, pieces not aligned to
 * pages) render the image of the whole-array upload, bit for bit. On a CPU device (PoCL
 * here) the whole-array upload is no upload: the buffers use the scene arrays where the
 * host built them (render.c, upload_in_place), which the test hook of pieces turns off; so
 * this also checks that images are the same both ways, and that nothing of the scene arrays
 * was copied in the first and all of them in the second. */
static void test_upload_pieces(void **state)
{
    static const char *const scenes[] = {
        "scenes/default.json",
        "tests/scenes/portability/spd-balls2.nff",
        "tests/scenes/portability/polygons.nff",
        "tests/scenes/origin/far.nff",
    };
    static const size_t pieces[] = {100, 4096 + 12, 65536 + 20};
    render_stats st;
    unsigned long long in_place, copied;
    (void)state;
    renderer_debug_world_origin(R, 0);
    settings(0, 0, RENDER_ROBUST);
    for (size_t si = 0; si < sizeof scenes / sizeof scenes[0]; si++) {
        scene sc;
        image whole = {0, 0, NULL};
        scene_init(&sc);
        renderer_debug_upload_piece(R, 0);
        if (scene_load(scenes[si], &sc, err, sizeof err) != 0 ||
            scene_finish(&sc, 48, 36, 0, err, sizeof err) != 0 ||
            renderer_set_scene(R, &sc, err, sizeof err) != 0 ||
            renderer_render(R, &whole, err, sizeof err) != 0)
            fail_msg("%s: %s", scenes[si], err);
        renderer_get_stats(R, &st);
        if (st.upload_in_place == 0)
            fail_msg("%s: no scene array used in place on PoCL's CPU device (%llu bytes copied)",
                     scenes[si], st.upload_copied);
        in_place = st.upload_in_place;
        copied = st.upload_copied;
        for (size_t k = 0; k < sizeof pieces / sizeof pieces[0]; k++) {
            image got = {0, 0, NULL};
            renderer_debug_upload_piece(R, pieces[k]);
            if (renderer_set_scene(R, &sc, err, sizeof err) != 0 ||
                renderer_render(R, &got, err, sizeof err) != 0)
                fail_msg("%s, pieces of %zu bytes: %s", scenes[si], pieces[k], err);
            renderer_get_stats(R, &st);
            if (st.upload_in_place != 0 || st.upload_copied != in_place + copied)
                fail_msg("%s, pieces of %zu bytes: %llu bytes in place and %llu copied, not 0 "
                         "and %llu",
                         scenes[si], pieces[k], st.upload_in_place, st.upload_copied,
                         in_place + copied);
            if (got.width != whole.width || got.height != whole.height ||
                memcmp(got.rgb, whole.rgb, (size_t)got.width * got.height * 3 * sizeof(float)))
                fail_msg("%s: uploaded in pieces of %zu bytes, another image", scenes[si],
                         pieces[k]);
            image_free(&got);
        }
        printf("  %s: the same image with the arrays in place (%llu bytes) and uploaded in "
               "pieces of %zu, %zu and %zu bytes\n",
               scenes[si], in_place, pieces[0], pieces[1], pieces[2]);
        image_free(&whole);
        scene_free(&sc);
    }
    renderer_debug_upload_piece(R, 0);
    renderer_debug_world_origin(R, 1);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_bvh_brute_force),
        cmocka_unit_test(test_refraction_slab),
        cmocka_unit_test(test_total_internal_reflection),
        cmocka_unit_test(test_cone_cases),
        cmocka_unit_test(test_cone_random),
        cmocka_unit_test(test_cone_flat_far),
        cmocka_unit_test(test_inside_spheres),
        cmocka_unit_test(test_specialised_builds),
        cmocka_unit_test(test_stats),
        cmocka_unit_test(test_spd),
        cmocka_unit_test(test_upload_pieces),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
