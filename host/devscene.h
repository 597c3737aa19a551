/* The scene as the kernels see it (see devscene.c). */
#ifndef CW_DEVSCENE_H
#define CW_DEVSCENE_H

#include <stddef.h>

#include "bvh.h"
#include "scene.h"
#include "types.h"
#include "world.h"

/* A mesh placed by instances, on its way to the kernels (devscene_inst.c): its triangles
 * (in mesh coordinates less center) are tri[first .. first + count), their boxes
 * mesh_boxes[box_first ..], and its tree starts at node root of the combined node array. */
typedef struct {
    int first, count, box_first;
    vec3d center; /* the middle of its bounding box: its triangles are stored relative to it */
    float lo[3], hi[3]; /* bounds of the stored (relative) vertices */
    int root;           /* -1 until its tree is built; also -1 for a mesh with no triangle left */
} devscene_mesh;

/* The device arrays of a scene, and the BVH over all its primitives. Degenerate
 * primitives (no surface) are left out, the others keep their order within their kind:
 * a hit's index is an index into these arrays. A mesh placed two or more times (scene_mesh.h)
 * keeps one copy of its triangles, after the world's, and its own tree, after the top
 * level's nodes; each placement is a cw_instance whose box is in the top level. */
typedef struct {
    cw_sphere *sph;
    int *sph_mat; /* sphere i's material (kernels/types.h, cw_sphere) */
    cw_triangle *tri;
    cw_tri8 *tri_blocks; /* the leaves of triangles only, eight to a block */
    cw_sph4 *sph_blocks; /* the leaves of spheres only, four to a block */
    cw_float4 *normals;
    cw_polygon *pg;
    cw_float4 *verts;
    cw_cone *cones;
    cw_light *lights;
    cw_material *mats;
    bvh_box *boxes; /* until the BVH is built */
    int *box_ref;   /* box i bounds primitive box_ref[i] (a CW_REF); until the BVH is built */
    int *refs;      /* BVH leaf entries as CW_REFs: the top level's, then each mesh's */
    int nrefs;
    cw_instance *inst;
    int ninst;
    devscene_mesh *meshes; /* indexed like scene.meshes; only those placed are filled */
    int nmesh;
    bvh_box *mesh_boxes; /* the mesh triangles' boxes; until the BVH is built */
    int *mesh_box_ref;   /* their CW_REFs */
    int nmesh_box;
    int *bands; /* edge bands of large polygons (cw_polygon) */
    size_t nbands, bands_cap;
    int nsph, ntri, nnorm, npg, nverts, ncone, nbox, nblocks, nsph_blocks;
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

/* Hands over the host array behind kernel buffer `which` (a cw_world_arg): ds forgets it
 * without freeing it and returns it; the new owner frees it with sys_device_free (every
 * such array comes from sys_device_calloc). The counts stay. */
void *devscene_take_array(devscene *ds, int which);

cw_float4 devscene_f4(vec3f v, float w);

/* Builds the arrays and the primitives' boxes (no BVH yet). Every position is converted to
 * float relative to the local origin `origin` (NULL: the world's), the difference taken
 * in double: with the camera's eye as the origin, what a ray meets near the viewer keeps
 * full float precision however far the scene is from 0 (docs/model.md). Returns 0, or -1
 * with err (too many primitives, out of memory); call devscene_free either way. */
int devscene_convert(const scene *s, const vec3d *origin, devscene *ds, char *err, size_t errlen);

/* Builds the BVH over the boxes, collapses it to the wide tree the kernels traverse, turns
 * its leaf entries into CW_REFs and packs its leaves of triangles only or spheres only into
 * blocks (cw_tri8, cw_sph4); then frees what only the build needed (the boxes,
 * the box map, the binary tree's arrays). Returns 0, or -1 with err. */
int devscene_build_bvh(devscene *ds, char *err, size_t errlen);

void devscene_free(devscene *ds);

/* For devscene_inst.c: adds a primitive's box (widened against rounding) for the top level. */
void devscene_push_box(devscene *ds, const bvh_box *b, int ref);

/* devscene_inst.c: the meshes placed by instances (their triangles after the world's, and
 * their boxes) and the instances (cw_instance and their boxes in the top level); called by
 * devscene_convert once the world's triangles are in. Returns 0, or -1 with err. */
int devinst_convert(const scene *s, devscene *ds, char *err, size_t errlen);
/* The number of mesh triangles devinst_convert may add (those of placed meshes). */
size_t devinst_triangles(const scene *s);
/* Builds each placed mesh's tree and appends it to the top level's (nodes and refs),
 * setting the instances' roots. Called by devscene_build_bvh. Returns 0, or -1 with err. */
int devinst_build(devscene *ds, char *err, size_t errlen);

#endif
