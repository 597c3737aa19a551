/* Hard cases of the robust geometry, through the real kernels on PoCL: renderer_intersect
 * (closest hit over the BVH) and renderer_occluded (any hit, shadow rays). Every test
 * prints the figures it measured, for the robust path (asserted) and for the fast path
 * (RENDER_FAST: Moeller-Trumbore, textbook quadratic, fixed 1e-4 offsets, fast relaxed
 * math), whose failures are figures, never assertions.
 *
 *  1. spheres: far and tiny (radius/distance 1e-1 .. 1e-6 at distances 1 .. 1e6), huge
 *     (radius 1e6), and rays starting on, just inside and just outside the surface (of
 *     ordinary spheres and of spheres visible from inside only: a negative radius, whose
 *     one hit is where the ray leaves), against a double-precision answer on the same
 *     float ray;
 *  2. watertightness: a closed mesh far from the origin, 1,000,000 rays from inside aimed
 *     exactly at its shared edges and vertices: no misses;
 *  3. self-hits: secondary rays spawned with the kernels' own prim_surface/shade_spawn
 *     (kernels/shade.h and prim.h compiled here as host C99) from spheres, triangles, polygons and
 *     cones at scales 1e-4 .. 1e4, at the origin and 1e4 x scale away from it;
 *  4. grazing rays at a sphere's silhouette, and exact tangents;
 *  5. degenerate (collinear, coincident), needle and tiny triangles, rays parallel to a
 *     face;
 *  6. images invariant under scaling and translation of the whole scene;
 *  7. the shading's own power and ulp steps (shade_pow, shade_nudge) against libm.
 *
 * Tolerances. u = 2^-24 is float's unit roundoff. A float computation that works with
 * coordinates of magnitude M cannot place a surface better than a few u M, so:
 *  - a sphere's hit/miss must agree with double precision unless the ray's closest
 *    approach to the centre is within KB u M of the radius (M = |o - c| + r), or a root
 *    lies within KB u M / cos of the origin (the ray starts on the surface, within
 *    rounding; cos: between the ray and the normal at the roots); KB = 8 covers the
 *    rounding of f = o - c, b = f.d, f - b d, its square and r^2 - |f - b d|^2 (about
 *    6 u M at worst; the widest disagreement measured is about 1 u M). Where both hit,
 *    t must agree within KT u M / cos, KT = 16 (measured: at most about 5);
 *  - a triangle's hit/miss must agree unless the double-precision hit point lies within
 *    KB u M / cos of an edge line (M = the largest |vertex - origin|).
 * The host compiles with -std=c99, i.e. -ffp-contract=off (and the default x86-64 target
 * has no FMA instructions); the kernels set FP_CONTRACT OFF. The test reports how many
 * device results equal the host's bit for bit (OpenCL's dot() and normalize() may round
 * differently from the host's v3_dot and v3_norm, so that is a figure, not an assertion). */
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>

/* The kernels' geometry, compiled as host C99 (kernels/compat.h). Included before the
 * host headers: shade.h names a parameter like the host type `image`. */
#include "shade.h"

#include "testutil.h"
#include "sys.h"

#include "devscene.h"

#include "image.h"
#include "image_diff.h"
#include "render.h"
#include "render_debug.h"
#include "scene.h"
#include "scene_load.h"

#define U_F 5.9604644775390625e-8 /* u = 2^-24 */
#define KB 8.0                    /* hit/miss decision band, in units of u M (see above) */
#define KT 16.0                   /* t tolerance, in units of u M / cos */
#define BATCH 100000              /* rays per renderer_intersect call */
#define PI_D 3.14159265358979323846
#define OUT_DIR "build/test-output"

static renderer *R;  /* robust path (the default) */
static renderer *RF; /* fast path */
static char err[2048];

static int setup(void **state)
{
    render_settings st;
    (void)state;
    if (tu_renderer_open(&R, 1) != 0 || tu_renderer_open(&RF, 0) != 0)
        return -1;
    /* rays in world coordinates through the test hooks (the image test sets the default) */
    renderer_debug_world_origin(R, 1);
    renderer_debug_world_origin(RF, 1);
    render_settings_default(&st);
    st.precision = RENDER_FAST;
    if (renderer_set_settings(RF, &st, err, sizeof err) != 0) {
        fprintf(stderr, "renderer_set_settings: %s\n", err);
        return -1;
    }
    return 0;
}

static int teardown(void **state)
{
    (void)state;
    tu_renderer_close(&RF);
    return tu_renderer_close(&R);
}

/* ---- deterministic random numbers (xorshift64*) -------------------------------------- */

static uint64_t rng_s = 1;

static void rng_seed(uint64_t seed)
{
    rng_s = seed * 0x9E3779B97F4A7C15ULL + 0x2545F4914F6CDD1DULL;
    if (rng_s == 0)
        rng_s = 1;
}

static double rnd(void)
{
    rng_s ^= rng_s >> 12;
    rng_s ^= rng_s << 25;
    rng_s ^= rng_s >> 27;
    return (double)((rng_s * 0x2545F4914F6CDD1DULL) >> 11) * (1.0 / 9007199254740992.0);
}

static double rnd_in(double a, double b)
{
    return a + (b - a) * rnd();
}

static int rnd_int(int n)
{
    int k = (int)(rnd() * n);
    return k < n ? k : n - 1;
}

/* ---- double vectors ------------------------------------------------------------------ */

typedef struct {
    double x, y, z;
} dvec;

static dvec dv(double x, double y, double z)
{
    dvec r;
    r.x = x;
    r.y = y;
    r.z = z;
    return r;
}

static dvec dadd(dvec a, dvec b)
{
    return dv(a.x + b.x, a.y + b.y, a.z + b.z);
}

static dvec dsub(dvec a, dvec b)
{
    return dv(a.x - b.x, a.y - b.y, a.z - b.z);
}

static dvec dscale(dvec a, double s)
{
    return dv(a.x * s, a.y * s, a.z * s);
}

static double ddot(dvec a, dvec b)
{
    return a.x * b.x + a.y * b.y + a.z * b.z;
}

static dvec dcross(dvec a, dvec b)
{
    return dv(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x);
}

static double dlen(dvec a)
{
    return sqrt(ddot(a, a));
}

static dvec dnorm(dvec a)
{
    return dscale(a, 1.0 / dlen(a));
}

static dvec dv4(cw_float4 a)
{
    return dv(a.x, a.y, a.z);
}

static dvec dv3(vec3 a)
{
    return dv(a.x, a.y, a.z);
}

static vec3f fv(dvec a)
{
    return vec3f_make((float)a.x, (float)a.y, (float)a.z);
}

/* a rounded to float, as the kernels' vec3 */
static vec3 v3d(dvec a)
{
    return v3((float)a.x, (float)a.y, (float)a.z);
}

static dvec rnd_dir(void)
{
    double z = rnd_in(-1, 1), phi = rnd_in(0, 2 * PI_D), s = sqrt(1 - z * z);
    return dv(s * cos(phi), s * sin(phi), z);
}

static dvec rnd_ball(void)
{
    dvec p;
    do
        p = dv(rnd_in(-1, 1), rnd_in(-1, 1), rnd_in(-1, 1));
    while (ddot(p, p) > 1);
    return p;
}

/* e1, e2: unit vectors with (e1, e2, n) orthonormal */
static void dbasis(dvec n, dvec *e1, dvec *e2)
{
    dvec a = fabs(n.x) < 0.6 ? dv(1, 0, 0) : dv(0, 1, 0);
    *e1 = dnorm(dcross(n, a));
    *e2 = dcross(dnorm(n), *e1);
}

/* ---- rays ---------------------------------------------------------------------------- */

/* The float ray from o towards d: o rounded, d normalised in double and rounded. */
static cw_ray make_ray(dvec o, dvec d)
{
    cw_ray r;
    dvec n = dnorm(d);
    memset(&r, 0, sizeof r);
    r.origin.x = (float)o.x;
    r.origin.y = (float)o.y;
    r.origin.z = (float)o.z;
    r.dir.x = (float)n.x;
    r.dir.y = (float)n.y;
    r.dir.z = (float)n.z;
    r.weight.x = r.weight.y = r.weight.z = 1;
    r.depth = 1;
    return r;
}

static cw_ray ray_v3(vec3 o, vec3 d, int skip)
{
    cw_ray r;
    memset(&r, 0, sizeof r);
    r.origin = v4_from3(o, 0.0f);
    r.dir = v4_from3(d, 0.0f);
    r.weight.x = r.weight.y = r.weight.z = 1;
    r.depth = 2;
    r.skip = skip;
    return r;
}

static void ray_str(char *buf, size_t n, const cw_ray *r)
{
    snprintf(buf, n, "o=(%.9g, %.9g, %.9g) d=(%.9g, %.9g, %.9g) skip=%d", r->origin.x, r->origin.y,
             r->origin.z, r->dir.x, r->dir.y, r->dir.z, r->skip);
}

/* Closest hits of n rays on renderer r, in batches. */
static void trace(renderer *r, const cw_ray *rays, size_t n, cw_hit *hits)
{
    size_t i, k;
    for (i = 0; i < n; i += k) {
        k = n - i < BATCH ? n - i : BATCH;
        if (renderer_intersect(r, rays + i, (int)k, hits + i, err, sizeof err) != 0)
            fail_msg("renderer_intersect: %s", err);
    }
}

static void occlude(renderer *r, const cw_shadow_ray *rays, size_t n, int *blocked)
{
    size_t i, k;
    for (i = 0; i < n; i += k) {
        k = n - i < BATCH ? n - i : BATCH;
        if (renderer_occluded(r, rays + i, (int)k, blocked + i, err, sizeof err) != 0)
            fail_msg("renderer_occluded: %s", err);
    }
}

static int hit_has_nan(const cw_hit *h)
{
    return isnan(h->t) || isnan(h->u) || isnan(h->v) || isinf(h->t);
}

/* ---- scenes -------------------------------------------------------------------------- */

/* An empty scene with a valid camera and one white material (index 0). */
static void base_scene(scene *s)
{
    vec3f white = vec3f_make(1, 1, 1), black = vec3f_make(0, 0, 0);
    tu_base_scene(s, SCENE_PERSPECTIVE, 10, 1, 1);
    assert_true(tu_add_material(s, white, white, black, black, black, 1, 1) >= 0);
}

static void add_sphere(scene *s, dvec c, double r)
{
    tu_add_sphere(s, c.x, c.y, c.z, r, 0);
}

static void add_triangle(scene *s, vec3f a, vec3f b, vec3f c)
{
    tu_add_triangle(s, a, b, c, 0);
}

static void add_polygon(scene *s, const vec3f *v, int n)
{
    tu_add_polygon(s, v, n, 0);
}

static void add_cone(scene *s, vec3f base, float r0, vec3f apex, float r1)
{
    scene_cone c;
    c.base = tu_d(base);
    c.apex = tu_d(apex);
    c.base_radius = r0;
    c.apex_radius = r1;
    c.material = 0;
    assert_true(scene_push(&s->cones, &c, sizeof c) >= 0);
}

/* Finishes the scene and uploads it to both renderers. */
static void upload(scene *s)
{
    if (scene_finish(s, 0, 0, 0, err, sizeof err) != 0 ||
        renderer_set_scene(R, s, err, sizeof err) != 0 ||
        renderer_set_scene(RF, s, err, sizeof err) != 0)
        fail_msg("%s", err);
}

/* ---- the device arrays, rebuilt on the host --------------------------------------------- */

/* The device arrays as the renderer builds them (host/devscene.c, the same indices:
 * test_selfhit checks it against the device's t), the BVH and its triangle blocks
 * included (a device hit in a block names its block, which prim_surface reads), and the
 * kernels' view of them. */
typedef struct {
    devscene d;
    cw_world w;
} host_world;

static void host_world_init(host_world *hw, const scene *s)
{
    char msg[256];
    devscene_world a;
    memset(&hw->w, 0, sizeof hw->w);
    if (devscene_convert(s, NULL, &hw->d, msg, sizeof msg) != 0 ||
        devscene_build_bvh(&hw->d, msg, sizeof msg) != 0)
        fail_msg("%s", msg);
    devscene_world_arrays(&hw->d, &a);
#define HOST_WORLD_BIND(type, name, what) hw->w.name = a.name;
    CW_WORLD_BUFFERS(HOST_WORLD_BIND)
#undef HOST_WORLD_BIND
}

static void host_world_free(host_world *hw)
{
    devscene_free(&hw->d);
}

/* The kernels' test of one primitive, run on the host. Returns 1 on a hit, with *t. */
static int host_isect(const host_world *hw, int kind, int idx, const cw_ray *ray, float *t)
{
    vec3 o = v3_from4(ray->origin), d = v3_from4(ray->dir);
    float u, v;
    cw_rayinfo ri;
    if (kind == CW_PRIM_SPHERE)
        return isect_sphere(&hw->d.sph[idx], o, d, 0.0f, CW_FAR, t);
    if (kind == CW_PRIM_TRIANGLE) {
        ri = isect_rayinfo(o, d);
        return isect_triangle(&hw->d.tri[idx], &ri, 0.0f, CW_FAR, t, &u, &v);
    }
    if (kind == CW_PRIM_POLYGON)
        return isect_polygon(&hw->d.pg[idx], hw->d.verts, hw->d.bands, o, d, 0.0f, CW_FAR, t);
    return isect_cone(&hw->d.cones[idx], o, d, 0.0f, CW_FAR, t);
}

/* ---- spheres against double precision --------------------------------------------------- */

typedef struct {
    int n; /* real roots: 0 or 2 (a tangent gives two equal ones) */
    double t0, t1;
    double rho;  /* distance from the centre to the ray's line */
    double M;    /* |o - c| + r: the magnitude the float computation works at */
    double cosi; /* |cos| of the angle between the ray and the normal at the roots */
    int inside;  /* a negative radius: visible from inside only, t1 alone counts */
} sph_ref;

/* The exact roots (to double rounding) of |o + t d - c| = r for the float ray and sphere
 * converted to double; d's length is not assumed to be 1. A negative radius (visible from
 * inside only) gives the same roots, of which only t1 (the ray leaving) is a hit. */
static sph_ref sphere_ref(const cw_ray *ray, const cw_sphere *sp)
{
    dvec o = dv4(ray->origin), d = dv4(ray->dir), c = dv4(sp->center);
    double r = fabs(sp->center.w), a = ddot(d, d);
    dvec f = dsub(o, c);
    double b = ddot(f, d);
    dvec perp = dsub(f, dscale(d, b / a));
    double rho2 = ddot(perp, perp), disc = r * r - rho2, sq, q, cc, tmp;
    sph_ref ref;
    ref.rho = sqrt(rho2);
    ref.M = dlen(f) + r;
    ref.cosi = disc > 0 ? sqrt(disc) / r : 0;
    ref.n = 0;
    ref.t0 = ref.t1 = 0;
    ref.inside = sp->center.w < 0;
    if (disc < 0)
        return ref;
    sq = sqrt(a * disc);
    q = -b - (b >= 0 ? sq : -sq);
    cc = ddot(f, f) - r * r;
    ref.n = 2;
    if (q == 0)
        return ref;
    ref.t0 = q / a;
    ref.t1 = cc / q;
    if (ref.t0 > ref.t1) {
        tmp = ref.t0;
        ref.t0 = ref.t1;
        ref.t1 = tmp;
    }
    return ref;
}

typedef struct {
    long n, ref_hits, hits, agree, band, out, nan;
    double widest;   /* widest in-band disagreement, in units of u M (closest approach or root) */
    double max_rel;  /* relative t error where both hit */
    double max_unit; /* |dt| cos / (u M) where both hit */
    double *rel;
    long nrel, cap;
    int shown; /* reproducers printed */
} sph_stats;

static void sph_stats_init(sph_stats *st, long cap)
{
    memset(st, 0, sizeof *st);
    st->cap = cap;
    st->rel = malloc((size_t)cap * sizeof *st->rel);
    assert_non_null(st->rel);
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

static double sph_median(sph_stats *st)
{
    if (st->nrel == 0)
        return 0;
    qsort(st->rel, (size_t)st->nrel, sizeof *st->rel, cmp_double);
    return st->rel[st->nrel / 2];
}

/* Classifies one kernel answer against double precision (see the file comment). show:
 * print up to 3 disagreements outside the band, as reproducers. */
static void sph_check(sph_stats *st, const cw_ray *ray, const cw_sphere *sp, const cw_hit *hit,
                      int show)
{
    sph_ref ref = sphere_ref(ray, sp);
    double r = fabs(sp->center.w), um = U_F * ref.M;
    double tb = ref.cosi > 0 ? KT * um / ref.cosi : INFINITY;
    int khit = hit->kind == CW_PRIM_SPHERE, rhit = 0, agree;
    double texp = 0, dist_band;
    st->n++;
    if (hit_has_nan(hit) && khit)
        st->nan++;
    if (ref.n && ref.t0 > 0 && !ref.inside) {
        rhit = 1;
        texp = ref.t0;
    } else if (ref.n && ref.t1 > 0) {
        rhit = 1;
        texp = ref.t1;
    }
    st->ref_hits += rhit;
    st->hits += khit;
    agree = (!khit && !rhit) || (khit && rhit && fabs(hit->t - texp) <= tb);
    if (agree) {
        st->agree++;
        if (khit) {
            double rel = fabs(hit->t - texp) / texp, unit = fabs(hit->t - texp) * ref.cosi / um;
            if (rel > st->max_rel)
                st->max_rel = rel;
            if (unit > st->max_unit)
                st->max_unit = unit;
            if (st->nrel < st->cap)
                st->rel[st->nrel++] = rel;
        }
        return;
    }
    /* how far from undecidable: the closest approach's distance from the radius, or the
     * nearest root's distance from the origin, in the units of the band */
    dist_band = fabs(ref.rho - r) / um;
    if (ref.n) {
        double d0 = fabs(ref.t0) * ref.cosi / um, d1 = fabs(ref.t1) * ref.cosi / um;
        dist_band = fmin(dist_band, fmin(d0, d1));
    }
    if (dist_band <= KB) {
        st->band++;
        if (dist_band > st->widest)
            st->widest = dist_band;
        return;
    }
    st->out++;
    if (show && st->shown < 3) {
        char buf[256];
        st->shown++;
        ray_str(buf, sizeof buf, ray);
        printf("    DISAGREE: ray %s, sphere c=(%.9g, %.9g, %.9g) r=%.9g: kernel %s t=%.9g; "
               "double %s t0=%.17g t1=%.17g, |rho-r| = %.3g uM, M = %.6g\n",
               buf, sp->center.x, sp->center.y, sp->center.z, r, khit ? "hit" : "miss", hit->t,
               rhit ? "hit" : "miss", ref.t0, ref.t1, fabs(ref.rho - r) / um, ref.M);
    }
}

/* Traces n rays at the scene's one sphere on both paths, accumulating the statistics. */
static void sphere_run(const cw_sphere *sp, const cw_ray *rays, size_t n, cw_hit *hits,
                       sph_stats *rob, sph_stats *fast)
{
    size_t i;
    trace(R, rays, n, hits);
    for (i = 0; i < n; i++)
        sph_check(rob, &rays[i], sp, &hits[i], 1);
    trace(RF, rays, n, hits);
    for (i = 0; i < n; i++)
        sph_check(fast, &rays[i], sp, &hits[i], 0);
}

/* A scene holding one sphere; *sp: the sphere as the device has it. */
static void sphere_scene(dvec c, double r, cw_sphere *sp)
{
    scene s;
    host_world hw;
    base_scene(&s);
    add_sphere(&s, c, r);
    upload(&s);
    host_world_init(&hw, &s);
    assert_int_equal(hw.d.nsph, 1);
    *sp = hw.d.sph[0];
    host_world_free(&hw);
    scene_free(&s);
}

static void sph_print(const char *what, sph_stats *rob, sph_stats *fast)
{
    double med = sph_median(rob);
    printf("  %s: robust: %ld of %ld disagree with double outside the band (%ld inside it, "
           "widest %.2g uM; %ld hit), rel t err max %.2g median %.2g, |dt| <= %.2g uM/cos; "
           "fast: %ld disagree outside the band (%ld inside), rel t err max %.2g\n",
           what, rob->out, rob->n, rob->band, rob->widest, rob->ref_hits, rob->max_rel, med,
           rob->max_unit, fast->out, fast->band, fast->max_rel);
}

static void sph_stats_free(sph_stats *st)
{
    free(st->rel);
}

/* 1a. Far and tiny spheres: radius/distance 1e-1 .. 1e-6 at distances 1 .. 1e6. Rays from
 * random origins near the world origin towards random points of the disc of radius
 * sqrt(2) r around the centre, perpendicular to the line of sight: about half hit. */
static void test_sphere_far_tiny(void **state)
{
    static const double ratios[] = {1e-1, 1e-2, 1e-3, 1e-4, 1e-5, 1e-6};
    static const double dists[] = {1, 1e2, 1e4, 1e6};
    const size_t per = 25000; /* rays per (ratio, distance): 100000 per ratio */
    cw_ray *rays = malloc(per * sizeof *rays);
    cw_hit *hits = malloc(per * sizeof *hits);
    size_t ir, id, i;
    long total_out = 0, total_nan = 0;
    double t0 = sys_now(), worst_rel = 0;
    (void)state;
    assert_true(rays && hits);
    rng_seed(1);
    printf("far-tiny spheres (%zu rays per ratio, distances 1, 1e2, 1e4, 1e6):\n",
           per * sizeof dists / sizeof dists[0]);
    for (ir = 0; ir < sizeof ratios / sizeof ratios[0]; ir++) {
        sph_stats rob, fast;
        char what[64];
        sph_stats_init(&rob, 100000);
        sph_stats_init(&fast, 100000);
        for (id = 0; id < sizeof dists / sizeof dists[0]; id++) {
            double D = dists[id], r = ratios[ir] * D;
            dvec c = dscale(rnd_dir(), D);
            cw_sphere sp;
            sphere_scene(c, r, &sp);
            c = dv4(sp.center);
            r = sp.center.w;
            for (i = 0; i < per; i++) {
                dvec o = dscale(rnd_ball(), 0.01 * D), e1, e2, q;
                double rad = sqrt(2.0) * r * sqrt(rnd()), phi = rnd_in(0, 2 * PI_D);
                dbasis(dsub(c, o), &e1, &e2);
                q = dadd(c, dadd(dscale(e1, rad * cos(phi)), dscale(e2, rad * sin(phi))));
                rays[i] = make_ray(o, dsub(q, o));
            }
            sphere_run(&sp, rays, per, hits, &rob, &fast);
        }
        snprintf(what, sizeof what, "r/D %.0e", ratios[ir]);
        sph_print(what, &rob, &fast);
        total_out += rob.out;
        total_nan += rob.nan;
        if (rob.max_rel > worst_rel)
            worst_rel = rob.max_rel;
        sph_stats_free(&rob);
        sph_stats_free(&fast);
    }
    printf("  far-tiny spheres: %ld disagreements outside the band, %ld NaN, worst rel t err "
           "%.2g (%.1f s)\n",
           total_out, total_nan, worst_rel, sys_now() - t0);
    free(rays);
    free(hits);
    assert_int_equal(total_nan, 0);
    assert_int_equal(total_out, 0);
    assert_true(worst_rel < 1e-5);
}

/* 1b. A huge sphere (radius 1e6) seen from heights -1e4 .. 1e4 above its surface, and three
 * spheres (small near the origin, small far from it, huge) from origins on, just inside
 * and just outside the surface (nominally c + (r + delta) n, delta = 0, +-1 .. +-256 u M;
 * the double reference uses the rounded float origin whatever delta it got). */
static void test_sphere_huge_and_surface(void **state)
{
    static const double heights[] = {-1e4, -1e2, -1, 0.1, 1, 1e2, 1e4};
    static const double deltas[] = {0, 1, 4, 16, 64, 256};
    const size_t per = 10000;
    cw_ray *rays = malloc(per * sizeof *rays);
    cw_hit *hits = malloc(per * sizeof *hits);
    size_t ih, i, is, id;
    long total_out = 0, total_nan = 0;
    double t0 = sys_now();
    cw_sphere sp;
    dvec c;
    (void)state;
    assert_true(rays && hits);
    rng_seed(2);
    printf("huge sphere (r = 1e6, centre (0, -1e6, 0)), %zu rays per height, random "
           "directions:\n",
           per);
    sphere_scene(dv(0, -1e6, 0), 1e6, &sp);
    c = dv4(sp.center);
    for (ih = 0; ih < sizeof heights / sizeof heights[0]; ih++) {
        sph_stats rob, fast;
        char what[64];
        sph_stats_init(&rob, (long)per);
        sph_stats_init(&fast, (long)per);
        for (i = 0; i < per; i++) {
            dvec n = dnorm(dv(rnd_in(-1e3, 1e3), 1e6, rnd_in(-1e3, 1e3)));
            rays[i] = make_ray(dadd(c, dscale(n, sp.center.w + heights[ih])), rnd_dir());
        }
        sphere_run(&sp, rays, per, hits, &rob, &fast);
        snprintf(what, sizeof what, "height %g", heights[ih]);
        sph_print(what, &rob, &fast);
        total_out += rob.out;
        total_nan += rob.nan;
        sph_stats_free(&rob);
        sph_stats_free(&fast);
    }

    printf("rays from the surface (nominal offsets 0, +-1, 4, 16, 64, 256 u M along the normal), "
           "%zu rays per offset:\n",
           per);
    for (is = 0; is < 5; is++) {
        /* the last two visible from inside only (a negative radius) */
        static const char *const names[] = {
            "r 0.3 at (0.5, -0.25, 0.75)", "r 2 at (3e3, -1e3, 2e3)", "r 1e6 at (0, -1e6, 0)",
            "inside-only r 0.3 at (0.5, -0.25, 0.75)", "inside-only r 2 at (3e3, -1e3, 2e3)"};
        static const double cs[5][4] = {{0.5, -0.25, 0.75, 0.3},
                                        {3e3, -1e3, 2e3, 2},
                                        {0, -1e6, 0, 1e6},
                                        {0.5, -0.25, 0.75, -0.3},
                                        {3e3, -1e3, 2e3, -2}};
        double R0;
        sph_stats rob[3], fast[3]; /* on, inside, outside */
        int k;
        sphere_scene(dv(cs[is][0], cs[is][1], cs[is][2]), cs[is][3], &sp);
        c = dv4(sp.center);
        R0 = fabs(sp.center.w);
        assert_true((sp.center.w < 0) == (cs[is][3] < 0)); /* the sign reaches the kernels */
        for (k = 0; k < 3; k++) {
            sph_stats_init(&rob[k], 11 * (long)per);
            sph_stats_init(&fast[k], 11 * (long)per);
        }
        for (id = 0; id < 2 * (sizeof deltas / sizeof deltas[0]) - 1; id++) {
            /* id 0: on the surface; odd: inside; even: outside */
            double um = U_F * 2 * R0;
            double delta = id == 0 ? 0 : (id % 2 ? -1 : 1) * deltas[(id + 1) / 2] * um;
            int cls = id == 0 ? 0 : (id % 2 ? 1 : 2);
            for (i = 0; i < per; i++) {
                dvec n = rnd_dir();
                rays[i] = make_ray(dadd(c, dscale(n, R0 + delta)), rnd_dir());
            }
            sphere_run(&sp, rays, per, hits, &rob[cls], &fast[cls]);
        }
        for (k = 0; k < 3; k++) {
            static const char *const cls_name[] = {"on", "inside", "outside"};
            char what[96];
            snprintf(what, sizeof what, "%s, origin %s", names[is], cls_name[k]);
            sph_print(what, &rob[k], &fast[k]);
            total_out += rob[k].out;
            total_nan += rob[k].nan;
            sph_stats_free(&rob[k]);
            sph_stats_free(&fast[k]);
        }
    }
    printf("  huge and on-surface spheres: %ld disagreements outside the band, %ld NaN (%.1f s)\n",
           total_out, total_nan, sys_now() - t0);
    free(rays);
    free(hits);
    assert_int_equal(total_nan, 0);
    assert_int_equal(total_out, 0);
}

/* ---- 2. watertightness ------------------------------------------------------------------- */

typedef struct {
    dvec *v;
    int (*f)[3];
    int nv, nf, capv, capf;
} mesh;

static int mesh_vertex(mesh *m, dvec p)
{
    if (m->nv == m->capv) {
        m->capv = m->capv ? 2 * m->capv : 64;
        m->v = realloc(m->v, (size_t)m->capv * sizeof *m->v);
        assert_non_null(m->v);
    }
    m->v[m->nv] = p;
    return m->nv++;
}

static void mesh_face(mesh *m, int a, int b, int c)
{
    if (m->nf == m->capf) {
        m->capf = m->capf ? 2 * m->capf : 64;
        m->f = realloc(m->f, (size_t)m->capf * sizeof *m->f);
        assert_non_null(m->f);
    }
    m->f[m->nf][0] = a;
    m->f[m->nf][1] = b;
    m->f[m->nf][2] = c;
    m->nf++;
}

/* the midpoint vertex of edge (a, b), made once per edge (linear search: small meshes) */
static int mesh_mid(mesh *m, int (*cache)[3], int *ncache, int a, int b)
{
    int lo = a < b ? a : b, hi = a < b ? b : a, i, v;
    for (i = 0; i < *ncache; i++)
        if (cache[i][0] == lo && cache[i][1] == hi)
            return cache[i][2];
    v = mesh_vertex(m, dnorm(dscale(dadd(m->v[a], m->v[b]), 0.5)));
    cache[*ncache][0] = lo;
    cache[*ncache][1] = hi;
    cache[*ncache][2] = v;
    (*ncache)++;
    return v;
}

/* A unit icosphere: the icosahedron subdivided `levels` times, consistently wound. */
static void icosphere(mesh *m, int levels)
{
    static const int ico[20][3] = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                                   {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                                   {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                                   {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
    double t = (1 + sqrt(5.0)) / 2;
    double p[12][3] = {{-1, t, 0},  {1, t, 0},  {-1, -t, 0}, {1, -t, 0}, {0, -1, t},  {0, 1, t},
                       {0, -1, -t}, {0, 1, -t}, {t, 0, -1},  {t, 0, 1},  {-t, 0, -1}, {-t, 0, 1}};
    int i, l;
    memset(m, 0, sizeof *m);
    for (i = 0; i < 12; i++)
        mesh_vertex(m, dnorm(dv(p[i][0], p[i][1], p[i][2])));
    for (i = 0; i < 20; i++)
        mesh_face(m, ico[i][0], ico[i][1], ico[i][2]);
    for (l = 0; l < levels; l++) {
        int nf = m->nf, ncache = 0;
        int(*old)[3] = m->f;
        int(*cache)[3] = malloc((size_t)nf * 3 * sizeof *cache);
        assert_non_null(cache);
        m->f = NULL;
        m->nf = m->capf = 0;
        for (i = 0; i < nf; i++) {
            int a = old[i][0], b = old[i][1], c = old[i][2];
            int ab = mesh_mid(m, cache, &ncache, a, b), bc = mesh_mid(m, cache, &ncache, b, c),
                ca = mesh_mid(m, cache, &ncache, c, a);
            mesh_face(m, a, ab, ca);
            mesh_face(m, b, bc, ab);
            mesh_face(m, c, ca, bc);
            mesh_face(m, ab, bc, ca);
        }
        free(old);
        free(cache);
    }
}

/* Rays from random interior points at points of the mesh's shared edges (4 in 5: an edge
 * and a parameter at random) and at its vertices (1 in 5). */
static void watertight_case(const char *what, dvec centre, double radius, long nrays,
                            long *rob_miss_out)
{
    mesh m;
    scene s;
    vec3f *fvert;
    int(*edges)[2];
    int ne = 0, i, k;
    long done, rob_miss = 0, fast_miss = 0, n_edge = 0, n_vert = 0, nan = 0;
    double max_rel = 0, t0 = sys_now();
    cw_ray *rays = malloc(BATCH * sizeof *rays);
    cw_hit *hits = malloc(BATCH * sizeof *hits);
    double *texp = malloc(BATCH * sizeof *texp);
    int shown = 0;
    assert_true(rays && hits && texp);

    icosphere(&m, 3);
    fvert = malloc((size_t)m.nv * sizeof *fvert);
    edges = malloc((size_t)m.nf * 3 * sizeof *edges);
    assert_true(fvert && edges);
    for (i = 0; i < m.nv; i++)
        fvert[i] = fv(dadd(centre, dscale(m.v[i], radius)));
    base_scene(&s);
    for (i = 0; i < m.nf; i++) {
        add_triangle(&s, fvert[m.f[i][0]], fvert[m.f[i][1]], fvert[m.f[i][2]]);
        /* each undirected edge appears once as (a < b) in a closed, consistently wound mesh */
        for (k = 0; k < 3; k++) {
            int a = m.f[i][k], b = m.f[i][(k + 1) % 3];
            if (a < b) {
                edges[ne][0] = a;
                edges[ne][1] = b;
                ne++;
            }
        }
    }
    assert_int_equal(ne * 2, m.nf * 3); /* closed: every edge shared by two faces */
    upload(&s);

    for (done = 0; done < nrays; done += BATCH) {
        long n = nrays - done < BATCH ? nrays - done : BATCH, j;
        for (j = 0; j < n; j++) {
            dvec o = dv4(devscene_f4(fv(dadd(centre, dscale(rnd_ball(), 0.5 * radius))), 0)), q;
            if (rnd() < 0.8) {
                int e = rnd_int(ne);
                dvec a = dv(fvert[edges[e][0]].x, fvert[edges[e][0]].y, fvert[edges[e][0]].z);
                dvec b = dv(fvert[edges[e][1]].x, fvert[edges[e][1]].y, fvert[edges[e][1]].z);
                q = dadd(a, dscale(dsub(b, a), rnd()));
                n_edge++;
            } else {
                int v = rnd_int(m.nv);
                q = dv(fvert[v].x, fvert[v].y, fvert[v].z);
                n_vert++;
            }
            rays[j] = make_ray(o, dsub(q, o));
            texp[j] = dlen(dsub(q, o));
        }
        trace(R, rays, (size_t)n, hits);
        for (j = 0; j < n; j++) {
            if (isnan(hits[j].t))
                nan++;
            if (hits[j].kind != CW_PRIM_TRIANGLE) {
                rob_miss++;
                if (shown++ < 3) {
                    char buf[256];
                    ray_str(buf, sizeof buf, &rays[j]);
                    printf("    MISS: ray %s (expected exit at t = %.9g)\n", buf, texp[j]);
                }
            } else {
                double rel = fabs(hits[j].t - texp[j]) / texp[j];
                if (rel > max_rel)
                    max_rel = rel;
            }
        }
        trace(RF, rays, (size_t)n, hits);
        for (j = 0; j < n; j++)
            fast_miss += hits[j].kind != CW_PRIM_TRIANGLE;
    }
    printf("  %s: %d triangles, %d shared edges: %ld rays (%ld at edge points, %ld at vertices): "
           "robust %ld misses, %ld NaN, max rel t error %.2g; fast (Moeller-Trumbore) %ld misses "
           "(%.1f s)\n",
           what, m.nf, ne, nrays, n_edge, n_vert, rob_miss, nan, max_rel, fast_miss,
           sys_now() - t0);
    *rob_miss_out += rob_miss + nan;
    /* the exit point is the aimed-at point: t within a few u of the coordinates' size */
    assert_true(max_rel < 1e-4);
    free(rays);
    free(hits);
    free(texp);
    free(fvert);
    free(edges);
    free(m.v);
    free(m.f);
    scene_free(&s);
}

static void test_watertight_mesh(void **state)
{
    long miss = 0;
    (void)state;
    rng_seed(3);
    printf("watertight mesh (icosphere, rays from random interior points):\n");
    watertight_case("centre (1e3, -2e3, 5e3), radius 1", dv(1e3, -2e3, 5e3), 1, 1000000, &miss);
    watertight_case("centre (-3e5, 1e5, 2e5), radius 50", dv(-3e5, 1e5, 2e5), 50, 200000, &miss);
    assert_int_equal(miss, 0);
}

/* ---- 3. self-hits ------------------------------------------------------------------------ */

/* One scene per (scale, offset): a sphere, a pair of coplanar triangles sharing a diagonal,
 * a pair of coplanar polygons sharing an edge, an open cone; 8 x scale apart, so that
 * nothing but the surface itself lies within reach of a shadow ray (1.5 x scale long). A
 * "surface" is the primitive kind: the twins of a pair are the same surface.
 * Self-hits: a secondary ray hitting the surface it leaves, where it cannot legitimately:
 * reflection and shadow rays leave the side they arrived at and cannot meet the same sphere,
 * plane or (from outside) cone again; a refracted ray enters the sphere and meets it again
 * only at the far side, after a chord >= 1.49 r (ior 1.5), so there a hit closer than 0.5 r
 * is a self-hit; a ray refracted through a flat pair cannot meet its plane again.
 * Eye rays: from 6 x scale away in random directions at random points of each surface (the
 * sphere's whole disc, grazing rays included; half of the flat pairs' points within 1e-3 of
 * their shared edge or on it); cone hits from inside are skipped (legitimate re-hits there).
 * Spawning: prim_surface and shade_spawn on the host, skip = the surface's s.flat, exactly
 * as the shading does (shade_secondary); the fast path as its kernel does (o + t d + 1e-4 n, no
 * skip). */
#define SH_KINDS 4

typedef struct {
    dvec centre[SH_KINDS];
    dvec quad[4]; /* triangle pair: (0,1,2), (0,2,3) */
    dvec hex[6];  /* polygon pair: (0,1,2,3), (3,4,5,0) */
    dvec cone_base, cone_apex;
    double cone_r0, cone_r1;
} sh_layout;

static dvec sh_x(dvec p, double scale, dvec off)
{
    return dadd(off, dscale(p, scale));
}

static void sh_build(scene *s, sh_layout *L, double scale, dvec off)
{
    dvec e1 = dv(1.2, 0, 0.5), e2 = dv(0.2, 1.1, -0.4), c, n, f1, f2;
    vec3f v[6];
    int k;
    base_scene(s);
    L->centre[0] = dv(0, 0, 0);
    L->centre[1] = dv(8, 0, 0);
    L->centre[2] = dv(16, 0, 0);
    L->centre[3] = dv(24, 0, 0);
    add_sphere(s, sh_x(L->centre[0], scale, off), scale);
    c = L->centre[1];
    L->quad[0] = dsub(dsub(c, e1), e2);
    L->quad[1] = dsub(dadd(c, e1), e2);
    L->quad[2] = dadd(dadd(c, e1), e2);
    L->quad[3] = dadd(dsub(c, e1), e2);
    for (k = 0; k < 4; k++)
        v[k] = fv(sh_x(L->quad[k], scale, off));
    add_triangle(s, v[0], v[1], v[2]);
    add_triangle(s, v[0], v[2], v[3]);
    c = L->centre[2];
    n = dnorm(dv(0.3, -0.5, 1));
    dbasis(n, &f1, &f2);
    for (k = 0; k < 6; k++) {
        L->hex[k] =
            dadd(c, dadd(dscale(f1, 1.3 * cos(k * PI_D / 3)), dscale(f2, 1.3 * sin(k * PI_D / 3))));
        v[k] = fv(sh_x(L->hex[k], scale, off));
    }
    add_polygon(s, v, 4);
    {
        vec3f w[4];
        w[0] = v[3];
        w[1] = v[4];
        w[2] = v[5];
        w[3] = v[0];
        add_polygon(s, w, 4);
    }
    L->cone_base = dv(24, -1, 0);
    L->cone_apex = dv(24, 1, 0);
    L->cone_r0 = 1;
    L->cone_r1 = 0.3;
    add_cone(s, fv(sh_x(L->cone_base, scale, off)), (float)(scale * L->cone_r0),
             fv(sh_x(L->cone_apex, scale, off)), (float)(scale * L->cone_r1));
}

static int sh_surface(int kind)
{
    return kind - 1; /* sphere 0, triangles 1, polygons 2, cones 3 */
}

/* A random point (local coordinates) on surface g, seen from eye e. */
static dvec sh_target(const sh_layout *L, int g, dvec e)
{
    dvec e1, e2;
    if (g == 0) { /* a random point of the sphere's disc seen from e: grazing ones included */
        double rad = 0.9999 * sqrt(rnd()), phi = rnd_in(0, 2 * PI_D);
        dbasis(dsub(e, L->centre[0]), &e1, &e2);
        return dadd(L->centre[0], dadd(dscale(e1, rad * cos(phi)), dscale(e2, rad * sin(phi))));
    }
    if (g == 1) { /* half in the quad, half within 1e-3 of the shared diagonal (or on it) */
        dvec a = L->quad[0], b = L->quad[1], c = L->quad[2], d = L->quad[3];
        if (rnd() < 0.5)
            return dadd(a, dadd(dscale(dsub(b, a), rnd()), dscale(dsub(d, a), rnd())));
        return dadd(dadd(a, dscale(dsub(c, a), rnd())),
                    dscale(dsub(b, d), rnd() < 0.3 ? 0 : rnd_in(-1e-3, 1e-3)));
    }
    if (g == 2) { /* half in the hexagon's inscribed disc, half near the shared edge */
        dvec a = L->hex[0], b = L->hex[3], f = dsub(L->hex[1], L->hex[5]);
        if (rnd() < 0.5) {
            double rad = 1.3 * 0.86 * sqrt(rnd()), phi = rnd_in(0, 2 * PI_D);
            dvec n = dnorm(dcross(dsub(L->hex[1], L->hex[0]), dsub(L->hex[2], L->hex[0])));
            dbasis(n, &e1, &e2);
            return dadd(L->centre[2], dadd(dscale(e1, rad * cos(phi)), dscale(e2, rad * sin(phi))));
        }
        return dadd(dadd(a, dscale(dsub(b, a), rnd_in(0.01, 0.99))),
                    dscale(f, rnd() < 0.3 ? 0 : rnd_in(-1e-3, 1e-3)));
    }
    { /* cone: a point of its side, on the half facing e */
        double h = rnd_in(0.02, 0.98), r = L->cone_r0 + (L->cone_r1 - L->cone_r0) * h;
        dvec ax = dnorm(dsub(L->cone_apex, L->cone_base));
        dvec toe = dsub(e, L->cone_base), radial;
        double ang = rnd_in(-1.3, 1.3);
        toe = dnorm(dsub(toe, dscale(ax, ddot(toe, ax))));
        e2 = dcross(ax, toe);
        radial = dadd(dscale(toe, cos(ang)), dscale(e2, sin(ang)));
        return dadd(dadd(L->cone_base, dscale(ax, 2 * h)), dscale(radial, r));
    }
}

/* The fast path's origin (shade_spawn with CW_FAST: p = o + t d, moved 1e-4 along the
 * geometric normal to dir's side). ng: the geometric normal (the same formula on both
 * paths, so prim_surface's is used). */
static vec3 fast_spawn(vec3 p, vec3 ng, vec3 dir)
{
    vec3 n = v3_dot(dir, ng) < 0.0f ? v3_scale(ng, -1.0f) : ng;
    return v3_add(p, v3_scale(n, 1e-4f));
}

typedef struct {
    long eye_hits[SH_KINDS], inside_cone;
    long rays[3];           /* reflection, shadow, refraction */
    long self[3];           /* self-hits per kind of ray */
    long self_by[SH_KINDS]; /* self-hits per surface */
    long nan;
    long t_exact, t_checked;   /* host isect equal to the device's t, bit for bit */
    double max_off[SH_KINDS];  /* largest |spawned origin - hit point| / scale */
    double max_ulps[SH_KINDS]; /* the same in ulps of the hit point's largest coordinate */
} sh_stats;

/* ulp of a float of magnitude x (x normal) */
static double ulp_of(double x)
{
    int e;
    frexp(x, &e);
    return ldexp(1.0, e - 24);
}

static void sh_offset(sh_stats *st, int g, vec3 p, vec3 so, double scale)
{
    double off = dlen(dsub(dv3(so), dv3(p)));
    double m = fmax(fabs(p.x), fmax(fabs(p.y), fabs(p.z)));
    if (off / scale > st->max_off[g])
        st->max_off[g] = off / scale;
    if (m > 0 && off / ulp_of(m) > st->max_ulps[g])
        st->max_ulps[g] = off / ulp_of(m);
}

/* Spawns, traces and counts (see sh_build). fast: use the fast path's spawn and renderer. */
static void sh_run(const host_world *hw, const cw_ray *eye, const cw_hit *eh, size_t n,
                   double scale, int fast, sh_stats *st, int show)
{
    cw_ray *sec = malloc(2 * n * sizeof *sec);
    int *sec_surf = malloc(2 * n * sizeof *sec_surf), *sec_type = malloc(2 * n * sizeof *sec_type);
    float *sec_limit = malloc(2 * n * sizeof *sec_limit);
    cw_shadow_ray *sh = malloc(n * sizeof *sh);
    int *sh_surf = malloc(n * sizeof *sh_surf), *blocked = malloc(n * sizeof *blocked);
    cw_hit *h2 = malloc(2 * n * sizeof *h2);
    size_t i, ns = 0, nsh = 0;
    int shown = 0;
    renderer *r = fast ? RF : R;
    assert_true(sec && sec_surf && sec_type && sec_limit && sh && sh_surf && blocked && h2);
    for (i = 0; i < n; i++) {
        vec3 o = v3_from4(eye[i].origin), d = v3_from4(eye[i].dir), nf, p, l, refl, lp, tl, so;
        cw_surface s;
        int g, skip;
        float dist;
        dvec ld;
        if (eh[i].kind == CW_PRIM_NONE)
            continue;
        g = sh_surface(eh[i].kind);
        if (!fast) {
            float th = -1.0f;
            st->t_checked++;
            if (host_isect(hw, eh[i].kind, eh[i].index, &eye[i], &th) && th == eh[i].t)
                st->t_exact++;
            else if (!(fabsf(th - eh[i].t) <= 1e-4f * eh[i].t))
                fail_msg("hit index %d (kind %d): host t %.9g, device t %.9g: the host arrays do "
                         "not match the device's",
                         eh[i].index, eh[i].kind, th, eh[i].t);
        }
        s = prim_surface(&hw->w, eh[i], o, d);
        if (g == 3 && v3_dot(d, s.ng) > 0.0f) { /* inside the cone: legitimate re-hits */
            st->inside_cone++;
            continue;
        }
        st->eye_hits[g]++;
        nf = v3_dot(s.ns, d) > 0.0f ? v3_scale(s.ns, -1.0f) : s.ns;
        p = fast ? v3_add(o, v3_scale(d, eh[i].t)) : s.p;
        skip = fast ? 0 : s.flat;
        if (isnan(p.x) || isnan(s.ng.x) || isnan(s.ng.y) || isnan(s.ng.z))
            st->nan++;
        /* reflection */
        refl = v3_norm(v3_sub(d, v3_scale(nf, 2.0f * v3_dot(d, nf))));
        so = fast ? fast_spawn(p, s.ng, refl) : shade_spawn(&s, refl);
        sh_offset(st, g, p, so, scale);
        sec[ns] = ray_v3(so, refl, skip);
        sec_surf[ns] = g;
        sec_type[ns] = 0;
        sec_limit[ns] = FLT_MAX;
        ns++;
        /* shadow ray towards a light 1.5 x scale away, somewhere on the side facing the ray */
        ld = rnd_dir();
        if (ddot(ld, dv3(nf)) < 0)
            ld = dscale(ld, -1);
        lp = v3d(dadd(dv3(p), dscale(ld, 1.5 * scale)));
        tl = v3_sub(lp, p);
        dist = v3_len(tl);
        if (dist > 0.0f) {
            l = v3_scale(tl, 1.0f / dist);
            if (v3_dot(nf, l) > 0.0f) {
                so = fast ? fast_spawn(p, s.ng, l) : shade_spawn(&s, l);
                memset(&sh[nsh], 0, sizeof sh[nsh]);
                sh[nsh].origin = v4_from3(so, v3_len(v3_sub(lp, so)));
                sh[nsh].dir = v4_from3(l, 0.0f);
                sh[nsh].skip = skip;
                sh_surf[nsh] = g;
                nsh++;
            }
        }
        /* refraction (ior 1.5), as shade_secondary computes it: spheres and the flat pairs */
        if (g != 3) {
            int entering = v3_dot(d, s.ng) < 0.0f;
            float eta = entering ? 1.0f / 1.5f : 1.5f, cosi = -v3_dot(d, nf);
            float k2 = 1.0f - eta * eta * (1.0f - cosi * cosi);
            if (k2 >= 0.0f) {
                vec3 td = v3_norm(v3_add(v3_scale(d, eta), v3_scale(nf, eta * cosi - sqrtf(k2))));
                so = fast ? fast_spawn(p, s.ng, td) : shade_spawn(&s, td);
                sec[ns] = ray_v3(so, td, skip);
                sec_surf[ns] = g;
                sec_type[ns] = 2;
                sec_limit[ns] = g == 0 ? 0.5f * hw->d.sph[eh[i].index].center.w : FLT_MAX;
                ns++;
            }
        }
    }
    if (ns > 0)
        trace(r, sec, ns, h2);
    for (i = 0; i < ns; i++) {
        st->rays[sec_type[i]]++;
        if (hit_has_nan(&h2[i]) && h2[i].kind != CW_PRIM_NONE)
            st->nan++;
        if (h2[i].kind != CW_PRIM_NONE && sh_surface(h2[i].kind) == sec_surf[i] &&
            h2[i].t < sec_limit[i]) {
            st->self[sec_type[i]]++;
            st->self_by[sec_surf[i]]++;
            if (show && shown++ < 3) {
                char buf[256];
                ray_str(buf, sizeof buf, &sec[i]);
                printf("    SELF-HIT (%s ray): %s hit kind %d index %d at t = %.9g\n",
                       sec_type[i] ? "refraction" : "reflection", buf, h2[i].kind, h2[i].index,
                       h2[i].t);
            }
        }
    }
    if (nsh > 0)
        occlude(r, sh, nsh, blocked);
    for (i = 0; i < nsh; i++) {
        st->rays[1]++;
        if (blocked[i]) {
            st->self[1]++;
            st->self_by[sh_surf[i]]++;
            if (show && shown++ < 3) {
                char buf[256];
                cw_ray tmp = ray_v3(v3_from4(sh[i].origin), v3_from4(sh[i].dir), sh[i].skip);
                ray_str(buf, sizeof buf, &tmp);
                printf("    SELF-HIT (shadow ray, tmax %.9g): %s\n", sh[i].origin.w, buf);
            }
        }
    }
    free(sec);
    free(sec_surf);
    free(sec_type);
    free(sec_limit);
    free(sh);
    free(sh_surf);
    free(blocked);
    free(h2);
}

static void test_selfhit_scales(void **state)
{
    static const double scales[] = {1e-4, 1e-2, 1, 1e2, 1e4};
    const size_t n = 8000; /* eye rays per scene */
    cw_ray *eye = malloc(n * sizeof *eye);
    cw_hit *eh = malloc(n * sizeof *eh);
    size_t is, io, i;
    long total = 0, total_nan = 0, fast_total = 0, exact = 0, checked = 0;
    double t0 = sys_now();
    (void)state;
    assert_true(eye && eh);
    rng_seed(4);
    printf("self-hits (reflection, shadow and refraction rays from sphere, triangle pair, "
           "polygon pair, cone; %zu eye rays per scene):\n",
           n);
    for (is = 0; is < sizeof scales / sizeof scales[0]; is++) {
        for (io = 0; io < 2; io++) {
            double scale = scales[is];
            dvec off = io ? dscale(dnorm(dv(1, -2, 3)), 1e4 * scale) : dv(0, 0, 0);
            scene s;
            sh_layout L;
            host_world hw;
            sh_stats rob, fst;
            uint64_t seed_state;
            sh_build(&s, &L, scale, off);
            upload(&s);
            host_world_init(&hw, &s);
            for (i = 0; i < n; i++) {
                int g = (int)(i % SH_KINDS);
                dvec u, e, q;
                do
                    u = rnd_dir();
                while (fabs(u.x) > 0.5);
                e = dadd(L.centre[g], dscale(u, 6));
                q = sh_target(&L, g, e);
                eye[i] =
                    make_ray(sh_x(e, scale, off), dsub(sh_x(q, scale, off), sh_x(e, scale, off)));
            }
            memset(&rob, 0, sizeof rob);
            memset(&fst, 0, sizeof fst);
            seed_state = rng_s; /* same light directions for both paths */
            trace(R, eye, n, eh);
            sh_run(&hw, eye, eh, n, scale, 0, &rob, 1);
            rng_s = seed_state;
            trace(RF, eye, n, eh);
            sh_run(&hw, eye, eh, n, scale, 1, &fst, 0);
            printf("  scale %g, offset %g: eye hits %ld/%ld/%ld/%ld (sphere/triangles/polygons/"
                   "cone outside), rays %ld/%ld/%ld (refl/shadow/refr): robust self-hits "
                   "%ld/%ld/%ld; fast self-hits %ld/%ld/%ld (by surface %ld/%ld/%ld/%ld)\n",
                   scale, io ? 1e4 * scale : 0.0, rob.eye_hits[0], rob.eye_hits[1], rob.eye_hits[2],
                   rob.eye_hits[3], rob.rays[0], rob.rays[1], rob.rays[2], rob.self[0], rob.self[1],
                   rob.self[2], fst.self[0], fst.self[1], fst.self[2], fst.self_by[0],
                   fst.self_by[1], fst.self_by[2], fst.self_by[3]);
            printf("    robust spawn offsets, max per surface: %.2g/%.2g/%.2g/%.2g x scale, "
                   "%.0f/%.0f/%.0f/%.0f ulps of the hit point\n",
                   rob.max_off[0], rob.max_off[1], rob.max_off[2], rob.max_off[3], rob.max_ulps[0],
                   rob.max_ulps[1], rob.max_ulps[2], rob.max_ulps[3]);
            total += rob.self[0] + rob.self[1] + rob.self[2];
            total_nan += rob.nan;
            fast_total += fst.self[0] + fst.self[1] + fst.self[2];
            exact += rob.t_exact;
            checked += rob.t_checked;
            /* every surface must have been hit and tested */
            assert_true(rob.eye_hits[0] > 0 && rob.eye_hits[1] > 0 && rob.eye_hits[2] > 0 &&
                        rob.eye_hits[3] > 0);
            host_world_free(&hw);
            scene_free(&s);
        }
    }
    printf("  self-hits: robust %ld, NaN %ld; fast %ld; device t equal to the host's kernel code "
           "bit for bit on %ld of %ld eye hits (%.1f s)\n",
           total, total_nan, fast_total, exact, checked, sys_now() - t0);
    free(eye);
    free(eh);
    assert_int_equal(total_nan, 0);
    assert_int_equal(total, 0);
}

/* ---- 4. grazing rays ---------------------------------------------------------------------- */

/* Rays whose closest approach to the centre is r (1 + k 1e-7), k = 0, +-1 .. +-128, in random
 * orientations, from 2 .. 10 radii away; and exact tangents (axis-aligned rays at exactly
 * distance r from the centre, all values exact in float). */
static void test_grazing(void **state)
{
    static const int ks[] = {0, 1, 2, 4, 8, 16, 32, 64, 128};
    static const double cs[2][4] = {{0.25, -0.5, -5, 1}, {1e3, 2e3, -3e3, 0.5}};
    const size_t per = 4000; /* per sign of k */
    cw_ray *rays = malloc(2 * per * sizeof *rays);
    cw_hit *hits = malloc(2 * per * sizeof *hits);
    size_t ic, ik, i;
    long total_out = 0, total_nan = 0;
    (void)state;
    assert_true(rays && hits);
    rng_seed(5);
    printf("grazing rays (closest approach r (1 + k 1e-7)), %zu rays per k:\n", 2 * per);
    for (ic = 0; ic < 2; ic++) {
        cw_sphere sp;
        dvec c;
        double r;
        sphere_scene(dv(cs[ic][0], cs[ic][1], cs[ic][2]), cs[ic][3], &sp);
        c = dv4(sp.center);
        r = sp.center.w;
        printf("  sphere r %g at (%g, %g, %g):\n", r, c.x, c.y, c.z);
        for (ik = 0; ik < sizeof ks / sizeof ks[0]; ik++) {
            sph_stats rob, fast;
            long n2 = 0;
            sph_stats_init(&rob, 2 * (long)per);
            sph_stats_init(&fast, 2 * (long)per);
            for (i = 0; i < 2 * per; i++) {
                double k = (i < per ? 1 : -1) * ks[ik];
                dvec d = rnd_dir(), e1, e2, q;
                double phi = rnd_in(0, 2 * PI_D);
                dbasis(d, &e1, &e2);
                q = dadd(c, dscale(dadd(dscale(e1, cos(phi)), dscale(e2, sin(phi))),
                                   r * (1 + k * 1e-7)));
                rays[i] = make_ray(dsub(q, dscale(d, rnd_in(2, 10) * r)), d);
            }
            if (ks[ik] == 0)
                n2 = (long)per; /* k = 0 once */
            sphere_run(&sp, rays, 2 * per - (size_t)n2, hits, &rob, &fast);
            printf("    k = +-%d: %ld rays, double %ld hits, robust %ld hits: %ld disagree "
                   "outside the band, %ld inside it (widest %.2g uM); fast %ld hits, %ld "
                   "outside, %ld inside\n",
                   ks[ik], rob.n, rob.ref_hits, rob.hits, rob.out, rob.band, rob.widest, fast.hits,
                   fast.out, fast.band);
            total_out += rob.out;
            total_nan += rob.nan;
            sph_stats_free(&rob);
            sph_stats_free(&fast);
        }
    }

    { /* exact tangents: closest approach exactly r in float, so r^2 - |perp|^2 = 0 */
        static const double tc[2][4] = {{2, -3, -8, 1.5}, {1024, -2048, -4096, 0.375}};
        long ok = 0, nt = 0, fast_ok = 0;
        int a, sgn, side;
        for (ic = 0; ic < 2; ic++) {
            cw_sphere sp;
            cw_hit fh[12];
            double want[12];
            sphere_scene(dv(tc[ic][0], tc[ic][1], tc[ic][2]), tc[ic][3], &sp);
            i = 0;
            for (a = 0; a < 3; a++) { /* ray along axis a, displaced by r along axis (a+1)%3 */
                for (sgn = -1; sgn <= 1; sgn += 2) {
                    for (side = -1; side <= 1; side += 2) {
                        double o[3] = {tc[ic][0], tc[ic][1], tc[ic][2]}, d[3] = {0, 0, 0};
                        o[(a + 1) % 3] += side * tc[ic][3];
                        o[a] -= sgn * 4.0;
                        d[a] = sgn;
                        rays[i] = make_ray(dv(o[0], o[1], o[2]), dv(d[0], d[1], d[2]));
                        want[i] = 4.0;
                        i++;
                    }
                }
            }
            trace(R, rays, 12, hits);
            trace(RF, rays, 12, fh);
            for (i = 0; i < 12; i++) {
                sph_ref ref = sphere_ref(&rays[i], &sp);
                nt++;
                assert_true(ref.n == 2 && ref.rho == sp.center.w); /* exact tangent */
                if (hits[i].kind == CW_PRIM_SPHERE && hits[i].t == (float)want[i] &&
                    !hit_has_nan(&hits[i]))
                    ok++;
                else {
                    char buf[256];
                    ray_str(buf, sizeof buf, &rays[i]);
                    printf("    TANGENT: ray %s: kind %d t %.9g (want a hit at %g)\n", buf,
                           hits[i].kind, hits[i].t, want[i]);
                }
                fast_ok += fh[i].kind == CW_PRIM_SPHERE && fh[i].t == (float)want[i];
            }
        }
        printf("  exact tangents: robust %ld of %ld hit at the tangent point exactly; fast %ld\n",
               ok, nt, fast_ok);
        assert_int_equal(ok, nt);
    }
    printf("  grazing: %ld disagreements outside the band, %ld NaN\n", total_out, total_nan);
    free(rays);
    free(hits);
    assert_int_equal(total_nan, 0);
    assert_int_equal(total_out, 0);
}

/* ---- 5. degenerate, needle, tiny triangles -----------------------------------------------------
 */

/* Double-precision test of the float ray against triangle t: 1 and *t_out, *edge_dist (the
 * hit point's distance to the nearest edge line, in units of u M / cos, negative outside)
 * when the ray's line meets the plane in front of the origin; 0 otherwise. */
static int tri_ref(const cw_ray *ray, const cw_triangle *t, double *t_out, double *edge_units)
{
    dvec o = dv4(ray->origin), d = dv4(ray->dir);
    dvec p[3] = {dv4(t->p0), dv4(t->p1), dv4(t->p2)}, n, q;
    double dn, tt, M = 0, cosv, m = INFINITY;
    int k, inside = 1;
    n = dcross(dsub(p[1], p[0]), dsub(p[2], p[0]));
    if (dlen(n) == 0)
        return 0;
    n = dnorm(n);
    dn = ddot(n, d);
    if (dn == 0)
        return 0;
    tt = ddot(n, dsub(p[0], o)) / dn;
    if (!(tt > 0))
        return 0;
    q = dadd(o, dscale(d, tt));
    for (k = 0; k < 3; k++) {
        dvec a = p[k], b = p[(k + 1) % 3], e = dsub(b, a);
        double side = ddot(dcross(e, dsub(q, a)), n), dist = fabs(side) / dlen(e);
        if (side < 0)
            inside = 0;
        if (dist < m)
            m = dist;
        if (dlen(dsub(a, o)) > M)
            M = dlen(dsub(a, o));
    }
    cosv = fabs(dn) / dlen(d);
    *t_out = tt;
    *edge_units = (inside ? 1 : -1) * m * cosv / (U_F * M);
    return 1;
}

/* Zero-area triangles: exactly collinear vertices (dyadic values, exact in float, so the
 * triangles are degenerate in float too) and coincident ones, near the origin and 2048 away;
 * 100,000 rays aimed at points of their segments from random directions (one in ten from
 * the segment's own z plane). No hit, no NaN. Then the renderer end to end: a 1x1
 * orthographic camera whose one ray is the first ray found to hit (the reproducer printed
 * with it), or a fixed reproducer: the pixel must be the background, not NaN. */
static void test_degenerate_zero_area(void **state)
{
    static const double base[6][3] = {{0, 0, -2},       {0.25, 0.5, -3},       {-1, -1, -2.5},
                                      {-0.5, 0.75, -2}, {0.375, 0.125, -2.25}, {1, 1, -3}};
    static const double dir[6][3] = {{1, 0, 0}, {0.25, 0.5, 0.75}, {0.5, -0.25, 0.125},
                                     {0, 0, 0}, {0.5, 0.5, 0},     {0.125, -0.375, 0.25}};
    static const char *const kind_name[3] = {"collinear", "coincident pair", "all equal"};
    const size_t n = 100000;
    cw_ray *rays = malloc(n * sizeof *rays);
    cw_hit *hits = malloc(n * sizeof *hits);
    scene s;
    host_world hw;
    long rob_hits = 0, fast_hits = 0, nan = 0, shade_nan = 0, by_kind[3] = {0, 0, 0};
    long aimed[3] = {0, 0, 0}, px_bad = 0;
    double off[2] = {0, 2048};
    int nt = 0, k, tri_kind[12], found = -1;
    size_t i;
    cw_ray repro;
    (void)state;
    assert_true(rays && hits);
    rng_seed(6);
    base_scene(&s);
    for (k = 0; k < 12; k++) {
        int j = k % 6;
        double o = off[k / 6];
        dvec a = dv(base[j][0] + o, base[j][1] - o, base[j][2] + o);
        dvec dd = dv(dir[j][0], dir[j][1], dir[j][2]);
        if (j == 3) { /* coincident: p0 = p1, p2 elsewhere */
            add_triangle(&s, fv(a), fv(a), fv(dadd(a, dv(1, -0.5, -0.5))));
            tri_kind[k] = 1;
        } else if (j == 5) { /* all three equal */
            add_triangle(&s, fv(a), fv(a), fv(a));
            tri_kind[k] = 2;
        } else { /* collinear: a, a + 3 d, a + d */
            add_triangle(&s, fv(a), fv(dadd(a, dscale(dd, 3))), fv(dadd(a, dd)));
            tri_kind[k] = 0;
        }
        nt++;
    }
    upload(&s);
    host_world_init(&hw, &s);
    for (i = 0; i < n; i++) {
        int ti = rnd_int(nt);
        const cw_triangle *t = &hw.d.tri[ti];
        dvec p0 = dv4(t->p0), p1 = dv4(t->p1), p2 = dv4(t->p2), q, o;
        double w = rnd();
        aimed[tri_kind[ti]]++;
        q = rnd() < 0.5 ? dadd(p0, dscale(dsub(p1, p0), w)) : dadd(p0, dscale(dsub(p2, p0), w));
        o = dadd(q, dscale(rnd_dir(), rnd_in(0.5, 5)));
        if (rnd() < 0.1)
            o.z = q.z;
        rays[i] = make_ray(o, dsub(q, o));
    }
    trace(R, rays, n, hits);
    for (i = 0; i < n; i++) {
        if (isnan(hits[i].t) || isnan(hits[i].u) || isnan(hits[i].v))
            nan++;
        if (hits[i].kind != CW_PRIM_NONE) {
            const cw_triangle *t = &hw.d.tri[hits[i].index];
            cw_surface sf =
                prim_surface(&hw.w, hits[i], v3_from4(rays[i].origin), v3_from4(rays[i].dir));
            by_kind[tri_kind[hits[i].index]]++;
            if (found < 0)
                found = (int)i;
            if (rob_hits++ < 3) {
                char buf[256];
                ray_str(buf, sizeof buf, &rays[i]);
                printf("    DEGENERATE HIT: ray %s hits triangle (%.9g, %.9g, %.9g) (%.9g, %.9g, "
                       "%.9g) (%.9g, %.9g, %.9g) at t = %.9g, u = %.9g, v = %.9g; prim_surface "
                       "normal (%g, %g, %g)\n",
                       buf, t->p0.x, t->p0.y, t->p0.z, t->p1.x, t->p1.y, t->p1.z, t->p2.x, t->p2.y,
                       t->p2.z, hits[i].t, hits[i].u, hits[i].v, sf.ng.x, sf.ng.y, sf.ng.z);
            }
            if (!isfinite(sf.ng.x) || !isfinite(sf.ng.y) || !isfinite(sf.ng.z))
                shade_nan++;
        }
    }
    trace(RF, rays, n, hits);
    for (i = 0; i < n; i++)
        fast_hits += hits[i].kind != CW_PRIM_NONE;
    printf("zero-area triangles (%d; %zu rays at their segments): robust %ld hits, %ld NaN in "
           "hits, %ld non-finite normals from prim_surface; fast %ld hits\n",
           nt, n, rob_hits, nan, shade_nan, fast_hits);
    for (k = 0; k < 3; k++)
        printf("  %s: %ld rays, robust %ld hits\n", kind_name[k], aimed[k], by_kind[k]);

    /* end to end: the renderer's own camera ray, origin = eye and direction = -w exactly */
    if (found >= 0) {
        repro = rays[found];
    } else { /* a ray that hit the collinear triangle (0.25, 0.5, -3) + {0, 3, 1} (0.25, 0.5,
              * 0.75) when this test was written */
        repro = make_ray(dv(0, 0, 0), dv(1, 0, 0));
        repro.origin.x = 1.80175662f;
        repro.origin.y = 0.801202357f;
        repro.origin.z = -0.608117342f;
        repro.dir.x = -0.647593021f;
        repro.dir.y = 0.676852643f;
        repro.dir.z = -0.349991083f;
    }
    {
        scene_light l;
        dvec w = dscale(dv4(repro.dir), -1), u, v;
        image img;
        dbasis(w, &u, &v);
        s.camera.projection = SCENE_ORTHOGRAPHIC;
        s.camera.eye = vec3d_make(repro.origin.x, repro.origin.y, repro.origin.z);
        s.camera.w = vec3f_make(-repro.dir.x, -repro.dir.y, -repro.dir.z);
        s.camera.u = fv(u);
        s.camera.v = fv(v);
        s.camera.l = s.camera.b = -1e-3f;
        s.camera.r = s.camera.t = 1e-3f;
        s.background = vec3f_make(0.25f, 0.5f, 0.75f);
        l.position = vec3d_make(3, 4, 5);
        l.intensity = vec3f_make(1, 1, 1);
        assert_true(scene_push(&s.lights, &l, sizeof l) >= 0);
        upload(&s);
        if (renderer_render(R, &img, err, sizeof err) != 0)
            fail_msg("%s", err);
        px_bad = !(img.rgb[0] == 0.25f && img.rgb[1] == 0.5f && img.rgb[2] == 0.75f);
        printf("  rendered through %s ray: pixel (%g, %g, %g), background (0.25, 0.5, 0.75)\n",
               found >= 0 ? "that first hitting" : "the fixed reproducer", img.rgb[0], img.rgb[1],
               img.rgb[2]);
        image_free(&img);
    }
    host_world_free(&hw);
    scene_free(&s);
    free(rays);
    free(hits);
    assert_int_equal(nan, 0);
    assert_int_equal(shade_nan, 0);
    assert_int_equal(rob_hits, 0);
    assert_int_equal(px_bad, 0);
}

/* Needles: base 1e-6, sides 1, at distance 2 in random orientations; rays from the origin
 * at random points in and around them (barycentrics -0.1 .. 1.1). Hit/miss as double
 * precision says, except within the band of an edge; no NaN, finite normals. */
static void test_needle_triangles(void **state)
{
    const size_t n = 100000;
    const int nt = 20;
    cw_ray *rays = malloc(n * sizeof *rays);
    cw_hit *hits = malloc(n * sizeof *hits);
    scene s;
    host_world hw;
    long agree = 0, band = 0, out = 0, nan = 0, rob_hits = 0, fast_hits = 0, ref_in = 0;
    long shade_nan = 0, fast_agree = 0;
    size_t i;
    int k;
    (void)state;
    assert_true(rays && hits);
    rng_seed(7);
    base_scene(&s);
    for (k = 0; k < nt; k++) {
        dvec c = dscale(rnd_dir(), 2), e1, e2, a, b, tip;
        dbasis(dadd(dnorm(c), dscale(rnd_dir(), 0.5)), &e1, &e2);
        a = dadd(c, dscale(e1, -0.5));
        b = dadd(a, dscale(e2, 1e-6));
        tip = dadd(c, dscale(e1, 0.5));
        add_triangle(&s, fv(a), fv(b), fv(tip));
    }
    upload(&s);
    host_world_init(&hw, &s);
    for (i = 0; i < n; i++) {
        const cw_triangle *t = &hw.d.tri[rnd_int(nt)];
        dvec p0 = dv4(t->p0), p1 = dv4(t->p1), p2 = dv4(t->p2), q;
        double b1 = rnd(), b2 = rnd() * (1 - b1);
        b1 = b1 * 1.2 - 0.1;
        b2 = b2 * 1.2 - 0.1;
        q = dadd(p0, dadd(dscale(dsub(p1, p0), b1), dscale(dsub(p2, p0), b2)));
        rays[i] = make_ray(dv(0, 0, 0), q);
    }
    trace(R, rays, n, hits);
    for (i = 0; i < n; i++) {
        double tr, eu;
        int rin = 0, near = 0, j;
        if (hit_has_nan(&hits[i]) && hits[i].kind != CW_PRIM_NONE)
            nan++;
        rob_hits += hits[i].kind != CW_PRIM_NONE;
        if (hits[i].kind != CW_PRIM_NONE) {
            cw_surface sf =
                prim_surface(&hw.w, hits[i], v3_from4(rays[i].origin), v3_from4(rays[i].dir));
            if (!isfinite(sf.ng.x) || !isfinite(sf.ng.y) || !isfinite(sf.ng.z) || !isfinite(sf.p.x))
                shade_nan++;
        }
        /* the ray may pass near other needles than the aimed one: any of them counts */
        for (j = 0; j < nt; j++) {
            if (tri_ref(&rays[i], &hw.d.tri[j], &tr, &eu)) {
                if (eu >= 0)
                    rin = 1;
                if (fabs(eu) <= KB)
                    near = 1;
            }
        }
        ref_in += rin;
        if (rin == (hits[i].kind != CW_PRIM_NONE))
            agree++;
        else if (near)
            band++;
        else
            out++;
    }
    trace(RF, rays, n, hits);
    for (i = 0; i < n; i++) {
        double tr, eu;
        int rin = 0, j;
        fast_hits += hits[i].kind != CW_PRIM_NONE;
        for (j = 0; j < nt; j++)
            if (tri_ref(&rays[i], &hw.d.tri[j], &tr, &eu) && eu >= 0)
                rin = 1;
        fast_agree += rin == (hits[i].kind != CW_PRIM_NONE);
    }
    printf("needle triangles (%d: base 1e-6, sides 1, at distance 2; %zu rays in and around "
           "them): double says %ld inside; robust %ld hits, %ld agree, %ld disagree within the "
           "band of an edge, %ld outside it, %ld NaN, %ld non-finite from prim_surface; fast "
           "%ld hits, %ld agree\n",
           nt, n, ref_in, rob_hits, agree, band, out, nan, shade_nan, fast_hits, fast_agree);
    host_world_free(&hw);
    scene_free(&s);
    free(rays);
    free(hits);
    assert_int_equal(nan, 0);
    assert_int_equal(shade_nan, 0);
    assert_int_equal(out, 0);
}

/* Tiny triangles, which no determinant epsilon may drop: 5000 equilateral ones of
 * circumradius 1e-6 at distance 1 in random directions, rays from the origin (exactly 0)
 * and from random points within 1e-3 of it to their centroids; then one triangle of size
 * 1e-3 .. 1e-18 near the z axis at z = -1 with axis-aligned rays through interior points
 * (exact rays: no direction rounding). Every ray must hit its triangle. */
static void test_tiny_triangles(void **state)
{
    static const double sizes[] = {1e-3, 1e-6, 1e-9, 1e-12, 1e-15, 1e-18};
    const int nt = 5000;
    cw_ray *rays = malloc(2 * (size_t)nt * sizeof *rays);
    cw_hit *hits = malloc(2 * (size_t)nt * sizeof *hits);
    scene s;
    long miss = 0, fast_miss = 0, nan = 0, miss_total = 0;
    size_t i, is;
    int k;
    (void)state;
    assert_true(rays && hits);
    rng_seed(8);
    base_scene(&s);
    for (k = 0; k < nt; k++) {
        dvec c = rnd_dir(), e1, e2, v[3];
        int j;
        dbasis(dadd(c, dscale(rnd_dir(), 0.5)), &e1, &e2);
        for (j = 0; j < 3; j++)
            v[j] = dadd(c, dscale(dadd(dscale(e1, cos(j * 2 * PI_D / 3)),
                                       dscale(e2, sin(j * 2 * PI_D / 3))),
                                  1e-6));
        add_triangle(&s, fv(v[0]), fv(v[1]), fv(v[2]));
    }
    upload(&s);
    for (i = 0; i < 2 * (size_t)nt; i++) {
        const scene_triangle *t = &SCENE_AT(s.triangles, scene_triangle, i % nt);
        dvec q = dv(0, 0, 0), o;
        for (k = 0; k < 3; k++)
            q = dadd(q, dscale(dv(t->p[k].x, t->p[k].y, t->p[k].z), 1.0 / 3));
        o = i < (size_t)nt ? dv(0, 0, 0) : dscale(rnd_ball(), 1e-3);
        rays[i] = make_ray(o, dsub(q, o));
    }
    trace(R, rays, 2 * (size_t)nt, hits);
    for (i = 0; i < 2 * (size_t)nt; i++) {
        if (hit_has_nan(&hits[i]) && hits[i].kind != CW_PRIM_NONE)
            nan++;
        if (hits[i].kind != CW_PRIM_TRIANGLE || hits[i].index != (int)(i % nt)) {
            if (miss++ < 3) {
                char buf[256];
                ray_str(buf, sizeof buf, &rays[i]);
                printf("    TINY MISS: ray %s, got kind %d index %d\n", buf, hits[i].kind,
                       hits[i].index);
            }
        }
    }
    trace(RF, rays, 2 * (size_t)nt, hits);
    for (i = 0; i < 2 * (size_t)nt; i++)
        fast_miss += hits[i].kind != CW_PRIM_TRIANGLE || hits[i].index != (int)(i % nt);
    printf("tiny triangles (%d, circumradius 1e-6 at distance 1; %d rays at their centroids): "
           "robust %ld misses, %ld NaN; fast %ld misses\n",
           nt, 2 * nt, miss, nan, fast_miss);
    scene_free(&s);
    miss_total += miss + nan;

    printf("tiny triangles by absolute size, axis-aligned rays through interior points:");
    for (is = 0; is < sizeof sizes / sizeof sizes[0]; is++) {
        double sz = sizes[is];
        long m_rob = 0, m_fast = 0;
        const size_t m = 200;
        scene s1;
        base_scene(&s1);
        add_triangle(&s1, fv(dv(sz, 0.25 * sz, -1)), fv(dv(-0.5 * sz, sz, -1)),
                     fv(dv(-0.25 * sz, -sz, -1)));
        upload(&s1);
        for (i = 0; i < m; i++) {
            const scene_triangle *t = &SCENE_AT(s1.triangles, scene_triangle, 0);
            dvec p0 = dv(t->p[0].x, t->p[0].y, t->p[0].z);
            dvec p1 = dv(t->p[1].x, t->p[1].y, t->p[1].z);
            dvec p2 = dv(t->p[2].x, t->p[2].y, t->p[2].z);
            double b1 = rnd_in(0.1, 0.8), b2 = rnd_in(0.1, 0.9 - b1);
            dvec q = dadd(p0, dadd(dscale(dsub(p1, p0), b1), dscale(dsub(p2, p0), b2)));
            rays[i] = make_ray(dv(q.x, q.y, 0), dv(0, 0, -1));
        }
        trace(R, rays, m, hits);
        for (i = 0; i < m; i++)
            m_rob += hits[i].kind != CW_PRIM_TRIANGLE || hit_has_nan(&hits[i]);
        trace(RF, rays, m, hits);
        for (i = 0; i < m; i++)
            m_fast += hits[i].kind != CW_PRIM_TRIANGLE;
        printf(" %g: robust %ld/%zu missed, fast %ld;", sz, m_rob, m, m_fast);
        miss_total += m_rob;
        scene_free(&s1);
    }
    printf("\n");
    free(rays);
    free(hits);
    assert_int_equal(miss_total, 0);
}

/* Rays parallel to a face: exactly (d.z = 0) in its plane z = -2 and 1e-30 .. 1e-7 off it,
 * through the triangle's outline, near the origin and 1000 away: no hit, no NaN. Rays in a
 * tilted face's plane up to rounding: any answer, but no NaN. */
static void test_parallel_rays(void **state)
{
    static const double dz[] = {0, 1e-7, -1e-7, 1e-30, -1e-30};
    const size_t m = 20000;
    cw_ray *rays = malloc(m * sizeof *rays);
    cw_hit *hits = malloc(m * sizeof *hits);
    scene s;
    long hitsn = 0, nan = 0, tilted_hits = 0, tilted_nan = 0, fast_hits = 0;
    dvec tn = dnorm(dv(0.3, -0.4, 0.85)), te1, te2, tc = dv(0.5, 0.5, -4);
    size_t i;
    (void)state;
    assert_true(rays && hits);
    rng_seed(9);
    base_scene(&s);
    add_triangle(&s, vec3f_make(0, 0, -2), vec3f_make(1, 0, -2), vec3f_make(0, 1, -2));
    add_triangle(&s, vec3f_make(1000, 0, -2), vec3f_make(1001, 0, -2), vec3f_make(1000, 1, -2));
    dbasis(tn, &te1, &te2);
    add_triangle(&s, fv(dadd(tc, te1)), fv(dadd(tc, te2)), fv(dsub(tc, dadd(te1, te2))));
    upload(&s);
    for (i = 0; i < m; i++) {
        double x0 = rnd() < 0.5 ? 0 : 1000, ang = rnd_in(0, 2 * PI_D);
        double b1 = rnd(), b2 = rnd() * (1 - b1);
        dvec q = dv(x0 + b1, b2, -2), d = dv(cos(ang), sin(ang), 0);
        dvec o = dsub(q, dscale(d, rnd_in(1.5, 3)));
        o.z = -2 + dz[rnd_int(sizeof dz / sizeof dz[0])];
        rays[i] = make_ray(o, d);
        rays[i].dir.z = 0; /* exactly parallel */
    }
    trace(R, rays, m, hits);
    for (i = 0; i < m; i++) {
        hitsn += hits[i].kind != CW_PRIM_NONE;
        nan += isnan(hits[i].t) || isnan(hits[i].u) || isnan(hits[i].v);
    }
    trace(RF, rays, m, hits);
    for (i = 0; i < m; i++)
        fast_hits += hits[i].kind != CW_PRIM_NONE;
    for (i = 0; i < m; i++) { /* the tilted face: direction and origin in its plane */
        double ang = rnd_in(0, 2 * PI_D);
        dvec d = dadd(dscale(te1, cos(ang)), dscale(te2, sin(ang)));
        dvec o = dsub(dadd(tc, dscale(te1, rnd_in(-0.3, 0.3))), dscale(d, 2));
        rays[i] = make_ray(o, d);
    }
    trace(R, rays, m, hits);
    for (i = 0; i < m; i++) {
        tilted_hits += hits[i].kind != CW_PRIM_NONE;
        tilted_nan += isnan(hits[i].t) || isnan(hits[i].u) || isnan(hits[i].v);
    }
    printf("rays parallel to a face (%zu exactly parallel, in the plane or 1e-30 .. 1e-7 off "
           "it): robust %ld hits, %ld NaN; fast %ld hits; %zu rays in a tilted face's plane up "
           "to rounding: robust %ld hits, %ld NaN\n",
           m, hitsn, nan, fast_hits, m, tilted_hits, tilted_nan);
    scene_free(&s);
    free(rays);
    free(hits);
    assert_int_equal(hitsn, 0);
    assert_int_equal(nan + tilted_nan, 0);
}

/* ---- 6. image invariance ------------------------------------------------------------------ */

static vec3d xf(vec3d p, double scale, dvec off)
{
    dvec q = dadd(off, dscale(dv(p.x, p.y, p.z), scale));
    return vec3d_make(q.x, q.y, q.z);
}

/* Scales the whole scene by `scale` about the origin, then moves it by off: camera, lights,
 * geometry. The viewing basis and window are angular and stay. */
static void transform_scene(scene *s, double scale, dvec off)
{
    size_t i;
    int k;
    s->camera.eye = xf(s->camera.eye, scale, off);
    for (i = 0; i < s->spheres.count; i++) {
        scene_sphere *sp = &SCENE_AT(s->spheres, scene_sphere, i);
        sp->center = xf(sp->center, scale, off);
        sp->radius = (float)(sp->radius * scale);
    }
    for (i = 0; i < s->triangles.count; i++)
        for (k = 0; k < 3; k++)
            SCENE_AT(s->triangles, scene_triangle, i).p[k] =
                xf(SCENE_AT(s->triangles, scene_triangle, i).p[k], scale, off);
    for (i = 0; i < s->poly_verts.count; i++)
        SCENE_AT(s->poly_verts, vec3d, i) = xf(SCENE_AT(s->poly_verts, vec3d, i), scale, off);
    for (i = 0; i < s->lights.count; i++)
        SCENE_AT(s->lights, scene_light, i).position =
            xf(SCENE_AT(s->lights, scene_light, i).position, scale, off);
    for (i = 0; i < s->cones.count; i++) {
        scene_cone *c = &SCENE_AT(s->cones, scene_cone, i);
        c->base = xf(c->base, scale, off);
        c->apex = xf(c->apex, scale, off);
        c->base_radius = (float)(c->base_radius * scale);
        c->apex_radius = (float)(c->apex_radius * scale);
    }
}

#define INV_SCENE "tests/scenes/robust/invariance.json"
#define INV_TOL 1e-2      /* a pixel "differs" when a channel moves by more than this */
#define INV_MAX_MEAN 1e-3 /* no acne: mean absolute difference, at every offset */

static void render_inv(renderer *r, double scale, dvec off, image *img)
{
    scene s;
    scene_init(&s);
    if (scene_load(INV_SCENE, &s, err, sizeof err) != 0)
        fail_msg("%s", err);
    transform_scene(&s, scale, off);
    if (scene_finish(&s, 0, 0, 0, err, sizeof err) != 0 ||
        renderer_set_scene(r, &s, err, sizeof err) != 0 ||
        renderer_render(r, img, err, sizeof err) != 0)
        fail_msg("%s", err);
    scene_free(&s);
}

static long image_nan(const image *img)
{
    long i, n = 0;
    for (i = 0; i < 3L * img->width * img->height; i++)
        n += !isfinite(img->rgb[i]);
    return n;
}

/* 6. The scene of tests/scenes/robust/invariance.json (64x48, depth 3: floor and upright
 * mirror polygons, chrome, glass and diffuse spheres, two triangles sharing an edge, two
 * lights) scaled by 1e-6 .. 1e6 and moved by 0, 1e3, 1e4 and 1e5 times the scale along
 * (0.6, -0.3, 0.74): camera, lights and geometry, in double (the scene model's positions).
 * Compared with the image at scale 1, offset 0: pixels differing by more than 1e-2 in a
 * channel at most 0.5% (silhouettes moved by the rounding of the scaled window), and no
 * acne: mean absolute difference below 1e-3 everywhere. The renderer converts positions
 * relative to the camera's eye (the local origin), so the offset changes nothing (before
 * it, 1e4 x scale needed 1% and 1e5 x scale failed with 4.7%; tests/test_origin.c has the
 * float-only figures). The fast path, compared with its own image at scale 1, is
 * printed. */
static void test_image_invariance(void **state)
{
    static const double scales[] = {1e-6, 1e-3, 1, 1e3, 1e6};
    static const double offs[] = {0, 1e3, 1e4, 1e5};
    static const double max_over[] = {0.005, 0.005, 0.005, 0.005}; /* -1: figure only */
    image ref, fref;
    size_t is, io;
    long fails = 0, nan = 0, fast_fails = 0, checked = 0;
    dvec dir = dnorm(dv(0.6, -0.3, 0.74));
    double t0 = sys_now();
    (void)state;
    /* the renderer's own local origin (the camera's eye), as clwhitted renders */
    renderer_debug_world_origin(R, 0);
    renderer_debug_world_origin(RF, 0);
    render_inv(R, 1, dv(0, 0, 0), &ref);
    render_inv(RF, 1, dv(0, 0, 0), &fref);
    nan += image_nan(&ref);
    {
        image_diff_stats st;
        image_compare(&ref, &fref, NULL, INV_TOL, &st);
        printf("image invariance (%dx%d, depth 3): fast vs robust at scale 1: %ld pixels over "
               "%g, mean %.2g\n",
               ref.width, ref.height, st.over, INV_TOL, st.mean_abs);
    }
    for (io = 0; io < sizeof offs / sizeof offs[0]; io++) {
        for (is = 0; is < sizeof scales / sizeof scales[0]; is++) {
            double scale = scales[is];
            dvec off = dscale(dir, offs[io] * scale);
            image img, fimg;
            image_diff_stats st, fst;
            long npx = (long)ref.width * ref.height;
            int bad, fbad;
            if (scale == 1 && offs[io] == 0)
                continue;
            if (max_over[io] < 0 && scale != 1)
                continue; /* the figure-only offset: once */
            render_inv(R, scale, off, &img);
            render_inv(RF, scale, off, &fimg);
            if (max_over[io] >= 0)
                nan += image_nan(&img);
            assert_int_equal(image_compare(&ref, &img, NULL, INV_TOL, &st), 0);
            assert_int_equal(image_compare(&fref, &fimg, NULL, INV_TOL, &fst), 0);
            bad = st.over > (long)(max_over[io] * npx) || !(st.mean_abs < INV_MAX_MEAN);
            fbad = fst.over > (long)(0.005 * npx) || !(fst.mean_abs < INV_MAX_MEAN);
            if (max_over[io] >= 0) {
                checked++;
                fails += bad;
                fast_fails += fbad;
            }
            printf("  scale %g, offset %g x scale: robust %ld pixels over %g (%.2f%%), mean "
                   "%.2g, max %.2g%s; fast (vs fast at scale 1) %ld over (%.2f%%), mean %.2g, "
                   "max %.2g%s\n",
                   scale, offs[io], st.over, INV_TOL, 100.0 * st.over / npx, st.mean_abs,
                   st.max_abs,
                   max_over[io] < 0 ? "  (figure only)"
                   : bad            ? "  FAIL"
                                    : "",
                   fst.over, 100.0 * fst.over / npx, fst.mean_abs, fst.max_abs,
                   fbad ? "  (fails the 0.5% check)" : "");
            if (bad && max_over[io] >= 0) {
                char path[256];
                mkdir("build", 0777);
                mkdir(OUT_DIR, 0777);
                snprintf(path, sizeof path, OUT_DIR "/robust-invariance-%g-%g-diff.png", scale,
                         offs[io]);
                image_write_diff(&ref, &img, NULL, INV_TOL, 10, path, err, sizeof err);
                printf("    diff image: %s\n", path);
                snprintf(path, sizeof path, OUT_DIR "/robust-invariance-%g-%g.png", scale,
                         offs[io]);
                image_write(&img, path, err, sizeof err);
                image_write(&ref, OUT_DIR "/robust-invariance-ref.png", err, sizeof err);
            }
            image_free(&img);
            image_free(&fimg);
        }
    }
    printf("  image invariance: robust %ld of %ld transformed scenes fail, %ld NaN pixels; fast "
           "fails %ld of %ld (%.1f s)\n",
           fails, checked, nan, fast_fails, checked, sys_now() - t0);
    image_free(&ref);
    image_free(&fref);
    renderer_debug_world_origin(R, 1);
    renderer_debug_world_origin(RF, 1);
    assert_int_equal(nan, 0);
    assert_int_equal(fails, 0);
}

/* 7. shade_pow (the Blinn-Phong power, kernels/shade.h, here compiled as host C99) against
 * double precision: x from 1e-30 to 1, exponents of real materials (0.1 .. 10000). The
 * exponent y = p log2 x is a float, so its rounding alone costs a relative error of about
 * 2^-24 ln 2 |y| in 2^y: the bound is 3e-7 (1 + |y|) wherever x^p >= 1e-30 (measured:
 * 1.67e-7 (1 + |y|); the float library's exp2f(p log2f(x)): 7.2e-8 (1 + |y|)). x = 1 and
 * p = 0 give exactly 1, x = 0 gives 0. */
static void test_shade_pow(void **state)
{
    static const float ps[] = {0.1f,  0.5f,  1.0f,   2.0f,    4.81884f,
                               10.0f, 33.0f, 100.0f, 1000.0f, 10000.0f};
    double worst = 0.0;
    int k, n = 0;
    (void)state;
    for (k = 0; k < (int)(sizeof ps / sizeof ps[0]); k++) {
        float x;
        assert_true(shade_pow(1.0f, ps[k]) == 1.0f);
        assert_true(shade_pow(0.0f, ps[k]) == 0.0f);
        for (x = 1e-30f; x <= 1.0f; x = x * 1.0007f + 1e-9f) {
            double want = pow((double)x, (double)ps[k]), got = shade_pow(x, ps[k]);
            double y = fabs((double)ps[k] * log2((double)x)), rel;
            if (want < 1e-30)
                continue;
            n++;
            rel = fabs(got - want) / want / (1.0 + y);
            if (rel > worst)
                worst = rel;
            if (rel > 3e-7)
                fail_msg("shade_pow(%.9g, %g) = %.9g, want %.9g (relative error %.3g (1 + |y|))", x,
                         ps[k], got, want, rel);
        }
    }
    assert_true(shade_pow(0.3f, 0.0f) == 1.0f);
    printf("    shade_pow: %d values, worst relative error %.3g (1 + |p log2 x|)\n", n, worst);
}

/* shade_nudge is nextafterf toward the side of dir, on positive, negative and zero floats. */
static void test_shade_nudge(void **state)
{
    static const float xs[] = {0.0f,    -0.0f,  1.0f,   -1.0f,     1e-38f,
                               -1e-38f, 1e-45f, 3.5e4f, -7.25e-3f, FLT_MAX / 2};
    int k;
    (void)state;
    for (k = 0; k < (int)(sizeof xs / sizeof xs[0]); k++) {
        float up = shade_nudge(xs[k], 0.5f), down = shade_nudge(xs[k], -2.0f);
        assert_true(memcmp(&up, &(float){nextafterf(xs[k], INFINITY)}, sizeof up) == 0);
        assert_true(memcmp(&down, &(float){nextafterf(xs[k], -INFINITY)}, sizeof down) == 0);
        assert_true(memcmp(&(float){shade_nudge(xs[k], 0.0f)}, &xs[k], sizeof up) == 0);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_sphere_far_tiny),  cmocka_unit_test(test_sphere_huge_and_surface),
        cmocka_unit_test(test_watertight_mesh),  cmocka_unit_test(test_selfhit_scales),
        cmocka_unit_test(test_grazing),          cmocka_unit_test(test_degenerate_zero_area),
        cmocka_unit_test(test_needle_triangles), cmocka_unit_test(test_tiny_triangles),
        cmocka_unit_test(test_parallel_rays),    cmocka_unit_test(test_image_invariance),
        cmocka_unit_test(test_shade_pow),        cmocka_unit_test(test_shade_nudge),
    };
    /* CW_TEST_FILTER=test_grazing (a cmocka pattern, * allowed): run only those tests */
    if (getenv("CW_TEST_FILTER"))
        cmocka_set_test_filter(getenv("CW_TEST_FILTER"));
    return cmocka_run_group_tests(tests, setup, teardown);
}
