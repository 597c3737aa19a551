/* Comparing images (per-channel statistics under a tolerance and a mask) and writing diff
 * images, for tests and tools. See image_diff.h. */
#include "image_diff.h"

#include <math.h>
#include <stddef.h>
#include <string.h>

#include "image.h"
#include "image_internal.h"

/* Absolute difference of two channel values; equal values (including equal infinities)
 * differ by 0, two NaNs by 0, a NaN against a number by +infinity. */
static double chan_diff(float a, float b)
{
    double d;
    if (a == b || (isnan(a) && isnan(b)))
        return 0.0;
    d = fabs((double)a - (double)b);
    return isnan(d) ? INFINITY : d;
}

int image_compare(const image *a, const image *b, const unsigned char *mask, double tol,
                  image_diff_stats *st)
{
    image_diff_stats s;
    double sum = 0.0;
    memset(&s, 0, sizeof s);
    s.worst_x = s.worst_y = -1;
    if (st)
        *st = s;
    if (!a || !b || a->width != b->width || a->height != b->height || a->width < 0 || a->height < 0)
        return -1;
    if ((size_t)a->width * (size_t)a->height > 0 && (!a->rgb || !b->rgb))
        return -1;
    for (int y = 0; y < a->height; y++) {
        for (int x = 0; x < a->width; x++) {
            size_t p = (size_t)y * (size_t)a->width + (size_t)x;
            int over = 0;
            if (mask && !mask[p])
                continue;
            s.compared++;
            for (int c = 0; c < 3; c++) {
                double d = chan_diff(a->rgb[p * 3 + c], b->rgb[p * 3 + c]);
                sum += d;
                if (d > tol)
                    over = 1;
                if (d > s.max_abs || s.worst_x < 0) {
                    if (d > s.max_abs)
                        s.max_abs = d;
                    s.worst_x = x;
                    s.worst_y = y;
                }
            }
            if (over)
                s.over++;
        }
    }
    s.mean_abs = s.compared ? sum / (3.0 * (double)s.compared) : 0.0;
    if (st)
        *st = s;
    return 0;
}

int image_write_diff(const image *a, const image *b, const unsigned char *mask, double tol,
                     double gain, const char *path, char *err, size_t errlen)
{
    image d;
    int rc;
    if (!a || !b || !a->rgb || !b->rgb || a->width != b->width || a->height != b->height) {
        image_set_err(err, errlen, "%s: cannot diff images of different sizes (%dx%d vs %dx%d)",
                      path ? path : "(null)", a ? a->width : 0, a ? a->height : 0, b ? b->width : 0,
                      b ? b->height : 0);
        return -1;
    }
    if (image_alloc(&d, a->width, a->height) != 0) {
        image_set_err(err, errlen, "%s: out of memory for the diff image", path ? path : "(null)");
        return -1;
    }
    for (size_t p = 0; p < (size_t)a->width * (size_t)a->height; p++) {
        const float *pa = a->rgb + p * 3, *pb = b->rgb + p * 3;
        float *o = d.rgb + p * 3;
        if (mask && !mask[p]) {
            /* Masked out: a's luminance, clamped to [0,1], dimmed to a quarter, as grey. */
            double l = 0.2126 * pa[0] + 0.7152 * pa[1] + 0.0722 * pa[2];
            if (!(l > 0.0))
                l = 0.0;
            if (l > 1.0)
                l = 1.0;
            o[0] = o[1] = o[2] = (float)(0.25 * l);
            continue;
        }
        double dd[3];
        int over = 0;
        for (int c = 0; c < 3; c++) {
            dd[c] = chan_diff(pa[c], pb[c]);
            if (dd[c] > tol)
                over = 1;
        }
        if (over) {
            o[0] = 1.0f;
            o[1] = o[2] = 0.0f;
        } else {
            for (int c = 0; c < 3; c++) {
                double v = dd[c] * gain;
                o[c] = (float)(!(v > 0.0) ? 0.0 : v > 1.0 ? 1.0 : v);
            }
        }
    }
    rc = image_write(&d, path, err, errlen);
    image_free(&d);
    return rc;
}
