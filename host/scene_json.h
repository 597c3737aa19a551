/* The reader of clwhitted's own scene format, JSON (the schema is described in
 * scene_json.c). */
#ifndef CW_SCENE_JSON_H
#define CW_SCENE_JSON_H

#include <stddef.h>

#include "scene.h"

/* json_scene_load reads a file; json_scene_parse reads text in memory, naming it `name` in
 * errors. Both return 0, or -1 with "name:line: message" in err. */
int json_scene_load(const char *path, scene *s, char *err, size_t errlen);
int json_scene_parse(const char *text, size_t len, const char *name, scene *s, char *err,
                     size_t errlen);

/* Reads a mesh file into a new mesh of s (scene.meshes, scene.mesh_tris; its materials
 * appended) and sets *mesh to its index; returns 0, or -1 with "path: message" in err. The
 * JSON reader calls it for "mesh" objects, once per file however often it is placed. */
typedef int (*json_mesh_reader)(const char *path, scene *s, int *mesh, char *err, size_t errlen);

/* Sets the mesh reader for every JSON scene read after it, process-wide (scene_load.c sets
 * assimp's importer). Without one (NULL, the default), a "mesh" object is an error naming
 * its line: the JSON reader itself reads no mesh format. */
void json_set_mesh_reader(json_mesh_reader fn);

/* Reads a camera file (clwhitted --camera; the preview's C key writes one): a JSON object
 * with "camera" as in a scene, and optionally "image" and "max_depth", and puts them into
 * s (before scene_finish), leaving the rest of s alone. Returns 0, or -1 with
 * "path:line: message" in err. */
int json_camera_load(const char *path, scene *s, char *err, size_t errlen);

#endif
