/* The scene model: what a reader produces and the renderer consumes.
 * Readers know nothing of OpenCL; the renderer knows nothing of file formats. */
#ifndef CW_SCENE_H
#define CW_SCENE_H

#include <stddef.h>

typedef struct {
    float x, y, z;
} vec3f;

enum scene_projection {
    SCENE_PERSPECTIVE = 0,
    SCENE_ORTHOGRAPHIC = 1,
    SCENE_OBLIQUE = 2,
};

typedef struct {
    enum scene_projection projection;
    vec3f eye;
    vec3f u, v, w;       /* orthonormal viewing basis, w points backwards (away from the view) */
    float l, r, b, t;    /* image-plane window, in u and v units */
    float d;             /* perspective: distance from eye to image plane */
    vec3f dir;           /* oblique: the common ray direction (world space, unit length) */
    float nff_angle_deg; /* > 0: NFF angle, spanning the centres of the outer pixel rows */
    float fov_deg;       /* > 0: vertical field of view at the image edges (perspective) */
                         /* with either, the window is derived in scene_finish() from the
                          * final image size, so a size override keeps square pixels */
} scene_camera;

typedef struct {
    vec3f ka, kd, ks, km; /* ambient, diffuse, specular, mirror: RGB */
    float p;              /* Phong exponent */
    vec3f kt;             /* transmission: weight of the refracted ray */
    float ior;            /* index of refraction */
} scene_material;

typedef struct {
    vec3f position;
    vec3f intensity; /* RGB */
} scene_light;

typedef struct {
    vec3f center;
    float radius; /* NFF allows a negative radius (inside visible); stored as given */
    int material;
} scene_sphere;

typedef struct {
    vec3f p[3];
    vec3f n[3]; /* vertex normals, used when has_normals */
    int has_normals;
    int material;
} scene_triangle;

typedef struct {
    int first; /* index of the first vertex in scene.poly_verts */
    int count; /* number of vertices, >= 3 */
    int material;
} scene_polygon;

typedef struct {
    vec3f base, apex;
    float base_radius, apex_radius;
    int material;
} scene_cone;

/* A growable array of elements of one type. */
typedef struct {
    void *data;
    size_t count, cap;
} scene_array;

typedef struct {
    char *name; /* scene name: the file's base name without extension */
    scene_camera camera;
    int width, height;
    int max_depth;
    vec3f background;
    vec3f ambient;

    scene_array materials;  /* scene_material */
    scene_array lights;     /* scene_light */
    scene_array spheres;    /* scene_sphere */
    scene_array triangles;  /* scene_triangle */
    scene_array polygons;   /* scene_polygon */
    scene_array poly_verts; /* vec3f */
    scene_array cones;      /* scene_cone: open cones and cylinders */
} scene;

#define SCENE_AT(arr, type, i) (((type *)(arr).data)[i])
#define SCENE_DEFAULT_MAX_DEPTH 5

/* Sets defaults: no objects, black background, zero ambient, depth 5. */
void scene_init(scene *s);
void scene_free(scene *s);

/* Sets s->name to the base name of path without its extension ("scene" if empty).
 * Returns 0, or -1 when out of memory. */
int scene_set_name(scene *s, const char *path);

/* Appends one element of elem_size bytes; returns its index or -1 when out of memory. */
long scene_push(scene_array *a, const void *elem, size_t elem_size);

/* Completes a loaded scene for the given image size (width/height may be 0 to keep the
 * scene's own): derives the NFF window, checks that the camera basis is orthonormal.
 * Returns 0, or -1 with a message in err. */
int scene_finish(scene *s, int width, int height, int max_depth, char *err, size_t errlen);

/* Checks a scene's consistency: a known projection, finite values everywhere, material
 * indices in range, polygon vertex ranges inside poly_verts, non-zero vertex normals.
 * scene_finish calls it. Returns 0, or -1 with "name: what is wrong" in err. */
int scene_check(const scene *s, char *err, size_t errlen);

/* Checks the view alone, as scene_finish would for the scene's own image size and depth:
 * the size (1..65536 per side, at most SCENE_MAX_PIXELS), the depth, the window derived
 * from an NFF angle or a field of view, finite camera values, l < r and b < t, a positive
 * perspective distance, an orthonormal basis, an oblique direction into the view. Changes
 * nothing. Readers call it so that a bad view fails with a line number. Returns 0, or -1
 * with the reason (no name prefix) in err. */
int scene_check_view(const scene *s, char *err, size_t errlen);

/* Limits on what a reader accepts. */
#define SCENE_MAX_SIDE 65536            /* pixels per image side */
#define SCENE_MAX_PIXELS (1L << 28)     /* pixels per image */
#define SCENE_MAX_FILE_BYTES (1L << 30) /* bytes per scene file */

/* Loads a scene, choosing the reader by extension (.nff, .json). Returns 0, or -1 with
 * "file:line: message" in err. */
int scene_load(const char *path, scene *s, char *err, size_t errlen);

/* Reads a whole file into a malloc'd NUL-terminated buffer (directories, unreadable files
 * and files over SCENE_MAX_FILE_BYTES are errors naming the path and the reason). Reading
 * stops after the first chunk holding a NUL byte: that is binary, which the readers reject
 * with its line, so /dev/zero is not read forever. Returns 0, or -1 with err. */
int scene_read_file(const char *path, char **out, size_t *outlen, char *err, size_t errlen);

/* A reader's parser: text in buf[0..len), writable, with buf[len] == '\0'. */
typedef int (*scene_text_parser)(char *buf, size_t len, const char *name, scene *s, char *err,
                                 size_t errlen);
/* Runs a parser on a NUL-terminated copy of text, or on the contents of a file. */
int scene_parse_copy(scene_text_parser parse, const char *text, size_t len, const char *name,
                     scene *s, char *err, size_t errlen);
int scene_parse_file(scene_text_parser parse, const char *path, scene *s, char *err, size_t errlen);

/* The readers. *_load reads a file; *_parse reads text in memory, naming it `name` in
 * errors. Both return 0, or -1 with "name:line: message" in err. */
int nff_load(const char *path, scene *s, char *err, size_t errlen);
int nff_parse(const char *text, size_t len, const char *name, scene *s, char *err, size_t errlen);
int json_scene_load(const char *path, scene *s, char *err, size_t errlen);
int json_scene_parse(const char *text, size_t len, const char *name, scene *s, char *err,
                     size_t errlen);

/* 1 when the triangle has no area in float arithmetic: the cross product of its edges, as
 * the kernels compute it, is exactly zero (coincident or collinear vertices). Such a
 * triangle has no normal and is left out of rendering. */
int scene_triangle_degenerate(const scene_triangle *t);

/* Copies text from a file into out for an error message: at most max bytes of the
 * NUL-terminated string s, with control characters and bytes that are not UTF-8 written as
 * \xNN, and "..." when cut short. out is always NUL-terminated. Returns out. */
const char *scene_printable(const char *s, size_t max, char *out, size_t outlen);

/* For a message about a number stored as a float: when rounding to single precision
 * changes x into 0 or +-180 (bounds the readers check), " (V in single precision)" in buf;
 * otherwise "". Returns buf. */
const char *scene_single_note(double x, char *buf, size_t len);

/* Vector helpers shared by readers and the camera set-up. */
vec3f vec3f_make(float x, float y, float z);
vec3f vec3f_sub(vec3f a, vec3f b);
vec3f vec3f_cross(vec3f a, vec3f b);
float vec3f_dot(vec3f a, vec3f b);
float vec3f_length(vec3f a);
/* Returns 0 and the unit vector, or -1 when a is zero or not finite. */
int vec3f_normalize(vec3f a, vec3f *out);
/* Newell's normal of a polygon, not normalised: its length is twice the area. */
void scene_newell(const vec3f *v, int n, double out[3]);
/* The plane the renderer uses for a polygon: the unit Newell normal, the mean offset
 * n.x = offset of the vertices, and the dominant axis of the normal (dropped for the 2-D
 * inside test). Returns 0, or -1 for a degenerate polygon. */
int scene_polygon_plane(const vec3f *v, int n, double normal[3], double *offset, int *axis);
/* Builds u, v, w from a view direction (eye towards look-at) and an up vector, as in
 * Shirley & Marschner: w = -view/|view|, u = up x w / |up x w|, v = w x u.
 * Returns -1 when the view is zero or up is parallel to it. */
int scene_camera_basis(scene_camera *c, vec3f view, vec3f up);

#endif
