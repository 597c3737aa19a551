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
 * median centroid, which halves the count.
 *
 * On several threads (bvh_build_threads) the tree is the same, bit for bit: the top of the
 * tree is built first, its large nodes binned in parallel (each thread bins a range; the
 * bins are merged in range order, and a min or max keeps the earlier of equal values, as
 * one pass in order does); its nodes of at most `cutoff` primitives become subtrees, built
 * concurrently, each on its own range of the working array and into its own range of the
 * node array (2k - 1 slots for k primitives: the most a subtree can need). A last pass
 * closes the gaps, which puts every node where the one-thread build puts it. */
#include "bvh.h"

#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "box.h"
#include "config.h"

#define MAX_BINS 16 /* per axis; a node of fewer primitives gets as many bins as it has */
#define PAR_MIN_PRIMS (1 << 15) /* fewer primitives: one thread builds everything */
#define PAR_BIN_MIN (1 << 14)   /* a top node of fewer primitives is binned on one thread */
#define PAR_SUBTREES 8          /* subtrees per thread the top of the tree is cut into */
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

/* A subtree built on its own: its task, where its nodes go (provisionally) and what it
 * became. */
typedef struct {
    task t;
    int pos;       /* its root's slot in the provisional layout; 2 * count - 1 slots are kept */
    int num_nodes; /* nodes built */
    int depth;     /* deepest node */
    int final;     /* its root's index once the gaps are closed */
} subtree;

/* What a build shares between its threads. */
typedef struct {
    prim *w;
    cw_bvh_node *nodes;
    int max_leaf, threads;
    int cutoff; /* the top of the tree: tasks of at most this many primitives are subtrees */
    subtree *subs;
    int nsubs, subs_cap;
    int *order; /* subtrees by size, largest first */
    int next;   /* next of order to build */
    pthread_mutex_t lock;
} builder;

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

/* Bins w[begin, end) by doubled centroid on each axis. */
static void bin_range(const prim *w, int begin, int end, const float clo[3], const float scale[3],
                      int nb, bin bins[3][MAX_BINS])
{
    float last = (float)(nb - 1);
    for (int a = 0; a < 3; a++) {
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
}

/* One thread's share of a node's binning. */
typedef struct {
    const prim *w;
    int begin, end, nb;
    const float *clo, *scale;
    bin bins[3][MAX_BINS];
} bin_part;

static void *bin_part_run(void *arg)
{
    bin_part *bp = arg;
    bin_range(bp->w, bp->begin, bp->end, bp->clo, bp->scale, bp->nb, bp->bins);
    return NULL;
}

/* bin_range on `threads` threads: each bins a range, and the bins are merged in range order,
 * so that every count, min and max is what one pass in order gives. */
static void bin_parallel(const prim *w, int begin, int end, const float clo[3],
                         const float scale[3], int nb, int threads, bin bins[3][MAX_BINS])
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
    bin_range(w, begin, begin + (int)((long long)n / threads), clo, scale, nb, bins);
    for (int k = 1; k < threads; k++) {
        if (started[k])
            pthread_join(tid[k], NULL);
        else
            bin_part_run(&part[k]); /* no thread: bin it here */
        for (int a = 0; a < 3; a++) {
            for (int b = 0; b < nb; b++) {
                bins[a][b].count += part[k].bins[a][b].count;
                box_grow(bins[a][b].lo, bins[a][b].hi, part[k].bins[a][b].lo,
                         part[k].bins[a][b].hi);
            }
        }
    }
}

/* Best binned SAH split of w[begin, end) whose doubled centroids span [clo, chi], with
 * nb bins per axis, binned on `threads` threads. Returns the cost relative to the node area
 * (C_trav + sum of child area * count / node area), or INFINITY when no bin boundary
 * separates the primitives; sets *axis, *split (the first bin of the second child) and the
 * bin scales. */
static double best_split(const prim *w, int begin, int end, const float clo[3], const float chi[3],
                         double node_area, int nb, int threads, float scale[3], int *axis,
                         int *split)
{
    bin bins[3][MAX_BINS];
    double best = INFINITY;
    for (int a = 0; a < 3; a++) {
        float ext = chi[a] - clo[a];
        scale[a] = ext > 0.0f ? (float)nb / ext : 0.0f;
    }
    if (threads > 1)
        bin_parallel(w, begin, end, clo, scale, nb, threads, bins);
    else
        bin_range(w, begin, end, clo, scale, nb, bins);
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

/* Records task t as a subtree to build later, rooted at slot pos. Returns 0, or -1 when
 * out of memory. */
static int defer_subtree(builder *bd, const task *t, int pos)
{
    if (bd->nsubs == bd->subs_cap) {
        int cap = bd->subs_cap ? 2 * bd->subs_cap : 64;
        subtree *ns = realloc(bd->subs, (size_t)cap * sizeof *ns);
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

/* Builds the nodes of the subtree of task *root into nodes[0, ...) (node indices relative to
 * nodes; leaf starts index the working array). In the top phase (top = 1), the large nodes
 * are binned on bd->threads threads and every task of at most bd->cutoff primitives becomes
 * a subtree for later, keeping 2 * count - 1 slots. Returns the slots used, or -1 when out
 * of memory; raises *depth to the deepest node made. */
static int build_nodes(builder *bd, cw_bvh_node *nodes, const task *root, int top, int *depth)
{
    task stack[BVH_MAX_DEPTH + 2];
    prim *w = bd->w;
    int sp = 1, num_nodes = 0, max_leaf = bd->max_leaf;
    int leaf_cap = max_leaf > BVH_COINCIDENT_LEAF ? max_leaf : BVH_COINCIDENT_LEAF;
    stack[0] = *root;
    while (sp > 0) {
        task t = stack[--sp], *left, *right;
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
            int threads = top && count >= PAR_BIN_MIN ? bd->threads : 1;
            double cost = best_split(w, t.begin, t.end, t.clo, t.chi, box_area(t.lo, t.hi), nb,
                                     threads, scale, &axis, &split);
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
        sp += 2;
    }
    return num_nodes;
}

/* Builds the subtrees in order of bd->order until none is left (one such loop per thread). */
static void *build_subtrees(void *arg)
{
    builder *bd = arg;
    for (;;) {
        subtree *st;
        task t;
        int k;
        pthread_mutex_lock(&bd->lock);
        k = bd->next < bd->nsubs ? bd->order[bd->next++] : -1;
        pthread_mutex_unlock(&bd->lock);
        if (k < 0)
            return NULL;
        st = &bd->subs[k];
        t = st->t;
        t.parent = -1;
        st->num_nodes = build_nodes(bd, bd->nodes + st->pos, &t, 0, &st->depth);
    }
}

/* Subtree k before subtree j: larger first (it would finish last otherwise), then in tree
 * order. */
static int builds_before(const builder *bd, int k, int j)
{
    int ck = bd->subs[k].t.end - bd->subs[k].t.begin, cj = bd->subs[j].t.end - bd->subs[j].t.begin;
    return ck != cj ? ck > cj : k < j;
}

/* The final index of the node at provisional slot pos (a top node or a subtree's root). */
static int final_index(const builder *bd, const int *top_pos, const int *top_final, int ntop,
                       int pos)
{
    int lo = 0, hi = bd->nsubs - 1;
    while (lo <= hi) { /* subtrees are in slot order */
        int mid = (lo + hi) / 2;
        if (bd->subs[mid].pos == pos)
            return bd->subs[mid].final;
        if (bd->subs[mid].pos < pos)
            lo = mid + 1;
        else
            hi = mid - 1;
    }
    lo = 0;
    hi = ntop - 1;
    while (lo <= hi) {
        int mid = (lo + hi) / 2;
        if (top_pos[mid] == pos)
            return top_final[mid];
        if (top_pos[mid] < pos)
            lo = mid + 1;
        else
            hi = mid - 1;
    }
    return -1; /* not reached: every slot referred to is one of them */
}

/* Closes the gaps the subtrees left in bd->nodes[0, slots): each node moves to where the
 * one-thread build puts it, and the second-child indices follow. Returns the node count, or
 * -1 when out of memory. */
static int close_gaps(builder *bd, int slots)
{
    int *top_pos = malloc((size_t)(bd->nsubs + 1) * 2 * sizeof *top_pos), *top_final;
    int pos = 0, k = 0, t = 0, ntop = 0, next = 0;
    if (!top_pos)
        return -1;
    top_final = top_pos + bd->nsubs + 1;
    while (pos < slots) { /* where each piece goes */
        if (k < bd->nsubs && bd->subs[k].pos == pos) {
            bd->subs[k].final = next;
            next += bd->subs[k].num_nodes;
            pos += 2 * (bd->subs[k].t.end - bd->subs[k].t.begin) - 1;
            k++;
        } else {
            top_pos[ntop] = pos;
            top_final[ntop++] = next++;
            pos++;
        }
    }
    for (pos = k = 0; pos < slots;) { /* move them, left to right: never over one to move */
        if (k < bd->nsubs && bd->subs[k].pos == pos) {
            const subtree *st = &bd->subs[k++];
            cw_bvh_node *dst = bd->nodes + st->final;
            memmove(dst, bd->nodes + pos, (size_t)st->num_nodes * sizeof *dst);
            for (int i = 0; i < st->num_nodes; i++)
                if (dst[i].count <= 0)
                    dst[i].start += st->final;
            pos += 2 * (st->t.end - st->t.begin) - 1;
        } else {
            cw_bvh_node *dst = bd->nodes + top_final[t++];
            *dst = bd->nodes[pos++];
            if (dst->count <= 0)
                dst->start = final_index(bd, top_pos, top_final, ntop, dst->start);
        }
    }
    free(top_pos);
    return next;
}

/* Builds the nodes over bd->w[0, n) on bd->threads threads (see the top of this file).
 * Returns the node count, or -1 when out of memory; sets *depth. */
static int build_parallel(builder *bd, const task *root, int *depth)
{
    pthread_t tid[CW_BVH_MAX_THREADS];
    int started[CW_BVH_MAX_THREADS], slots, num_nodes = -1;
    if (pthread_mutex_init(&bd->lock, NULL) != 0)
        return build_nodes(bd, bd->nodes, root, 0, depth);
    bd->cutoff = bd->max_leaf > BVH_COINCIDENT_LEAF ? bd->max_leaf : BVH_COINCIDENT_LEAF;
    if (root->end / (PAR_SUBTREES * bd->threads) > bd->cutoff)
        bd->cutoff = root->end / (PAR_SUBTREES * bd->threads);
    slots = build_nodes(bd, bd->nodes, root, 1, depth);
    if (slots < 0)
        goto out;
    bd->order = malloc((size_t)(bd->nsubs > 0 ? bd->nsubs : 1) * sizeof *bd->order);
    if (!bd->order)
        goto out;
    for (int k = 0; k < bd->nsubs; k++) { /* insertion sort: a few dozen subtrees */
        int j = k;
        for (; j > 0 && builds_before(bd, k, bd->order[j - 1]); j--)
            bd->order[j] = bd->order[j - 1];
        bd->order[j] = k;
    }
    for (int k = 1; k < bd->threads; k++)
        started[k] = pthread_create(&tid[k], NULL, build_subtrees, bd) == 0;
    build_subtrees(bd); /* this thread too; the others' share if they did not start */
    for (int k = 1; k < bd->threads; k++)
        if (started[k])
            pthread_join(tid[k], NULL);
    for (int k = 0; k < bd->nsubs; k++)
        if (bd->subs[k].depth > *depth)
            *depth = bd->subs[k].depth;
    num_nodes = close_gaps(bd, slots);
out:
    pthread_mutex_destroy(&bd->lock);
    free(bd->order);
    free(bd->subs);
    return num_nodes;
}

/* The thread count for a build: threads, or one per online core when threads <= 0, at most
 * CW_BVH_MAX_THREADS. */
static int thread_count(int threads)
{
    if (threads <= 0) {
        long cores = sysconf(_SC_NPROCESSORS_ONLN);
        threads = cores > 0 ? (int)(cores < CW_BVH_MAX_THREADS ? cores : CW_BVH_MAX_THREADS) : 1;
    }
    return threads < CW_BVH_MAX_THREADS ? threads : CW_BVH_MAX_THREADS;
}

int bvh_build(bvh *out, const bvh_box *boxes, int n, int max_leaf, char *err, size_t errlen)
{
    return bvh_build_threads(out, boxes, n, max_leaf, CW_BVH_THREADS, err, errlen);
}

int bvh_build_threads(bvh *out, const bvh_box *boxes, int n, int max_leaf, int threads, char *err,
                      size_t errlen)
{
    cw_bvh_node *shrunk;
    builder bd;
    task root;
    int *refs;
    memset(out, 0, sizeof *out);
    memset(&bd, 0, sizeof bd);
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
    bd.nodes = malloc((size_t)(2 * n - 1) * sizeof *bd.nodes);
    if (!bd.nodes)
        goto out_free_refs;
    bd.w = malloc((size_t)n * sizeof *bd.w);
    if (!bd.w)
        goto out_free_nodes;

    for (int i = 0; i < n; i++) {
        for (int a = 0; a < 3; a++) {
            bd.w[i].lo[a] = boxes[i].lo[a];
            bd.w[i].hi[a] = boxes[i].hi[a];
        }
        bd.w[i].idx = i;
        bd.w[i].pad = 0;
    }
    bd.max_leaf = max_leaf;
    bd.threads = n >= PAR_MIN_PRIMS ? thread_count(threads) : 1;
    task_range(&root, bd.w, 0, n);
    root.depth = 1;
    root.parent = -1;
    out->num_nodes = bd.threads > 1 ? build_parallel(&bd, &root, &out->depth)
                                    : build_nodes(&bd, bd.nodes, &root, 0, &out->depth);
    if (out->num_nodes < 0) {
        free(bd.w);
        goto out_free_nodes;
    }
    for (int i = 0; i < n; i++)
        refs[i] = bd.w[i].idx;
    free(bd.w);

    shrunk = realloc(bd.nodes, (size_t)out->num_nodes * sizeof *bd.nodes);
    out->nodes = shrunk ? shrunk : bd.nodes;
    out->refs = refs;
    out->num_refs = n;
    return 0;

out_free_nodes:
    free(bd.nodes);
out_free_refs:
    free(refs);
out_oom:
    memset(out, 0, sizeof *out);
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
