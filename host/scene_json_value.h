/* Inside the JSON reader (scene_json.c): the parsed document, and its values checked
 * against the types the schema wants, each failing with "name:line: path: what is wrong",
 * the line being where the offending node starts in the text. cJSON keeps no line
 * numbers: jv_line walks the text and the tree together, in document order, until it
 * reaches the node (object members are located at their key); that walk runs only when
 * there is an error, so a good scene costs nothing extra. */
#ifndef CW_SCENE_JSON_VALUE_H
#define CW_SCENE_JSON_VALUE_H

#include <cJSON.h>
#include <stddef.h>

#include "scene.h"
#include "scene_io.h"

typedef struct {
    const char *text; /* the NUL-terminated text that cJSON parsed */
    size_t len;
    const cJSON *root;    /* the parsed tree */
    const scene_msg *msg; /* where messages go */
} jv_doc;

/* The line where node's value starts (for object members: where its key starts). */
long jv_line(const jv_doc *doc, const cJSON *node);
/* Fails with the line of node `at` (line 1 when NULL). Returns -1. */
int jv_fail(const jv_doc *doc, const cJSON *at, const char *fmt, ...) SCENE_PRINTF(3, 4);
int jv_oom(const jv_doc *doc, const cJSON *at);
/* "a number", "an array", ... for messages. */
const char *jv_type_name(const cJSON *n);

/* Checks that node is an object whose keys are all in `allowed` (a NULL-terminated list;
 * NULL: any key) and unique. `path` names it in messages ("camera", "objects[3]"). */
int jv_check_object(const jv_doc *doc, const cJSON *node, const char *path,
                    const char *const *allowed);
/* The member named key, or NULL. */
const cJSON *jv_member(const cJSON *obj, const char *key);
/* A required member; when missing, fails naming the object's own node and returns NULL. */
const cJSON *jv_need(const jv_doc *doc, const cJSON *obj, const char *path, const char *key);

/* A finite number of magnitude at most CW_MAX_ABS. */
int jv_number(const jv_doc *doc, const cJSON *node, const char *path, double *out);
/* An integer in lo..hi. */
int jv_int(const jv_doc *doc, const cJSON *node, const char *path, int lo, int hi, int *out);
/* An array of exactly n numbers; `form` shows the expected shape, e.g. "[x, y, z]". */
int jv_numbers(const jv_doc *doc, const cJSON *node, const char *path, int n, const char *form,
               double *out);
/* A direction [x, y, z] (float). */
int jv_vec3(const jv_doc *doc, const cJSON *node, const char *path, vec3f *out);
/* A position [x, y, z] (double: scene.h, vec3d). */
int jv_point(const jv_doc *doc, const cJSON *node, const char *path, vec3d *out);
/* A colour: [r, g, b] or one number (grey). */
int jv_colour(const jv_doc *doc, const cJSON *node, const char *path, vec3f *out);
/* An array of at least lo, at most hi points, into *pts (malloc'd; NULL on failure). */
int jv_points(const jv_doc *doc, const cJSON *node, const char *path, int lo, int hi, vec3d **pts,
              int *count);

#endif
