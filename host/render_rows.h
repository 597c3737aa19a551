/* The renderer's row-band helpers shared by render.c and render_rows.c (the public part,
 * renderer_render_rows and renderer_resolve, is in render.h). For render*.c only. */
#ifndef CW_RENDER_ROWS_H
#define CW_RENDER_ROWS_H

#include "image.h"
#include "types.h"

/* The SPD frame: rays through the (nx+1) x (ny+1) pixel corners of f, i.e. the centres of
 * an image one pixel larger whose window is half a pixel wider on every side (of a crop:
 * the corners of its pixels in the full image's grid of corners). */
void rrows_spd_frame(const cw_frame *f, cw_frame *corners);

/* The image (img allocated at its size) from an accumulation of rgb + sample count per
 * pixel: each pixel divided by its count (none: black); or, for SPD, from the
 * (width+1) x (height+1) corner accumulation, the four corners of each pixel averaged. */
void rrows_resolve_mean(const float *px, image *img);
void rrows_resolve_spd(const float *px, image *img);

#endif
