/* Reading mesh files through assimp's C API. See mesh_import.h. */
#include "mesh_import.h"

#include <assimp/cimport.h>
#include <assimp/material.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "assimp_dl.h"
#include "scene_geom.h"
#include "sys.h"
#include "xform.h"

/* Triangulated, points and lines sorted out, the data structure validated (indices in
 * range), invalid data (zero normals, NaN) removed. Normals are not generated: a file
 * without them is shaded flat. */
#define MESH_AI_FLAGS                                                                              \
    (aiProcess_Triangulate | aiProcess_SortByPType | aiProcess_ValidateDataStructure |             \
     aiProcess_FindInvalidData)

int mesh_is_mesh_file(const char *path)
{
    static const char *const ext[] = {".obj", ".ply", ".gltf", ".glb", ".stl"};
    for (size_t i = 0; i < sizeof ext / sizeof ext[0]; i++)
        if (sys_has_ext(path, ext[i]))
            return 1;
    return 0;
}

static vec3f color_of(const struct aiMaterial *m, const char *key, vec3f dflt, int *found)
{
    struct aiColor4D c;
    if (aiGetMaterialColor(m, key, 0, 0, &c) == AI_SUCCESS && isfinite(c.r) && isfinite(c.g) &&
        isfinite(c.b)) {
        if (found)
            *found = 1;
        return vec3f_make(c.r, c.g, c.b);
    }
    return dflt;
}

static float float_of(const struct aiMaterial *m, const char *key, float dflt)
{
    ai_real v;
    if (aiGetMaterialFloatArray(m, key, 0, 0, &v, NULL) == AI_SUCCESS && isfinite(v))
        return (float)v;
    return dflt;
}

/* An assimp material as a Whitted material (docs/scene-formats.md, "Meshes"). */
static scene_material material_of(const struct aiMaterial *m, int *textured)
{
    scene_material sm;
    int has_kd = 0;
    memset(&sm, 0, sizeof sm);
    sm.kd = color_of(m, "$clr.diffuse", vec3f_make(0.8f, 0.8f, 0.8f), &has_kd);
    sm.ka = color_of(m, "$clr.ambient", sm.kd, NULL);
    sm.ks = color_of(m, "$clr.specular", vec3f_make(0, 0, 0), NULL);
    sm.p = float_of(m, "$mat.shininess", 1.0f);
    if (sm.p < 0.0f)
        sm.p = 0.0f;
    sm.ior = 1.0f;
    if (aiGetMaterialTextureCount(m, aiTextureType_DIFFUSE) > 0 ||
        aiGetMaterialTextureCount(m, aiTextureType_BASE_COLOR) > 0)
        (*textured)++;
    return sm;
}

/* row-major aiMatrix4x4 (a1..a4 the first row) as a scene_xform */
static int xform_of(const struct aiMatrix4x4 *a, scene_xform *x)
{
    double m[16] = {a->a1, a->a2, a->a3, a->a4, a->b1, a->b2, a->b3, a->b4,
                    a->c1, a->c2, a->c3, a->c4, a->d1, a->d2, a->d3, a->d4};
    return xform_from_matrix(x, m);
}

typedef struct {
    scene *s;
    const struct aiScene *ai;
    int mat_base; /* the scene's index of the file's material 0 */
    mesh_import_info *info;
    const char *name;
    char *err;
    size_t errlen;
} importer;

static int add_mesh(importer *im, const struct aiMesh *am, const scene_xform *x)
{
    unsigned f;
    int mirror = xform_det(x) < 0.0;
    int mat =
        im->mat_base + (am->mMaterialIndex < im->ai->mNumMaterials ? (int)am->mMaterialIndex : 0);
    if (!(am->mPrimitiveTypes & aiPrimitiveType_TRIANGLE)) {
        im->info->non_faces += am->mNumFaces;
        return 0;
    }
    for (f = 0; f < am->mNumFaces; f++) {
        const struct aiFace *face = &am->mFaces[f];
        vec3d p[3];
        vec3f n[3], pf[3];
        int k, smooth = am->mNormals != NULL;
        if (face->mNumIndices != 3) {
            im->info->non_faces++;
            continue;
        }
        for (k = 0; k < 3; k++) {
            unsigned vi = face->mIndices[mirror ? 2 - k : k];
            struct aiVector3D v;
            if (vi >= am->mNumVertices) {
                snprintf(im->err, im->errlen,
                         "%s: mesh '%s', face %u: vertex index %u out of range (%u vertices)",
                         im->name, am->mName.data, f, vi, am->mNumVertices);
                return -1;
            }
            v = am->mVertices[vi];
            if (!isfinite(v.x) || !isfinite(v.y) || !isfinite(v.z)) {
                snprintf(im->err, im->errlen, "%s: mesh '%s', vertex %u is not finite", im->name,
                         am->mName.data, vi);
                return -1;
            }
            p[k] = xform_point(x, vec3d_make(v.x, v.y, v.z));
            pf[k] = vec3f_make((float)p[k].x, (float)p[k].y, (float)p[k].z);
            if (smooth) {
                struct aiVector3D nv = am->mNormals[vi];
                if (xform_normal(x, vec3f_make(nv.x, nv.y, nv.z), &n[k]) != 0)
                    smooth = 0; /* a zero or invalid normal: this triangle is flat */
            }
        }
        if (scene_triangle_degenerate(pf)) {
            im->info->degenerate++;
            continue;
        }
        if (scene_push_mesh_triangle(im->s, p, smooth ? n : NULL, mat) < 0) {
            snprintf(im->err, im->errlen, "%s: out of memory", im->name);
            return -1;
        }
        im->info->triangles++;
    }
    return 0;
}

/* Depth-first over the node tree with an explicit stack (a file may nest deeply). */
static int add_nodes(importer *im)
{
    typedef struct {
        const struct aiNode *node;
        scene_xform x;
    } item;
    size_t n = 0, cap = 64;
    item *stack = malloc(cap * sizeof *stack);
    int rc = 0;
    if (!stack) {
        snprintf(im->err, im->errlen, "%s: out of memory", im->name);
        return -1;
    }
    stack[n].node = im->ai->mRootNode;
    xform_identity(&stack[n].x);
    n++;
    while (n > 0 && rc == 0) {
        item it = stack[--n];
        scene_xform local, x;
        unsigned i;
        if (xform_of(&it.node->mTransformation, &local) != 0) {
            snprintf(im->err, im->errlen, "%s: node '%s' has a projective transform", im->name,
                     it.node->mName.data);
            rc = -1;
            break;
        }
        xform_compose(&x, &it.x, &local);
        for (i = 0; i < it.node->mNumMeshes && rc == 0; i++) {
            unsigned mi = it.node->mMeshes[i];
            if (mi >= im->ai->mNumMeshes) {
                snprintf(im->err, im->errlen, "%s: node '%s' refers to mesh %u of %u", im->name,
                         it.node->mName.data, mi, im->ai->mNumMeshes);
                rc = -1;
            } else {
                rc = add_mesh(im, im->ai->mMeshes[mi], &x);
            }
        }
        for (i = 0; i < it.node->mNumChildren && rc == 0; i++) {
            if (n == cap) {
                item *grown = cap > ((size_t)-1) / 2 / sizeof *stack
                                  ? NULL
                                  : realloc(stack, 2 * cap * sizeof *stack);
                if (!grown) {
                    snprintf(im->err, im->errlen, "%s: out of memory", im->name);
                    rc = -1;
                    break;
                }
                stack = grown;
                cap *= 2;
            }
            stack[n].node = it.node->mChildren[i];
            stack[n].x = x;
            n++;
        }
    }
    free(stack);
    return rc;
}

static int import_scene(const struct aiScene *ai, const char *name, scene *s, int *mesh,
                        mesh_import_info *info, char *err, size_t errlen)
{
    importer im;
    scene_mesh m;
    unsigned i;
    size_t mat_count = s->materials.count;
    memset(info, 0, sizeof *info);
    if (!ai) {
        const char *why = aiGetErrorString();
        snprintf(err, errlen, "%s: cannot read the mesh (%s)", name,
                 why && *why ? why : "unknown error");
        return -1;
    }
    if (!ai->mRootNode) {
        snprintf(err, errlen, "%s: the file has no scene graph (no root node)", name);
        return -1;
    }
    im.s = s;
    im.ai = ai;
    im.mat_base = (int)mat_count;
    im.info = info;
    im.name = name;
    im.err = err;
    im.errlen = errlen;
    info->cameras = (int)ai->mNumCameras;
    info->lights = (int)ai->mNumLights;
    for (i = 0; i < ai->mNumMaterials || i == 0; i++) {
        scene_material sm;
        if (i < ai->mNumMaterials) {
            sm = material_of(ai->mMaterials[i], &info->textured);
        } else { /* a file without materials: one grey default */
            memset(&sm, 0, sizeof sm);
            sm.kd = sm.ka = vec3f_make(0.8f, 0.8f, 0.8f);
            sm.p = 1.0f;
            sm.ior = 1.0f;
        }
        if (scene_push(&s->materials, &sm, sizeof sm) < 0)
            goto out_of_memory;
    }
    m.first = s->mesh_tris.count;
    m.count = 0;
    m.source = strdup(name);
    if (!m.source)
        goto out_of_memory;
    if (add_nodes(&im) != 0) {
        free(m.source);
        return -1;
    }
    m.count = s->mesh_tris.count - m.first;
    if (m.count == 0) {
        snprintf(err, errlen, "%s: no triangles (%zu degenerate, %zu points or lines)", name,
                 info->degenerate, info->non_faces);
        free(m.source);
        return -1;
    }
    {
        long idx = scene_push(&s->meshes, &m, sizeof m);
        if (idx < 0) {
            free(m.source);
            goto out_of_memory;
        }
        *mesh = (int)idx;
    }
    return 0;
out_of_memory:
    snprintf(err, errlen, "%s: out of memory", name);
    return -1;
}

int mesh_import(const char *path, scene *s, int *mesh, mesh_import_info *info, char *err,
                size_t errlen)
{
    const struct aiScene *ai;
    int rc;
    if (assimp_load(err, errlen) != 0)
        return -1;
    ai = aiImportFile(path, MESH_AI_FLAGS);
    rc = import_scene(ai, path, s, mesh, info, err, errlen);
    if (ai)
        aiReleaseImport(ai);
    return rc;
}

int mesh_import_memory(const void *data, size_t size, const char *hint, const char *name, scene *s,
                       int *mesh, mesh_import_info *info, char *err, size_t errlen)
{
    const struct aiScene *ai;
    if (size > 0xffffffffu) {
        snprintf(err, errlen, "%s: too large", name);
        return -1;
    }
    if (assimp_load(err, errlen) != 0)
        return -1;
    ai = aiImportFileFromMemory(data, (unsigned)size, MESH_AI_FLAGS, hint);
    {
        int rc = import_scene(ai, name, s, mesh, info, err, errlen);
        if (ai)
            aiReleaseImport(ai);
        return rc;
    }
}
