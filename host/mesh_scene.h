/* A scene made of one mesh file given on the command line (clwhitted model.glb): the mesh
 * placed once, the file's own camera and lights when it has them, else a camera that frames
 * the mesh's bounds and two default lights (docs/scene-formats.md, "Mesh files"). */
#ifndef CW_MESH_SCENE_H
#define CW_MESH_SCENE_H

#include <stddef.h>

#include "mesh_import.h"
#include "scene.h"

/* The warnings of an import on stderr, once per file: a missing MTL, degenerate
 * triangles, points and lines left out, textures and vertex colours ignored. */
void mesh_scene_warn(const char *path, const mesh_import_info *info);

/* Loads path as a scene; warnings (degenerate triangles, textures, a missing MTL) on
 * stderr. Returns 0, or -1 with "path: message" in err. */
int mesh_scene_load(const char *path, scene *s, char *err, size_t errlen);

/* The same from memory, without warnings; hint is the format's extension without the dot
 * ("glb"), name is used in messages. For the fuzzer. */
int mesh_scene_memory(const void *data, size_t size, const char *hint, const char *name, scene *s,
                      char *err, size_t errlen);

#endif
