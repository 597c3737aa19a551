/* Reading mesh files through assimp's C API. See mesh_import.h. */
#include "mesh_import.h"

#include <assimp/cimport.h>
#include <assimp/light.h>
#include <assimp/camera.h>
#include <assimp/material.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "assimp_dl.h"
#include "mesh_file.h"
#include "mesh_material.h"
#include "scene_geom.h"
#include "scene_io.h"
#include "sys.h"
#include "xform.h"

/* Read with the data structure validated (indices in range), then checked here
 * (check_meshes), then triangulated and points and lines sorted out. The checks come
 * first because assimp 5.2 (Debian 12) cannot fail safely there: its triangulation aborts
 * on a face without vertices, and a post-processing step that fails (FindInvalidData on
 * NaN vertices) crashes in aiApplyPostProcessing's own clean-up; so non-finite vertices
 * are refused here and invalid normals are handled per triangle (add_mesh). Normals are
 * not generated: a file without them is shaded flat. */
#define MESH_AI_READ aiProcess_ValidateDataStructure
#define MESH_AI_POST (aiProcess_Triangulate | aiProcess_SortByPType)

/* assimp's warnings that make a file bad here: it dropped faces whose indices were out of
 * range (the glTF reader), which would render a mesh with holes without a word. Caught
 * through a log stream attached for the import (assimp's logger is global: one import
 * at a time). */
typedef struct {
    char bad[256]; /* the first such warning, printable */
} mesh_log;

static void log_line(const char *msg, char *user)
{
    mesh_log *l = (mesh_log *)(void *)user;
    const char *p;
    char line[256];
    size_t n;
    if (l->bad[0] || (strncmp(msg, "Warn", 4) != 0 && strncmp(msg, "Error", 5) != 0))
        return;
    if (!strstr(msg, "out-of-range") && !strstr(msg, "out of range"))
        return;
    p = strstr(msg, ": ");
    p = p ? p + 2 : msg;
    n = strlen(p);
    while (n > 0 && (p[n - 1] == '\n' || p[n - 1] == '\r'))
        n--;
    snprintf(line, sizeof line, "%.*s", (int)(n < sizeof line ? n : sizeof line - 1), p);
    scene_printable(line, sizeof line, l->bad, sizeof l->bad);
}

/* assimp's import of the file at path, or of size bytes at data (path NULL; hint: the
 * format's extension), with its log caught in *log. */
static const struct aiScene *read_logged(const char *path, const void *data, size_t size,
                                         const char *hint, mesh_log *log)
{
    struct aiLogStream stream;
    const struct aiScene *ai;
    log->bad[0] = '\0';
    stream.callback = log_line;
    stream.user = (char *)(void *)log;
    aiAttachLogStream(&stream);
    ai = path ? aiImportFile(path, MESH_AI_READ)
              : aiImportFileFromMemory(data, (unsigned)size, MESH_AI_READ, hint);
    aiDetachLogStream(&stream);
    return ai;
}

/* The file's lights beyond this many are left out. */
#define MESH_MAX_LIGHTS 64

int mesh_is_mesh_file(const char *path)
{
    static const char *const ext[] = {".obj", ".ply", ".gltf", ".glb", ".stl"};
    for (size_t i = 0; i < sizeof ext / sizeof ext[0]; i++)
        if (sys_has_ext(path, ext[i]))
            return 1;
    return 0;
}

void mesh_view_free(mesh_view *v)
{
    if (!v)
        return;
    free(v->lights);
    v->lights = NULL;
    v->light_count = 0;
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
    mesh_format fmt;
    int mat_base; /* the scene's index of the file's material 0 */
    mesh_import_info *info;
    mesh_view *view; /* NULL: no camera or lights wanted */
    const char *name;
    char *err;
    size_t errlen;
} importer;

/* "mesh N" or "mesh N ('NAME')" for messages, the name from the file made printable */
static const char *mesh_label(const struct aiMesh *am, unsigned index, char *buf, size_t len)
{
    char shown[SCENE_SHOWN_LEN];
    if (am->mName.length > 0 && am->mName.data[0])
        snprintf(buf, len, "mesh %u ('%s')", index, scene_shown(am->mName.data, shown));
    else
        snprintf(buf, len, "mesh %u", index);
    return buf;
}

static int add_mesh(importer *im, unsigned index, const scene_xform *x)
{
    const struct aiMesh *am = im->ai->mMeshes[index];
    unsigned f;
    int mirror = xform_det(x) < 0.0;
    int mat =
        im->mat_base + (am->mMaterialIndex < im->ai->mNumMaterials ? (int)am->mMaterialIndex : 0);
    char label[SCENE_SHOWN_LEN + 16];
    if (!(am->mPrimitiveTypes & aiPrimitiveType_TRIANGLE)) {
        im->info->non_faces += am->mNumFaces;
        return 0;
    }
    if (am->mColors[0])
        im->info->colored++;
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
                         "%s: %s, face %u: vertex index %u out of range (%u vertices)", im->name,
                         mesh_label(am, index, label, sizeof label), f, vi, am->mNumVertices);
                return -1;
            }
            v = am->mVertices[vi];
            if (!isfinite(v.x) || !isfinite(v.y) || !isfinite(v.z)) {
                snprintf(im->err, im->errlen, "%s: %s, vertex %u is not finite (%g %g %g)",
                         im->name, mesh_label(am, index, label, sizeof label), vi, (double)v.x,
                         (double)v.y, (double)v.z);
                return -1;
            }
            p[k] = xform_point(x, vec3d_make(v.x, v.y, v.z));
            pf[k] = vec3f_make((float)p[k].x, (float)p[k].y, (float)p[k].z);
            if (!isfinite(pf[k].x) || !isfinite(pf[k].y) || !isfinite(pf[k].z)) {
                snprintf(im->err, im->errlen,
                         "%s: %s, vertex %u is out of range once its node transforms are applied",
                         im->name, mesh_label(am, index, label, sizeof label), vi);
                return -1;
            }
            if (smooth) {
                struct aiVector3D nv = am->mNormals[vi];
                if (!isfinite(nv.x) || !isfinite(nv.y) || !isfinite(nv.z) ||
                    xform_normal(x, vec3f_make(nv.x, nv.y, nv.z), &n[k]) != 0)
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

static vec3f vec_of(const scene_xform *x, struct aiVector3D v)
{
    double in[3] = {v.x, v.y, v.z}, out[3];
    xform_vector(x, in, out);
    return vec3f_make((float)out[0], (float)out[1], (float)out[2]);
}

/* The file's first camera, node being its node with world transform x. */
static void take_camera(importer *im, const struct aiCamera *c, const scene_xform *x)
{
    mesh_view *v = im->view;
    struct aiVector3D pos = c->mPosition;
    double aspect = isfinite(c->mAspect) && c->mAspect > 0.0f ? c->mAspect : 0.0;
    double hfov = c->mHorizontalFOV;
    if (im->fmt == MESH_FORMAT_GLTF) {
        /* a glTF camera sits at its node's origin; assimp 5.2 also copies the node's
         * translation into mPosition (assimp issue #5054), which would count it twice */
        pos.x = pos.y = pos.z = 0.0f;
    }
    v->eye = xform_point(x, vec3d_make(pos.x, pos.y, pos.z));
    v->dir = vec_of(x, c->mLookAt);
    v->up = vec_of(x, c->mUp);
    v->aspect = aspect;
    v->ortho_half = 0.0;
    v->yfov_deg = 0.0;
    if (c->mOrthographicWidth > 0.0f && isfinite(c->mOrthographicWidth)) {
        v->ortho_half = c->mOrthographicWidth;
    } else if (im->fmt == MESH_FORMAT_GLTF) {
        /* assimp's glTF reader stores yfov times the aspect ratio as the horizontal field */
        v->yfov_deg = hfov / (aspect > 0.0 ? aspect : 1.0) * 180.0 / 3.14159265358979323846;
    } else {
        /* a horizontal field of view: the vertical one from the aspect ratio */
        double half = tan(0.5 * hfov) / (aspect > 0.0 ? aspect : 1.0);
        v->yfov_deg = 2.0 * atan(half) * 180.0 / 3.14159265358979323846;
    }
    v->has_camera = isfinite(v->eye.x) && isfinite(v->eye.y) && isfinite(v->eye.z) &&
                    isfinite(v->yfov_deg) && isfinite(v->ortho_half) &&
                    (v->yfov_deg > 0.0 || v->ortho_half > 0.0);
}

static int take_light(importer *im, const struct aiLight *l, const scene_xform *x)
{
    mesh_view *v = im->view;
    mesh_light ml;
    vec3f dir;
    if (l->mType == aiLightSource_AMBIENT || l->mType == aiLightSource_UNDEFINED ||
        v->light_count >= MESH_MAX_LIGHTS)
        return 0;
    memset(&ml, 0, sizeof ml);
    ml.color = vec3f_make(l->mColorDiffuse.r, l->mColorDiffuse.g, l->mColorDiffuse.b);
    if (!(ml.color.x >= 0.0f && ml.color.y >= 0.0f && ml.color.z >= 0.0f) ||
        !isfinite(ml.color.x + ml.color.y + ml.color.z))
        return 0;
    ml.position = xform_point(x, vec3d_make(l->mPosition.x, l->mPosition.y, l->mPosition.z));
    ml.directional = l->mType == aiLightSource_DIRECTIONAL;
    if (ml.directional) {
        if (vec3f_normalize(vec_of(x, l->mDirection), &dir) != 0)
            return 0;
        ml.dir = dir;
    } else if (!isfinite(ml.position.x) || !isfinite(ml.position.y) || !isfinite(ml.position.z)) {
        return 0;
    }
    if (!v->lights) {
        v->lights = malloc(MESH_MAX_LIGHTS * sizeof *v->lights);
        if (!v->lights) {
            snprintf(im->err, im->errlen, "%s: out of memory", im->name);
            return -1;
        }
    }
    v->lights[v->light_count++] = ml;
    return 0;
}

/* A node's camera and lights: those whose name is the node's. */
static int take_view(importer *im, const struct aiNode *node, const scene_xform *x)
{
    const struct aiScene *ai = im->ai;
    unsigned i;
    if (!im->view)
        return 0;
    if (ai->mNumCameras > 0 && !im->view->has_camera &&
        strcmp(ai->mCameras[0]->mName.data, node->mName.data) == 0)
        take_camera(im, ai->mCameras[0], x);
    for (i = 0; i < ai->mNumLights; i++)
        if (strcmp(ai->mLights[i]->mName.data, node->mName.data) == 0 &&
            take_light(im, ai->mLights[i], x) != 0)
            return -1;
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
    char shown[SCENE_SHOWN_LEN];
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
            snprintf(im->err, im->errlen, "%s: node '%s' has a projective or non-finite transform",
                     im->name, scene_shown(it.node->mName.data, shown));
            rc = -1;
            break;
        }
        xform_compose(&x, &it.x, &local);
        rc = take_view(im, it.node, &x);
        for (i = 0; i < it.node->mNumMeshes && rc == 0; i++) {
            unsigned mi = it.node->mMeshes[i];
            if (mi >= im->ai->mNumMeshes) {
                snprintf(im->err, im->errlen, "%s: node '%s' refers to mesh %u of %u", im->name,
                         scene_shown(it.node->mName.data, shown), mi, im->ai->mNumMeshes);
                rc = -1;
            } else {
                rc = add_mesh(im, mi, &x);
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

static int import_scene(const struct aiScene *ai, const char *name, mesh_format fmt, scene *s,
                        int *mesh, mesh_import_info *info, mesh_view *view, char *err,
                        size_t errlen);

/* What assimp's post-processing takes for granted: finite vertices; every face has
 * vertices, in range, and its kind (point, line, triangle, polygon) among the mesh's
 * primitive types. */
static int check_meshes(const struct aiScene *ai, const char *name, char *err, size_t errlen)
{
    unsigned m, f, k;
    char label[SCENE_SHOWN_LEN + 16];
    for (m = 0; m < ai->mNumMeshes; m++) {
        const struct aiMesh *am = ai->mMeshes[m];
        if (!am || (am->mNumFaces > 0 && !am->mFaces) || (am->mNumVertices > 0 && !am->mVertices)) {
            snprintf(err, errlen, "%s: mesh %u has no faces or vertices", name, m);
            return -1;
        }
        for (k = 0; k < am->mNumVertices; k++) {
            struct aiVector3D v = am->mVertices[k];
            if (!isfinite(v.x) || !isfinite(v.y) || !isfinite(v.z)) {
                snprintf(err, errlen, "%s: %s, vertex %u is not finite (%g %g %g)", name,
                         mesh_label(am, m, label, sizeof label), k, (double)v.x, (double)v.y,
                         (double)v.z);
                return -1;
            }
        }
        for (f = 0; f < am->mNumFaces; f++) {
            const struct aiFace *face = &am->mFaces[f];
            unsigned n = face->mNumIndices, kind;
            if (n == 0 || !face->mIndices) {
                snprintf(err, errlen, "%s: %s, face %u has no vertices", name,
                         mesh_label(am, m, label, sizeof label), f);
                return -1;
            }
            kind = n == 1   ? aiPrimitiveType_POINT
                   : n == 2 ? aiPrimitiveType_LINE
                   : n == 3 ? aiPrimitiveType_TRIANGLE
                            : aiPrimitiveType_POLYGON;
            if (!(am->mPrimitiveTypes & kind)) {
                snprintf(err, errlen,
                         "%s: %s, face %u has %u vertices, which the mesh's primitive types do not "
                         "allow",
                         name, mesh_label(am, m, label, sizeof label), f, n);
                return -1;
            }
            for (k = 0; k < n; k++)
                if (face->mIndices[k] >= am->mNumVertices) {
                    snprintf(err, errlen,
                             "%s: %s, face %u: vertex index %u out of range (%u vertices)", name,
                             mesh_label(am, m, label, sizeof label), f, face->mIndices[k],
                             am->mNumVertices);
                    return -1;
                }
        }
    }
    return 0;
}

/* The file assimp read (ai, NULL when it failed) checked, post-processed and imported;
 * releases ai. */
static int import_read(const struct aiScene *ai, const mesh_log *log, const char *name,
                       mesh_format fmt, scene *s, int *mesh, mesh_import_info *info,
                       mesh_view *view, char *err, size_t errlen)
{
    int rc;
    if (ai && log->bad[0]) {
        snprintf(err, errlen, "%s: cannot read the mesh: %s", name, log->bad);
        aiReleaseImport(ai);
        return -1;
    }
    if (ai && check_meshes(ai, name, err, errlen) != 0) {
        aiReleaseImport(ai);
        return -1;
    }
    if (ai) {
        ai = aiApplyPostProcessing(ai, MESH_AI_POST); /* NULL: failed (not these steps) */
        if (!ai) {
            snprintf(err, errlen, "%s: cannot read the mesh: assimp's post-processing failed",
                     name);
            return -1;
        }
    }
    rc = import_scene(ai, name, fmt, s, mesh, info, view, err, errlen);
    if (ai)
        aiReleaseImport(ai);
    return rc;
}

static int import_scene(const struct aiScene *ai, const char *name, mesh_format fmt, scene *s,
                        int *mesh, mesh_import_info *info, mesh_view *view, char *err,
                        size_t errlen)
{
    importer im;
    scene_mesh m;
    unsigned i;
    size_t mat_count = s->materials.count;
    if (!ai) {
        const char *why = aiGetErrorString();
        char shown[512];
        snprintf(err, errlen, "%s: cannot read the mesh: %s", name,
                 why && *why ? scene_printable(why, 400, shown, sizeof shown) : "unknown error");
        return -1;
    }
    if (!ai->mRootNode) {
        snprintf(err, errlen, "%s: the file has no scene graph (no root node)", name);
        return -1;
    }
    im.s = s;
    im.ai = ai;
    im.fmt = fmt;
    im.mat_base = (int)mat_count;
    im.info = info;
    im.view = view;
    im.name = name;
    im.err = err;
    im.errlen = errlen;
    info->cameras = (int)ai->mNumCameras;
    info->lights = (int)ai->mNumLights;
    for (i = 0; i < ai->mNumMaterials || i == 0; i++) {
        scene_material sm;
        if (i < ai->mNumMaterials)
            mesh_material_map(ai->mMaterials[i], fmt, &sm, &info->textured);
        else /* a file without materials */
            mesh_material_default(&sm);
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

int mesh_import_view(const char *path, scene *s, int *mesh, mesh_import_info *info, mesh_view *view,
                     char *err, size_t errlen)
{
    mesh_format fmt = mesh_format_of(path);
    memset(info, 0, sizeof *info);
    if (view)
        memset(view, 0, sizeof *view);
    if (mesh_file_check(path, err, errlen) != 0)
        return -1;
    if (fmt == MESH_FORMAT_OBJ)
        info->missing_mtl =
            mesh_file_mtllibs(path, info->missing_mtl_name, sizeof info->missing_mtl_name);
    if (assimp_load(err, errlen) != 0)
        return -1;
    {
        mesh_log log;
        const struct aiScene *ai;
        char msg[1200], shown[1024];
        int rc;
        /* assimp 5.2 crashes on some malformed OBJ and PLY files (make fuzz finds them):
         * that ends here with an error naming the file, not a crash */
        snprintf(msg, sizeof msg,
                 "clwhitted: %s: cannot read the mesh: the mesh library (assimp) crashed on "
                 "it; the file is malformed",
                 sys_escape(shown, sizeof shown, path));
        sys_guard_begin(msg);
        ai = read_logged(path, NULL, 0, NULL, &log);
        rc = import_read(ai, &log, path, fmt, s, mesh, info, view, err, errlen);
        sys_guard_end();
        return rc;
    }
}

int mesh_import(const char *path, scene *s, int *mesh, mesh_import_info *info, char *err,
                size_t errlen)
{
    return mesh_import_view(path, s, mesh, info, NULL, err, errlen);
}

int mesh_import_memory(const void *data, size_t size, const char *hint, const char *name, scene *s,
                       int *mesh, mesh_import_info *info, mesh_view *view, char *err, size_t errlen)
{
    memset(info, 0, sizeof *info);
    if (view)
        memset(view, 0, sizeof *view);
    if (size == 0) {
        snprintf(err, errlen, "%s: the mesh file is empty", name);
        return -1;
    }
    if (size > 0xffffffffu) {
        snprintf(err, errlen, "%s: too large", name);
        return -1;
    }
    if (strcmp(hint, "glb") == 0 && mesh_glb_check(data, size, name, err, errlen) != 0)
        return -1;
    if (assimp_load(err, errlen) != 0)
        return -1;
    {
        mesh_log log;
        const struct aiScene *ai = read_logged(NULL, data, size, hint, &log);
        return import_read(ai, &log, name, mesh_format_of(hint), s, mesh, info, view, err, errlen);
    }
}
