/* Reading images into linear float RGB, for tests and tools (clwhitted never reads one). */
#ifndef CW_IMAGE_READ_H
#define CW_IMAGE_READ_H

#include <stddef.h>

#include "image.h"

/* Readers. image_read_exr returns the linear values.
 * image_read_png returns the stored values scaled to [0,1] (8- or 16-bit), decoded from
 * sRGB when srgb_decode != 0, else as stored (e.g. POV-Ray's linear 16-bit output). */
int image_read_exr(const char *path, image *img, char *err, size_t errlen);
int image_read_png(const char *path, int srgb_decode, image *img, char *err, size_t errlen);

#endif
