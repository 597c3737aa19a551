/* The bounding volume hierarchy: a binned surface-area-heuristic (SAH) builder over
 * axis-aligned boxes, flattened depth-first into cw_bvh_node, and its collapse into the
 * wide tree the kernels traverse (cw_bvhw_node, kernels/types.h: CW_BVH_WIDTH children per
 * node). */
#ifndef CW_BVH_H
#define CW_BVH_H

#include <stddef.h>

#include "types.h"

/* Every tree bvh_build returns is at most this deep (root = 1), whatever the input: a
 * traversal stack of BVH_MAX_DEPTH entries always suffices. */
#define BVH_MAX_DEPTH 64
/* Largest leaf made when all centroids of a node coincide (no split can separate them),
 * unless max_leaf is larger; bigger sets are split by count. */
#define BVH_COINCIDENT_LEAF 64
/* Largest n bvh_build accepts (the node count, at most 2n - 1, must fit an int). */
#define BVH_MAX_PRIMS (1 << 29)

typedef struct {
    float lo[3], hi[3];
} bvh_box;

/* One node of the flattened binary tree (depth-first order: an interior node's first
 * child is the next node). */
typedef struct {
    float lo[3];
    int start; /* leaf: first entry in the primitive-reference array;
                * interior: index of the second child */
    float hi[3];
    int count; /* leaf: number of primitives (> 0); interior: -(split axis) (0, -1, -2) */
} cw_bvh_node;

typedef struct {
    cw_bvh_node *nodes; /* depth-first: an interior node's first child is the next node */
    int num_nodes;
    int *refs; /* leaf entries: indices into the input box array, each input primitive once */
    int num_refs;
    int depth; /* maximum depth (root = 1; 0 for an empty tree) */
} bvh;

/* Builds over n boxes (n >= 0); n == 0 gives an empty tree (num_nodes == 0, NULL arrays).
 * max_leaf (>= 1): most primitives per leaf; a leaf may be larger (up to
 * max(max_leaf, BVH_COINCIDENT_LEAF)) only when all its centroids coincide. Boxes with NaN
 * or infinite coordinates give a valid tree (every primitive once, bounded depth) whose
 * boxes need not contain them. Returns 0, or -1 with a message in err (out of memory,
 * n or max_leaf out of range); on failure *out is an empty tree. */
int bvh_build(bvh *out, const bvh_box *boxes, int n, int max_leaf, char *err, size_t errlen);
/* bvh_build on `threads` threads (<= 0: one per online core; bvh_build takes CW_BVH_THREADS
 * from config.h). The tree is the same, bit for bit, for every thread count. */
int bvh_build_threads(bvh *out, const bvh_box *boxes, int n, int max_leaf, int threads, char *err,
                      size_t errlen);
/* Block classes: primitives the kernels keep in blocks in a leaf of one class only
 * (triangles: eight to a block, cw_tri8; spheres: four, cw_sph4) and test BVH_BLOCK_TEST at
 * a time (one test of eight lanes; about as fast as four on a CPU with 256-bit vectors). */
#define BVH_BLOCK_CLASSES 2
#define BVH_BLOCK_TEST 8

/* bvh_build_threads where blocks[i] (0 .. BVH_BLOCK_CLASSES) gives box i's block class: the
 * SAH prices a leaf of n primitives of one class at ceil(n / BVH_BLOCK_TEST) tests, so it
 * prefers full tests; 0 (or blocks NULL) is a primitive tested alone (bvh_build_threads'
 * tree). threads <= 0: one per online core. */
int bvh_build_blocks(bvh *out, const bvh_box *boxes, const unsigned char *blocks, int n,
                     int max_leaf, int threads, char *err, size_t errlen);
/* bvh_build_blocks for a caller done with its boxes (*boxes, from malloc): they are freed,
 * and *boxes set to NULL, as soon as the builder has its own copy, before its working
 * arrays fill, so that the two copies are never both held through the build (4M spheres:
 * 96 MB less at the peak of the process); freed on failure too. */
int bvh_build_blocks_take(bvh *out, bvh_box **boxes, const unsigned char *blocks, int n,
                          int max_leaf, int threads, char *err, size_t errlen);
void bvh_free(bvh *b);

/* SAH cost of a built tree: the sum over nodes of area(node) / area(root) times C_trav = 1
 * for an interior node or count * C_isect (C_isect = 1) for a leaf. A root of zero or
 * non-finite area weights every node by 1. 0 for an empty tree. */
double bvh_sah_cost(const bvh *b);

/* The wide tree the kernels traverse: each node of a binary tree is merged with the nodes
 * below it into up to CW_BVH_WIDTH lanes, chosen for the least sum of the wide nodes'
 * areas (the wide tree's SAH cost; a dynamic programme over the binary tree). Depth-first,
 * the root first. stack_need: the most entries a traversal stack holds (each node leaves
 * all but one of its interior children on it while it goes down that one). */
typedef struct {
    cw_bvhw_node *nodes;
    int num_nodes;
    int stack_need;
} bvhw;

/* Collapses a built tree (b->num_nodes may be 0: an empty result). Returns 0, or -1 with
 * a message in err (out of memory). */
int bvh_collapse_wide(const bvh *b, bvhw *out, char *err, size_t errlen);
/* bvh_collapse_wide on `threads` threads (<= 0: one per online core; bvh_collapse_wide takes
 * CW_BVH_THREADS). The wide tree is the same, bit for bit, for every thread count. */
int bvh_collapse_wide_threads(const bvh *b, bvhw *out, int threads, char *err, size_t errlen);
void bvhw_free(bvhw *b);

#endif
