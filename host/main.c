/* clwhitted: command line. */
#include <errno.h>
#include <getopt.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "image.h"
#include "preview.h"
#include "render.h"
#include "scene.h"

#define CW_VERSION "0.1.0"

static void usage(FILE *f)
{
    fprintf(f,
            "usage: clwhitted [options] SCENE\n"
            "Renders SCENE (.nff or .json) with an OpenCL Whitted ray tracer.\n"
            "\n"
            "  -o, --output FILE     output image, .exr (linear float) or .png (sRGB 8-bit)\n"
            "                        (default: the scene's name with .exr, in the current folder)\n"
            "  -W, --width N         image width in pixels (default: the scene's)\n"
            "  -H, --height N        image height in pixels (default: the scene's)\n"
            "  -d, --depth N         maximum ray depth, the eye ray being 1 (default: the\n"
            "                        scene's, else 5)\n"
            "      --spp N           samples per pixel, a deterministic stratified pattern\n"
            "                        (default: 1, the pixel centre)\n"
            "      --precision P     robust (default): watertight, error-bounded intersection;\n"
            "                        fast: fast relaxed math and a fixed epsilon\n"
            "      --spd             SPD testing procedure: rays through the pixel corners,\n"
            "                        four corners averaged per pixel\n"
            "      --stats           count rays (eye, shadow, secondary; hits) and print them\n"
            "                        with the time of each phase\n"
            "      --device SPEC     OpenCL device: P:D (platform:device as --list-devices\n"
            "                        prints) or part of its name (default: the first CPU device)\n"
            "      --list-devices    list the OpenCL platforms and devices, then exit\n"
            "      --preview         open a window that shows the render as it refines, with\n"
            "                        camera controls (needs a display; press H in it for keys)\n"
            "      --preview-script FILE  drive the preview from FILE (for tests)\n"
            "  -q, --quiet           print nothing but errors\n"
            "  -h, --help            show this help, then exit\n"
            "      --version         show the version, then exit\n"
            "\n"
            "Exit status: 0 success, 1 input or render error, 2 usage error.\n");
}

static int parse_int(const char *opt, const char *s, int lo, int hi, int *out)
{
    char *end;
    long v;
    errno = 0;
    v = strtol(s, &end, 10);
    if (errno || end == s || *end || v < lo || v > hi) {
        fprintf(stderr, "clwhitted: %s expects an integer in %d..%d, got '%s'\n", opt, lo, hi, s);
        return -1;
    }
    *out = (int)v;
    return 0;
}

/* "dir/name.nff" -> "name.exr" in the current folder. */
static char *default_output(const scene *s)
{
    const char *name = s->name && *s->name ? s->name : "render";
    size_t n = strlen(name) + 5;
    char *out = malloc(n);
    if (out)
        snprintf(out, n, "%s.exr", name);
    return out;
}

static double now_seconds(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + ts.tv_nsec * 1e-9;
}

/* Says which parts of a scene are parsed but not rendered yet. */
static void warn_unrendered(const scene *s)
{
    size_t i, transmitting = 0;
    if (s->cones.count)
        fprintf(stderr,
                "clwhitted: warning: %zu cone(s)/cylinder(s) are parsed but not rendered yet\n",
                s->cones.count);
    for (i = 0; i < s->materials.count; i++) {
        const scene_material *m = &SCENE_AT(s->materials, scene_material, i);
        if (m->kt.x > 0 || m->kt.y > 0 || m->kt.z > 0)
            transmitting++;
    }
    if (transmitting)
        fprintf(stderr,
                "clwhitted: warning: %zu material(s) with transmission: refraction is not "
                "rendered yet (treated as opaque)\n",
                transmitting);
}

int main(int argc, char **argv)
{
    enum { OPT_DEVICE = 256, OPT_LIST, OPT_VERSION, OPT_SPP, OPT_PRECISION, OPT_SPD, OPT_STATS };
    enum { OPT_PREVIEW = 300, OPT_PVS /* --preview-script */ };
    static const struct option longopts[] = {{"output", required_argument, NULL, 'o'},
                                             {"width", required_argument, NULL, 'W'},
                                             {"height", required_argument, NULL, 'H'},
                                             {"depth", required_argument, NULL, 'd'},
                                             {"device", required_argument, NULL, OPT_DEVICE},
                                             {"spp", required_argument, NULL, OPT_SPP},
                                             {"precision", required_argument, NULL, OPT_PRECISION},
                                             {"spd", no_argument, NULL, OPT_SPD},
                                             {"stats", no_argument, NULL, OPT_STATS},
                                             {"list-devices", no_argument, NULL, OPT_LIST},
                                             {"preview", no_argument, NULL, OPT_PREVIEW},
                                             {"preview-script", required_argument, NULL, OPT_PVS},
                                             {"quiet", no_argument, NULL, 'q'},
                                             {"help", no_argument, NULL, 'h'},
                                             {"version", no_argument, NULL, OPT_VERSION},
                                             {NULL, 0, NULL, 0}};
    const char *output = NULL, *device = NULL;
    char *default_out = NULL;
    int width = 0, height = 0, depth = 0, quiet = 0, list = 0, c, rc = 1;
    char err[2048];
    scene s;
    renderer *r = NULL;
    image img = {0, 0, NULL};
    double t0, t_load, t_setup, t_render;
    render_settings settings;
    render_stats st;
    int preview = 0;
    const char *preview_script = NULL;

    render_settings_default(&settings);

    while ((c = getopt_long(argc, argv, "o:W:H:d:qh", longopts, NULL)) != -1) {
        switch (c) {
        case 'o':
            output = optarg;
            break;
        case 'W':
            if (parse_int("--width", optarg, 1, 65536, &width))
                return 2;
            break;
        case 'H':
            if (parse_int("--height", optarg, 1, 65536, &height))
                return 2;
            break;
        case 'd':
            if (parse_int("--depth", optarg, 1, 64, &depth))
                return 2;
            break;
        case OPT_DEVICE:
            device = optarg;
            break;
        case OPT_SPP:
            if (parse_int("--spp", optarg, 1, 65536, &settings.spp))
                return 2;
            break;
        case OPT_PRECISION:
            if (strcmp(optarg, "robust") == 0)
                settings.precision = RENDER_ROBUST;
            else if (strcmp(optarg, "fast") == 0)
                settings.precision = RENDER_FAST;
            else {
                fprintf(stderr,
                        "clwhitted: --precision expects 'robust' or 'fast', got '%s'\n"
                        "Try 'clwhitted --help'.\n",
                        optarg);
                return 2;
            }
            break;
        case OPT_SPD:
            settings.spd = 1;
            break;
        case OPT_STATS:
            settings.stats = 1;
            break;
        case OPT_LIST:
            list = 1;
            break;
        case OPT_PREVIEW:
            preview = 1;
            break;
        case OPT_PVS:
            preview_script = optarg;
            break;
        case 'q':
            quiet = 1;
            break;
        case 'h':
            usage(stdout);
            return 0;
        case OPT_VERSION:
            printf("clwhitted %s\n", CW_VERSION);
            return 0;
        default:
            fprintf(stderr, "Try 'clwhitted --help'.\n");
            return 2;
        }
    }
    if (list) {
        if (renderer_list_devices(err, sizeof err) != 0) {
            fprintf(stderr, "clwhitted: %s\n", err);
            return 1;
        }
        return 0;
    }
    if (output && image_check_path(output, err, sizeof err) != 0) {
        fprintf(stderr, "clwhitted: %s\nTry 'clwhitted --help'.\n", err);
        return 2;
    }
    if (optind != argc - 1) {
        fprintf(stderr, "clwhitted: %s\nTry 'clwhitted --help'.\n",
                optind >= argc ? "no scene file given" : "more than one scene file given");
        return 2;
    }

    t0 = now_seconds();
    scene_init(&s);
    if (scene_load(argv[optind], &s, err, sizeof err) != 0 ||
        scene_finish(&s, width, height, depth, err, sizeof err) != 0) {
        fprintf(stderr, "clwhitted: %s\n", err);
        goto out_free_scene;
    }
    if (preview || preview_script) {
        preview_options po = {device, settings, preview_script, quiet};
        if (!quiet)
            warn_unrendered(&s);
        rc = preview_run(&s, &po);
        goto out_free_scene;
    }
    if (!output) {
        default_out = default_output(&s);
        if (!default_out) {
            fprintf(stderr, "clwhitted: out of memory\n");
            goto out_free_scene;
        }
        output = default_out;
    }
    if (!quiet)
        warn_unrendered(&s);
    t_load = now_seconds();
    if (renderer_create(&r, device, err, sizeof err) != 0 ||
        renderer_set_settings(r, &settings, err, sizeof err) != 0 ||
        renderer_set_scene(r, &s, err, sizeof err) != 0) {
        fprintf(stderr, "clwhitted: %s\n", err);
        goto out_destroy;
    }
    t_setup = now_seconds();
    if (renderer_render(r, &img, err, sizeof err) != 0) {
        fprintf(stderr, "clwhitted: %s\n", err);
        goto out_destroy;
    }
    t_render = now_seconds();
    if (image_write(&img, output, err, sizeof err) != 0) {
        fprintf(stderr, "clwhitted: %s\n", err);
        goto out_free_image;
    }
    if (!quiet)
        printf("clwhitted: wrote %s (%dx%d, depth %d) on %s: load %.3f s, setup %.3f s, "
               "render %.3f s\n",
               output, s.width, s.height, s.max_depth, renderer_device_name(r), t_load - t0,
               t_setup - t_load, t_render - t_setup);
    if (settings.stats) {
        renderer_get_stats(r, &st);
        printf("rays: eye %llu (hit %llu), shadow %llu (blocked %llu), secondary %llu "
               "(hit %llu)\n",
               st.eye_rays, st.eye_hits, st.shadow_rays, st.shadow_blocked, st.secondary_rays,
               st.secondary_hits);
        printf("time: parse %.3f s, build %.3f s, compile %.3f s, upload %.3f s, trace %.3f s "
               "(%d passes)\n",
               t_load - t0, st.build_s, st.compile_s, st.upload_s, st.trace_s, st.passes);
    }
    rc = 0;
out_free_image:
    image_free(&img);
out_destroy:
    renderer_destroy(r);
out_free_scene:
    free(default_out);
    scene_free(&s);
    return rc;
}
