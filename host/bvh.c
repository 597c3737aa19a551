/* Binned SAH builder for the bounding volume hierarchy (see bvh.h).
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
 * median centroid, which halves the count. */
#include "bvh.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "box.h"

#define MAX_BINS 16 /* per axis; a node of fewer primitives gets as many bins as it has */
#define C_TRAV 1.0
#define C_ISECT 1.0

typedef struct {
    float lo[3];
    int idx; /* index into the input boxes */
    float hi[3];
    int pad;
} prim;

typedef struct {
    float lo[3], hi[3];
    int count;
    int pad;
} bin;

/* A node to make: its range of the working array and what is known of it. */
typedef struct {
    int begin, end;
    int depth;            /* root = 1 */
    int parent;           /* node whose second child this is, or -1 (first child or root) */
    float lo[3], hi[3];   /* bounds of the boxes */
    float clo[3], chi[3]; /* bounds of the doubled centroids */
} task;

_Static_assert(sizeof(prim) == 32, "prim is 32 bytes");

/* Bin of a doubled centroid: NaN goes to bin 0, out-of-range values to the end bins. */
static inline int bin_of(float c, float cmin, float scale, float last)
{
    float f = (c - cmin) * scale;
    f = f > 0.0f ? f : 0.0f;
    f = f < last ? f : last;
    return (int)f;
}

/* Sort key of a doubled centroid for median splits: a total order (NaN first). */
static inline float centroid_key(const prim *p, int axis)
{
    float c = p->lo[axis] + p->hi[axis];
    return c == c ? c : -INFINITY;
}

static inline void swap_prims(prim *a, prim *b)
{
    prim t = *a;
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
static void select_nth(prim *w, int begin, int end, int nth, int axis)
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

/* Best binned SAH split of w[begin, end) whose doubled centroids span [clo, chi], with
 * nb bins per axis. Returns the cost relative to the node area (C_trav + sum of child
 * area * count / node area), or INFINITY when no bin boundary separates the primitives;
 * sets *axis, *split (the first bin of the second child) and the bin scales. */
static double best_split(const prim *w, int begin, int end, const float clo[3], const float chi[3],
                         double node_area, int nb, float scale[3], int *axis, int *split)
{
    bin bins[3][MAX_BINS];
    double best = INFINITY;
    float last = (float)(nb - 1);
    for (int a = 0; a < 3; a++) {
        float ext = chi[a] - clo[a];
        scale[a] = ext > 0.0f ? (float)nb / ext : 0.0f;
        for (int b = 0; b < nb; b++) {
            box_empty(bins[a][b].lo, bins[a][b].hi);
            bins[a][b].count = 0;
        }
    }
    for (int i = begin; i < end; i++) {
        const prim *p = &w[i];
        for (int a = 0; a < 3; a++) {
            bin *b = &bins[a][bin_of(p->lo[a] + p->hi[a], clo[a], scale[a], last)];
            b->count++;
            box_grow(b->lo, b->hi, p->lo, p->hi);
        }
    }
    for (int a = 0; a < 3; a++) {
        double right_area[MAX_BINS];
        int right_count[MAX_BINS];
        float lo[3], hi[3];
        int count = 0;
        if (scale[a] == 0.0f)
            continue;
        box_empty(lo, hi);
        for (int b = nb - 1; b > 0; b--) {
            count += bins[a][b].count;
            right_count[b] = count;
            if (bins[a][b].count > 0)
                box_grow(lo, hi, bins[a][b].lo, bins[a][b].hi);
            right_area[b] = count > 0 ? box_area(lo, hi) : 0.0;
        }
        box_empty(lo, hi);
        count = 0;
        for (int b = 1; b < nb; b++) {
            double cost;
            if (bins[a][b - 1].count == 0)
                continue; /* the same split as the previous boundary */
            box_grow(lo, hi, bins[a][b - 1].lo, bins[a][b - 1].hi);
            count += bins[a][b - 1].count;
            if (right_count[b] == 0)
                break;
            cost = box_area(lo, hi) * count + right_area[b] * right_count[b];
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

static void task_empty(task *t)
{
    box_empty(t->lo, t->hi);
    box_empty(t->clo, t->chi);
}

static inline void task_grow(task *t, const prim *p)
{
    float c[3];
    for (int a = 0; a < 3; a++)
        c[a] = p->lo[a] + p->hi[a];
    box_grow(t->lo, t->hi, p->lo, p->hi);
    box_grow(t->clo, t->chi, c, c);
}

/* Sets t's range and computes its bounds. */
static void task_range(task *t, const prim *w, int begin, int end)
{
    t->begin = begin;
    t->end = end;
    task_empty(t);
    for (int i = begin; i < end; i++)
        task_grow(t, &w[i]);
}

/* Moves the primitives of t's range in bins below split (along axis) to the front; sets
 * the ranges and bounds of the two sides. */
static void partition_bins(prim *w, const task *t, int axis, int split, float scale, float last,
                           task *left, task *right)
{
    int i = t->begin, j = t->end - 1;
    float cmin = t->clo[axis];
    task_empty(left);
    task_empty(right);
    for (;;) {
        while (i <= j && bin_of(w[i].lo[axis] + w[i].hi[axis], cmin, scale, last) < split)
            task_grow(left, &w[i++]);
        while (i <= j && bin_of(w[j].lo[axis] + w[j].hi[axis], cmin, scale, last) >= split)
            task_grow(right, &w[j--]);
        if (i >= j)
            break;
        swap_prims(&w[i], &w[j]);
        task_grow(left, &w[i++]);
        task_grow(right, &w[j--]);
    }
    left->begin = t->begin;
    left->end = right->begin = i;
    right->end = t->end;
}

/* Builds the nodes over w[0, n); returns the node count and sets *depth. */
static int build_nodes(cw_bvh_node *nodes, prim *w, int n, int max_leaf, int *depth)
{
    task stack[BVH_MAX_DEPTH + 2];
    int top = 0, num_nodes = 0;
    int leaf_cap = max_leaf > BVH_COINCIDENT_LEAF ? max_leaf : BVH_COINCIDENT_LEAF;
    *depth = 0;
    task_range(&stack[0], w, 0, n);
    stack[0].depth = 1;
    stack[0].parent = -1;
    top = 1;
    while (top > 0) {
        task t = stack[--top], *left, *right;
        int ni = num_nodes++, count = t.end - t.begin, axis = 0, split_done = 0, coincident = 1;
        cw_bvh_node *node = &nodes[ni];
        if (t.parent >= 0)
            nodes[t.parent].start = ni;
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
        right = &stack[top];
        left = &stack[top + 1];
        if (!coincident && t.depth + 1 + median_levels(count - 1, max_leaf) <= BVH_MAX_DEPTH) {
            float scale[3];
            int split = 0, nb = count < MAX_BINS ? count : MAX_BINS;
            double cost = best_split(w, t.begin, t.end, t.clo, t.chi, box_area(t.lo, t.hi), nb,
                                     scale, &axis, &split);
            if (cost < C_ISECT * count || (count > max_leaf && cost < INFINITY)) {
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
            task_range(left, w, t.begin, mid);
            task_range(right, w, mid, t.end);
        }
        node->start = -1; /* set when the second child is made */
        node->count = -axis;
        right->depth = left->depth = t.depth + 1;
        right->parent = ni;
        left->parent = -1;
        top += 2;
    }
    return num_nodes;
}

int bvh_build(bvh *out, const bvh_box *boxes, int n, int max_leaf, char *err, size_t errlen)
{
    cw_bvh_node *nodes, *shrunk;
    prim *work;
    int *refs;
    memset(out, 0, sizeof *out);
    if (n < 0 || n > BVH_MAX_PRIMS) {
        snprintf(err, errlen, "bvh: %d primitives (the most is %d)", n, BVH_MAX_PRIMS);
        return -1;
    }
    if (max_leaf < 1) {
        snprintf(err, errlen, "bvh: maximum leaf size %d (must be at least 1)", max_leaf);
        return -1;
    }
    if (n == 0)
        return 0;

    refs = malloc((size_t)n * sizeof *refs);
    if (!refs)
        goto out_oom;
    nodes = malloc((size_t)(2 * n - 1) * sizeof *nodes);
    if (!nodes)
        goto out_free_refs;
    work = malloc((size_t)n * sizeof *work);
    if (!work)
        goto out_free_nodes;

    for (int i = 0; i < n; i++) {
        for (int a = 0; a < 3; a++) {
            work[i].lo[a] = boxes[i].lo[a];
            work[i].hi[a] = boxes[i].hi[a];
        }
        work[i].idx = i;
        work[i].pad = 0;
    }
    out->num_nodes = build_nodes(nodes, work, n, max_leaf, &out->depth);
    for (int i = 0; i < n; i++)
        refs[i] = work[i].idx;
    free(work);

    shrunk = realloc(nodes, (size_t)out->num_nodes * sizeof *nodes);
    out->nodes = shrunk ? shrunk : nodes;
    out->refs = refs;
    out->num_refs = n;
    return 0;

out_free_nodes:
    free(nodes);
out_free_refs:
    free(refs);
out_oom:
    snprintf(err, errlen, "bvh: out of memory for %d primitives", n);
    return -1;
}

void bvh_free(bvh *b)
{
    free(b->nodes);
    free(b->refs);
    memset(b, 0, sizeof *b);
}

double bvh_sah_cost(const bvh *b)
{
    double root, sum = 0.0;
    if (b->num_nodes == 0)
        return 0.0;
    root = box_area(b->nodes[0].lo, b->nodes[0].hi);
    for (int i = 0; i < b->num_nodes; i++) {
        const cw_bvh_node *nd = &b->nodes[i];
        double cost = nd->count > 0 ? C_ISECT * nd->count : C_TRAV;
        double w = root > 0.0 && isfinite(root) ? box_area(nd->lo, nd->hi) / root : 1.0;
        sum += w * cost;
    }
    return sum;
}

/* ---- the 4-wide tree ------------------------------------------------------------------ */

static void f4_set(cw_float4 *v, int i, float x)
{
    if (i == 0)
        v->x = x;
    else if (i == 1)
        v->y = x;
    else if (i == 2)
        v->z = x;
    else
        v->w = x;
}

static void set_lane(cw_bvh4_node *q, int i, const cw_bvh_node *n)
{
    f4_set(&q->lo_x, i, n ? n->lo[0] : 0.0f);
    f4_set(&q->lo_y, i, n ? n->lo[1] : 0.0f);
    f4_set(&q->lo_z, i, n ? n->lo[2] : 0.0f);
    f4_set(&q->hi_x, i, n ? n->hi[0] : 0.0f);
    f4_set(&q->hi_y, i, n ? n->hi[1] : 0.0f);
    f4_set(&q->hi_z, i, n ? n->hi[2] : 0.0f);
}

/* Builds the 4-wide node for binary node i2 at out->nodes[out->num_nodes++]; returns
 * its index and sets *need to the stack entries its subtree's traversal needs. The
 * recursion is as deep as the binary tree (at most BVH_MAX_DEPTH). */
static int collapse(const cw_bvh_node *n2, int i2, bvh4 *out, int *need)
{
    int slots[4], ns = 0, k = out->num_nodes++, i, interior = 0, deepest = 0;
    cw_bvh4_node *q;

    if (n2[i2].count > 0) {
        slots[ns++] = i2;
    } else {
        slots[ns++] = i2 + 1;
        slots[ns++] = n2[i2].start;
        while (ns < 4) {
            int best = -1;
            double best_area = -1;
            for (i = 0; i < ns; i++)
                if (n2[slots[i]].count <= 0 &&
                    box_area(n2[slots[i]].lo, n2[slots[i]].hi) > best_area) {
                    best = i;
                    best_area = box_area(n2[slots[i]].lo, n2[slots[i]].hi);
                }
            if (best < 0)
                break;
            slots[ns++] = n2[slots[best]].start;
            slots[best] = slots[best] + 1;
        }
    }
    for (i = 0; i < 4; i++) {
        q = &out->nodes[k];
        if (i >= ns) {
            set_lane(q, i, NULL);
            q->child[i] = 0;
            q->count[i] = -1;
        } else if (n2[slots[i]].count > 0) {
            set_lane(q, i, &n2[slots[i]]);
            q->child[i] = n2[slots[i]].start;
            q->count[i] = n2[slots[i]].count;
        } else {
            int sub = 0, c;
            set_lane(q, i, &n2[slots[i]]);
            q->count[i] = 0;
            c = collapse(n2, slots[i], out, &sub);
            out->nodes[k].child[i] = c;
            interior++;
            if (sub > deepest)
                deepest = sub;
        }
    }
    /* going down one interior child leaves the others on the stack */
    *need = (interior > 1 ? interior - 1 : 0) + deepest;
    return k;
}

int bvh_collapse4(const bvh *b, bvh4 *out, char *err, size_t errlen)
{
    int need = 0;
    memset(out, 0, sizeof *out);
    if (b->num_nodes == 0)
        return 0;
    out->nodes = calloc((size_t)b->num_nodes, sizeof *out->nodes);
    if (!out->nodes) {
        snprintf(err, errlen, "out of memory for the 4-wide BVH (%d nodes)", b->num_nodes);
        return -1;
    }
    collapse(b->nodes, 0, out, &need);
    out->stack_need = need + 1;
    return 0;
}

void bvh4_free(bvh4 *b)
{
    free(b->nodes);
    memset(b, 0, sizeof *b);
}
