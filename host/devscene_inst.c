/* The second level of the kernels' BVH: meshes placed two or more times keep one copy of
 * their triangles and one tree each; each placement is a cw_instance in the top level,
 * with its transforms in float relative to the local origin (composed in double). See
 * devscene.h. */
#include "devscene.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "box.h"
#include "scene_geom.h"
#include "sys.h"
#include "xform.h"

/* Which meshes the instances place (marks[m] = 1). */
static unsigned char *placed_meshes(const scene *s)
{
    unsigned char *marks = calloc(s->meshes.count + 1, 1);
    if (!marks)
        return NULL;
    for (size_t i = 0; i < s->instances.count; i++) {
        int m = SCENE_AT(s->instances, scene_instance, i).mesh;
        if (m >= 0 && (size_t)m < s->meshes.count)
            marks[m] = 1;
    }
    return marks;
}

size_t devinst_triangles(const scene *s)
{
    size_t n = 0;
    unsigned char *marks;
    if (s->instances.count == 0)
        return 0;
    marks = placed_meshes(s);
    for (size_t m = 0; m < s->meshes.count; m++)
        if (!marks || marks[m]) /* out of memory: an upper bound */
            n += SCENE_AT(s->meshes, scene_mesh, m).count;
    free(marks);
    return n;
}

/* The triangles of mesh m relative to its centre, after the world's; their boxes. */
static int convert_mesh(const scene *s, size_t m, devscene *ds)
{
    const scene_mesh *sm = &SCENE_AT(s->meshes, scene_mesh, m);
    devscene_mesh *dm = &ds->meshes[m];
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    size_t t;
    dm->first = ds->ntri;
    dm->box_first = ds->nmesh_box;
    dm->root = -1;
    box_empty(dm->lo, dm->hi);
    for (t = sm->first; t < sm->first + sm->count; t++) {
        const scene_triangle *st = &SCENE_AT(s->mesh_tris, scene_triangle, t);
        for (int k = 0; k < 3; k++) {
            const double c[3] = {st->p[k].x, st->p[k].y, st->p[k].z};
            for (int a = 0; a < 3; a++) {
                lo[a] = fmin(lo[a], c[a]);
                hi[a] = fmax(hi[a], c[a]);
            }
        }
    }
    dm->center = vec3d_make(0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1]), 0.5 * (lo[2] + hi[2]));
    for (t = sm->first; t < sm->first + sm->count; t++) {
        const scene_triangle *st = &SCENE_AT(s->mesh_tris, scene_triangle, t);
        const vec3f *n = scene_triangle_normals(s, st);
        cw_triangle *ct = &ds->tri[ds->ntri];
        vec3f p[3];
        bvh_box b;
        for (int k = 0; k < 3; k++)
            p[k] = vec3d_diff(st->p[k], dm->center);
        if (scene_triangle_degenerate(p))
            continue;
        ct->p0 = devscene_f4(p[0], 0);
        ct->p1 = devscene_f4(p[1], 0);
        ct->p2 = devscene_f4(p[2], 0);
        ct->material = st->material;
        ct->normals = -1;
        if (n) {
            ct->normals = ds->nnorm;
            for (int k = 0; k < 3; k++)
                ds->normals[ds->nnorm++] = devscene_f4(n[k], 0);
        }
        box_empty(b.lo, b.hi);
        for (int k = 0; k < 3; k++)
            box_add_point(b.lo, b.hi, p[k].x, p[k].y, p[k].z);
        box_grow(dm->lo, dm->hi, b.lo, b.hi);
        box_widen(b.lo, b.hi, 1e-6f);
        ds->mesh_boxes[ds->nmesh_box] = b;
        ds->mesh_box_ref[ds->nmesh_box] = CW_REF(CW_PRIM_TRIANGLE, ds->ntri);
        ds->nmesh_box++;
        ds->ntri++;
    }
    dm->count = ds->ntri - dm->first;
    return 0;
}

static void rows4(cw_float4 *rows, const scene_xform *x)
{
    for (int r = 0; r < 3; r++) {
        rows[r].x = (float)x->m[4 * r];
        rows[r].y = (float)x->m[4 * r + 1];
        rows[r].z = (float)x->m[4 * r + 2];
        rows[r].w = (float)x->m[4 * r + 3];
    }
}

/* Instance i as the kernels see it, and its box (the mesh's box carried to the world) in
 * the top level. Returns 1 when added, 0 when its mesh has no triangle, -1 on error. */
static int convert_instance(const scene *s, size_t i, devscene *ds, char *err, size_t errlen)
{
    const scene_instance *in = &SCENE_AT(s->instances, scene_instance, i);
    const devscene_mesh *dm = &ds->meshes[in->mesh];
    scene_xform shift, to_world, to_mesh, tmp;
    cw_instance *ci = &ds->inst[ds->ninst];
    bvh_box b;
    if (dm->count == 0)
        return 0;
    /* mesh (less its centre) -> world -> relative to the local origin, in double */
    xform_translate(&shift, dm->center.x, dm->center.y, dm->center.z);
    xform_compose(&tmp, &in->to_world, &shift);
    xform_translate(&shift, -ds->origin.x, -ds->origin.y, -ds->origin.z);
    xform_compose(&to_world, &shift, &tmp);
    if (xform_invert(&to_world, &to_mesh) != 0) {
        snprintf(err, errlen, "instance %zu: its transform is singular", i);
        return -1;
    }
    rows4(ci->to_world, &to_world);
    rows4(ci->to_mesh, &to_mesh);
    for (int r = 0; r < 3; r++)
        if (!isfinite(ci->to_mesh[r].x) || !isfinite(ci->to_mesh[r].y) ||
            !isfinite(ci->to_mesh[r].z) || !isfinite(ci->to_mesh[r].w)) {
            snprintf(err, errlen, "instance %zu: its transform overflows single precision", i);
            return -1;
        }
    ci->root = in->mesh; /* until devinst_build puts the mesh's root node here */
    ci->material = in->material;
    ci->pad0 = ci->pad1 = 0;
    box_empty(b.lo, b.hi);
    for (int c = 0; c < 8; c++) {
        vec3d corner = vec3d_make(c & 1 ? dm->hi[0] : dm->lo[0], c & 2 ? dm->hi[1] : dm->lo[1],
                                  c & 4 ? dm->hi[2] : dm->lo[2]);
        vec3d w = xform_point(&to_world, corner);
        box_add_point(b.lo, b.hi, (float)w.x, (float)w.y, (float)w.z);
    }
    devscene_push_box(ds, &b, CW_REF(CW_PRIM_INSTANCE, ds->ninst));
    ds->ninst++;
    return 1;
}

int devinst_convert(const scene *s, devscene *ds, char *err, size_t errlen)
{
    unsigned char *marks;
    size_t m, i, nbox = devinst_triangles(s);
    if (s->instances.count == 0)
        return 0;
    marks = placed_meshes(s);
    ds->meshes = calloc(s->meshes.count + 1, sizeof *ds->meshes);
    ds->mesh_boxes = malloc((nbox + 1) * sizeof *ds->mesh_boxes);
    ds->mesh_box_ref = malloc((nbox + 1) * sizeof *ds->mesh_box_ref);
    ds->inst = sys_device_calloc(s->instances.count + 1, sizeof *ds->inst);
    if (!marks || !ds->meshes || !ds->mesh_boxes || !ds->mesh_box_ref || !ds->inst) {
        free(marks);
        snprintf(err, errlen, "out of memory for %zu mesh triangles", nbox);
        return -1;
    }
    ds->nmesh = (int)s->meshes.count;
    for (m = 0; m < s->meshes.count; m++)
        if (marks[m])
            convert_mesh(s, m, ds);
    free(marks);
    for (i = 0; i < s->instances.count; i++)
        if (convert_instance(s, i, ds, err, errlen) < 0)
            return -1;
    return 0;
}

/* Appends tree t (collapsed from b, whose refs index the mesh boxes from box_first) to
 * the combined node and reference arrays; returns its root's index, or -1 on error. */
static int append_tree(devscene *ds, const bvh *b, const bvhw *t, int box_first, char *err,
                       size_t errlen)
{
    bvhw *all = &ds->tree_wide;
    int base = all->num_nodes, rbase = ds->nrefs;
    cw_bvhw_node *nodes =
        sys_device_realloc(all->nodes, (size_t)base + (size_t)t->num_nodes, sizeof *nodes);
    if (!nodes) {
        snprintf(err, errlen, "out of memory for the meshes' BVH");
        return -1;
    }
    all->nodes = nodes;
    for (int n = 0; n < t->num_nodes; n++) {
        cw_bvhw_node nd = t->nodes[n];
        for (int i = 0; i < CW_BVH_WIDTH; i++) {
            if (nd.count[i] == 0)
                nd.child[i] += base; /* interior */
            else if (nd.count[i] > 0)
                nd.child[i] += rbase; /* leaf: its references */
        }
        nodes[base + n] = nd;
    }
    all->num_nodes += t->num_nodes;
    for (int r = 0; r < b->num_refs; r++)
        ds->refs[rbase + r] = ds->mesh_box_ref[box_first + b->refs[r]];
    ds->nrefs += b->num_refs;
    return base;
}

int devinst_build(devscene *ds, char *err, size_t errlen)
{
    unsigned char *blocks = NULL; /* all 1: a mesh's leaves hold triangles only */
    int most = 0;
    for (int m = 0; m < ds->nmesh; m++)
        most = ds->meshes[m].count > most ? ds->meshes[m].count : most;
    if (most > 0) {
        blocks = malloc((size_t)most);
        if (!blocks) {
            snprintf(err, errlen, "out of memory for a mesh's BVH");
            return -1;
        }
        memset(blocks, 1, (size_t)most);
    }
    for (int m = 0; m < ds->nmesh; m++) {
        devscene_mesh *dm = &ds->meshes[m];
        bvh b;
        bvhw t;
        int rc;
        if (dm->count == 0)
            continue;
        memset(&t, 0, sizeof t);
        if (bvh_build_blocks(&b, ds->mesh_boxes + dm->box_first, blocks, dm->count, BVH_BLOCK_TEST,
                             CW_BVH_THREADS, err, errlen) != 0) {
            free(blocks);
            return -1;
        }
        rc = bvh_collapse_wide(&b, &t, err, errlen);
        if (rc == 0 && t.stack_need > CW_BVH_STACK) {
            snprintf(
                err, errlen,
                "a mesh's BVH needs a traversal stack of %d entries, more than the kernels' %d",
                t.stack_need, CW_BVH_STACK);
            rc = -1;
        }
        if (rc == 0)
            dm->root = append_tree(ds, &b, &t, dm->box_first, err, errlen);
        bvh_free(&b);
        bvhw_free(&t);
        if (rc != 0 || dm->root < 0) {
            free(blocks);
            return -1;
        }
    }
    free(blocks);
    for (int i = 0; i < ds->ninst; i++)
        ds->inst[i].root = ds->meshes[ds->inst[i].root].root;
    free(ds->mesh_boxes);
    free(ds->mesh_box_ref);
    ds->mesh_boxes = NULL;
    ds->mesh_box_ref = NULL;
    return 0;
}
