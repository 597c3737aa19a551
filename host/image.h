/* Images: linear float RGB in memory, written as OpenEXR (linear) or PNG (sRGB). */
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
/* Checks that image_write can write this kind of file (.exr or .png), before a render. */
int image_check_path(const char *path, char *err, size_t errlen);
int image_write_exr(const image *img, const char *path, char *err, size_t errlen);
int image_write_png(const image *img, const char *path, char *err, size_t errlen);

/* Readers (for tests and tools). image_read_exr returns the linear values.
 * image_read_png returns the stored values scaled to [0,1] (8- or 16-bit), decoded from
 * sRGB when srgb_decode != 0, else as stored (e.g. POV-Ray's linear 16-bit output). */
int image_read_exr(const char *path, image *img, char *err, size_t errlen);
int image_read_png(const char *path, int srgb_decode, image *img, char *err, size_t errlen);

typedef struct {
    double max_abs;  /* largest absolute channel difference over compared pixels */
    double mean_abs; /* mean absolute channel difference over compared pixels */
    long compared;   /* pixels compared (mask != 0) */
    long over;       /* compared pixels with any channel differing by more than tol */
    int worst_x, worst_y;
} image_diff_stats;

/* Compares a and b (same size) on the pixels where mask is non-zero (mask NULL: all).
 * Returns 0, or -1 when the sizes differ. */
int image_compare(const image *a, const image *b, const unsigned char *mask, double tol,
                  image_diff_stats *st);

/* Writes a diff image: |a-b| scaled by `gain` per channel, pixels over tol in red when
 * the mask allows them, masked-out pixels dimmed. Format by extension. */
int image_write_diff(const image *a, const image *b, const unsigned char *mask, double tol,
                     double gain, const char *path, char *err, size_t errlen);

#endif
