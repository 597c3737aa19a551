/* The native scene format: JSON, read with cJSON and checked against a strict schema
 * (unknown and duplicate keys are errors, to catch typos):
 *
 * { "image": {"width": 640, "height": 480},        optional; positive integers
 *   "max_depth": 5,                                optional; integer 1..64
 *   "background": c, "ambient": c,                 optional; default black
 *   "camera": {                                    required
 *     "projection": "perspective" | "orthographic" | "oblique",   default perspective
 *     "eye": [x,y,z], "up": [x,y,z],               required
 *     "look_at": [x,y,z] or "view": [x,y,z],       exactly one
 *     "window": [l,r,b,t] or "fov": degrees,       fov: perspective only, the full vertical
 *       or "angle": degrees,                       angle at the image edges; angle: NFF's,
 *                                                  spanning the outer pixel rows' centres
 *     "distance": d,                               perspective only; default 1
 *     "direction": [x,y,z] },                      oblique only, required there
 *   "materials": {"name": {"ka","kd","ks","km","kt": c, "p": >= 0, "ior": > 0}},
 *   "lights": [{"position": [x,y,z], "intensity": c}],
 *   "objects": [{"type": "sphere" | "triangle" | "polygon" | "cone" | "cylinder", ...}] }
 *                                                  the keys of each: scene_json_objects.c
 *
 * A colour c is [r,g,b] or one number (grey). Numbers must be finite, magnitude <= 1e18
 * (CW_MAX_ABS); an image side at most 65536 (CW_MAX_SIDE), a depth at most 64 (CW_MAX_DEPTH).
 *
 * cJSON keeps no line numbers. A syntax error's line comes from the parse end; a schema
 * error's from jv_line() (scene_json_value.h). This file reads the sections of the
 * schema; scene_json_objects.c the objects; scene_json_value.c the typed values they are
 * made of.
 */
#include "scene_json.h"

#include <cJSON.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "config.h"
#include "scene_geom.h"
#include "scene_io.h"
#include "scene_json_objects.h"
#include "scene_json_value.h"

typedef struct {
    jv_doc doc; /* the text, its tree and where messages go */
    scene *s;
    jo_material *mats; /* material names, sorted */
    size_t nmats;
    int camera_only; /* a camera file (--camera): "image", "max_depth" and "camera" only */
} jreader;

static json_mesh_reader mesh_reader; /* json_set_mesh_reader */

void json_set_mesh_reader(json_mesh_reader fn)
{
    mesh_reader = fn;
}

/* ---- sections ------------------------------------------------------------------------------ */

static int read_image(const jreader *r, const cJSON *img)
{
    static const char *const keys[] = {"width", "height", NULL};
    const cJSON *m;
    if (jv_check_object(&r->doc, img, "image", keys) != 0)
        return -1;
    if ((m = jv_member(img, "width")) &&
        jv_int(&r->doc, m, "image.width", 1, CW_MAX_SIDE, &r->s->width) != 0)
        return -1;
    if ((m = jv_member(img, "height")) &&
        jv_int(&r->doc, m, "image.height", 1, CW_MAX_SIDE, &r->s->height) != 0)
        return -1;
    if ((long long)r->s->width * r->s->height > CW_MAX_PIXELS)
        return jv_fail(&r->doc, img, "image: %dx%d has more than 2^28 pixels", r->s->width,
                       r->s->height);
    return 0;
}

static int read_camera(const jreader *r, const cJSON *cam)
{
    static const char *const keys[] = {"projection", "eye",       "look_at", "view",
                                       "up",         "window",    "fov",     "distance",
                                       "angle",      "direction", NULL};
    scene_camera *c = &r->s->camera;
    const cJSON *m, *look, *viewn, *up, *win, *fov, *dist, *dirn, *ang;
    vec3d eye;
    vec3f upv, view;
    double d = 1.0;
    char buf[SCENE_SHOWN_LEN];

    if (jv_check_object(&r->doc, cam, "camera", keys) != 0)
        return -1;
    c->projection = SCENE_PERSPECTIVE;
    if ((m = jv_member(cam, "projection"))) {
        const char *p = cJSON_GetStringValue(m);
        if (p && strcmp(p, "perspective") == 0)
            c->projection = SCENE_PERSPECTIVE;
        else if (p && strcmp(p, "orthographic") == 0)
            c->projection = SCENE_ORTHOGRAPHIC;
        else if (p && strcmp(p, "oblique") == 0)
            c->projection = SCENE_OBLIQUE;
        else if (p)
            return jv_fail(&r->doc, m,
                           "camera.projection: expected \"perspective\", \"orthographic\" or "
                           "\"oblique\", found \"%s\"",
                           scene_shown(p, buf));
        else
            return jv_fail(&r->doc, m, "camera.projection: expected a string, found %s",
                           jv_type_name(m));
    }
    if (!(m = jv_need(&r->doc, cam, "camera", "eye")) ||
        jv_point(&r->doc, m, "camera.eye", &eye) != 0)
        return -1;
    look = jv_member(cam, "look_at");
    viewn = jv_member(cam, "view");
    if (look && viewn)
        return jv_fail(&r->doc, viewn, "camera: give either \"look_at\" or \"view\", not both");
    if (!look && !viewn)
        return jv_fail(&r->doc, cam,
                       "camera: missing \"look_at\" (a point) or \"view\" (a direction)");
    if (look) {
        vec3d at;
        if (jv_point(&r->doc, look, "camera.look_at", &at) != 0)
            return -1;
        view = vec3d_diff(at, eye);
        if (view.x == 0 && view.y == 0 && view.z == 0)
            return jv_fail(&r->doc, look,
                           "camera.look_at: equals the eye, so there is no view direction");
    } else {
        if (jv_vec3(&r->doc, viewn, "camera.view", &view) != 0)
            return -1;
        if (view.x == 0 && view.y == 0 && view.z == 0)
            return jv_fail(&r->doc, viewn, "camera.view: the view direction is zero");
    }
    if (!(up = jv_need(&r->doc, cam, "camera", "up")) ||
        jv_vec3(&r->doc, up, "camera.up", &upv) != 0)
        return -1;
    if (scene_camera_basis(c, view, upv) != 0)
        return jv_fail(&r->doc, up, "camera.up: zero or parallel to the view direction");
    c->eye = eye;
    c->nff_angle_deg = 0.0f;

    dist = jv_member(cam, "distance");
    fov = jv_member(cam, "fov");
    dirn = jv_member(cam, "direction");
    win = jv_member(cam, "window");
    ang = jv_member(cam, "angle");
    if (ang) { /* NFF's angle: a window at distance 1 from the final image size */
        double deg;
        if (c->projection != SCENE_PERSPECTIVE)
            return jv_fail(&r->doc, ang,
                           "camera.angle: only a perspective camera has an NFF angle; give "
                           "\"window\"");
        if (fov || win || dist)
            return jv_fail(&r->doc, ang,
                           "camera.angle: give one of \"angle\", \"fov\" and \"window\", and no "
                           "\"distance\" with \"angle\" (it is 1)");
        if (jv_number(&r->doc, ang, "camera.angle", &deg) != 0)
            return -1;
        if (!((float)deg > 0 && (float)deg < 180)) /* as stored: a float */
            return jv_fail(&r->doc, ang,
                           "camera.angle: must lie strictly between 0 and 180 degrees, found "
                           "%.10g%s",
                           deg, scene_single_note(deg, buf, sizeof buf));
        c->nff_angle_deg = (float)deg;
        c->d = 1.0f;
    }
    if (c->projection != SCENE_PERSPECTIVE && dist)
        return jv_fail(&r->doc, dist,
                       "camera.distance: only a perspective camera has an image-plane distance");
    if (c->projection != SCENE_PERSPECTIVE && fov)
        return jv_fail(
            &r->doc, fov,
            "camera.fov: only a perspective camera has a field of view; give \"window\"");
    if (c->projection != SCENE_OBLIQUE && dirn)
        return jv_fail(&r->doc, dirn,
                       "camera.direction: only an oblique camera has a ray direction");
    if (dist) {
        if (jv_number(&r->doc, dist, "camera.distance", &d) != 0)
            return -1;
        if (!((float)d > 0)) /* as stored: a float */
            return jv_fail(&r->doc, dist, "camera.distance: must be > 0, found %.10g%s", d,
                           scene_single_note(d, buf, sizeof buf));
    }
    c->d = (float)d;
    if (fov && win)
        return jv_fail(&r->doc, win, "camera: give either \"window\" or \"fov\", not both");
    if (fov) {
        double deg;
        if (jv_number(&r->doc, fov, "camera.fov", &deg) != 0)
            return -1;
        if (!((float)deg > 0 && (float)deg < 180)) /* as stored: a float */
            return jv_fail(&r->doc, fov,
                           "camera.fov: must lie strictly between 0 and 180 degrees, found %.10g%s",
                           deg, scene_single_note(deg, buf, sizeof buf));
        c->fov_deg = (float)deg; /* the window follows from the final image size */
    } else if (win) {
        double w[4];
        if (jv_numbers(&r->doc, win, "camera.window", 4, "[l, r, b, t]", w) != 0)
            return -1;
        if (!((float)w[0] < (float)w[1]) || !((float)w[2] < (float)w[3])) /* as floats */
            return jv_fail(&r->doc, win,
                           "camera.window: needs l < r and b < t, found [%g, %g, %g, %g]", w[0],
                           w[1], w[2], w[3]);
        c->l = (float)w[0];
        c->r = (float)w[1];
        c->b = (float)w[2];
        c->t = (float)w[3];
    } else if (!ang) {
        return jv_fail(&r->doc, cam, "camera: missing \"window\" [l, r, b, t]%s",
                       c->projection == SCENE_PERSPECTIVE ? ", \"fov\" or \"angle\"" : "");
    }
    if (c->projection == SCENE_OBLIQUE) {
        if (!dirn)
            return jv_fail(&r->doc, cam, "camera: an oblique camera needs \"direction\" [x, y, z]");
        if (jv_vec3(&r->doc, dirn, "camera.direction", &c->dir) != 0)
            return -1;
        if (vec3f_normalize(c->dir, &c->dir) != 0)
            return jv_fail(&r->doc, dirn, "camera.direction: the direction is zero");
        if (vec3f_dot(c->dir, c->w) >= 0)
            return jv_fail(&r->doc, dirn, "camera.direction: must point into the view (against w)");
    }
    /* what is left, e.g. a field of view too small or too wide for the distance and size */
    if (scene_check_view(r->s, buf, sizeof buf) != 0)
        return jv_fail(&r->doc,
                       fov   ? fov
                       : ang ? ang
                             : cam,
                       "camera: gives no usable view: %s", buf);
    return 0;
}

static int read_materials(jreader *r, const cJSON *mats)
{
    static const char *const keys[] = {"ka", "kd", "ks", "km", "kt", "p", "ior", NULL};
    static const char *const colours[] = {"ka", "kd", "ks", "km", "kt"};
    const cJSON *m;
    size_t n = 0;
    char buf[SCENE_SHOWN_LEN];
    if (jv_check_object(&r->doc, mats, "materials", NULL) != 0)
        return -1;
    r->nmats = (size_t)cJSON_GetArraySize(mats);
    r->mats = malloc((r->nmats ? r->nmats : 1) * sizeof *r->mats);
    if (!r->mats)
        return jv_oom(&r->doc, mats);
    for (m = mats->child; m; m = m->next) {
        scene_material mat;
        vec3f *dst[5];
        const cJSON *v;
        char path[SCENE_SHOWN_LEN + 16], note[64];
        double x;
        long idx;
        int k;
        memset(&mat, 0, sizeof mat);
        mat.p = 1;
        mat.ior = 1;
        dst[0] = &mat.ka;
        dst[1] = &mat.kd;
        dst[2] = &mat.ks;
        dst[3] = &mat.km;
        dst[4] = &mat.kt;
        scene_shown(m->string, buf);
        snprintf(path, sizeof path, "materials.%s", buf);
        if (jv_check_object(&r->doc, m, path, keys) != 0)
            return -1;
        for (k = 0; k < 5; k++) {
            if ((v = jv_member(m, colours[k]))) {
                snprintf(path, sizeof path, "materials.%s.%s", buf, colours[k]);
                if (jv_colour(&r->doc, v, path, dst[k]) != 0)
                    return -1;
            }
        }
        if ((v = jv_member(m, "p"))) {
            snprintf(path, sizeof path, "materials.%s.p", buf);
            if (jv_number(&r->doc, v, path, &x) != 0)
                return -1;
            if (!(x >= 0))
                return jv_fail(&r->doc, v, "%s: the Phong exponent must be >= 0, found %g", path,
                               x);
            mat.p = (float)x;
        }
        if ((v = jv_member(m, "ior"))) {
            snprintf(path, sizeof path, "materials.%s.ior", buf);
            if (jv_number(&r->doc, v, path, &x) != 0)
                return -1;
            if (!((float)x > 0)) /* as stored: a float */
                return jv_fail(&r->doc, v, "%s: the index of refraction must be > 0, found %.10g%s",
                               path, x, scene_single_note(x, note, sizeof note));
            mat.ior = (float)x;
        }
        idx = scene_push(&r->s->materials, &mat, sizeof mat);
        if (idx < 0)
            return jv_oom(&r->doc, m);
        r->mats[n].name = m->string;
        r->mats[n].index = (int)idx;
        n++;
    }
    r->nmats = n;
    qsort(r->mats, n, sizeof *r->mats, jo_material_cmp);
    return 0;
}

static int read_lights(const jreader *r, const cJSON *lights)
{
    static const char *const keys[] = {"position", "intensity", NULL};
    const cJSON *l, *m;
    int i = 0;
    if (!cJSON_IsArray(lights))
        return jv_fail(&r->doc, lights, "lights: expected an array, found %s",
                       jv_type_name(lights));
    for (l = lights->child; l; l = l->next, i++) {
        scene_light light;
        char path[64], sub[96];
        snprintf(path, sizeof path, "lights[%d]", i);
        if (jv_check_object(&r->doc, l, path, keys) != 0)
            return -1;
        snprintf(sub, sizeof sub, "%s.position", path);
        if (!(m = jv_need(&r->doc, l, path, "position")) ||
            jv_point(&r->doc, m, sub, &light.position) != 0)
            return -1;
        snprintf(sub, sizeof sub, "%s.intensity", path);
        if (!(m = jv_need(&r->doc, l, path, "intensity")) ||
            jv_colour(&r->doc, m, sub, &light.intensity) != 0)
            return -1;
        if (scene_push(&r->s->lights, &light, sizeof light) < 0)
            return jv_oom(&r->doc, l);
    }
    return 0;
}

static int read_scene(jreader *r, const cJSON *root)
{
    static const char *const keys[] = {"image",     "max_depth", "background", "ambient", "camera",
                                       "materials", "lights",    "objects",    NULL};
    static const char *const camera_keys[] = {"image", "max_depth", "camera", NULL};
    const cJSON *m;
    scene *s = r->s;
    if (!cJSON_IsObject(root))
        return jv_fail(&r->doc, root, "expected a JSON object at the top level, found %s",
                       jv_type_name(root));
    if (jv_check_object(&r->doc, root, r->camera_only ? "camera file" : "scene",
                        r->camera_only ? camera_keys : keys) != 0)
        return -1;
    if (!r->camera_only) {
        s->width = 640;
        s->height = 480;
    }
    if ((m = jv_member(root, "image")) && read_image(r, m) != 0)
        return -1;
    if ((m = jv_member(root, "max_depth")) &&
        jv_int(&r->doc, m, "max_depth", 1, CW_MAX_DEPTH, &s->max_depth) != 0)
        return -1;
    if ((m = jv_member(root, "background")) &&
        jv_colour(&r->doc, m, "background", &s->background) != 0)
        return -1;
    if ((m = jv_member(root, "ambient")) && jv_colour(&r->doc, m, "ambient", &s->ambient) != 0)
        return -1;
    if (!(m = jv_member(root, "camera")))
        return jv_fail(&r->doc, root, "missing \"camera\"");
    if (read_camera(r, m) != 0)
        return -1;
    if ((m = jv_member(root, "materials")) && read_materials(r, m) != 0)
        return -1;
    if ((m = jv_member(root, "lights")) && read_lights(r, m) != 0)
        return -1;
    if ((m = jv_member(root, "objects"))) {
        const cJSON *o;
        int i = 0, rc = 0;
        jo_reader objs;
        jo_mesh_files files;
        memset(&files, 0, sizeof files);
        objs.doc = &r->doc;
        objs.s = s;
        objs.mats = r->mats;
        objs.nmats = r->nmats;
        objs.files = &files;
        objs.read_mesh = mesh_reader;
        if (!cJSON_IsArray(m))
            return jv_fail(&r->doc, m, "objects: expected an array, found %s", jv_type_name(m));
        for (o = m->child; o && rc == 0; o = o->next, i++)
            rc = jo_read_object(&objs, o, i);
        jo_mesh_files_free(&files);
        return rc;
    }
    return 0;
}

/* The deepest nesting of arrays and objects in text before `end` (strings skipped), to tell
 * cJSON's nesting limit from a syntax error. */
static long deepest_nesting(const char *text, const char *end)
{
    long depth = 0, deepest = 0;
    const char *p;
    for (p = text; p < end; p++) {
        if (*p == '"') {
            for (p++; p < end && *p != '"'; p++)
                if (*p == '\\' && p + 1 < end)
                    p++;
        } else if (*p == '[' || *p == '{') {
            if (++depth > deepest)
                deepest = depth;
        } else if (*p == ']' || *p == '}') {
            depth--;
        }
    }
    return deepest;
}

/* ---- entry points -------------------------------------------------------------------------- */

/* Parses buf[0..len): a scene, or a camera file. */
static int parse_any(char *buf, size_t len, const scene_msg *msg, scene *s, int camera_only)
{
    jreader r;
    cJSON *root;
    const char *end = NULL, *p;
    int rc;
    memset(&r, 0, sizeof r);
    r.doc.text = buf;
    r.doc.len = len;
    r.doc.msg = msg;
    r.s = s;
    r.camera_only = camera_only;
    for (p = buf; p < buf + len && (unsigned char)*p <= 32; p++)
        ;
    if (p == buf + len)
        return scene_fail(msg, scene_line_at(buf, p), "empty file: expected a JSON object");
    /* len + 1 takes in the terminating NUL, which cJSON needs to see to reject trailing text */
    root = cJSON_ParseWithLengthOpts(buf, len + 1, &end, 1);
    if (!root) {
        const char *at = end ? end : cJSON_GetErrorPtr();
        char near[32], shownbuf[SCENE_SHOWN_LEN];
        size_t k = 0;
        if (!at || at < buf || at > buf + len)
            at = buf + len;
        while (at + k < buf + len && k + 1 < sizeof near && at[k] != '\n' && at[k] != '\r') {
            near[k] = at[k];
            k++;
        }
        near[k] = '\0';
        if (deepest_nesting(buf, at < buf + len ? at + 1 : at) > CJSON_NESTING_LIMIT)
            return scene_fail(msg, scene_line_at(buf, at),
                              "JSON nested deeper than %d levels (arrays and objects)",
                              (int)CJSON_NESTING_LIMIT);
        if (k == 0)
            return scene_fail(msg, scene_line_at(buf, at),
                              "JSON syntax error at the end of the line or file (unclosed value?)");
        return scene_fail(msg, scene_line_at(buf, at), "JSON syntax error near '%s'",
                          scene_shown(near, shownbuf));
    }
    r.doc.root = root;
    rc = read_scene(&r, root);
    free(r.mats);
    cJSON_Delete(root);
    return rc;
}

/* scene_text_parsers: a scene, a camera file. */
static int parse_buffer(char *buf, size_t len, const scene_msg *msg, scene *s)
{
    return parse_any(buf, len, msg, s, 0);
}

static int parse_camera_buffer(char *buf, size_t len, const scene_msg *msg, scene *s)
{
    return parse_any(buf, len, msg, s, 1);
}

int json_camera_load(const char *path, scene *s, char *err, size_t errlen)
{
    scene cam;
    int rc;
    scene_init(&cam);
    cam.width = cam.height = cam.max_depth = 0;
    rc = scene_parse_file(parse_camera_buffer, path, &cam, err, errlen);
    if (rc == 0) {
        s->camera = cam.camera;
        if (cam.width > 0)
            s->width = cam.width;
        if (cam.height > 0)
            s->height = cam.height;
        if (cam.max_depth > 0)
            s->max_depth = cam.max_depth;
    }
    scene_free(&cam);
    return rc;
}

int json_scene_parse(const char *text, size_t len, const char *name, scene *s, char *err,
                     size_t errlen)
{
    return scene_parse_copy(parse_buffer, text, len, name, s, err, errlen);
}

int json_scene_load(const char *path, scene *s, char *err, size_t errlen)
{
    return scene_parse_file(parse_buffer, path, s, err, errlen);
}
