/* The binned SAH build of one tree or subtree (see bvh_sah.h; bvh.c drives it, on one
 * thread or several).
 *
 * The primitives are copied once into a working array (box and input index, 32 bytes
 * each) that is partitioned in place, node by node, depth-first with an explicit stack,
 * so that the nodes come out in the depth-first layout the kernels traverse and every
 * leaf is a contiguous run of the working array. Per node: one pass binning the centroids
 * on all three axes (MAX_BINS bins, fewer for small nodes), one pass partitioning, which
 * also computes the two children's box and centroid bounds. Centroids are kept doubled
 * (lo + hi) and never stored.
 *
 * Depth is bounded: a node splits by SAH only while a worst-case split (n - 1 on one side)
 * would still leave room to finish by median splits within BVH_MAX_DEPTH; otherwise, and
 * whenever binning finds no split (non-finite or degenerate boxes), it splits at the
 * median centroid, which halves the count.
 *
 * A large node at the top of a parallel build is binned on several threads: each bins a
 * range, and the bins are merged in range order (a min or max keeps the earlier of equal
 * values, as one pass in order does), so the split is the one-thread split. */
#include "bvh_sah.h"

#ifdef __SSE2__
#include <emmintrin.h>
#endif
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "box.h"
#include "config.h"

#define MAX_BINS 16           /* per axis; a node of fewer primitives gets as many bins as it has */
#define PAR_BIN_MIN (1 << 14) /* primitives per thread when a top node is binned in parallel */

/* v4_: four floats at once, lane 3 unused (zero), for the inner loops: SSE where the
 * compiler has it, else plain C with the same results (min and max are the comparisons of
 * box_grow, so NaN and signed zeros come out the same either way). */
#ifdef __SSE2__
typedef __m128 v4;
static inline v4 v4_load3(const float *p) /* p[0..2]; p[3] is read, not used */
{
    return _mm_and_ps(_mm_loadu_ps(p), _mm_castsi128_ps(_mm_set_epi32(0, -1, -1, -1)));
}
static inline v4 v4_set(float x, float y, float z)
{
    return _mm_set_ps(0.0f, z, y, x);
}
static inline v4 v4_add(v4 a, v4 b)
{
    return _mm_add_ps(a, b);
}
static inline v4 v4_min(v4 a, v4 b)
{
    return _mm_min_ps(a, b);
} /* a < b ? a : b */
static inline v4 v4_max(v4 a, v4 b)
{
    return _mm_max_ps(a, b);
} /* a > b ? a : b */
static inline void v4_store(float *p, v4 a)
{
    _mm_storeu_ps(p, a);
}
/* The bins of a doubled centroid c on the three axes: bin_of lane by lane. */
static inline void v4_bins(v4 c, v4 cmin, v4 scale, v4 last, int b[3])
{
    v4 f = _mm_mul_ps(_mm_sub_ps(c, cmin), scale);
    __m128i k = _mm_cvttps_epi32(_mm_min_ps(_mm_max_ps(f, _mm_setzero_ps()), last));
    b[0] = _mm_cvtsi128_si32(k);
    b[1] = _mm_cvtsi128_si32(_mm_shuffle_epi32(k, 1));
    b[2] = _mm_cvtsi128_si32(_mm_shuffle_epi32(k, 2));
}
#else
typedef struct {
    float v[4];
} v4;
static inline v4 v4_load3(const float *p)
{
    v4 r = {{p[0], p[1], p[2], 0.0f}};
    return r;
}
static inline v4 v4_set(float x, float y, float z)
{
    v4 r = {{x, y, z, 0.0f}};
    return r;
}
static inline v4 v4_add(v4 a, v4 b)
{
    for (int k = 0; k < 4; k++)
        a.v[k] += b.v[k];
    return a;
}
static inline v4 v4_min(v4 a, v4 b)
{
    for (int k = 0; k < 4; k++)
        a.v[k] = a.v[k] < b.v[k] ? a.v[k] : b.v[k];
    return a;
}
static inline v4 v4_max(v4 a, v4 b)
{
    for (int k = 0; k < 4; k++)
        a.v[k] = a.v[k] > b.v[k] ? a.v[k] : b.v[k];
    return a;
}
static inline void v4_store(float *p, v4 a)
{
    memcpy(p, a.v, sizeof a.v);
}
#endif

/* One bin of each axis: the box of its primitives (lane 3 unused); the counts apart. */
typedef struct {
    float lo[4], hi[4];
} bin;

typedef struct {
    bin box[3][MAX_BINS];
    int count[3][MAX_BINS];
    int blocked[BVH_BLOCK_CLASSES][3][MAX_BINS]; /* of count, those of each block class */
} bins;

_Static_assert(sizeof(sah_prim) == 32, "sah_prim is 32 bytes");

/* Bin of a doubled centroid: NaN goes to bin 0, out-of-range values to the end bins. */
static inline int bin_of(float c, float cmin, float scale, float last)
{
    float f = (c - cmin) * scale;
    f = f > 0.0f ? f : 0.0f;
    f = f < last ? f : last;
    return (int)f;
}

#ifndef __SSE2__
static inline void v4_bins(v4 c, v4 cmin, v4 scale, v4 last, int b[3])
{
    for (int a = 0; a < 3; a++)
        b[a] = bin_of(c.v[a], cmin.v[a], scale.v[a], last.v[a]);
}
#endif

/* Sort key of a doubled centroid for median splits: a total order (NaN first). */
static inline float centroid_key(const sah_prim *p, int axis)
{
    float c = p->lo[axis] + p->hi[axis];
    return c == c ? c : -INFINITY;
}

static inline void swap_prims(sah_prim *a, sah_prim *b)
{
    sah_prim t = *a;
    *a = *b;
    *b = t;
}

/* Levels of median splits needed below a node of n primitives to reach leaves of at most
 * max_leaf. */
static int median_levels(int n, int max_leaf)
{
    int k = 0;
    while (n > max_leaf) {
        n -= n / 2;
        k++;
    }
    return k;
}

/* Rearranges w[begin, end) so that w[nth] holds the element of its rank by centroid along
 * axis, smaller-or-equal ones before it and greater-or-equal after (three-way quickselect,
 * median-of-three pivot: terminates on any keys, duplicates included). */
static void select_nth(sah_prim *w, int begin, int end, int nth, int axis)
{
    while (end - begin > 1) {
        float k0 = centroid_key(&w[begin], axis);
        float k1 = centroid_key(&w[begin + (end - begin) / 2], axis);
        float k2 = centroid_key(&w[end - 1], axis);
        float pivot =
            k0 < k1 ? (k1 < k2 ? k1 : (k0 < k2 ? k2 : k0)) : (k0 < k2 ? k0 : (k1 < k2 ? k2 : k1));
        int lt = begin, i = begin, gt = end;
        while (i < gt) {
            float k = centroid_key(&w[i], axis);
            if (k < pivot)
                swap_prims(&w[lt++], &w[i++]);
            else if (k > pivot)
                swap_prims(&w[i], &w[--gt]);
            else
                i++;
        }
        if (nth < lt)
            end = lt;
        else if (nth >= gt)
            begin = gt;
        else
            return;
    }
}

/* Bins w[begin, end) by doubled centroid on each axis. */
static void bin_range(const sah_prim *w, int begin, int end, const float clo[3],
                      const float scale[3], int nb, bins *bn)
{
    float last = (float)(nb - 1);
    v4 vclo = v4_set(clo[0], clo[1], clo[2]), vscale = v4_set(scale[0], scale[1], scale[2]);
    v4 vlast = v4_set(last, last, last);
    for (int a = 0; a < 3; a++) {
        for (int b = 0; b < nb; b++) {
            box_empty(bn->box[a][b].lo, bn->box[a][b].hi);
            bn->box[a][b].lo[3] = bn->box[a][b].hi[3] = 0.0f;
            bn->count[a][b] = 0;
            for (int c = 0; c < BVH_BLOCK_CLASSES; c++)
                bn->blocked[c][a][b] = 0;
        }
    }
    for (int i = begin; i < end; i++) {
        v4 lo = v4_load3(w[i].lo), hi = v4_load3(w[i].hi);
        int k[3];
        v4_bins(v4_add(lo, hi), vclo, vscale, vlast, k);
        for (int a = 0; a < 3; a++) {
            bin *b = &bn->box[a][k[a]];
            v4_store(b->lo, v4_min(lo, v4_load3(b->lo)));
            v4_store(b->hi, v4_max(hi, v4_load3(b->hi)));
            bn->count[a][k[a]]++;
            if (w[i].block > 0)
                bn->blocked[w[i].block - 1][a][k[a]]++;
        }
    }
}

/* One thread's share of a node's binning. */
typedef struct {
    const sah_prim *w;
    int begin, end, nb;
    const float *clo, *scale;
    bins bn;
} bin_part;

static void *bin_part_run(void *arg)
{
    bin_part *bp = arg;
    bin_range(bp->w, bp->begin, bp->end, bp->clo, bp->scale, bp->nb, &bp->bn);
    return NULL;
}

/* bin_range on `threads` threads: each bins a range, and the bins are merged in range order,
 * so that every count, min and max is what one pass in order gives. */
static void bin_parallel(const sah_prim *w, int begin, int end, const float clo[3],
                         const float scale[3], int nb, int threads, bins *bn)
{
    bin_part part[CW_BVH_MAX_THREADS];
    pthread_t tid[CW_BVH_MAX_THREADS];
    int started[CW_BVH_MAX_THREADS], n = end - begin;
    for (int k = 1; k < threads; k++) {
        bin_part *bp = &part[k];
        bp->w = w;
        bp->begin = begin + (int)((long long)n * k / threads);
        bp->end = begin + (int)((long long)n * (k + 1) / threads);
        bp->nb = nb;
        bp->clo = clo;
        bp->scale = scale;
        started[k] = pthread_create(&tid[k], NULL, bin_part_run, bp) == 0;
    }
    bin_range(w, begin, begin + (int)((long long)n / threads), clo, scale, nb, bn);
    for (int k = 1; k < threads; k++) {
        if (started[k])
            pthread_join(tid[k], NULL);
        else
            bin_part_run(&part[k]); /* no thread: bin it here */
        for (int a = 0; a < 3; a++) {
            for (int b = 0; b < nb; b++) {
                bn->count[a][b] += part[k].bn.count[a][b];
                for (int c = 0; c < BVH_BLOCK_CLASSES; c++)
                    bn->blocked[c][a][b] += part[k].bn.blocked[c][a][b];
                box_grow(bn->box[a][b].lo, bn->box[a][b].hi, part[k].bn.box[a][b].lo,
                         part[k].bn.box[a][b].hi);
            }
        }
    }
}

/* The SAH intersection cost (in C_ISECT) of a leaf of n primitives, nb[c] of them of
 * block class c + 1: blocks of SAH_BLOCK where all are of one class, else one test each. */
static inline double leaf_cost(int n, const int nb[BVH_BLOCK_CLASSES])
{
    for (int c = 0; c < BVH_BLOCK_CLASSES; c++)
        if (nb[c] == n)
            return (double)((n + SAH_BLOCK - 1) / SAH_BLOCK);
    return (double)n;
}

/* Best binned SAH split of w[begin, end) whose doubled centroids span [clo, chi], with
 * nb bins per axis, binned on `threads` threads. Returns the cost relative to the node area
 * (C_trav + sum of child area * leaf_cost(child) / node area), or INFINITY when no bin
 * boundary separates the primitives; sets *axis, *split (the first bin of the second
 * child) and the bin scales, and nblocked[c] to the primitives of block class c + 1. */
static double best_split(const sah_prim *w, int begin, int end, const float clo[3],
                         const float chi[3], double node_area, int nb, int threads, float scale[3],
                         int *axis, int *split, int nblocked[BVH_BLOCK_CLASSES])
{
    bins bn;
    double best = INFINITY;
    int first_axis = 1;
    for (int c = 0; c < BVH_BLOCK_CLASSES; c++)
        nblocked[c] = 0;
    for (int a = 0; a < 3; a++) {
        float ext = chi[a] - clo[a];
        scale[a] = ext > 0.0f ? (float)nb / ext : 0.0f;
    }
    if (threads > 1)
        bin_parallel(w, begin, end, clo, scale, nb, threads, &bn);
    else
        bin_range(w, begin, end, clo, scale, nb, &bn);
    for (int a = 0; a < 3; a++) {
        double right_area[MAX_BINS], right_cost[MAX_BINS];
        int right_count[MAX_BINS];
        float lo[3], hi[3];
        int count = 0, blocked[BVH_BLOCK_CLASSES] = {0};
        if (scale[a] == 0.0f)
            continue;
        box_empty(lo, hi);
        for (int b = nb - 1; b > 0; b--) {
            count += bn.count[a][b];
            for (int c = 0; c < BVH_BLOCK_CLASSES; c++)
                blocked[c] += bn.blocked[c][a][b];
            right_count[b] = count;
            right_cost[b] = leaf_cost(count, blocked);
            if (bn.count[a][b] > 0)
                box_grow(lo, hi, bn.box[a][b].lo, bn.box[a][b].hi);
            right_area[b] = count > 0 ? box_area(lo, hi) : 0.0;
        }
        if (first_axis) { /* every primitive is in one bin of each binned axis */
            for (int c = 0; c < BVH_BLOCK_CLASSES; c++)
                nblocked[c] = blocked[c] + bn.blocked[c][a][0];
            first_axis = 0;
        }
        box_empty(lo, hi);
        count = 0;
        for (int c = 0; c < BVH_BLOCK_CLASSES; c++)
            blocked[c] = 0;
        for (int b = 1; b < nb; b++) {
            double cost;
            if (bn.count[a][b - 1] == 0)
                continue; /* the same split as the previous boundary */
            box_grow(lo, hi, bn.box[a][b - 1].lo, bn.box[a][b - 1].hi);
            count += bn.count[a][b - 1];
            for (int c = 0; c < BVH_BLOCK_CLASSES; c++)
                blocked[c] += bn.blocked[c][a][b - 1];
            if (right_count[b] == 0)
                break;
            cost = box_area(lo, hi) * leaf_cost(count, blocked) + right_area[b] * right_cost[b];
            if (cost < best) {
                best = cost;
                *axis = a;
                *split = b;
            }
        }
    }
    if (best == INFINITY)
        return INFINITY;
    return C_TRAV + C_ISECT * best / node_area;
}

/* The bounds of a task while they grow: box and doubled-centroid box. */
typedef struct {
    v4 lo, hi, clo, chi;
} bounds;

static inline void bounds_empty(bounds *b)
{
    b->lo = b->clo = v4_set(INFINITY, INFINITY, INFINITY);
    b->hi = b->chi = v4_set(-INFINITY, -INFINITY, -INFINITY);
}

static inline void bounds_grow(bounds *b, const sah_prim *p)
{
    v4 lo = v4_load3(p->lo), hi = v4_load3(p->hi), c = v4_add(lo, hi);
    b->lo = v4_min(lo, b->lo);
    b->hi = v4_max(hi, b->hi);
    b->clo = v4_min(c, b->clo);
    b->chi = v4_max(c, b->chi);
}

static void bounds_to_task(const bounds *b, sah_task *t)
{
    float f[4][4];
    v4_store(f[0], b->lo);
    v4_store(f[1], b->hi);
    v4_store(f[2], b->clo);
    v4_store(f[3], b->chi);
    for (int a = 0; a < 3; a++) {
        t->lo[a] = f[0][a];
        t->hi[a] = f[1][a];
        t->clo[a] = f[2][a];
        t->chi[a] = f[3][a];
    }
}

void sah_task_range(sah_task *t, const sah_prim *w, int begin, int end)
{
    bounds b;
    bounds_empty(&b);
    for (int i = begin; i < end; i++)
        bounds_grow(&b, &w[i]);
    t->begin = begin;
    t->end = end;
    bounds_to_task(&b, t);
}

/* Moves the primitives of t's range in bins below split (along axis) to the front; sets
 * the ranges and bounds of the two sides. */
static void partition_bins(sah_prim *w, const sah_task *t, int axis, int split, float scale,
                           float last, sah_task *left, sah_task *right)
{
    int i = t->begin, j = t->end - 1;
    float cmin = t->clo[axis];
    bounds l, r;
    bounds_empty(&l);
    bounds_empty(&r);
    for (;;) {
        while (i <= j && bin_of(w[i].lo[axis] + w[i].hi[axis], cmin, scale, last) < split)
            bounds_grow(&l, &w[i++]);
        while (i <= j && bin_of(w[j].lo[axis] + w[j].hi[axis], cmin, scale, last) >= split)
            bounds_grow(&r, &w[j--]);
        if (i >= j)
            break;
        swap_prims(&w[i], &w[j]);
        bounds_grow(&l, &w[i++]);
        bounds_grow(&r, &w[j--]);
    }
    bounds_to_task(&l, left);
    bounds_to_task(&r, right);
    left->begin = t->begin;
    left->end = right->begin = i;
    right->end = t->end;
}

/* Records task t as a subtree to build later, rooted at slot pos. Returns 0, or -1 when
 * out of memory. */
static int defer_subtree(sah_builder *bd, const sah_task *t, int pos)
{
    if (bd->nsubs == bd->subs_cap) {
        int cap = bd->subs_cap ? 2 * bd->subs_cap : 64;
        sah_subtree *ns = realloc(bd->subs, (size_t)cap * sizeof *ns);
        if (!ns)
            return -1;
        bd->subs = ns;
        bd->subs_cap = cap;
    }
    memset(&bd->subs[bd->nsubs], 0, sizeof bd->subs[0]);
    bd->subs[bd->nsubs].t = *t;
    bd->subs[bd->nsubs].pos = pos;
    bd->nsubs++;
    return 0;
}

int sah_build_nodes(sah_builder *bd, cw_bvh_node *nodes, const sah_task *root, int top, int *depth)
{
    sah_task stack[BVH_MAX_DEPTH + 2];
    sah_prim *w = bd->w;
    int sp = 1, num_nodes = 0, max_leaf = bd->max_leaf;
    int leaf_cap = max_leaf > BVH_COINCIDENT_LEAF ? max_leaf : BVH_COINCIDENT_LEAF;
    stack[0] = *root;
    while (sp > 0) {
        sah_task t = stack[--sp], *left, *right;
        int ni = num_nodes++, count = t.end - t.begin, axis = 0, split_done = 0, coincident = 1;
        cw_bvh_node *node = &nodes[ni];
        if (t.parent >= 0)
            nodes[t.parent].start = ni;
        if (top && count <= bd->cutoff) {
            if (defer_subtree(bd, &t, ni) != 0)
                return -1;
            num_nodes += 2 * count - 2; /* the most its subtree can need */
            continue;
        }
        if (t.depth > *depth)
            *depth = t.depth;
        for (int a = 0; a < 3; a++) {
            node->lo[a] = t.lo[a];
            node->hi[a] = t.hi[a];
            if (t.chi[a] > t.clo[a])
                coincident = 0;
        }
        if (count == 1 || (coincident && count <= leaf_cap)) {
            node->start = t.begin;
            node->count = count;
            continue;
        }

        /* second child below the first, so that the first is made next (index ni + 1) */
        right = &stack[sp];
        left = &stack[sp + 1];
        if (!coincident && t.depth + 1 + median_levels(count - 1, max_leaf) <= BVH_MAX_DEPTH) {
            float scale[3];
            int split = 0, nb = count < MAX_BINS ? count : MAX_BINS;
            int nblocked[BVH_BLOCK_CLASSES];
            int threads = top ? count / PAR_BIN_MIN : 1; /* enough work for each */
            threads = threads < 1 ? 1 : (threads > bd->threads ? bd->threads : threads);
            double cost = best_split(w, t.begin, t.end, t.clo, t.chi, box_area(t.lo, t.hi), nb,
                                     threads, scale, &axis, &split, nblocked);
            if (cost < C_ISECT * leaf_cost(count, nblocked) ||
                (count > max_leaf && cost < INFINITY)) {
                partition_bins(w, &t, axis, split, scale[axis], (float)(nb - 1), left, right);
                /* both sides are non-empty (the bins said so); stay safe all the same */
                split_done = left->end > t.begin && left->end < t.end;
            }
        }
        if (!split_done) {
            int mid = t.begin + count / 2;
            if (!coincident && count <= max_leaf) {
                node->start = t.begin; /* SAH prefers a leaf, or no split exists */
                node->count = count;
                continue;
            }
            if (!coincident) { /* median split along the widest centroid extent */
                float ext = -1.0f;
                for (int a = 0; a < 3; a++) {
                    if (t.chi[a] - t.clo[a] > ext) {
                        ext = t.chi[a] - t.clo[a];
                        axis = a;
                    }
                }
                select_nth(w, t.begin, t.end, mid, axis);
            } /* else split by count: any order will do */
            sah_task_range(left, w, t.begin, mid);
            sah_task_range(right, w, mid, t.end);
        }
        node->start = -1; /* set when the second child is made */
        node->count = -axis;
        right->depth = left->depth = t.depth + 1;
        right->parent = ni;
        left->parent = -1;
        sp += 2;
    }
    return num_nodes;
}
