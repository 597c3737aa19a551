/* Reading mesh files (OBJ with MTL, PLY, glTF 2.0, STL and what else the Open Asset Import
 * Library reads) through assimp's C API into a scene_mesh of the scene model: triangulated,
 * the file's node transforms applied in double precision, vertex normals kept where the
 * file has them (smooth shading), degenerate triangles dropped and counted, the file's
 * materials appended to the scene's. */
#ifndef CW_MESH_IMPORT_H
#define CW_MESH_IMPORT_H

#include <stddef.h>

#include "scene.h"

/* What an import found, for warnings and for a scene made of the mesh alone. */
typedef struct {
    size_t triangles;  /* triangles kept */
    size_t degenerate; /* triangles dropped: no area (coincident or collinear vertices) */
    size_t non_faces;  /* points and lines dropped */
    int textured;      /* materials with textures (not part of the model: ignored) */
    int cameras;       /* cameras in the file */
    int lights;        /* lights in the file */
} mesh_import_info;

/* 1 when path names a mesh file by its extension (.obj .ply .gltf .glb .stl, any case). */
int mesh_is_mesh_file(const char *path);

/* Reads the mesh file path into a new mesh of s (its triangles in s->mesh_tris, its
 * materials appended to s->materials) and sets *mesh to its index. Returns 0, or -1 with
 * "path: message" in err (the file cannot be read, assimp's own error, no triangles,
 * non-finite vertices). */
int mesh_import(const char *path, scene *s, int *mesh, mesh_import_info *info, char *err,
                size_t errlen);

/* The same from memory; hint is the format's extension without the dot ("ply"). For the
 * fuzzer; name is used in messages. */
int mesh_import_memory(const void *data, size_t size, const char *hint, const char *name, scene *s,
                       int *mesh, mesh_import_info *info, char *err, size_t errlen);

#endif
