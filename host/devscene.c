/* The scene as the kernels see it: the arrays of kernels/types.h built from a finished
 * scene (host/scene.h), and the BVH over all its primitives. The renderer uploads them;
 * the tests build the same arrays to run the kernels' own functions on the host. */
#include "devscene.h"

#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "box.h"
#include "polygon.h"
#include "scene_geom.h"
#include "sys.h"

#define PACK_PARTS 2               /* the packing of triangle leaves: parts, one thread each */
#define PACK_PAR_BLOCKS (1L << 16) /* fewer blocks: all parts on one thread */

/* One line per kernel buffer of kernels/world.h: where its host array is, and its length. */
#define DEVSCENE_ARRAYS(X)                                                                         \
    X(nodes, ds->tree_wide.nodes, ds->tree_wide.num_nodes)                                         \
    X(refs, ds->refs, ds->nrefs)                                                                   \
    X(spheres, ds->sph, ds->nsph)                                                                  \
    X(sphere_materials, ds->sph_mat, ds->nsph)                                                     \
    X(triangles, ds->tri, ds->ntri)                                                                \
    X(tri_blocks, ds->tri_blocks, ds->nblocks)                                                     \
    X(sph_blocks, ds->sph_blocks, ds->nsph_blocks)                                                 \
    X(normals, ds->normals, ds->nnorm)                                                             \
    X(polygons, ds->pg, ds->npg)                                                                   \
    X(poly_verts, ds->verts, ds->nverts)                                                           \
    X(poly_bands, ds->bands, ds->nbands)                                                           \
    X(cones, ds->cones, ds->ncone)                                                                 \
    X(instances, ds->inst, ds->ninst)

void devscene_world_arrays(const devscene *ds, devscene_world *w)
{
#define DEVSCENE_SET(name, data, count)                                                            \
    w->name = (data);                                                                              \
    w->n_##name = (size_t)(count);
    DEVSCENE_ARRAYS(DEVSCENE_SET)
#undef DEVSCENE_SET
}

void *devscene_take_array(devscene *ds, int which)
{
    void *taken = NULL;
#define DEVSCENE_TAKE(name, data, count)                                                           \
    case CW_WORLD_ARG_##name:                                                                      \
        taken = data;                                                                              \
        data = NULL;                                                                               \
        break;
    switch (which) {
        DEVSCENE_ARRAYS(DEVSCENE_TAKE)
    default:
        break;
    }
#undef DEVSCENE_TAKE
    return taken;
}

void devscene_free_array(devscene *ds, int which)
{
    sys_device_free(devscene_take_array(ds, which));
}

cw_float4 devscene_f4(vec3f v, float w)
{
    cw_float4 r;
    r.x = v.x;
    r.y = v.y;
    r.z = v.z;
    r.w = w;
    return r;
}

/* A world position in the kernels' coordinates: relative to the local origin, rounded to
 * float once (the difference is taken in double). */
static cw_float4 local4(const devscene *ds, vec3d p, float w)
{
    return devscene_f4(vec3d_diff(p, ds->origin), w);
}

static void find_materials(const scene *s, devscene *ft)
{
    size_t i;
    ft->mirrors = ft->transmitters = 0;
    for (i = 0; i < s->materials.count; i++) {
        const scene_material *m = &SCENE_AT(s->materials, scene_material, i);
        if (m->km.x > 0 || m->km.y > 0 || m->km.z > 0)
            ft->mirrors = 1;
        if (m->kt.x > 0 || m->kt.y > 0 || m->kt.z > 0)
            ft->transmitters = 1;
    }
}

void devscene_free(devscene *ds)
{
    /* the kernels' arrays, from the one list (the wide nodes too: bvhw_free finds none) */
#define DEVSCENE_FREE(name, data, count)                                                           \
    sys_device_free(data);                                                                         \
    data = NULL;
    DEVSCENE_ARRAYS(DEVSCENE_FREE)
#undef DEVSCENE_FREE
    free(ds->lights);
    free(ds->mats);
    free(ds->boxes);
    free(ds->box_ref);
    free(ds->meshes);
    free(ds->mesh_boxes);
    free(ds->mesh_box_ref);
    bvh_free(&ds->tree);
    bvhw_free(&ds->tree_wide);
}

/* Adds the box of primitive ref, widened by a relative margin so that rounding in the
 * kernels' intersection tests never puts a hit just outside its box. */
void devscene_push_box(devscene *ds, const bvh_box *b, int ref)
{
    bvh_box bb = *b;
    box_widen(bb.lo, bb.hi, 1e-6f);
    ds->boxes[ds->nbox] = bb;
    ds->box_ref[ds->nbox] = ref;
    ds->nbox++;
}

static int bands_push(devscene *ds, int v)
{
    if (ds->nbands == ds->bands_cap) {
        size_t cap = ds->bands_cap ? 2 * ds->bands_cap : 1024;
        int *nb = sys_device_realloc(ds->bands, cap, sizeof *nb);
        if (!nb)
            return -1;
        ds->bands = nb;
        ds->bands_cap = cap;
    }
    ds->bands[ds->nbands++] = v;
    return 0;
}

/* The band of projected coordinate y, computed exactly as the kernel computes it. */
static int band_of(const cw_polygon *pg, float y)
{
    return (int)((y - pg->band_lo) * pg->band_scale);
}

/* The bands an edge is listed in: those its range meets, and one more each side against
 * rounding, within [0, nb). */
static void edge_bands(const cw_polygon *pg, float ya, float yb, int nb, int *b0, int *b1)
{
    *b0 = band_of(pg, fminf(ya, yb)) - 1;
    *b1 = band_of(pg, fmaxf(ya, yb)) + 1;
    if (*b0 < 0)
        *b0 = 0;
    if (*b1 > nb - 1)
        *b1 = nb - 1;
}

/* Edge bands for a polygon of many vertices (its vertices already projected): the range
 * of the second projected coordinate is cut into count/4 bands, and each band lists the
 * edges whose range meets it (one band of margin each side, against rounding), so that the
 * inside test reads a few edges instead of all. A polygon whose edges would be listed too
 * often (long edges across many bands) keeps band_count 0: every edge is tested. The lists
 * are filled by counting sort: one pass to size each band, one to fill. */
static int polygon_bands(devscene *ds, cw_polygon *pg)
{
    const cw_float4 *v = &ds->verts[pg->first];
    int n = pg->count, nb = n / 4, k, b, b0, b1, total = 0, *fill;
    float lo = v[0].y, hi = v[0].y;
    size_t table, lists;

    pg->band_count = 0;
    pg->band_first = 0;
    pg->band_lo = 0.0f;
    pg->band_scale = 0.0f;
    if (n < 32)
        return 0;
    for (k = 1; k < n; k++) {
        lo = fminf(lo, v[k].y);
        hi = fmaxf(hi, v[k].y);
    }
    if (!(hi > lo))
        return 0;
    pg->band_lo = lo;
    pg->band_scale = (float)nb / (hi - lo);
    for (k = 0; k < n; k++) {
        edge_bands(pg, v[k == 0 ? n - 1 : k - 1].y, v[k].y, nb, &b0, &b1);
        total += b1 - b0 + 1;
    }
    if (total > 8 * n)
        return 0;
    /* the (first, count) table, then the lists; counts first, then prefix sums */
    table = ds->nbands;
    lists = table + 2 * (size_t)nb;
    for (b = 0; b < 2 * nb + total; b++)
        if (bands_push(ds, 0) != 0)
            return -1;
    for (k = 0; k < n; k++) {
        edge_bands(pg, v[k == 0 ? n - 1 : k - 1].y, v[k].y, nb, &b0, &b1);
        for (b = b0; b <= b1; b++)
            ds->bands[table + 2 * (size_t)b + 1]++;
    }
    for (b = 0; b < nb; b++)
        ds->bands[table + 2 * (size_t)b] =
            b == 0 ? (int)lists
                   : ds->bands[table + 2 * (size_t)b - 2] + ds->bands[table + 2 * (size_t)b - 1];
    fill = malloc((size_t)nb * sizeof *fill);
    if (!fill)
        return -1;
    for (b = 0; b < nb; b++)
        fill[b] = ds->bands[table + 2 * (size_t)b];
    for (k = 0; k < n; k++) {
        edge_bands(pg, v[k == 0 ? n - 1 : k - 1].y, v[k].y, nb, &b0, &b1);
        for (b = b0; b <= b1; b++)
            ds->bands[fill[b]++] = pg->first + k;
    }
    free(fill);
    pg->band_first = (int)table;
    pg->band_count = nb;
    return 0;
}

int devscene_convert(const scene *s, const vec3d *origin, devscene *ds, char *err, size_t errlen)
{
    size_t i, nprim = s->spheres.count + s->triangles.count + s->polygons.count + s->cones.count;
    size_t k, nmtri = devinst_triangles(s), ntop = nprim + s->instances.count;

    memset(ds, 0, sizeof *ds);
    ds->origin = origin ? *origin : vec3d_make(0, 0, 0);
    if (ntop + nmtri > (size_t)1 << 27) {
        snprintf(err, errlen,
                 "%zu primitives and instances: more than the 2^27 the renderer can address",
                 ntop + nmtri);
        return -1;
    }
    ds->sph = sys_device_calloc(s->spheres.count + 1, sizeof *ds->sph);
    ds->sph_mat = sys_device_calloc(s->spheres.count + 1, sizeof *ds->sph_mat);
    ds->tri = sys_device_calloc(s->triangles.count + nmtri + 1, sizeof *ds->tri);
    ds->normals = sys_device_calloc(s->tri_normals.count + 1, sizeof *ds->normals);
    ds->pg = sys_device_calloc(s->polygons.count + 1, sizeof *ds->pg);
    ds->verts = sys_device_calloc(s->poly_verts.count + 1, sizeof *ds->verts);
    ds->nverts = (int)s->poly_verts.count;
    ds->cones = sys_device_calloc(s->cones.count + 1, sizeof *ds->cones);
    ds->lights = calloc(s->lights.count + 1, sizeof *ds->lights);
    ds->mats = calloc(s->materials.count + 1, sizeof *ds->mats);
    ds->boxes = calloc(ntop + 1, sizeof *ds->boxes);
    ds->box_ref = calloc(ntop + 1, sizeof *ds->box_ref);
    if (!ds->sph || !ds->sph_mat || !ds->tri || !ds->normals || !ds->pg || !ds->verts ||
        !ds->cones || !ds->lights || !ds->mats || !ds->boxes || !ds->box_ref) {
        snprintf(err, errlen, "out of memory for a scene of %zu primitives", nprim);
        return -1;
    }
    for (i = 0; i < s->spheres.count; i++) {
        const scene_sphere *ss = &SCENE_AT(s->spheres, scene_sphere, i);
        float rad = fabsf(ss->radius);
        bvh_box b;
        if (!(rad > 0))
            continue; /* no surface */
        /* the radius keeps its sign: negative, the sphere is visible from inside only */
        cw_float4 c = local4(ds, ss->center, ss->radius);
        ds->sph[ds->nsph].center = c;
        ds->sph_mat[ds->nsph] = ss->material;
        box_empty(b.lo, b.hi);
        box_add_point(b.lo, b.hi, c.x - rad, c.y - rad, c.z - rad);
        box_add_point(b.lo, b.hi, c.x + rad, c.y + rad, c.z + rad);
        devscene_push_box(ds, &b, CW_REF(CW_PRIM_SPHERE, ds->nsph));
        ds->nsph++;
    }
    for (i = 0; i < s->triangles.count; i++) {
        const scene_triangle *st = &SCENE_AT(s->triangles, scene_triangle, i);
        const vec3f *n;
        vec3f p[3];
        for (k = 0; k < 3; k++)
            p[k] = vec3d_diff(st->p[k], ds->origin);
        if (scene_triangle_degenerate(p))
            continue; /* no area, no normal */
        cw_triangle *t = &ds->tri[ds->ntri];
        bvh_box b;
        box_empty(b.lo, b.hi);
        t->p0 = devscene_f4(p[0], 0);
        t->p1 = devscene_f4(p[1], 0);
        t->p2 = devscene_f4(p[2], 0);
        t->material = st->material;
        t->normals = -1;
        if ((n = scene_triangle_normals(s, st)) != NULL) {
            t->normals = ds->nnorm;
            for (k = 0; k < 3; k++)
                ds->normals[ds->nnorm++] = devscene_f4(n[k], 0);
        }
        for (k = 0; k < 3; k++)
            box_add_point(b.lo, b.hi, p[k].x, p[k].y, p[k].z);
        devscene_push_box(ds, &b, CW_REF(CW_PRIM_TRIANGLE, ds->ntri));
        ds->ntri++;
    }
    for (i = 0; i < s->poly_verts.count; i++)
        ds->verts[i] = local4(ds, SCENE_AT(s->poly_verts, vec3d, i), 0);
    for (i = 0; i < s->polygons.count; i++) {
        const scene_polygon *sp = &SCENE_AT(s->polygons, scene_polygon, i);
        const vec3d *v = &SCENE_AT(s->poly_verts, vec3d, sp->first);
        cw_polygon *pg = &ds->pg[ds->npg];
        double nn[3], off;
        int axis;
        bvh_box b;
        if (scene_polygon_plane(v, sp->count, &ds->origin, nn, &off, &axis) != 0)
            continue; /* degenerate: no area, cannot be hit */
        pg->plane.x = (float)nn[0];
        pg->plane.y = (float)nn[1];
        pg->plane.z = (float)nn[2];
        pg->plane.w = (float)off;
        pg->first = sp->first;
        pg->count = sp->count;
        pg->material = sp->material;
        pg->axis = axis;
        box_empty(b.lo, b.hi);
        { /* the kernels read the vertices projected along the dominant axis */
            int pj;
            for (pj = 0; pj < sp->count; pj++) {
                vec3f pv = vec3d_diff(v[pj], ds->origin);
                box_add_point(b.lo, b.hi, pv.x, pv.y, pv.z);
                ds->verts[sp->first + pj] = isect_polygon_vertex(v3(pv.x, pv.y, pv.z), axis);
            }
        }
        if (polygon_bands(ds, pg) != 0) {
            snprintf(err, errlen, "out of memory for polygon edge bands");
            return -1;
        }
        devscene_push_box(ds, &b, CW_REF(CW_PRIM_POLYGON, ds->npg));
        ds->npg++;
    }
    for (i = 0; i < s->cones.count; i++) {
        const scene_cone *sc = &SCENE_AT(s->cones, scene_cone, i);
        cw_cone *cn = &ds->cones[ds->ncone];
        double ax = sc->apex.x - sc->base.x, ay = sc->apex.y - sc->base.y,
               az = sc->apex.z - sc->base.z;
        double h = sqrt(ax * ax + ay * ay + az * az);
        float r0 = fabsf(sc->base_radius), r1 = fabsf(sc->apex_radius);
        float a[3], c0[3], c1[3];
        vec3f base = vec3d_diff(sc->base, ds->origin), apex = vec3d_diff(sc->apex, ds->origin);
        bvh_box b;
        if (!(h > 0) || !(r0 > 0 || r1 > 0))
            continue; /* no surface */
        a[0] = (float)(ax / h);
        a[1] = (float)(ay / h);
        a[2] = (float)(az / h);
        cn->base = devscene_f4(base, r0);
        cn->axis.x = a[0];
        cn->axis.y = a[1];
        cn->axis.z = a[2];
        cn->axis.w = (float)h;
        cn->apex_radius = r1;
        cn->slope = (r1 - r0) / cn->axis.w; /* as the kernels computed it per test */
        cn->material = sc->material;
        c0[0] = base.x;
        c0[1] = base.y;
        c0[2] = base.z;
        c1[0] = apex.x;
        c1[1] = apex.y;
        c1[2] = apex.z;
        box_empty(b.lo, b.hi);
        box_add_disc(b.lo, b.hi, c0, a, r0);
        box_add_disc(b.lo, b.hi, c1, a, r1);
        devscene_push_box(ds, &b, CW_REF(CW_PRIM_CONE, ds->ncone));
        ds->ncone++;
    }
    ds->dropped = (int)nprim - ds->nbox; /* before the instances' boxes */
    if (devinst_convert(s, ds, err, errlen) != 0)
        return -1;
    for (i = 0; i < s->lights.count; i++) {
        const scene_light *sl = &SCENE_AT(s->lights, scene_light, i);
        ds->lights[i].position = local4(ds, sl->position, 0);
        ds->lights[i].intensity = devscene_f4(sl->intensity, 0);
    }
    for (i = 0; i < s->materials.count; i++) {
        const scene_material *sm = &SCENE_AT(s->materials, scene_material, i);
        ds->mats[i].ka = devscene_f4(sm->ka, sm->p);
        ds->mats[i].kd = devscene_f4(sm->kd, 0);
        ds->mats[i].ks = devscene_f4(sm->ks, 0);
        ds->mats[i].km = devscene_f4(sm->km, 0);
        ds->mats[i].kt = devscene_f4(sm->kt, sm->ior);
    }
    find_materials(s, ds);
    return 0;
}

/* The kind of block a leaf of count references from refs[first] packs into: triangles
 * (CW_PRIM_TRIANGLE) or spheres (CW_PRIM_SPHERE) when it holds two or more of that kind
 * only, else 0 (a leaf of one stays a reference: a block of one tests no faster). */
static int leaf_block_kind(const int *refs, int first, int count)
{
    int kind;
    if (count < 2)
        return 0;
    kind = CW_REF_KIND(refs[first]);
    if (kind != CW_PRIM_TRIANGLE && kind != CW_PRIM_SPHERE)
        return 0;
    for (int k = first + 1; k < first + count; k++)
        if (CW_REF_KIND(refs[k]) != kind)
            return 0;
    return kind;
}

static void set_lane(cw_float4 *v, int lane, float x)
{
    float *f = lane == 0 ? &v->x : lane == 1 ? &v->y : lane == 2 ? &v->z : &v->w;
    *f = x;
}

/* The triangle and sphere blocks the leaves of wide nodes [n0, n1) need (see pack_nodes). */
static void count_blocks(const devscene *ds, int n0, int n1, size_t *ntb, size_t *nsb)
{
    *ntb = *nsb = 0;
    for (int n = n0; n < n1; n++)
        for (int i = 0; i < CW_BVH_WIDTH; i++) {
            int c = ds->tree_wide.nodes[n].count[i];
            int kind = c > 0 ? leaf_block_kind(ds->refs, ds->tree_wide.nodes[n].child[i], c) : 0;
            if (kind == CW_PRIM_TRIANGLE)
                *ntb += ((size_t)c + 7) / 8;
            else if (kind == CW_PRIM_SPHERE)
                *nsb += ((size_t)c + 3) / 4;
        }
}

/* Packs the c triangles of a leaf from refs[first] into blocks of eight from
 * ds->tri_blocks[b]: row r of lane i in v[2 * r + i / 4] (see cw_tri8). */
static void pack_triangles(devscene *ds, int first, int c, size_t b)
{
    for (int k = 0; k < c; k++) {
        cw_tri8 *blk = &ds->tri_blocks[b + (size_t)k / 8];
        int idx = CW_REF_INDEX(ds->refs[first + k]), lane = k % 8, half = lane / 4;
        const cw_float4 *p[3] = {&ds->tri[idx].p0, &ds->tri[idx].p1, &ds->tri[idx].p2};
        for (int v = 0; v < 3; v++) {
            set_lane(&blk->v[2 * (3 * v) + half], lane % 4, p[v]->x);
            set_lane(&blk->v[2 * (3 * v + 1) + half], lane % 4, p[v]->y);
            set_lane(&blk->v[2 * (3 * v + 2) + half], lane % 4, p[v]->z);
        }
        blk->index[lane] = idx;
        blk->material[lane] = ds->tri[idx].material;
        blk->normals[lane] = ds->tri[idx].normals;
    }
    for (int k = c; k % 8 != 0; k++)
        ds->tri_blocks[b + (size_t)k / 8].index[k % 8] = -1;
}

/* Packs the c spheres of a leaf from refs[first] into blocks from ds->sph_blocks[b]. */
static void pack_spheres(devscene *ds, int first, int c, size_t b)
{
    for (int k = 0; k < c; k++) {
        cw_sph4 *blk = &ds->sph_blocks[b + (size_t)k / 4];
        int idx = CW_REF_INDEX(ds->refs[first + k]), lane = k % 4;
        const cw_float4 *ce = &ds->sph[idx].center;
        set_lane(&blk->cx, lane, ce->x);
        set_lane(&blk->cy, lane, ce->y);
        set_lane(&blk->cz, lane, ce->z);
        set_lane(&blk->r, lane, ce->w);
        blk->index[lane] = idx;
        blk->material[lane] = ds->sph_mat[idx];
    }
    for (int k = c; k % 4 != 0; k++)
        ds->sph_blocks[b + (size_t)k / 4].index[k % 4] = -1;
}

/* Packs the leaves of wide nodes [n0, n1) into blocks from ds->tri_blocks[tb] and
 * ds->sph_blocks[sb] on. */
static void pack_nodes(devscene *ds, int n0, int n1, size_t tb, size_t sb)
{
    for (int n = n0; n < n1; n++)
        for (int i = 0; i < CW_BVH_WIDTH; i++) {
            cw_bvhw_node *nd = &ds->tree_wide.nodes[n];
            int c = nd->count[i], first = nd->child[i];
            int kind = c > 0 ? leaf_block_kind(ds->refs, first, c) : 0, nb;
            if (kind == CW_PRIM_TRIANGLE) {
                nb = (c + 7) / 8;
                pack_triangles(ds, first, c, tb);
                nd->child[i] = (int)tb;
                nd->count[i] = -1 - nb;
                tb += (size_t)nb;
            } else if (kind == CW_PRIM_SPHERE) {
                nb = (c + 3) / 4;
                pack_spheres(ds, first, c, sb);
                nd->child[i] = (int)sb;
                nd->count[i] = -1 - (nb | CW_LEAF_SPHERES);
                sb += (size_t)nb;
            }
        }
}

/* One part of the packing: wide nodes [n0, n1), their blocks from tb and sb on. */
typedef struct {
    devscene *ds;
    int n0, n1;
    size_t tb, sb;
} pack_part;

static void *pack_part_run(void *arg)
{
    pack_part *pp = arg;
    pack_nodes(pp->ds, pp->n0, pp->n1, pp->tb, pp->sb);
    return NULL;
}

/* Packs every leaf of two or more triangles only, or two or more spheres only, into blocks
 * (of eight triangles, cw_tri8, or four spheres, cw_sph4; in leaf order, so the kernels
 * test them in the order of the references) and points the leaf at its blocks. A leaf of one
 * primitive stays a reference: a block of one would test no faster and cost more memory. The nodes
 * are cut into PACK_PARTS ranges, each counted, then packed on its own thread where the scene is
 * big (the same blocks as one pass in order). */
static int pack_leaves(devscene *ds, char *err, size_t errlen)
{
    pack_part part[PACK_PARTS];
    pthread_t tid[PACK_PARTS];
    int started[PACK_PARTS] = {0}, nn = ds->tree_wide.num_nodes, threaded;
    size_t ntb = 0, nsb = 0;
    for (int k = 0; k < PACK_PARTS; k++) {
        size_t t, sp;
        part[k].ds = ds;
        part[k].n0 = (int)((long long)nn * k / PACK_PARTS);
        part[k].n1 = (int)((long long)nn * (k + 1) / PACK_PARTS);
        part[k].tb = ntb;
        part[k].sb = nsb;
        count_blocks(ds, part[k].n0, part[k].n1, &t, &sp);
        ntb += t;
        nsb += sp;
    }
    if (ntb == 0 && nsb == 0)
        return 0;
    if (ntb > 0 && !(ds->tri_blocks = sys_device_calloc(ntb, sizeof *ds->tri_blocks))) {
        snprintf(err, errlen, "out of memory for %zu triangle blocks", ntb);
        return -1;
    }
    if (nsb > 0 && !(ds->sph_blocks = sys_device_calloc(nsb, sizeof *ds->sph_blocks))) {
        snprintf(err, errlen, "out of memory for %zu sphere blocks", nsb);
        return -1;
    }
    threaded = ntb + nsb >= PACK_PAR_BLOCKS;
    for (int k = 1; k < PACK_PARTS; k++)
        started[k] = threaded && pthread_create(&tid[k], NULL, pack_part_run, &part[k]) == 0;
    for (int k = 0; k < PACK_PARTS; k++)
        if (!started[k])
            pack_part_run(&part[k]);
    for (int k = 1; k < PACK_PARTS; k++)
        if (started[k])
            pthread_join(tid[k], NULL);
    ds->nblocks = (int)ntb;
    ds->nsph_blocks = (int)nsb;
    return 0;
}

/* Builds the BVH over the primitives' boxes, collapses it to the wide tree the kernels
 * traverse, turns its leaf entries into CW_REFs and packs the leaves of triangles only. */
int devscene_build_bvh(devscene *ds, char *err, size_t errlen)
{
    int i, rc;
    /* triangles (class 1) and spheres (class 2) are kept in blocks in a leaf of one kind
     * only (pack_leaves) and tested BVH_BLOCK_TEST at a time */
    unsigned char *blocks = malloc(ds->nbox > 0 ? (size_t)ds->nbox : 1);
    if (!blocks) {
        snprintf(err, errlen, "out of memory for the BVH");
        return -1;
    }
    for (i = 0; i < ds->nbox; i++)
        blocks[i] = CW_REF_KIND(ds->box_ref[i]) == CW_PRIM_TRIANGLE ? 1
                    : CW_REF_KIND(ds->box_ref[i]) == CW_PRIM_SPHERE ? 2
                                                                    : 0;
    /* the builder frees the boxes once it has its own copy */
    rc = bvh_build_blocks_take(&ds->tree, &ds->boxes, blocks, ds->nbox, BVH_BLOCK_TEST,
                               CW_BVH_THREADS, err, errlen);
    free(blocks);
    if (rc != 0)
        return -1;
    if (bvh_collapse_wide(&ds->tree, &ds->tree_wide, err, errlen) != 0)
        return -1;
    if (ds->tree_wide.stack_need > CW_BVH_STACK) {
        snprintf(err, errlen,
                 "the BVH needs a traversal stack of %d entries, more than the kernels' %d",
                 ds->tree_wide.stack_need, CW_BVH_STACK);
        return -1;
    }
    { /* the leaf entries become CW_REFs in place, with room for the meshes' after them */
        size_t room = (size_t)ds->tree.num_refs + (size_t)ds->nmesh_box + 1;
        int *grown;
        for (i = 0; i < ds->tree.num_refs; i++)
            ds->tree.refs[i] = ds->box_ref[ds->tree.refs[i]];
        grown = sys_device_calloc(room, sizeof *ds->refs);
        if (!grown) {
            snprintf(err, errlen, "out of memory for the BVH");
            return -1;
        }
        if (ds->tree.num_refs > 0) /* an empty scene's tree has no array */
            memcpy(grown, ds->tree.refs, (size_t)ds->tree.num_refs * sizeof *ds->refs);
        free(ds->tree.refs);
        ds->refs = grown;
        ds->tree.refs = NULL;
    }
    ds->nrefs = ds->tree.num_refs;
    /* only the kernels' arrays stay: the binary tree and the box map have served */
    free(ds->box_ref);
    ds->box_ref = NULL;
    free(ds->tree.nodes);
    ds->tree.nodes = NULL;
    if (devinst_build(ds, err, errlen) != 0)
        return -1;
    return pack_leaves(ds, err, errlen);
}
