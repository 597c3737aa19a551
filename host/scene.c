/* The scene model: growable arrays, defaults and the checks of a finished scene. */
#include "scene.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "scene_geom.h"
#include "scene_mesh.h"
#include "xform.h"

/* The messages below say "2^28 pixels". */
_Static_assert(CW_MAX_PIXELS == 1L << 28, "CW_MAX_PIXELS is not 2^28: fix the messages");

void scene_init(scene *s)
{
    memset(s, 0, sizeof *s);
    s->max_depth = CW_DEFAULT_DEPTH;
    s->camera.projection = SCENE_PERSPECTIVE;
    s->camera.d = 1.0f;
}

static void array_free(scene_array *a)
{
    free(a->data);
    a->data = NULL;
    a->count = a->cap = 0;
}

void scene_drop_primitives(scene *s)
{
    array_free(&s->spheres);
    array_free(&s->triangles);
    array_free(&s->tri_normals);
    array_free(&s->polygons);
    array_free(&s->poly_verts);
    array_free(&s->cones);
}

void scene_free(scene *s)
{
    free(s->name);
    array_free(&s->materials);
    array_free(&s->lights);
    scene_drop_primitives(s);
    for (size_t i = 0; i < s->meshes.count; i++)
        free(SCENE_AT(s->meshes, scene_mesh, i).source);
    array_free(&s->meshes);
    array_free(&s->mesh_tris);
    array_free(&s->instances);
    scene_init(s);
}

long scene_push(scene_array *a, const void *elem, size_t elem_size)
{
    if (a->count == a->cap) {
        size_t cap = a->cap ? a->cap * 2 : 16;
        void *data;
        if (cap > ((size_t)-1) / elem_size || cap > (size_t)0x7fffffff)
            return -1;
        data = realloc(a->data, cap * elem_size);
        if (!data)
            return -1;
        a->data = data;
        a->cap = cap;
    }
    memcpy((char *)a->data + a->count * elem_size, elem, elem_size);
    return (long)a->count++;
}

static long push_triangle(scene *s, scene_array *dst, const vec3d p[3], const vec3f *n,
                          int material)
{
    scene_triangle t;
    memcpy(t.p, p, sizeof t.p);
    t.normals = 0;
    t.material = material;
    if (n) {
        long first = (long)s->tri_normals.count;
        if (first > 0x7ffffff0L) /* the index must fit an int */
            return -1;
        for (int k = 0; k < 3; k++)
            if (scene_push(&s->tri_normals, &n[k], sizeof n[k]) < 0)
                return -1;
        t.normals = (int)first + 1;
    }
    return scene_push(dst, &t, sizeof t);
}

long scene_push_triangle(scene *s, const vec3d p[3], const vec3f *n, int material)
{
    return push_triangle(s, &s->triangles, p, n, material);
}

long scene_push_mesh_triangle(scene *s, const vec3d p[3], const vec3f *n, int material)
{
    return push_triangle(s, &s->mesh_tris, p, n, material);
}

const vec3f *scene_triangle_normals(const scene *s, const scene_triangle *t)
{
    return t->normals > 0 ? &SCENE_AT(s->tri_normals, vec3f, (size_t)(t->normals - 1)) : NULL;
}

/* Sets s->name to the base name of path without its extension. */
int scene_set_name(scene *s, const char *path)
{
    const char *base = strrchr(path, '/'), *dot;
    size_t n;
    base = base ? base + 1 : path;
    dot = strrchr(base, '.');
    n = dot && dot != base ? (size_t)(dot - base) : strlen(base);
    if (n == 0) {
        base = "scene";
        n = 5;
    }
    free(s->name);
    s->name = malloc(n + 1);
    if (!s->name)
        return -1;
    memcpy(s->name, base, n);
    s->name[n] = '\0';
    return 0;
}

static int finite3(vec3f a)
{
    return isfinite(a.x) && isfinite(a.y) && isfinite(a.z);
}

static int finite3d(vec3d a)
{
    return isfinite(a.x) && isfinite(a.y) && isfinite(a.z);
}

static int known_projection(const scene_camera *c)
{
    return c->projection == SCENE_PERSPECTIVE || c->projection == SCENE_ORTHOGRAPHIC ||
           c->projection == SCENE_OBLIQUE;
}

static int camera_finite(const scene_camera *c)
{
    return finite3d(c->eye) && finite3(c->u) && finite3(c->v) && finite3(c->w) && finite3(c->dir) &&
           isfinite(c->l) && isfinite(c->r) && isfinite(c->b) && isfinite(c->t) && isfinite(c->d);
}

/* "name: what i problem" in err; returns -1. */
static int fail_item(char *err, size_t errlen, const char *name, const char *what, size_t i,
                     const char *problem)
{
    snprintf(err, errlen, "%s: %s %zu %s", name, what, i, problem);
    return -1;
}

static int check_material_index(const char *name, int m, size_t count, const char *what, size_t i,
                                char *err, size_t errlen)
{
    if (m < 0 || (size_t)m >= count) {
        snprintf(err, errlen, "%s: %s %zu uses material %d, but the scene has %zu material%s", name,
                 what, i, m, count, count == 1 ? "" : "s");
        return -1;
    }
    return 0;
}

static int check_triangles(const scene *s, const scene_array *tris, const char *what, char *err,
                           size_t errlen)
{
    const char *name = s->name ? s->name : "scene";
    size_t i, nm = s->materials.count;
    for (i = 0; i < tris->count; i++) {
        const scene_triangle *t = &SCENE_AT(*tris, scene_triangle, i);
        const vec3f *n;
        int k;
        if (t->normals < 0 || (t->normals > 0 && (size_t)t->normals + 2 > s->tri_normals.count))
            return fail_item(err, errlen, name, what, i, "has invalid vertex normals");
        n = scene_triangle_normals(s, t);
        for (k = 0; k < 3; k++)
            if (!finite3d(t->p[k]) || (n && !finite3(n[k])))
                return fail_item(err, errlen, name, what, i, "has non-finite values");
        if (n)
            for (k = 0; k < 3; k++)
                if (!(vec3f_length(n[k]) > 0.0f))
                    return fail_item(err, errlen, name, what, i, "has a zero vertex normal");
        if (check_material_index(name, t->material, nm, what, i, err, errlen) != 0)
            return -1;
    }
    return 0;
}

int scene_check(const scene *s, char *err, size_t errlen)
{
    const scene_camera *c = &s->camera;
    const char *name = s->name ? s->name : "scene";
    size_t i, nm = s->materials.count;
    if (!known_projection(c)) {
        snprintf(err, errlen, "%s: unknown camera projection %d", name, (int)c->projection);
        return -1;
    }
    if (!camera_finite(c) || !finite3(s->background) || !finite3(s->ambient)) {
        snprintf(err, errlen, "%s: camera, background or ambient has non-finite values", name);
        return -1;
    }
    for (i = 0; i < nm; i++) {
        const scene_material *m = &SCENE_AT(s->materials, scene_material, i);
        if (!finite3(m->ka) || !finite3(m->kd) || !finite3(m->ks) || !finite3(m->km) ||
            !isfinite(m->p))
            return fail_item(err, errlen, name, "material", i, "has non-finite values");
    }
    for (i = 0; i < s->lights.count; i++) {
        const scene_light *l = &SCENE_AT(s->lights, scene_light, i);
        if (!finite3d(l->position) || !finite3(l->intensity))
            return fail_item(err, errlen, name, "light", i, "has non-finite values");
    }
    for (i = 0; i < s->spheres.count; i++) {
        const scene_sphere *sp = &SCENE_AT(s->spheres, scene_sphere, i);
        if (!finite3d(sp->center) || !isfinite(sp->radius))
            return fail_item(err, errlen, name, "sphere", i, "has non-finite values");
        if (check_material_index(name, sp->material, nm, "sphere", i, err, errlen) != 0)
            return -1;
    }
    if (check_triangles(s, &s->triangles, "triangle", err, errlen) != 0 ||
        check_triangles(s, &s->mesh_tris, "mesh triangle", err, errlen) != 0)
        return -1;
    for (i = 0; i < s->meshes.count; i++) {
        const scene_mesh *m = &SCENE_AT(s->meshes, scene_mesh, i);
        if (m->first > s->mesh_tris.count || m->count > s->mesh_tris.count - m->first)
            return fail_item(err, errlen, name, "mesh", i, "has invalid triangles");
    }
    for (i = 0; i < s->instances.count; i++) {
        const scene_instance *in = &SCENE_AT(s->instances, scene_instance, i);
        scene_xform inv;
        if (in->mesh < 0 || (size_t)in->mesh >= s->meshes.count)
            return fail_item(err, errlen, name, "instance", i, "places a mesh that does not exist");
        if (in->material != -1 &&
            check_material_index(name, in->material, nm, "instance", i, err, errlen) != 0)
            return -1;
        if (xform_invert(&in->to_world, &inv) != 0)
            return fail_item(err, errlen, name, "instance", i,
                             "has a transform that is not finite or not invertible");
    }
    for (i = 0; i < s->polygons.count; i++) {
        const scene_polygon *p = &SCENE_AT(s->polygons, scene_polygon, i);
        int k;
        if (p->count < 3 || p->first < 0 ||
            (size_t)p->first + (size_t)p->count > s->poly_verts.count) {
            snprintf(err, errlen, "%s: polygon %zu has invalid vertices (first %d, count %d)", name,
                     i, p->first, p->count);
            return -1;
        }
        for (k = 0; k < p->count; k++)
            if (!finite3d(SCENE_AT(s->poly_verts, vec3d, p->first + k)))
                return fail_item(err, errlen, name, "polygon", i, "has non-finite values");
        if (check_material_index(name, p->material, nm, "polygon", i, err, errlen) != 0)
            return -1;
    }
    return 0;
}

/* The view part of scene_finish, on a scene whose size and depth are final: derives the
 * window from an NFF angle or a field of view, then checks the view. Messages have no
 * name prefix. */
static int finish_view(scene *s, char *err, size_t errlen)
{
    scene_camera *c = &s->camera;
    int derived = c->nff_angle_deg > 0.0f || c->fov_deg > 0.0f; /* the window, from an angle */
    if (s->width <= 0 || s->height <= 0 || s->width > CW_MAX_SIDE || s->height > CW_MAX_SIDE ||
        (long long)s->width * s->height > CW_MAX_PIXELS) {
        snprintf(err, errlen, "image size %dx%d out of range (1..%d per side, at most 2^28 pixels)",
                 s->width, s->height, CW_MAX_SIDE);
        return -1;
    }
    if (s->max_depth < 1 || s->max_depth > CW_MAX_DEPTH) {
        snprintf(err, errlen, "maximum depth %d out of range (1..%d)", s->max_depth, CW_MAX_DEPTH);
        return -1;
    }
    if (c->nff_angle_deg > 0.0f) {
        /* NFF: the angle spans the centres of the outer pixel rows; square pixels. */
        double half = tan(c->nff_angle_deg * 0.5 * 3.14159265358979323846 / 180.0);
        int rows = s->height > 1 ? s->height - 1 : 1;
        double pitch = 2.0 * half / rows;
        c->r = (float)(pitch * s->width * 0.5);
        c->l = -c->r;
        c->t = (float)(pitch * s->height * 0.5);
        c->b = -c->t;
        c->d = 1.0f;
    } else if (c->fov_deg > 0.0f) {
        double t = c->d * tan(c->fov_deg * 0.5 * 3.14159265358979323846 / 180.0);
        c->t = (float)t;
        c->b = -c->t;
        c->r = (float)(t * s->width / s->height);
        c->l = -c->r;
    }
    if (!camera_finite(c)) {
        snprintf(err, errlen, "camera has non-finite values%s",
                 derived ? " (the window derived from the angle or field of view overflows)" : "");
        return -1;
    }
    if (!(c->r > c->l) || !(c->t > c->b)) {
        snprintf(err, errlen, "camera window must have l < r and b < t%s",
                 derived ? " (the angle or field of view is too small for the image size)" : "");
        return -1;
    }
    if (c->projection == SCENE_PERSPECTIVE && !(c->d > 0.0f)) {
        snprintf(err, errlen, "perspective camera needs a positive image-plane distance");
        return -1;
    }
    if (fabsf(vec3f_length(c->u) - 1) > 1e-4f || fabsf(vec3f_length(c->v) - 1) > 1e-4f ||
        fabsf(vec3f_length(c->w) - 1) > 1e-4f || fabsf(vec3f_dot(c->u, c->v)) > 1e-4f ||
        fabsf(vec3f_dot(c->u, c->w)) > 1e-4f || fabsf(vec3f_dot(c->v, c->w)) > 1e-4f) {
        snprintf(err, errlen, "camera basis u, v, w is not orthonormal");
        return -1;
    }
    if (c->projection == SCENE_OBLIQUE) {
        if (vec3f_normalize(c->dir, &c->dir) != 0 || vec3f_dot(c->dir, c->w) >= 0.0f) {
            snprintf(err, errlen,
                     "oblique camera direction must be non-zero and point into the view (-w side)");
            return -1;
        }
    }
    return 0;
}

int scene_check_view(const scene *s, char *err, size_t errlen)
{
    scene tmp;
    scene_init(&tmp);
    tmp.camera = s->camera;
    tmp.width = s->width;
    tmp.height = s->height;
    tmp.max_depth = s->max_depth;
    return finish_view(&tmp, err, errlen);
}

int scene_finish(scene *s, int width, int height, int max_depth, char *err, size_t errlen)
{
    const char *name = s->name ? s->name : "scene";
    char msg[256];
    if (width > 0)
        s->width = width;
    if (height > 0)
        s->height = height;
    if (max_depth > 0)
        s->max_depth = max_depth;
    if (!known_projection(&s->camera))
        return scene_check(s, err, errlen); /* names the bad projection */
    if (finish_view(s, msg, sizeof msg) != 0) {
        snprintf(err, errlen, "%s: %s", name, msg);
        return -1;
    }
    /* a mesh placed once is plain triangles: only shared meshes stay instances */
    if (scene_flatten_instances(s, 0, msg, sizeof msg) != 0) {
        snprintf(err, errlen, "%s: %s", name, msg);
        return -1;
    }
    return scene_check(s, err, errlen);
}
