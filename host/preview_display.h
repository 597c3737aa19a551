/* What the preview window shows: an 8-bit sRGB copy of the rendered image, encoded as the
 * PNG writer does, drawn with glDrawPixels (legacy GL, which Mesa's llvmpipe has); and
 * the grab of the window's pixels for the test script. */
#ifndef CW_PREVIEW_DISPLAY_H
#define CW_PREVIEW_DISPLAY_H

#include <stddef.h>

#include "image.h"
#include "preview_glfw.h"
#include "scene.h"

typedef struct {
    unsigned char *px; /* 8-bit sRGB, bottom row first, w x h; NULL: none yet */
    int w, h;
    char overlay[1024];     /* text drawn over the picture (lines split by '\n'); "": none */
    unsigned char *scratch; /* the picture with the overlay, as drawn */
    double last;            /* when it was last drawn (sys_now) */
    double thr[256];        /* thr[c]: the smallest linear value with code >= c */
} pvd_display;

/* An empty display; pvd_free releases its buffer. */
void pvd_init(pvd_display *d);
void pvd_free(pvd_display *d);

/* Resizes the buffer to w x h, scaling the old picture (nearest) into it. Returns 0, or
 * -1 with err. */
int pvd_resize(pvd_display *d, int w, int h, char *err, size_t errlen);

/* Paints the top `rows` rows of img (any size: scaled, nearest) into the buffer. */
void pvd_paint(pvd_display *d, const image *img, int rows);

/* Sets the overlay (on: the status lines, the camera's eye and view direction, and the
 * keys; off: none). */
void pvd_overlay(pvd_display *d, int on, const char *status, const scene_camera *c,
                 const char *keys);

/* Draws the buffer into the window's back buffer, with the overlay text at the top left
 * (white on a darkened box; the buffer itself is left alone), and swaps if `swap`. Returns
 * 0, or -1 with err (an OpenGL error). */
int pvd_draw(pvd_display *d, pvg_window *w, int swap, char *err, size_t errlen);

/* Grabs what the window shows and writes it to path (.png: the 8-bit values as shown;
 * .exr: those values decoded to linear). Returns 0, or -1 with err. */
int pvd_grab(pvd_display *d, pvg_window *w, const char *path, char *err, size_t errlen);

#endif
