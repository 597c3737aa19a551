/* Geometry on the scene model: vectors, polygon normals and planes, the zero-area rule,
 * degenerate triangles, the camera basis. See scene_geom.h. */
#include "scene_geom.h"

#include <math.h>
#include <string.h>

/* The zero-area rule's threshold, relative to the squared size of the polygon. */
#define SCENE_ZERO_AREA 1e-12

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

vec3d vec3d_make(double x, double y, double z)
{
    vec3d v;
    v.x = x;
    v.y = y;
    v.z = z;
    return v;
}

vec3d vec3d_add_scaled(vec3d a, vec3f d, double s)
{
    return vec3d_make(a.x + s * d.x, a.y + s * d.y, a.z + s * d.z);
}

vec3d vec3d_sub(vec3d a, vec3d b)
{
    return vec3d_make(a.x - b.x, a.y - b.y, a.z - b.z);
}

vec3f vec3d_diff(vec3d a, vec3d b)
{
    return vec3f_make((float)(a.x - b.x), (float)(a.y - b.y), (float)(a.z - b.z));
}

/* Adds the edge a -> b to Newell's sums. */
static void newell_edge(double n[3], vec3d a, vec3d b)
{
    n[0] += ((double)a.y - b.y) * ((double)a.z + b.z);
    n[1] += ((double)a.z - b.z) * ((double)a.x + b.x);
    n[2] += ((double)a.x - b.x) * ((double)a.y + b.y);
}

static double length3(const double n[3])
{
    return sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
}

static vec3d relative(vec3d v, const vec3d *origin)
{
    return origin ? vec3d_sub(v, *origin) : v;
}

void scene_newell(const vec3d *v, int n, const vec3d *origin, double out[3])
{
    int i;
    out[0] = out[1] = out[2] = 0.0;
    for (i = 0; i < n; i++)
        newell_edge(out, relative(v[i], origin), relative(v[(i + 1) % n], origin));
}

int scene_polygon_plane(const vec3d *v, int n, const vec3d *origin, double normal[3],
                        double *offset, int *axis)
{
    double len;
    int i;
    scene_newell(v, n, origin, normal);
    len = length3(normal);
    if (!(len > 0.0) || !isfinite(len))
        return -1;
    for (i = 0; i < 3; i++)
        normal[i] /= len;
    *offset = 0.0;
    for (i = 0; i < n; i++) {
        vec3d p = relative(v[i], origin);
        *offset += normal[0] * p.x + normal[1] * p.y + normal[2] * p.z;
    }
    *offset /= n;
    *axis = fabs(normal[0]) > fabs(normal[1]) ? (fabs(normal[0]) > fabs(normal[2]) ? 0 : 2)
                                              : (fabs(normal[1]) > fabs(normal[2]) ? 1 : 2);
    return 0;
}

void scene_area_init(scene_area *a)
{
    int k;
    for (k = 0; k < 3; k++) /* field by field: a memset costs more, once per polygon */
        a->normal[k] = a->lo[k] = a->hi[k] = 0.0;
    a->len = 0.0;
    a->first = a->prev = vec3d_make(0, 0, 0);
    a->count = 0;
}

void scene_area_add(scene_area *a, vec3d v)
{
    double c[3];
    int k;
    c[0] = v.x;
    c[1] = v.y;
    c[2] = v.z;
    if (a->count == 0) {
        a->first = v;
        for (k = 0; k < 3; k++)
            a->lo[k] = a->hi[k] = c[k];
    } else {
        newell_edge(a->normal, a->prev, v);
    }
    for (k = 0; k < 3; k++) { /* without branches: coordinates in a file are in no order */
        a->lo[k] = c[k] < a->lo[k] ? c[k] : a->lo[k];
        a->hi[k] = c[k] > a->hi[k] ? c[k] : a->hi[k];
    }
    a->prev = v;
    a->count++;
}

double scene_area_size(const scene_area *a)
{
    double d[3];
    int k;
    for (k = 0; k < 3; k++)
        d[k] = a->hi[k] - a->lo[k];
    return length3(d);
}

int scene_area_zero(scene_area *a)
{
    double size2 = 0;
    int k;
    if (a->count == 0)
        return 1;
    newell_edge(a->normal, a->prev, a->first);
    a->len = length3(a->normal);
    for (k = 0; k < 3; k++)
        size2 += (a->hi[k] - a->lo[k]) * (a->hi[k] - a->lo[k]);
    return !(a->len > SCENE_ZERO_AREA * size2) || !isfinite(a->len);
}

int scene_polygon_zero_area(const vec3d *v, int n)
{
    scene_area a;
    int i;
    scene_area_init(&a);
    for (i = 0; i < n; i++)
        scene_area_add(&a, v[i]);
    return scene_area_zero(&a);
}

int scene_triangle_degenerate(const vec3f p[3])
{
    float e1x = p[1].x - p[0].x, e1y = p[1].y - p[0].y, e1z = p[1].z - p[0].z;
    float e2x = p[2].x - p[0].x, e2y = p[2].y - p[0].y, e2z = p[2].z - p[0].z;
    float cx = e1y * e2z - e1z * e2y, cy = e1z * e2x - e1x * e2z, cz = e1x * e2y - e1y * e2x;
    return cx == 0.0f && cy == 0.0f && cz == 0.0f;
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

vec3f scene_camera_world_up(const scene_camera *c)
{
    static const vec3f axes[3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    vec3f best = c->v;
    float best_dv = 0.05f; /* cos 87 degrees */
    int i;
    for (i = 0; i < 3; i++) {
        float du = vec3f_dot(axes[i], c->u), dv = vec3f_dot(axes[i], c->v);
        if (fabsf(du) < 1e-4f && fabsf(dv) > best_dv) {
            best_dv = fabsf(dv);
            best = dv > 0 ? axes[i] : vec3f_make(-axes[i].x, -axes[i].y, -axes[i].z);
        }
    }
    return best;
}
