/* Mesh files through assimp (host/mesh_import.c, mesh_material.c, mesh_scene.c), on the
 * small meshes of tests/scenes/mesh/ (written by tests/scenes/mesh/generate, checked here
 * to be what it writes):
 *   - the material mapping of MTL and glTF against the table of docs/scene-formats.md;
 *     PLY and STL get the default material;
 *   - a glTF file's own camera and light, placed by their nodes;
 *   - one file of each format (OBJ+MTL, PLY ASCII and binary, glTF .gltf and .glb, STL)
 *     against a reference image in tests/ref/ (the tolerance of test_regress: at most 0.1%
 *     of the pixels over 1e-3, mean below 1e-4; the image and a diff image in
 *     build/test-output/ on failure; CW_UPDATE_REFS=1 rewrites them);
 *   - the same sphere as OBJ, PLY (both) and glTF (both) gives the same image once the
 *     materials are made the same (at most 1e-5 apart anywhere);
 *   - a mesh whose nodes carry a transform renders like the same mesh pre-transformed
 *     (the same tolerance as the references). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "testutil.h"

#include "image.h"
#include "image_diff.h"
#include "image_read.h"
#include "mesh_import.h"
#include "render.h"
#include "scene.h"
#include "scene_load.h"

#define MESH_DIR "tests/scenes/mesh"
#define REF_DIR "tests/ref"
#define OUT_DIR "build/test-output"
#define PIXEL_TOL 1e-3
#define MAX_OVER_FRACTION 0.001
#define MAX_MEAN 1e-4
#define W 64
#define H 48

TU_RENDERER_FIXTURE(0)
static char err[2048];

static void near3(vec3f got, float x, float y, float z, const char *what)
{
    if (fabsf(got.x - x) > 1e-5f || fabsf(got.y - y) > 1e-5f || fabsf(got.z - z) > 1e-5f)
        fail_msg("%s: got (%g %g %g), expected (%g %g %g)", what, got.x, got.y, got.z, x, y, z);
}

static void nearf(float got, float want, const char *what)
{
    if (fabsf(got - want) > 1e-4f * (1.0f + fabsf(want)))
        fail_msg("%s: got %g, expected %g", what, got, want);
}

/* The material of the mesh triangle whose first vertex has this x (materials.obj puts
 * the k-th material's triangle at x = 3k). */
static const scene_material *material_at_x(const scene *s, double x)
{
    for (size_t i = 0; i < s->mesh_tris.count; i++) {
        const scene_triangle *t = &SCENE_AT(s->mesh_tris, scene_triangle, i);
        for (int k = 0; k < 3; k++)
            if (t->p[k].x == x && t->p[k].y == 0.0 && t->p[(k + 1) % 3].x == x + 1)
                return &SCENE_AT(s->materials, scene_material, t->material);
    }
    fail_msg("no triangle at x = %g", x);
    return NULL;
}

static void load(const char *path, scene *s)
{
    scene_init(s);
    if (scene_load(path, s, err, sizeof err) != 0)
        fail_msg("%s", err);
}

static void test_mtl_materials(void **state)
{
    scene s;
    const scene_material *m;
    (void)state;
    load(MESH_DIR "/materials.obj", &s);
    m = material_at_x(&s, 0); /* plain: Kd only; no Ka: ambient like diffuse */
    near3(m->kd, 0.5f, 0.6f, 0.7f, "plain kd");
    near3(m->ka, 0.5f, 0.6f, 0.7f, "plain ka");
    near3(m->ks, 0, 0, 0, "plain ks");
    near3(m->km, 0, 0, 0, "plain km");
    near3(m->kt, 0, 0, 0, "plain kt");
    m = material_at_x(&s, 3); /* shiny: Ka, Kd, Ks, Ns, illum 2 */
    near3(m->ka, 0.1f, 0.1f, 0.1f, "shiny ka");
    near3(m->kd, 0.2f, 0.3f, 0.4f, "shiny kd");
    near3(m->ks, 0.5f, 0.5f, 0.5f, "shiny ks");
    nearf(m->p, 64, "shiny p");
    near3(m->km, 0, 0, 0, "shiny km (illum 2: no mirror)");
    m = material_at_x(&s, 6); /* mirror: illum 3, km = Ks */
    near3(m->km, 0.8f, 0.7f, 0.6f, "mirror km");
    nearf(m->p, 200, "mirror p");
    m = material_at_x(&s, 9); /* glass: illum 7, d 0.1, Ni 1.5 */
    near3(m->kt, 0.9f, 0.9f, 0.9f, "glass kt = 1 - d");
    near3(m->km, 0.3f, 0.3f, 0.3f, "glass km = Ks");
    nearf(m->ior, 1.5f, "glass ior");
    m = material_at_x(&s, 12); /* tinted: illum 6, Tf, Ni 1.33, d 1 */
    near3(m->kt, 0.9f, 0.5f, 0.1f, "tinted kt = Tf");
    nearf(m->ior, 1.33f, "tinted ior");
    m = material_at_x(&s, 15); /* faded: illum 1, d 0.25: see-through, index 1 */
    near3(m->kt, 0.75f, 0.75f, 0.75f, "faded kt");
    nearf(m->ior, 1.0f, "faded ior");
    near3(m->km, 0, 0, 0, "faded km");
    scene_free(&s);
}

/* The material of the glTF primitive k of materials.gltf (16 triangles each). */
static const scene_material *gltf_material(const scene *s, int k)
{
    const scene_triangle *t = &SCENE_AT(s->mesh_tris, scene_triangle, 16 * (size_t)k);
    return &SCENE_AT(s->materials, scene_material, t->material);
}

static void test_gltf_materials(void **state)
{
    scene s;
    const scene_material *m;
    float f0 = 0.04f; /* ((1.5 - 1) / (1.5 + 1))^2 */
    (void)state;
    load(MESH_DIR "/materials.gltf", &s);
    assert_int_equal(s.mesh_tris.count, 80);
    m = gltf_material(&s, 0); /* red: dielectric, roughness 0.3 */
    near3(m->kd, 0.7f, 0.25f, 0.2f, "red kd");
    near3(m->ka, 0.7f, 0.25f, 0.2f, "red ka");
    near3(m->ks, f0, f0, f0, "red ks = F0");
    nearf(m->p, 2.0f / (0.09f * 0.09f) - 2.0f, "red p = 2/alpha^2 - 2, alpha = roughness^2");
    near3(m->km, 0, 0, 0, "red km");
    near3(m->kt, 0, 0, 0, "red kt");
    m = gltf_material(&s, 1); /* gold: metal, roughness 0.1 */
    near3(m->kd, 0, 0, 0, "gold kd");
    near3(m->ks, 1.0f, 0.8f, 0.4f, "gold ks = base");
    near3(m->km, 0.9f, 0.72f, 0.36f, "gold km = base x metallic x (1 - roughness)");
    nearf(m->p, 10000.0f, "gold p (capped)");
    m = gltf_material(&s, 2); /* half metal, rough */
    near3(m->kd, 0.25f, 0.25f, 0.25f, "half kd");
    near3(m->ks, 0.27f, 0.27f, 0.27f, "half ks = mix(F0, base, metallic)");
    near3(m->km, 0, 0, 0, "half km (roughness 1)");
    nearf(m->p, 1.0f, "half p (at least 1)");
    m = gltf_material(&s, 3); /* glass: transmission 0.9, ior 1.5 */
    near3(m->kd, 0.1f, 0.1f, 0.1f, "glass kd");
    near3(m->kt, 0.9f, 0.9f, 0.9f, "glass kt");
    near3(m->km, f0 * 0.9f, f0 * 0.9f, f0 * 0.9f, "glass km");
    nearf(m->ior, 1.5f, "glass ior");
    m = gltf_material(&s, 4); /* glTF's defaults: metallic 1, roughness 1, white */
    near3(m->kd, 0, 0, 0, "default kd");
    near3(m->ks, 1, 1, 1, "default ks");
    scene_free(&s);
}

static void test_ply_stl_default_material(void **state)
{
    static const char *const files[] = {MESH_DIR "/ico-ascii.ply", MESH_DIR "/ico-binary.ply",
                                        MESH_DIR "/ico.stl"};
    (void)state;
    for (size_t i = 0; i < sizeof files / sizeof files[0]; i++) {
        scene s;
        const scene_material *m;
        load(files[i], &s);
        m = &SCENE_AT(s.materials, scene_material,
                      SCENE_AT(s.mesh_tris, scene_triangle, 0).material);
        near3(m->kd, 0.8f, 0.8f, 0.8f, files[i]);
        near3(m->ka, 0.8f, 0.8f, 0.8f, files[i]);
        near3(m->ks, 0, 0, 0, files[i]);
        /* vertex normals kept (STL: assimp gives each vertex its facet's normal) */
        assert_true(SCENE_AT(s.mesh_tris, scene_triangle, 0).normals != 0);
        scene_free(&s);
    }
}

/* camera.gltf: a camera on a node at (4, 0, 0) turned 90 degrees about y (looking down
 * -x), yfov 30 degrees, aspect 4:3; a point light on a node at (3, 3, 1). */
static void test_file_camera_and_light(void **state)
{
    scene s, framed;
    const scene_light *l;
    (void)state;
    load(MESH_DIR "/camera.gltf", &s);
    assert_true(fabs(s.camera.eye.x - 4.0) < 1e-6 && fabs(s.camera.eye.y) < 1e-6 &&
                fabs(s.camera.eye.z) < 1e-6);
    near3(s.camera.w, 1, 0, 0, "camera w (looks down -x)");
    near3(s.camera.v, 0, 1, 0, "camera v");
    nearf(s.camera.fov_deg, 30.0f, "vertical field of view");
    assert_int_equal(s.width, 640);
    assert_int_equal(s.height, 480);
    assert_int_equal(s.lights.count, 1);
    l = &SCENE_AT(s.lights, scene_light, 0);
    assert_true(fabs(l->position.x - 3) < 1e-6 && fabs(l->position.y - 3) < 1e-6 &&
                fabs(l->position.z - 1) < 1e-6);
    near3(l->intensity, 1.0f, 0.9f, 0.8f, "light: colour scaled to a brightest channel of 1");
    /* the same sphere without camera and lights: the framing camera and two lights */
    load(MESH_DIR "/ico.gltf", &framed);
    assert_int_equal(framed.lights.count, 2);
    nearf(framed.camera.fov_deg, 40.0f, "default field of view");
    assert_true(framed.camera.eye.x > 0 && framed.camera.eye.y > 0 && framed.camera.eye.z > 0);
    scene_free(&framed);
    scene_free(&s);
}

/* Renders path at W x H; with one_material, every material is made the same first. */
static void render_file(const char *path, int one_material, image *img)
{
    scene s;
    load(path, &s);
    if (one_material) {
        scene_material m;
        memset(&m, 0, sizeof m);
        m.ka = m.kd = vec3f_make(0.6f, 0.5f, 0.4f);
        m.ks = vec3f_make(0.3f, 0.3f, 0.3f);
        m.p = 30.0f;
        m.ior = 1.0f;
        for (size_t i = 0; i < s.materials.count; i++)
            SCENE_AT(s.materials, scene_material, i) = m;
    }
    if (scene_finish(&s, W, H, 0, err, sizeof err) != 0 ||
        renderer_set_scene(R, &s, err, sizeof err) != 0 ||
        renderer_render(R, img, err, sizeof err) != 0)
        fail_msg("%s: %s", path, err);
    scene_free(&s);
}

/* Compares a with b (the reference); on failure writes a and a diff image. */
static void compare(const image *a, const image *b, const char *name, double tol,
                    double over_fraction, double max_mean)
{
    image_diff_stats st;
    char out_path[256], diff_path[256];
    long limit = (long)(over_fraction * (double)a->width * a->height);
    assert_int_equal(image_compare(a, b, NULL, tol, &st), 0);
    printf("  %s: max |diff| %.3g at (%d,%d), mean %.3g, %ld pixels over %g (limit %ld)\n", name,
           st.max_abs, st.worst_x, st.worst_y, st.mean_abs, st.over, tol, limit);
    if (st.over > limit || st.mean_abs > max_mean) {
        snprintf(out_path, sizeof out_path, "%s/%s.exr", OUT_DIR, name);
        snprintf(diff_path, sizeof diff_path, "%s/%s-diff.png", OUT_DIR, name);
        mkdir("build", 0777);
        mkdir(OUT_DIR, 0777);
        if (image_write(a, out_path, err, sizeof err) != 0 ||
            image_write_diff(a, b, NULL, tol, 10.0, diff_path, err, sizeof err) != 0)
            fprintf(stderr, "  could not write the failure images: %s\n", err);
        else
            fprintf(stderr, "  rendered image: %s, diff image: %s\n", out_path, diff_path);
        fail_msg("%s differs beyond the tolerance", name);
    }
}

static void test_formats_against_references(void **state)
{
    static const char *const names[] = {"ico.obj",  "ico-ascii.ply", "ico-binary.ply",
                                        "ico.gltf", "ico.glb",       "ico.stl"};
    (void)state;
    for (size_t i = 0; i < sizeof names / sizeof names[0]; i++) {
        char path[256], ref_path[256], name[64];
        image img, ref;
        snprintf(path, sizeof path, "%s/%s", MESH_DIR, names[i]);
        snprintf(name, sizeof name, "mesh-%s", names[i]);
        *strrchr(name, '.') = '-';
        snprintf(ref_path, sizeof ref_path, "%s/%s.exr", REF_DIR, name);
        render_file(path, 0, &img);
        if (getenv("CW_UPDATE_REFS")) {
            if (image_write(&img, ref_path, err, sizeof err) != 0)
                fail_msg("%s", err);
            printf("  updated %s\n", ref_path);
        } else {
            if (image_read_exr(ref_path, &ref, err, sizeof err) != 0)
                fail_msg("reference: %s", err);
            compare(&img, &ref, name, PIXEL_TOL, MAX_OVER_FRACTION, MAX_MEAN);
            image_free(&ref);
        }
        image_free(&img);
    }
}

static void test_same_mesh_same_image(void **state)
{
    static const char *const names[] = {"ico-ascii.ply", "ico-binary.ply", "ico.gltf", "ico.glb"};
    image obj, img;
    (void)state;
    render_file(MESH_DIR "/ico.obj", 1, &obj);
    for (size_t i = 0; i < sizeof names / sizeof names[0]; i++) {
        char path[256], name[64];
        snprintf(path, sizeof path, "%s/%s", MESH_DIR, names[i]);
        snprintf(name, sizeof name, "mesh-same-%s", names[i]);
        render_file(path, 1, &img);
        compare(&img, &obj, name, 1e-5, 0.0, 1e-6);
        image_free(&img);
    }
    /* and the check can fail: the flat STL sphere is not the smooth one */
    render_file(MESH_DIR "/ico.stl", 1, &img);
    {
        image_diff_stats st;
        assert_int_equal(image_compare(&img, &obj, NULL, 1e-5, &st), 0);
        printf("  flat STL against the smooth OBJ: %ld pixels over 1e-5\n", st.over);
        assert_true(st.over > 100);
    }
    image_free(&img);
    image_free(&obj);
}

static void test_node_transforms(void **state)
{
    image moved, flat;
    (void)state;
    render_file(MESH_DIR "/ico-moved.gltf", 0, &moved);
    render_file(MESH_DIR "/ico-moved-flat.gltf", 0, &flat);
    compare(&moved, &flat, "mesh-node-transform", PIXEL_TOL, MAX_OVER_FRACTION, MAX_MEAN);
    image_free(&moved);
    image_free(&flat);
}

/* The committed meshes are what the generator writes. */
static void test_generator(void **state)
{
    static const char *const files[] = {
        "ico.obj",       "ico.mtl",       "ico-ascii.ply",  "ico-binary.ply", "ico.stl",
        "ico.gltf",      "ico.bin",       "ico.glb",        "ico-moved.gltf", "ico-moved-flat.gltf",
        "materials.obj", "materials.mtl", "materials.gltf", "camera.gltf",    "camera.bin"};
    const char *dir = OUT_DIR "/mesh-generated";
    char cmd[512];
    (void)state;
    mkdir("build", 0777);
    mkdir(OUT_DIR, 0777);
    snprintf(cmd, sizeof cmd, "python3 %s/generate %s", MESH_DIR, dir);
    assert_int_equal(system(cmd), 0);
    for (size_t i = 0; i < sizeof files / sizeof files[0]; i++) {
        snprintf(cmd, sizeof cmd, "cmp %s/%s %s/%s", MESH_DIR, files[i], dir, files[i]);
        if (system(cmd) != 0)
            fail_msg("%s/%s is not what tests/scenes/mesh/generate writes", MESH_DIR, files[i]);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_mtl_materials),
        cmocka_unit_test(test_gltf_materials),
        cmocka_unit_test(test_ply_stl_default_material),
        cmocka_unit_test(test_file_camera_and_light),
        cmocka_unit_test(test_formats_against_references),
        cmocka_unit_test(test_same_mesh_same_image),
        cmocka_unit_test(test_node_transforms),
        cmocka_unit_test(test_generator),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
