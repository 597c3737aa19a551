/* The scene model: the types a reader produces and the renderer consumes, their growable
 * arrays, defaults and the checks a finished scene passes. Readers know nothing of OpenCL;
 * the renderer knows nothing of file formats; the model knows neither. Geometry on these
 * types is in scene_geom.h, reading files in scene_load.h. */
#ifndef CW_SCENE_H
#define CW_SCENE_H

#include <stddef.h>

#include "config.h"

typedef struct {
    float x, y, z;
} vec3f;

/* A position in world coordinates: kept in double precision from the readers through
 * every transform, and converted to float only for the kernels, relative to a local
 * origin near the camera (devscene.c), so that a scene far from 0 loses nothing. Colours,
 * directions and normals stay vec3f. */
typedef struct {
    double x, y, z;
} vec3d;

enum scene_projection {
    SCENE_PERSPECTIVE = 0,
    SCENE_ORTHOGRAPHIC = 1,
    SCENE_OBLIQUE = 2,
};

typedef struct {
    vec3d eye; /* first: no padding, so that cameras compare with memcmp */
    enum scene_projection projection;
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
    vec3d position;
    vec3f intensity; /* RGB */
} scene_light;

typedef struct {
    vec3d center;
    float radius; /* NFF allows a negative radius (inside visible); stored as given */
    int material;
} scene_sphere;

typedef struct {
    vec3d p[3];
    int normals; /* smooth: 1 + index of the first of its three vertex normals in
                  * scene.tri_normals (scene_triangle_normals); 0: flat */
    int material;
} scene_triangle;

typedef struct {
    int first; /* index of the first vertex in scene.poly_verts */
    int count; /* number of vertices, >= 3 */
    int material;
} scene_polygon;

typedef struct {
    vec3d base, apex;
    float base_radius, apex_radius;
    int material;
} scene_cone;

/* A mesh read from a file (host/mesh_import.c): its triangles (scene_triangle, vertex
 * normals in scene.tri_normals as for any triangle) kept in the mesh's own coordinates in
 * scene.mesh_tris, and placed in the world only by instances (scene_mesh.h). */
typedef struct {
    size_t first, count; /* its triangles: scene.mesh_tris[first .. first + count) */
    char *source;        /* the file it was read from, for messages (owned; may be NULL) */
} scene_mesh;

/* An affine transform in double precision: p' = A p + t, with m[4r + c] = A[r][c] for
 * c < 3 and m[4r + 3] = t[r] (row-major 3x4). host/xform.h composes and applies them. */
typedef struct {
    double m[12];
} scene_xform;

/* One placement of a mesh in the world. */
typedef struct {
    int mesh;             /* index into scene.meshes */
    int material;         /* >= 0: every triangle of the mesh takes this material here;
                           * -1: each keeps its own */
    scene_xform to_world; /* mesh coordinates to world coordinates; invertible */
} scene_instance;

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

    scene_array materials;   /* scene_material */
    scene_array lights;      /* scene_light */
    scene_array spheres;     /* scene_sphere */
    scene_array triangles;   /* scene_triangle */
    scene_array tri_normals; /* vec3f: the vertex normals of smooth triangles, three each */
    scene_array polygons;    /* scene_polygon */
    scene_array poly_verts;  /* vec3d */
    scene_array cones;       /* scene_cone: open cones and cylinders */
    scene_array meshes;      /* scene_mesh */
    scene_array mesh_tris;   /* scene_triangle: the meshes' triangles, in mesh coordinates */
    scene_array instances;   /* scene_instance: placements of the meshes */
} scene;

#define SCENE_AT(arr, type, i) (((type *)(arr).data)[i])

/* Sets defaults: no objects, black background, zero ambient, depth CW_DEFAULT_DEPTH. */
void scene_init(scene *s);
void scene_free(scene *s);
/* Frees and empties the primitive arrays (spheres, triangles and their vertex normals,
 * polygons and their vertices, cones); the camera, size, lights, materials, meshes and
 * instances stay. For a caller done with the primitives (see renderer_set_scene_dropping). */
void scene_drop_primitives(scene *s);

/* Sets s->name to the base name of path without its extension ("scene" if empty).
 * Returns 0, or -1 when out of memory. */
int scene_set_name(scene *s, const char *path);

/* Appends one element of elem_size bytes; returns its index or -1 when out of memory. */
long scene_push(scene_array *a, const void *elem, size_t elem_size);

/* Appends a smooth triangle with vertex normals n[3] (or a flat one when n is NULL).
 * Returns its index or -1 when out of memory. */
long scene_push_triangle(scene *s, const vec3d p[3], const vec3f *n, int material);

/* The same for a triangle of a mesh, in mesh coordinates (scene.mesh_tris); the caller
 * then sets the mesh's count. Every triangle owns its three normals (never shared):
 * scene_flatten_instances transforms them in place. */
long scene_push_mesh_triangle(scene *s, const vec3d p[3], const vec3f *n, int material);

/* The three vertex normals of triangle t, or NULL when it is flat. */
const vec3f *scene_triangle_normals(const scene *s, const scene_triangle *t);

/* Completes a loaded scene for the given image size (width/height may be 0 to keep the
 * scene's own): derives the NFF window, checks that the camera basis is orthonormal,
 * flattens the instances of meshes placed only once (scene_mesh.h).
 * Returns 0, or -1 with a message in err. */
int scene_finish(scene *s, int width, int height, int max_depth, char *err, size_t errlen);

/* Checks a scene's consistency: a known projection, finite values everywhere, material
 * indices in range, polygon vertex ranges inside poly_verts, non-zero vertex normals,
 * mesh triangle ranges inside mesh_tris, instances of existing meshes with finite,
 * invertible transforms.
 * scene_finish calls it. Returns 0, or -1 with "name: what is wrong" in err. */
int scene_check(const scene *s, char *err, size_t errlen);

/* Checks the view alone, as scene_finish would for the scene's own image size and depth:
 * the size (1..CW_MAX_SIDE per side, at most CW_MAX_PIXELS), the depth (1..CW_MAX_DEPTH),
 * the window derived from an NFF angle or a field of view, finite camera values, l < r
 * and b < t, a positive perspective distance, an orthonormal basis, an oblique direction
 * into the view. Changes nothing. Readers call it so that a bad view fails with a line
 * number. Returns 0, or -1 with the reason (no name prefix) in err. */
int scene_check_view(const scene *s, char *err, size_t errlen);

#endif
