/* Images: linear float RGB in memory, written as OpenEXR (linear) or PNG (sRGB); tone maps
 * and the sRGB transfer pair. Reading images: image_read.h; comparing them: image_diff.h
 * (tests and tools; clwhitted itself only writes). */
#ifndef CW_IMAGE_H
#define CW_IMAGE_H

#include <stddef.h>

typedef struct {
    int width, height;
    float *rgb; /* width*height RGB triples, row 0 at the top */
} image;

int image_alloc(image *img, int width, int height); /* zero-filled; 0 or -1 */
void image_free(image *img);

/* Writes by extension (.exr: linear float RGB; .png: sRGB-encoded 8-bit) to a temporary
 * file beside `path`, then renames it, so a failure never leaves a half-written image.
 * Returns 0, or -1 with a message in err. */
int image_write(const image *img, const char *path, char *err, size_t errlen);

/* How image_write_ex encodes, and the metadata it writes into the file's header. */
#define IMAGE_TONEMAP_CLAMP 0    /* clamp to [0,1] */
#define IMAGE_TONEMAP_REINHARD 1 /* c / (1 + c) per channel */
#define IMAGE_TONEMAP_ACES 2     /* Narkowicz's ACES filmic fit, per channel */
typedef struct {
    double exposure; /* PNG: values are multiplied by 2^exposure, then tone mapped */
    int tonemap;     /* PNG: IMAGE_TONEMAP_*; EXR keeps the linear values */
    int half;        /* EXR: 16-bit half floats instead of 32-bit floats */
    int png16;       /* PNG: 16 bits per channel instead of 8 */
    /* Metadata (NULL or render_s < 0: left out). PNG: tEXt chunks Title, Software, Source,
     * Comment, Render Time, Creation Time and a tIME chunk. EXR: string attributes scene,
     * software, device, comments, capDate (local time), float utcOffset and renderTime. */
    const char *title;    /* the scene */
    const char *software; /* e.g. "clwhitted 0.1.0" */
    const char *source;   /* the device */
    const char *comment;  /* the settings */
    double render_s;      /* render time, seconds */
} image_write_opts;

/* Defaults: exposure 0, clamp, 32-bit floats, no metadata. */
void image_write_opts_default(image_write_opts *o);
/* image_write with options (o NULL: the defaults). */
int image_write_ex(const image *img, const char *path, const image_write_opts *o, char *err,
                   size_t errlen);
/* The PNG display value of a linear value, before sRGB encoding: exposure, tone map, clamp
 * to [0,1] (NaN -> 0). */
double image_display_value(double linear, double exposure, int tonemap);
/* The sRGB transfer function and its inverse, on [0,1] (IEC 61966-2-1). */
double image_srgb_encode(double linear);
double image_srgb_decode(double encoded);
/* "clamp", "reinhard", "aces" -> IMAGE_TONEMAP_*, or -1; and back. */
int image_tonemap_parse(const char *name);
const char *image_tonemap_name(int tonemap);
/* The versions of the image libraries, e.g. "libpng 1.6.39, OpenEXR 3.1.5". */
const char *image_library_versions(void);

/* Checks that image_write can write this kind of file (.exr or .png), before a render. */
int image_check_path(const char *path, char *err, size_t errlen);
/* image_write in one format whatever the extension, with the default options. */
int image_write_exr(const image *img, const char *path, char *err, size_t errlen);
int image_write_png(const image *img, const char *path, char *err, size_t errlen);

#endif
