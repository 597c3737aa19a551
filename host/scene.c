/* The scene model: growable arrays, defaults, finishing checks, reader dispatch. */
#include "scene.h"

#include <errno.h>
#include <sys/stat.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

void scene_init(scene *s)
{
    memset(s, 0, sizeof *s);
    s->max_depth = SCENE_DEFAULT_MAX_DEPTH;
    s->camera.projection = SCENE_PERSPECTIVE;
    s->camera.d = 1.0f;
}

static void array_free(scene_array *a)
{
    free(a->data);
    a->data = NULL;
    a->count = a->cap = 0;
}

void scene_free(scene *s)
{
    free(s->name);
    array_free(&s->materials);
    array_free(&s->lights);
    array_free(&s->spheres);
    array_free(&s->triangles);
    array_free(&s->polygons);
    array_free(&s->poly_verts);
    array_free(&s->cones);
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

vec3f vec3f_make(float x, float y, float z)
{
    vec3f v;
    v.x = x;
    v.y = y;
    v.z = z;
    return v;
}

vec3f vec3f_sub(vec3f a, vec3f b)
{
    return vec3f_make(a.x - b.x, a.y - b.y, a.z - b.z);
}

vec3f vec3f_cross(vec3f a, vec3f b)
{
    return vec3f_make(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x);
}

float vec3f_dot(vec3f a, vec3f b)
{
    return a.x * b.x + a.y * b.y + a.z * b.z;
}

float vec3f_length(vec3f a)
{
    return (float)sqrt((double)a.x * a.x + (double)a.y * a.y + (double)a.z * a.z);
}

int vec3f_normalize(vec3f a, vec3f *out)
{
    double len = sqrt((double)a.x * a.x + (double)a.y * a.y + (double)a.z * a.z);
    if (!(len > 0.0) || !isfinite(len))
        return -1;
    *out = vec3f_make((float)(a.x / len), (float)(a.y / len), (float)(a.z / len));
    return 0;
}

void scene_newell(const vec3f *v, int n, double out[3])
{
    int i;
    out[0] = out[1] = out[2] = 0.0;
    for (i = 0; i < n; i++) {
        vec3f a = v[i], b = v[(i + 1) % n];
        out[0] += ((double)a.y - b.y) * ((double)a.z + b.z);
        out[1] += ((double)a.z - b.z) * ((double)a.x + b.x);
        out[2] += ((double)a.x - b.x) * ((double)a.y + b.y);
    }
}

int scene_polygon_plane(const vec3f *v, int n, double normal[3], double *offset, int *axis)
{
    double len;
    int i;
    scene_newell(v, n, normal);
    len = sqrt(normal[0] * normal[0] + normal[1] * normal[1] + normal[2] * normal[2]);
    if (!(len > 0.0) || !isfinite(len))
        return -1;
    for (i = 0; i < 3; i++)
        normal[i] /= len;
    *offset = 0.0;
    for (i = 0; i < n; i++)
        *offset += normal[0] * v[i].x + normal[1] * v[i].y + normal[2] * v[i].z;
    *offset /= n;
    *axis = fabs(normal[0]) > fabs(normal[1]) ? (fabs(normal[0]) > fabs(normal[2]) ? 0 : 2)
                                              : (fabs(normal[1]) > fabs(normal[2]) ? 1 : 2);
    return 0;
}

int scene_camera_basis(scene_camera *c, vec3f view, vec3f up)
{
    vec3f w, u;
    if (vec3f_normalize(vec3f_make(-view.x, -view.y, -view.z), &w) != 0)
        return -1;
    /* up parallel to the view: the cross product vanishes (relative to the sizes) */
    {
        vec3f x = vec3f_cross(up, w);
        float ul = vec3f_length(up);
        if (!(ul > 0.0f) || !(vec3f_length(x) > 1e-6f * ul))
            return -1;
        if (vec3f_normalize(x, &u) != 0)
            return -1;
    }
    c->w = w;
    c->u = u;
    c->v = vec3f_cross(w, u);
    return 0;
}

static int finite3(vec3f a)
{
    return isfinite(a.x) && isfinite(a.y) && isfinite(a.z);
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

int scene_check(const scene *s, char *err, size_t errlen)
{
    const scene_camera *c = &s->camera;
    const char *name = s->name ? s->name : "scene";
    size_t i, nm = s->materials.count;
    if (c->projection != SCENE_PERSPECTIVE && c->projection != SCENE_ORTHOGRAPHIC &&
        c->projection != SCENE_OBLIQUE) {
        snprintf(err, errlen, "%s: unknown camera projection %d", name, (int)c->projection);
        return -1;
    }
    if (!finite3(c->eye) || !finite3(c->u) || !finite3(c->v) || !finite3(c->w) ||
        !finite3(c->dir) || !isfinite(c->l) || !isfinite(c->r) || !isfinite(c->b) ||
        !isfinite(c->t) || !isfinite(c->d) || !finite3(s->background) || !finite3(s->ambient)) {
        snprintf(err, errlen, "%s: camera, background or ambient has non-finite values", name);
        return -1;
    }
    for (i = 0; i < nm; i++) {
        const scene_material *m = &SCENE_AT(s->materials, scene_material, i);
        if (!finite3(m->ka) || !finite3(m->kd) || !finite3(m->ks) || !finite3(m->km) ||
            !isfinite(m->p)) {
            snprintf(err, errlen, "%s: material %zu has non-finite values", name, i);
            return -1;
        }
    }
    for (i = 0; i < s->lights.count; i++) {
        const scene_light *l = &SCENE_AT(s->lights, scene_light, i);
        if (!finite3(l->position) || !finite3(l->intensity)) {
            snprintf(err, errlen, "%s: light %zu has non-finite values", name, i);
            return -1;
        }
    }
    for (i = 0; i < s->spheres.count; i++) {
        const scene_sphere *sp = &SCENE_AT(s->spheres, scene_sphere, i);
        if (!finite3(sp->center) || !isfinite(sp->radius)) {
            snprintf(err, errlen, "%s: sphere %zu has non-finite values", name, i);
            return -1;
        }
        if (check_material_index(name, sp->material, nm, "sphere", i, err, errlen) != 0)
            return -1;
    }
    for (i = 0; i < s->triangles.count; i++) {
        const scene_triangle *t = &SCENE_AT(s->triangles, scene_triangle, i);
        int k;
        for (k = 0; k < 3; k++)
            if (!finite3(t->p[k]) || (t->has_normals && !finite3(t->n[k]))) {
                snprintf(err, errlen, "%s: triangle %zu has non-finite values", name, i);
                return -1;
            }
        if (t->has_normals)
            for (k = 0; k < 3; k++)
                if (!(vec3f_length(t->n[k]) > 0.0f)) {
                    snprintf(err, errlen, "%s: triangle %zu has a zero vertex normal", name, i);
                    return -1;
                }
        if (check_material_index(name, t->material, nm, "triangle", i, err, errlen) != 0)
            return -1;
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
            if (!finite3(SCENE_AT(s->poly_verts, vec3f, p->first + k))) {
                snprintf(err, errlen, "%s: polygon %zu has non-finite values", name, i);
                return -1;
            }
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
    if (s->width <= 0 || s->height <= 0 || s->width > SCENE_MAX_SIDE ||
        s->height > SCENE_MAX_SIDE || (long long)s->width * s->height > SCENE_MAX_PIXELS) {
        snprintf(err, errlen,
                 "image size %dx%d out of range (1..65536 per side, at most 2^28 pixels)", s->width,
                 s->height);
        return -1;
    }
    if (s->max_depth < 1 || s->max_depth > 64) {
        snprintf(err, errlen, "maximum depth %d out of range (1..64)", s->max_depth);
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
    if (!finite3(c->eye) || !finite3(c->u) || !finite3(c->v) || !finite3(c->w) ||
        !finite3(c->dir) || !isfinite(c->l) || !isfinite(c->r) || !isfinite(c->b) ||
        !isfinite(c->t) || !isfinite(c->d)) {
        snprintf(err, errlen, "camera has non-finite values%s",
                 c->nff_angle_deg > 0.0f || c->fov_deg > 0.0f
                     ? " (the window derived from the angle or field of view overflows)"
                     : "");
        return -1;
    }
    if (!(c->r > c->l) || !(c->t > c->b)) {
        snprintf(err, errlen, "camera window must have l < r and b < t%s",
                 c->nff_angle_deg > 0.0f || c->fov_deg > 0.0f
                     ? " (the angle or field of view is too small for the image size)"
                     : "");
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
    if (s->camera.projection != SCENE_PERSPECTIVE && s->camera.projection != SCENE_ORTHOGRAPHIC &&
        s->camera.projection != SCENE_OBLIQUE)
        return scene_check(s, err, errlen); /* names the bad projection */
    if (finish_view(s, msg, sizeof msg) != 0) {
        snprintf(err, errlen, "%s: %s", name, msg);
        return -1;
    }
    return scene_check(s, err, errlen);
}

/* Reads a whole file into a NUL-terminated buffer. */
int scene_read_file(const char *path, char **out, size_t *outlen, char *err, size_t errlen)
{
    struct stat st;
    FILE *f;
    char *buf = NULL;
    size_t len = 0, cap = 65536, want = 0;
    if (stat(path, &st) == 0) {
        if (S_ISDIR(st.st_mode)) {
            snprintf(err, errlen, "%s: cannot read: %s", path, strerror(EISDIR));
            return -1;
        }
        if (S_ISREG(st.st_mode) && st.st_size > (off_t)SCENE_MAX_FILE_BYTES) {
            snprintf(err, errlen,
                     "%s: file too large (%lld bytes; a scene file may have at most %ld)", path,
                     (long long)st.st_size, (long)SCENE_MAX_FILE_BYTES);
            return -1;
        }
        if (S_ISREG(st.st_mode) && st.st_size > 0)
            want = (size_t)st.st_size + 2; /* one read, then one more to see the end */
    }
    f = fopen(path, "rb");
    if (!f) {
        snprintf(err, errlen, "%s: cannot open: %s", path, strerror(errno));
        return -1;
    }
    if (want > cap)
        cap = want;
    for (;;) {
        size_t n;
        if (!buf || cap - len < 2) {
            char *nb;
            if (buf)
                cap *= 2;
            nb = realloc(buf, cap);
            if (!nb) {
                free(buf);
                fclose(f);
                snprintf(err, errlen, "%s: out of memory", path);
                return -1;
            }
            buf = nb;
        }
        n = fread(buf + len, 1, cap - len - 1, f);
        len += n;
        if (n == 0) {
            if (ferror(f)) {
                int e = errno;
                free(buf);
                fclose(f);
                snprintf(err, errlen, "%s: cannot read: %s", path, strerror(e));
                return -1;
            }
            break;
        }
        if (len > (size_t)SCENE_MAX_FILE_BYTES) {
            free(buf);
            fclose(f);
            snprintf(err, errlen, "%s: file too large (a scene file may have at most %ld bytes)",
                     path, (long)SCENE_MAX_FILE_BYTES);
            return -1;
        }
        if (memchr(buf + len - n, '\0', n))
            break; /* binary: the reader reports the NUL byte and its line */
    }
    fclose(f);
    buf[len] = '\0';
    *out = buf;
    *outlen = len;
    return 0;
}

/* The length of the UTF-8 sequence at u (at most avail bytes), or 0 when it is not one or
 * encodes a C1 control character. */
static size_t utf8_sequence(const unsigned char *u, size_t avail)
{
    unsigned char lo = 0x80, hi = 0xBF;
    size_t n, k;
    if (u[0] >= 0xC2 && u[0] <= 0xDF)
        n = 2;
    else if (u[0] >= 0xE0 && u[0] <= 0xEF)
        n = 3;
    else if (u[0] >= 0xF0 && u[0] <= 0xF4)
        n = 4;
    else
        return 0;
    if (u[0] == 0xC2)
        lo = 0xA0; /* U+0080..U+009F: C1 controls */
    else if (u[0] == 0xE0)
        lo = 0xA0; /* overlong */
    else if (u[0] == 0xED)
        hi = 0x9F; /* surrogates */
    else if (u[0] == 0xF0)
        lo = 0x90; /* overlong */
    else if (u[0] == 0xF4)
        hi = 0x8F; /* above U+10FFFF */
    if (n > avail)
        return 0;
    for (k = 1; k < n; k++) {
        if (u[k] < lo || u[k] > hi)
            return 0;
        lo = 0x80;
        hi = 0xBF;
    }
    return n;
}

const char *scene_single_note(double x, char *buf, size_t len)
{
    float f = (float)x;
    if (len == 0)
        return buf;
    buf[0] = '\0';
    if ((double)f != x && (f == 0.0f || fabsf(f) == 180.0f))
        snprintf(buf, len, " (%g in single precision)", (double)f);
    return buf;
}

const char *scene_printable(const char *s, size_t max, char *out, size_t outlen)
{
    size_t i = 0, o = 0;
    if (outlen == 0)
        return out;
    while (i < max && s[i] != '\0') {
        const unsigned char *u = (const unsigned char *)s + i;
        char esc[8];
        const char *piece = (const char *)u;
        size_t take = 1, n;
        if (u[0] < 0x20 || u[0] == 0x7f) {
            snprintf(esc, sizeof esc, "\\x%02X", u[0]);
            piece = esc;
        } else if (u[0] >= 0x80) {
            n = utf8_sequence(u, max - i);
            if (n == 0) {
                snprintf(esc, sizeof esc, "\\x%02X", u[0]);
                piece = esc;
            } else {
                take = n;
            }
        }
        n = piece == esc ? strlen(esc) : take;
        if (o + n + 4 > outlen) /* keep room for "..." and the NUL */
            break;
        memcpy(out + o, piece, n);
        o += n;
        i += take;
    }
    if (s[i] != '\0' && o + 4 <= outlen) { /* cut short */
        memcpy(out + o, "...", 3);
        o += 3;
    }
    out[o < outlen ? o : outlen - 1] = '\0';
    return out;
}

int scene_parse_copy(scene_text_parser parse, const char *text, size_t len, const char *name,
                     scene *s, char *err, size_t errlen)
{
    char *buf = malloc(len + 1);
    int rc;
    if (!buf) {
        snprintf(err, errlen, "%s:1: out of memory", name);
        return -1;
    }
    memcpy(buf, text, len);
    buf[len] = '\0';
    rc = parse(buf, len, name, s, err, errlen);
    free(buf);
    return rc;
}

int scene_parse_file(scene_text_parser parse, const char *path, scene *s, char *err, size_t errlen)
{
    char *buf;
    size_t len;
    int rc;
    if (scene_read_file(path, &buf, &len, err, errlen) != 0)
        return -1;
    rc = parse(buf, len, path, s, err, errlen);
    free(buf);
    return rc;
}

static int ends_with(const char *s, const char *suffix)
{
    size_t n = strlen(s), m = strlen(suffix);
    size_t i;
    if (n < m)
        return 0;
    for (i = 0; i < m; i++) {
        char a = s[n - m + i];
        if (a >= 'A' && a <= 'Z')
            a = (char)(a - 'A' + 'a');
        if (a != suffix[i])
            return 0;
    }
    return 1;
}

int scene_load(const char *path, scene *s, char *err, size_t errlen)
{
    if (ends_with(path, ".json"))
        return json_scene_load(path, s, err, errlen);
    if (ends_with(path, ".nff"))
        return nff_load(path, s, err, errlen);
    snprintf(err, errlen, "%s: unknown scene format (expected a .nff or .json file)", path);
    return -1;
}

int scene_triangle_degenerate(const scene_triangle *t)
{
    float e1x = t->p[1].x - t->p[0].x, e1y = t->p[1].y - t->p[0].y, e1z = t->p[1].z - t->p[0].z;
    float e2x = t->p[2].x - t->p[0].x, e2y = t->p[2].y - t->p[0].y, e2z = t->p[2].z - t->p[0].z;
    float cx = e1y * e2z - e1z * e2y, cy = e1z * e2x - e1x * e2z, cz = e1x * e2y - e1y * e2x;
    return cx == 0.0f && cy == 0.0f && cz == 0.0f;
}
