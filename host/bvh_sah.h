/* The binned SAH build of one tree or subtree, for bvh.c (internal: see bvh_sah.c). The
 * types a build shares between its threads. */
#ifndef CW_BVH_SAH_H
#define CW_BVH_SAH_H

#include <pthread.h>

#include "bvh.h"

#define C_TRAV 1.0  /* SAH cost of visiting an interior node */
#define C_ISECT 1.0 /* SAH cost of testing one primitive, or SAH_BLOCK of a block class */
/* Primitives of a block class (1 .. BVH_BLOCK_CLASSES) are tested SAH_BLOCK at a time where
 * a leaf holds only primitives of that class (the kernels' cw_tri8, or two cw_sph4, in one
 * test): such a leaf of n costs C_ISECT * ceil(n / SAH_BLOCK). */
#define SAH_BLOCK BVH_BLOCK_TEST

/* One primitive in the working array: its box and input index (32 bytes). */
typedef struct {
    float lo[3];
    int idx; /* index into the input boxes */
    float hi[3];
    int block; /* block class: 0 none, 1 .. BVH_BLOCK_CLASSES (see SAH_BLOCK) */
} sah_prim;

/* A node to make: its range of the working array and what is known of it. */
typedef struct {
    int begin, end;
    int depth;            /* root = 1 */
    int parent;           /* node whose second child this is, or -1 (first child or root) */
    float lo[3], hi[3];   /* bounds of the boxes */
    float clo[3], chi[3]; /* bounds of the doubled centroids */
} sah_task;

/* A subtree built on its own: its task, where its nodes go (provisionally) and what it
 * became. */
typedef struct {
    sah_task t;
    int pos;       /* its root's slot in the provisional layout; 2 * count - 1 slots are kept */
    int num_nodes; /* nodes built */
    int depth;     /* deepest node */
    int final;     /* its root's index once the gaps are closed */
} sah_subtree;

/* What a build shares between its threads. */
typedef struct {
    sah_prim *w;
    cw_bvh_node *nodes;
    int max_leaf, threads;
    int cutoff; /* the top of the tree: tasks of at most this many primitives are subtrees */
    sah_subtree *subs;
    int nsubs, subs_cap;
    int *order; /* subtrees by size, largest first */
    int next;   /* next of order to build */
    pthread_mutex_t lock;
} sah_builder;

/* Sets t's range of w and computes its bounds. */
void sah_task_range(sah_task *t, const sah_prim *w, int begin, int end);

/* Builds the nodes of the subtree of task *root into nodes[0, ...) (node indices relative to
 * nodes; leaf starts index the working array bd->w). In the top phase (top = 1), the large
 * nodes are binned on bd->threads threads and every task of at most bd->cutoff primitives
 * becomes a subtree in bd->subs for later, keeping 2 * count - 1 slots. Returns the slots
 * used, or -1 when out of memory; raises *depth to the deepest node made. */
int sah_build_nodes(sah_builder *bd, cw_bvh_node *nodes, const sah_task *root, int top, int *depth);

#endif
