/* Inside the JSON reader: a "transform" value read into a scene_xform (xform.h), for the
 * placements of meshes. Its forms:
 *
 *   [step, step, ...]   the steps applied in order (the first to the object first)
 *   step                one step alone
 *
 * where a step is an object with one key:
 *
 *   {"translate": [x, y, z]}
 *   {"scale": s} or {"scale": [sx, sy, sz]}             no factor zero
 *   {"rotate": {"axis": [x, y, z], "degrees": d}}       right-handed, about an axis
 *                                                       through the origin; axis not zero
 *   {"matrix": [[a, b, c, tx], [d, e, f, ty], [g, h, i, tz], [0, 0, 0, 1]]}
 *                                                       rows acting on column vectors;
 *                                                       the last row 0 0 0 1, invertible
 *
 * The composition is in double precision and must be invertible. */
#ifndef CW_SCENE_JSON_XFORM_H
#define CW_SCENE_JSON_XFORM_H

#include <cJSON.h>

#include "scene.h"
#include "scene_json_value.h"

/* Reads node into *x; path names it in messages ("objects[3].transform"). Returns 0, or
 * -1 having failed with the line of the offending part. */
int jx_transform(const jv_doc *doc, const cJSON *node, const char *path, scene_xform *x);

#endif
