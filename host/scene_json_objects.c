/* The JSON reader's "objects": each entry checked against the keys of its type and added
 * to the scene (see scene_json_objects.h; the schema is in scene_json.c's comment):
 *
 *   {"type": "sphere", "center", "radius" (> 0), "inside" (optional bool), "material"}
 *   {"type": "triangle", "vertices": 3 points, "normals" (optional), "material"}
 *   {"type": "polygon", "vertices": >= 3 planar points, "normals" (optional), "material"}
 *   {"type": "cone", "base", "base_radius" (>= 0), "apex", "apex_radius" (>= 0), "material"}
 *   {"type": "cylinder", "base", "apex", "radius" (> 0), "material"}
 *   {"type": "mesh", "file", "transform" (optional), "material" (optional)}
 *
 * "inside": true makes a sphere visible from inside only (NFF's negative radius, stored
 * as one). A polygon with normals is a smooth patch (NFF's pp): the fan of smooth
 * triangles (v0, vi, vi+1). */
#include "scene_json_objects.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "config.h"
#include "scene_geom.h"
#include "scene_io.h"
#include "scene_json_xform.h"
#include "scene_mesh.h"
#include "xform.h"

int jo_material_cmp(const void *a, const void *b)
{
    return strcmp(((const jo_material *)a)->name, ((const jo_material *)b)->name);
}

int jo_find_material(const jo_reader *r, const cJSON *obj, const char *path)
{
    const cJSON *m = jv_need(r->doc, obj, path, "material");
    const char *name;
    jo_material key, *hit;
    char buf[SCENE_SHOWN_LEN];
    if (!m)
        return -1;
    if (!(name = cJSON_GetStringValue(m)))
        return jv_fail(r->doc, m, "%s.material: expected a material name, found %s", path,
                       jv_type_name(m));
    key.name = name;
    key.index = 0;
    hit = r->nmats ? bsearch(&key, r->mats, r->nmats, sizeof key, jo_material_cmp) : NULL;
    if (!hit)
        return jv_fail(r->doc, m, "%s.material: no material named \"%s\" in \"materials\"", path,
                       scene_shown(name, buf));
    return hit->index;
}

/* 0 when the polygon has an area (see scene_area_zero); otherwise fails at `node`. Also
 * gives the unit normal and the size of the polygon. */
static int check_area(const jo_reader *r, const cJSON *node, const char *path, const vec3d *p,
                      int n, double unit[3], double *size_out)
{
    scene_area a;
    int i, k;
    scene_area_init(&a);
    for (i = 0; i < n; i++)
        scene_area_add(&a, p[i]);
    if (scene_area_zero(&a))
        return jv_fail(r->doc, node, "%s: the %s has zero area", path,
                       n == 3 ? "triangle" : "polygon");
    for (k = 0; k < 3; k++)
        unit[k] = a.normal[k] / a.len;
    *size_out = scene_area_size(&a);
    return 0;
}

/* Fails unless every vertex lies within 1e-4 * size of the plane through the centroid. */
static int check_planar(const jo_reader *r, const cJSON *verts, const char *path, const vec3d *pts,
                        int n, const double unit[3], double size)
{
    double c[3] = {0, 0, 0};
    const cJSON *vn = verts->child;
    int k;
    for (k = 0; k < n; k++) {
        c[0] += pts[k].x;
        c[1] += pts[k].y;
        c[2] += pts[k].z;
    }
    c[0] /= n;
    c[1] /= n;
    c[2] /= n;
    for (k = 0; k < n; k++, vn = vn->next) {
        double off =
            (pts[k].x - c[0]) * unit[0] + (pts[k].y - c[1]) * unit[1] + (pts[k].z - c[2]) * unit[2];
        if (fabs(off) > 1e-4 * size)
            return jv_fail(r->doc, vn,
                           "%s[%d]: the polygon is not planar: this vertex lies %g off its "
                           "plane (tolerance %g)",
                           path, k, fabs(off), 1e-4 * size);
    }
    return 0;
}

/* A required number that must be > 0 (positive = 1) or >= 0 once stored as a float. */
static int radius(const jo_reader *r, const cJSON *o, const char *path, const char *key,
                  int positive, float *out)
{
    char sub[96], buf[SCENE_SHOWN_LEN];
    const cJSON *m;
    double x;
    snprintf(sub, sizeof sub, "%s.%s", path, key);
    if (!(m = jv_need(r->doc, o, path, key)) || jv_number(r->doc, m, sub, &x) != 0)
        return -1;
    if (positive ? !((float)x > 0) : !((float)x >= 0)) /* as stored: a float */
        return jv_fail(r->doc, m, "%s: the radius must be %s 0, found %.10g%s", sub,
                       positive ? ">" : ">=", x, scene_single_note(x, buf, sizeof buf));
    *out = (float)x;
    return 0;
}

/* A required point. */
static int point(const jo_reader *r, const cJSON *o, const char *path, const char *key, vec3d *out)
{
    char sub[96];
    const cJSON *m;
    snprintf(sub, sizeof sub, "%s.%s", path, key);
    if (!(m = jv_need(r->doc, o, path, key)) || jv_point(r->doc, m, sub, out) != 0)
        return -1;
    return 0;
}

static int read_sphere(const jo_reader *r, const cJSON *o, const char *path)
{
    scene_sphere sp;
    const cJSON *m;
    int mat;
    if (point(r, o, path, "center", &sp.center) != 0 ||
        radius(r, o, path, "radius", 1, &sp.radius) != 0)
        return -1;
    if ((m = jv_member(o, "inside"))) {
        if (!cJSON_IsBool(m))
            return jv_fail(r->doc, m, "%s.inside: expected true or false, found %s", path,
                           jv_type_name(m));
        if (cJSON_IsTrue(m))
            sp.radius = -sp.radius; /* the model's inside-only sphere (scene.h) */
    }
    if ((mat = jo_find_material(r, o, path)) < 0)
        return -1;
    sp.material = mat;
    return scene_push(&r->s->spheres, &sp, sizeof sp) < 0 ? jv_oom(r->doc, o) : 0;
}

/* A cone (cylinder = 0: base_radius and apex_radius) or a cylinder (one radius). */
static int read_cone(const jo_reader *r, const cJSON *o, const char *path, int cylinder)
{
    scene_cone c;
    int mat;
    if (point(r, o, path, "base", &c.base) != 0 || point(r, o, path, "apex", &c.apex) != 0)
        return -1;
    if (cylinder) {
        if (radius(r, o, path, "radius", 1, &c.base_radius) != 0)
            return -1;
        c.apex_radius = c.base_radius;
    } else {
        if (radius(r, o, path, "base_radius", 0, &c.base_radius) != 0 ||
            radius(r, o, path, "apex_radius", 0, &c.apex_radius) != 0)
            return -1;
        if (c.base_radius == 0 && c.apex_radius == 0)
            return jv_fail(r->doc, o, "%s: base_radius and apex_radius are both zero", path);
    }
    if (c.base.x == c.apex.x && c.base.y == c.apex.y && c.base.z == c.apex.z)
        return jv_fail(r->doc, jv_member(o, "apex"), "%s.apex: equals the base", path);
    if ((mat = jo_find_material(r, o, path)) < 0)
        return -1;
    c.material = mat;
    return scene_push(&r->s->cones, &c, sizeof c) < 0 ? jv_oom(r->doc, o) : 0;
}

/* "normals": n non-zero vectors, normalised into nv (malloc'd). */
static int read_normals(const jo_reader *r, const cJSON *m, const char *path, int n, vec3f **nv)
{
    vec3d *nrm;
    const cJSON *e;
    char sub[96];
    int nn, k;
    *nv = NULL;
    snprintf(sub, sizeof sub, "%s.normals", path);
    if (jv_points(r->doc, m, sub, n, n, &nrm, &nn) != 0)
        return -1;
    if (!(*nv = malloc((size_t)n * sizeof **nv))) {
        free(nrm);
        return jv_oom(r->doc, m);
    }
    for (k = 0, e = m->child; k < n; k++, e = e->next) {
        vec3f nf = vec3f_make((float)nrm[k].x, (float)nrm[k].y, (float)nrm[k].z);
        if (vec3f_normalize(nf, &(*nv)[k]) != 0) {
            free(nrm);
            free(*nv);
            *nv = NULL;
            return jv_fail(r->doc, e, "%s[%d]: the normal is zero", sub, k);
        }
    }
    free(nrm);
    return 0;
}

/* Adds the points as the scene has them: a triangle, a polygon, or the fan of smooth
 * triangles of a polygon with normals. */
static int add_faces(const jo_reader *r, const cJSON *o, const vec3d *pts, const vec3f *nv, int n,
                     int tri, int mat)
{
    int k;
    if (tri || nv) {
        for (k = 2; k < n; k++) {
            vec3d p[3];
            vec3f fn[3];
            p[0] = pts[0];
            p[1] = pts[k - 1];
            p[2] = pts[k];
            if (nv) {
                fn[0] = nv[0];
                fn[1] = nv[k - 1];
                fn[2] = nv[k];
            }
            if (scene_push_triangle(r->s, p, nv ? fn : NULL, mat) < 0)
                return jv_oom(r->doc, o);
        }
        return 0;
    } else {
        scene_polygon poly;
        poly.first = (int)r->s->poly_verts.count;
        poly.count = n;
        poly.material = mat;
        for (k = 0; k < n; k++)
            if (scene_push(&r->s->poly_verts, &pts[k], sizeof pts[k]) < 0)
                return jv_oom(r->doc, o);
        return scene_push(&r->s->polygons, &poly, sizeof poly) < 0 ? jv_oom(r->doc, o) : 0;
    }
}

static int read_faces(const jo_reader *r, const cJSON *o, const char *path, int tri)
{
    vec3d *pts = NULL;
    vec3f *nv = NULL;
    int n, mat, rc = -1;
    double unit[3] = {0, 0, 0}, size = 0;
    const cJSON *m, *verts = jv_need(r->doc, o, path, "vertices");
    char sub[96];
    if (!verts)
        return -1;
    snprintf(sub, sizeof sub, "%s.vertices", path);
    if (jv_points(r->doc, verts, sub, 3, tri ? 3 : CW_MAX_VERTS, &pts, &n) != 0)
        return -1;
    if (check_area(r, verts, sub, pts, n, unit, &size) != 0)
        goto free_pts;
    if (!tri && check_planar(r, verts, sub, pts, n, unit, size) != 0)
        goto free_pts;
    if ((mat = jo_find_material(r, o, path)) < 0)
        goto free_pts;
    if ((m = jv_member(o, "normals")) && read_normals(r, m, path, n, &nv) != 0)
        goto free_pts;
    rc = add_faces(r, o, pts, nv, n, tri, mat);
    free(nv);
free_pts:
    free(pts);
    return rc;
}

void jo_mesh_files_free(jo_mesh_files *f)
{
    free(f->id);
    free(f->mesh);
    memset(f, 0, sizeof *f);
}

/* file relative to the folder of the scene file `scene_path` (as it is when absolute, or
 * when the scene has no folder); malloc'd, NULL when out of memory. */
static char *beside(const char *scene_path, const char *file)
{
    const char *slash = strrchr(scene_path, '/');
    size_t dir = file[0] == '/' || !slash ? 0 : (size_t)(slash - scene_path) + 1;
    char *p = malloc(dir + strlen(file) + 1);
    if (p) {
        memcpy(p, scene_path, dir);
        strcpy(p + dir, file);
    }
    return p;
}

/* A mesh file placed in the scene: read once (the same file again is another placement of
 * the same mesh: an instance, not a copy), placed with its transform and, when given, every
 * triangle's material overridden. */
static int read_mesh(const jo_reader *r, const cJSON *o, const char *path)
{
    const cJSON *f = jv_need(r->doc, o, path, "file"), *t, *m;
    const char *file;
    char *full, why[1024], shown[SCENE_SHOWN_LEN];
    int mesh = -1, material = -1;
    size_t k;
    scene_xform x;
    struct stat st;
    if (!f)
        return -1;
    if (!(file = cJSON_GetStringValue(f)) || !*file)
        return jv_fail(r->doc, f, "%s.file: expected the name of a mesh file, found %s", path,
                       cJSON_IsString(f) ? "an empty string" : jv_type_name(f));
    xform_identity(&x);
    if ((t = jv_member(o, "transform"))) {
        char tpath[80];
        snprintf(tpath, sizeof tpath, "%s.transform", path);
        if (jx_transform(r->doc, t, tpath, &x) != 0)
            return -1;
    }
    if ((m = jv_member(o, "material")) && (material = jo_find_material(r, o, path)) < 0)
        return -1;
    if (!r->read_mesh)
        return jv_fail(r->doc, f, "%s.file: mesh files cannot be read here", path);
    if (!(full = beside(r->doc->msg->name, file)))
        return jv_oom(r->doc, f);
    if (stat(full, &st) != 0) {
        int e = errno;
        free(full);
        return jv_fail(r->doc, f, "%s.file \"%s\": %s", path, scene_shown(file, shown),
                       strerror(e));
    }
    for (k = 0; k < r->files->count; k++)
        if (r->files->id[2 * k] == (unsigned long long)st.st_dev &&
            r->files->id[2 * k + 1] == (unsigned long long)st.st_ino) {
            mesh = r->files->mesh[k];
            break;
        }
    if (mesh < 0) {
        unsigned long long *ni = realloc(r->files->id, 2 * (r->files->count + 1) * sizeof *ni);
        int *nm = ni ? realloc(r->files->mesh, (r->files->count + 1) * sizeof *nm) : NULL;
        if (ni)
            r->files->id = ni;
        if (nm)
            r->files->mesh = nm;
        if (!ni || !nm) {
            free(full);
            return jv_oom(r->doc, f);
        }
        if (r->read_mesh(full, r->s, &mesh, why, sizeof why) != 0) {
            free(full);
            return jv_fail(r->doc, f, "%s.file \"%s\": %s", path, scene_shown(file, shown), why);
        }
        r->files->id[2 * r->files->count] = (unsigned long long)st.st_dev;
        r->files->id[2 * r->files->count + 1] = (unsigned long long)st.st_ino;
        r->files->mesh[r->files->count] = mesh;
        r->files->count++;
    }
    free(full);
    if (scene_place_mesh(r->s, mesh, &x, material) < 0)
        return jv_oom(r->doc, o);
    return 0;
}

int jo_read_object(const jo_reader *r, const cJSON *o, int i)
{
    static const char *const sphere_keys[] = {"type",   "center",   "radius",
                                              "inside", "material", NULL};
    static const char *const face_keys[] = {"type", "vertices", "normals", "material", NULL};
    static const char *const cone_keys[] = {"type",        "base",     "base_radius", "apex",
                                            "apex_radius", "material", NULL};
    static const char *const cylinder_keys[] = {"type", "base", "apex", "radius", "material", NULL};
    static const char *const mesh_keys[] = {"type", "file", "transform", "material", NULL};
    static const struct {
        const char *name;
        const char *const *keys;
    } types[] = {{"sphere", sphere_keys}, {"triangle", face_keys},     {"polygon", face_keys},
                 {"cone", cone_keys},     {"cylinder", cylinder_keys}, {"mesh", mesh_keys}};
    char path[64], buf[SCENE_SHOWN_LEN];
    const cJSON *t;
    const char *type;
    size_t k;
    snprintf(path, sizeof path, "objects[%d]", i);
    if (jv_check_object(r->doc, o, path, NULL) != 0)
        return -1;
    if (!(t = jv_need(r->doc, o, path, "type")))
        return -1;
    if (!(type = cJSON_GetStringValue(t)))
        return jv_fail(r->doc, t, "%s.type: expected a string, found %s", path, jv_type_name(t));
    for (k = 0; k < sizeof types / sizeof types[0]; k++)
        if (strcmp(type, types[k].name) == 0)
            break;
    if (k == sizeof types / sizeof types[0])
        return jv_fail(r->doc, t,
                       "%s.type: unknown object type \"%s\" (expected \"sphere\", \"triangle\", "
                       "\"polygon\", \"cone\", \"cylinder\" or \"mesh\")",
                       path, scene_shown(type, buf));
    if (jv_check_object(r->doc, o, path, types[k].keys) != 0)
        return -1;
    switch (k) {
    case 0:
        return read_sphere(r, o, path);
    case 1:
    case 2:
        return read_faces(r, o, path, k == 1);
    case 5:
        return read_mesh(r, o, path);
    default:
        return read_cone(r, o, path, k == 4);
    }
}
