/* Comparing images and writing diff images, for tests and tools. */
#ifndef CW_IMAGE_DIFF_H
#define CW_IMAGE_DIFF_H

#include <stddef.h>

#include "image.h"

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
