/* The command line of clwhitted: option table, ranges, messages, --help, --version. */
#include "cli.h"

#include <errno.h>
#include <getopt.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli_num.h"
#include "config.h"
#include "progress.h"
#include "scene_geom.h"
#include "sys.h"
#include "version.h"

#define STR_(x) #x
#define STR(x) STR_(x)

/* clang-format off */
static void usage(FILE *f)
{
    fputs(
"usage: clwhitted [options] SCENE...\n"
"Renders each SCENE (.nff, .json, or a mesh file: .obj .ply .gltf .glb .stl)\nwith an OpenCL Whitted ray tracer.\n"
"\n"
"Output:\n"
"  -o, --output FILE     output image: .exr (linear float) or .png (sRGB), for one\n"
"                        SCENE (default: each scene's name with .exr, here)\n"
"      --exposure EV     PNG: multiply the values by 2^EV before tone mapping,\n"
"                        -" STR(CW_MAX_EXPOSURE) ".." STR(CW_MAX_EXPOSURE) " (default: 0)\n"
"      --tonemap CURVE   PNG: clamp (to [0,1]), reinhard (c/(1+c) per channel) or\n"
"                        aces (Narkowicz's filmic fit) (default: clamp)\n"
"      --png16           PNG: 16 bits per channel (default: off, 8 bits)\n"
"      --half            EXR: 16-bit half floats (default: off, 32-bit floats)\n"
"\n"
"Rendering:\n"
"  -W, --width N         image width in pixels, 1.." STR(CW_MAX_SIDE) " (default: the scene's)\n"
"  -H, --height N        image height in pixels, 1.." STR(CW_MAX_SIDE) " (default: the scene's)\n"
"  -d, --depth N         maximum ray depth, 1.." STR(CW_MAX_DEPTH) ", the eye ray being 1 (default:\n"
"                        the scene's, else " STR(CW_DEFAULT_DEPTH) ")\n"
"      --camera FILE     the camera (and image size and depth) of a JSON camera file,\n"
"                        as the preview's C key writes it; -W, -H, -d still win\n"
"                        (default: the scene's camera)\n"
"      --look-from X,Y,Z  the eye; alone, it keeps the view direction\n"
"                        (default: the scene's, or --camera's)\n"
"      --look-at X,Y,Z   the point the eye looks at (default: the scene's view\n"
"                        direction)\n"
"      --up X,Y,Z        the image's vertical (default: the scene's up)\n"
"      --fov DEG         vertical field of view of a perspective camera, at the\n"
"                        image edges, 0..180 exclusive (default: the scene's)\n"
"      --crop X0,X1,Y0,Y1  render only the pixels X0..X1-1, Y0..Y1-1 (row 0 at the\n"
"                        top) of the full image: exactly those pixels of it\n"
"                        (default: the whole image)\n"
"      --spp N           samples per pixel, 1.." STR(CW_MAX_SPP) ", a deterministic stratified\n"
"                        pattern (default: 1, the pixel centre)\n"
"      --precision P     robust: watertight, error-bounded intersection; fast: fast\n"
"                        relaxed math and a fixed epsilon (default: robust)\n"
"      --spd             SPD testing procedure: rays through the pixel corners,\n"
"                        four corners averaged per pixel; not with --spp\n"
"                        (default: off)\n"
"      --device SPEC     OpenCL device: P:D (platform:device as --list-devices\n"
"                        prints) or part of its name (default: the first CPU device)\n"
"      --kernel K        execution strategy: pixel (a work-item traces a pixel's\n"
"                        whole ray tree) or wavefront (a launch per ray depth);\n"
"                        the image is the same (default: auto, pixel on CPU\n"
"                        devices and wavefront on others)\n"
"      --flatten         copy each placement of a mesh into the scene's own\n"
"                        triangles rather than placing one copy (more memory;\n"
"                        for comparison) (default: off)\n"
"      --threads N       CPU threads, 1.." STR(CW_MAX_THREADS) ": PoCL's device, the BVH build and\n"
"                        the image writers (default: one a core)\n"
"\n"
"Information:\n"
"      --stats           count rays (eye, shadow, secondary; hits) and the BVH\n"
"                        walks' work, and print them with the time of each phase\n"
"                        and the device (default: off)\n"
"      --repeat N        after each image, render it N - 1 more times on the same\n"
"                        device (1.." STR(CW_MAX_REPEAT) ") and print every render's time, the\n"
"                        least and the median: timing on a busy machine (default: 1)\n"
"  -q, --quiet           print nothing but errors: no progress bar or summary\n"
"                        (default: off)\n"
"      --list-devices    list the OpenCL platforms and devices, then exit\n"
"      --preview         open a window that shows the render as it refines, with\n"
"                        camera controls (needs a display; press H in it for keys,\n"
"                        C to print the camera for a batch render);\n"
"                        one SCENE, no output, crop, --spd or --stats options\n"
"      --preview-script FILE  drive the preview from FILE (for tests)\n"
"  -h, --help            show this help, then exit\n"
"      --version         show the version, then exit\n"
"\n"
"On a terminal a progress bar is drawn on stderr; a summary line (output, size,\n"
"time, Mrays/s; the kernel compile apart) goes to stdout after each image.\n"
"\n"
"Environment:\n"
"  CLWHITTED_BUILD_OPTIONS  extra OpenCL kernel build options (default: none)\n"
"  CLWHITTED_CACHE_DIR      built kernel binaries, so a second run skips the compiler\n"
"                           (default: ~/.cache/clwhitted; empty: no cache)\n"
"  CLWHITTED_SUMMARY        the summary line: short, or long (every phase's time and\n"
"                           the device, for scripts) (default: short)\n"
"  CLWHITTED_PROGRESS       progress: always (a bar), never, log (a line every\n"
"                           " STR(CW_PROGRESS_LOG_S) " s, for logs), or auto (default: auto, a bar when\n"
"                           stderr is a terminal)\n"
"  POCL_DEVICES             PoCL device drivers to offer, e.g. pthread or basic\n"
"  POCL_MAX_PTHREAD_COUNT   threads of PoCL's pthread device (default: one a core;\n"
"                           --threads sets it)\n"
"  POCL_AFFINITY            1: PoCL's threads pinned one per CPU (default: 1 when\n"
"                           they are one per CPU and the CPU set is not narrowed)\n"
"  POCL_CACHE_DIR           PoCL's compiled-kernel cache (default:\n"
"                           ~/.cache/pocl/kcache)\n"
"  OCL_ICD_VENDORS          where the OpenCL loader finds drivers (default:\n"
"                           /etc/OpenCL/vendors)\n"
"\n"
"Exit status: 0 success, 1 input or render error, 2 usage error.\n",
        f);
}
/* clang-format on */

static void version(void)
{
    printf("clwhitted %s\n"
           "OpenCL %d.%d API, kernels embedded; %s\n",
           CW_VERSION, CL_TARGET_OPENCL_VERSION / 100, CL_TARGET_OPENCL_VERSION / 10 % 10,
           image_library_versions());
}

/* An argument as messages show it (control characters escaped). */
static const char *shown(const char *arg)
{
    static char buf[256];
    return sys_escape(buf, sizeof buf, arg);
}

static int parse_int(const char *opt, const char *s, int lo, int hi, int *out)
{
    long v;
    if (cli_parse_long(s, lo, hi, &v) != 0) {
        fprintf(stderr, "clwhitted: %s expects an integer in %d..%d, got '%s'\n" CLI_HINT, opt, lo,
                hi, shown(s));
        return -1;
    }
    *out = (int)v;
    return 0;
}

static int parse_double(const char *opt, const char *s, double lo, double hi, double *out)
{
    if (cli_parse_double(s, lo, hi, out) != 0) {
        fprintf(stderr, "clwhitted: %s expects a number in %g..%g, got '%s'\n" CLI_HINT, opt, lo,
                hi, shown(s));
        return -1;
    }
    return 0;
}

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
    OPT_HALF,
    OPT_PREVIEW,
    OPT_PREVIEW_SCRIPT,
    OPT_KERNEL,
    OPT_THREADS,
    OPT_REPEAT,
    OPT_CROP,
    OPT_PNG16,
    OPT_CAMERA,
    OPT_LOOK_FROM,
    OPT_LOOK_AT,
    OPT_UP,
    OPT_FOV,
    OPT_FLATTEN
};

static const struct option cli_longopts[] = {
    {"output", required_argument, NULL, 'o'},
    {"width", required_argument, NULL, 'W'},
    {"height", required_argument, NULL, 'H'},
    {"depth", required_argument, NULL, 'd'},
    {"device", required_argument, NULL, OPT_DEVICE},
    {"kernel", required_argument, NULL, OPT_KERNEL},
    {"spp", required_argument, NULL, OPT_SPP},
    {"precision", required_argument, NULL, OPT_PRECISION},
    {"spd", no_argument, NULL, OPT_SPD},
    {"stats", no_argument, NULL, OPT_STATS},
    {"exposure", required_argument, NULL, OPT_EXPOSURE},
    {"tonemap", required_argument, NULL, OPT_TONEMAP},
    {"half", no_argument, NULL, OPT_HALF},
    {"png16", no_argument, NULL, OPT_PNG16},
    {"threads", required_argument, NULL, OPT_THREADS},
    {"repeat", required_argument, NULL, OPT_REPEAT},
    {"crop", required_argument, NULL, OPT_CROP},
    {"camera", required_argument, NULL, OPT_CAMERA},
    {"look-from", required_argument, NULL, OPT_LOOK_FROM},
    {"look-at", required_argument, NULL, OPT_LOOK_AT},
    {"up", required_argument, NULL, OPT_UP},
    {"fov", required_argument, NULL, OPT_FOV},
    {"flatten", no_argument, NULL, OPT_FLATTEN},
    {"list-devices", no_argument, NULL, OPT_LIST},
    {"preview", no_argument, NULL, OPT_PREVIEW},
    {"preview-script", required_argument, NULL, OPT_PREVIEW_SCRIPT},
    {"quiet", no_argument, NULL, 'q'},
    {"help", no_argument, NULL, 'h'},
    {"version", no_argument, NULL, OPT_VERSION},
    {NULL, 0, NULL, 0}};

/* --crop X0,X1,Y0,Y1: four integers, X0 < X1 and Y0 < Y1 (the image's size is checked
 * once the scene is loaded). */
static int parse_crop(const char *s, render_settings *st)
{
    long v[4];
    char buf[128], *p, *q;
    int k;
    if (strlen(s) < sizeof buf) {
        memcpy(buf, s, strlen(s) + 1);
        for (k = 0, p = buf; k < 4; k++, p = q + 1) {
            q = strchr(p, ',');
            if ((q == NULL) != (k == 3))
                break;
            if (q)
                *q = '\0';
            if (cli_parse_long(p, 0, CW_MAX_SIDE, &v[k]) != 0)
                break;
            if (!q) {
                k++;
                break;
            }
        }
        if (k == 4 && v[0] < v[1] && v[2] < v[3]) {
            for (k = 0; k < 4; k++)
                st->crop[k] = (int)v[k];
            return 0;
        }
    }
    fprintf(stderr,
            "clwhitted: --crop expects X0,X1,Y0,Y1 with 0 <= X0 < X1 and 0 <= Y0 < Y1 "
            "(pixels), got '%s'\n" CLI_HINT,
            s);
    return -1;
}

/* X,Y,Z: three numbers of magnitude at most CW_MAX_ABS; a zero vector refused when
 * nonzero is set. */
static int parse_xyz(const char *opt, const char *s, int nonzero, double out[3])
{
    char buf[256], *p, *q;
    int k;
    if (strlen(s) < sizeof buf) {
        memcpy(buf, s, strlen(s) + 1);
        for (k = 0, p = buf; k < 3; k++) {
            q = strchr(p, ',');
            if ((q == NULL) != (k == 2))
                break;
            if (q)
                *q = '\0';
            if (cli_parse_double(p, -CW_MAX_ABS, CW_MAX_ABS, &out[k]) != 0)
                break;
            if (q)
                p = q + 1;
        }
        if (k == 3 && (!nonzero || out[0] != 0 || out[1] != 0 || out[2] != 0))
            return 0;
    }
    fprintf(stderr,
            "clwhitted: %s expects X,Y,Z: three numbers of magnitude at most %g%s, got "
            "'%s'\n" CLI_HINT,
            opt, CW_MAX_ABS, nonzero ? ", not all zero" : "", shown(s));
    return -1;
}

/* One option; returns 0, or -1 after printing a usage error. */
static int parse_option(int c, const char *arg, cli_options *o)
{
    switch (c) {
    case 'o':
        o->output = arg;
        return 0;
    case 'W':
        return parse_int("--width", arg, 1, CW_MAX_SIDE, &o->width);
    case 'H':
        return parse_int("--height", arg, 1, CW_MAX_SIDE, &o->height);
    case 'd':
        return parse_int("--depth", arg, 1, CW_MAX_DEPTH, &o->depth);
    case OPT_DEVICE:
        if (!*arg) {
            fprintf(stderr, "clwhitted: --device expects P:D or part of a device name, got "
                            "''\n" CLI_HINT);
            return -1;
        }
        o->device = arg;
        return 0;
    case OPT_SPP:
        o->spp_given = 1;
        return parse_int("--spp", arg, 1, CW_MAX_SPP, &o->settings.spp);
    case OPT_THREADS:
        return parse_int("--threads", arg, 1, CW_MAX_THREADS, &o->threads);
    case OPT_REPEAT:
        return parse_int("--repeat", arg, 1, CW_MAX_REPEAT, &o->repeat);
    case OPT_CROP:
        return parse_crop(arg, &o->settings);
    case OPT_PNG16:
        o->write.png16 = 1;
        return 0;
    case OPT_CAMERA:
        o->camera = arg;
        return 0;
    case OPT_FLATTEN:
        o->view.flatten = 1;
        return 0;
    case OPT_LOOK_FROM:
    case OPT_LOOK_AT:
    case OPT_UP: {
        double v[3];
        const char *name = c == OPT_LOOK_FROM ? "--look-from"
                           : c == OPT_LOOK_AT ? "--look-at"
                                              : "--up";
        if (parse_xyz(name, arg, c == OPT_UP, v) != 0)
            return -1;
        if (c == OPT_LOOK_FROM) {
            o->view.has_eye = 1;
            o->view.eye = vec3d_make(v[0], v[1], v[2]);
        } else if (c == OPT_LOOK_AT) {
            o->view.has_at = 1;
            o->view.at = vec3d_make(v[0], v[1], v[2]);
        } else {
            o->view.has_up = 1;
            o->view.up = vec3f_make((float)v[0], (float)v[1], (float)v[2]);
        }
        return 0;
    }
    case OPT_FOV:
        if (parse_double("--fov", arg, 0, 180, &o->view.fov_deg) != 0)
            return -1;
        if (!((float)o->view.fov_deg > 0 && (float)o->view.fov_deg < 180)) {
            fprintf(stderr,
                    "clwhitted: --fov expects degrees strictly between 0 and 180, got "
                    "'%s'\n" CLI_HINT,
                    shown(arg));
            return -1;
        }
        o->view.has_fov = 1;
        return 0;
    case OPT_PRECISION:
        if (strcmp(arg, "robust") == 0)
            o->settings.precision = RENDER_ROBUST;
        else if (strcmp(arg, "fast") == 0)
            o->settings.precision = RENDER_FAST;
        else {
            fprintf(stderr,
                    "clwhitted: --precision expects 'robust' or 'fast', got '%s'\n" CLI_HINT,
                    shown(arg));
            return -1;
        }
        return 0;
    case OPT_SPD:
        o->settings.spd = 1;
        return 0;
    case OPT_KERNEL:
        o->settings.strategy = render_strategy_parse(arg);
        if (o->settings.strategy < 0) {
            fprintf(
                stderr,
                "clwhitted: --kernel expects 'auto', 'pixel' or 'wavefront', got '%s'\n" CLI_HINT,
                shown(arg));
            return -1;
        }
        return 0;
    case OPT_STATS:
        o->settings.stats = 1;
        return 0;
    case OPT_EXPOSURE:
        o->png_opt = "--exposure";
        return parse_double("--exposure", arg, -CW_MAX_EXPOSURE, CW_MAX_EXPOSURE,
                            &o->write.exposure);
    case OPT_TONEMAP:
        o->png_opt = "--tonemap";
        o->write.tonemap = image_tonemap_parse(arg);
        if (o->write.tonemap < 0) {
            fprintf(
                stderr,
                "clwhitted: --tonemap expects 'clamp', 'reinhard' or 'aces', got '%s'\n" CLI_HINT,
                shown(arg));
            return -1;
        }
        return 0;
    case OPT_HALF:
        o->write.half = 1;
        return 0;
    case OPT_LIST:
        o->list_devices = 1;
        return 0;
    case OPT_PREVIEW:
        o->preview = 1;
        return 0;
    case OPT_PREVIEW_SCRIPT:
        o->preview = 1;
        o->preview_script = arg;
        return 0;
    case 'q':
        o->quiet = 1;
        return 0;
    default: /* getopt has said what is wrong, on one line */
        fprintf(stderr, CLI_HINT);
        return -1;
    }
}

/* Prints a usage error (one line and the hint). Returns CLI_EXIT. */
static int usage_error(const char *msg)
{
    fprintf(stderr, "clwhitted: %s\n" CLI_HINT, msg);
    return CLI_EXIT;
}

/* Options that make no sense together, and the environment: a usage error each. Returns
 * 0, or -1 after printing it. */
static int check_combinations(cli_options *o)
{
    char err[2048];
    const char *env = getenv("CLWHITTED_PROGRESS");
    int png = o->output && sys_has_ext(o->output, ".png");

    if (o->output && image_check_path(o->output, err, sizeof err) != 0)
        return usage_error(shown(err)), -1;
    if ((o->progress = progress_mode_parse(env)) < 0) {
        snprintf(err, sizeof err,
                 "CLWHITTED_PROGRESS expects 'auto', 'always', 'never' or 'log', got '%.64s'", env);
        return usage_error(err), -1;
    }
    env = getenv("CLWHITTED_SUMMARY");
    if (env && *env && strcmp(env, "short") != 0 && strcmp(env, "long") != 0) {
        snprintf(err, sizeof err, "CLWHITTED_SUMMARY expects 'short' or 'long', got '%.64s'",
                 shown(env));
        return usage_error(err), -1;
    }
    o->summary_long = env && strcmp(env, "long") == 0;
    if (o->settings.spd && o->spp_given)
        return usage_error("--spd traces the pixel corners: it takes no --spp"), -1;
    if (o->output && o->nscenes > 1)
        return usage_error("-o names one image: give one scene with it, or none to write "
                           "each scene's NAME.exr"),
               -1;
    if (o->preview) {
        const char *bad = o->nscenes > 1        ? "more than one scene"
                          : o->output           ? "-o"
                          : o->png_opt          ? o->png_opt
                          : o->write.half       ? "--half"
                          : o->write.png16      ? "--png16"
                          : o->settings.spd     ? "--spd"
                          : o->settings.stats   ? "--stats"
                          : o->repeat > 1       ? "--repeat"
                          : o->settings.crop[1] ? "--crop"
                                                : NULL;
        if (bad) {
            snprintf(err, sizeof err,
                     "%s does not apply to --preview (F5 saves NAME-preview-TIME.exr and .png; "
                     "C prints the camera for a batch render)",
                     bad);
            return usage_error(err), -1;
        }
        return 0;
    }
    if (!png && o->png_opt) {
        snprintf(err, sizeof err,
                 "%s applies to PNG output (-o FILE.png); EXR keeps the linear "
                 "values",
                 o->png_opt);
        return usage_error(err), -1;
    }
    if (!png && o->write.png16)
        return usage_error("--png16 applies to PNG output (-o FILE.png)"), -1;
    if (png && o->write.half)
        return usage_error("--half applies to EXR output"), -1;
    return 0;
}

int cli_parse(int argc, char **argv, cli_options *o, int *status)
{
    static char progname[] = "clwhitted"; /* getopt's own messages name the program by it */
    int c;

    memset(o, 0, sizeof *o);
    o->repeat = 1;
    render_settings_default(&o->settings);
    image_write_opts_default(&o->write);
    if (argc > 0)
        argv[0] = progname;
    *status = 2;
    while ((c = getopt_long(argc, argv, "o:W:H:d:qh", cli_longopts, NULL)) != -1) {
        if (c == 'h' || c == OPT_VERSION) {
            if (c == 'h')
                usage(stdout);
            else
                version();
            *status = 0;
            return CLI_EXIT;
        }
        if (parse_option(c, optarg, o) != 0)
            return CLI_EXIT;
    }
    if (o->list_devices)
        return CLI_RUN;
    if (o->width > 0 && o->height > 0 && (long long)o->width * o->height > CW_MAX_PIXELS) {
        fprintf(stderr,
                "clwhitted: -W %d -H %d is %lld pixels; an image may have at most %ld "
                "(2^28)\n" CLI_HINT,
                o->width, o->height, (long long)o->width * o->height, (long)CW_MAX_PIXELS);
        return CLI_EXIT;
    }
    if (optind >= argc)
        return usage_error("no scene file given");
    o->scenes = (const char *const *)argv + optind;
    o->nscenes = argc - optind;
    o->scene = o->scenes[0];
    return check_combinations(o) == 0 ? CLI_RUN : CLI_EXIT;
}
