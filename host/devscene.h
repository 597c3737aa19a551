/* The scene as the kernels see it (see devscene.c). */
#ifndef CW_DEVSCENE_H
#define CW_DEVSCENE_H

#include <stddef.h>

#include "bvh.h"
#include "scene.h"
#include "types.h"
#include "world.h"

/* The device arrays of a scene, and the BVH over all its primitives. Degenerate
 * primitives (no surface) are left out, the others keep their order within their kind:
 * a hit's index is an index into these arrays. */
typedef struct {
    cw_sphere *sph;
    cw_triangle *tri;
    cw_tri4 *tri_blocks; /* the leaves of triangles only, four to a block */
    cw_float4 *normals;
    cw_polygon *pg;
    cw_float4 *verts;
    cw_cone *cones;
    cw_light *lights;
    cw_material *mats;
    bvh_box *boxes; /* until the BVH is built */
    int *box_ref;   /* box i bounds primitive box_ref[i] (a CW_REF); until the BVH is built */
    int *refs;      /* BVH leaf entries as CW_REFs */
    int *bands;     /* edge bands of large polygons (cw_polygon) */
    size_t nbands, bands_cap;
    int nsph, ntri, nnorm, npg, nverts, ncone, nbox, nblocks;
    bvh tree; /* the binary tree: after devscene_build_bvh only its counts and depth */
    bvhw tree_wide;
    int dropped;      /* primitives left out as degenerate */
    int mirrors;      /* some material has km > 0 */
    int transmitters; /* some material has kt > 0 */
    vec3d origin;     /* the local origin: every position in the arrays is relative to it */
} devscene;

/* The host array behind each kernel buffer (kernels/world.h): for X(type, name, what), the
 * elements `name` and their number `n_name`. */
#define DEVSCENE_ARRAY(type, name, what)                                                           \
    const type *name;                                                                              \
    size_t n_##name;
typedef struct {
    CW_WORLD_BUFFERS(DEVSCENE_ARRAY)
} devscene_world;
#undef DEVSCENE_ARRAY

/* Fills w with the arrays of ds, one per kernel buffer (after devscene_build_bvh). */
void devscene_world_arrays(const devscene *ds, devscene_world *w);

/* Frees the host array behind kernel buffer `which` (a cw_world_arg) once it is uploaded,
 * so that the host copy and the device copy of a scene are never all held at once; the
 * counts stay. */
void devscene_free_array(devscene *ds, int which);

cw_float4 devscene_f4(vec3f v, float w);

/* Builds the arrays and the primitives' boxes (no BVH yet). Every position is converted to
 * float relative to the local origin `origin` (NULL: the world's), the difference taken
 * in double: with the camera's eye as the origin, what a ray meets near the viewer keeps
 * full float precision however far the scene is from 0 (docs/model.md). Returns 0, or -1
 * with err (too many primitives, out of memory); call devscene_free either way. */
int devscene_convert(const scene *s, const vec3d *origin, devscene *ds, char *err, size_t errlen);

/* Builds the BVH over the boxes, collapses it to the wide tree the kernels traverse, turns
 * its leaf entries into CW_REFs and packs its leaves of triangles only into blocks of four
 * (cw_tri4); then frees what only the build needed (the boxes,
 * the box map, the binary tree's arrays). Returns 0, or -1 with err. */
int devscene_build_bvh(devscene *ds, char *err, size_t errlen);

void devscene_free(devscene *ds);

#endif
