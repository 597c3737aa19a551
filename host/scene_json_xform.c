/* The JSON reader's transforms: steps (translate, scale, rotate, matrix) composed in
 * order into one affine transform in double precision. See scene_json_xform.h. */
#include "scene_json_xform.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "xform.h"

/* {"rotate": {"axis": [x, y, z], "degrees": d}} */
static int read_rotate(const jv_doc *doc, const cJSON *v, const char *path, scene_xform *x)
{
    static const char *const keys[] = {"axis", "degrees", NULL};
    char sub[256];
    const cJSON *axis, *degn;
    double a[3], deg;
    if (jv_check_object(doc, v, path, keys) != 0)
        return -1;
    snprintf(sub, sizeof sub, "%s.axis", path);
    if (!(axis = jv_need(doc, v, path, "axis")) ||
        jv_numbers(doc, axis, sub, 3, "[x, y, z]", a) != 0)
        return -1;
    snprintf(sub, sizeof sub, "%s.degrees", path);
    if (!(degn = jv_need(doc, v, path, "degrees")) || jv_number(doc, degn, sub, &deg) != 0)
        return -1;
    if (xform_rotate(x, a[0], a[1], a[2], deg) != 0)
        return jv_fail(doc, axis, "%s.axis: the axis is zero", path);
    return 0;
}

/* {"matrix": [[4 numbers] x 4]} */
static int read_matrix(const jv_doc *doc, const cJSON *v, const char *path, scene_xform *x)
{
    double m[16];
    const cJSON *row;
    char sub[256];
    int i = 0;
    scene_xform inv;
    if (!cJSON_IsArray(v))
        return jv_fail(doc, v, "%s: expected 4 rows of 4 numbers, found %s", path, jv_type_name(v));
    if (cJSON_GetArraySize(v) != 4)
        return jv_fail(doc, v, "%s: expected 4 rows of 4 numbers, found %d rows", path,
                       cJSON_GetArraySize(v));
    for (row = v->child; row; row = row->next, i++) {
        snprintf(sub, sizeof sub, "%s[%d]", path, i);
        if (jv_numbers(doc, row, sub, 4, "[a, b, c, d]", m + 4 * i) != 0)
            return -1;
    }
    if (xform_from_matrix(x, m) != 0)
        return jv_fail(doc, v->child->next->next->next,
                       "%s[3]: the last row must be [0, 0, 0, 1] (an affine transform), found "
                       "[%g, %g, %g, %g]",
                       path, m[12], m[13], m[14], m[15]);
    if (xform_invert(x, &inv) != 0)
        return jv_fail(doc, v, "%s: the matrix is singular (determinant %g): it is not invertible",
                       path, xform_det(x));
    return 0;
}

/* One step: an object with one key. */
static int read_step(const jv_doc *doc, const cJSON *step, const char *path, scene_xform *x)
{
    static const char *const keys[] = {"translate", "scale", "rotate", "matrix", NULL};
    char sub[224];
    const cJSON *v;
    double t[3];
    if (jv_check_object(doc, step, path, keys) != 0)
        return -1;
    if (cJSON_GetArraySize(step) != 1)
        return jv_fail(doc, step,
                       "%s: a step has exactly one of \"translate\", \"scale\", \"rotate\" and "
                       "\"matrix\", found %d keys",
                       path, cJSON_GetArraySize(step));
    v = step->child;
    snprintf(sub, sizeof sub, "%s.%s", path, v->string);
    if (strcmp(v->string, "translate") == 0) {
        if (jv_numbers(doc, v, sub, 3, "[x, y, z]", t) != 0)
            return -1;
        xform_translate(x, t[0], t[1], t[2]);
    } else if (strcmp(v->string, "scale") == 0) {
        if (cJSON_IsNumber(v)) {
            if (jv_number(doc, v, sub, &t[0]) != 0)
                return -1;
            t[1] = t[2] = t[0];
        } else if (jv_numbers(doc, v, sub, 3, "one number or [sx, sy, sz]", t) != 0) {
            return -1;
        }
        if (t[0] == 0 || t[1] == 0 || t[2] == 0)
            return jv_fail(doc, v, "%s: a scale factor of zero is singular (not invertible)", sub);
        xform_scale(x, t[0], t[1], t[2]);
    } else if (strcmp(v->string, "rotate") == 0) {
        return read_rotate(doc, v, sub, x);
    } else {
        return read_matrix(doc, v, sub, x);
    }
    return 0;
}

int jx_transform(const jv_doc *doc, const cJSON *node, const char *path, scene_xform *x)
{
    scene_xform step, inv;
    const cJSON *s;
    char sub[192];
    int i = 0;
    if (cJSON_IsObject(node))
        return read_step(doc, node, path, x);
    if (!cJSON_IsArray(node))
        return jv_fail(doc, node,
                       "%s: expected an array of steps or one step (an object with "
                       "\"translate\", \"scale\", \"rotate\" or \"matrix\"), found %s",
                       path, jv_type_name(node));
    xform_identity(x);
    for (s = node->child; s; s = s->next, i++) {
        snprintf(sub, sizeof sub, "%s[%d]", path, i);
        if (read_step(doc, s, sub, &step) != 0)
            return -1;
        xform_compose(x, &step, x); /* this step after the ones before */
    }
    if (xform_invert(x, &inv) != 0)
        return jv_fail(doc, node,
                       "%s: the steps compose into a transform that is not invertible "
                       "(determinant %g)",
                       path, xform_det(x));
    return 0;
}
