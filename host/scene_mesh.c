/* Meshes and their placements. See scene_mesh.h. */
#include "scene_mesh.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "xform.h"

long scene_place_mesh(scene *s, int mesh, const scene_xform *to_world, int material)
{
    scene_instance in;
    in.mesh = mesh;
    in.material = material;
    if (to_world)
        in.to_world = *to_world;
    else
        xform_identity(&in.to_world);
    return scene_push(&s->instances, &in, sizeof in);
}

int scene_instance_bounds(const scene *s, size_t i, double lo[3], double hi[3])
{
    const scene_instance *in = &SCENE_AT(s->instances, scene_instance, i);
    const scene_mesh *m = &SCENE_AT(s->meshes, scene_mesh, (size_t)in->mesh);
    if (m->count == 0)
        return -1;
    for (int a = 0; a < 3; a++) {
        lo[a] = INFINITY;
        hi[a] = -INFINITY;
    }
    for (size_t t = m->first; t < m->first + m->count; t++) {
        const scene_triangle *tr = &SCENE_AT(s->mesh_tris, scene_triangle, t);
        for (int k = 0; k < 3; k++) {
            vec3d p = xform_point(&in->to_world, tr->p[k]);
            double c[3] = {p.x, p.y, p.z};
            for (int a = 0; a < 3; a++) {
                if (c[a] < lo[a])
                    lo[a] = c[a];
                if (c[a] > hi[a])
                    hi[a] = c[a];
            }
        }
    }
    return 0;
}

/* n carried by the transform whose inverse is inv: inv's linear part transposed, times n,
 * normalised (a zero result keeps n). */
static vec3f normal_by(const scene_xform *inv, vec3f n)
{
    vec3f r;
    double v[3], len;
    for (int i = 0; i < 3; i++)
        v[i] = inv->m[i] * n.x + inv->m[4 + i] * n.y + inv->m[8 + i] * n.z;
    len = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    if (!(len > 0.0) || !isfinite(len))
        return n;
    r.x = (float)(v[0] / len);
    r.y = (float)(v[1] / len);
    r.z = (float)(v[2] / len);
    return r;
}

/* Triangle t placed by in: its vertices (in reverse order under a mirroring transform, so
 * the counter-clockwise front stays the front), its normals n (when it has them) and its
 * material. */
static void place_triangle(const scene_instance *in, const scene_xform *inv, int mirror,
                           scene_triangle *t, vec3f *n)
{
    vec3d p[3];
    vec3f nn[3];
    for (int k = 0; k < 3; k++) {
        int src = mirror ? 2 - k : k;
        p[k] = xform_point(&in->to_world, t->p[src]);
        if (n)
            nn[k] = normal_by(inv, n[src]);
    }
    for (int k = 0; k < 3; k++) {
        t->p[k] = p[k];
        if (n)
            n[k] = nn[k];
    }
    if (in->material >= 0)
        t->material = in->material;
}

static int flatten_one(scene *s, const scene_instance *in, char *err, size_t errlen)
{
    const scene_mesh *m = &SCENE_AT(s->meshes, scene_mesh, (size_t)in->mesh);
    int mirror = xform_det(&in->to_world) < 0.0;
    scene_xform inv;
    if (xform_invert(&in->to_world, &inv) != 0) {
        snprintf(err, errlen, "an instance of mesh %d has a singular transform", in->mesh);
        return -1;
    }
    for (size_t t = m->first; t < m->first + m->count; t++) {
        /* copies: pushing grows s->tri_normals, which may move */
        scene_triangle tr = SCENE_AT(s->mesh_tris, scene_triangle, t);
        const vec3f *n0 = scene_triangle_normals(s, &tr);
        vec3f n[3];
        if (n0)
            memcpy(n, n0, sizeof n);
        place_triangle(in, &inv, mirror, &tr, n0 ? n : NULL);
        if (scene_push_triangle(s, tr.p, n0 ? n : NULL, tr.material) < 0) {
            snprintf(err, errlen, "out of memory flattening an instance of mesh %d", in->mesh);
            return -1;
        }
    }
    return 0;
}

/* The common case of a mesh file given alone: one mesh, all of mesh_tris, placed once,
 * and no other triangle. Its triangles are placed where they are and become the scene's
 * triangles, without a copy (a 10M-triangle mesh would need twice its memory). */
static int flatten_alone(scene *s, char *err, size_t errlen)
{
    const scene_instance *in = &SCENE_AT(s->instances, scene_instance, 0);
    scene_mesh *m = &SCENE_AT(s->meshes, scene_mesh, 0);
    scene_array tmp;
    scene_xform inv;
    int mirror = xform_det(&in->to_world) < 0.0, ident = xform_is_identity(&in->to_world);
    if (xform_invert(&in->to_world, &inv) != 0) {
        snprintf(err, errlen, "an instance of mesh %d has a singular transform", in->mesh);
        return -1;
    }
    if (!ident || in->material >= 0)
        for (size_t t = 0; t < s->mesh_tris.count; t++) {
            scene_triangle *tr = &SCENE_AT(s->mesh_tris, scene_triangle, t);
            vec3f *n = tr->normals > 0 ? &SCENE_AT(s->tri_normals, vec3f, (size_t)(tr->normals - 1))
                                       : NULL;
            place_triangle(in, &inv, mirror, tr, n);
        }
    tmp = s->triangles;
    s->triangles = s->mesh_tris;
    s->mesh_tris = tmp;
    m->first = m->count = 0;
    s->instances.count = 0;
    return 0;
}

/* Drops the triangles of meshes that no instance places any longer (placed[m] = 0; their
 * normals stay in tri_normals, unused); frees mesh_tris when no instance is left. */
static void compact_meshes(scene *s, const int *placed)
{
    size_t kept = 0;
    for (size_t i = 0; i < s->meshes.count; i++) {
        scene_mesh *m = &SCENE_AT(s->meshes, scene_mesh, i);
        if (!placed[i]) {
            m->first = m->count = 0;
            continue;
        }
        memmove(&SCENE_AT(s->mesh_tris, scene_triangle, kept),
                &SCENE_AT(s->mesh_tris, scene_triangle, m->first),
                m->count * sizeof(scene_triangle));
        m->first = kept;
        kept += m->count;
    }
    s->mesh_tris.count = kept;
    if (kept == 0) {
        free(s->mesh_tris.data);
        s->mesh_tris.data = NULL;
        s->mesh_tris.cap = 0;
    }
}

int scene_flatten_instances(scene *s, int all, char *err, size_t errlen)
{
    size_t i, kept = 0, n = s->instances.count;
    int *uses;
    if (n == 0)
        return 0;
    uses = calloc(s->meshes.count + 1, sizeof *uses);
    if (!uses) {
        snprintf(err, errlen, "out of memory");
        return -1;
    }
    for (i = 0; i < n; i++) {
        int mesh = SCENE_AT(s->instances, scene_instance, i).mesh;
        if (mesh >= 0 && (size_t)mesh < s->meshes.count)
            uses[mesh]++;
    }
    if (n == 1 && s->meshes.count == 1 && uses[0] == 1 && s->triangles.count == 0 &&
        SCENE_AT(s->meshes, scene_mesh, 0).first == 0 &&
        SCENE_AT(s->meshes, scene_mesh, 0).count == s->mesh_tris.count) {
        free(uses);
        return flatten_alone(s, err, errlen);
    }
    for (i = 0; i < n; i++) {
        scene_instance in = SCENE_AT(s->instances, scene_instance, i);
        int bad = in.mesh < 0 || (size_t)in.mesh >= s->meshes.count; /* scene_check names it */
        if (!bad && (all || uses[in.mesh] == 1)) {
            if (flatten_one(s, &in, err, errlen) != 0) {
                free(uses);
                return -1;
            }
        } else {
            SCENE_AT(s->instances, scene_instance, kept++) = in;
        }
    }
    s->instances.count = kept;
    /* the meshes still placed: those of the instances kept (a bad index keeps them all) */
    for (i = 0; i < s->meshes.count; i++)
        uses[i] = 0;
    for (i = 0; i < kept; i++) {
        int mesh = SCENE_AT(s->instances, scene_instance, i).mesh;
        if (mesh >= 0 && (size_t)mesh < s->meshes.count)
            uses[mesh] = 1;
        else
            for (size_t m = 0; m < s->meshes.count; m++)
                uses[m] = 1;
    }
    compact_meshes(s, uses);
    free(uses);
    return 0;
}
