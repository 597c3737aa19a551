/* Internal to the image files (image.c, image_exr.c, image_png.c, image_read.c,
 * image_diff.c): what the writers, the readers and the comparison share. Other modules use
 * image.h, image_read.h and image_diff.h. */
#ifndef CW_IMAGE_INTERNAL_H
#define CW_IMAGE_INTERNAL_H

#include <stddef.h>
#include <stdint.h>
#include <time.h>

#include <openexr.h>
#include <png.h>

#include "image.h"

/* Formats a message into err (nothing when err is NULL or errlen is 0). */
void image_set_err(char *err, size_t errlen, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;

/* Rejects images that cannot be written or whose size overflows: 0, or -1 with err. */
int image_check_writable(const image *img, const char *path, char *err, size_t errlen);

/* Tone maps an exposed linear value to [0,1]; NaN and non-positive values give 0. */
double image_tonemap_value(double x, int tonemap);

/* 8-bit sRGB of a display value d (a tone mapped value, see image_tonemap_value), by
 * definition: NaN and d <= 0 give 0, d >= 1 gives 255, else
 * floor(image_srgb_encode(d) * 255 + 0.5). */
unsigned char image_srgb8_exact(double d);

/* The same function by table, exactly: bound[k] is the least double whose code is k or
 * more (found by search on image_srgb8_exact itself, so the table holds whatever the
 * platform's pow gives), and bin[i] the code of i / IMAGE_SRGB8_BINS, where the search for
 * a value's code starts. A code is the number of bounds at or below the value, which is
 * the definition wherever it does not decrease between neighbouring doubles
 * (tests/test_image.c checks that around every bound). Building one takes a few thousand
 * pow calls (about 0.1 ms); image_srgb8_encode then costs a few operations per value where
 * the definition costs a pow. */
#define IMAGE_SRGB8_BINS 4096
#define IMAGE_SRGB8_FBINS 0x3f80 /* the top 16 bits of the floats in [0,1) */
typedef struct {
    double bound[256]; /* bound[0] = 0 */
    unsigned char bin[IMAGE_SRGB8_BINS + 1];
    /* the same for float values (the clamp tone map at exposure 0): the bits of the least
     * float at or above each bound (fbound[256] above them all), and the code of the least
     * float of each value of the top 16 bits */
    uint32_t fbound[257];
    unsigned char fbin[IMAGE_SRGB8_FBINS];
} image_srgb8_table;

void image_srgb8_table_init(image_srgb8_table *t);
unsigned char image_srgb8(const image_srgb8_table *t, double d);
/* out[i] = image_srgb8(t, image_tonemap_value(linear[i] * scale, tonemap)), i < n. */
void image_srgb8_encode(const image_srgb8_table *t, const float *linear, size_t n, double scale,
                        int tonemap, unsigned char *out);

/* Metadata times: local time as "YYYY:MM:DD hh:mm:ss" (the EXR capDate form) with UTC
 * minus local time in seconds (the EXR utcOffset); UTC as ISO 8601 (the PNG Creation
 * Time). An empty string when the time cannot be converted. */
void image_local_date(time_t t, char *buf, size_t n, float *utc_offset);
void image_iso8601_utc(time_t t, char *buf, size_t n);

/* The threads an image writer compresses on: one per core it may use, at most
 * CW_MAX_WRITE_THREADS. */
int image_write_threads(void);

/* The writers behind image_write_ex (o not NULL), in image_exr.c and image_png.c. */
int image_exr_write(const image *img, const char *path, const image_write_opts *o, char *err,
                    size_t errlen);
int image_png_write(const image *img, const char *path, const image_write_opts *o, char *err,
                    size_t errlen);

/* OpenEXRCore error handling, shared by the EXR writer and reader (image_exr.c).
 * Per-context state: the last message OpenEXRCore reported, and (for writing) our own
 * output stream on the temporary file's descriptor, so that every write error is ours to
 * see and the library never opens or unlinks files itself. */
typedef struct {
    char msg[512];
    int fd;
    int write_errno;
} image_exr_state;

/* The context's error handler: stores the message in its image_exr_state (user data). */
void image_exr_error_cb(exr_const_context_t ctxt, exr_result_t code, const char *msg);
/* Formats "path: what failed: CODE (message)" for an OpenEXRCore result. */
void image_exr_fail(char *err, size_t errlen, const char *path, const char *what, exr_result_t rv,
                    const image_exr_state *st);
/* Checks the result of an OpenEXRCore call: on failure names the step in *what and
 * returns 1; on success clears the stored library message, so that a later failure's
 * message is its own. */
int image_exr_failed(image_exr_state *st, exr_result_t rv, const char *desc, const char **what);

/* libpng error handling, shared by the PNG writer and reader (image_png.c): the error
 * callback records the message and longjmps back to the setjmp in the function that owns
 * the png struct. Those functions only modify state in objects owned by their callers
 * after setjmp, so nothing of theirs can be clobbered. */
typedef struct {
    char msg[256];
} image_png_errctx;

void image_png_error_cb(png_structp png, png_const_charp msg);
void image_png_warning_cb(png_structp png, png_const_charp msg); /* ignores warnings */

#endif
