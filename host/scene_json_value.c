/* The JSON reader's typed values: a member of the parsed tree checked to be what the schema
 * wants there (an object with known, unique keys; a number in range; a point, a colour, a
 * list of points), failing with the line of the offending node. See scene_json_value.h. */
#include "scene_json_value.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "config.h"
#include "scene_geom.h"

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

long jv_line(const jv_doc *doc, const cJSON *node)
{
    jscan sc;
    sc.p = doc->text + scene_bom_len(doc->text, doc->len);
    sc.end = doc->text + doc->len;
    sc.line = 1;
    sc.target = node;
    sc.found = 1;
    scan_value(&sc, doc->root, 1);
    return sc.found;
}

/* ---- messages ---------------------------------------------------------------------------- */

int jv_fail(const jv_doc *doc, const cJSON *at, const char *fmt, ...)
{
    va_list ap;
    long line = at ? jv_line(doc, at) : 1;
    va_start(ap, fmt);
    scene_vfail(doc->msg, line, fmt, ap);
    va_end(ap);
    return -1;
}

int jv_oom(const jv_doc *doc, const cJSON *at)
{
    return jv_fail(doc, at, "out of memory");
}

const char *jv_type_name(const cJSON *n)
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
int jv_check_object(const jv_doc *doc, const cJSON *node, const char *path,
                    const char *const *allowed)
{
    const cJSON *c, *d;
    char buf[SCENE_SHOWN_LEN];
    if (!cJSON_IsObject(node))
        return jv_fail(doc, node, "%s: expected an object, found %s", path, jv_type_name(node));
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
                return jv_fail(doc, c, "%s: unknown key \"%s\" (expected one of: %s)", path,
                               scene_shown(c->string, buf), list);
            }
            /* only allowed keys so far, so this stays short */
            for (d = node->child; d != c; d = d->next)
                if (strcmp(d->string, c->string) == 0)
                    return jv_fail(doc, c, "%s: duplicate key \"%s\" (first at line %ld)", path,
                                   scene_shown(c->string, buf), jv_line(doc, d));
        }
    }
    if (!allowed) { /* any number of keys: sort them */
        if (find_duplicate(node, &c, &d) != 0)
            return jv_oom(doc, node);
        if (c)
            return jv_fail(doc, c, "%s: duplicate key \"%s\" (first at line %ld)", path,
                           scene_shown(c->string, buf), jv_line(doc, d));
    }
    return 0;
}

int jv_number(const jv_doc *doc, const cJSON *node, const char *path, double *out)
{
    double x;
    if (!cJSON_IsNumber(node))
        return jv_fail(doc, node, "%s: expected a number, found %s", path, jv_type_name(node));
    x = node->valuedouble;
    if (!isfinite(x))
        return jv_fail(doc, node, "%s: number is not finite", path);
    if (fabs(x) > CW_MAX_ABS)
        return jv_fail(doc, node,
                       "%s: number %g out of range (magnitude above " SCENE_STR(CW_MAX_ABS) ")",
                       path, x);
    *out = x;
    return 0;
}

int jv_int(const jv_doc *doc, const cJSON *node, const char *path, int lo, int hi, int *out)
{
    double x;
    if (jv_number(doc, node, path, &x) != 0)
        return -1;
    if (x != floor(x) || x < lo || x > hi)
        return jv_fail(doc, node, "%s: expected an integer in %d..%d, found %g", path, lo, hi, x);
    *out = (int)x;
    return 0;
}

/* An array of exactly n numbers; `form` shows the expected shape, e.g. "[x, y, z]". */
int jv_numbers(const jv_doc *doc, const cJSON *node, const char *path, int n, const char *form,
               double *out)
{
    const cJSON *c;
    int i = 0;
    if (!cJSON_IsArray(node))
        return jv_fail(doc, node, "%s: expected %s (%d numbers), found %s", path, form, n,
                       jv_type_name(node));
    if (cJSON_GetArraySize(node) != n)
        return jv_fail(doc, node, "%s: expected %s (%d numbers), found an array of %d", path, form,
                       n, cJSON_GetArraySize(node));
    for (c = node->child; c; c = c->next, i++) {
        char sub[160];
        snprintf(sub, sizeof sub, "%s[%d]", path, i);
        if (jv_number(doc, c, sub, &out[i]) != 0)
            return -1;
    }
    return 0;
}

int jv_vec3(const jv_doc *doc, const cJSON *node, const char *path, vec3f *out)
{
    double d[3];
    if (jv_numbers(doc, node, path, 3, "[x, y, z]", d) != 0)
        return -1;
    *out = vec3f_make((float)d[0], (float)d[1], (float)d[2]);
    return 0;
}

int jv_point(const jv_doc *doc, const cJSON *node, const char *path, vec3d *out)
{
    double d[3];
    if (jv_numbers(doc, node, path, 3, "[x, y, z]", d) != 0)
        return -1;
    out->x = d[0];
    out->y = d[1];
    out->z = d[2];
    return 0;
}

/* A colour: [r, g, b] or one number (grey). */
int jv_colour(const jv_doc *doc, const cJSON *node, const char *path, vec3f *out)
{
    double d[3];
    if (cJSON_IsNumber(node)) {
        if (jv_number(doc, node, path, d) != 0)
            return -1;
        *out = vec3f_make((float)d[0], (float)d[0], (float)d[0]);
        return 0;
    }
    if (!cJSON_IsArray(node))
        return jv_fail(doc, node, "%s: expected a colour ([r, g, b] or one number), found %s", path,
                       jv_type_name(node));
    if (jv_numbers(doc, node, path, 3, "[r, g, b]", d) != 0)
        return -1;
    *out = vec3f_make((float)d[0], (float)d[1], (float)d[2]);
    return 0;
}

const cJSON *jv_member(const cJSON *obj, const char *key)
{
    return cJSON_GetObjectItemCaseSensitive(obj, key);
}

/* A required member; fails naming the object's own node. */
const cJSON *jv_need(const jv_doc *doc, const cJSON *obj, const char *path, const char *key)
{
    const cJSON *m = jv_member(obj, key);
    if (!m)
        jv_fail(doc, obj, "%s: missing \"%s\"", path, key);
    return m;
}

/* Reads an array of at least lo, at most hi points into pts (malloc'd). */
int jv_points(const jv_doc *doc, const cJSON *node, const char *path, int lo, int hi, vec3d **pts,
              int *count)
{
    const cJSON *c;
    int n, i = 0;
    *pts = NULL;
    if (!cJSON_IsArray(node))
        return jv_fail(doc, node, "%s: expected an array of points [x, y, z], found %s", path,
                       jv_type_name(node));
    n = cJSON_GetArraySize(node);
    if (n < lo || n > hi) {
        if (lo == hi)
            return jv_fail(doc, node, "%s: expected %d points, found %d", path, lo, n);
        return jv_fail(doc, node, "%s: expected %d..%d points, found %d", path, lo, hi, n);
    }
    *pts = malloc((size_t)n * sizeof **pts);
    if (!*pts)
        return jv_oom(doc, node);
    for (c = node->child; c; c = c->next, i++) {
        char sub[160];
        snprintf(sub, sizeof sub, "%s[%d]", path, i);
        if (jv_point(doc, c, sub, &(*pts)[i]) != 0) {
            free(*pts);
            *pts = NULL;
            return -1;
        }
    }
    *count = n;
    return 0;
}
