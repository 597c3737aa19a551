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
 *                                                  angle at the image edges
 *     "distance": d,                               perspective only; default 1
 *     "direction": [x,y,z] },                      oblique only, required there
 *   "materials": {"name": {"ka","kd","ks","km","kt": c, "p": >= 0, "ior": > 0}},
 *   "lights": [{"position": [x,y,z], "intensity": c}],
 *   "objects": [{"type": "sphere", "center", "radius" (> 0), "material"},
 *               {"type": "triangle", "vertices": 3 points, "normals" (optional), "material"},
 *               {"type": "polygon", "vertices": >= 3 planar points, "material"}] }
 *
 * A colour c is [r,g,b] or one number (grey). Numbers must be finite, magnitude <= 1e30.
 *
 * cJSON keeps no line numbers. A syntax error's line comes from the parse end; for a
 * schema error, locate_line() walks the text and the tree together, in document order,
 * until it reaches the offending node (object members are located at their key). That
 * walk runs only when there is an error, so a good scene costs nothing extra.
 */
#include "scene.h"

#include <cJSON.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define J_MAX_ABS 1e30
#define J_MAX_VERTS 10000000

typedef struct {
    const char *name;
    int index;
} mat_entry;

typedef struct {
    const char *text; /* the NUL-terminated copy that cJSON parsed */
    size_t len;
    const char *name; /* for messages */
    char *err;
    size_t errlen;
    scene *s;
    const cJSON *root; /* the parsed tree */
    mat_entry *mats;   /* material names, sorted */
    size_t nmats;
} jreader;

/* ---- line numbers ---------------------------------------------------------------------- */

typedef struct {
    const char *p, *end;
    long line;
    const cJSON *target;
    long found;
} jscan;

static void scan_ws(jscan *sc)
{
    while (sc->p < sc->end && (unsigned char)*sc->p <= 32) {
        if (*sc->p == '\n')
            sc->line++;
        sc->p++;
    }
}

static void scan_string(jscan *sc)
{
    sc->p++; /* the opening quote */
    while (sc->p < sc->end && *sc->p != '"') {
        if (*sc->p == '\\' && sc->p + 1 < sc->end)
            sc->p++;
        if (*sc->p == '\n')
            sc->line++;
        sc->p++;
    }
    sc->p++;
}

/* Walks the value at sc->p, which cJSON parsed into node (NULL when out of step). When
 * `self` is set, node itself may be the target (array elements and the root; object
 * members are matched at their key). Returns 1 once the target is found. */
static int scan_value(jscan *sc, const cJSON *node, int self)
{
    scan_ws(sc);
    if (self && node == sc->target) {
        sc->found = sc->line;
        return 1;
    }
    if (sc->p >= sc->end)
        return 0;
    if (*sc->p == '{' || *sc->p == '[') {
        int obj = *sc->p == '{';
        char close = obj ? '}' : ']';
        const cJSON *child = node ? node->child : NULL;
        sc->p++;
        for (;;) {
            scan_ws(sc);
            if (sc->p >= sc->end)
                return 0;
            if (*sc->p == close) {
                sc->p++;
                return 0;
            }
            if (*sc->p == ',') {
                sc->p++;
                continue;
            }
            if (obj) {
                if (child && child == sc->target) {
                    sc->found = sc->line;
                    return 1;
                }
                scan_string(sc);
                scan_ws(sc);
                if (sc->p < sc->end && *sc->p == ':')
                    sc->p++;
            }
            if (scan_value(sc, child, !obj))
                return 1;
            child = child ? child->next : NULL;
        }
    }
    if (*sc->p == '"') {
        scan_string(sc);
        return 0;
    }
    while (sc->p < sc->end && (unsigned char)*sc->p > 32 && *sc->p != ',' && *sc->p != ']' &&
           *sc->p != '}')
        sc->p++;
    return 0;
}

static long count_lines(const char *text, const char *upto)
{
    long line = 1;
    for (; text < upto; text++)
        line += *text == '\n';
    return line;
}

/* The line where node's value starts (for object members: where its key starts). */
static long locate_line(const jreader *r, const cJSON *node)
{
    jscan sc;
    sc.p = r->text;
    sc.end = r->text + r->len;
    sc.line = 1;
    sc.target = node;
    sc.found = 1;
    if (r->len >= 3 && memcmp(sc.p, "\xEF\xBB\xBF", 3) == 0)
        sc.p += 3;
    scan_value(&sc, r->root, 1);
    return sc.found;
}

/* ---- messages ---------------------------------------------------------------------------- */

#if defined(__GNUC__)
static int vfail_line(const jreader *r, long line, const char *fmt, va_list ap)
    __attribute__((format(printf, 3, 0)));
static int fail_line(const jreader *r, long line, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));
static int jfail(const jreader *r, const cJSON *at, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));
#endif

static int vfail_line(const jreader *r, long line, const char *fmt, va_list ap)
{
    int n;
    if (!r->err || r->errlen == 0)
        return -1;
    n = snprintf(r->err, r->errlen, "%s:%ld: ", r->name, line);
    if (n >= 0 && (size_t)n < r->errlen)
        vsnprintf(r->err + n, r->errlen - (size_t)n, fmt, ap);
    return -1;
}

static int fail_line(const jreader *r, long line, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    vfail_line(r, line, fmt, ap);
    va_end(ap);
    return -1;
}

/* Fails with the line of node `at`. */
static int jfail(const jreader *r, const cJSON *at, const char *fmt, ...)
{
    va_list ap;
    long line = at ? locate_line(r, at) : 1;
    va_start(ap, fmt);
    vfail_line(r, line, fmt, ap);
    va_end(ap);
    return -1;
}

static int oom(const jreader *r, const cJSON *at)
{
    return jfail(r, at, "out of memory");
}

static const char *type_name(const cJSON *n)
{
    if (cJSON_IsNumber(n))
        return "a number";
    if (cJSON_IsString(n))
        return "a string";
    if (cJSON_IsArray(n))
        return "an array";
    if (cJSON_IsObject(n))
        return "an object";
    if (cJSON_IsBool(n))
        return "a boolean";
    if (cJSON_IsNull(n))
        return "null";
    return "an unknown value";
}

/* Text from the file, made printable for a message (at most 40 bytes). */
#define SHOWN_LEN 176
static const char *shown(const char *text, char *buf)
{
    return scene_printable(text ? text : "", 40, buf, SHOWN_LEN);
}

/* ---- typed values -------------------------------------------------------------------------- */

typedef struct {
    const cJSON *node;
    size_t index; /* in document order */
} key_entry;

static int cmp_key(const void *a, const void *b)
{
    const key_entry *x = a, *y = b;
    int c = strcmp(x->node->string, y->node->string);
    if (c != 0)
        return c;
    return x->index < y->index ? -1 : x->index > y->index;
}

/* Finds the first member (in document order) whose key an earlier member has, in
 * O(n log n): *dup is it and *first the earlier one, or both NULL. Returns -1 when out of
 * memory. */
static int find_duplicate(const cJSON *node, const cJSON **dup, const cJSON **first)
{
    const cJSON *c;
    key_entry *keys;
    size_t n = 0, i, best = (size_t)-1;
    *dup = *first = NULL;
    for (c = node->child; c; c = c->next)
        n++;
    if (n < 2)
        return 0;
    keys = malloc(n * sizeof *keys);
    if (!keys)
        return -1;
    for (i = 0, c = node->child; c; c = c->next, i++) {
        keys[i].node = c;
        keys[i].index = i;
    }
    qsort(keys, n, sizeof *keys, cmp_key);
    /* in each run of equal keys, sorted by position, the second one is the earliest repeat */
    for (i = 1; i < n; i++)
        if (strcmp(keys[i].node->string, keys[i - 1].node->string) == 0 &&
            (i < 2 || strcmp(keys[i - 1].node->string, keys[i - 2].node->string) != 0) &&
            (best == (size_t)-1 || keys[i].index < keys[best].index))
            best = i;
    if (best != (size_t)-1) {
        *dup = keys[best].node;
        *first = keys[best - 1].node;
    }
    free(keys);
    return 0;
}

/* Checks that node is an object whose keys are all in `allowed` (NULL: any key) and
 * unique. `path` names it in messages. */
static int check_object(const jreader *r, const cJSON *node, const char *path,
                        const char *const *allowed)
{
    const cJSON *c, *d;
    char buf[SHOWN_LEN];
    if (!cJSON_IsObject(node))
        return jfail(r, node, "%s: expected an object, found %s", path, type_name(node));
    for (c = node->child; c; c = c->next) {
        if (allowed) {
            const char *const *a;
            for (a = allowed; *a; a++)
                if (strcmp(*a, c->string) == 0)
                    break;
            if (!*a) {
                char list[256];
                size_t n = 0;
                list[0] = '\0';
                for (a = allowed; *a && n < sizeof list; a++)
                    n += (size_t)snprintf(list + n, sizeof list - n, "%s%s",
                                          a == allowed ? "" : ", ", *a);
                return jfail(r, c, "%s: unknown key \"%s\" (expected one of: %s)", path,
                             shown(c->string, buf), list);
            }
            /* only allowed keys so far, so this stays short */
            for (d = node->child; d != c; d = d->next)
                if (strcmp(d->string, c->string) == 0)
                    return jfail(r, c, "%s: duplicate key \"%s\" (first at line %ld)", path,
                                 shown(c->string, buf), locate_line(r, d));
        }
    }
    if (!allowed) { /* any number of keys: sort them */
        if (find_duplicate(node, &c, &d) != 0)
            return oom(r, node);
        if (c)
            return jfail(r, c, "%s: duplicate key \"%s\" (first at line %ld)", path,
                         shown(c->string, buf), locate_line(r, d));
    }
    return 0;
}

static int get_number(const jreader *r, const cJSON *node, const char *path, double *out)
{
    double x;
    if (!cJSON_IsNumber(node))
        return jfail(r, node, "%s: expected a number, found %s", path, type_name(node));
    x = node->valuedouble;
    if (!isfinite(x))
        return jfail(r, node, "%s: number is not finite", path);
    if (fabs(x) > J_MAX_ABS)
        return jfail(r, node, "%s: number %g out of range (magnitude above 1e30)", path, x);
    *out = x;
    return 0;
}

static int get_int(const jreader *r, const cJSON *node, const char *path, int lo, int hi, int *out)
{
    double x;
    if (get_number(r, node, path, &x) != 0)
        return -1;
    if (x != floor(x) || x < lo || x > hi)
        return jfail(r, node, "%s: expected an integer in %d..%d, found %g", path, lo, hi, x);
    *out = (int)x;
    return 0;
}

/* An array of exactly n numbers; `form` shows the expected shape, e.g. "[x, y, z]". */
static int get_numbers(const jreader *r, const cJSON *node, const char *path, int n,
                       const char *form, double *out)
{
    const cJSON *c;
    int i = 0;
    if (!cJSON_IsArray(node))
        return jfail(r, node, "%s: expected %s (%d numbers), found %s", path, form, n,
                     type_name(node));
    if (cJSON_GetArraySize(node) != n)
        return jfail(r, node, "%s: expected %s (%d numbers), found an array of %d", path, form, n,
                     cJSON_GetArraySize(node));
    for (c = node->child; c; c = c->next, i++) {
        char sub[160];
        snprintf(sub, sizeof sub, "%s[%d]", path, i);
        if (get_number(r, c, sub, &out[i]) != 0)
            return -1;
    }
    return 0;
}

static int get_vec3(const jreader *r, const cJSON *node, const char *path, vec3f *out)
{
    double d[3];
    if (get_numbers(r, node, path, 3, "[x, y, z]", d) != 0)
        return -1;
    *out = vec3f_make((float)d[0], (float)d[1], (float)d[2]);
    return 0;
}

/* A colour: [r, g, b] or one number (grey). */
static int get_colour(const jreader *r, const cJSON *node, const char *path, vec3f *out)
{
    double d[3];
    if (cJSON_IsNumber(node)) {
        if (get_number(r, node, path, d) != 0)
            return -1;
        *out = vec3f_make((float)d[0], (float)d[0], (float)d[0]);
        return 0;
    }
    if (!cJSON_IsArray(node))
        return jfail(r, node, "%s: expected a colour ([r, g, b] or one number), found %s", path,
                     type_name(node));
    if (get_numbers(r, node, path, 3, "[r, g, b]", d) != 0)
        return -1;
    *out = vec3f_make((float)d[0], (float)d[1], (float)d[2]);
    return 0;
}

static const cJSON *member(const cJSON *obj, const char *key)
{
    return cJSON_GetObjectItemCaseSensitive(obj, key);
}

/* A required member; fails naming the object's own node. */
static const cJSON *need(const jreader *r, const cJSON *obj, const char *path, const char *key)
{
    const cJSON *m = member(obj, key);
    if (!m)
        jfail(r, obj, "%s: missing \"%s\"", path, key);
    return m;
}

/* ---- sections ------------------------------------------------------------------------------ */

static int read_image(const jreader *r, const cJSON *img)
{
    static const char *const keys[] = {"width", "height", NULL};
    const cJSON *m;
    if (check_object(r, img, "image", keys) != 0)
        return -1;
    if ((m = member(img, "width")) && get_int(r, m, "image.width", 1, 65536, &r->s->width) != 0)
        return -1;
    if ((m = member(img, "height")) && get_int(r, m, "image.height", 1, 65536, &r->s->height) != 0)
        return -1;
    if ((long long)r->s->width * r->s->height > SCENE_MAX_PIXELS)
        return jfail(r, img, "image: %dx%d has more than 2^28 pixels", r->s->width, r->s->height);
    return 0;
}

static int read_camera(const jreader *r, const cJSON *cam)
{
    static const char *const keys[] = {"projection", "eye", "look_at",  "view",      "up",
                                       "window",     "fov", "distance", "direction", NULL};
    scene_camera *c = &r->s->camera;
    const cJSON *m, *look, *viewn, *up, *win, *fov, *dist, *dirn;
    vec3f eye, upv, view;
    double d = 1.0;
    char buf[SHOWN_LEN];

    if (check_object(r, cam, "camera", keys) != 0)
        return -1;
    c->projection = SCENE_PERSPECTIVE;
    if ((m = member(cam, "projection"))) {
        const char *p = cJSON_GetStringValue(m);
        if (p && strcmp(p, "perspective") == 0)
            c->projection = SCENE_PERSPECTIVE;
        else if (p && strcmp(p, "orthographic") == 0)
            c->projection = SCENE_ORTHOGRAPHIC;
        else if (p && strcmp(p, "oblique") == 0)
            c->projection = SCENE_OBLIQUE;
        else if (p)
            return jfail(r, m,
                         "camera.projection: expected \"perspective\", \"orthographic\" or "
                         "\"oblique\", found \"%s\"",
                         shown(p, buf));
        else
            return jfail(r, m, "camera.projection: expected a string, found %s", type_name(m));
    }
    if (!(m = need(r, cam, "camera", "eye")) || get_vec3(r, m, "camera.eye", &eye) != 0)
        return -1;
    look = member(cam, "look_at");
    viewn = member(cam, "view");
    if (look && viewn)
        return jfail(r, viewn, "camera: give either \"look_at\" or \"view\", not both");
    if (!look && !viewn)
        return jfail(r, cam, "camera: missing \"look_at\" (a point) or \"view\" (a direction)");
    if (look) {
        vec3f at;
        if (get_vec3(r, look, "camera.look_at", &at) != 0)
            return -1;
        view = vec3f_sub(at, eye);
        if (view.x == 0 && view.y == 0 && view.z == 0)
            return jfail(r, look, "camera.look_at: equals the eye, so there is no view direction");
    } else {
        if (get_vec3(r, viewn, "camera.view", &view) != 0)
            return -1;
        if (view.x == 0 && view.y == 0 && view.z == 0)
            return jfail(r, viewn, "camera.view: the view direction is zero");
    }
    if (!(up = need(r, cam, "camera", "up")) || get_vec3(r, up, "camera.up", &upv) != 0)
        return -1;
    if (scene_camera_basis(c, view, upv) != 0)
        return jfail(r, up, "camera.up: zero or parallel to the view direction");
    c->eye = eye;
    c->nff_angle_deg = 0.0f;

    dist = member(cam, "distance");
    fov = member(cam, "fov");
    dirn = member(cam, "direction");
    win = member(cam, "window");
    if (c->projection != SCENE_PERSPECTIVE && dist)
        return jfail(r, dist,
                     "camera.distance: only a perspective camera has an image-plane distance");
    if (c->projection != SCENE_PERSPECTIVE && fov)
        return jfail(r, fov,
                     "camera.fov: only a perspective camera has a field of view; give \"window\"");
    if (c->projection != SCENE_OBLIQUE && dirn)
        return jfail(r, dirn, "camera.direction: only an oblique camera has a ray direction");
    if (dist) {
        if (get_number(r, dist, "camera.distance", &d) != 0)
            return -1;
        if (!((float)d > 0)) /* as stored: a float */
            return jfail(r, dist, "camera.distance: must be > 0, found %.10g%s", d,
                         scene_single_note(d, buf, sizeof buf));
    }
    c->d = (float)d;
    if (fov && win)
        return jfail(r, win, "camera: give either \"window\" or \"fov\", not both");
    if (fov) {
        double deg;
        if (get_number(r, fov, "camera.fov", &deg) != 0)
            return -1;
        if (!((float)deg > 0 && (float)deg < 180)) /* as stored: a float */
            return jfail(r, fov,
                         "camera.fov: must lie strictly between 0 and 180 degrees, found %.10g%s",
                         deg, scene_single_note(deg, buf, sizeof buf));
        c->fov_deg = (float)deg; /* the window follows from the final image size */
    } else if (win) {
        double w[4];
        if (get_numbers(r, win, "camera.window", 4, "[l, r, b, t]", w) != 0)
            return -1;
        if (!((float)w[0] < (float)w[1]) || !((float)w[2] < (float)w[3])) /* as floats */
            return jfail(r, win, "camera.window: needs l < r and b < t, found [%g, %g, %g, %g]",
                         w[0], w[1], w[2], w[3]);
        c->l = (float)w[0];
        c->r = (float)w[1];
        c->b = (float)w[2];
        c->t = (float)w[3];
    } else {
        return jfail(r, cam, "camera: missing \"window\" [l, r, b, t]%s",
                     c->projection == SCENE_PERSPECTIVE ? " or \"fov\"" : "");
    }
    if (c->projection == SCENE_OBLIQUE) {
        if (!dirn)
            return jfail(r, cam, "camera: an oblique camera needs \"direction\" [x, y, z]");
        if (get_vec3(r, dirn, "camera.direction", &c->dir) != 0)
            return -1;
        if (vec3f_normalize(c->dir, &c->dir) != 0)
            return jfail(r, dirn, "camera.direction: the direction is zero");
        if (vec3f_dot(c->dir, c->w) >= 0)
            return jfail(r, dirn, "camera.direction: must point into the view (against w)");
    }
    /* what is left, e.g. a field of view too small or too wide for the distance and size */
    if (scene_check_view(r->s, buf, sizeof buf) != 0)
        return jfail(r, fov ? fov : cam, "camera: gives no usable view: %s", buf);
    return 0;
}

static int cmp_mat(const void *a, const void *b)
{
    return strcmp(((const mat_entry *)a)->name, ((const mat_entry *)b)->name);
}

static int read_materials(jreader *r, const cJSON *mats)
{
    static const char *const keys[] = {"ka", "kd", "ks", "km", "kt", "p", "ior", NULL};
    static const char *const colours[] = {"ka", "kd", "ks", "km", "kt"};
    const cJSON *m;
    size_t n = 0;
    char buf[SHOWN_LEN];
    if (check_object(r, mats, "materials", NULL) != 0)
        return -1;
    r->nmats = (size_t)cJSON_GetArraySize(mats);
    r->mats = malloc((r->nmats ? r->nmats : 1) * sizeof *r->mats);
    if (!r->mats)
        return oom(r, mats);
    for (m = mats->child; m; m = m->next) {
        scene_material mat;
        vec3f *dst[5];
        const cJSON *v;
        char path[SHOWN_LEN + 16], note[64];
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
        shown(m->string, buf);
        snprintf(path, sizeof path, "materials.%s", buf);
        if (check_object(r, m, path, keys) != 0)
            return -1;
        for (k = 0; k < 5; k++) {
            if ((v = member(m, colours[k]))) {
                snprintf(path, sizeof path, "materials.%s.%s", buf, colours[k]);
                if (get_colour(r, v, path, dst[k]) != 0)
                    return -1;
            }
        }
        if ((v = member(m, "p"))) {
            snprintf(path, sizeof path, "materials.%s.p", buf);
            if (get_number(r, v, path, &x) != 0)
                return -1;
            if (!(x >= 0))
                return jfail(r, v, "%s: the Phong exponent must be >= 0, found %g", path, x);
            mat.p = (float)x;
        }
        if ((v = member(m, "ior"))) {
            snprintf(path, sizeof path, "materials.%s.ior", buf);
            if (get_number(r, v, path, &x) != 0)
                return -1;
            if (!((float)x > 0)) /* as stored: a float */
                return jfail(r, v, "%s: the index of refraction must be > 0, found %.10g%s", path,
                             x, scene_single_note(x, note, sizeof note));
            mat.ior = (float)x;
        }
        idx = scene_push(&r->s->materials, &mat, sizeof mat);
        if (idx < 0)
            return oom(r, m);
        r->mats[n].name = m->string;
        r->mats[n].index = (int)idx;
        n++;
    }
    r->nmats = n;
    qsort(r->mats, n, sizeof *r->mats, cmp_mat);
    return 0;
}

static int read_lights(const jreader *r, const cJSON *lights)
{
    static const char *const keys[] = {"position", "intensity", NULL};
    const cJSON *l, *m;
    int i = 0;
    if (!cJSON_IsArray(lights))
        return jfail(r, lights, "lights: expected an array, found %s", type_name(lights));
    for (l = lights->child; l; l = l->next, i++) {
        scene_light light;
        char path[64], sub[96];
        snprintf(path, sizeof path, "lights[%d]", i);
        if (check_object(r, l, path, keys) != 0)
            return -1;
        snprintf(sub, sizeof sub, "%s.position", path);
        if (!(m = need(r, l, path, "position")) || get_vec3(r, m, sub, &light.position) != 0)
            return -1;
        snprintf(sub, sizeof sub, "%s.intensity", path);
        if (!(m = need(r, l, path, "intensity")) || get_colour(r, m, sub, &light.intensity) != 0)
            return -1;
        if (scene_push(&r->s->lights, &light, sizeof light) < 0)
            return oom(r, l);
    }
    return 0;
}

/* Reads an array of at least lo, at most hi points into pts (malloc'd). */
static int get_points(const jreader *r, const cJSON *node, const char *path, int lo, int hi,
                      vec3f **pts, int *count)
{
    const cJSON *c;
    int n, i = 0;
    *pts = NULL;
    if (!cJSON_IsArray(node))
        return jfail(r, node, "%s: expected an array of points [x, y, z], found %s", path,
                     type_name(node));
    n = cJSON_GetArraySize(node);
    if (n < lo || n > hi) {
        if (lo == hi)
            return jfail(r, node, "%s: expected %d points, found %d", path, lo, n);
        return jfail(r, node, "%s: expected %d..%d points, found %d", path, lo, hi, n);
    }
    *pts = malloc((size_t)n * sizeof **pts);
    if (!*pts)
        return oom(r, node);
    for (c = node->child; c; c = c->next, i++) {
        char sub[160];
        snprintf(sub, sizeof sub, "%s[%d]", path, i);
        if (get_vec3(r, c, sub, &(*pts)[i]) != 0) {
            free(*pts);
            *pts = NULL;
            return -1;
        }
    }
    *count = n;
    return 0;
}

/* The size (bounding box diagonal) of a polygon. */
static double poly_size(const vec3f *p, int n)
{
    double lo[3], hi[3];
    int i, k;
    lo[0] = hi[0] = p[0].x;
    lo[1] = hi[1] = p[0].y;
    lo[2] = hi[2] = p[0].z;
    for (i = 0; i < n; i++) {
        double q[3];
        q[0] = p[i].x;
        q[1] = p[i].y;
        q[2] = p[i].z;
        for (k = 0; k < 3; k++) {
            if (q[k] < lo[k])
                lo[k] = q[k];
            if (q[k] > hi[k])
                hi[k] = q[k];
        }
    }
    return sqrt((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) +
                (hi[2] - lo[2]) * (hi[2] - lo[2]));
}

/* 0 when the polygon has an area; otherwise fails at `node`. */
static int check_area(const jreader *r, const cJSON *node, const char *path, const vec3f *p, int n,
                      double unit[3], double *size_out)
{
    double nrm[3], size = poly_size(p, n), len;
    scene_newell(p, n, nrm);
    *size_out = size;
    len = sqrt(nrm[0] * nrm[0] + nrm[1] * nrm[1] + nrm[2] * nrm[2]);
    if (!(len > 1e-12 * size * size) || !isfinite(len))
        return jfail(r, node, "%s: the %s has zero area", path, n == 3 ? "triangle" : "polygon");
    unit[0] = nrm[0] / len;
    unit[1] = nrm[1] / len;
    unit[2] = nrm[2] / len;
    return 0;
}

static int find_material(const jreader *r, const cJSON *obj, const char *path)
{
    const cJSON *m = need(r, obj, path, "material");
    const char *name;
    mat_entry key, *hit;
    char buf[SHOWN_LEN];
    if (!m)
        return -1;
    if (!(name = cJSON_GetStringValue(m)))
        return jfail(r, m, "%s.material: expected a material name, found %s", path, type_name(m));
    key.name = name;
    key.index = 0;
    hit = r->nmats ? bsearch(&key, r->mats, r->nmats, sizeof key, cmp_mat) : NULL;
    if (!hit)
        return jfail(r, m, "%s.material: no material named \"%s\" in \"materials\"", path,
                     shown(name, buf));
    return hit->index;
}

static int read_object(const jreader *r, const cJSON *o, int i)
{
    static const char *const sphere_keys[] = {"type", "center", "radius", "material", NULL};
    static const char *const tri_keys[] = {"type", "vertices", "normals", "material", NULL};
    static const char *const poly_keys[] = {"type", "vertices", "material", NULL};
    char path[64], sub[96];
    const cJSON *t, *m;
    const char *type;
    int mat;
    char buf[SHOWN_LEN];
    snprintf(path, sizeof path, "objects[%d]", i);
    if (check_object(r, o, path, NULL) != 0)
        return -1;
    if (!(t = need(r, o, path, "type")))
        return -1;
    type = cJSON_GetStringValue(t);
    if (!type || (strcmp(type, "sphere") != 0 && strcmp(type, "triangle") != 0 &&
                  strcmp(type, "polygon") != 0)) {
        if (!type)
            return jfail(r, t, "%s.type: expected a string, found %s", path, type_name(t));
        return jfail(r, t,
                     "%s.type: unknown object type \"%s\" (expected \"sphere\", \"triangle\" or "
                     "\"polygon\")",
                     path, shown(type, buf));
    }
    if (check_object(r, o, path,
                     type[0] == 's'   ? sphere_keys
                     : type[0] == 't' ? tri_keys
                                      : poly_keys) != 0)
        return -1;

    if (type[0] == 's') {
        scene_sphere sp;
        double rad;
        snprintf(sub, sizeof sub, "%s.center", path);
        if (!(m = need(r, o, path, "center")) || get_vec3(r, m, sub, &sp.center) != 0)
            return -1;
        snprintf(sub, sizeof sub, "%s.radius", path);
        if (!(m = need(r, o, path, "radius")) || get_number(r, m, sub, &rad) != 0)
            return -1;
        if (!((float)rad > 0)) /* as stored: a float */
            return jfail(r, m, "%s: the radius must be > 0, found %.10g%s", sub, rad,
                         scene_single_note(rad, buf, sizeof buf));
        if ((mat = find_material(r, o, path)) < 0)
            return -1;
        sp.radius = (float)rad;
        sp.material = mat;
        return scene_push(&r->s->spheres, &sp, sizeof sp) < 0 ? oom(r, o) : 0;
    }

    {
        vec3f *pts;
        int n, k;
        double unit[3] = {0, 0, 0}, size = 0;
        const cJSON *verts = need(r, o, path, "vertices");
        int tri = type[0] == 't';
        if (!verts)
            return -1;
        snprintf(sub, sizeof sub, "%s.vertices", path);
        if (get_points(r, verts, sub, 3, tri ? 3 : J_MAX_VERTS, &pts, &n) != 0)
            return -1;
        if (check_area(r, verts, sub, pts, n, unit, &size) != 0) {
            free(pts);
            return -1;
        }
        if (!tri) {
            /* planar: every vertex within 1e-4 * size of the plane through the centroid */
            double c[3] = {0, 0, 0};
            const cJSON *vn = verts->child;
            for (k = 0; k < n; k++) {
                c[0] += pts[k].x;
                c[1] += pts[k].y;
                c[2] += pts[k].z;
            }
            c[0] /= n;
            c[1] /= n;
            c[2] /= n;
            for (k = 0; k < n; k++, vn = vn->next) {
                double off = (pts[k].x - c[0]) * unit[0] + (pts[k].y - c[1]) * unit[1] +
                             (pts[k].z - c[2]) * unit[2];
                if (fabs(off) > 1e-4 * size) {
                    free(pts);
                    return jfail(r, vn,
                                 "%s[%d]: the polygon is not planar: this vertex lies %g off its "
                                 "plane (tolerance %g)",
                                 sub, k, fabs(off), 1e-4 * size);
                }
            }
        }
        if ((mat = find_material(r, o, path)) < 0) {
            free(pts);
            return -1;
        }
        if (tri) {
            scene_triangle st;
            memset(&st, 0, sizeof st);
            memcpy(st.p, pts, sizeof st.p);
            free(pts);
            st.material = mat;
            if ((m = member(o, "normals"))) {
                vec3f *nrm;
                int nn;
                const cJSON *e;
                snprintf(sub, sizeof sub, "%s.normals", path);
                if (get_points(r, m, sub, 3, 3, &nrm, &nn) != 0)
                    return -1;
                for (k = 0, e = m->child; k < 3; k++, e = e->next) {
                    if (vec3f_normalize(nrm[k], &st.n[k]) != 0) {
                        free(nrm);
                        return jfail(r, e, "%s[%d]: the normal is zero", sub, k);
                    }
                }
                free(nrm);
                st.has_normals = 1;
            }
            return scene_push(&r->s->triangles, &st, sizeof st) < 0 ? oom(r, o) : 0;
        } else {
            scene_polygon poly;
            poly.first = (int)r->s->poly_verts.count;
            poly.count = n;
            poly.material = mat;
            for (k = 0; k < n; k++) {
                if (scene_push(&r->s->poly_verts, &pts[k], sizeof pts[k]) < 0) {
                    free(pts);
                    return oom(r, o);
                }
            }
            free(pts);
            return scene_push(&r->s->polygons, &poly, sizeof poly) < 0 ? oom(r, o) : 0;
        }
    }
}

static int read_scene(jreader *r, const cJSON *root)
{
    static const char *const keys[] = {"image",     "max_depth", "background", "ambient", "camera",
                                       "materials", "lights",    "objects",    NULL};
    const cJSON *m;
    scene *s = r->s;
    if (!cJSON_IsObject(root))
        return jfail(r, root, "expected a JSON object at the top level, found %s", type_name(root));
    if (check_object(r, root, "scene", keys) != 0)
        return -1;
    s->width = 640;
    s->height = 480;
    if ((m = member(root, "image")) && read_image(r, m) != 0)
        return -1;
    if ((m = member(root, "max_depth")) && get_int(r, m, "max_depth", 1, 64, &s->max_depth) != 0)
        return -1;
    if ((m = member(root, "background")) && get_colour(r, m, "background", &s->background) != 0)
        return -1;
    if ((m = member(root, "ambient")) && get_colour(r, m, "ambient", &s->ambient) != 0)
        return -1;
    if (!(m = member(root, "camera")))
        return jfail(r, root, "missing \"camera\"");
    if (read_camera(r, m) != 0)
        return -1;
    if ((m = member(root, "materials")) && read_materials(r, m) != 0)
        return -1;
    if ((m = member(root, "lights")) && read_lights(r, m) != 0)
        return -1;
    if ((m = member(root, "objects"))) {
        const cJSON *o;
        int i = 0;
        if (!cJSON_IsArray(m))
            return jfail(r, m, "objects: expected an array, found %s", type_name(m));
        for (o = m->child; o; o = o->next, i++)
            if (read_object(r, o, i) != 0)
                return -1;
    }
    return 0;
}

/* ---- entry points -------------------------------------------------------------------------- */

/* Parses buf[0..len), which has buf[len] == '\0'. */
static int parse_buffer(char *buf, size_t len, const char *name, scene *s, char *err, size_t errlen)
{
    jreader r;
    cJSON *root;
    const char *end = NULL, *nul, *p;
    int rc;
    memset(&r, 0, sizeof r);
    r.text = buf;
    r.len = len;
    r.name = name;
    r.err = err;
    r.errlen = errlen;
    r.s = s;
    if (scene_set_name(s, name) != 0)
        return fail_line(&r, 1, "out of memory");
    if ((nul = memchr(buf, '\0', len)))
        return fail_line(&r, count_lines(buf, nul), "unexpected NUL byte (not a text file?)");
    for (p = buf; p < buf + len && (unsigned char)*p <= 32; p++)
        ;
    if (p == buf + len)
        return fail_line(&r, count_lines(buf, p), "empty file: expected a JSON object");
    /* len + 1 takes in the terminating NUL, which cJSON needs to see to reject trailing text */
    root = cJSON_ParseWithLengthOpts(buf, len + 1, &end, 1);
    if (!root) {
        const char *at = end ? end : cJSON_GetErrorPtr();
        char near[32], shownbuf[SHOWN_LEN];
        size_t k = 0;
        if (!at || at < buf || at > buf + len)
            at = buf + len;
        while (at + k < buf + len && k + 1 < sizeof near && at[k] != '\n' && at[k] != '\r') {
            near[k] = at[k];
            k++;
        }
        near[k] = '\0';
        if (k == 0)
            return fail_line(&r, count_lines(buf, at),
                             "JSON syntax error at the end of the line or file (unclosed value?)");
        return fail_line(&r, count_lines(buf, at), "JSON syntax error near '%s'",
                         shown(near, shownbuf));
    }
    r.root = root;
    rc = read_scene(&r, root);
    free(r.mats);
    cJSON_Delete(root);
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
