/* Inside the JSON reader (scene_json.c): the "objects" array, one object after another
 * (spheres, triangles, polygons, cones, cylinders and placed meshes), each checked and
 * added to the scene. The sections (scene_json.c) read the materials first; the objects name them.
 */
#ifndef CW_SCENE_JSON_OBJECTS_H
#define CW_SCENE_JSON_OBJECTS_H

#include <cJSON.h>
#include <stddef.h>

#include "scene.h"
#include "scene_json.h"
#include "scene_json_value.h"

/* A material's name in "materials" and its index in scene.materials. */
typedef struct {
    const char *name;
    int index;
} jo_material;

/* The mesh files the objects have read: a file placed again is not read again. */
typedef struct {
    unsigned long long *id; /* the file's device and inode, two per file: the same file
                             * however it is named */
    int *mesh;              /* its index in scene.meshes */
    size_t count;
} jo_mesh_files;

typedef struct {
    const jv_doc *doc;
    scene *s;
    const jo_material *mats; /* sorted by name (jo_material_cmp) */
    size_t nmats;
    jo_mesh_files *files;
    json_mesh_reader read_mesh; /* NULL: "mesh" objects are refused */
} jo_reader;

void jo_mesh_files_free(jo_mesh_files *f);

/* The order of jo_reader.mats (qsort and bsearch). */
int jo_material_cmp(const void *a, const void *b);

/* The index of the material that obj's "material" key names (required); or -1 having
 * failed with the line of the key (or of obj when it is missing). path names obj. */
int jo_find_material(const jo_reader *r, const cJSON *obj, const char *path);

/* Reads objects[i] (the node o) into the scene. Returns 0, or -1 having failed. */
int jo_read_object(const jo_reader *r, const cJSON *o, int i);

#endif
