/* The kernel buffer list: every read-only scene buffer the kernels take, in kernel
 * argument order, written once. The kernels' parameters (CW_WORLD_ARGS), the cw_world
 * struct, its binding (CW_MAKE_WORLD) and the argument indices (cw_world_arg) are generated
 * from it here; the host generates its cl_mem fields, uploads, release and argument binding
 * from the same list (host/render.c), and host/devscene.c names the host array of each.
 * Adding a buffer: one line here, and its array in host/devscene.c. */
#ifndef CW_WORLD_H
#define CW_WORLD_H

#include "flags.h"
#include "types.h"

/* X(element type, name, what): one line per buffer; `what` names it in messages. */
#define CW_WORLD_BUFFERS(X)                                                                        \
    X(cw_bvhw_node, nodes, "BVH nodes") /* the wide BVH */                                         \
    X(int, refs, "BVH references")      /* BVH leaf entries: CW_REF(kind, index) */                \
    X(cw_sphere, spheres, "spheres")                                                               \
    X(int, sphere_materials, "sphere materials") /* sphere i's material */                         \
    X(cw_triangle, triangles, "triangles")                                                         \
    X(cw_tri8, tri_blocks, "triangle blocks") /* the leaves of triangles only, 8 by 8 */           \
    X(cw_sph4, sph_blocks, "sphere blocks")   /* the leaves of spheres only, 4 by 4 */             \
    X(cw_float4, normals, "vertex normals")   /* of smooth triangles */                            \
    X(cw_polygon, polygons, "polygons")                                                            \
    X(cw_float4, poly_verts, "polygon vertices")                                                   \
    X(int, poly_bands, "polygon edge bands") /* of large polygons (cw_polygon) */                  \
    X(cw_cone, cones, "cones")                                                                     \
    X(cw_instance, instances, "instances") /* placed meshes (two-level BVH) */

/* The scene as the kernels see it. */
typedef struct {
#define CW_WORLD_FIELD(type, name, what) CW_GLOBAL const type *name;
    CW_WORLD_BUFFERS(CW_WORLD_FIELD)
#undef CW_WORLD_FIELD
    int num_nodes; /* from the frame: 0 for an empty scene */
#if CW_STATS
    int *walk; /* the work-item's walk counts (CW_WALK_COUNTS from CW_COUNT_CLOSEST_NODES) */
#endif
} cw_world;

/* Kernel argument indices: the frame first, then each buffer; kernels that take the world
 * have their own arguments from CW_WORLD_NARGS on. */
#define CW_WORLD_INDEX(type, name, what) CW_WORLD_ARG_##name,
enum cw_world_arg { CW_WORLD_ARG_frame, CW_WORLD_BUFFERS(CW_WORLD_INDEX) CW_WORLD_NARGS };
#undef CW_WORLD_INDEX

/* The parameters of an entry kernel that takes the world: the frame f, then the buffers. */
#define CW_WORLD_PARAM(type, name, what) , CW_GLOBAL const type *name
#define CW_WORLD_ARGS CW_GLOBAL const cw_frame *f CW_WORLD_BUFFERS(CW_WORLD_PARAM)

/* Binds the parameters of CW_WORLD_ARGS into the cw_world w; with CW_STATS, its walk
 * counts are the int array walk[CW_WALK_COUNTS] (zeroed here). */
#define CW_WORLD_BIND(type, name, what) (w).name = name;
#define CW_WALK_COUNTS 4
#if CW_STATS
#define CW_WORLD_WALK(w, walk)                                                                     \
    do {                                                                                           \
        for (int walk_k = 0; walk_k < CW_WALK_COUNTS; walk_k++)                                    \
            (walk)[walk_k] = 0;                                                                    \
        (w).walk = (walk);                                                                         \
    } while (0)
#else
#define CW_WORLD_WALK(w, walk) ((void)(walk))
#endif
#define CW_MAKE_WORLD(w, walk)                                                                     \
    do {                                                                                           \
        CW_WORLD_BUFFERS(CW_WORLD_BIND)                                                            \
        (w).num_nodes = f->num_nodes;                                                              \
        CW_WORLD_WALK(w, walk);                                                                    \
    } while (0)

#endif
