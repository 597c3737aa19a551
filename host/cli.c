/* The command line of clwhitted: option table, ranges, messages, --help, --version. */
#include "cli.h"

#include <errno.h>
#include <getopt.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli_num.h"
#include "config.h"
#include "sys.h"
#include "version.h"

#define STR_(x) #x
#define STR(x) STR_(x)

static void usage(FILE *f)
{
    fprintf(
        f,
        "usage: clwhitted [options] SCENE\n"
        "Renders SCENE (.nff or .json) with an OpenCL Whitted ray tracer.\n"
        "\n"
        "Output:\n"
        "  -o, --output FILE     output image: .exr (linear float) or .png (sRGB 8-bit)\n"
        "                        (default: the scene's name with .exr, in the current folder)\n"
        "      --exposure EV     PNG: multiply the values by 2^EV before tone mapping,\n"
        "                        -" STR(CW_MAX_EXPOSURE) ".." STR(
            CW_MAX_EXPOSURE) " (default: 0)\n"
                             "      --tonemap CURVE   PNG: clamp (to [0,1]), reinhard (c/(1+c) per "
                             "channel) or\n"
                             "                        aces (Narkowicz's filmic fit) (default: "
                             "clamp)\n"
                             "      --half            EXR: 16-bit half floats (default: off, "
                             "32-bit floats)\n"
                             "\n"
                             "Rendering:\n"
                             "  -W, --width N         image width in pixels, 1.." STR(
                                 CW_MAX_SIDE) " (default: the scene's)\n"
                                              "  -H, --height N        image height in pixels, "
                                              "1.." STR(
                                                  CW_MAX_SIDE) " (default: the scene's)\n"
                                                               "  -d, --depth N         maximum "
                                                               "ray depth, 1.." STR(
                                                                   CW_MAX_DEPTH) ", the eye ray "
                                                                                 "being 1 "
                                                                                 "(default:\n"
                                                                                 "                 "
                                                                                 "       the "
                                                                                 "scene's, "
                                                                                 "else " STR(
                                                                                     CW_DEFAULT_DEPTH) ")\n"
                                                                                                       "      --spp N           samples per pixel, 1.." STR(
                                                                                                           CW_MAX_SPP) ", a deterministic stratified\n"
                                                                                                                       "                        pattern (default: 1, the pixel centre)\n"
                                                                                                                       "      --precision P     robust: watertight, error-bounded intersection; fast: fast\n"
                                                                                                                       "                        relaxed math and a fixed epsilon (default: robust)\n"
                                                                                                                       "      --spd             SPD testing procedure: rays through the pixel corners,\n"
                                                                                                                       "                        four corners averaged per pixel (default: off)\n"
                                                                                                                       "      --device SPEC     OpenCL device: P:D (platform:device as --list-devices\n"
                                                                                                                       "                        prints) or part of its name (default: the first CPU device)\n"
                                                                                                                       "      --kernel K        execution strategy: pixel (a work-item traces a pixel's\n"
                                                                                                                       "                        whole ray tree) or wavefront (a launch per ray depth);\n"
                                                                                                                       "                        the image is the same (default: auto, pixel on CPU\n"
                                                                                                                       "                        devices and wavefront on others)\n"
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
    OPT_KERNEL
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
    {"list-devices", no_argument, NULL, OPT_LIST},
    {"preview", no_argument, NULL, OPT_PREVIEW},
    {"preview-script", required_argument, NULL, OPT_PREVIEW_SCRIPT},
    {"quiet", no_argument, NULL, 'q'},
    {"help", no_argument, NULL, 'h'},
    {"version", no_argument, NULL, OPT_VERSION},
    {NULL, 0, NULL, 0}};

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
        o->device = arg;
        return 0;
    case OPT_SPP:
        return parse_int("--spp", arg, 1, CW_MAX_SPP, &o->settings.spp);
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
        return parse_double("--exposure", arg, -CW_MAX_EXPOSURE, CW_MAX_EXPOSURE,
                            &o->write.exposure);
    case OPT_TONEMAP:
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

int cli_parse(int argc, char **argv, cli_options *o, int *status)
{
    static char progname[] = "clwhitted"; /* getopt's own messages name the program by it */
    char err[2048];
    int c;

    memset(o, 0, sizeof *o);
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
    if (o->output && image_check_path(o->output, err, sizeof err) != 0) {
        fprintf(stderr, "clwhitted: %s\n" CLI_HINT, shown(err));
        return CLI_EXIT;
    }
    if (o->width > 0 && o->height > 0 && (long long)o->width * o->height > CW_MAX_PIXELS) {
        fprintf(stderr,
                "clwhitted: -W %d -H %d is %lld pixels; an image may have at most %ld "
                "(2^28)\n" CLI_HINT,
                o->width, o->height, (long long)o->width * o->height, (long)CW_MAX_PIXELS);
        return CLI_EXIT;
    }
    if (optind != argc - 1) {
        fprintf(stderr, "clwhitted: %s\n" CLI_HINT,
                optind >= argc ? "no scene file given" : "more than one scene file given");
        return CLI_EXIT;
    }
    o->scene = argv[optind];
    return CLI_RUN;
}
