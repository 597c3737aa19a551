/* Images: the image model (allocation), write options and their defaults, tone maps, the
 * sRGB transfer pair and the exact 8-bit sRGB encoding by table, and the metadata times
 * both writers use. See image.h. */
#include "image.h"

#include <math.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "config.h"
#include "image_internal.h"
#include "sys.h"

/* ------------------------------------------------------------------------------------ */
/* The image model                                                                      */

int image_alloc(image *img, int width, int height)
{
    if (!img)
        return -1;
    img->width = img->height = 0;
    img->rgb = NULL;
    if (width <= 0 || height <= 0 || (size_t)width > SIZE_MAX / 3 / sizeof(float) / (size_t)height)
        return -1;
    img->rgb = calloc((size_t)width * (size_t)height * 3, sizeof(float));
    if (!img->rgb)
        return -1;
    img->width = width;
    img->height = height;
    return 0;
}

void image_free(image *img)
{
    if (!img)
        return;
    free(img->rgb);
    img->rgb = NULL;
    img->width = img->height = 0;
}

/* ------------------------------------------------------------------------------------ */
/* Options, tone maps, the sRGB transfer pair, library versions                         */

void image_write_opts_default(image_write_opts *o)
{
    memset(o, 0, sizeof *o);
    o->exposure = 0.0;
    o->tonemap = IMAGE_TONEMAP_CLAMP;
    o->render_s = -1.0;
}

int image_tonemap_parse(const char *name)
{
    if (strcmp(name, "clamp") == 0)
        return IMAGE_TONEMAP_CLAMP;
    if (strcmp(name, "reinhard") == 0)
        return IMAGE_TONEMAP_REINHARD;
    if (strcmp(name, "aces") == 0)
        return IMAGE_TONEMAP_ACES;
    return -1;
}

const char *image_tonemap_name(int tonemap)
{
    switch (tonemap) {
    case IMAGE_TONEMAP_REINHARD:
        return "reinhard";
    case IMAGE_TONEMAP_ACES:
        return "aces";
    default:
        return "clamp";
    }
}

/* Tone maps an exposed linear value to [0,1]; NaN and non-positive values give 0. Static
 * so that the row encoder below inlines it; image_tonemap_value is the same function. */
static double tonemap_value(double x, int tonemap)
{
    if (!(x > 0.0))
        return 0.0;
    if (x > 1e100) /* also +inf: every curve is at (or clamped to) 1 there */
        return 1.0;
    if (tonemap == IMAGE_TONEMAP_REINHARD)
        x = x / (1.0 + x);
    else if (tonemap == IMAGE_TONEMAP_ACES)
        x = x * (2.51 * x + 0.03) / (x * (2.43 * x + 0.59) + 0.14);
    return x > 1.0 ? 1.0 : x;
}

double image_tonemap_value(double x, int tonemap)
{
    return tonemap_value(x, tonemap);
}

double image_display_value(double linear, double exposure, int tonemap)
{
    return image_tonemap_value(linear * pow(2.0, exposure), tonemap);
}

double image_srgb_encode(double x)
{
    return x <= 0.0031308 ? 12.92 * x : 1.055 * pow(x, 1.0 / 2.4) - 0.055;
}

double image_srgb_decode(double v)
{
    return v <= 0.04045 ? v / 12.92 : pow((v + 0.055) / 1.055, 2.4);
}

/* ------------------------------------------------------------------------------------ */
/* 8-bit sRGB: the definition, and the same function by table                            */

unsigned char image_srgb8_exact(double d)
{
    if (!(d > 0.0)) /* also NaN */
        return 0;
    if (d >= 1.0)
        return 255;
    return (unsigned char)floor(image_srgb_encode(d) * 255.0 + 0.5);
}

/* The least double d in (0,1) with image_srgb8_exact(d) >= k, for k in 1..255: from the
 * inverse transfer's estimate, widen a bracket lo < hi with code(lo) < k <= code(hi), then
 * halve it until lo and hi are neighbouring doubles. */
static double srgb8_bound(int k)
{
    double g = image_srgb_decode((k - 0.5) / 255.0), lo = g, hi = g, step = g * 1e-13;
    while (image_srgb8_exact(lo) >= k) {
        lo -= step;
        step *= 2;
    }
    step = g * 1e-13;
    while (image_srgb8_exact(hi) < k) {
        hi += step;
        step *= 2;
    }
    for (;;) {
        double mid = lo + (hi - lo) * 0.5;
        if (mid <= lo || mid >= hi)
            return hi;
        if (image_srgb8_exact(mid) >= k)
            hi = mid;
        else
            lo = mid;
    }
}

/* The bits of a float (positive floats order as their bits do). */
static uint32_t float_bits(float f)
{
    uint32_t b;
    memcpy(&b, &f, sizeof b);
    return b;
}

void image_srgb8_table_init(image_srgb8_table *t)
{
    int k, i, c = 0;
    t->bound[0] = 0.0;
    for (k = 1; k < 256; k++)
        t->bound[k] = srgb8_bound(k);
    for (i = 0; i <= IMAGE_SRGB8_BINS; i++) {
        double d = (double)i / IMAGE_SRGB8_BINS;
        while (c < 255 && d >= t->bound[c + 1])
            c++;
        t->bin[i] = (unsigned char)c;
    }
    /* The float bounds: the least float at or above each double bound. */
    t->fbound[0] = 0;
    for (k = 1; k < 256; k++) {
        float f = (float)t->bound[k];
        if ((double)f < t->bound[k])
            f = nextafterf(f, 2.0f);
        t->fbound[k] = float_bits(f);
    }
    t->fbound[256] = UINT32_MAX; /* a sentinel above every float in [0,1) */
    for (i = 0, c = 0; i < IMAGE_SRGB8_FBINS; i++) {
        while (c < 255 && (uint32_t)i << 16 >= t->fbound[c + 1])
            c++;
        t->fbin[i] = (unsigned char)c;
    }
}

/* The number of bounds at or below d: the bin of d gives the count at its lower end, and
 * no bin spans more than one code step (the steepest part of the curve, 12.92 * 255 codes
 * per unit, is 0.8 codes per bin), so the loop runs at most once; it is a loop all the
 * same, so that the result never depends on that margin. */
static unsigned char srgb8_lookup(const image_srgb8_table *t, double d)
{
    int c;
    if (!(d > 0.0))
        return 0;
    if (d >= 1.0)
        return 255;
    c = t->bin[(int)(d * IMAGE_SRGB8_BINS)];
    while (c < 255 && d >= t->bound[c + 1])
        c++;
    return (unsigned char)c;
}

unsigned char image_srgb8(const image_srgb8_table *t, double d)
{
    return srgb8_lookup(t, d);
}

/* The same on the linear float itself, when the display value is that float clamped
 * (IMAGE_TONEMAP_CLAMP, scale 1): a float's code is the number of float bounds at or below
 * it, its bits' top 16 bits (the exponent and 7 mantissa bits) giving the start. */
static unsigned char srgb8_lookup_float(const image_srgb8_table *t, float f)
{
    uint32_t b = float_bits(f);
    int c;
    if (b - 1u >= 0x3f7fffffu) /* not in (0, 1): 0, negative or NaN give 0; 1 to inf 255 */
        return b >= 0x3f800000u && b <= 0x7f800000u ? 255 : 0;
    c = t->fbin[b >> 16];
    while (b >= t->fbound[c + 1])
        c++;
    return (unsigned char)c;
}

void image_srgb8_encode(const image_srgb8_table *t, const float *linear, size_t n, double scale,
                        int tonemap, unsigned char *out)
{
    size_t i;
    if (tonemap == IMAGE_TONEMAP_CLAMP && scale == 1.0)
        for (i = 0; i < n; i++)
            out[i] = srgb8_lookup_float(t, linear[i]);
    else
        for (i = 0; i < n; i++)
            out[i] = srgb8_lookup(t, tonemap_value(linear[i] * scale, tonemap));
}

const char *image_library_versions(void)
{
    static char buf[128];
    int maj = 0, min = 0, patch = 0;
    const char *extra = NULL;
    exr_get_library_version(&maj, &min, &patch, &extra);
    snprintf(buf, sizeof buf, "libpng %s, OpenEXR %d.%d.%d%s", png_get_libpng_ver(NULL), maj, min,
             patch, extra ? extra : "");
    return buf;
}

/* ------------------------------------------------------------------------------------ */
/* Shared by the writers and readers (image_internal.h)                                 */

void image_set_err(char *err, size_t errlen, const char *fmt, ...)
{
    va_list ap;
    if (!err || errlen == 0)
        return;
    va_start(ap, fmt);
    vsnprintf(err, errlen, fmt, ap);
    va_end(ap);
}

/* Rejects images that cannot be written or whose size overflows. */
int image_check_writable(const image *img, const char *path, char *err, size_t errlen)
{
    if (!path || !*path) {
        image_set_err(err, errlen, "image: no output path given");
        return -1;
    }
    if (!img || !img->rgb || img->width <= 0 || img->height <= 0) {
        image_set_err(err, errlen, "%s: no image data to write", path);
        return -1;
    }
    if ((size_t)img->width > SIZE_MAX / 3 / sizeof(float) / (size_t)img->height) {
        image_set_err(err, errlen, "%s: image size %dx%d too large", path, img->width, img->height);
        return -1;
    }
    return 0;
}

int image_write_threads(void)
{
    int threads = sys_cpu_count();
    return threads < CW_MAX_WRITE_THREADS ? threads : CW_MAX_WRITE_THREADS;
}

/* Local time as "YYYY:MM:DD hh:mm:ss" (the EXR capDate form) or ISO 8601 UTC, and UTC
 * minus local time in seconds (the EXR utcOffset). */
void image_local_date(time_t t, char *buf, size_t n, float *utc_offset)
{
    struct tm local, utc;
    time_t as_local;
    buf[0] = '\0';
    *utc_offset = 0.0f;
    if (!localtime_r(&t, &local) || !gmtime_r(&t, &utc))
        return;
    strftime(buf, n, "%Y:%m:%d %H:%M:%S", &local);
    utc.tm_isdst = -1;
    as_local = mktime(&utc); /* the UTC wall time read as local time */
    if (as_local != (time_t)-1)
        *utc_offset = (float)difftime(as_local, t);
}

void image_iso8601_utc(time_t t, char *buf, size_t n)
{
    struct tm utc;
    buf[0] = '\0';
    if (gmtime_r(&t, &utc))
        strftime(buf, n, "%Y-%m-%dT%H:%M:%SZ", &utc);
}
