/* Images: the image model (allocation), write options and their defaults, tone maps and
 * the sRGB transfer pair, and the metadata times both writers use. See image.h. */
#include "image.h"

#include <math.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "image_internal.h"

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

/* Tone maps an exposed linear value to [0,1]; NaN and non-positive values give 0. */
double image_tonemap_value(double x, int tonemap)
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
