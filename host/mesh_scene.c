/* A scene made of one mesh file. See mesh_scene.h. */
#include "mesh_scene.h"

#include <math.h>
#include <stdio.h>

#include "mesh_import.h"
#include "scene_geom.h"
#include "scene_mesh.h"

/* The default view: from the front (+z), raised 25 degrees and turned 35 degrees to the
 * right, at a distance where the bounding sphere fills the vertical field of view. */
#define MESH_FOV 40.0
#define MESH_ELEVATION 25.0
#define MESH_AZIMUTH 35.0

static void frame_camera(scene *s, const double lo[3], const double hi[3])
{
    const double deg = 3.14159265358979323846 / 180.0;
    double c[3], r = 0.0, dist, dir[3];
    vec3f view, up = vec3f_make(0, 1, 0);
    for (int a = 0; a < 3; a++) {
        c[a] = 0.5 * (lo[a] + hi[a]);
        r += (hi[a] - lo[a]) * (hi[a] - lo[a]);
    }
    r = 0.5 * sqrt(r);
    if (!(r > 0.0))
        r = 1.0;
    dist = r / sin(0.5 * MESH_FOV * deg) * 1.05;
    dir[0] = cos(MESH_ELEVATION * deg) * sin(MESH_AZIMUTH * deg);
    dir[1] = sin(MESH_ELEVATION * deg);
    dir[2] = cos(MESH_ELEVATION * deg) * cos(MESH_AZIMUTH * deg);
    s->camera.projection = SCENE_PERSPECTIVE;
    s->camera.eye = vec3d_make(c[0] + dist * dir[0], c[1] + dist * dir[1], c[2] + dist * dir[2]);
    view = vec3f_make((float)-dir[0], (float)-dir[1], (float)-dir[2]);
    scene_camera_basis(&s->camera, view, up);
    s->camera.fov_deg = (float)MESH_FOV;
    s->camera.d = 1.0f;
    /* two lights: a key light above, left and in front of the camera, and a weaker fill
     * light to the right, both well outside the bounds */
    {
        scene_light key, fill;
        double kd[3] = {-0.6, 0.9, 0.5}, fd[3] = {0.9, 0.3, 0.4};
        key.position = vec3d_make(c[0] + 4 * r * (kd[0] + dir[0]), c[1] + 4 * r * (kd[1] + dir[1]),
                                  c[2] + 4 * r * (kd[2] + dir[2]));
        key.intensity = vec3f_make(0.75f, 0.75f, 0.75f);
        fill.position = vec3d_make(c[0] + 4 * r * (fd[0] + dir[0]), c[1] + 4 * r * (fd[1] + dir[1]),
                                   c[2] + 4 * r * (fd[2] + dir[2]));
        fill.intensity = vec3f_make(0.3f, 0.3f, 0.35f);
        scene_push(&s->lights, &key, sizeof key);
        scene_push(&s->lights, &fill, sizeof fill);
    }
}

int mesh_scene_load(const char *path, scene *s, char *err, size_t errlen)
{
    mesh_import_info info;
    int mesh;
    double lo[3], hi[3];
    if (scene_set_name(s, path) != 0) {
        snprintf(err, errlen, "%s: out of memory", path);
        return -1;
    }
    if (mesh_import(path, s, &mesh, &info, err, errlen) != 0)
        return -1;
    if (scene_place_mesh(s, mesh, NULL, -1) < 0 ||
        scene_instance_bounds(s, s->instances.count - 1, lo, hi) != 0) {
        snprintf(err, errlen, "%s: out of memory", path);
        return -1;
    }
    s->width = 640;
    s->height = 480;
    s->background = vec3f_make(0.08f, 0.09f, 0.11f);
    s->ambient = vec3f_make(0.15f, 0.15f, 0.15f);
    frame_camera(s, lo, hi);
    mesh_scene_warn(path, &info);
    return 0;
}

void mesh_scene_warn(const char *path, const mesh_import_info *info)
{
    if (info->degenerate > 0)
        fprintf(stderr, "clwhitted: warning: %s: %zu degenerate triangle%s left out\n", path,
                info->degenerate, info->degenerate == 1 ? "" : "s");
    if (info->textured > 0)
        fprintf(stderr,
                "clwhitted: warning: %s: textures are not part of the model; %d textured "
                "material%s drawn in %s base colour\n",
                path, info->textured, info->textured == 1 ? "" : "s",
                info->textured == 1 ? "its" : "their");
}
