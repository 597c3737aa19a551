/* Tests for the BVH builder (host/bvh.c): the structural invariants of the flattened tree
 * on random and degenerate box sets, closest hits by a reference traversal against brute
 * force, SAH quality, the wide tree and its blocks of eight triangles (each block test
 * against eight single tests, run on the host), and the figures of a one-million-triangle build
 * (printed, not asserted: timings are noisy). No OpenCL. */
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "testutil.h"
#include "sys.h"

#include "box.h"
#include "bvh.h"
#include "config.h"
#include "devscene.h"
#include "scene_load.h"
#include "sphere.h"
#include "triangle.h"

/* ======================================================================================== */
/* Helpers                                                                                  */

/* uniform in [0, 1) */
static float rnd(void)
{
    return (float)(tu_rng_next() >> 40) * (1.0f / 16777216.0f);
}

static float rnd_range(float a, float b)
{
    return a + (b - a) * rnd();
}

static bvh_box *alloc_boxes(int n)
{
    bvh_box *b = malloc((size_t)(n > 0 ? n : 1) * sizeof *b);
    assert_non_null(b);
    return b;
}

static void set_box(bvh_box *b, float x, float y, float z, float hx, float hy, float hz)
{
    b->lo[0] = x - hx;
    b->lo[1] = y - hy;
    b->lo[2] = z - hz;
    b->hi[0] = x + hx;
    b->hi[1] = y + hy;
    b->hi[2] = z + hz;
}

/* n random boxes: centres uniform in [0, extent)^3, half-sizes in [0, size). */
static bvh_box *random_boxes(int n, uint64_t seed, float extent, float size)
{
    bvh_box *b = alloc_boxes(n);
    tu_rng_seed(seed);
    for (int i = 0; i < n; i++) {
        float x = rnd() * extent, y = rnd() * extent, z = rnd() * extent;
        set_box(&b[i], x, y, z, rnd() * size, rnd() * size, rnd() * size);
    }
    return b;
}

static void build_ok(bvh *t, const bvh_box *boxes, int n, int max_leaf)
{
    char err[256] = "";
    if (bvh_build(t, boxes, n, max_leaf, err, sizeof err) != 0)
        fail_msg("bvh_build(n = %d, max_leaf = %d) failed: %s", n, max_leaf, err);
}

/* ======================================================================================== */
/* Structural invariants                                                                    */

typedef struct {
    const bvh *t;
    const bvh_box *boxes;
    int n, max_leaf;
    int finite; /* check boxes (containment, tightness, split order) */
    const char *what;
    int next_node, next_ref, max_depth, leaves, big_leaves;
    unsigned char *seen;
} checker;

static int box_equal(const float alo[3], const float ahi[3], const float blo[3], const float bhi[3])
{
    for (int a = 0; a < 3; a++)
        if (alo[a] != blo[a] || ahi[a] != bhi[a])
            return 0;
    return 1;
}

/* Checks the subtree at node i (depth: of i), visited in depth-first order; returns the
 * bounds of its doubled centroids (lo + hi, as the builder bins them) and its box. */
static void check_node(checker *ck, int i, int depth, float clo[3], float chi[3], float lo[3],
                       float hi[3])
{
    const cw_bvh_node *nd;
    if (depth > BVH_MAX_DEPTH)
        fail_msg("%s: depth %d exceeds BVH_MAX_DEPTH", ck->what, depth);
    if (i != ck->next_node || i < 0 || i >= ck->t->num_nodes)
        fail_msg("%s: node %d is not next in depth-first order (expected %d of %d)", ck->what, i,
                 ck->next_node, ck->t->num_nodes);
    ck->next_node++;
    if (depth > ck->max_depth)
        ck->max_depth = depth;
    nd = &ck->t->nodes[i];
    for (int a = 0; a < 3; a++) {
        clo[a] = lo[a] = INFINITY;
        chi[a] = hi[a] = -INFINITY;
    }
    if (nd->count > 0) {
        int coincident = 1;
        if (nd->start != ck->next_ref || nd->start + nd->count > ck->t->num_refs)
            fail_msg("%s: leaf %d covers refs [%d, %d), expected to start at %d of %d", ck->what, i,
                     nd->start, nd->start + nd->count, ck->next_ref, ck->t->num_refs);
        for (int k = nd->start; k < nd->start + nd->count; k++) {
            int r = ck->t->refs[k];
            const bvh_box *b;
            if (r < 0 || r >= ck->n)
                fail_msg("%s: refs[%d] = %d out of range", ck->what, k, r);
            if (ck->seen[r])
                fail_msg("%s: primitive %d appears twice", ck->what, r);
            ck->seen[r] = 1;
            b = &ck->boxes[r];
            for (int a = 0; a < 3; a++) {
                float c = b->lo[a] + b->hi[a];
                if (k > nd->start && c != clo[a])
                    coincident = 0;
                clo[a] = c < clo[a] ? c : clo[a];
                chi[a] = c > chi[a] ? c : chi[a];
                lo[a] = b->lo[a] < lo[a] ? b->lo[a] : lo[a];
                hi[a] = b->hi[a] > hi[a] ? b->hi[a] : hi[a];
            }
        }
        ck->next_ref += nd->count;
        ck->leaves++;
        if (nd->count > ck->max_leaf) {
            int cap = ck->max_leaf > BVH_COINCIDENT_LEAF ? ck->max_leaf : BVH_COINCIDENT_LEAF;
            ck->big_leaves++;
            if (nd->count > cap)
                fail_msg("%s: leaf %d has %d primitives (cap %d)", ck->what, i, nd->count, cap);
            if (ck->finite && !coincident)
                fail_msg("%s: leaf %d has %d primitives (max_leaf %d) whose centroids differ",
                         ck->what, i, nd->count, ck->max_leaf);
        }
    } else {
        int axis = -nd->count;
        float lclo[3], lchi[3], llo[3], lhi[3], rclo[3], rchi[3], rlo[3], rhi[3];
        if (axis < 0 || axis > 2)
            fail_msg("%s: interior node %d has count %d", ck->what, i, nd->count);
        check_node(ck, i + 1, depth + 1, lclo, lchi, llo, lhi);
        if (nd->start != ck->next_node)
            fail_msg("%s: node %d: second child %d, expected %d", ck->what, i, nd->start,
                     ck->next_node);
        check_node(ck, nd->start, depth + 1, rclo, rchi, rlo, rhi);
        for (int a = 0; a < 3; a++) {
            clo[a] = fminf(lclo[a], rclo[a]);
            chi[a] = fmaxf(lchi[a], rchi[a]);
            lo[a] = fminf(llo[a], rlo[a]);
            hi[a] = fmaxf(lhi[a], rhi[a]);
        }
        /* the first child lies on the lower side of the split axis (the kernel visits the
         * nearer child first by it) */
        if (ck->finite && lchi[axis] > rclo[axis])
            fail_msg("%s: node %d split on axis %d, but its first child's centroids reach %g "
                     "and its second's start at %g",
                     ck->what, i, axis, 0.5 * lchi[axis], 0.5 * rclo[axis]);
    }
    /* the node box is exactly the union of what is below it (so it contains it) */
    if (ck->finite && !box_equal(nd->lo, nd->hi, lo, hi))
        fail_msg("%s: node %d box (%g %g %g)-(%g %g %g) is not the union of its contents "
                 "(%g %g %g)-(%g %g %g)",
                 ck->what, i, nd->lo[0], nd->lo[1], nd->lo[2], nd->hi[0], nd->hi[1], nd->hi[2],
                 lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]);
}

/* Every invariant of a tree built over boxes[0, n) with max_leaf; returns the number of
 * leaves larger than max_leaf (allowed only for coincident centroids). */
static int check_tree(const bvh *t, const bvh_box *boxes, int n, int max_leaf, int finite,
                      const char *what)
{
    checker ck;
    float clo[3], chi[3], lo[3], hi[3];
    memset(&ck, 0, sizeof ck);
    ck.t = t;
    ck.boxes = boxes;
    ck.n = n;
    ck.max_leaf = max_leaf;
    ck.finite = finite;
    ck.what = what;
    if (t->num_refs != n)
        fail_msg("%s: %d refs for %d primitives", what, t->num_refs, n);
    if (n == 0) {
        if (t->num_nodes != 0 || t->depth != 0)
            fail_msg("%s: empty input gave %d nodes, depth %d", what, t->num_nodes, t->depth);
        return 0;
    }
    if (t->num_nodes < 1 || t->num_nodes > 2 * n - 1)
        fail_msg("%s: %d nodes for %d primitives", what, t->num_nodes, n);
    ck.seen = calloc((size_t)n, 1);
    assert_non_null(ck.seen);
    check_node(&ck, 0, 1, clo, chi, lo, hi);
    free(ck.seen);
    if (ck.next_node != t->num_nodes)
        fail_msg("%s: %d nodes reachable of %d", what, ck.next_node, t->num_nodes);
    if (ck.next_ref != n)
        fail_msg("%s: leaves cover %d refs of %d", what, ck.next_ref, n);
    if (ck.max_depth != t->depth)
        fail_msg("%s: depth %d reported, %d measured", what, t->depth, ck.max_depth);
    if (ck.leaves != (t->num_nodes + 1) / 2)
        fail_msg("%s: %d leaves in %d nodes (a binary tree has (nodes + 1) / 2)", what, ck.leaves,
                 t->num_nodes);
    return ck.big_leaves;
}

/* Builds, checks, frees; returns the number of leaves larger than max_leaf. */
static int build_check(const bvh_box *boxes, int n, int max_leaf, int finite, const char *what)
{
    bvh t;
    int big;
    build_ok(&t, boxes, n, max_leaf);
    big = check_tree(&t, boxes, n, max_leaf, finite, what);
    printf("  %-34s n %7d  max_leaf %2d: %7d nodes, depth %2d, SAH %.4g\n", what, n, max_leaf,
           t.num_nodes, t.depth, bvh_sah_cost(&t));
    bvh_free(&t);
    return big;
}

/* ======================================================================================== */
/* Reference traversal                                                                      */

typedef struct {
    float o[3], d[3], inv[3];
} ray;

typedef struct {
    float c[3], r;
} sphere;

/* An origin in [lo, hi)^3 and a random unit direction with no tiny component (so that
 * the slab test needs no special cases). */
static ray random_ray(float lo, float hi)
{
    ray r;
    float len;
    for (int a = 0; a < 3; a++)
        r.o[a] = rnd_range(lo, hi);
    do {
        for (int a = 0; a < 3; a++)
            r.d[a] = rnd_range(-1.0f, 1.0f);
        len = sqrtf(r.d[0] * r.d[0] + r.d[1] * r.d[1] + r.d[2] * r.d[2]);
    } while (len < 0.1f || len > 1.0f || fabsf(r.d[0]) < 1e-3f * len ||
             fabsf(r.d[1]) < 1e-3f * len || fabsf(r.d[2]) < 1e-3f * len);
    for (int a = 0; a < 3; a++) {
        r.d[a] /= len;
        r.inv[a] = 1.0f / r.d[a];
    }
    return r;
}

/* Slab test: the parameter interval [*t0, *t1] of the ray inside the box, clipped to
 * [0, tmax]; 1 when not empty. Rounding is monotone, so a box containing another always
 * gives an interval containing the other's. */
static int slab(const ray *r, const float lo[3], const float hi[3], float tmax, float *t0,
                float *t1)
{
    float a0 = 0.0f, a1 = tmax;
    for (int a = 0; a < 3; a++) {
        float ta = (lo[a] - r->o[a]) * r->inv[a], tb = (hi[a] - r->o[a]) * r->inv[a];
        if (ta > tb) {
            float s = ta;
            ta = tb;
            tb = s;
        }
        a0 = ta > a0 ? ta : a0;
        a1 = tb < a1 ? tb : a1;
    }
    *t0 = a0;
    *t1 = a1;
    return a0 <= a1;
}

/* Box primitive: the first crossing of its surface ahead of the origin, or INFINITY. */
static float hit_box(const ray *r, const bvh_box *b)
{
    float t0, t1;
    if (!slab(r, b->lo, b->hi, INFINITY, &t0, &t1))
        return INFINITY;
    if (t0 > 0.0f)
        return t0;
    return t1 > 0.0f ? t1 : INFINITY;
}

static float hit_sphere(const ray *r, const sphere *s)
{
    float oc[3], b = 0.0f, c = 0.0f, disc, q, t;
    for (int a = 0; a < 3; a++) {
        oc[a] = r->o[a] - s->c[a];
        b += oc[a] * r->d[a];
        c += oc[a] * oc[a];
    }
    c -= s->r * s->r;
    disc = b * b - c;
    if (disc < 0.0f)
        return INFINITY;
    q = sqrtf(disc);
    t = -b - q;
    if (t > 1e-4f)
        return t;
    t = -b + q;
    return t > 1e-4f ? t : INFINITY;
}

typedef struct {
    const sphere *spheres; /* or NULL: the primitives are the boxes */
    const bvh_box *boxes;
} prims;

static float hit_prim(const prims *p, const ray *r, int i)
{
    return p->spheres ? hit_sphere(r, &p->spheres[i]) : hit_box(r, &p->boxes[i]);
}

/* Closest hit: smallest t, ties to the smallest index. */
static int closer(float t, int i, float best_t, int best_i)
{
    return t < best_t || (t == best_t && t < INFINITY && i < best_i);
}

static int brute_force(const prims *p, int n, const ray *r, float *t_out)
{
    float best_t = INFINITY;
    int best_i = -1;
    for (int i = 0; i < n; i++) {
        float t = hit_prim(p, r, i);
        if (closer(t, i, best_t, best_i)) {
            best_t = t;
            best_i = i;
        }
    }
    *t_out = best_t;
    return best_i;
}

/* The traversal the kernels do: nearer child first by the split axis, a stack of far
 * children, nodes beyond the closest hit so far skipped. *visits counts nodes entered. */
static int traverse(const bvh *t, const prims *p, const ray *r, float *t_out, long *visits)
{
    int stack[BVH_MAX_DEPTH];
    int top = 0, node = 0, best_i = -1;
    float best_t = INFINITY;
    if (t->num_nodes == 0) {
        *t_out = best_t;
        return -1;
    }
    for (;;) {
        const cw_bvh_node *nd = &t->nodes[node];
        float t0, t1;
        (*visits)++;
        /* with a tiny relative allowance: sphere hits are not exactly inside their boxes */
        (void)slab(r, nd->lo, nd->hi, best_t, &t0, &t1);
        if (t0 <= t1 * (1.0f + 1e-6f)) {
            if (nd->count > 0) {
                for (int k = nd->start; k < nd->start + nd->count; k++) {
                    int i = t->refs[k];
                    float th = hit_prim(p, r, i);
                    if (closer(th, i, best_t, best_i)) {
                        best_t = th;
                        best_i = i;
                    }
                }
            } else {
                int first = node + 1, second = nd->start;
                if (r->d[-nd->count] < 0.0f) {
                    int s = first;
                    first = second;
                    second = s;
                }
                assert_true(top < BVH_MAX_DEPTH);
                stack[top++] = second;
                node = first;
                continue;
            }
        }
        if (top == 0)
            break;
        node = stack[--top];
    }
    *t_out = best_t;
    return best_i;
}

/* Traces nrays random rays through a tree over p (n primitives) and by brute force: the
 * hits must be identical. */
static void compare_traversal(const prims *p, const bvh_box *boxes, int n, int max_leaf, int nrays,
                              float ray_lo, float ray_hi, const char *what)
{
    bvh t;
    long visits = 0;
    int hits = 0;
    build_ok(&t, boxes, n, max_leaf);
    check_tree(&t, boxes, n, max_leaf, 1, what);
    for (int k = 0; k < nrays; k++) {
        ray r = random_ray(ray_lo, ray_hi);
        float tb, tt;
        int ib = brute_force(p, n, &r, &tb);
        int it = traverse(&t, p, &r, &tt, &visits);
        if (ib != it || tb != tt)
            fail_msg("%s: ray %d from (%g %g %g) dir (%g %g %g): tree hits %d at %.9g, brute "
                     "force %d at %.9g",
                     what, k, r.o[0], r.o[1], r.o[2], r.d[0], r.d[1], r.d[2], it, tt, ib, tb);
        hits += ib >= 0;
    }
    printf("  %-30s n %6d: %d of %d rays hit, %.1f nodes visited per ray (%d nodes)\n", what, n,
           hits, nrays, (double)visits / nrays, t.num_nodes);
    if (n > 0 && hits == 0)
        fail_msg("%s: no ray hit anything: the test proves nothing", what);
    bvh_free(&t);
}

/* Spheres in [0, 10)^3, conservative boxes (padded for rounding, as a renderer must). */
static void sphere_scene(int n, uint64_t seed, float rmin, float rmax, int max_leaf)
{
    sphere *s = malloc((size_t)(n > 0 ? n : 1) * sizeof *s);
    bvh_box *b = alloc_boxes(n);
    prims p;
    char what[64];
    assert_non_null(s);
    tu_rng_seed(seed);
    for (int i = 0; i < n; i++) {
        for (int a = 0; a < 3; a++)
            s[i].c[a] = rnd_range(0.0f, 10.0f);
        s[i].r = rnd_range(rmin, rmax);
        for (int a = 0; a < 3; a++) {
            float pad = 1e-5f * (fabsf(s[i].c[a]) + s[i].r);
            b[i].lo[a] = s[i].c[a] - s[i].r - pad;
            b[i].hi[a] = s[i].c[a] + s[i].r + pad;
        }
    }
    p.spheres = s;
    p.boxes = b;
    snprintf(what, sizeof what, "spheres, seed %d", (int)seed);
    compare_traversal(&p, b, n, max_leaf, 3000, -2.0f, 12.0f, what);
    free(s);
    free(b);
}

/* ======================================================================================== */
/* Tests                                                                                    */

static void test_errors(void **state)
{
    bvh t;
    char err[256];
    bvh_box one;
    (void)state;
    set_box(&one, 0, 0, 0, 1, 1, 1);
    err[0] = '\0';
    assert_int_equal(bvh_build(&t, &one, -1, 4, err, sizeof err), -1);
    assert_non_null(strstr(err, "-1 primitives"));
    assert_null(t.nodes);
    err[0] = '\0';
    assert_int_equal(bvh_build(&t, &one, BVH_MAX_PRIMS + 1, 4, err, sizeof err), -1);
    assert_non_null(strstr(err, "primitives"));
    err[0] = '\0';
    assert_int_equal(bvh_build(&t, &one, 1, 0, err, sizeof err), -1);
    assert_non_null(strstr(err, "leaf size 0"));
    assert_int_equal(t.num_nodes, 0);
    bvh_free(&t); /* an empty tree frees */
}

static void test_empty_and_tiny(void **state)
{
    bvh t;
    bvh_box b[3];
    (void)state;
    build_ok(&t, NULL, 0, 4);
    assert_int_equal(t.num_nodes, 0);
    assert_int_equal(t.num_refs, 0);
    assert_int_equal(t.depth, 0);
    assert_null(t.nodes);
    assert_null(t.refs);
    assert_true(bvh_sah_cost(&t) == 0.0);
    bvh_free(&t);

    set_box(&b[0], 1, 2, 3, 0.5f, 0.25f, 1);
    build_ok(&t, b, 1, 4);
    check_tree(&t, b, 1, 4, 1, "one box");
    assert_int_equal(t.num_nodes, 1);
    assert_int_equal(t.depth, 1);
    assert_int_equal(t.nodes[0].start, 0);
    assert_int_equal(t.nodes[0].count, 1);
    assert_true(t.nodes[0].lo[0] == 0.5f && t.nodes[0].hi[2] == 4.0f);
    assert_true(fabs(bvh_sah_cost(&t) - 1.0) < 1e-12);
    bvh_free(&t);

    /* two far-apart boxes with max_leaf 1: a root and two leaves, split along x */
    set_box(&b[0], 10, 0, 0, 1, 1, 1);
    set_box(&b[1], 0, 0, 0, 1, 1, 1);
    build_ok(&t, b, 2, 1);
    check_tree(&t, b, 2, 1, 1, "two boxes");
    assert_int_equal(t.num_nodes, 3);
    assert_int_equal(t.depth, 2);
    assert_int_equal(t.nodes[0].count, 0); /* -(axis 0) */
    assert_int_equal(t.nodes[0].start, 2);
    assert_int_equal(t.refs[t.nodes[1].start], 1); /* the lower one first */
    assert_int_equal(t.refs[t.nodes[2].start], 0);
    /* SAH by hand: root area 2(12*2 + 2*2 + 2*12) = 104, each leaf 24 */
    assert_true(fabs(bvh_sah_cost(&t) - (1.0 + 2.0 * 24.0 / 104.0)) < 1e-12);
    bvh_free(&t);

    /* split along z: count is -2 */
    set_box(&b[0], 0, 0, 10, 1, 1, 1);
    set_box(&b[1], 0, 0, 0, 1, 1, 1);
    set_box(&b[2], 0, 0, 20, 1, 1, 1);
    build_ok(&t, b, 3, 1);
    check_tree(&t, b, 3, 1, 1, "three boxes on z");
    assert_int_equal(t.nodes[0].count, -2);
    bvh_free(&t);
}

static void test_random_invariants(void **state)
{
    static const int sizes[] = {1, 2, 3, 5, 17, 1000, 100000};
    (void)state;
    for (size_t k = 0; k < sizeof sizes / sizeof sizes[0]; k++) {
        int n = sizes[k];
        bvh_box *b = random_boxes(n, 1000 + k, 100.0f, 0.5f + 2.0f * (float)(k % 3));
        char what[64];
        snprintf(what, sizeof what, "random, seed %d", (int)(1000 + k));
        assert_int_equal(build_check(b, n, 4, 1, what), 0);
        if (n == 1000) {
            assert_int_equal(build_check(b, n, 1, 1, "random, max_leaf 1"), 0);
            assert_int_equal(build_check(b, n, 2, 1, "random, max_leaf 2"), 0);
            assert_int_equal(build_check(b, n, 8, 1, "random, max_leaf 8"), 0);
            assert_int_equal(build_check(b, n, 100, 1, "random, max_leaf 100"), 0);
        }
        free(b);
    }
    /* large boxes overlapping everything, and boxes of very different sizes */
    {
        int n = 5000;
        bvh_box *b = random_boxes(n, 77, 10.0f, 20.0f);
        assert_int_equal(build_check(b, n, 4, 1, "random, overlapping"), 0);
        tu_rng_seed(78);
        for (int i = 0; i < n; i++) {
            float h = powf(10.0f, rnd_range(-4.0f, 2.0f));
            set_box(&b[i], rnd() * 100, rnd() * 100, rnd() * 100, h, h * rnd(), h);
        }
        assert_int_equal(build_check(b, n, 4, 1, "random, sizes 1e-4..1e2"), 0);
        free(b);
    }
}

static void test_degenerate_invariants(void **state)
{
    int n = 1000, big;
    bvh_box *b = alloc_boxes(100000);
    (void)state;

    /* all identical: leaves up to BVH_COINCIDENT_LEAF, split by count above it */
    for (int i = 0; i < n; i++)
        set_box(&b[i], 1, 2, 3, 0.5f, 0.5f, 0.5f);
    big = build_check(b, n, 4, 1, "identical boxes");
    assert_true(big > 0);
    big = build_check(b, BVH_COINCIDENT_LEAF, 4, 1, "identical, exactly the cap");
    assert_int_equal(big, 1);
    big = build_check(b, 100000, 4, 1, "100000 identical boxes");
    assert_true(big > 0);

    /* identical centroids, different sizes */
    tu_rng_seed(5);
    for (int i = 0; i < n; i++)
        set_box(&b[i], 1, 2, 3, rnd(), rnd(), rnd());
    build_check(b, n, 4, 1, "same centroid, random sizes");

    /* points (zero-size boxes) on a line: every area is zero */
    for (int i = 0; i < n; i++)
        set_box(&b[i], (float)i * 0.1f, 0, 0, 0, 0, 0);
    assert_int_equal(build_check(b, n, 4, 1, "points on a line"), 0);
    /* boxes centred on a line, random sizes */
    tu_rng_seed(6);
    for (int i = 0; i < n; i++)
        set_box(&b[i], 5.0f, rnd() * 100.0f, 5.0f, rnd(), rnd(), rnd());
    assert_int_equal(build_check(b, n, 4, 1, "centroids on a line"), 0);
    /* a line with three positions only, many duplicates */
    for (int i = 0; i < n; i++)
        set_box(&b[i], 0, 0, (float)(i % 3), 0.1f, 0.1f, 0.1f);
    build_check(b, n, 4, 1, "three positions");
    /* one cluster of duplicates and scattered boxes */
    tu_rng_seed(7);
    for (int i = 0; i < n; i++) {
        if (i % 2)
            set_box(&b[i], 3, 3, 3, 0.1f, 0.1f, 0.1f);
        else
            set_box(&b[i], rnd() * 10, rnd() * 10, rnd() * 10, 0.1f, 0.1f, 0.1f);
    }
    build_check(b, n, 4, 1, "half duplicates");

    /* huge offset, tiny boxes: 1e6 + [0, 1) */
    tu_rng_seed(8);
    for (int i = 0; i < n; i++)
        set_box(&b[i], 1e6f + rnd(), 1e6f + rnd(), -1e6f + rnd(), 1e-3f, 1e-3f, 1e-3f);
    assert_int_equal(build_check(b, n, 4, 1, "1e6 offset"), 0);
    /* tiny coordinates */
    tu_rng_seed(9);
    for (int i = 0; i < n; i++)
        set_box(&b[i], 1e-30f * rnd(), 1e-30f * rnd(), 1e-30f * rnd(), 1e-33f, 1e-33f, 1e-33f);
    assert_int_equal(build_check(b, n, 4, 1, "1e-30 coordinates"), 0);
    /* huge coordinates: areas overflow a float */
    tu_rng_seed(10);
    for (int i = 0; i < n; i++)
        set_box(&b[i], 1e30f * rnd(), 1e30f * rnd(), 1e30f * rnd(), 1e27f, 1e27f, 1e27f);
    assert_int_equal(build_check(b, n, 4, 1, "1e30 coordinates"), 0);
    /* denormal spread: centroid extents of a few ulps */
    for (int i = 0; i < n; i++)
        set_box(&b[i], (float)(i % 7) * 1e-44f, 0, 0, 0, 0, 0);
    build_check(b, n, 4, 1, "denormal spread");

    /* exponentially spaced: every SAH split peels off the far end, so the depth bound
     * must force median splits */
    for (int i = 0; i < 250; i++)
        set_box(&b[i], ldexpf(1.0f, i / 2), 0, 0, 0.25f, 0.25f, 0.25f);
    assert_int_equal(build_check(b, 250, 4, 1, "2^(i/2) on a line"), 0);
    for (int i = 0; i < 20000; i++)
        set_box(&b[i], powf(1.004f, (float)i), 1, 1, 0.5f, 0.5f, 0.5f);
    assert_int_equal(build_check(b, 20000, 1, 1, "1.004^i on a line, max_leaf 1"), 0);
    free(b);
}

static void test_nonfinite(void **state)
{
    int n = 1000;
    bvh_box *b = random_boxes(n, 11, 10.0f, 0.5f);
    (void)state;
    for (int i = 0; i < n; i += 7)
        b[i].lo[i % 3] = NAN;
    for (int i = 3; i < n; i += 11)
        b[i].hi[(i + 1) % 3] = INFINITY;
    for (int i = 5; i < n; i += 13)
        b[i].lo[i % 3] = -INFINITY;
    for (int i = 1; i < n; i += 17)
        for (int a = 0; a < 3; a++)
            b[i].lo[a] = b[i].hi[a] = NAN;
    build_check(b, n, 4, 0, "NaN and inf mixed in");
    for (int i = 0; i < n; i++)
        for (int a = 0; a < 3; a++)
            b[i].lo[a] = b[i].hi[a] = NAN;
    build_check(b, n, 4, 0, "all NaN");
    for (int i = 0; i < n; i++)
        for (int a = 0; a < 3; a++) {
            b[i].lo[a] = -INFINITY;
            b[i].hi[a] = INFINITY;
        }
    build_check(b, n, 4, 0, "all infinite");
    for (int i = 0; i < n; i++)
        set_box(&b[i], (i % 2) ? INFINITY : -INFINITY, (float)i, 0, 0, 0, 0);
    build_check(b, n, 4, 0, "centroids at +-inf");
    for (int i = 0; i < n; i++)
        set_box(&b[i], (float)i * 1e36f, 0, 0, 3e38f, 0, 0); /* lo + hi overflows */
    build_check(b, n, 4, 0, "overflowing centroids");
    free(b);
}

static void test_traversal_spheres(void **state)
{
    (void)state;
    sphere_scene(1, 21, 1.0f, 2.0f, 4);
    sphere_scene(2, 22, 1.0f, 2.0f, 4);
    sphere_scene(7, 23, 0.5f, 2.0f, 1);
    sphere_scene(2000, 24, 0.05f, 0.3f, 4);
    sphere_scene(2000, 25, 0.2f, 1.5f, 4); /* overlapping */
    sphere_scene(5000, 26, 0.01f, 0.1f, 1);
    sphere_scene(5000, 27, 0.01f, 0.1f, 8);
}

static void test_traversal_boxes(void **state)
{
    int n = 3000;
    bvh_box *b = random_boxes(n, 31, 10.0f, 0.2f);
    prims p;
    (void)state;
    p.spheres = NULL;
    p.boxes = b;
    compare_traversal(&p, b, n, 4, 3000, -2.0f, 12.0f, "random boxes");
    tu_rng_seed(32);
    for (int i = 0; i < n; i++) /* a few identical stacks: ties broken by index */
        set_box(&b[i], (float)(i % 5) * 2.0f, 5, 5, 0.5f + 0.001f * (float)(i % 3), 0.5f, 0.5f);
    compare_traversal(&p, b, n, 4, 3000, -2.0f, 12.0f, "stacks of identical boxes");
    for (int i = 0; i < n; i++)
        set_box(&b[i], 5, (float)i * 0.01f, 5, 1, 0.004f, 1);
    compare_traversal(&p, b, n, 4, 3000, -2.0f, 32.0f, "slabs along a line");
    tu_rng_seed(33);
    for (int i = 0; i < n; i++)
        set_box(&b[i], 1e4f + rnd() * 10, 1e4f + rnd() * 10, 1e4f + rnd() * 10, 0.1f, 0.1f, 0.1f);
    compare_traversal(&p, b, n, 4, 3000, 1e4f - 2.0f, 1e4f + 12.0f, "random boxes at 1e4");
    free(b);
}

/* The SAH cost of the tree a plain object-median builder would make (split at the median
 * centroid along the widest centroid extent, leaves of at most max_leaf), unnormalised. */
static const bvh_box *median_boxes;
static int median_axis;

static int median_cmp(const void *pa, const void *pb)
{
    const bvh_box *a = &median_boxes[*(const int *)pa], *b = &median_boxes[*(const int *)pb];
    float ca = a->lo[median_axis] + a->hi[median_axis];
    float cb = b->lo[median_axis] + b->hi[median_axis];
    return (ca > cb) - (ca < cb);
}

static double area_of(const float lo[3], const float hi[3])
{
    double dx = hi[0] - lo[0], dy = hi[1] - lo[1], dz = hi[2] - lo[2];
    return 2.0 * (dx * dy + dy * dz + dz * dx);
}

static double median_cost(int *idx, int n, int max_leaf, double *root_area)
{
    float lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    float clo[3] = {INFINITY, INFINITY, INFINITY}, chi[3] = {-INFINITY, -INFINITY, -INFINITY};
    double area;
    for (int i = 0; i < n; i++) {
        const bvh_box *b = &median_boxes[idx[i]];
        for (int a = 0; a < 3; a++) {
            lo[a] = fminf(lo[a], b->lo[a]);
            hi[a] = fmaxf(hi[a], b->hi[a]);
            clo[a] = fminf(clo[a], b->lo[a] + b->hi[a]);
            chi[a] = fmaxf(chi[a], b->lo[a] + b->hi[a]);
        }
    }
    area = area_of(lo, hi);
    if (root_area)
        *root_area = area;
    if (n <= max_leaf)
        return area * n;
    median_axis = 0;
    for (int a = 1; a < 3; a++)
        if (chi[a] - clo[a] > chi[median_axis] - clo[median_axis])
            median_axis = a;
    qsort(idx, (size_t)n, sizeof *idx, median_cmp);
    return area + median_cost(idx, n / 2, max_leaf, NULL) +
           median_cost(idx + n / 2, n - n / 2, max_leaf, NULL);
}

/* SAH cost of the builder's tree against a single leaf and against an object-median tree:
 * returns the ratio to the median tree's cost. */
static double sah_versus_median(const bvh_box *b, int n, const char *what)
{
    bvh t;
    double cost, median, root_area;
    int *idx = malloc((size_t)n * sizeof *idx);
    assert_non_null(idx);
    for (int i = 0; i < n; i++)
        idx[i] = i;
    median_boxes = b;
    median = median_cost(idx, n, 4, &root_area) / root_area;
    free(idx);
    build_ok(&t, b, n, 4);
    check_tree(&t, b, n, 4, 1, what);
    cost = bvh_sah_cost(&t);
    printf("  %s, n %d: SAH %.2f; a single leaf %d (ratio %.2e); object-median tree %.2f "
           "(ratio %.3f); %d nodes, depth %d\n",
           what, n, cost, n, cost / n, median, cost / median, t.num_nodes, t.depth);
    /* a good tree costs tens, against n for a single leaf */
    assert_true(cost / n < 0.01);
    bvh_free(&t);
    return cost / median;
}

static void test_sah_quality(void **state)
{
    int n = 50000;
    bvh_box *b = random_boxes(n, 41, 1.0f, 0.002f);
    (void)state;
    /* uniform: the SAH wins by its leaf-or-split choice (measured 0.76) */
    assert_true(sah_versus_median(b, n, "uniform small boxes") < 0.95);
    /* clustered, mixed sizes: the SAH wins by far (measured 0.25) */
    tu_rng_seed(42);
    for (int i = 0; i < n; i++) {
        int cl = (int)(rnd() * 20.0f);
        float cx = (float)(cl % 5) * 20.0f, cy = (float)(cl / 5) * 20.0f, cz = (float)(cl % 3);
        float h = (i % 50) ? 0.01f : 2.0f;
        set_box(&b[i], cx + rnd() * rnd() * 5, cy + rnd() * 5, cz * 30.0f + rnd() * 0.5f, h, h, h);
    }
    assert_true(sah_versus_median(b, n, "clusters, mixed sizes") < 0.5);
    free(b);
}

/* One million random triangles (edges up to about 1% of the scene): the figures. */
static void test_million_triangles(void **state)
{
    int n = 1000000;
    bvh_box *b = alloc_boxes(n);
    bvh t;
    double t0, t1;
    (void)state;
    tu_rng_seed(51);
    for (int i = 0; i < n; i++) {
        float v[3][3];
        for (int a = 0; a < 3; a++) {
            v[0][a] = rnd() * 100.0f;
            v[1][a] = v[0][a] + rnd_range(-1.0f, 1.0f);
            v[2][a] = v[0][a] + rnd_range(-1.0f, 1.0f);
        }
        for (int a = 0; a < 3; a++) {
            b[i].lo[a] = fminf(v[0][a], fminf(v[1][a], v[2][a]));
            b[i].hi[a] = fmaxf(v[0][a], fmaxf(v[1][a], v[2][a]));
        }
    }
    t0 = sys_now();
    build_ok(&t, b, n, 4);
    t1 = sys_now();
    printf("  1M random triangles: build %.3f s, %d nodes, depth %d, SAH %.2f\n", t1 - t0,
           t.num_nodes, t.depth, bvh_sah_cost(&t));
    check_tree(&t, b, n, 4, 1, "1M triangles");
    bvh_free(&t);
    free(b);
}

/* ======================================================================================== */
/* Threads: the same tree, bit for bit, for every thread count                              */

/* Builds b[0..n) on 1 thread and on each count in threads[]; fails unless every tree has the
 * same bytes (nodes, refs, depth). Returns the one-thread node count. */
static int same_on_threads(const bvh_box *b, int n, int max_leaf, const char *what)
{
    static const int threads[] = {2, 3, CW_BVH_MAX_THREADS};
    char err[256] = "";
    bvh one;
    int nodes;
    if (bvh_build_threads(&one, b, n, max_leaf, 1, err, sizeof err) != 0)
        fail_msg("%s: one thread: %s", what, err);
    for (size_t k = 0; k < sizeof threads / sizeof threads[0]; k++) {
        bvh t;
        if (bvh_build_threads(&t, b, n, max_leaf, threads[k], err, sizeof err) != 0)
            fail_msg("%s: %d threads: %s", what, threads[k], err);
        if (t.num_nodes != one.num_nodes || t.depth != one.depth || t.num_refs != one.num_refs ||
            memcmp(t.nodes, one.nodes, (size_t)one.num_nodes * sizeof *one.nodes) != 0 ||
            memcmp(t.refs, one.refs, (size_t)one.num_refs * sizeof *one.refs) != 0)
            fail_msg("%s, max_leaf %d: %d threads build another tree (%d nodes, depth %d; one "
                     "thread: %d nodes, depth %d)",
                     what, max_leaf, threads[k], t.num_nodes, t.depth, one.num_nodes, one.depth);
        bvh_free(&t);
    }
    nodes = one.num_nodes;
    bvh_free(&one);
    return nodes;
}

static void test_threads_identical(void **state)
{
    int n = 100000;
    bvh_box *b = random_boxes(n, 61, 100.0f, 0.5f);
    (void)state;
    same_on_threads(b, n, 4, "uniform");
    same_on_threads(b, n, 1, "uniform");
    same_on_threads(b, 40000, 8, "uniform, 40k"); /* just above the parallel threshold */
    /* clusters of very different density and size: unbalanced SAH splits at the top */
    tu_rng_seed(62);
    for (int i = 0; i < n; i++) {
        float c = (float)(i % 7 == 0 ? 1000 : i % 3) * 10.0f, h = (i % 50) ? 0.01f : 3.0f;
        set_box(&b[i], c + rnd() * rnd() * 5, rnd() * 5, rnd() * 0.5f, h, h * rnd(), h);
    }
    same_on_threads(b, n, 4, "clusters");
    /* coordinates of +0 and -0 (equal, different bits) mixed: the bins and bounds merged
     * across threads must keep the one a single pass keeps */
    for (int i = 0; i < n; i++) {
        float z = (i % 3) ? 0.0f : -0.0f;
        set_box(&b[i], (float)(i % 1000), z, (float)(i / 1000), 0.25f, 0.0f, 0.25f);
        b[i].lo[1] = (i % 5) ? -0.0f : 0.0f;
        b[i].hi[1] = z;
    }
    same_on_threads(b, n, 4, "signed zeros");
    /* coincident centroids (split by count), a line, NaN and infinite boxes */
    for (int i = 0; i < n; i++)
        set_box(&b[i], (float)(i % 3), 1, 1, 0.5f, 0.5f, 0.5f);
    same_on_threads(b, n, 4, "three points");
    for (int i = 0; i < n; i++)
        set_box(&b[i], powf(1.0001f, (float)i), 1, 1, 0.5f, 0.5f, 0.5f);
    same_on_threads(b, n, 1, "a geometric line");
    free(b);
    b = random_boxes(n, 63, 10.0f, 0.5f);
    for (int i = 0; i < n; i += 7)
        b[i].lo[i % 3] = NAN;
    for (int i = 3; i < n; i += 11)
        b[i].hi[(i + 1) % 3] = INFINITY;
    for (int i = 1; i < n; i += 17)
        for (int a = 0; a < 3; a++)
            b[i].lo[a] = b[i].hi[a] = NAN;
    same_on_threads(b, n, 4, "NaN and inf mixed in");
    free(b);
}

/* Leaves and their mean size in a tree (binary). */
static double mean_leaf(const bvh *t, int *leaves)
{
    int n = 0, refs = 0;
    for (int i = 0; i < t->num_nodes; i++)
        if (t->nodes[i].count > 0) {
            n++;
            refs += t->nodes[i].count;
        }
    *leaves = n;
    return n > 0 ? (double)refs / n : 0.0;
}

/* bvh_build_blocks: boxes marked as blocks (the kernels' triangles, tested BVH_BLOCK_TEST
 * at a time in a leaf of such only) get leaves priced by tests, so fuller leaves; unmarked boxes,
 * or no marks, give bvh_build's tree bit for bit; a mixed set keeps every invariant, the same tree
 * on every thread count. */
static void test_block_leaves(void **state)
{
    int n = 40000, leaves_plain, leaves_blk, leaves_mixed; /* parallel at the top */
    bvh_box *b = random_boxes(n, 71, 10.0f, 0.4f);         /* overlapping, like a triangle soup */
    unsigned char *none = calloc((size_t)n, 1), *all = malloc((size_t)n),
                  *mixed = malloc((size_t)n);
    char err[256] = "";
    bvh plain, zero, blk, mix, mix2;
    double m_plain, m_blk, m_mixed;
    (void)state;
    assert_non_null(none);
    assert_non_null(all);
    assert_non_null(mixed);
    memset(all, 1, (size_t)n);
    for (int i = 0; i < n; i++)
        mixed[i] = (unsigned char)(i % 5 != 0);
    build_ok(&plain, b, n, 4);
    assert_int_equal(bvh_build_blocks(&zero, b, none, n, 4, 0, err, sizeof err), 0);
    assert_int_equal(zero.num_nodes, plain.num_nodes);
    assert_memory_equal(zero.nodes, plain.nodes, (size_t)plain.num_nodes * sizeof *plain.nodes);
    assert_memory_equal(zero.refs, plain.refs, (size_t)n * sizeof *plain.refs);
    assert_int_equal(bvh_build_blocks(&blk, b, all, n, BVH_BLOCK_TEST, 0, err, sizeof err), 0);
    check_tree(&blk, b, n, BVH_BLOCK_TEST, 1, "all blocks");
    assert_int_equal(bvh_build_blocks(&mix, b, mixed, n, BVH_BLOCK_TEST, 3, err, sizeof err), 0);
    check_tree(&mix, b, n, BVH_BLOCK_TEST, 1, "4 in 5 blocks");
    assert_int_equal(bvh_build_blocks(&mix2, b, mixed, n, BVH_BLOCK_TEST, 1, err, sizeof err), 0);
    assert_int_equal(mix2.num_nodes, mix.num_nodes);
    assert_memory_equal(mix2.nodes, mix.nodes, (size_t)mix.num_nodes * sizeof *mix.nodes);
    assert_memory_equal(mix2.refs, mix.refs, (size_t)n * sizeof *mix.refs);
    { /* two classes, in alternate halves of space: leaves of one class each fill up */
        bvh two;
        int leaves_two;
        double m_two;
        for (int i = 0; i < n; i++)
            mixed[i] = (unsigned char)(b[i].lo[0] < 5.0f ? 1 : 2);
        assert_int_equal(bvh_build_blocks(&two, b, mixed, n, BVH_BLOCK_TEST, 3, err, sizeof err),
                         0);
        check_tree(&two, b, n, BVH_BLOCK_TEST, 1, "two classes");
        m_two = mean_leaf(&two, &leaves_two);
        printf("  mean leaf: %.2f with two classes (%d leaves)\n", m_two, leaves_two);
        assert_true(m_two > 6.0);
        bvh_free(&two);
    }
    m_plain = mean_leaf(&plain, &leaves_plain);
    m_blk = mean_leaf(&blk, &leaves_blk);
    m_mixed = mean_leaf(&mix, &leaves_mixed);
    printf("  mean leaf: %.2f unmarked (%d leaves), %.2f all blocks (%d), %.2f 4 in 5 (%d)\n",
           m_plain, leaves_plain, m_blk, leaves_blk, m_mixed, leaves_mixed);
    /* up to BVH_BLOCK_TEST (a block of eight) cost one test: the soup's leaves fill up
     * (measured 1.33 -> 7.59; with one block of four a test, 3.86) */
    assert_true(m_blk > 6.0 && m_blk > 2.0 * m_plain);
    assert_true(m_mixed > m_plain && m_mixed < m_blk);
    bvh_free(&plain);
    bvh_free(&zero);
    bvh_free(&blk);
    bvh_free(&mix);
    bvh_free(&mix2);
    free(none);
    free(all);
    free(mixed);
    free(b);
}

/* bvh_build_blocks_take: the same tree as bvh_build_blocks, bit for bit, with the caller's
 * boxes freed and its pointer cleared (the sanitizer build would report a leak or a double
 * free); also when the build fails or is empty. */
static void test_build_take(void **state)
{
    int n = 30000;
    bvh_box *b = random_boxes(n, 73, 10.0f, 0.4f), *given = malloc((size_t)n * sizeof *b);
    unsigned char *mixed = malloc((size_t)n);
    char err[256] = "";
    bvh kept, taken;
    (void)state;
    assert_non_null(given);
    assert_non_null(mixed);
    memcpy(given, b, (size_t)n * sizeof *b);
    for (int i = 0; i < n; i++)
        mixed[i] = (unsigned char)(i % 3 != 0);
    assert_int_equal(bvh_build_blocks(&kept, b, mixed, n, 4, 2, err, sizeof err), 0);
    assert_int_equal(bvh_build_blocks_take(&taken, &given, mixed, n, 4, 2, err, sizeof err), 0);
    assert_null(given);
    assert_int_equal(taken.num_nodes, kept.num_nodes);
    assert_memory_equal(taken.nodes, kept.nodes, (size_t)kept.num_nodes * sizeof *kept.nodes);
    assert_memory_equal(taken.refs, kept.refs, (size_t)n * sizeof *kept.refs);
    check_tree(&taken, b, n, 4, 1, "taken boxes");
    bvh_free(&taken);
    given = malloc(sizeof *given); /* a failed build (leaf size 0) frees them too */
    assert_non_null(given);
    assert_int_equal(bvh_build_blocks_take(&taken, &given, NULL, 1, 0, 1, err, sizeof err), -1);
    assert_null(given);
    assert_int_equal(taken.num_nodes, 0);
    given = malloc(sizeof *given); /* and an empty one */
    assert_non_null(given);
    assert_int_equal(bvh_build_blocks_take(&taken, &given, NULL, 0, 4, 1, err, sizeof err), 0);
    assert_null(given);
    assert_int_equal(taken.num_nodes, 0);
    bvh_free(&kept);
    free(mixed);
    free(b);
}

/* ======================================================================================== */
/* The root split against a plain reference of the binned SAH                               */

#define REF_BINS 16 /* bvh_sah.c's MAX_BINS */

static void ref_grow(float lo[3], float hi[3], const float plo[3], const float phi[3])
{
    for (int a = 0; a < 3; a++) {
        lo[a] = plo[a] < lo[a] ? plo[a] : lo[a];
        hi[a] = phi[a] > hi[a] ? phi[a] : hi[a];
    }
}

static void ref_empty(float lo[3], float hi[3])
{
    for (int a = 0; a < 3; a++) {
        lo[a] = INFINITY;
        hi[a] = -INFINITY;
    }
}

static double ref_area(const float lo[3], const float hi[3])
{
    double dx = (double)hi[0] - lo[0], dy = (double)hi[1] - lo[1], dz = (double)hi[2] - lo[2];
    if (!(dx >= 0.0 && dy >= 0.0 && dz >= 0.0))
        return 0.0;
    return 2.0 * (dx * dy + dy * dz + dz * dx);
}

static int ref_bin(const bvh_box *b, int a, float cmin, float scale)
{
    float f = (b->lo[a] + b->hi[a] - cmin) * scale;
    f = f > 0.0f ? f : 0.0f;
    f = f < (float)(REF_BINS - 1) ? f : (float)(REF_BINS - 1);
    return (int)f;
}

/* The root split of n >= REF_BINS boxes, one box and one comparison at a time, as the
 * builder's documentation states it: doubled centroids binned on each axis, the cheapest
 * boundary (first on ties, axes in order), the boxes of the two sides. Sets in_left[i]. */
static void ref_root_split(const bvh_box *b, int n, int *axis, unsigned char *in_left, float llo[3],
                           float lhi[3], float rlo[3], float rhi[3])
{
    float clo[3], chi[3], scale[3], lo[3], hi[3];
    float blo[3][REF_BINS][3], bhi[3][REF_BINS][3];
    int count[3][REF_BINS] = {{0}}, split = 0;
    double best = INFINITY;
    ref_empty(clo, chi);
    for (int i = 0; i < n; i++) {
        float c[3];
        for (int a = 0; a < 3; a++)
            c[a] = b[i].lo[a] + b[i].hi[a];
        ref_grow(clo, chi, c, c);
    }
    for (int a = 0; a < 3; a++) {
        scale[a] = chi[a] - clo[a] > 0.0f ? (float)REF_BINS / (chi[a] - clo[a]) : 0.0f;
        for (int k = 0; k < REF_BINS; k++)
            ref_empty(blo[a][k], bhi[a][k]);
    }
    for (int i = 0; i < n; i++)
        for (int a = 0; a < 3; a++) {
            int k = ref_bin(&b[i], a, clo[a], scale[a]);
            count[a][k]++;
            ref_grow(blo[a][k], bhi[a][k], b[i].lo, b[i].hi);
        }
    for (int a = 0; a < 3; a++) {
        double right_area[REF_BINS];
        int right_count[REF_BINS], c = 0;
        if (scale[a] == 0.0f)
            continue;
        ref_empty(lo, hi);
        for (int k = REF_BINS - 1; k > 0; k--) {
            c += count[a][k];
            right_count[k] = c;
            if (count[a][k] > 0)
                ref_grow(lo, hi, blo[a][k], bhi[a][k]);
            right_area[k] = c > 0 ? ref_area(lo, hi) : 0.0;
        }
        ref_empty(lo, hi);
        c = 0;
        for (int k = 1; k < REF_BINS; k++) {
            double cost;
            if (count[a][k - 1] == 0)
                continue;
            ref_grow(lo, hi, blo[a][k - 1], bhi[a][k - 1]);
            c += count[a][k - 1];
            if (right_count[k] == 0)
                break;
            cost = ref_area(lo, hi) * c + right_area[k] * right_count[k];
            if (cost < best) {
                best = cost;
                *axis = a;
                split = k;
            }
        }
    }
    assert_true(best < INFINITY);
    ref_empty(llo, lhi);
    ref_empty(rlo, rhi);
    for (int i = 0; i < n; i++) {
        in_left[i] = ref_bin(&b[i], *axis, clo[*axis], scale[*axis]) < split;
        if (in_left[i])
            ref_grow(llo, lhi, b[i].lo, b[i].hi);
        else
            ref_grow(rlo, rhi, b[i].lo, b[i].hi);
    }
}

/* The number of primitives below node k of t. */
static int subtree_count(const bvh *t, int k)
{
    if (t->nodes[k].count > 0)
        return t->nodes[k].count;
    return subtree_count(t, k + 1) + subtree_count(t, t->nodes[k].start);
}

/* The root's split axis, its children's boxes and the primitives below its first child must
 * be the reference's, on one thread and on several (the root binned in parallel). The boxes
 * are compared by value: which of +0 and -0 a box keeps depends on the order the partition
 * visits its primitives in (test_threads_identical checks the bits across thread counts). */
static void root_like_reference(const bvh_box *b, int n, const char *what)
{
    unsigned char *in_left = calloc((size_t)n, 1);
    float llo[3], lhi[3], rlo[3], rhi[3];
    int axis = -1;
    assert_non_null(in_left);
    ref_root_split(b, n, &axis, in_left, llo, lhi, rlo, rhi);
    for (int threads = 1; threads <= 2; threads++) {
        char err[256] = "";
        bvh t;
        const cw_bvh_node *l, *r;
        int nl;
        if (bvh_build_threads(&t, b, n, 4, threads, err, sizeof err) != 0)
            fail_msg("%s: %s", what, err);
        l = &t.nodes[1];
        r = &t.nodes[t.nodes[0].start];
        if (t.nodes[0].count != -axis || !box_equal(l->lo, l->hi, llo, lhi) ||
            !box_equal(r->lo, r->hi, rlo, rhi))
            fail_msg("%s, %d thread(s): the root's split (axis %d, first child [%g %g %g]-[%g %g "
                     "%g]) is not the reference's (axis %d, [%g %g %g]-[%g %g %g])",
                     what, threads, -t.nodes[0].count, l->lo[0], l->lo[1], l->lo[2], l->hi[0],
                     l->hi[1], l->hi[2], axis, llo[0], llo[1], llo[2], lhi[0], lhi[1], lhi[2]);
        nl = subtree_count(&t, 1);
        for (int i = 0; i < t.num_refs; i++)
            if ((i < nl) != in_left[t.refs[i]])
                fail_msg("%s, %d thread(s): primitive %d is on the wrong side of the root", what,
                         threads, t.refs[i]);
        bvh_free(&t);
    }
    free(in_left);
}

static void test_root_split_reference(void **state)
{
    int n = 70000; /* above the parallel build's threshold */
    bvh_box *b = random_boxes(n, 71, 100.0f, 2.0f);
    (void)state;
    root_like_reference(b, n, "uniform");
    for (int i = 0; i < n; i++) { /* a flat cloud: +0 and -0 along y */
        float z = (i % 3) ? 0.0f : -0.0f;
        set_box(&b[i], rnd() * 10.0f, z, rnd() * 3.0f, 0.25f, 0.0f, 0.25f);
        b[i].lo[1] = (i % 5) ? -0.0f : 0.0f;
        b[i].hi[1] = z;
    }
    root_like_reference(b, n, "signed zeros");
    tu_rng_seed(72);
    for (int i = 0; i < n; i++) { /* two clusters far apart, of very different sizes */
        float c = i % 9 == 0 ? 1000.0f : 0.0f, h = i % 9 == 0 ? 5.0f : 0.01f;
        set_box(&b[i], c + rnd() * 20.0f, rnd() * 20.0f, rnd(), h, h * rnd(), h);
    }
    root_like_reference(b, n, "clusters");
    free(b);
}

/* The box of lane i of wide node nd. */
static void lane_box(const cw_bvhw_node *nd, int i, float lo[3], float hi[3])
{
    for (int a = 0; a < 3; a++) {
        lo[a] = nd->bound[a].v[i];
        hi[a] = nd->bound[3 + a].v[i];
    }
}

/* Walks the wide tree from node k: every lane's box must equal the binary node it came
 * from (checked through containment of what lies below), an empty lane's box must be
 * at +infinity (no ray enters it), every primitive must be reached once, and the stack a
 * traversal needs must stay within what bvh_collapse_wide reports. */
static int walk_wide(const bvhw *q, const bvh *t, const bvh_box *boxes, int k, int *seen,
                     int *reached)
{
    int i, need = 0, deepest = 0, interior = 0;
    const cw_bvhw_node *nd = &q->nodes[k];
    assert_true(k >= 0 && k < q->num_nodes);
    for (i = 0; i < CW_BVH_WIDTH; i++) {
        int c = nd->count[i], j, a;
        float lo[3], hi[3];
        lane_box(nd, i, lo, hi);
        if (c == -1) { /* empty: a box at +infinity */
            for (a = 0; a < 3; a++)
                assert_true(lo[a] == INFINITY && hi[a] == INFINITY);
            continue;
        }
        if (c < 0) /* blocks of triangles: not packed here */
            fail_msg("node %d lane %d: count %d before packing", k, i, c);
        if (c > 0) {
            for (j = nd->child[i]; j < nd->child[i] + c; j++) {
                int p = t->refs[j];
                assert_true(p >= 0 && p < t->num_refs);
                seen[p]++;
                (*reached)++;
                for (a = 0; a < 3; a++) {
                    assert_true(boxes[p].lo[a] >= lo[a]);
                    assert_true(boxes[p].hi[a] <= hi[a]);
                }
            }
        } else {
            const cw_bvhw_node *ch = &q->nodes[nd->child[i]];
            int l;
            assert_true(nd->child[i] > k); /* depth-first: children come later */
            for (l = 0; l < CW_BVH_WIDTH; l++) {
                if (ch->count[l] < 0)
                    continue;
                for (a = 0; a < 3; a++) {
                    assert_true(ch->bound[a].v[l] >= lo[a]);
                    assert_true(ch->bound[3 + a].v[l] <= hi[a]);
                }
            }
            interior++;
            need = walk_wide(q, t, boxes, nd->child[i], seen, reached);
            if (need > deepest)
                deepest = need;
        }
    }
    return (interior > 1 ? interior - 1 : 0) + deepest;
}

static void test_collapse_wide(void **state)
{
    static const int sizes[] = {0, 1, 2, 5, 17, 1000, 100000, 300000};
    char err[256];
    size_t s;
    (void)state;
    for (s = 0; s < sizeof sizes / sizeof sizes[0]; s++) {
        int n = sizes[s], reached = 0, i, need;
        bvh_box *boxes = random_boxes(n, 100 + (uint64_t)n, 100.0f, 1.0f);
        int *seen = calloc((size_t)n + 1, sizeof *seen);
        bvh t;
        bvhw q;
        assert_non_null(seen);
        build_ok(&t, boxes, n, 4);
        assert_int_equal(bvh_collapse_wide(&t, &q, err, sizeof err), 0);
        if (n == 0) {
            assert_int_equal(q.num_nodes, 0);
        } else {
            assert_true(q.num_nodes >= 1 && q.num_nodes <= t.num_nodes);
            need = walk_wide(&q, &t, boxes, 0, seen, &reached) + 1;
            assert_int_equal(reached, n);
            for (i = 0; i < n; i++)
                assert_int_equal(seen[i], 1);
            assert_int_equal(need, q.stack_need);
            assert_true(q.stack_need <= CW_BVH_STACK);
        }
        /* the same wide tree, bit for bit, on one thread and on several (100000
         * primitives: the root's lanes collapsed in parallel) */
        for (int threads = 1; threads <= 3; threads += 2) {
            bvhw other;
            assert_int_equal(bvh_collapse_wide_threads(&t, &other, threads, err, sizeof err), 0);
            if (other.num_nodes != q.num_nodes || other.stack_need != q.stack_need ||
                (q.num_nodes > 0 &&
                 memcmp(other.nodes, q.nodes, (size_t)q.num_nodes * sizeof *q.nodes) != 0))
                fail_msg("%d primitives: the collapse on %d thread(s) gives another wide tree "
                         "(%d nodes, stack %d; default: %d nodes, stack %d)",
                         n, threads, other.num_nodes, other.stack_need, q.num_nodes, q.stack_need);
            bvhw_free(&other);
        }
        printf("  %d-wide: %d primitives, %d binary nodes -> %d wide nodes, stack %d\n",
               CW_BVH_WIDTH, n, t.num_nodes, q.num_nodes, q.stack_need);
        bvhw_free(&q);
        bvh_free(&t);
        free(seen);
        free(boxes);
    }
}

/* ---- the collapse's choice: the least sum of wide-node areas ------------------------------- */

/* The least sum of wide-node areas over every way to collapse the subtree of binary node n
 * when n is a wide node of its own, found by exhaustive search (not bvh.c's dynamic
 * programme): its lanes are a frontier of its subtree (nodes whose subtrees hold each leaf
 * once) of at most CW_BVH_WIDTH nodes, other than n alone, and each interior lane is a wide
 * node in turn. */
static double exhaustive_wide(const cw_bvh_node *n2, int n);

/* The least cost of lanes covering the subtree of binary node n, at most k of them; -1
 * when k lanes cannot cover it (k < 1). as_one: n may be one lane itself. */
static double exhaustive_lanes(const cw_bvh_node *n2, int n, int k, int as_one)
{
    double best = -1.0;
    if (k < 1)
        return -1.0;
    if (as_one)
        best = n2[n].count > 0 ? 0.0 : exhaustive_wide(n2, n);
    if (n2[n].count <= 0 && k >= 2)
        for (int a = 1; a < k; a++) {
            double l = exhaustive_lanes(n2, n + 1, a, 1);
            double r = exhaustive_lanes(n2, n2[n].start, k - a, 1);
            if (l >= 0.0 && r >= 0.0 && (best < 0.0 || l + r < best))
                best = l + r;
        }
    return best;
}

static double exhaustive_wide(const cw_bvh_node *n2, int n)
{
    return box_area(n2[n].lo, n2[n].hi) + exhaustive_lanes(n2, n, CW_BVH_WIDTH, 0);
}

/* The sum of the areas of a wide tree's nodes (each the union of its lanes' boxes). */
static double wide_area_sum(const bvhw *q)
{
    double sum = 0.0;
    for (int k = 0; k < q->num_nodes; k++) {
        float lo[3], hi[3];
        box_empty(lo, hi);
        for (int i = 0; i < CW_BVH_WIDTH; i++) {
            float blo[3], bhi[3];
            if (q->nodes[k].count[i] == -1)
                continue; /* an empty lane */
            lane_box(&q->nodes[k], i, blo, bhi);
            box_grow(lo, hi, blo, bhi);
        }
        sum += box_area(lo, hi);
    }
    return sum;
}

/* The collapse against an exhaustive search of every collapse on small random trees
 * (leaves of up to 2, so that up to 20 leaves give many ways): the same least area sum. */
static void test_collapse_least_area(void **state)
{
    char err[256];
    int trees = 0;
    (void)state;
    for (int n = 2; n <= 40; n += 2) {
        for (uint64_t seed = 1; seed <= 5; seed++) {
            bvh_box *boxes = random_boxes(n, 7000 + 100 * (uint64_t)n + seed, 10.0f, 2.0f);
            bvh t;
            bvhw q;
            double want, got;
            build_ok(&t, boxes, n, 2);
            assert_int_equal(bvh_collapse_wide(&t, &q, err, sizeof err), 0);
            want = t.nodes[0].count > 0 ? 0.0 : exhaustive_wide(t.nodes, 0);
            got = t.nodes[0].count > 0 ? 0.0 : wide_area_sum(&q);
            if (fabs(got - want) > 1e-9 * want)
                fail_msg("%d primitives (seed %d): the wide tree's area sum is %.17g, the least "
                         "of all collapses %.17g",
                         n, (int)seed, got, want);
            trees++;
            bvhw_free(&q);
            bvh_free(&t);
            free(boxes);
        }
    }
    printf("  %d small trees: the collapse's area sum is the exhaustive least\n", trees);
}

/* ---- blocks of triangles and spheres --------------------------------------------------- */

static void tri4_lane(cw_float4 *v, int lane, float x)
{
    float *f = lane == 0 ? &v->x : lane == 1 ? &v->y : lane == 2 ? &v->z : &v->w;
    *f = x;
}

static float tri4_get(const cw_float4 *v, int lane)
{
    return lane == 0 ? v->x : lane == 1 ? v->y : lane == 2 ? v->z : v->w;
}

/* A random triangle near the unit cube; now and then a degenerate one (two equal
 * vertices, or three on a line) or one sharing an edge with the previous. */
static void random_triangle(cw_triangle *t, const cw_triangle *prev)
{
    cw_float4 *p[3] = {&t->p0, &t->p1, &t->p2};
    int kind = (int)(rnd() * 8.0f);
    memset(t, 0, sizeof *t);
    for (int k = 0; k < 3; k++) {
        p[k]->x = rnd_range(-1.0f, 1.0f);
        p[k]->y = rnd_range(-1.0f, 1.0f);
        p[k]->z = rnd_range(-1.0f, 1.0f);
    }
    if (kind == 0)
        t->p2 = t->p1;
    if (kind == 1) {
        t->p2.x = 2.0f * t->p1.x - t->p0.x;
        t->p2.y = 2.0f * t->p1.y - t->p0.y;
        t->p2.z = 2.0f * t->p1.z - t->p0.z;
    }
    if (kind == 2 && prev) { /* the edge p0-p1 shared, reversed */
        t->p0 = prev->p1;
        t->p1 = prev->p0;
    }
}

/* isect_sph8 against isect_sphere on each lane in order (the first closest wins, unused
 * lanes left out): the same winner and the same t, bit for bit, for rays at the spheres,
 * grazing them, from inside them, at inside-only (negative radius) and zero-radius ones,
 * and with tmax cutting between the roots. One block or two: with up to four spheres, the
 * second block holds spheres too, which the lane mask (15) must leave out. */
static void test_sph8_matches_single(void **state)
{
    int rays = 0, hits = 0;
    (void)state;
    tu_rng_seed(78);
    for (int trial = 0; trial < 4000; trial++) {
        cw_sphere sp[8];
        cw_sph4 bs[2];
        int used = 1 + (int)(rnd() * 8.0f);
        unsigned lanes = used > 4 ? 255u : 15u;
        memset(bs, 0, sizeof bs);
        memset(sp, 0, sizeof sp);
        for (int l = 0; l < 8; l++) {
            cw_sph4 *bp = &bs[l / 4];
            int bl = l % 4;
            float r = rnd_range(0.05f, 1.0f), kind = rnd();
            sp[l].center.x = rnd_range(-2.0f, 2.0f);
            sp[l].center.y = rnd_range(-2.0f, 2.0f);
            sp[l].center.z = rnd_range(-2.0f, 2.0f);
            sp[l].center.w = kind < 0.15f ? -r : kind < 0.2f ? 0.0f : r;
            if (l > 0 && kind > 0.9f) /* the same sphere twice: a tie */
                sp[l] = sp[l - 1];
            if (l >= used && (used > 4 || l < 4)) {
                bp->index[bl] = -1;
                continue;
            }
            tri4_lane(&bp->cx, bl, sp[l].center.x);
            tri4_lane(&bp->cy, bl, sp[l].center.y);
            tri4_lane(&bp->cz, bl, sp[l].center.z);
            tri4_lane(&bp->r, bl, sp[l].center.w);
            bp->index[bl] = 20 + l;
        }
        for (int r = 0; r < 16; r++) {
            const cw_sphere *aim = &sp[(int)(rnd() * (float)used)];
            vec3 c = v3_from4(aim->center), o, target;
            float rad = cw_fabs(aim->center.w);
            if (r % 4 == 0) /* from inside the aimed sphere */
                o = v3_add(c, v3(rad * 0.3f, -rad * 0.2f, rad * 0.1f));
            else
                o = v3(rnd_range(-5.0f, 5.0f), rnd_range(-5.0f, 5.0f), rnd_range(-5.0f, 5.0f));
            target = v3_add(c, v3(rnd_range(-1.0f, 1.0f) * rad, rnd_range(-1.0f, 1.0f) * rad,
                                  rnd_range(-1.0f, 1.0f) * rad));
            if (r % 8 == 3) /* grazing: at the rim seen from o */
                target = v3_add(c, v3(rad, 0.0f, 0.0f));
            vec3 d = v3_sub(target, o);
            if (v3_len(d) == 0.0f)
                continue;
            d = v3_norm(d);
            float tmax = r % 5 == 0 ? rnd_range(0.1f, 6.0f) : CW_FAR;
            float tmin = r % 7 == 0 ? rnd_range(0.0f, 2.0f) : 0.0f;
            float t1 = 0, best = tmax, t4 = 0;
            int want = -1;
            for (int l = 0; l < used; l++) {
                float t;
                if (isect_sphere(&sp[l], o, d, tmin, best, &t)) {
                    best = t;
                    t1 = t;
                    want = l;
                }
            }
            int got = isect_sph8(&bs[0], &bs[1], lanes, o, d, tmin, tmax, &t4);
            assert_int_equal(got, want);
            if (want >= 0) {
                assert_memory_equal(&t4, &t1, sizeof t1);
                hits++;
            }
            rays++;
        }
    }
    printf("  %d rays, %d hits: isect_sph8 = isect_sphere lane by lane\n", rays, hits);
    assert_true(hits > rays / 4);
}

/* isect_tri8 against isect_triangle on each lane in order (the first closest wins, skip
 * and unused lanes left out): the same winner and the same t, u and v, bit for bit, for
 * rays through the triangles, along their edges and past them. One to eight lanes used: the
 * unused ones (index -1, zero vertices, as the packing leaves them) must never hit. */
static void test_tri8_matches_single(void **state)
{
    int rays = 0, hits = 0;
    (void)state;
    tu_rng_seed(77);
    for (int trial = 0; trial < 4000; trial++) {
        cw_triangle tri[8];
        cw_tri8 bs;
        int used = 1 + (int)(rnd() * 8.0f);
        memset(&bs, 0, sizeof bs);
        for (int l = 0; l < 8; l++) {
            int half = l / 4, bl = l % 4;
            random_triangle(&tri[l], l > 0 ? &tri[l - 1] : NULL);
            if (l >= used) {
                bs.index[l] = -1;
                continue;
            }
            const cw_float4 *p[3] = {&tri[l].p0, &tri[l].p1, &tri[l].p2};
            for (int v = 0; v < 3; v++) {
                tri4_lane(&bs.v[2 * (3 * v) + half], bl, p[v]->x);
                tri4_lane(&bs.v[2 * (3 * v + 1) + half], bl, p[v]->y);
                tri4_lane(&bs.v[2 * (3 * v + 2) + half], bl, p[v]->z);
            }
            bs.index[l] = 10 + l;
        }
        for (int r = 0; r < 16; r++) {
            vec3 o = v3(rnd_range(-3.0f, 3.0f), rnd_range(-3.0f, 3.0f), rnd_range(-3.0f, 3.0f));
            const cw_triangle *aim = &tri[(int)(rnd() * (float)used)];
            float a = rnd(), c = rnd() * (1.0f - a);
            vec3 target;
            if (r % 4 == 0) /* on an edge */
                c = 1.0f - a;
            target = v3_add(v3_scale(v3_from4(aim->p0), 1.0f - a - c),
                            v3_add(v3_scale(v3_from4(aim->p1), a), v3_scale(v3_from4(aim->p2), c)));
            if (r % 8 == 7) /* past it */
                target = v3_add(target, v3(2.0f, 0.0f, 0.0f));
            vec3 d = v3_sub(target, o);
            if (v3_len(d) == 0.0f)
                continue;
            d = v3_norm(d);
            cw_rayinfo ri = isect_rayinfo(o, d);
            float tmax = r % 5 == 0 ? rnd_range(0.5f, 4.0f) : CW_FAR;
            int skip = r % 3 == 0 ? CW_REF(CW_PRIM_TRIANGLE, 10 + (int)(rnd() * 8.0f)) + 1 : 0;
            float t1 = 0, u1 = 0, v1 = 0, best = tmax, t4 = 0, u4 = 0, v4v = 0;
            int want = -1;
            for (int l = 0; l < used; l++) {
                float t, u, v;
                if (CW_REF(CW_PRIM_TRIANGLE, 10 + l) + 1 == skip)
                    continue;
                if (isect_triangle(&tri[l], &ri, 0.0f, best, &t, &u, &v)) {
                    best = t;
                    t1 = t;
                    u1 = u;
                    v1 = v;
                    want = l;
                }
            }
            int got = isect_tri8(&bs, &ri, 0.0f, tmax, skip, &t4, &u4, &v4v);
            assert_int_equal(got, want);
            if (want >= 0) {
                assert_memory_equal(&t4, &t1, sizeof t1);
                assert_memory_equal(&u4, &u1, sizeof u1);
                assert_memory_equal(&v4v, &v1, sizeof v1);
                hits++;
            }
            rays++;
        }
    }
    printf("  %d rays against blocks of 1-8 triangles, %d hits: the same as one by one\n", rays,
           hits);
    assert_true(hits > rays / 4);
}

/* A scene of spheres, polygons and triangles, some of them in coincident pairs (some leaves
 * mixed, most not): every leaf of two or more triangles only becomes blocks holding its
 * triangles in reference order, every other leaf keeps its references, and every primitive
 * is reached exactly once. */
static void test_triangle_blocks(void **state)
{
    char dir[] = "/tmp/cw-test-blocks-XXXXXX", path[64], err[256];
    int nprims, reached = 0, in_blocks = 0, sph_in_blocks = 0;
    FILE *f;
    scene s;
    devscene ds;
    int *seen;
    (void)state;
    assert_non_null(mkdtemp(dir));
    snprintf(path, sizeof path, "%s/blocks.nff", dir);
    f = fopen(path, "w");
    assert_non_null(f);
    fprintf(f, "v\nfrom 0 0 10\nat 0 0 0\nup 0 1 0\nangle 45\nhither 1\nresolution 32 32\n"
               "b 0 0 0\nl 0 10 10\nf 1 0 0 0.5 0.5 30 0 1\n");
    tu_rng_seed(5);
    for (int k = 0; k < 3000; k++) {
        float x = rnd_range(-5, 5), y = rnd_range(-5, 5), z = rnd_range(-5, 5);
        if (k % 10 == 0)
            fprintf(f, "s %g %g %g 0.05\n", x, y, z);
        else if (k % 10 == 1)
            fprintf(f, "p 4\n%g %g %g\n%g %g %g\n%g %g %g\n%g %g %g\n", x, y, z, x + 0.1, y, z,
                    x + 0.1, y + 0.1, z, x, y + 0.1, z);
        else if (k % 10 < 6)
            fprintf(f, "p 3\n%g %g %g\n%g %g %g\n%g %g %g\n", x, y, z, x + 0.1, y, z, x, y + 0.1,
                    z + 0.05);
        else /* both sides of one triangle: the same box, so the same leaf */
            fprintf(f, "p 3\n%g %g %g\n%g %g %g\n%g %g %g\np 3\n%g %g %g\n%g %g %g\n%g %g %g\n", x,
                    y, z, x + 0.1, y, z, x, y + 0.1, z + 0.05, x, y, z, x, y + 0.1, z + 0.05,
                    x + 0.1, y, z);
    }
    fclose(f);
    scene_init(&s);
    if (scene_load(path, &s, err, sizeof err) != 0)
        fail_msg("%s", err);
    unlink(path);
    rmdir(dir);
    assert_int_equal(scene_finish(&s, 0, 0, 0, err, sizeof err), 0);
    memset(&ds, 0, sizeof ds);
    assert_int_equal(devscene_convert(&s, NULL, &ds, err, sizeof err), 0);
    assert_int_equal(devscene_build_bvh(&ds, err, sizeof err), 0);
    nprims = ds.nsph + ds.ntri + ds.npg;
    assert_int_equal(nprims, 3000 + 1200);
    seen = calloc((size_t)nprims, sizeof *seen);
    assert_non_null(seen);
    for (int n = 0; n < ds.tree_wide.num_nodes; n++) {
        const cw_bvhw_node *nd = &ds.tree_wide.nodes[n];
        for (int i = 0; i < CW_BVH_WIDTH; i++) {
            int c = nd->count[i];
            if (c > 0) {
                int tris = 0, sphs = 0;
                for (int k = nd->child[i]; k < nd->child[i] + c; k++) {
                    int ref = ds.refs[k], idx = CW_REF_INDEX(ref), kind = CW_REF_KIND(ref);
                    tris += kind == CW_PRIM_TRIANGLE;
                    sphs += kind == CW_PRIM_SPHERE;
                    seen[kind == CW_PRIM_SPHERE     ? idx
                         : kind == CW_PRIM_TRIANGLE ? ds.nsph + idx
                                                    : ds.nsph + ds.ntri + idx]++;
                    reached++;
                }
                /* a leaf of two or more triangles only or spheres only would be blocks */
                assert_true((tris < c && sphs < c) || c == 1);
            } else if (c < -1 && ((-1 - c) & CW_LEAF_SPHERES)) {
                int nb = (-1 - c) & (CW_LEAF_SPHERES - 1), lanes = 0;
                assert_true(nd->child[i] >= 0 && nd->child[i] + nb <= ds.nsph_blocks);
                for (int bk = nd->child[i]; bk < nd->child[i] + nb; bk++)
                    for (int l = 0; l < 4; l++) {
                        int idx = ds.sph_blocks[bk].index[l];
                        const cw_sph4 *sb = &ds.sph_blocks[bk];
                        if (idx < 0) { /* only the last block has unused lanes, at its end */
                            assert_int_equal(bk, nd->child[i] + nb - 1);
                            assert_true(tri4_get(&sb->r, l) == 0.0f);
                            continue;
                        }
                        assert_true(lanes == 4 * (bk - nd->child[i]) + l);
                        assert_true(idx < ds.nsph);
                        assert_true(tri4_get(&sb->cx, l) == ds.sph[idx].center.x);
                        assert_true(tri4_get(&sb->cy, l) == ds.sph[idx].center.y);
                        assert_true(tri4_get(&sb->cz, l) == ds.sph[idx].center.z);
                        assert_true(tri4_get(&sb->r, l) == ds.sph[idx].center.w);
                        assert_int_equal(sb->material[l], ds.sph_mat[idx]);
                        seen[idx]++;
                        reached++;
                        lanes++;
                        sph_in_blocks++;
                    }
                assert_true(lanes > 4 * (nb - 1) && lanes <= 4 * nb);
            } else if (c < -1) {
                int nb = -1 - c, lanes = 0;
                assert_true(nd->child[i] >= 0 && nd->child[i] + nb <= ds.nblocks);
                for (int bk = nd->child[i]; bk < nd->child[i] + nb; bk++)
                    for (int l = 0; l < 8; l++) {
                        const cw_tri8 *tb = &ds.tri_blocks[bk];
                        int idx = tb->index[l], half = l / 4;
                        if (idx < 0) { /* only the last block has unused lanes, at its end */
                            assert_int_equal(bk, nd->child[i] + nb - 1);
                            for (int r = 0; r < 9; r++) /* zero vertices: never a hit */
                                assert_true(tri4_get(&tb->v[2 * r + half], l % 4) == 0.0f);
                            continue;
                        }
                        assert_true(lanes == 8 * (bk - nd->child[i]) + l);
                        assert_true(idx < ds.ntri);
                        for (int v = 0; v < 3; v++) {
                            const cw_float4 *p = v == 0   ? &ds.tri[idx].p0
                                                 : v == 1 ? &ds.tri[idx].p1
                                                          : &ds.tri[idx].p2;
                            assert_true(tri4_get(&tb->v[2 * (3 * v) + half], l % 4) == p->x);
                            assert_true(tri4_get(&tb->v[2 * (3 * v + 1) + half], l % 4) == p->y);
                            assert_true(tri4_get(&tb->v[2 * (3 * v + 2) + half], l % 4) == p->z);
                        }
                        assert_int_equal(tb->material[l], ds.tri[idx].material);
                        seen[ds.nsph + idx]++;
                        reached++;
                        lanes++;
                        in_blocks++;
                    }
                assert_true(lanes > 8 * (nb - 1) && lanes <= 8 * nb);
            }
        }
    }
    assert_int_equal(reached, nprims);
    for (int k = 0; k < nprims; k++)
        assert_int_equal(seen[k], 1);
    printf("  %d primitives: %d triangles, %d of them in %d blocks; %d spheres, %d in %d blocks\n",
           nprims, ds.ntri, in_blocks, ds.nblocks, ds.nsph, sph_in_blocks, ds.nsph_blocks);
    assert_true(in_blocks >= 2400); /* the pairs at least */
    assert_true(sph_in_blocks > 0);
    free(seen);
    devscene_free(&ds);
    scene_free(&s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_errors),
        cmocka_unit_test(test_collapse_wide),
        cmocka_unit_test(test_collapse_least_area),
        cmocka_unit_test(test_tri8_matches_single),
        cmocka_unit_test(test_sph8_matches_single),
        cmocka_unit_test(test_triangle_blocks),
        cmocka_unit_test(test_empty_and_tiny),
        cmocka_unit_test(test_random_invariants),
        cmocka_unit_test(test_degenerate_invariants),
        cmocka_unit_test(test_nonfinite),
        cmocka_unit_test(test_traversal_spheres),
        cmocka_unit_test(test_traversal_boxes),
        cmocka_unit_test(test_sah_quality),
        cmocka_unit_test(test_million_triangles),
        cmocka_unit_test(test_threads_identical),
        cmocka_unit_test(test_block_leaves),
        cmocka_unit_test(test_build_take),
        cmocka_unit_test(test_root_split_reference),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
