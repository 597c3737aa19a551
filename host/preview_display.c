/* The preview's display (see preview_display.h): the 8-bit sRGB picture, drawing it into
 * the window, and grabbing the window back. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "preview_display.h"
#include "preview_font.h"
#include "sys.h"

void pvd_init(pvd_display *d)
{
    int c;
    memset(d, 0, sizeof *d);
    d->thr[0] = 0.0;
    for (c = 1; c < 256; c++)
        d->thr[c] = image_srgb_decode((c - 0.5) / 255.0);
}

void pvd_free(pvd_display *d)
{
    free(d->scratch);
    d->scratch = NULL;
    free(d->px);
    d->px = NULL;
}

/* The code of image_write_png: floor(encode(x) * 255 + 0.5), clamped, NaN -> 0; as a
 * search over the thresholds (identical except within rounding of a threshold). */
static unsigned char srgb8(const pvd_display *d, float f)
{
    double x = f;
    int lo = 0, hi = 255;
    if (!(x > 0.0))
        return 0;
    if (x >= 1.0)
        return 255;
    while (lo < hi) { /* the largest c with thr[c] <= x */
        int mid = (lo + hi + 1) / 2;
        if (d->thr[mid] <= x)
            lo = mid;
        else
            hi = mid - 1;
    }
    return (unsigned char)lo;
}

int pvd_resize(pvd_display *d, int w, int h, char *err, size_t errlen)
{
    unsigned char *px;
    int x, y;
    if (w == d->w && h == d->h && d->px)
        return 0;
    px = calloc((size_t)w * (size_t)h, 3);
    if (!px) {
        snprintf(err, errlen, "out of memory for a %dx%d display", w, h);
        return -1;
    }
    if (d->px)
        for (y = 0; y < h; y++) {
            int sy = (int)((long long)y * d->h / h);
            for (x = 0; x < w; x++) {
                int sx = (int)((long long)x * d->w / w);
                memcpy(px + 3 * ((size_t)y * w + x), d->px + 3 * ((size_t)sy * d->w + sx), 3);
            }
        }
    free(d->px);
    d->px = px;
    d->w = w;
    d->h = h;
    return 0;
}

void pvd_paint(pvd_display *d, const image *img, int rows)
{
    int x, y, W = d->w, H = d->h;
    for (y = 0; y < H; y++) {
        int sy = (int)((long long)y * img->height / H);
        unsigned char *dst = d->px + 3 * (size_t)(H - 1 - y) * W;
        if (sy >= rows)
            break;
        for (x = 0; x < W; x++) {
            int sx = (int)((long long)x * img->width / W);
            const float *src = img->rgb + 3 * ((size_t)sy * img->width + sx);
            dst[3 * x + 0] = srgb8(d, src[0]);
            dst[3 * x + 1] = srgb8(d, src[1]);
            dst[3 * x + 2] = srgb8(d, src[2]);
        }
    }
}

void pvd_overlay(pvd_display *d, int on, const char *status, const scene_camera *c,
                 const char *keys)
{
    if (!on)
        d->overlay[0] = '\0';
    else
        snprintf(d->overlay, sizeof d->overlay, "%s\neye %.3g %.3g %.3g\nview %.3g %.3g %.3g\n%s",
                 status, c->eye.x, c->eye.y, c->eye.z, -c->w.x, -c->w.y, -c->w.z, keys);
}

/* The overlay's lines into buf (w x h, bottom row first) from the top left: each line on
 * a box of the picture at half brightness, its glyphs in white. */
static void draw_text(unsigned char *buf, int w, int h, const char *text)
{
    int top = 2, x, y, k;
    const char *line = text;
    while (*line && top + PVF_H <= h) {
        int n = (int)strcspn(line, "\n"), right = 2 + PVF_W * n + 2;
        if (right > w)
            right = w;
        for (y = top - 1; y < top + PVF_H && y < h; y++)
            for (x = 0; x < right; x++) {
                unsigned char *q = buf + 3 * ((size_t)(h - 1 - y) * w + x);
                q[0] /= 2, q[1] /= 2, q[2] /= 2;
            }
        for (k = 0; k < n && 2 + PVF_W * (k + 1) <= w; k++) {
            int c = (unsigned char)line[k];
            const unsigned char *g =
                pvf_glyphs[(c < PVF_FIRST || c > PVF_LAST ? '?' : c) - PVF_FIRST];
            for (y = 0; y < PVF_H; y++)
                for (x = 0; x < PVF_W; x++)
                    if (g[y] & (1 << (PVF_W - 1 - x)))
                        memset(buf + 3 * ((size_t)(h - 1 - (top + y)) * w + 2 + PVF_W * k + x), 255,
                               3);
        }
        top += PVF_H + 1;
        line += n + (line[n] == '\n');
    }
}

int pvd_draw(pvd_display *d, pvg_window *w, int swap, char *err, size_t errlen)
{
    const pvg_gl *gl = &w->gl;
    const unsigned char *shown = d->px;
    gl->Viewport(0, 0, w->fb_w, w->fb_h);
    gl->ClearColor(0.0f, 0.0f, 0.0f, 1.0f);
    gl->Clear(PVG_GL_COLOR_BUFFER_BIT);
    if (d->px) {
        if (gl->WindowPos2i)
            gl->WindowPos2i(0, 0);
        else
            gl->RasterPos2f(-1.0f, -1.0f);
        gl->PixelStorei(PVG_GL_UNPACK_ALIGNMENT, 1);
        if (d->overlay[0]) {
            size_t n = 3 * (size_t)d->w * (size_t)d->h;
            unsigned char *s = realloc(d->scratch, n);
            if (s) { /* without memory the picture is shown without the overlay */
                d->scratch = s;
                memcpy(s, d->px, n);
                draw_text(s, d->w, d->h, d->overlay);
                shown = s;
            }
        }
        gl->DrawPixels(d->w, d->h, PVG_GL_RGB, PVG_GL_UNSIGNED_BYTE, shown);
    }
    if (pvg_gl_check(w, "glDrawPixels", err, errlen))
        return -1;
    if (swap)
        w->glfw.SwapBuffers(w->win);
    d->last = sys_now();
    return 0;
}

/* The display is redrawn and swapped first; the pixels are then read from the X server's
 * copy of the window (XGetImage: what is on the screen, after the swap). On a non-X11
 * window: glReadPixels of the back buffer just drawn, before its swap (Mesa's software
 * front buffer cannot be read back). */
int pvd_grab(pvd_display *d, pvg_window *w, const char *path, char *err, size_t errlen)
{
    int fw = w->fb_w, fh = w->fb_h, x, y, c, rc = -1;
    unsigned char *px = malloc((size_t)fw * (size_t)fh * 3);
    image img = {0, 0, NULL};
    if (!px || image_alloc(&img, fw, fh) != 0) {
        snprintf(err, errlen, "out of memory for a %dx%d grab", fw, fh);
        goto free_pixels;
    }
    if (pvd_draw(d, w, 1, err, errlen))
        goto free_pixels;
    w->gl.Finish();
    if (pvg_x11_grab(w, px) != 0) {
        /* not X11: the back buffer drawn just before the swap */
        if (pvd_draw(d, w, 0, err, errlen))
            goto free_pixels;
        w->gl.ReadBuffer(PVG_GL_BACK);
        w->gl.PixelStorei(PVG_GL_PACK_ALIGNMENT, 1);
        w->gl.ReadPixels(0, 0, fw, fh, PVG_GL_RGB, PVG_GL_UNSIGNED_BYTE, px);
        if (pvg_gl_check(w, "glReadPixels(GL_BACK)", err, errlen))
            goto free_pixels;
        w->glfw.SwapBuffers(w->win);
    }
    for (y = 0; y < fh; y++)
        for (x = 0; x < fw; x++)
            for (c = 0; c < 3; c++)
                img.rgb[3 * ((size_t)y * fw + x) + c] =
                    (float)image_srgb_decode(px[3 * ((size_t)(fh - 1 - y) * fw + x) + c] / 255.0);
    rc = image_write(&img, path, err, errlen);
free_pixels:
    free(px);
    image_free(&img);
    return rc;
}
