/* A scene made of one mesh file. See mesh_scene.h. */
#include "mesh_scene.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "mesh_import.h"
#include "scene_geom.h"
#include "scene_mesh.h"

/* The defaults (docs/scene-formats.md, "Mesh files"): a 640x480 image; the view from the
 * front (+z), raised 25 degrees and turned 35 degrees to the right, at a distance where a
 * sphere around the mesh fills the vertical field of view of 40 degrees. */
#define MESH_WIDTH 640
#define MESH_HEIGHT 480
#define MESH_FOV 40.0
#define MESH_ELEVATION 25.0
#define MESH_AZIMUTH 35.0
#define MESH_PI 3.14159265358979323846

/* A sphere around the mesh (placed with the identity): centred on the box lo..hi, its
 * radius the farthest vertex from there (at most the box's half diagonal). */
static double bounds_sphere(const scene *s, int mesh, const double lo[3], const double hi[3],
                            double c[3])
{
    const scene_mesh *m = &SCENE_AT(s->meshes, scene_mesh, mesh);
    double r2 = 0.0, r;
    for (int a = 0; a < 3; a++)
        c[a] = 0.5 * (lo[a] + hi[a]);
    for (size_t i = m->first; i < m->first + m->count; i++) {
        const scene_triangle *t = &SCENE_AT(s->mesh_tris, scene_triangle, i);
        for (int k = 0; k < 3; k++) {
            double dx = t->p[k].x - c[0], dy = t->p[k].y - c[1], dz = t->p[k].z - c[2];
            double d2 = dx * dx + dy * dy + dz * dz;
            if (d2 > r2)
                r2 = d2;
        }
    }
    r = sqrt(r2);
    return r > 0.0 && isfinite(r) ? r : 1.0;
}

static int frame_camera(scene *s, const double c[3], double r, double dir[3])
{
    const double deg = MESH_PI / 180.0;
    double dist = r / sin(0.5 * MESH_FOV * deg) * 1.05;
    vec3f view, up = vec3f_make(0, 1, 0);
    dir[0] = cos(MESH_ELEVATION * deg) * sin(MESH_AZIMUTH * deg);
    dir[1] = sin(MESH_ELEVATION * deg);
    dir[2] = cos(MESH_ELEVATION * deg) * cos(MESH_AZIMUTH * deg);
    s->camera.projection = SCENE_PERSPECTIVE;
    s->camera.eye = vec3d_make(c[0] + dist * dir[0], c[1] + dist * dir[1], c[2] + dist * dir[2]);
    view = vec3f_make((float)-dir[0], (float)-dir[1], (float)-dir[2]);
    s->camera.fov_deg = (float)MESH_FOV;
    s->camera.d = 1.0f;
    return scene_camera_basis(&s->camera, view, up);
}

/* The file's own camera; -1 when it makes no usable view (the framing camera then). */
static int file_camera(scene *s, const mesh_view *v)
{
    scene_camera cam = s->camera;
    if (!v->has_camera || scene_camera_basis(&cam, v->dir, v->up) != 0)
        return -1;
    cam.eye = v->eye;
    cam.d = 1.0f;
    cam.nff_angle_deg = 0.0f;
    if (v->aspect > 0.0) {
        double h = MESH_WIDTH / v->aspect;
        s->height = h < 1.0 ? 1 : h > MESH_WIDTH * 4 ? MESH_WIDTH * 4 : (int)(h + 0.5);
    }
    if (v->yfov_deg > 0.0) {
        if (!(v->yfov_deg < 179.0))
            return -1;
        cam.projection = SCENE_PERSPECTIVE;
        cam.fov_deg = (float)v->yfov_deg;
    } else {
        cam.projection = SCENE_ORTHOGRAPHIC;
        cam.fov_deg = 0.0f;
        cam.r = (float)v->ortho_half;
        cam.l = -cam.r;
        cam.t = (float)(v->ortho_half * s->height / s->width);
        cam.b = -cam.t;
    }
    s->camera = cam;
    return 0;
}

/* The default lights: a key light above, left and in front of the camera, and a weaker
 * fill light to the right, both well outside the bounds (dir: towards the camera). */
static int default_lights(scene *s, const double c[3], double r, const double dir[3])
{
    static const double kd[3] = {-0.6, 0.9, 0.5}, fd[3] = {0.9, 0.3, 0.4};
    scene_light key, fill;
    key.position = vec3d_make(c[0] + 4 * r * (kd[0] + dir[0]), c[1] + 4 * r * (kd[1] + dir[1]),
                              c[2] + 4 * r * (kd[2] + dir[2]));
    key.intensity = vec3f_make(0.75f, 0.75f, 0.75f);
    fill.position = vec3d_make(c[0] + 4 * r * (fd[0] + dir[0]), c[1] + 4 * r * (fd[1] + dir[1]),
                               c[2] + 4 * r * (fd[2] + dir[2]));
    fill.intensity = vec3f_make(0.3f, 0.3f, 0.35f);
    if (scene_push(&s->lights, &key, sizeof key) < 0 ||
        scene_push(&s->lights, &fill, sizeof fill) < 0)
        return -1;
    return 0;
}

/* The file's lights, their colours scaled together so that the brightest channel of
 * their sum is 1; a directional light as a point light far away against its direction. */
static int file_lights(scene *s, const mesh_view *v, const double c[3], double r)
{
    double sum[3] = {0, 0, 0}, top, k;
    size_t i;
    for (i = 0; i < v->light_count; i++) {
        sum[0] += v->lights[i].color.x;
        sum[1] += v->lights[i].color.y;
        sum[2] += v->lights[i].color.z;
    }
    top = fmax(sum[0], fmax(sum[1], sum[2]));
    if (!(top > 0.0) || !isfinite(top))
        return 0;
    k = 1.0 / top;
    for (i = 0; i < v->light_count; i++) {
        const mesh_light *ml = &v->lights[i];
        scene_light l;
        l.intensity = vec3f_make((float)(ml->color.x * k), (float)(ml->color.y * k),
                                 (float)(ml->color.z * k));
        if (ml->directional)
            l.position = vec3d_make(c[0] - 1000.0 * r * ml->dir.x, c[1] - 1000.0 * r * ml->dir.y,
                                    c[2] - 1000.0 * r * ml->dir.z);
        else
            l.position = ml->position;
        if (scene_push(&s->lights, &l, sizeof l) < 0)
            return -1;
    }
    return 0;
}

/* The scene around the mesh just imported: placed once, the camera, the lights. */
static int build(scene *s, const char *name, int mesh, const mesh_view *view, char *err,
                 size_t errlen)
{
    double lo[3], hi[3], c[3], r, dir[3];
    if (scene_place_mesh(s, mesh, NULL, -1) < 0) {
        snprintf(err, errlen, "%s: out of memory", name);
        return -1;
    }
    if (scene_instance_bounds(s, s->instances.count - 1, lo, hi) != 0) {
        snprintf(err, errlen, "%s: the mesh has no bounds", name);
        return -1;
    }
    r = bounds_sphere(s, mesh, lo, hi, c);
    s->width = MESH_WIDTH;
    s->height = MESH_HEIGHT;
    s->background = vec3f_make(0.08f, 0.09f, 0.11f);
    s->ambient = vec3f_make(0.15f, 0.15f, 0.15f);
    if (frame_camera(s, c, r, dir) != 0) {
        snprintf(err, errlen, "%s: the mesh's bounds are out of range", name);
        return -1;
    }
    file_camera(s, view);
    if ((view->light_count > 0 ? file_lights(s, view, c, r) : 0) != 0 ||
        (s->lights.count == 0 && default_lights(s, c, r, dir) != 0)) {
        snprintf(err, errlen, "%s: out of memory", name);
        return -1;
    }
    return 0;
}

void mesh_scene_warn(const char *path, const mesh_import_info *info)
{
    if (info->missing_mtl > 0)
        fprintf(stderr,
                "clwhitted: warning: %s: material library '%s' not found; its materials drawn "
                "in the default material\n",
                path, info->missing_mtl_name);
    if (info->degenerate > 0)
        fprintf(stderr, "clwhitted: warning: %s: %zu degenerate triangle%s left out\n", path,
                info->degenerate, info->degenerate == 1 ? "" : "s");
    if (info->non_faces > 0)
        fprintf(stderr, "clwhitted: warning: %s: %zu point%s or line%s left out\n", path,
                info->non_faces, info->non_faces == 1 ? "" : "s", info->non_faces == 1 ? "" : "s");
    if (info->textured > 0)
        fprintf(stderr,
                "clwhitted: warning: %s: textures are not part of the model; %d textured "
                "material%s drawn in %s base colour\n",
                path, info->textured, info->textured == 1 ? "" : "s",
                info->textured == 1 ? "its" : "their");
    if (info->colored > 0)
        fprintf(stderr,
                "clwhitted: warning: %s: vertex colours are not part of the model; drawn in "
                "the material's colour\n",
                path);
}

int mesh_scene_load(const char *path, scene *s, char *err, size_t errlen)
{
    mesh_import_info info;
    mesh_view view;
    int mesh, rc = -1;
    if (scene_set_name(s, path) != 0) {
        snprintf(err, errlen, "%s: out of memory", path);
        return -1;
    }
    if (mesh_import_view(path, s, &mesh, &info, &view, err, errlen) == 0 &&
        build(s, path, mesh, &view, err, errlen) == 0) {
        mesh_scene_warn(path, &info);
        rc = 0;
    }
    mesh_view_free(&view);
    return rc;
}

int mesh_scene_memory(const void *data, size_t size, const char *hint, const char *name, scene *s,
                      char *err, size_t errlen)
{
    mesh_import_info info;
    mesh_view view;
    int mesh, rc = -1;
    if (scene_set_name(s, name) != 0) {
        snprintf(err, errlen, "%s: out of memory", name);
        return -1;
    }
    if (mesh_import_memory(data, size, hint, name, s, &mesh, &info, &view, err, errlen) == 0 &&
        build(s, name, mesh, &view, err, errlen) == 0)
        rc = 0;
    mesh_view_free(&view);
    return rc;
}
