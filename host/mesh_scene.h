/* A scene made of one mesh file given on the command line (clwhitted model.glb): the mesh
 * placed once, the file's own camera and lights when it has them, else a camera that frames
 * the mesh's bounds and two default lights (docs/scene-formats.md, "Mesh files"). */
#ifndef CW_MESH_SCENE_H
#define CW_MESH_SCENE_H

#include <stddef.h>

#include "mesh_import.h"
#include "scene.h"

/* The warnings of an import (degenerate triangles left out, textures ignored) on stderr,
 * once per file. */
void mesh_scene_warn(const char *path, const mesh_import_info *info);

/* Loads path as a scene. Returns 0, or -1 with "path: message" in err. */
int mesh_scene_load(const char *path, scene *s, char *err, size_t errlen);

#endif
