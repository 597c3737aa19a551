/* Reading mesh files (OBJ with MTL, PLY, glTF 2.0, STL and what else the Open Asset Import
 * Library reads) through assimp's C API into a scene_mesh of the scene model: triangulated,
 * the file's node transforms applied in double precision, vertex normals kept where the
 * file has them (smooth shading), degenerate triangles dropped and counted, the file's
 * materials mapped (mesh_material.h) and appended to the scene's; optionally the file's
 * own camera and lights, placed by their nodes. One import at a time: assimp's logger,
 * which catches its warnings here, and the crash guard around it (sys_guard_begin) are
 * process-wide. */
#ifndef CW_MESH_IMPORT_H
#define CW_MESH_IMPORT_H

#include <stddef.h>

#include "scene.h"

/* What an import found, for warnings and for a scene made of the mesh alone. */
typedef struct {
    size_t triangles;           /* triangles kept */
    size_t degenerate;          /* triangles dropped: no area (coincident or collinear vertices) */
    size_t non_faces;           /* points and lines dropped */
    int textured;               /* materials with textures (not part of the model: ignored) */
    int colored;                /* meshes with vertex colours (not part of the model: ignored) */
    int cameras;                /* cameras in the file */
    int lights;                 /* lights in the file */
    int missing_mtl;            /* OBJ: material libraries (mtllib) that cannot be opened */
    char missing_mtl_name[256]; /* the first of them, printable */
} mesh_import_info;

/* A light of the file, in world coordinates. */
typedef struct {
    vec3d position; /* a point or spot light's position */
    vec3f dir;      /* a directional light's direction (unit, the way the light travels) */
    int directional;
    vec3f color; /* colour times intensity, as the file gives it */
} mesh_light;

/* The file's own view, in world coordinates (its first camera, placed by its node). */
typedef struct {
    int has_camera;
    vec3d eye;
    vec3f dir, up;      /* unit view direction, and the up vector (not yet orthogonal) */
    double yfov_deg;    /* perspective: the vertical field of view; 0: orthographic */
    double ortho_half;  /* orthographic: half the window's width */
    double aspect;      /* width / height, or 0 when the file does not say */
    mesh_light *lights; /* light_count lights (malloc'd; free with mesh_view_free) */
    size_t light_count;
} mesh_view;

void mesh_view_free(mesh_view *v);

/* 1 when path names a mesh file by its extension (.obj .ply .gltf .glb .stl, any case). */
int mesh_is_mesh_file(const char *path);

/* Reads the mesh file path into a new mesh of s (its triangles in s->mesh_tris, its
 * materials appended to s->materials) and sets *mesh to its index. Returns 0, or -1 with
 * "path: message" in err (not a readable file, assimp's own error, no triangles,
 * non-finite vertices). */
int mesh_import(const char *path, scene *s, int *mesh, mesh_import_info *info, char *err,
                size_t errlen);

/* The same, and with view non-NULL also the file's first camera and its lights (free
 * them with mesh_view_free, also after a failure). */
int mesh_import_view(const char *path, scene *s, int *mesh, mesh_import_info *info, mesh_view *view,
                     char *err, size_t errlen);

/* mesh_import_view from memory; hint is the format's extension without the dot ("ply").
 * For the fuzzer; name is used in messages. */
int mesh_import_memory(const void *data, size_t size, const char *hint, const char *name, scene *s,
                       int *mesh, mesh_import_info *info, mesh_view *view, char *err,
                       size_t errlen);

#endif
