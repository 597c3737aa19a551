/* Loading a scene file: picks the reader by the extension; the command line's changes to
 * the camera. See scene_load.h. */
#include "scene_load.h"

#include <stdio.h>

#include "mesh_import.h"
#include "mesh_scene.h"
#include "scene_geom.h"
#include "scene_json.h"
#include "scene_mesh.h"
#include "scene_nff.h"
#include "sys.h"

int scene_load_camera(const char *path, scene *s, char *err, size_t errlen)
{
    if (!sys_has_ext(path, ".json")) {
        snprintf(err, errlen, "%s: a camera file is JSON (expected a .json file)", path);
        return -1;
    }
    return json_camera_load(path, s, err, errlen);
}

/* A JSON scene's mesh files (json_set_mesh_reader): assimp's importer, and its warnings. */
static int read_mesh(const char *path, scene *s, int *mesh, char *err, size_t errlen)
{
    mesh_import_info info;
    if (mesh_import(path, s, mesh, &info, err, errlen) != 0)
        return -1;
    mesh_scene_warn(path, &info);
    return 0;
}

int scene_load(const char *path, scene *s, char *err, size_t errlen)
{
    if (sys_has_ext(path, ".json")) {
        json_set_mesh_reader(read_mesh);
        return json_scene_load(path, s, err, errlen);
    }
    if (sys_has_ext(path, ".nff"))
        return nff_load(path, s, err, errlen);
    if (mesh_is_mesh_file(path))
        return mesh_scene_load(path, s, err, errlen);
    snprintf(err, errlen,
             "%s: unknown scene format (expected a .nff or .json scene, or a .obj, .ply, .gltf, "
             ".glb or .stl mesh)",
             path);
    return -1;
}

int scene_apply_view(scene *s, const scene_view *v, char *err, size_t errlen)
{
    scene_camera *c = &s->camera, moved = s->camera;
    vec3d eye = v->has_eye ? v->eye : c->eye;
    vec3f view = vec3f_make(-c->w.x, -c->w.y, -c->w.z);
    vec3f up = v->has_up ? v->up : scene_camera_world_up(c);
    if (v->has_fov && c->projection != SCENE_PERSPECTIVE) {
        snprintf(err, errlen, "--fov applies to a perspective camera; the scene's is %s",
                 c->projection == SCENE_ORTHOGRAPHIC ? "orthographic" : "oblique");
        return -1;
    }
    if (v->has_at) {
        view = vec3d_diff(v->at, eye);
        if (view.x == 0 && view.y == 0 && view.z == 0) {
            snprintf(err, errlen,
                     "the look-at point (%.9g, %.9g, %.9g) is the eye: no view direction", v->at.x,
                     v->at.y, v->at.z);
            return -1;
        }
    }
    if ((v->has_at || v->has_up) && scene_camera_basis(&moved, view, up) != 0) {
        snprintf(err, errlen, "%s (%g, %g, %g) is parallel to the view direction (%g, %g, %g)%s",
                 v->has_up ? "--up" : "the scene's up", up.x, up.y, up.z, view.x, view.y, view.z,
                 v->has_up ? "" : ": give --up");
        return -1;
    }
    moved.eye = eye;
    if (v->has_fov) {
        moved.fov_deg = (float)v->fov_deg;
        moved.nff_angle_deg = 0.0f; /* the window follows from the field of view */
    }
    *c = moved;
    return 0;
}

int scene_load_for_render(const char *path, const char *camera_file, const scene_view *view,
                          int width, int height, int depth, scene *s, char *err, size_t errlen)
{
    char why[512];
    if (scene_load(path, s, err, errlen) != 0 ||
        (camera_file && scene_load_camera(camera_file, s, err, errlen) != 0))
        return -1;
    if (view && scene_apply_view(s, view, why, sizeof why) != 0) {
        snprintf(err, errlen, "%s: the camera of the command line: %s", path, why);
        return -1;
    }
    if (view && view->flatten && scene_flatten_instances(s, 1, why, sizeof why) != 0) {
        snprintf(err, errlen, "%s: %s", path, why);
        return -1;
    }
    return scene_finish(s, width, height, depth, err, errlen);
}
