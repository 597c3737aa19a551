/* Mesh file materials as Whitted materials. See mesh_material.h; the mapping is the table
 * in docs/scene-formats.md ("Mesh files"). */
#include "mesh_material.h"

#include <assimp/material.h>
#include <math.h>
#include <string.h>
#include <strings.h>

#include "assimp_dl.h"
#include "scene_geom.h"

/* glTF's defaults (the metallic-roughness model): metallic 1, roughness 1, index 1.5 */
#define GLTF_IOR 1.5f
/* the Phong exponent from roughness is capped here (a mirror-like highlight) */
#define MESH_MAX_P 10000.0f

mesh_format mesh_format_of(const char *name_or_ext)
{
    const char *dot = strrchr(name_or_ext, '.');
    const char *ext = dot ? dot + 1 : name_or_ext;
    if (strcasecmp(ext, "ply") == 0)
        return MESH_FORMAT_PLY;
    if (strcasecmp(ext, "stl") == 0)
        return MESH_FORMAT_STL;
    if (strcasecmp(ext, "obj") == 0)
        return MESH_FORMAT_OBJ;
    if (strcasecmp(ext, "gltf") == 0 || strcasecmp(ext, "glb") == 0)
        return MESH_FORMAT_GLTF;
    return MESH_FORMAT_OTHER;
}

void mesh_material_default(scene_material *sm)
{
    memset(sm, 0, sizeof *sm);
    sm->kd = sm->ka = vec3f_make(0.8f, 0.8f, 0.8f);
    sm->p = 1.0f;
    sm->ior = 1.0f;
}

static float clamp01(float x)
{
    return x > 1.0f ? 1.0f : x > 0.0f ? x : 0.0f; /* NaN gives 0 */
}

static vec3f clamp3(vec3f c)
{
    return vec3f_make(clamp01(c.x), clamp01(c.y), clamp01(c.z));
}

static int has_key(const struct aiMaterial *m, const char *key)
{
    const struct aiMaterialProperty *p;
    return aiGetMaterialProperty(m, key, 0, 0, &p) == AI_SUCCESS;
}

/* A colour in 0..1 (a finite colour out of range is clamped), or dflt when absent. */
static vec3f color_of(const struct aiMaterial *m, const char *key, vec3f dflt)
{
    struct aiColor4D c;
    if (aiGetMaterialColor(m, key, 0, 0, &c) == AI_SUCCESS && isfinite(c.r) && isfinite(c.g) &&
        isfinite(c.b))
        return clamp3(vec3f_make(c.r, c.g, c.b));
    return dflt;
}

static float float_of(const struct aiMaterial *m, const char *key, float dflt)
{
    ai_real v;
    unsigned one = 1;
    if (aiGetMaterialFloatArray(m, key, 0, 0, &v, &one) == AI_SUCCESS && one == 1 && isfinite(v))
        return (float)v;
    return dflt;
}

static int int_of(const struct aiMaterial *m, const char *key, int dflt)
{
    int v;
    unsigned one = 1;
    if (aiGetMaterialIntegerArray(m, key, 0, 0, &v, &one) == AI_SUCCESS && one == 1)
        return v;
    return dflt;
}

static vec3f scale3(vec3f c, float s)
{
    return vec3f_make(c.x * s, c.y * s, c.z * s);
}

static int is_black(vec3f c)
{
    return c.x == 0.0f && c.y == 0.0f && c.z == 0.0f;
}

/* An index of refraction: a finite value >= 1 (below 1 or absent: dflt). */
static float ior_of(const struct aiMaterial *m, float dflt)
{
    float ior = float_of(m, "$mat.refracti", dflt);
    return ior >= 1.0f && ior <= 100.0f ? ior : dflt;
}

/* MTL (and any material with the classic keys): Kd, Ka, Ks, Ns, illum, d, Tf, Ni. */
static void map_classic(const struct aiMaterial *m, scene_material *sm)
{
    int illum = int_of(m, "$mat.illum", 2);
    float d = clamp01(float_of(m, "$mat.opacity", 1.0f));
    vec3f tf = color_of(m, "$clr.transparent", vec3f_make(1, 1, 1));
    sm->kd = color_of(m, "$clr.diffuse", vec3f_make(0.8f, 0.8f, 0.8f));
    sm->ka = color_of(m, "$clr.ambient", vec3f_make(0, 0, 0));
    if (is_black(sm->ka)) /* no Ka (assimp's default is black): ambient like diffuse */
        sm->ka = sm->kd;
    sm->ks = color_of(m, "$clr.specular", vec3f_make(0, 0, 0));
    sm->p = float_of(m, "$mat.shininess", 1.0f);
    if (!(sm->p >= 0.0f))
        sm->p = 0.0f;
    if (sm->p > MESH_MAX_P)
        sm->p = MESH_MAX_P;
    /* illum 3-7: reflection ray traced (3, 5 reflection; 4, 6, 7 glass or refraction) */
    if (illum >= 3 && illum <= 7)
        sm->km = sm->ks;
    /* transmission: dissolve (d < 1) in every mode, filtered by Tf; the transparent modes
     * (4, 6, 7, 9) transmit Tf even when d is 1 */
    if (d < 1.0f)
        sm->kt = scale3(tf, 1.0f - d);
    else if (illum == 4 || illum == 6 || illum == 7 || illum == 9)
        sm->kt = tf;
    sm->ior = ior_of(m, 1.0f);
}

/* glTF 2.0's metallic-roughness model, approximated (docs/scene-formats.md). */
static void map_gltf(const struct aiMaterial *m, scene_material *sm)
{
    vec3f base = color_of(m, "$clr.base", color_of(m, "$clr.diffuse", vec3f_make(1, 1, 1)));
    float metal = clamp01(float_of(m, "$mat.metallicFactor", 1.0f));
    float rough = clamp01(float_of(m, "$mat.roughnessFactor", 1.0f));
    float trans = clamp01(float_of(m, "$mat.transmission.factor", 0.0f));
    float ior = ior_of(m, GLTF_IOR);
    float f0 = (ior - 1.0f) / (ior + 1.0f), alpha = rough * rough, p;
    vec3f spec;
    f0 *= f0; /* a dielectric's reflectance at normal incidence: 0.04 at 1.5 */
    spec = vec3f_make(f0 + (base.x - f0) * metal, f0 + (base.y - f0) * metal,
                      f0 + (base.z - f0) * metal);
    sm->kd = scale3(base, (1.0f - metal) * (1.0f - trans));
    sm->ka = sm->kd;
    sm->ks = spec;
    p = alpha > 0.0f ? 2.0f / (alpha * alpha) - 2.0f : MESH_MAX_P;
    sm->p = p < 1.0f ? 1.0f : p > MESH_MAX_P ? MESH_MAX_P : p;
    /* a mirror for the smooth metal, and the dielectric's reflection where it transmits */
    sm->km = scale3(base, metal * (1.0f - rough));
    sm->km.x += f0 * trans * (1.0f - metal);
    sm->km.y += f0 * trans * (1.0f - metal);
    sm->km.z += f0 * trans * (1.0f - metal);
    sm->kt = scale3(base, trans * (1.0f - metal));
    sm->ior = ior;
}

void mesh_material_map(const struct aiMaterial *m, mesh_format fmt, scene_material *sm,
                       int *textured)
{
    mesh_material_default(sm);
    if (fmt == MESH_FORMAT_PLY || fmt == MESH_FORMAT_STL)
        return;
    if (has_key(m, "$clr.base") || has_key(m, "$mat.metallicFactor"))
        map_gltf(m, sm);
    else
        map_classic(m, sm);
    if (aiGetMaterialTextureCount(m, aiTextureType_DIFFUSE) > 0 ||
        aiGetMaterialTextureCount(m, aiTextureType_BASE_COLOR) > 0)
        (*textured)++;
}
