/* imgcmp: compares a rendered image with a reference under the portability-check
 * tolerance, prints one line of key=value statistics and exits 0 (agree) or 1 (disagree);
 * optionally writes a diff image. Also perturbs images on purpose, so that the check can
 * prove it fails (tools/portability-check --self-test).
 *
 * The rule (docs/portability.md): a pixel is "over" when any channel differs by
 * more than --tol; the images agree when
 *   - both have the same size and only finite values,
 *   - at most --max-over of the pixels are over (a fraction, rounded down, but at least
 *     --min-over pixels: a ray that passes within rounding of an edge may flip), and
 *   - the mean absolute difference over the pixels that are not over is at most --max-mean
 *     (catches a small bias everywhere that stays under --tol per pixel). */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli_num.h"
#include "image.h"
#include "image_diff.h"
#include "image_read.h"
#include "sys.h"

static void usage(FILE *f)
{
    fprintf(f,
            "usage: imgcmp [options] REFERENCE TEST\n"
            "       imgcmp --perturb KIND IN OUT\n"
            "Compares TEST with REFERENCE (.exr linear, or .png sRGB) and prints\n"
            "  size=WxH max=... mean=... inlier_mean=... over=N/M allowed=K worst=X,Y\n"
            "  nonfinite=N verdict=PASS|FAIL [why=...]\n"
            "  --tol T         per-channel tolerance of a pixel (default 1e-3)\n"
            "  --max-over F    largest fraction of pixels over T (default 0.005), rounded down\n"
            "  --min-over N    but always allow N pixels over T (default 1)\n"
            "  --max-mean M    largest mean difference of the pixels within T (default 1e-4)\n"
            "  --diff FILE     write a diff image (|a-b| x gain, pixels over T in red) when the\n"
            "                  images disagree\n"
            "  --diff-always   write it even when they agree\n"
            "  --gain G        gain of the diff image (default 100)\n"
            "--perturb writes IN changed on purpose, for self-tests: KIND is box (a 3x3 block\n"
            "  +0.5), pixel (one pixel +1), bias (+3e-4 everywhere), nan (one NaN pixel).\n"
            "Exit status: 0 agree (or perturbed), 1 disagree, 2 usage or read error.\n");
}

static int parse_double(const char *opt, const char *s, double lo, double hi, double *out)
{
    if (!s) {
        fprintf(stderr, "imgcmp: %s needs a value\n", opt);
        return -1;
    }
    if (cli_parse_double(s, lo, hi, out) != 0) {
        fprintf(stderr, "imgcmp: %s expects a number in [%g, %g], got '%s'\n", opt, lo, hi, s);
        return -1;
    }
    return 0;
}

static int read_image(const char *path, image *img)
{
    char err[1024];
    int rc = sys_has_ext(path, ".png") ? image_read_png(path, 1, img, err, sizeof err)
                                       : image_read_exr(path, img, err, sizeof err);
    if (rc != 0)
        fprintf(stderr, "imgcmp: %s\n", err);
    return rc;
}

static long count_nonfinite(const image *img)
{
    long n = 0;
    size_t i, count = (size_t)img->width * (size_t)img->height * 3;
    for (i = 0; i < count; i++)
        if (!isfinite(img->rgb[i]))
            n++;
    return n;
}

static int perturb(const char *kind, const char *in, const char *out)
{
    image img = {0, 0, NULL};
    char err[1024];
    int w, h, x, y, c, rc = 2;
    if (read_image(in, &img) != 0)
        return 2;
    w = img.width;
    h = img.height;
    if (strcmp(kind, "box") == 0) {
        for (y = h / 2 - 1; y <= h / 2 + 1; y++)
            for (x = w / 2 - 1; x <= w / 2 + 1; x++)
                if (x >= 0 && y >= 0 && x < w && y < h)
                    for (c = 0; c < 3; c++)
                        img.rgb[3 * ((size_t)y * w + x) + c] += 0.5f;
    } else if (strcmp(kind, "pixel") == 0) {
        for (c = 0; c < 3; c++)
            img.rgb[3 * ((size_t)(h / 2) * w + w / 2) + c] += 1.0f;
    } else if (strcmp(kind, "bias") == 0) {
        size_t i;
        for (i = 0; i < (size_t)w * h * 3; i++)
            img.rgb[i] += 3e-4f;
    } else if (strcmp(kind, "nan") == 0) {
        img.rgb[3 * ((size_t)(h / 2) * w + w / 2)] = nanf("");
    } else {
        fprintf(stderr, "imgcmp: unknown perturbation '%s' (box, pixel, bias, nan)\n", kind);
        goto out;
    }
    if (image_write(&img, out, err, sizeof err) != 0) {
        fprintf(stderr, "imgcmp: %s\n", err);
        goto out;
    }
    rc = 0;
out:
    image_free(&img);
    return rc;
}

int main(int argc, char **argv)
{
    double tol = 1e-3, max_over = 0.005, max_mean = 1e-4, gain = 100.0, min_over_d = 1.0;
    const char *diff = NULL, *files[2] = {NULL, NULL};
    int diff_always = 0, nfiles = 0, i, rc = 2;
    image ref = {0, 0, NULL}, test = {0, 0, NULL};
    image_diff_stats all, in;
    unsigned char *mask = NULL;
    long nonfinite, allowed, npix, min_over;
    char why[256] = "";
    char err[1024];

    for (i = 1; i < argc; i++) {
        const char *a = argv[i];
        if (strcmp(a, "-h") == 0 || strcmp(a, "--help") == 0) {
            usage(stdout);
            return 0;
        } else if (strcmp(a, "--perturb") == 0) {
            if (argc - i != 4) {
                usage(stderr);
                return 2;
            }
            return perturb(argv[i + 1], argv[i + 2], argv[i + 3]);
        } else if (strcmp(a, "--tol") == 0) {
            if (parse_double(a, argv[++i], 0.0, 1e30, &tol))
                return 2;
        } else if (strcmp(a, "--max-over") == 0) {
            if (parse_double(a, argv[++i], 0.0, 1.0, &max_over))
                return 2;
        } else if (strcmp(a, "--min-over") == 0) {
            if (parse_double(a, argv[++i], 0.0, 1e9, &min_over_d))
                return 2;
        } else if (strcmp(a, "--max-mean") == 0) {
            if (parse_double(a, argv[++i], 0.0, 1e30, &max_mean))
                return 2;
        } else if (strcmp(a, "--gain") == 0) {
            if (parse_double(a, argv[++i], 0.0, 1e30, &gain))
                return 2;
        } else if (strcmp(a, "--diff") == 0) {
            diff = argv[++i];
            if (!diff) {
                fprintf(stderr, "imgcmp: --diff needs a file name\n");
                return 2;
            }
        } else if (strcmp(a, "--diff-always") == 0) {
            diff_always = 1;
        } else if (a[0] == '-' && a[1] != '\0') {
            fprintf(stderr, "imgcmp: unknown option '%s'\n", a);
            usage(stderr);
            return 2;
        } else if (nfiles < 2) {
            files[nfiles++] = a;
        } else {
            fprintf(stderr, "imgcmp: more than two images given\n");
            return 2;
        }
    }
    if (nfiles != 2) {
        usage(stderr);
        return 2;
    }
    if (read_image(files[0], &ref) != 0 || read_image(files[1], &test) != 0)
        goto out;
    if (ref.width != test.width || ref.height != test.height) {
        printf("size=%dx%d verdict=FAIL why=size:%dx%d\n", ref.width, ref.height, test.width,
               test.height);
        rc = 1;
        goto out;
    }
    npix = (long)ref.width * ref.height;
    min_over = (long)min_over_d;
    nonfinite = count_nonfinite(&ref) + count_nonfinite(&test);
    mask = malloc((size_t)npix);
    if (!mask) {
        fprintf(stderr, "imgcmp: out of memory\n");
        goto out;
    }
    /* Statistics over all pixels, then the mean over the pixels within the tolerance. */
    image_compare(&ref, &test, NULL, tol, &all);
    for (i = 0; i < npix; i++) {
        int c, over = 0;
        for (c = 0; c < 3; c++) {
            float a = ref.rgb[3 * (size_t)i + c], b = test.rgb[3 * (size_t)i + c];
            double d = a == b ? 0.0 : fabs((double)a - (double)b);
            if (!(d <= tol))
                over = 1;
        }
        mask[i] = (unsigned char)!over;
    }
    image_compare(&ref, &test, mask, tol, &in);
    allowed = (long)floor(max_over * (double)npix);
    if (allowed < min_over)
        allowed = min_over;

    if (nonfinite)
        snprintf(why + strlen(why), sizeof why - strlen(why), "%snonfinite", *why ? "," : "");
    if (all.over > allowed)
        snprintf(why + strlen(why), sizeof why - strlen(why), "%sover", *why ? "," : "");
    if (in.mean_abs > max_mean)
        snprintf(why + strlen(why), sizeof why - strlen(why), "%smean", *why ? "," : "");
    rc = *why ? 1 : 0;
    printf("size=%dx%d max=%.3g mean=%.3g inlier_mean=%.3g over=%ld/%ld allowed=%ld worst=%d,%d "
           "nonfinite=%ld verdict=%s%s%s\n",
           ref.width, ref.height, all.max_abs, all.mean_abs, in.mean_abs, all.over, npix, allowed,
           all.worst_x, all.worst_y, nonfinite, rc ? "FAIL" : "PASS", rc ? " why=" : "", why);
    if (diff && (rc || diff_always) &&
        image_write_diff(&ref, &test, NULL, tol, gain, diff, err, sizeof err) != 0) {
        fprintf(stderr, "imgcmp: %s\n", err);
        rc = 2;
    }
out:
    free(mask);
    image_free(&ref);
    image_free(&test);
    return rc;
}
