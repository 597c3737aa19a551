/* The bounding volume hierarchy (see bvh.h): the build on one thread or several, and the
 * collapse into the wide tree. The binned SAH build itself is in bvh_sah.c.
 *
 * On several threads (bvh_build_threads) the tree is the same, bit for bit: the top of the
 * tree is built first (its large nodes binned on all threads); its nodes of at most
 * `cutoff` primitives become subtrees, built concurrently, each on its own range of the
 * working array and into its own range of the node array (2k - 1 slots for k primitives:
 * the most a subtree can need). A last pass closes the gaps, which puts every node where
 * the one-thread build puts it. */
#include "bvh.h"

#include <float.h>
#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "box.h"
#include "bvh_sah.h"
#include "config.h"
#include "sys.h"

#define PAR_MIN_PRIMS (1 << 15) /* fewer primitives: one thread builds everything */
#define PAR_SUBTREES 8          /* subtrees per thread the top of the tree is cut into */
#define PAR_MIN_WIDE (1 << 16)  /* fewer binary nodes: the collapse runs on one thread */

/* Builds the subtrees in order of bd->order until none is left (one such loop per thread). */
static void *build_subtrees(void *arg)
{
    sah_builder *bd = arg;
    for (;;) {
        sah_subtree *st;
        sah_task t;
        int k;
        pthread_mutex_lock(&bd->lock);
        k = bd->next < bd->nsubs ? bd->order[bd->next++] : -1;
        pthread_mutex_unlock(&bd->lock);
        if (k < 0)
            return NULL;
        st = &bd->subs[k];
        t = st->t;
        t.parent = -1;
        st->num_nodes = sah_build_nodes(bd, bd->nodes + st->pos, &t, 0, &st->depth);
    }
}

/* Subtree k before subtree j: larger first (it would finish last otherwise), then in tree
 * order. */
static int builds_before(const sah_builder *bd, int k, int j)
{
    int ck = bd->subs[k].t.end - bd->subs[k].t.begin, cj = bd->subs[j].t.end - bd->subs[j].t.begin;
    return ck != cj ? ck > cj : k < j;
}

/* The final index of the node at provisional slot pos (a top node or a subtree's root). */
static int final_index(const sah_builder *bd, const int *top_pos, const int *top_final, int ntop,
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
static int close_gaps(sah_builder *bd, int slots)
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
            const sah_subtree *st = &bd->subs[k++];
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
static int build_parallel(sah_builder *bd, const sah_task *root, int *depth)
{
    pthread_t tid[CW_BVH_MAX_THREADS];
    int started[CW_BVH_MAX_THREADS], slots, num_nodes = -1;
    if (pthread_mutex_init(&bd->lock, NULL) != 0)
        return sah_build_nodes(bd, bd->nodes, root, 0, depth);
    bd->cutoff = bd->max_leaf > BVH_COINCIDENT_LEAF ? bd->max_leaf : BVH_COINCIDENT_LEAF;
    if (root->end / (PAR_SUBTREES * bd->threads) > bd->cutoff)
        bd->cutoff = root->end / (PAR_SUBTREES * bd->threads);
    slots = sah_build_nodes(bd, bd->nodes, root, 1, depth);
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
    if (threads <= 0)
        threads = sys_cpu_count();
    return threads < CW_BVH_MAX_THREADS ? threads : CW_BVH_MAX_THREADS;
}

static int build(bvh *out, const bvh_box *boxes, bvh_box **take, const unsigned char *blocks, int n,
                 int max_leaf, int threads, char *err, size_t errlen);

int bvh_build(bvh *out, const bvh_box *boxes, int n, int max_leaf, char *err, size_t errlen)
{
    return build(out, boxes, NULL, NULL, n, max_leaf, CW_BVH_THREADS, err, errlen);
}

int bvh_build_threads(bvh *out, const bvh_box *boxes, int n, int max_leaf, int threads, char *err,
                      size_t errlen)
{
    return build(out, boxes, NULL, NULL, n, max_leaf, threads, err, errlen);
}

int bvh_build_blocks(bvh *out, const bvh_box *boxes, const unsigned char *blocks, int n,
                     int max_leaf, int threads, char *err, size_t errlen)
{
    return build(out, boxes, NULL, blocks, n, max_leaf, threads, err, errlen);
}

int bvh_build_blocks_take(bvh *out, bvh_box **boxes, const unsigned char *blocks, int n,
                          int max_leaf, int threads, char *err, size_t errlen)
{
    return build(out, *boxes, boxes, blocks, n, max_leaf, threads, err, errlen);
}

/* The builder's copy of the boxes is made: a caller's array given to it (take) is freed. */
static void drop_taken(bvh_box **take)
{
    if (take) {
        free(*take);
        *take = NULL;
    }
}

static int build(bvh *out, const bvh_box *boxes, bvh_box **take, const unsigned char *blocks, int n,
                 int max_leaf, int threads, char *err, size_t errlen)
{
    cw_bvh_node *shrunk;
    sah_builder bd;
    sah_task root;
    int *refs, *shrunk_refs;
    memset(out, 0, sizeof *out);
    memset(&bd, 0, sizeof bd);
    if (n < 0 || n > BVH_MAX_PRIMS) {
        snprintf(err, errlen, "bvh: %d primitives (the most is %d)", n, BVH_MAX_PRIMS);
        goto out_drop;
    }
    if (max_leaf < 1) {
        snprintf(err, errlen, "bvh: maximum leaf size %d (must be at least 1)", max_leaf);
        goto out_drop;
    }
    if (n == 0) {
        drop_taken(take);
        return 0;
    }

    bd.nodes = malloc((size_t)(2 * n - 1) * sizeof *bd.nodes);
    if (!bd.nodes)
        goto out_oom;
    bd.w = malloc((size_t)n * sizeof *bd.w);
    if (!bd.w)
        goto out_free_nodes;

    for (int i = 0; i < n; i++) {
        for (int a = 0; a < 3; a++) {
            bd.w[i].lo[a] = boxes[i].lo[a];
            bd.w[i].hi[a] = boxes[i].hi[a];
        }
        bd.w[i].idx = i;
        bd.w[i].block = blocks && blocks[i] <= BVH_BLOCK_CLASSES ? blocks[i] : 0;
    }
    drop_taken(take); /* before the build's own arrays fill */
    bd.max_leaf = max_leaf;
    bd.threads = n >= PAR_MIN_PRIMS ? thread_count(threads) : 1;
    sah_task_range(&root, bd.w, 0, n);
    root.depth = 1;
    root.parent = -1;
    out->num_nodes = bd.threads > 1 ? build_parallel(&bd, &root, &out->depth)
                                    : sah_build_nodes(&bd, bd.nodes, &root, 0, &out->depth);
    if (out->num_nodes < 0) {
        free(bd.w);
        goto out_free_nodes;
    }
    /* the leaf entries in place of the working array (entry i lies below prim i, read
     * first), which is then cut to their size: no fresh memory to fault in */
    refs = (int *)bd.w;
    for (int i = 0; i < n; i++)
        refs[i] = bd.w[i].idx;
    shrunk_refs = realloc(refs, (size_t)n * sizeof *refs);
    refs = shrunk_refs ? shrunk_refs : refs;

    shrunk = realloc(bd.nodes, (size_t)out->num_nodes * sizeof *bd.nodes);
    out->nodes = shrunk ? shrunk : bd.nodes;
    out->refs = refs;
    out->num_refs = n;
    return 0;

out_free_nodes:
    free(bd.nodes);
out_oom:
    memset(out, 0, sizeof *out);
    snprintf(err, errlen, "bvh: out of memory for %d primitives", n);
out_drop:
    drop_taken(take);
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

/* ---- the wide tree ------------------------------------------------------------------- */

/* Lane i of node q: the box of binary node n, or (n NULL) a box at +infinity, which no ray
 * enters (kernels/traverse.h, bvh_boxes). */
static void set_lane(cw_bvhw_node *q, int i, const cw_bvh_node *n)
{
    for (int a = 0; a < 3; a++) {
        q->bound[a].v[i] = n ? n->lo[a] : INFINITY;
        q->bound[3 + a].v[i] = n ? n->hi[a] : INFINITY;
    }
}

/* The collapse's plan: which binary nodes become the lanes of each wide node, chosen to
 * minimise the wide tree's SAH cost (Ylitie, Karras and Laine, "Efficient Incoherent Ray
 * Traversal on GPUs Through Compressed Wide BVHs", HPG 2017, without their leaf
 * re-forming). Every leaf is in the wide tree once whatever the choice, so that cost is
 * the sum of the wide nodes' areas. F(n, k) is its least value for the subtree of binary
 * node n as at most k lanes of its parent: n itself (a leaf, or a wide node of its own),
 * or for an interior n with k >= 2 its children's subtrees sharing the k lanes.
 * plan[8 n + k - 1] (k >= 2) says which: 0 for n itself, else the lanes of its first
 * child, the rest going to its second; plan[8 n] is the split of the 8 lanes of n's own
 * wide node. Filling lanes with small subtrees this way, rather than always opening the
 * lane of largest area, keeps the tree from ending in nodes of two or three lanes (1M
 * random triangles: 49855 wide nodes instead of 62204). */
static void plan_node(const cw_bvh_node *n2, int i, unsigned char *plan, double f[CW_BVH_WIDTH])
{
    const cw_bvh_node *n = &n2[i];
    double l[CW_BVH_WIDTH], r[CW_BVH_WIDTH], g[CW_BVH_WIDTH + 1], own;
    unsigned char ga[CW_BVH_WIDTH + 1], *pl;
    if (n->count > 0) { /* a leaf costs nothing; its plan is never read */
        for (int k = 0; k < CW_BVH_WIDTH; k++)
            f[k] = 0.0;
        return;
    }
    plan_node(n2, i + 1, plan, l);
    plan_node(n2, n->start, plan, r);
    for (int k = 2; k <= CW_BVH_WIDTH; k++) { /* k lanes shared by the two children */
        g[k] = l[0] + r[k - 2];
        ga[k] = 1;
        for (int a = 2; a < k; a++) {
            double c = l[a - 1] + r[k - a - 1];
            if (c < g[k]) {
                g[k] = c;
                ga[k] = (unsigned char)a;
            }
        }
    }
    own = box_area(n->lo, n->hi) + g[CW_BVH_WIDTH];
    pl = &plan[(size_t)i * CW_BVH_WIDTH];
    f[0] = own;
    pl[0] = ga[CW_BVH_WIDTH];
    for (int k = 2; k <= CW_BVH_WIDTH; k++) {
        int split = g[k] <= own;
        f[k - 1] = split ? g[k] : own;
        pl[k - 1] = split ? ga[k] : 0;
    }
}

/* Appends the lanes the plan gives the subtree of binary node i as at most k lanes. */
static void plan_lanes(const cw_bvh_node *n2, const unsigned char *plan, int i, int k, int *slots,
                       int *ns)
{
    int a = k >= 2 && n2[i].count <= 0 ? plan[(size_t)i * CW_BVH_WIDTH + k - 1] : 0;
    if (a == 0) {
        slots[(*ns)++] = i;
        return;
    }
    plan_lanes(n2, plan, i + 1, a, slots, ns);
    plan_lanes(n2, plan, n2[i].start, k - a, slots, ns);
}

/* The binary nodes that become the lanes of the wide node made for binary node i2, as the
 * plan says. Returns the count. */
static int choose_slots(const cw_bvh_node *n2, const unsigned char *plan, int i2,
                        int slots[CW_BVH_WIDTH])
{
    int ns = 0, a;
    if (n2[i2].count > 0) {
        slots[0] = i2;
        return 1;
    }
    a = plan[(size_t)i2 * CW_BVH_WIDTH];
    plan_lanes(n2, plan, i2 + 1, a, slots, &ns);
    plan_lanes(n2, plan, n2[i2].start, CW_BVH_WIDTH - a, slots, &ns);
    return ns;
}

/* The wide nodes collapse makes for binary node i2 (the same choices, nothing written). */
static int collapse_count(const cw_bvh_node *n2, const unsigned char *plan, int i2)
{
    int slots[CW_BVH_WIDTH], ns = choose_slots(n2, plan, i2, slots), c = 1;
    for (int i = 0; i < ns; i++)
        if (n2[slots[i]].count <= 0)
            c += collapse_count(n2, plan, slots[i]);
    return c;
}

/* Builds the wide node for binary node i2 at nodes[(*next)++], its subtree after it
 * depth-first; returns its index and sets *need to the stack entries its subtree's
 * traversal needs. The recursion is as deep as the binary tree (at most BVH_MAX_DEPTH). */
static int collapse(const cw_bvh_node *n2, const unsigned char *plan, int i2, cw_bvhw_node *nodes,
                    int *next, int *need)
{
    int slots[CW_BVH_WIDTH], ns = choose_slots(n2, plan, i2, slots), k = (*next)++, i;
    int interior = 0, deepest = 0;
    for (i = 0; i < CW_BVH_WIDTH; i++) {
        cw_bvhw_node *q = &nodes[k];
        if (i >= ns) {
            set_lane(q, i, NULL);
            q->child[i] = 0;
            q->count[i] = -1;
        } else if (n2[slots[i]].count > 0) {
            set_lane(q, i, &n2[slots[i]]);
            q->child[i] = n2[slots[i]].start;
            q->count[i] = n2[slots[i]].count;
        } else {
            int sub = 0;
            set_lane(q, i, &n2[slots[i]]);
            q->count[i] = 0;
            q->child[i] = collapse(n2, plan, slots[i], nodes, next, &sub);
            interior++;
            if (sub > deepest)
                deepest = sub;
        }
    }
    /* going down one interior child leaves the others on the stack */
    *need = (interior > 1 ? interior - 1 : 0) + deepest;
    return k;
}

/* The collapse of a big tree on several threads: the root's wide node is made first, and
 * its interior lanes' subtrees are counted (collapse_count), then written at the indices
 * the one-thread collapse gives them (the counts of the lanes before), lanes handed out
 * in order to whichever thread is free, in both phases. */
typedef struct {
    const cw_bvh_node *n2;
    const unsigned char *plan;
    cw_bvhw_node *nodes;
    int slots[CW_BVH_WIDTH], ns;
    int count[CW_BVH_WIDTH], first[CW_BVH_WIDTH], need[CW_BVH_WIDTH];
    int writing, next_lane;
    pthread_mutex_t lock;
} wide_par;

static void *wide_par_run(void *arg)
{
    wide_par *wp = arg;
    for (;;) {
        int i, next;
        pthread_mutex_lock(&wp->lock);
        i = wp->next_lane < wp->ns ? wp->next_lane++ : -1;
        pthread_mutex_unlock(&wp->lock);
        if (i < 0)
            return NULL;
        if (wp->n2[wp->slots[i]].count > 0)
            continue;
        if (!wp->writing) {
            wp->count[i] = collapse_count(wp->n2, wp->plan, wp->slots[i]);
        } else {
            next = wp->first[i];
            collapse(wp->n2, wp->plan, wp->slots[i], wp->nodes, &next, &wp->need[i]);
        }
    }
}

/* Runs one phase of wp on `threads` threads (this one included). */
static void wide_par_phase(wide_par *wp, int threads)
{
    pthread_t tid[CW_BVH_MAX_THREADS];
    int started[CW_BVH_MAX_THREADS];
    wp->next_lane = 0;
    for (int k = 1; k < threads; k++)
        started[k] = pthread_create(&tid[k], NULL, wide_par_run, wp) == 0;
    wide_par_run(wp);
    for (int k = 1; k < threads; k++)
        if (started[k])
            pthread_join(tid[k], NULL);
}

/* bvh_collapse_wide's work for a tree of at least two binary nodes on `threads` threads;
 * returns the wide node count and sets *need. */
static int collapse_parallel(const cw_bvh_node *n2, const unsigned char *plan, cw_bvhw_node *nodes,
                             int threads, int *need)
{
    wide_par wp;
    int next = 1, interior = 0, deepest = 0;
    memset(&wp, 0, sizeof wp);
    if (pthread_mutex_init(&wp.lock, NULL) != 0) {
        collapse(n2, plan, 0, nodes, &next, need);
        return next;
    }
    wp.n2 = n2;
    wp.plan = plan;
    wp.nodes = nodes;
    wp.ns = choose_slots(n2, plan, 0, wp.slots);
    wide_par_phase(&wp, threads);
    for (int i = 0; i < wp.ns; i++)
        if (n2[wp.slots[i]].count <= 0) {
            wp.first[i] = next;
            next += wp.count[i];
        }
    wp.writing = 1;
    wide_par_phase(&wp, threads);
    pthread_mutex_destroy(&wp.lock);
    for (int i = 0; i < CW_BVH_WIDTH; i++) { /* the root, as collapse makes it */
        const cw_bvh_node *c = i < wp.ns ? &n2[wp.slots[i]] : NULL;
        set_lane(&nodes[0], i, c);
        nodes[0].child[i] = !c ? 0 : c->count > 0 ? c->start : wp.first[i];
        nodes[0].count[i] = !c ? -1 : c->count > 0 ? c->count : 0;
        if (c && c->count <= 0) {
            interior++;
            if (wp.need[i] > deepest)
                deepest = wp.need[i];
        }
    }
    *need = (interior > 1 ? interior - 1 : 0) + deepest;
    return next;
}

int bvh_collapse_wide(const bvh *b, bvhw *out, char *err, size_t errlen)
{
    return bvh_collapse_wide_threads(b, out, CW_BVH_THREADS, err, errlen);
}

int bvh_collapse_wide_threads(const bvh *b, bvhw *out, int threads, char *err, size_t errlen)
{
    int need = 0;
    unsigned char *plan;
    double f[CW_BVH_WIDTH];
    threads = thread_count(threads);
    memset(out, 0, sizeof *out);
    if (b->num_nodes == 0)
        return 0;
    plan = malloc((size_t)b->num_nodes * CW_BVH_WIDTH);
    out->nodes = sys_device_calloc((size_t)b->num_nodes, sizeof *out->nodes);
    if (!out->nodes || !plan) {
        free(plan);
        sys_device_free(out->nodes);
        out->nodes = NULL;
        snprintf(err, errlen, "out of memory for the wide BVH (%d nodes)", b->num_nodes);
        return -1;
    }
    plan_node(b->nodes, 0, plan, f);
    if (threads > 1 && b->num_nodes >= PAR_MIN_WIDE && b->nodes[0].count <= 0) {
        out->num_nodes = collapse_parallel(b->nodes, plan, out->nodes, threads, &need);
    } else {
        collapse(b->nodes, plan, 0, out->nodes, &out->num_nodes, &need);
    }
    free(plan);
    out->stack_need = need + 1;
    { /* a fraction of the binary count is used: give the rest back */
        cw_bvhw_node *shrunk =
            sys_device_realloc(out->nodes, (size_t)out->num_nodes, sizeof *out->nodes);
        if (shrunk)
            out->nodes = shrunk;
    }
    return 0;
}

void bvhw_free(bvhw *b)
{
    sys_device_free(b->nodes);
    memset(b, 0, sizeof *b);
}
