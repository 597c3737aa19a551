/* Writing PNG (libpng): 8-bit sRGB after exposure and tone map, with the metadata of
 * image_write_opts as text chunks and tIME; and the libpng error handling that the reader
 * (image_read.c) shares. See image.h and image_internal.h. */
#include <errno.h>
#include <math.h>
#include <setjmp.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include <png.h>

#include "image.h"
#include "image_internal.h"
#include "sys.h"

/* ------------------------------------------------------------------------------------ */
/* Error handling (shared with the reader)                                               */

void image_png_error_cb(png_structp png, png_const_charp msg)
{
    image_png_errctx *e = png_get_error_ptr(png);
    if (e)
        snprintf(e->msg, sizeof e->msg, "%s", msg ? msg : "unknown libpng error");
    png_longjmp(png, 1);
}

void image_png_warning_cb(png_structp png, png_const_charp msg)
{
    (void)png;
    (void)msg; /* warnings (e.g. about ancillary chunks) are not errors for us */
}

/* ------------------------------------------------------------------------------------ */
/* Writing                                                                               */

/* Display value (see image_tonemap_value) -> 8-bit sRGB: NaN -> 0, clamp to [0,1], encode,
 * round to nearest. */
static unsigned char to_srgb8(double x)
{
    if (!(x > 0.0)) /* also NaN */
        return 0;
    if (x >= 1.0)
        return 255;
    return (unsigned char)floor(image_srgb_encode(x) * 255.0 + 0.5);
}

/* The PNG text chunks and modification time of image_write_opts' metadata. */
#define PNG_META_MAX 6
typedef struct {
    png_text text[PNG_META_MAX];
    int count;
    png_time mtime;
    char render_time[32], created[32];
} png_meta;

static int is_ascii(const char *s)
{
    for (; *s; s++)
        if ((unsigned char)*s >= 0x80)
            return 0;
    return 1;
}

static void png_meta_add(png_meta *m, const char *key, const char *value)
{
    png_text *t;
    if (!value || !*value || m->count >= PNG_META_MAX)
        return;
    t = &m->text[m->count++];
    memset(t, 0, sizeof *t);
    /* tEXt is Latin-1: UTF-8 (anything non-ASCII) goes into an uncompressed iTXt chunk. */
    t->compression = is_ascii(value) ? PNG_TEXT_COMPRESSION_NONE : PNG_ITXT_COMPRESSION_NONE;
    t->key = (png_charp)key;
    t->text = (png_charp)value;
    t->text_length = strlen(value);
}

static void png_meta_fill(png_meta *m, const image_write_opts *o)
{
    time_t now = time(NULL);
    memset(m, 0, sizeof *m);
    png_meta_add(m, "Title", o->title);
    png_meta_add(m, "Software", o->software);
    png_meta_add(m, "Source", o->source);
    png_meta_add(m, "Comment", o->comment);
    if (o->render_s >= 0) {
        snprintf(m->render_time, sizeof m->render_time, "%.3f s", o->render_s);
        png_meta_add(m, "Render Time", m->render_time);
    }
    image_iso8601_utc(now, m->created, sizeof m->created);
    png_meta_add(m, "Creation Time", m->created);
    png_convert_from_time_t(&m->mtime, now);
}

/* Writes an 8-bit RGB PNG from `data` (h rows of 3*w bytes) to fp. */
static int png_write_rgb8(FILE *fp, const unsigned char *data, int w, int h, const png_meta *m,
                          image_png_errctx *e)
{
    png_structp png =
        png_create_write_struct(PNG_LIBPNG_VER_STRING, e, image_png_error_cb, image_png_warning_cb);
    png_infop info;
    if (!png) {
        snprintf(e->msg, sizeof e->msg, "cannot create libpng write struct");
        return -1;
    }
    info = png_create_info_struct(png);
    if (!info) {
        png_destroy_write_struct(&png, NULL);
        snprintf(e->msg, sizeof e->msg, "cannot create libpng info struct");
        return -1;
    }
    if (setjmp(png_jmpbuf(png))) {
        png_destroy_write_struct(&png, &info);
        return -1;
    }
    png_init_io(png, fp);
    png_set_IHDR(png, info, (png_uint_32)w, (png_uint_32)h, 8, PNG_COLOR_TYPE_RGB,
                 PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
    /* sRGB chunk plus the matching gAMA and cHRM for decoders that ignore sRGB. */
    png_set_sRGB_gAMA_and_cHRM(png, info, PNG_sRGB_INTENT_PERCEPTUAL);
    if (m->count > 0)
        png_set_text(png, info, m->text, m->count);
    png_set_tIME(png, info, &m->mtime);
    png_set_compression_level(png, 6);
    png_write_info(png, info);
    for (int y = 0; y < h; y++)
        png_write_row(png, data + (size_t)y * (size_t)w * 3);
    png_write_end(png, info);
    png_destroy_write_struct(&png, &info);
    return 0;
}

int image_png_write(const image *img, const char *path, const image_write_opts *o, char *err,
                    size_t errlen)
{
    size_t n;
    unsigned char *data;
    sys_tmpfile t;
    FILE *fp;
    image_png_errctx e;
    png_meta meta;
    int rc, werr;
    double scale = pow(2.0, o->exposure);

    if (image_check_writable(img, path, err, errlen) != 0)
        return -1;
    if ((uint64_t)img->width > 0x7fffffffu || (uint64_t)img->height > 0x7fffffffu) {
        image_set_err(err, errlen, "%s: image too large for PNG", path);
        return -1;
    }
    n = (size_t)img->width * (size_t)img->height * 3;
    data = malloc(n);
    if (!data) {
        image_set_err(err, errlen, "%s: out of memory", path);
        return -1;
    }
    for (size_t i = 0; i < n; i++)
        data[i] = to_srgb8(image_tonemap_value(img->rgb[i] * scale, o->tonemap));
    png_meta_fill(&meta, o);

    if (sys_tmp_open(&t, path, err, errlen) != 0) {
        free(data);
        return -1;
    }
    fp = fdopen(t.fd, "wb");
    if (!fp) {
        image_set_err(err, errlen, "%s: cannot open stream on %s: %s", path, t.tmp,
                      strerror(errno));
        free(data);
        sys_tmp_abort(&t);
        return -1;
    }
    memset(&e, 0, sizeof e);
    rc = png_write_rgb8(fp, data, img->width, img->height, &meta, &e);
    free(data);
    werr = 0;
    if (rc == 0 && fflush(fp) != 0)
        werr = errno ? errno : EIO;
    if (rc == 0 && !werr && ferror(fp))
        werr = EIO;
    if (rc == 0 && !werr && fsync(fileno(fp)) != 0 && errno != EINVAL && errno != EROFS)
        werr = errno;
    if (fclose(fp) != 0 && rc == 0 && !werr)
        werr = errno ? errno : EIO;
    t.fd = -1; /* closed by fclose */
    if (rc != 0) {
        image_set_err(err, errlen, "%s: PNG encoding failed: %s", path,
                      e.msg[0] ? e.msg : "libpng error");
        sys_tmp_abort(&t);
        return -1;
    }
    if (werr) {
        image_set_err(err, errlen, "%s: writing %s failed: %s", path, t.tmp, strerror(werr));
        sys_tmp_abort(&t);
        return -1;
    }
    return sys_tmp_commit(&t, path, err, errlen);
}

int image_write_png(const image *img, const char *path, char *err, size_t errlen)
{
    image_write_opts def;
    image_write_opts_default(&def);
    return image_png_write(img, path, &def, err, errlen);
}
