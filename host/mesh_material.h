/* The materials of a mesh file as Whitted materials: what each format's material says
 * (MTL, glTF 2.0's metallic-roughness model), mapped onto ka, kd, ks, p, km, kt and the
 * index of refraction as the table in docs/scene-formats.md ("Mesh files") documents. */
#ifndef CW_MESH_MATERIAL_H
#define CW_MESH_MATERIAL_H

#include "scene.h"

struct aiMaterial;

/* The file formats, as far as the material mapping cares: PLY and STL files carry no
 * materials (what assimp reports for them is its own invention), so they get the
 * default material. */
typedef enum {
    MESH_FORMAT_OTHER = 0, /* OBJ and the rest: mapped by the material's keys */
    MESH_FORMAT_OBJ,
    MESH_FORMAT_GLTF, /* .gltf and .glb (also for their cameras: mesh_import.c) */
    MESH_FORMAT_PLY,
    MESH_FORMAT_STL,
} mesh_format;

/* The format of a file name or of an extension without the dot ("ply"), any case. */
mesh_format mesh_format_of(const char *name_or_ext);

/* The material of a mesh without one: a grey diffuse surface (kd = ka = 0.8). */
void mesh_material_default(scene_material *sm);

/* Maps m (assimp's material of a file of format fmt) onto sm; counts textures in
 * *textured (not part of the model: the caller warns once). */
void mesh_material_map(const struct aiMaterial *m, mesh_format fmt, scene_material *sm,
                       int *textured);

#endif
