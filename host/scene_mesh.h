/* Meshes and their placements on the scene model: placing a mesh, the world bounds of an
 * instance, and flattening an instance into world triangles (a copy of each of its
 * triangles, transformed in double precision). A mesh placed once is flattened by
 * scene_finish: only meshes placed two or more times reach the renderer as instances
 * (a two-level BVH, docs/architecture.md). */
#ifndef CW_SCENE_MESH_H
#define CW_SCENE_MESH_H

#include "scene.h"

/* Appends an instance of mesh with transform to_world (NULL: identity) and material
 * (-1: the mesh's own). Returns its index, or -1 when out of memory. */
long scene_place_mesh(scene *s, int mesh, const scene_xform *to_world, int material);

/* The world-space bounding box of instance i (its mesh's vertices, transformed).
 * Returns 0, or -1 for an empty mesh. */
int scene_instance_bounds(const scene *s, size_t i, double lo[3], double hi[3]);

/* Flattens instances into s->triangles and removes them from s->instances: every one
 * (all = 1), or those whose mesh no other instance places (all = 0). A mirroring
 * transform reverses the vertex order, so the counter-clockwise front stays the front.
 * Returns 0, or -1 with the reason in err (out of memory, a singular transform). */
int scene_flatten_instances(scene *s, int all, char *err, size_t errlen);

#endif
