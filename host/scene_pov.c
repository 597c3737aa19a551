/* Export of a finished scene as POV-Ray 3.7 SDL with the clwhitted shading model.
 *
 * POV-Ray 3.7 facts this relies on (source: core/render/trace.cpp, tracepixel.cpp,
 * core/shape/triangle.cpp, polygon.cpp, parser/parser_materials.cpp; each confirmed by
 * renders compared with a hand-written reference tracer to within 16-bit quantisation):
 *
 * Camera. A perspective ray is direction + (x/W - 0.5) right + (0.5 - y/H) up, from
 *   location, with x = column + 0.5 and y = row + 0.5 (row 0 at the top): pixel centres.
 *   An orthographic ray starts at location + (x/W - 0.5) right + (0.5 - y/H) up and goes
 *   along direction; the parser leaves explicit vectors alone (it only warns when they
 *   are not perpendicular), so a direction that is not perpendicular to right and up
 *   gives our oblique projection. Without look_at nothing depends on handedness: the
 *   image is not mirrored.
 * Shading of one texture layer (ComputeLightedTexture / ComputeOneDiffuseLight):
 *   pigment x finish ambient (a colour in 3.7) x ambient_light x opacity
 *   + pigment x emission x opacity
 *   + per light that is not blocked and has n.l >= 1e-10:
 *       pigment x diffuse x opacity x I x n.l            (brilliance 1)
 *     + specular x I x (n.h)^Roughness                    (h = normalised l + v, no
 *       normalisation factor; Roughness = 1/roughness as written, inverted at parse)
 *   where n is the normal turned towards the incoming ray. A light with n.l < 1e-10
 *   contributes nothing, specular included; shadow rays ignore occluders closer than
 *   1e-3 to either end. Layers are listed bottom first in SDL; a layer's contribution
 *   is multiplied by the product of the transmitted colours (colour x filter +
 *   transmit) of the layers above it, and its ambient/emission/diffuse (not specular)
 *   by its own opacity 1 - filter - transmit.
 * Reflection. reflection { rgb C } sets min = max = C, falloff 1, no fresnel, no
 *   metallic: it adds C x traced colour, untouched by anything else (not by the
 *   layer's opacity nor by the layers above). The mirror ray is traced from the hit
 *   point about the shading normal. A ray at trace level >= max_trace_level (the eye
 *   ray is level 1) returns black; with adc_bailout 0 no ray is cut for low weight.
 * Misses return the background colour, for mirror rays as well.
 * Light sources: point lights without fade_distance/fade_power are not attenuated.
 * Smooth triangles: POV-Ray normalises the vertex normals and interpolates
 *   barycentrically, like the renderer; but a stand-alone smooth_triangle whose vertex
 *   normals do not all lie on one side of the face is dropped as degenerate, so all
 *   triangles are written inside mesh { } objects, which keep them.
 * Polygons: POV-Ray drops a polygon whose points are off its plane by more than 1e-10
 *   (absolute), which float coordinates often are. The points are therefore moved onto
 *   the renderer's plane (Newell normal through the vertex average) along the plane's
 *   dominant axis, which keeps the renderer's inside test (it drops that axis) exact.
 */
#include "scene_pov.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "scene_geom.h"

/* transmit of the upper layers of a layered material (see write_layered) */
#define POV_LAYER_T 0.5

static int is_zero3(vec3f a)
{
    return a.x == 0.0f && a.y == 0.0f && a.z == 0.0f;
}

static float comp(vec3f a, int k)
{
    return k == 0 ? a.x : (k == 1 ? a.y : a.z);
}

/* floats are written with 9 significant digits, which round-trips them exactly */
static void put3(FILE *f, vec3f a)
{
    fprintf(f, "<%.9g, %.9g, %.9g>", (double)a.x, (double)a.y, (double)a.z);
}

/* positions (double) with 17, which round-trips them exactly */
static void putp3(FILE *f, vec3d a)
{
    fprintf(f, "<%.17g, %.17g, %.17g>", a.x, a.y, a.z);
}

static void putd3(FILE *f, const double *a)
{
    fprintf(f, "<%.17g, %.17g, %.17g>", a[0], a[1], a[2]);
}

static void roughness(FILE *f, float p)
{
    /* POV-Ray stores 1/roughness as the exponent; roughness 0 is kept as exponent 0
     * (with a warning), which is what p = 0 means. */
    if (p == 0.0f)
        fprintf(f, " roughness 0");
    else
        fprintf(f, " roughness %.17g", 1.0 / (double)p);
}

/* Single layer: pigment kd, diffuse 1, ambient ka/kd per channel, specular ks (grey). */
static int material_is_simple(const scene_material *m)
{
    int k;
    if (m->ks.x != m->ks.y || m->ks.x != m->ks.z)
        return 0;
    for (k = 0; k < 3; k++)
        if (comp(m->kd, k) == 0.0f && comp(m->ka, k) != 0.0f)
            return 0;
    return 1;
}

static int transmits(const scene_material *m)
{
    return !is_zero3(m->kt);
}

/* Transmission (kt > 0, with refraction) is written as POV-Ray's: pigment transmit T and an
 * interior ior. POV-Ray's model differs from clwhitted's there (it scales the local
 * shading by the opacity 1 - T and lets light through transmitting objects to shadows),
 * so such scenes are equivalent in work, not identical in pixels. */
static void write_simple(FILE *f, const scene_material *m)
{
    fprintf(f, "  texture {\n    pigment { %s ", transmits(m) ? "rgbt" : "rgb");
    if (transmits(m))
        fprintf(f, "<%.9g, %.9g, %.9g, %.9g>", (double)m->kd.x, (double)m->kd.y, (double)m->kd.z,
                (double)m->kt.x);
    else
        put3(f, m->kd);
    /* ambient is written as the exact quotient in double precision */
    fprintf(f, " }\n    finish {\n      ambient rgb <%.17g, %.17g, %.17g> emission 0\n",
            m->kd.x != 0.0f ? (double)m->ka.x / m->kd.x : 0.0,
            m->kd.y != 0.0f ? (double)m->ka.y / m->kd.y : 0.0,
            m->kd.z != 0.0f ? (double)m->ka.z / m->kd.z : 0.0);
    fprintf(f, "      diffuse 1 brilliance 1\n      specular %.9g", (double)m->ks.x);
    if (m->ks.x != 0.0f)
        roughness(f, m->p);
    fprintf(f, "\n");
    if (!is_zero3(m->km)) {
        fprintf(f, "      reflection { rgb ");
        put3(f, m->km);
        fprintf(f, " }\n");
    }
    fprintf(f, "    }\n  }\n");
}

/* Any ka, kd, ks, km per channel, with layers (top first, T = POV_LAYER_T):
 *   A  pigment rgbt <ka, T>, ambient 1/(1-T), reflection km       -> ka Ia, km x mirror
 *   D  pigment rgbt <kd, T>, diffuse 1/((1-T) T)                   -> kd I n.l
 *   F  pigment rgbf <ks/S, 1>, nothing else (S = largest |ks|)     -> filters what is below
 *   S  pigment rgb 0 (opaque), specular S/T^2, roughness 1/p       -> ks I (n.h)^p
 * D's contribution is scaled by its opacity 1-T and by A's transmission T; S's by the
 * transmission T T ks/S above it (specular ignores the own opacity). Without specular,
 * D is the opaque bottom layer (diffuse 1/T). The bottom layer is opaque, so nothing
 * is transmitted and shadows are full. */
static void write_layered(FILE *f, const scene_material *m)
{
    const double t = POV_LAYER_T;
    int spec = !is_zero3(m->ks);
    if (spec) {
        double s = fabs((double)m->ks.x);
        if (fabs((double)m->ks.y) > s)
            s = fabs((double)m->ks.y);
        if (fabs((double)m->ks.z) > s)
            s = fabs((double)m->ks.z);
        fprintf(f,
                "  texture { // S: specular, below the ks filter\n"
                "    pigment { rgb 0 }\n"
                "    finish { ambient 0 emission 0 diffuse 0 specular %.17g",
                s / (t * t));
        roughness(f, m->p);
        fprintf(f, " }\n  }\n");
        fprintf(f,
                "  texture { // F: filters the specular layer by ks/S\n"
                "    pigment { rgbf <%.17g, %.17g, %.17g, 1> }\n"
                "    finish { ambient 0 emission 0 diffuse 0 specular 0 }\n  }\n",
                m->ks.x / s, m->ks.y / s, m->ks.z / s);
        fprintf(f, "  texture { // D: diffuse\n    pigment { rgbt <%.9g, %.9g, %.9g, %.17g> }\n",
                (double)m->kd.x, (double)m->kd.y, (double)m->kd.z, t);
        fprintf(f,
                "    finish { ambient 0 emission 0 diffuse %.17g brilliance 1 specular 0 }\n  }\n",
                1.0 / ((1.0 - t) * t));
    } else {
        fprintf(f, "  texture { // D: diffuse (opaque bottom layer)\n    pigment { rgb ");
        put3(f, m->kd);
        fprintf(
            f,
            " }\n    finish { ambient 0 emission 0 diffuse %.17g brilliance 1 specular 0 }\n  }\n",
            1.0 / t);
    }
    fprintf(
        f, "  texture { // A: ambient and mirror\n    pigment { rgbt <%.9g, %.9g, %.9g, %.17g> }\n",
        (double)m->ka.x, (double)m->ka.y, (double)m->ka.z, t);
    fprintf(f, "    finish { ambient %.17g emission 0 diffuse 0 specular 0", 1.0 / (1.0 - t));
    if (!is_zero3(m->km)) {
        fprintf(f, " reflection { rgb ");
        put3(f, m->km);
        fprintf(f, " }");
    }
    fprintf(f, " }\n  }\n");
}

/* v moved along the dominant axis onto the plane nn.x = off */
static void onto_plane(vec3d v, const double nn[3], double off, int axis, double out[3])
{
    double rest = 0.0;
    int k;
    out[0] = v.x;
    out[1] = v.y;
    out[2] = v.z;
    for (k = 0; k < 3; k++)
        if (k != axis)
            rest += nn[k] * out[k];
    out[axis] = (off - rest) / nn[axis];
}

static int triangle_has_area(const scene_triangle *t)
{
    double e1[3], e2[3], c[3];
    e1[0] = (double)t->p[1].x - t->p[0].x;
    e1[1] = (double)t->p[1].y - t->p[0].y;
    e1[2] = (double)t->p[1].z - t->p[0].z;
    e2[0] = (double)t->p[2].x - t->p[0].x;
    e2[1] = (double)t->p[2].y - t->p[0].y;
    e2[2] = (double)t->p[2].z - t->p[0].z;
    c[0] = e1[1] * e2[2] - e1[2] * e2[1];
    c[1] = e1[2] * e2[0] - e1[0] * e2[2];
    c[2] = e1[0] * e2[1] - e1[1] * e2[0];
    return c[0] != 0.0 || c[1] != 0.0 || c[2] != 0.0;
}

/* The exporter needs a finished, consistent scene: scene_check plus the size. */
static int check_scene(const scene *s, char *err, size_t errlen)
{
    if (s->width <= 0 || s->height <= 0 || s->max_depth < 1) {
        snprintf(err, errlen,
                 "scene is not finished (size %dx%d, depth %d): call scene_finish first", s->width,
                 s->height, s->max_depth);
        return -1;
    }
    return scene_check(s, err, errlen);
}

static void write_camera(FILE *f, const scene_camera *c)
{
    /* The window centre and size, in the u, v basis. */
    double cu = 0.5 * ((double)c->l + c->r), cv = 0.5 * ((double)c->b + c->t);
    double su = (double)c->r - c->l, sv = (double)c->t - c->b;
    double u[3], v[3], w[3], e[3], right[3], up[3], dir[3], loc[3];
    int k;
    u[0] = c->u.x, u[1] = c->u.y, u[2] = c->u.z;
    v[0] = c->v.x, v[1] = c->v.y, v[2] = c->v.z;
    w[0] = c->w.x, w[1] = c->w.y, w[2] = c->w.z;
    e[0] = c->eye.x, e[1] = c->eye.y, e[2] = c->eye.z;
    for (k = 0; k < 3; k++) {
        right[k] = su * u[k];
        up[k] = sv * v[k];
    }
    if (c->projection == SCENE_PERSPECTIVE) {
        /* ray(i, j) = (l + (r-l)(i+0.5)/nx) u + (b + (t-b)(j+0.5)/ny) v - d w */
        for (k = 0; k < 3; k++) {
            loc[k] = e[k];
            dir[k] = cu * u[k] + cv * v[k] - (double)c->d * w[k];
        }
        fprintf(f, "camera {\n  perspective\n");
    } else {
        /* origin(i, j) = eye + (l + (r-l)(i+0.5)/nx) u + (b + (t-b)(j+0.5)/ny) v */
        for (k = 0; k < 3; k++)
            loc[k] = e[k] + cu * u[k] + cv * v[k];
        if (c->projection == SCENE_ORTHOGRAPHIC) {
            for (k = 0; k < 3; k++)
                dir[k] = -w[k];
            fprintf(f, "camera {\n  orthographic\n");
        } else {
            dir[0] = c->dir.x, dir[1] = c->dir.y, dir[2] = c->dir.z;
            fprintf(f, "camera {\n  // oblique: an orthographic camera with a slanted direction\n"
                       "  // (POV-Ray warns that the camera vectors are not perpendicular)\n"
                       "  orthographic\n");
        }
    }
    fprintf(f, "  location ");
    putd3(f, loc);
    fprintf(f, "\n  right ");
    putd3(f, right);
    fprintf(f, "\n  up ");
    putd3(f, up);
    fprintf(f, "\n  direction ");
    putd3(f, dir);
    fprintf(f, "\n}\n\n");
}

/* " texture { CW_Mn }" and, for transmitting materials, " interior { ior X }" */
static void write_material_ref(FILE *f, const scene *s, int mat)
{
    const scene_material *m = &SCENE_AT(s->materials, scene_material, (size_t)mat);
    fprintf(f, " texture { CW_M%d }", mat);
    if (transmits(m) && material_is_simple(m))
        fprintf(f, " interior { ior %.9g }", m->ior > 0 ? (double)m->ior : 1.0);
}

static void write_cones(FILE *f, const scene *s)
{
    size_t i;
    for (i = 0; i < s->cones.count; i++) {
        const scene_cone *c = &SCENE_AT(s->cones, scene_cone, i);
        fprintf(f, "cone { ");
        putp3(f, c->base);
        fprintf(f, ", %.9g, ", fabs((double)c->base_radius));
        putp3(f, c->apex);
        fprintf(f, ", %.9g open", fabs((double)c->apex_radius));
        write_material_ref(f, s, c->material);
        fprintf(f, " }\n");
    }
}

static void write_triangles(FILE *f, const scene *s, size_t *skipped)
{
    size_t i = 0, n = s->triangles.count;
    *skipped = 0;
    /* one mesh per run of triangles with the same material */
    while (i < n) {
        int mat = SCENE_AT(s->triangles, scene_triangle, i).material;
        size_t j, end = i;
        int any = 0, k;
        while (end < n && SCENE_AT(s->triangles, scene_triangle, end).material == mat)
            end++;
        for (j = i; j < end; j++) {
            const scene_triangle *t = &SCENE_AT(s->triangles, scene_triangle, j);
            const vec3f *nrm = scene_triangle_normals(s, t);
            if (!triangle_has_area(t)) {
                (*skipped)++;
                continue;
            }
            if (!any)
                fprintf(f, "mesh {\n");
            any = 1;
            /* triangle { p0, p1, p2 } or smooth_triangle { p0, n0, p1, n1, p2, n2 } */
            fprintf(f, "  %s { ", nrm ? "smooth_triangle" : "triangle");
            for (k = 0; k < 3; k++) {
                if (k > 0)
                    fprintf(f, ", ");
                putp3(f, t->p[k]);
                if (nrm) {
                    fprintf(f, ", ");
                    put3(f, nrm[k]);
                }
            }
            fprintf(f, " }\n");
        }
        if (any) {
            fprintf(f, " ");
            write_material_ref(f, s, mat);
            fprintf(f, "\n}\n");
        }
        i = end;
    }
}

static void write_polygons(FILE *f, const scene *s, size_t *skipped)
{
    size_t i;
    *skipped = 0;
    for (i = 0; i < s->polygons.count; i++) {
        const scene_polygon *p = &SCENE_AT(s->polygons, scene_polygon, i);
        const vec3d *v = &SCENE_AT(s->poly_verts, vec3d, p->first);
        double nn[3], off, q[3];
        int axis, k;
        if (scene_polygon_plane(v, p->count, NULL, nn, &off, &axis) != 0) {
            (*skipped)++; /* no area: the renderer leaves it out as well */
            continue;
        }
        /* the first point again closes the polygon (POV-Ray's convention) */
        fprintf(f, "polygon { %d", p->count + 1);
        for (k = 0; k <= p->count; k++) {
            onto_plane(v[k % p->count], nn, off, axis, q);
            fprintf(f, ",\n  ");
            putd3(f, q);
        }
        fprintf(f, "\n ");
        write_material_ref(f, s, p->material);
        fprintf(f, "\n}\n");
    }
}

int pov_write_scene(const scene *s, FILE *f, char *err, size_t errlen)
{
    size_t i, nm = s->materials.count, tri_skipped, poly_skipped;
    int any_kt = 0;
    char cmd[512];

    if (check_scene(s, err, errlen) != 0)
        return -1;
    if (s->instances.count > 0) {
        snprintf(err, errlen,
                 "the scene still places meshes: flatten its instances first "
                 "(scene_flatten_instances)");
        return -1;
    }
    pov_command_line(s, "SCENE.pov", "SCENE.png", cmd, sizeof cmd);
    fprintf(f,
            "// clwhitted scene \"%s\" as POV-Ray 3.7 scene description (written by scene2pov).\n"
            "// Same model as clwhitted: Blinn-Phong with hard shadows, ideal mirrors, no light\n"
            "// attenuation, %dx%d pixels, maximum ray depth %d. Render it at exactly this size,\n"
            "// without anti-aliasing, to linear 16-bit PNG:\n//   %s\n\n",
            s->name ? s->name : "scene", s->width, s->height, s->max_depth, cmd);
    fprintf(f, "#version 3.7;\n\nglobal_settings {\n  assumed_gamma 1.0\n  ambient_light rgb ");
    put3(f, s->ambient);
    fprintf(f, "\n  max_trace_level %d // the eye ray is level 1\n  adc_bailout 0\n}\n\n",
            s->max_depth);
    fprintf(f, "background { color rgb ");
    put3(f, s->background);
    fprintf(f, " }\n\n");
    write_camera(f, &s->camera);

    for (i = 0; i < s->lights.count; i++) {
        const scene_light *l = &SCENE_AT(s->lights, scene_light, i);
        fprintf(f, "light_source { ");
        putp3(f, l->position);
        fprintf(f, ", color rgb ");
        put3(f, l->intensity);
        fprintf(f, " }\n");
    }
    if (s->lights.count)
        fprintf(f, "\n");

    for (i = 0; i < nm; i++) {
        const scene_material *m = &SCENE_AT(s->materials, scene_material, i);
        fprintf(f, "// material %zu: ka ", i);
        put3(f, m->ka);
        fprintf(f, " kd ");
        put3(f, m->kd);
        fprintf(f, " ks ");
        put3(f, m->ks);
        fprintf(f, " km ");
        put3(f, m->km);
        fprintf(f, " p %.9g\n", (double)m->p);
        if (!is_zero3(m->kt))
            any_kt = 1;
        fprintf(f, "#declare CW_M%zu =\n", i);
        if (material_is_simple(m))
            write_simple(f, m);
        else
            write_layered(f, m);
        fprintf(f, "\n");
    }
    if (any_kt)
        fprintf(f, "// transmission: POV-Ray's transmit + interior ior (see write_simple in "
                   "scene_pov.c)\n\n");

    for (i = 0; i < s->spheres.count; i++) {
        const scene_sphere *sp = &SCENE_AT(s->spheres, scene_sphere, i);
        /* POV-Ray has no one-sided sphere: an inside-only one (negative radius) is written
         * as an ordinary sphere, exact for every ray that starts inside it (a camera and
         * lights inside, as in a sky dome), but seen from outside it hides what is behind */
        if (sp->radius < 0)
            fprintf(f, "// visible from inside only in the scene: the same from inside\n");
        fprintf(f, "sphere { ");
        putp3(f, sp->center);
        fprintf(f, ", %.9g", fabs((double)sp->radius));
        write_material_ref(f, s, sp->material);
        fprintf(f, " }\n");
    }
    write_triangles(f, s, &tri_skipped);
    write_polygons(f, s, &poly_skipped);
    if (tri_skipped || poly_skipped)
        fprintf(f, "// left out without area: %zu triangle(s), %zu polygon(s)\n", tri_skipped,
                poly_skipped);
    write_cones(f, s);
    if (fflush(f) != 0 || ferror(f)) {
        snprintf(err, errlen, "write error");
        return -1;
    }
    return 0;
}

/* s in single quotes for the shell, into dst (truncated to dlen). */
static void shell_quote(char *dst, size_t dlen, const char *s)
{
    size_t n = 0;
    const char *p;
    if (dlen < 3) {
        if (dlen)
            dst[0] = '\0';
        return;
    }
    dst[n++] = '\'';
    for (p = s; *p && n + 5 < dlen; p++) {
        if (*p == '\'') {
            memcpy(dst + n, "'\\''", 4); /* close, escaped quote, reopen */
            n += 4;
        } else {
            dst[n++] = *p;
        }
    }
    dst[n++] = '\'';
    dst[n] = '\0';
}

int pov_command_line(const scene *s, const char *pov_path, const char *out_path, char *buf,
                     size_t len)
{
    char opt[4096], in_q[8200], out_q[8200];
    snprintf(opt, sizeof opt, "+I%s", pov_path);
    shell_quote(in_q, sizeof in_q, opt);
    snprintf(opt, sizeof opt, "+O%s", out_path);
    shell_quote(out_q, sizeof out_q, opt);
    return snprintf(buf, len, "povray %s %s +W%d +H%d -D -A +Q9 +FN16 File_Gamma=1.0", in_q, out_q,
                    s->width, s->height);
}
