/* Meshes and their placements. See scene_mesh.h. */
#include "scene_mesh.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>

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

static int flatten_one(scene *s, const scene_instance *in, char *err, size_t errlen)
{
    const scene_mesh *m = &SCENE_AT(s->meshes, scene_mesh, (size_t)in->mesh);
    int mirror = xform_det(&in->to_world) < 0.0;
    for (size_t t = m->first; t < m->first + m->count; t++) {
        /* a copy: pushing may move s->mesh_tris' neighbours (tri_normals grows) */
        scene_triangle tr = SCENE_AT(s->mesh_tris, scene_triangle, t);
        const vec3f *n0 = scene_triangle_normals(s, &tr);
        vec3d p[3];
        vec3f n[3];
        for (int k = 0; k < 3; k++) {
            int src = mirror ? 2 - k : k;
            p[k] = xform_point(&in->to_world, tr.p[src]);
            if (n0 && xform_normal(&in->to_world, n0[src], &n[k]) != 0) {
                snprintf(err, errlen, "an instance of mesh %d has a singular transform", in->mesh);
                return -1;
            }
        }
        if (scene_push_triangle(s, p, n0 ? n : NULL,
                                in->material >= 0 ? in->material : tr.material) < 0) {
            snprintf(err, errlen, "out of memory flattening an instance of mesh %d", in->mesh);
            return -1;
        }
    }
    return 0;
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
    free(uses);
    return 0;
}
