/* imgtool: the images clwhitted writes, after the render (installed with clwhitted;
 * docs/usage.md#imgtool). Re-expose or tone-map an EXR without rendering again, crop,
 * compare two images, describe one; and the raw float dump that the quality report reads.
 *   imgtool convert [--exposure EV] [--tonemap C] [--png16] [--half] [--crop X0,X1,Y0,Y1]
 *                   [--linear] IN OUT
 *   imgtool diff [--tol T] [--diff FILE] A B
 *   imgtool info [--linear] IN...
 *   imgtool raw [--linear] IN OUT */
#include <getopt.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli_num.h"
#include "config.h"
#include "image.h"
#include "image_diff.h"
#include "image_read.h"
#include "sys.h"

static void usage(FILE *f)
{
    fputs("usage: imgtool convert [options] IN OUT  IN to OUT (.exr linear, .png sRGB):\n"
          "         --exposure EV   PNG: multiply by 2^EV before the tone map (default: 0)\n"
          "         --tonemap C     PNG: clamp, reinhard or aces (default: clamp)\n"
          "         --png16         PNG: 16 bits per channel (default: 8)\n"
          "         --half          EXR: 16-bit half floats (default: 32-bit floats)\n"
          "         --crop X0,X1,Y0,Y1  keep the pixels X0..X1-1, Y0..Y1-1 (row 0 at the top)\n"
          "       imgtool diff [options] A B       compare B with A (the same size): prints\n"
          "                                        size, max, mean, rmse, psnr and the\n"
          "                                        pixels over --tol; exit 0 when none is\n"
          "         --tol T         per-channel tolerance of a pixel (default: 0)\n"
          "         --diff FILE     write a diff image (|A-B| x 100, pixels over T in red)\n"
          "       imgtool info IN...               size, channel range and mean, non-finite\n"
          "                                        values\n"
          "       imgtool raw IN OUT               IN's linear RGB as raw float32 to OUT ('-':\n"
          "                                        standard output); prints 'WIDTH HEIGHT'\n"
          "IN: .exr (linear values) or .png (sRGB decoded; --linear: a PNG that holds linear\n"
          "values, as POV-Ray's 16-bit output).\n"
          "Exit status: 0 success (diff: no pixel over the tolerance), 1 input or output error\n"
          "(diff: images differ), 2 usage error.\n",
          f);
}

static int usage_error(const char *msg, const char *arg)
{
    fprintf(stderr, "imgtool: %s%s%s%s\nTry 'imgtool --help'.\n", msg, arg ? " '" : "",
            arg ? arg : "", arg ? "'" : "");
    return 2;
}

static int read_any(const char *path, int linear, image *img, char *err, size_t errlen)
{
    if (sys_has_ext(path, ".exr"))
        return image_read_exr(path, img, err, errlen);
    if (sys_has_ext(path, ".png"))
        return image_read_png(path, !linear, img, err, errlen);
    snprintf(err, errlen, "%s: unsupported image extension (expected .exr or .png)", path);
    return -1;
}

static int write_raw(const image *img, const char *path, char *err, size_t errlen)
{
    size_t n = (size_t)img->width * (size_t)img->height * 3;
    int to_stdout = strcmp(path, "-") == 0;
    FILE *f = to_stdout ? stdout : fopen(path, "wb");
    if (!f) {
        snprintf(err, errlen, "%s: cannot open for writing", path);
        return -1;
    }
    if (fwrite(img->rgb, sizeof(float), n, f) != n) {
        snprintf(err, errlen, "%s: write failed", path);
        if (!to_stdout)
            fclose(f);
        return -1;
    }
    if (to_stdout ? fflush(f) != 0 : fclose(f) != 0) {
        snprintf(err, errlen, "%s: write failed", path);
        return -1;
    }
    return 0;
}

/* Replaces img by its window c (x0, x1, y0, y1). Returns 0, or -1 with err. */
static int crop(image *img, const long *c, char *err, size_t errlen)
{
    image out;
    long y;
    if (c[1] > img->width || c[3] > img->height) {
        snprintf(err, errlen, "--crop %ld,%ld,%ld,%ld is not inside the %dx%d image", c[0], c[1],
                 c[2], c[3], img->width, img->height);
        return -1;
    }
    if (image_alloc(&out, (int)(c[1] - c[0]), (int)(c[3] - c[2])) != 0) {
        snprintf(err, errlen, "out of memory");
        return -1;
    }
    for (y = c[2]; y < c[3]; y++)
        memcpy(out.rgb + (size_t)(y - c[2]) * (size_t)out.width * 3,
               img->rgb + ((size_t)y * (size_t)img->width + (size_t)c[0]) * 3,
               (size_t)out.width * 3 * sizeof(float));
    image_free(img);
    *img = out;
    return 0;
}

static int parse_crop(const char *s, long *c)
{
    char buf[128], *p = buf, *q;
    int k;
    if (strlen(s) >= sizeof buf)
        return -1;
    strcpy(buf, s);
    for (k = 0; k < 4; k++, p = q + 1) {
        q = strchr(p, ',');
        if ((q == NULL) != (k == 3))
            return -1;
        if (q)
            *q = '\0';
        if (cli_parse_long(p, 0, CW_MAX_SIDE, &c[k]) != 0)
            return -1;
        if (!q)
            break;
    }
    return c[0] < c[1] && c[2] < c[3] ? 0 : -1;
}

enum { O_EXPOSURE = 256, O_TONEMAP, O_PNG16, O_HALF, O_CROP, O_LINEAR, O_TOL, O_DIFF };

static const struct option longopts[] = {{"exposure", required_argument, NULL, O_EXPOSURE},
                                         {"tonemap", required_argument, NULL, O_TONEMAP},
                                         {"png16", no_argument, NULL, O_PNG16},
                                         {"half", no_argument, NULL, O_HALF},
                                         {"crop", required_argument, NULL, O_CROP},
                                         {"linear", no_argument, NULL, O_LINEAR},
                                         {"tol", required_argument, NULL, O_TOL},
                                         {"diff", required_argument, NULL, O_DIFF},
                                         {"help", no_argument, NULL, 'h'},
                                         {NULL, 0, NULL, 0}};

typedef struct {
    image_write_opts w;
    long crop[4];
    int has_crop, linear, png_opt;
    double tol;
    const char *diff;
} tool_opts;

static void info(const char *path, const image *img)
{
    size_t n = (size_t)img->width * (size_t)img->height, i;
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    double sum[3] = {0, 0, 0};
    long nonfinite = 0;
    int c;
    for (i = 0; i < n; i++)
        for (c = 0; c < 3; c++) {
            double v = img->rgb[3 * i + (size_t)c];
            if (!isfinite(v)) {
                nonfinite++;
                continue;
            }
            lo[c] = v < lo[c] ? v : lo[c];
            hi[c] = v > hi[c] ? v : hi[c];
            sum[c] += v;
        }
    printf("%s: %dx%d, linear RGB\n", path, img->width, img->height);
    for (c = 0; c < 3; c++)
        printf("  %c: min %.6g, max %.6g, mean %.6g\n", "RGB"[c], lo[c], hi[c],
               n ? sum[c] / (double)n : 0.0);
    printf("  non-finite values: %ld\n", nonfinite);
}

static int diff(const tool_opts *t, const image *a, const image *b, const char *pa, const char *pb,
                char *err, size_t errlen)
{
    image_diff_stats st;
    double se = 0, mse, psnr;
    size_t n = (size_t)a->width * (size_t)a->height * 3, i;
    if (image_compare(a, b, NULL, t->tol, &st) != 0) {
        snprintf(err, errlen, "%s is %dx%d, %s is %dx%d: not the same size", pa, a->width,
                 a->height, pb, b->width, b->height);
        return -1;
    }
    for (i = 0; i < n; i++) {
        double d = (double)a->rgb[i] - (double)b->rgb[i];
        se += d * d;
    }
    mse = n ? se / (double)n : 0;
    psnr = mse > 0 ? 10 * log10(1.0 / mse) : INFINITY;
    printf("size=%dx%d max=%.6g mean=%.6g rmse=%.6g psnr=%.2f dB over=%ld/%ld tol=%g\n", a->width,
           a->height, st.max_abs, st.mean_abs, sqrt(mse), psnr, st.over, st.compared, t->tol);
    if (t->diff && image_write_diff(a, b, NULL, t->tol, 100.0, t->diff, err, errlen) != 0)
        return -1;
    return st.over > 0 ? 1 : 0;
}

int main(int argc, char **argv)
{
    static char progname[] = "imgtool";
    char err[1024] = "";
    image img = {0, 0, NULL}, b = {0, 0, NULL};
    tool_opts t;
    const char *cmd;
    int c, rc = 1, nargs, k;

    memset(&t, 0, sizeof t);
    image_write_opts_default(&t.w);
    if (argc >= 2 && (strcmp(argv[1], "-h") == 0 || strcmp(argv[1], "--help") == 0)) {
        usage(stdout);
        return 0;
    }
    if (argc < 2)
        return usage_error("no command given (convert, diff, info or raw)", NULL);
    cmd = argv[1];
    if (strcmp(cmd, "convert") && strcmp(cmd, "diff") && strcmp(cmd, "info") && strcmp(cmd, "raw"))
        return usage_error("unknown command", cmd);
    argv[1] = progname;
    while ((c = getopt_long(argc - 1, argv + 1, "h", longopts, NULL)) != -1) {
        int is_convert = strcmp(cmd, "convert") == 0, is_diff = strcmp(cmd, "diff") == 0;
        if (c == 'h') {
            usage(stdout);
            return 0;
        }
        if (c != O_LINEAR && ((c == O_TOL || c == O_DIFF) ? !is_diff : !is_convert) && c != '?') {
            char m[96];
            snprintf(m, sizeof m, "an option given does not apply to '%s'", cmd);
            return usage_error(m, NULL);
        }
        switch (c) {
        case O_EXPOSURE:
            t.png_opt = 1;
            if (cli_parse_double(optarg, -CW_MAX_EXPOSURE, CW_MAX_EXPOSURE, &t.w.exposure) != 0)
                return usage_error("--exposure expects a number in -64..64, got", optarg);
            break;
        case O_TONEMAP:
            t.png_opt = 1;
            if ((t.w.tonemap = image_tonemap_parse(optarg)) < 0)
                return usage_error("--tonemap expects 'clamp', 'reinhard' or 'aces', got", optarg);
            break;
        case O_PNG16:
            t.png_opt = t.w.png16 = 1;
            break;
        case O_HALF:
            t.w.half = 1;
            break;
        case O_CROP:
            if (parse_crop(optarg, t.crop) != 0)
                return usage_error("--crop expects X0,X1,Y0,Y1 with X0 < X1 and Y0 < Y1, got",
                                   optarg);
            t.has_crop = 1;
            break;
        case O_LINEAR:
            t.linear = 1;
            break;
        case O_TOL:
            if (cli_parse_double(optarg, 0, 1e30, &t.tol) != 0)
                return usage_error("--tol expects a number >= 0, got", optarg);
            break;
        case O_DIFF:
            t.diff = optarg;
            break;
        default: /* getopt has said what is wrong */
            fprintf(stderr, "Try 'imgtool --help'.\n");
            return 2;
        }
    }
    optind++; /* past the command, in argv's numbering */
    nargs = argc - optind;
    if (strcmp(cmd, "info") == 0 ? nargs < 1 : nargs != 2)
        return usage_error(strcmp(cmd, "info") == 0 ? "info expects one or more images"
                                                    : "expects two file names",
                           NULL);
    if (strcmp(cmd, "convert") == 0) {
        int png = sys_has_ext(argv[optind + 1], ".png");
        if (image_check_path(argv[optind + 1], err, sizeof err) != 0)
            return usage_error(err, NULL);
        if (t.png_opt && !png)
            return usage_error("--exposure, --tonemap and --png16 apply to PNG output", NULL);
        if (t.w.half && png)
            return usage_error("--half applies to EXR output", NULL);
    }
    if (strcmp(cmd, "info") == 0) {
        rc = 0;
        for (k = optind; k < argc; k++) {
            if (read_any(argv[k], t.linear, &img, err, sizeof err) != 0) {
                fprintf(stderr, "imgtool: %s\n", err);
                rc = 1;
                continue;
            }
            info(argv[k], &img);
            image_free(&img);
        }
        return rc;
    }
    if (read_any(argv[optind], t.linear, &img, err, sizeof err) != 0) {
        fprintf(stderr, "imgtool: %s\n", err);
        return 1;
    }
    if (strcmp(cmd, "raw") == 0) {
        if (write_raw(&img, argv[optind + 1], err, sizeof err) == 0) {
            fprintf(strcmp(argv[optind + 1], "-") == 0 ? stderr : stdout, "%d %d\n", img.width,
                    img.height);
            rc = 0;
        }
    } else if (strcmp(cmd, "diff") == 0) {
        int d = -1;
        if (read_any(argv[optind + 1], t.linear, &b, err, sizeof err) == 0)
            d = diff(&t, &img, &b, argv[optind], argv[optind + 1], err, sizeof err);
        image_free(&b);
        image_free(&img);
        if (d < 0)
            fprintf(stderr, "imgtool: %s\n", err);
        return d < 0 ? 1 : d; /* 1: they differ (said on stdout) */
    } else if ((!t.has_crop || crop(&img, t.crop, err, sizeof err) == 0) &&
               image_write_ex(&img, argv[optind + 1], &t.w, err, sizeof err) == 0) {
        rc = 0;
    }
    if (rc != 0 && err[0])
        fprintf(stderr, "imgtool: %s\n", err);
    image_free(&img);
    return rc;
}
