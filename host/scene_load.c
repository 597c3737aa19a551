/* Loading a scene file: picks the reader by the extension. See scene_load.h. */
#include "scene_load.h"

#include <stdio.h>

#include "mesh_import.h"
#include "mesh_scene.h"
#include "scene_json.h"
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

int scene_load(const char *path, scene *s, char *err, size_t errlen)
{
    if (sys_has_ext(path, ".json"))
        return json_scene_load(path, s, err, errlen);
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
