/* The preview's interactive camera (see viewcam.h). */
#include "viewcam.h"

#include "scene_geom.h"
#include "scene_mesh.h"

#include <math.h>
#include <stdio.h>

#define VC_PI 3.14159265358979323846
#define VC_MAX_ELEVATION (89.5 * VC_PI / 180.0)
#define VC_ZOOM_STEP 0.85

static vec3f add(vec3f a, vec3f b)
{
    return vec3f_make(a.x + b.x, a.y + b.y, a.z + b.z);
}

static vec3f scale(vec3f a, float k)
{
    return vec3f_make(a.x * k, a.y * k, a.z * k);
}

/* a rotated by angle radians about the unit axis k (Rodrigues). */
static vec3f rotate(vec3f a, vec3f k, double angle)
{
    double c = cos(angle), s = sin(angle), kd = vec3f_dot(k, a) * (1.0 - c);
    vec3f kx = vec3f_cross(k, a);
    return vec3f_make((float)(a.x * c + kx.x * s + k.x * kd),
                      (float)(a.y * c + kx.y * s + k.y * kd),
                      (float)(a.z * c + kx.z * s + k.z * kd));
}

static double clampd(double x, double lo, double hi)
{
    return x < lo ? lo : x > hi ? hi : x;
}

/* The oblique direction in world space from camera coordinates. */
static vec3f dir_world(const scene_camera *c, vec3f dc)
{
    vec3f d = add(add(scale(c->u, dc.x), scale(c->v, dc.y)), scale(c->w, dc.z));
    if (vec3f_normalize(d, &d) != 0)
        d = scale(c->w, -1.0f);
    return d;
}

/* Grows the box [lo, hi] by the point p, inflated by r. */
static void grow(vec3d *lo, vec3d *hi, vec3d p, float r, int *any)
{
    vec3d a = vec3d_make(p.x - r, p.y - r, p.z - r), b = vec3d_make(p.x + r, p.y + r, p.z + r);
    if (!*any) {
        *lo = a;
        *hi = b;
        *any = 1;
        return;
    }
    lo->x = fmin(lo->x, a.x);
    lo->y = fmin(lo->y, a.y);
    lo->z = fmin(lo->z, a.z);
    hi->x = fmax(hi->x, b.x);
    hi->y = fmax(hi->y, b.y);
    hi->z = fmax(hi->z, b.z);
}

/* The centre and diagonal of the scene's bounding box; returns 0 for an empty scene. */
static int scene_bounds(const scene *s, vec3d *centre, float *diag)
{
    vec3d lo = {0, 0, 0}, hi = {0, 0, 0};
    int any = 0, k;
    size_t i;
    for (i = 0; i < s->spheres.count; i++) {
        const scene_sphere *sp = &SCENE_AT(s->spheres, scene_sphere, i);
        grow(&lo, &hi, sp->center, fabsf(sp->radius), &any);
    }
    for (i = 0; i < s->triangles.count; i++)
        for (k = 0; k < 3; k++)
            grow(&lo, &hi, SCENE_AT(s->triangles, scene_triangle, i).p[k], 0.0f, &any);
    for (i = 0; i < s->poly_verts.count; i++)
        grow(&lo, &hi, SCENE_AT(s->poly_verts, vec3d, i), 0.0f, &any);
    for (i = 0; i < s->instances.count; i++) {
        double blo[3], bhi[3];
        if (scene_instance_bounds(s, i, blo, bhi) == 0) {
            grow(&lo, &hi, vec3d_make(blo[0], blo[1], blo[2]), 0.0f, &any);
            grow(&lo, &hi, vec3d_make(bhi[0], bhi[1], bhi[2]), 0.0f, &any);
        }
    }
    for (i = 0; i < s->cones.count; i++) {
        const scene_cone *cn = &SCENE_AT(s->cones, scene_cone, i);
        grow(&lo, &hi, cn->base, fabsf(cn->base_radius), &any);
        grow(&lo, &hi, cn->apex, fabsf(cn->apex_radius), &any);
    }
    if (!any)
        return 0;
    *centre = vec3d_make(0.5 * (lo.x + hi.x), 0.5 * (lo.y + hi.y), 0.5 * (lo.z + hi.z));
    *diag = vec3f_length(vec3d_diff(hi, lo));
    return 1;
}

void viewcam_init(viewcam *vc, const scene *s)
{
    const scene_camera *c = &s->camera;
    vec3d centre;
    vec3f view = scale(c->w, -1.0f);
    float diag = 0.0f, dist = 1.0f;
    if (scene_bounds(s, &centre, &diag)) {
        float along = vec3f_dot(vec3d_diff(centre, c->eye), view);
        float least = diag > 0.0f ? 1e-3f * diag : 1e-3f;
        dist = isfinite(along) && along > least ? along : (diag > 0.0f ? 0.5f * diag : 1.0f);
    }
    vc->cam = *c;
    vc->cam.nff_angle_deg = 0.0f; /* the window is explicit from now on */
    vc->cam.fov_deg = 0.0f;
    vc->width = s->width;
    vc->height = s->height;
    vc->dist = dist;
    vc->pivot = vec3d_add_scaled(c->eye, view, dist);
    vc->up = scene_camera_world_up(c);
    if (c->projection == SCENE_OBLIQUE)
        vc->dir_cam =
            vec3f_make(vec3f_dot(c->dir, c->u), vec3f_dot(c->dir, c->v), vec3f_dot(c->dir, c->w));
    else if (vec3f_normalize(vec3f_make(0.3f, -0.3f, -1.0f), &vc->dir_cam) != 0)
        vc->dir_cam = vec3f_make(0, 0, -1);
    vc->persp_d = c->projection == SCENE_PERSPECTIVE && c->d > 0.0f ? c->d : 1.0f;
    vc->min_dist = 1e-4f * (diag > dist ? diag : dist);

    vc->home = vc->cam;
    vc->home_width = vc->width;
    vc->home_height = vc->height;
    vc->home_pivot = vc->pivot;
    vc->home_dist = vc->dist;
    vc->home_up = vc->up;
    vc->home_dir_cam = vc->dir_cam;
}

void viewcam_set_size(viewcam *vc, int width, int height)
{
    scene_camera *c = &vc->cam;
    double cx = 0.5 * ((double)c->l + c->r), half_h = 0.5 * ((double)c->t - c->b), half_w;
    if (width < 1 || height < 1)
        return;
    half_w = half_h * width / height;
    c->l = (float)(cx - half_w);
    c->r = (float)(cx + half_w);
    vc->width = width;
    vc->height = height;
}

/* Points the camera from eye = pivot + dist * w_new at the pivot, level with world up. */
static void look_from(viewcam *vc, vec3f w_new)
{
    scene_camera c = vc->cam;
    if (vec3f_normalize(w_new, &w_new) != 0)
        return;
    if (scene_camera_basis(&c, scale(w_new, -1.0f), vc->up) != 0)
        return; /* straight along up: keep the old camera */
    c.eye = vec3d_add_scaled(vc->pivot, c.w, vc->dist);
    c.dir = dir_world(&c, vc->dir_cam);
    vc->cam = c;
}

void viewcam_orbit(viewcam *vc, float yaw, float pitch)
{
    double e0, e1, a;
    if (yaw != 0.0f)
        look_from(vc, rotate(vc->cam.w, vc->up, yaw));
    if (pitch != 0.0f) {
        e0 = asin(clampd(vec3f_dot(vc->cam.w, vc->up), -1.0, 1.0));
        e1 = clampd(e0 + pitch, -VC_MAX_ELEVATION, VC_MAX_ELEVATION);
        a = e1 - e0;
        /* v is w turned 90 degrees towards up, in the vertical plane through the view */
        look_from(vc, add(scale(vc->cam.w, (float)cos(a)), scale(vc->cam.v, (float)sin(a))));
    }
}

float viewcam_pixel_size(const viewcam *vc)
{
    const scene_camera *c = &vc->cam;
    float px = (c->t - c->b) / (float)(vc->height > 0 ? vc->height : 1);
    return c->projection == SCENE_PERSPECTIVE ? px * vc->dist / c->d : px;
}

static void move(viewcam *vc, vec3f delta)
{
    vc->cam.eye = vec3d_add_scaled(vc->cam.eye, delta, 1.0);
    vc->pivot = vec3d_add_scaled(vc->pivot, delta, 1.0);
}

void viewcam_pan(viewcam *vc, float dx, float dy)
{
    float px = viewcam_pixel_size(vc);
    move(vc, add(scale(vc->cam.u, -dx * px), scale(vc->cam.v, dy * px)));
}

static void scale_window(scene_camera *c, double k, int about_centre)
{
    double cx = about_centre ? 0.5 * ((double)c->l + c->r) : 0.0;
    double cy = about_centre ? 0.5 * ((double)c->b + c->t) : 0.0;
    c->l = (float)(cx + (c->l - cx) * k);
    c->r = (float)(cx + (c->r - cx) * k);
    c->b = (float)(cy + (c->b - cy) * k);
    c->t = (float)(cy + (c->t - cy) * k);
}

void viewcam_zoom(viewcam *vc, float steps)
{
    double k = pow(VC_ZOOM_STEP, steps);
    if (vc->cam.projection == SCENE_PERSPECTIVE) {
        double d = vc->dist * k, hi = 1e4 * vc->home_dist;
        d = clampd(d, vc->min_dist, hi > vc->dist ? hi : vc->dist);
        vc->dist = (float)d;
        vc->cam.eye = vec3d_add_scaled(vc->pivot, vc->cam.w, vc->dist);
    } else {
        double h = (double)vc->cam.t - vc->cam.b;
        /* keep the window within sane bounds of the pivot's distance */
        if ((k < 1.0 && h * k < 1e-5 * vc->dist) || (k > 1.0 && h * k > 1e5 * vc->dist))
            return;
        scale_window(&vc->cam, k, 1);
    }
}

void viewcam_fly(viewcam *vc, float forward, float right, float upward)
{
    move(vc, add(add(scale(vc->cam.w, -forward), scale(vc->cam.u, right)), scale(vc->up, upward)));
}

void viewcam_reset(viewcam *vc)
{
    int w = vc->width, h = vc->height;
    vc->cam = vc->home;
    vc->width = vc->home_width;
    vc->height = vc->home_height;
    vc->pivot = vc->home_pivot;
    vc->dist = vc->home_dist;
    vc->up = vc->home_up;
    vc->dir_cam = vc->home_dir_cam;
    vc->persp_d = vc->home.projection == SCENE_PERSPECTIVE ? vc->home.d : 1.0f;
    if (w != vc->width || h != vc->height)
        viewcam_set_size(vc, w, h);
}

/* Where the pivot appears in an oblique window: rays leave the eye plane along dir_cam
 * and reach the pivot's depth after t = dist / -dir_w. */
static void oblique_shift(const viewcam *vc, double *x, double *y)
{
    double t = vc->dir_cam.z < 0.0f ? vc->dist / -(double)vc->dir_cam.z : 0.0;
    *x = -t * vc->dir_cam.x;
    *y = -t * vc->dir_cam.y;
}

static void shift_window(scene_camera *c, double x, double y)
{
    c->l = (float)(c->l + x);
    c->r = (float)(c->r + x);
    c->b = (float)(c->b + y);
    c->t = (float)(c->t + y);
}

void viewcam_set_projection(viewcam *vc, enum scene_projection p)
{
    scene_camera *c = &vc->cam;
    double sx, sy;
    if (p == c->projection ||
        (p != SCENE_PERSPECTIVE && p != SCENE_ORTHOGRAPHIC && p != SCENE_OBLIQUE))
        return;
    oblique_shift(vc, &sx, &sy);
    /* first to the parallel window at the pivot's depth */
    if (c->projection == SCENE_PERSPECTIVE) {
        vc->persp_d = c->d;
        scale_window(c, vc->dist / c->d, 0);
    } else if (c->projection == SCENE_OBLIQUE) {
        shift_window(c, -sx, -sy);
    }
    if (p == SCENE_PERSPECTIVE) {
        c->d = vc->persp_d;
        scale_window(c, c->d / vc->dist, 0);
    } else if (p == SCENE_OBLIQUE) {
        shift_window(c, sx, sy);
    }
    c->dir = dir_world(c, vc->dir_cam);
    c->projection = p;
}

enum scene_projection viewcam_next_projection(enum scene_projection p)
{
    return p == SCENE_PERSPECTIVE    ? SCENE_ORTHOGRAPHIC
           : p == SCENE_ORTHOGRAPHIC ? SCENE_OBLIQUE
                                     : SCENE_PERSPECTIVE;
}

const char *viewcam_projection_name(enum scene_projection p)
{
    return p == SCENE_ORTHOGRAPHIC ? "orthographic"
           : p == SCENE_OBLIQUE    ? "oblique"
                                   : "perspective";
}

void viewcam_apply(const viewcam *vc, scene *s)
{
    s->camera = vc->cam;
    s->width = vc->width;
    s->height = vc->height;
}

int viewcam_to_json(const viewcam *vc, int max_depth, char *buf, size_t n)
{
    const scene_camera *c = &vc->cam;
    int k, m;
    k = snprintf(buf, n,
                 "{\n  \"image\": {\"width\": %d, \"height\": %d},\n  \"max_depth\": %d,\n"
                 "  \"camera\": {\n    \"projection\": \"%s\",\n"
                 "    \"eye\": [%.17g, %.17g, %.17g],\n    \"view\": [%.9g, %.9g, %.9g],\n"
                 "    \"up\": [%.9g, %.9g, %.9g],\n    \"window\": [%.9g, %.9g, %.9g, %.9g]",
                 vc->width, vc->height, max_depth, viewcam_projection_name(c->projection), c->eye.x,
                 c->eye.y, c->eye.z, -c->w.x, -c->w.y, -c->w.z, c->v.x, c->v.y, c->v.z, c->l, c->r,
                 c->b, c->t);
    if (k < 0 || (size_t)k >= n)
        return -1;
    if (c->projection == SCENE_PERSPECTIVE)
        m = snprintf(buf + k, n - (size_t)k, ",\n    \"distance\": %.9g\n  }\n}\n", c->d);
    else if (c->projection == SCENE_OBLIQUE)
        m = snprintf(buf + k, n - (size_t)k, ",\n    \"direction\": [%.9g, %.9g, %.9g]\n  }\n}\n",
                     c->dir.x, c->dir.y, c->dir.z);
    else
        m = snprintf(buf + k, n - (size_t)k, "\n  }\n}\n");
    if (m < 0 || (size_t)m >= n - (size_t)k)
        return -1;
    return 0;
}
