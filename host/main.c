/* clwhitted: command line. */
#include <errno.h>
#include <getopt.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "image.h"
#include "preview.h"
#include "progress.h"
#include "render.h"
#include "scene.h"
#include "scene_load.h"
#include "version.h"

#define HINT "Try 'clwhitted --help'.\n"

static void usage(FILE *f)
{
    fprintf(f,
            "usage: clwhitted [options] SCENE\n"
            "Renders SCENE (.nff or .json) with an OpenCL Whitted ray tracer.\n"
            "\n"
            "Output:\n"
            "  -o, --output FILE     output image: .exr (linear float) or .png (sRGB 8-bit)\n"
            "                        (default: the scene's name with .exr, in the current folder)\n"
            "      --exposure EV     PNG: multiply the values by 2^EV before tone mapping,\n"
            "                        -64..64 (default: 0)\n"
            "      --tonemap CURVE   PNG: clamp (to [0,1]), reinhard (c/(1+c) per channel) or\n"
            "                        aces (Narkowicz's filmic fit) (default: clamp)\n"
            "      --half            EXR: 16-bit half floats (default: off, 32-bit floats)\n"
            "\n"
            "Rendering:\n"
            "  -W, --width N         image width in pixels, 1..65536 (default: the scene's)\n"
            "  -H, --height N        image height in pixels, 1..65536 (default: the scene's)\n"
            "  -d, --depth N         maximum ray depth, 1..64, the eye ray being 1 (default:\n"
            "                        the scene's, else 5)\n"
            "      --spp N           samples per pixel, 1..65536, a deterministic stratified\n"
            "                        pattern (default: 1, the pixel centre)\n"
            "      --precision P     robust: watertight, error-bounded intersection; fast: fast\n"
            "                        relaxed math and a fixed epsilon (default: robust)\n"
            "      --spd             SPD testing procedure: rays through the pixel corners,\n"
            "                        four corners averaged per pixel (default: off)\n"
            "      --device SPEC     OpenCL device: P:D (platform:device as --list-devices\n"
            "                        prints) or part of its name (default: the first CPU device)\n"
            "\n"
            "Information:\n"
            "      --stats           count rays (eye, shadow, secondary; hits) and print them\n"
            "                        with the time of each phase (default: off)\n"
            "  -q, --quiet           print nothing but errors: no progress bar, summary or\n"
            "                        warnings (default: off)\n"
            "      --list-devices    list the OpenCL platforms and devices, then exit\n"
            "      --preview         open a window that shows the render as it refines, with\n"
            "                        camera controls (needs a display; press H in it for keys)\n"
            "      --preview-script FILE  drive the preview from FILE (for tests)\n"
            "  -h, --help            show this help, then exit\n"
            "      --version         show the version, then exit\n"
            "\n"
            "On a terminal a progress bar is drawn on stderr; a summary line (output, size,\n"
            "times, Mrays/s) goes to stdout at the end.\n"
            "\n"
            "Environment:\n"
            "  CLWHITTED_BUILD_OPTIONS  extra OpenCL kernel build options (default: none)\n"
            "  CLWHITTED_CACHE_DIR      built kernel binaries, so a second run skips the compiler\n"
            "                           (default: ~/.cache/clwhitted; empty: no cache)\n"
            "  CLWHITTED_PROGRESS       progress bar: always, never, or auto (default: auto,\n"
            "                           when stderr is a terminal)\n"
            "  POCL_DEVICES             PoCL device drivers to offer, e.g. pthread or basic\n"
            "  POCL_MAX_PTHREAD_COUNT   threads of PoCL's pthread device (default: one a core)\n"
            "  POCL_CACHE_DIR           PoCL's compiled-kernel cache (default:\n"
            "                           ~/.cache/pocl/kcache)\n"
            "  OCL_ICD_VENDORS          where the OpenCL loader finds drivers (default:\n"
            "                           /etc/OpenCL/vendors)\n"
            "\n"
            "Exit status: 0 success, 1 input or render error, 2 usage error.\n");
}

static void version(void)
{
    printf("clwhitted %s\n"
           "OpenCL %d.%d API, kernels embedded; %s\n",
           CW_VERSION, CL_TARGET_OPENCL_VERSION / 100, CL_TARGET_OPENCL_VERSION / 10 % 10,
           image_library_versions());
}

static int parse_int(const char *opt, const char *s, int lo, int hi, int *out)
{
    char *end;
    long v;
    errno = 0;
    v = strtol(s, &end, 10);
    if (errno || end == s || *end || v < lo || v > hi) {
        fprintf(stderr, "clwhitted: %s expects an integer in %d..%d, got '%s'\n" HINT, opt, lo, hi,
                s);
        return -1;
    }
    *out = (int)v;
    return 0;
}

static int parse_double(const char *opt, const char *s, double lo, double hi, double *out)
{
    char *end;
    double v;
    errno = 0;
    v = strtod(s, &end);
    if (errno || end == s || *end || !(v >= lo && v <= hi)) {
        fprintf(stderr, "clwhitted: %s expects a number in %g..%g, got '%s'\n" HINT, opt, lo, hi,
                s);
        return -1;
    }
    *out = v;
    return 0;
}

/* Whether image_write writes this path as EXR (its extension is .exr, in any case). */
static int is_exr_path(const char *path)
{
    size_t n = strlen(path);
    return n >= 4 && path[n - 4] == '.' && (path[n - 3] | 0x20) == 'e' &&
           (path[n - 2] | 0x20) == 'x' && (path[n - 1] | 0x20) == 'r';
}

/* The base name of a path. */
static const char *base_name(const char *path)
{
    const char *slash = strrchr(path, '/');
    return slash ? slash + 1 : path;
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

/* Prints an error, clearing the progress line first. */
static void fail_msg(progress_bar *bar, const char *msg)
{
    progress_clear(bar);
    fprintf(stderr, "clwhitted: %s\n", msg);
}

int main(int argc, char **argv)
{
    enum {
        OPT_DEVICE = 256,
        OPT_LIST,
        OPT_VERSION,
        OPT_SPP,
        OPT_PRECISION,
        OPT_SPD,
        OPT_STATS,
        OPT_EXPOSURE,
        OPT_TONEMAP,
        OPT_HALF
    };
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
                                             {"exposure", required_argument, NULL, OPT_EXPOSURE},
                                             {"tonemap", required_argument, NULL, OPT_TONEMAP},
                                             {"half", no_argument, NULL, OPT_HALF},
                                             {"list-devices", no_argument, NULL, OPT_LIST},
                                             {"preview", no_argument, NULL, OPT_PREVIEW},
                                             {"preview-script", required_argument, NULL, OPT_PVS},
                                             {"quiet", no_argument, NULL, 'q'},
                                             {"help", no_argument, NULL, 'h'},
                                             {"version", no_argument, NULL, OPT_VERSION},
                                             {NULL, 0, NULL, 0}};
    static char progname[] = "clwhitted"; /* getopt's own messages name the program by it */
    const char *output = NULL, *device = NULL;
    char *default_out = NULL;
    int width = 0, height = 0, depth = 0, quiet = 0, list = 0, c, rc = 1, is_exr;
    char err[2048], meta_settings[256], title[256], software[64], rate[32];
    scene s;
    renderer *r = NULL;
    image img = {0, 0, NULL};
    double t0, t_load, t_setup, t_render, t_write, trace_s;
    unsigned long long rays;
    render_settings settings;
    render_stats st;
    image_write_opts wopts;
    progress_bar bar;
    int preview = 0;
    const char *preview_script = NULL;

    render_settings_default(&settings);
    image_write_opts_default(&wopts);
    if (argc > 0)
        argv[0] = progname;

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
                        "clwhitted: --precision expects 'robust' or 'fast', got '%s'\n" HINT,
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
        case OPT_EXPOSURE:
            if (parse_double("--exposure", optarg, -64, 64, &wopts.exposure))
                return 2;
            break;
        case OPT_TONEMAP:
            wopts.tonemap = image_tonemap_parse(optarg);
            if (wopts.tonemap < 0) {
                fprintf(
                    stderr,
                    "clwhitted: --tonemap expects 'clamp', 'reinhard' or 'aces', got '%s'\n" HINT,
                    optarg);
                return 2;
            }
            break;
        case OPT_HALF:
            wopts.half = 1;
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
            version();
            return 0;
        default: /* getopt has said what is wrong, on one line */
            fprintf(stderr, HINT);
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
        fprintf(stderr, "clwhitted: %s\n" HINT, err);
        return 2;
    }
    if (optind != argc - 1) {
        fprintf(stderr, "clwhitted: %s\n" HINT,
                optind >= argc ? "no scene file given" : "more than one scene file given");
        return 2;
    }

    progress_init(&bar, stderr,
                  progress_wanted(quiet, getenv("CLWHITTED_PROGRESS"), isatty(STDERR_FILENO)));
    t0 = now_seconds();
    scene_init(&s);
    progress_status(&bar, "loading the scene ...");
    if (scene_load(argv[optind], &s, err, sizeof err) != 0 ||
        scene_finish(&s, width, height, depth, err, sizeof err) != 0) {
        fail_msg(&bar, err);
        goto out_free_scene;
    }
    progress_clear(&bar);
    if (preview || preview_script) {
        preview_options po = {device, settings, preview_script, quiet};
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
    is_exr = is_exr_path(output);
    if (!quiet) {
        if (is_exr && (wopts.exposure != 0 || wopts.tonemap != IMAGE_TONEMAP_CLAMP))
            fprintf(stderr, "clwhitted: warning: --exposure and --tonemap apply to PNG output "
                            "only; EXR keeps the linear values\n");
        if (!is_exr && wopts.half)
            fprintf(stderr, "clwhitted: warning: --half applies to EXR output only\n");
    }
    t_load = now_seconds();
    progress_status(&bar, "building the kernels ...");
    if (renderer_create(&r, device, err, sizeof err) != 0 ||
        renderer_set_settings(r, &settings, err, sizeof err) != 0 ||
        renderer_set_scene(r, &s, err, sizeof err) != 0) {
        fail_msg(&bar, err);
        goto out_destroy;
    }
    t_setup = now_seconds();
    renderer_set_progress(r, progress_update, &bar);
    progress_begin(&bar);
    progress_update(&bar, 0.0, 0);
    if (renderer_render(r, &img, err, sizeof err) != 0) {
        fail_msg(&bar, err);
        goto out_destroy;
    }
    progress_clear(&bar);
    t_render = now_seconds();
    renderer_get_stats(r, &st);
    trace_s = st.trace_s > 0 ? st.trace_s : t_render - t_setup;
    rays = st.eye_rays + st.secondary_rays + st.shadow_rays;
    progress_format_rate(rate, sizeof rate, trace_s > 0 ? (double)rays / trace_s * 1e-6 : 0.0);

    /* metadata */
    snprintf(software, sizeof software, "clwhitted %s", CW_VERSION);
    snprintf(title, sizeof title, "%s", base_name(argv[optind]));
    if (is_exr)
        snprintf(meta_settings, sizeof meta_settings, "%dx%d, depth %d, spp %d, precision %s%s%s",
                 s.width, s.height, s.max_depth, settings.spp,
                 settings.precision == RENDER_FAST ? "fast" : "robust", settings.spd ? ", spd" : "",
                 wopts.half ? ", half floats" : "");
    else
        snprintf(meta_settings, sizeof meta_settings,
                 "%dx%d, depth %d, spp %d, precision %s%s, exposure %+g EV, tonemap %s", s.width,
                 s.height, s.max_depth, settings.spp,
                 settings.precision == RENDER_FAST ? "fast" : "robust", settings.spd ? ", spd" : "",
                 wopts.exposure, image_tonemap_name(wopts.tonemap));
    wopts.title = title;
    wopts.software = software;
    wopts.source = renderer_device_name(r);
    wopts.comment = meta_settings;
    wopts.render_s = trace_s;
    if (image_write_ex(&img, output, &wopts, err, sizeof err) != 0) {
        fprintf(stderr, "clwhitted: %s\n", err);
        goto out_free_image;
    }
    t_write = now_seconds();
    if (!quiet)
        printf("clwhitted: wrote %s (%dx%d, depth %d) in %.3f s on %s: load %.3f s, setup %.3f s, "
               "render %.3f s, %s Mrays/s\n",
               output, s.width, s.height, s.max_depth, t_write - t0, renderer_device_name(r),
               t_load - t0, t_setup - t_load, t_render - t_setup, rate);
    if (settings.stats) {
        printf("rays: eye %llu (hit %llu), shadow %llu (blocked %llu), secondary %llu "
               "(hit %llu)\n",
               st.eye_rays, st.eye_hits, st.shadow_rays, st.shadow_blocked, st.secondary_rays,
               st.secondary_hits);
        printf("time: parse %.3f s, build %.3f s, compile %.3f s, upload %.3f s, trace %.3f s "
               "(%d passes)\n",
               t_load - t0, st.build_s, st.compile_s, st.upload_s, st.trace_s, st.passes);
        printf("kernels: raygen %.3f s, intersect %.3f s, shade %.3f s, occlude %.3f s\n",
               st.raygen_s, st.intersect_s, st.shade_s, st.occlude_s);
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
