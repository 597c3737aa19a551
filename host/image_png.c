/* Writing PNG: 8- or 16-bit sRGB after exposure and tone map, with the metadata of
 * image_write_opts as text chunks and tIME (libpng), the pixels compressed in pieces on
 * several threads (zlib, par.c); and the libpng error handling that the reader
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
#include <zlib.h>

#include "image.h"
#include "config.h"
#include "image_internal.h"
#include "par.h"
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

/* libpng writes the chunks before the pixels (IHDR, gAMA, sRGB, cHRM, tIME, the text);
 * the pixels are compressed here, in pieces of whole rows on several threads (par.c), and
 * written as one IDAT chunk per piece in order, then IEND. Each piece is a raw deflate
 * stream of its own ended by a sync flush (the last by the final block), so the pieces
 * joined are one zlib stream: the header, the pieces, the Adler-32 of all the rows
 * (combined from the pieces'). Rows are not filtered (filter type 0 on every row).
 *
 * Measured on the seven SPD scenes at 512x512 (callgrind instructions per image; bytes
 * for all seven): libpng's adaptive filters at zlib level 6 (the writer before this one)
 * 156 M, 940 KB; no filter at level 2 36 M, 969 KB; level 1 saves 0.5% of the
 * instructions for 2% more bytes, level 3 costs 4% more for 2% fewer; the adaptive
 * filters at level 1 cost 107 M for 1054 KB (these images, flat areas and sharp edges,
 * compress better unfiltered). */
#define PNG_ZLIB_LEVEL 2

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

/* Writes the signature and the chunks before the pixels of an 8- or 16-bit RGB PNG to fp. */
static int png_write_head(FILE *fp, int w, int h, int bits, const png_meta *m, image_png_errctx *e)
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
    png_set_IHDR(png, info, (png_uint_32)w, (png_uint_32)h, bits, PNG_COLOR_TYPE_RGB,
                 PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
    /* sRGB chunk plus the matching gAMA and cHRM for decoders that ignore sRGB. */
    png_set_sRGB_gAMA_and_cHRM(png, info, PNG_sRGB_INTENT_PERCEPTUAL);
    if (m->count > 0)
        png_set_text(png, info, m->text, m->count);
    png_set_tIME(png, info, &m->mtime);
    png_write_info(png, info); /* everything set above goes before the pixels */
    png_destroy_write_struct(&png, &info);
    return 0;
}

/* A failure (on the thread that met it): PNG_ERR_*, the zlib code, the errno. */
#define PNG_ERR_MEMORY 1
#define PNG_ERR_ZLIB 2
#define PNG_ERR_WRITE 3
typedef struct {
    int kind, zerr, werr;
} png_err;

/* One thread's deflate stream, piece of filtered rows and failure; one slot's compressed
 * piece. */
typedef struct {
    z_stream z;
    int z_ready;
    unsigned char *rows;
    png_err err;
} png_thread;

typedef struct {
    unsigned char *out;
    size_t cap, len;  /* compressed bytes */
    uLong adler;      /* of the piece's filtered rows */
    size_t raw_bytes; /* filtered rows in the piece */
} png_slot;

/* The pixel compression of one image. */
typedef struct {
    const image *img;
    image_srgb8_table srgb;
    double scale;
    int tonemap;
    double exposure;
    int png16;        /* 16 bits per channel */
    size_t row_bytes; /* 1 + 3 * width (6 * width at 16 bits): the filter type byte and the
                       * pixels */
    int rows, pieces; /* rows per piece (the last may have fewer) */
    png_thread th[CW_MAX_WRITE_THREADS];
    png_slot *slot;
    int window;
    FILE *fp;
    uLong adler; /* of the rows emitted so far */
} png_pixels;

static int png_fail(png_err *e, int kind, int zerr)
{
    e->kind = kind;
    e->zerr = zerr;
    e->werr = kind == PNG_ERR_WRITE ? (errno ? errno : EIO) : 0;
    return kind;
}

/* n linear values to 16-bit sRGB, big-endian: exposure, tone map, the sRGB transfer,
 * rounded to the nearest of 65536 levels. */
static void png_encode16(const float *v, size_t n, double exposure, int tonemap, unsigned char *out)
{
    size_t i;
    for (i = 0; i < n; i++) {
        double e = image_srgb_encode(image_display_value(v[i], exposure, tonemap));
        unsigned q = (unsigned)(e * 65535.0 + 0.5);
        out[2 * i] = (unsigned char)(q >> 8);
        out[2 * i + 1] = (unsigned char)(q & 0xff);
    }
}

/* Compresses piece j: its rows in sRGB, filter type 0, deflated into slot j % window. */
static int png_piece_job(void *ctx, int j, int thread)
{
    png_pixels *p = ctx;
    png_thread *t = &p->th[thread];
    png_slot *sl = &p->slot[j % p->window];
    int y0 = j * p->rows, w = p->img->width, last = j == p->pieces - 1;
    int n = last ? p->img->height - y0 : p->rows, y, zr;
    size_t raw = (size_t)n * p->row_bytes, bound;

    if (!t->rows && !(t->rows = malloc((size_t)p->rows * p->row_bytes)))
        return png_fail(&t->err, PNG_ERR_MEMORY, 0);
    if (!t->z_ready) {
        /* raw deflate (no zlib header or trailer: those are written around the pieces) */
        zr = deflateInit2(&t->z, PNG_ZLIB_LEVEL, Z_DEFLATED, -15, 8, Z_DEFAULT_STRATEGY);
        if (zr != Z_OK)
            return png_fail(&t->err, zr == Z_MEM_ERROR ? PNG_ERR_MEMORY : PNG_ERR_ZLIB, zr);
        t->z_ready = 1;
    } else if ((zr = deflateReset(&t->z)) != Z_OK) {
        return png_fail(&t->err, PNG_ERR_ZLIB, zr);
    }
    for (y = 0; y < n; y++) {
        unsigned char *row = t->rows + (size_t)y * p->row_bytes;
        row[0] = 0; /* filter type None */
        if (p->png16)
            png_encode16(p->img->rgb + (size_t)(y0 + y) * (size_t)w * 3, (size_t)w * 3, p->exposure,
                         p->tonemap, row + 1);
        else
            image_srgb8_encode(&p->srgb, p->img->rgb + (size_t)(y0 + y) * (size_t)w * 3,
                               (size_t)w * 3, p->scale, p->tonemap, row + 1);
    }
    /* deflateBound covers a whole stream; a sync flush adds at most an empty stored block */
    bound = deflateBound(&t->z, (uLong)raw) + 16;
    if (sl->cap < bound) {
        free(sl->out);
        sl->cap = 0;
        if (!(sl->out = malloc(bound)))
            return png_fail(&t->err, PNG_ERR_MEMORY, 0);
        sl->cap = bound;
    }
    t->z.next_in = t->rows;
    t->z.avail_in = (uInt)raw;
    t->z.next_out = sl->out;
    t->z.avail_out = (uInt)sl->cap;
    zr = deflate(&t->z, last ? Z_FINISH : Z_SYNC_FLUSH);
    if ((last ? zr != Z_STREAM_END : zr != Z_OK) || t->z.avail_in != 0 || t->z.avail_out == 0)
        return png_fail(&t->err, PNG_ERR_ZLIB, zr);
    sl->len = sl->cap - t->z.avail_out;
    sl->adler = adler32(adler32(0L, Z_NULL, 0), t->rows, (uInt)raw);
    sl->raw_bytes = raw;
    return 0;
}

static void put_be32(unsigned char *b, uLong v)
{
    b[0] = (unsigned char)(v >> 24);
    b[1] = (unsigned char)(v >> 16);
    b[2] = (unsigned char)(v >> 8);
    b[3] = (unsigned char)v;
}

/* Writes one chunk: its type, then the parts of its data in order (NULL parts skipped). */
static int png_put_chunk(png_pixels *p, const char *type, const unsigned char *const *part,
                         const size_t *len, int nparts)
{
    unsigned char head[8], tail[4];
    size_t total = 0;
    uLong crc = crc32(0L, Z_NULL, 0);
    int i;
    for (i = 0; i < nparts; i++)
        total += part[i] ? len[i] : 0;
    put_be32(head, (uLong)total);
    memcpy(head + 4, type, 4);
    crc = crc32(crc, head + 4, 4);
    for (i = 0; i < nparts; i++)
        if (part[i])
            crc = crc32(crc, part[i], (uInt)len[i]);
    put_be32(tail, crc);
    if (fwrite(head, 1, 8, p->fp) != 8)
        goto fail;
    for (i = 0; i < nparts; i++)
        if (part[i] && len[i] && fwrite(part[i], 1, len[i], p->fp) != len[i])
            goto fail;
    if (fwrite(tail, 1, 4, p->fp) != 4)
        goto fail;
    return 0;
fail: /* on the calling thread, thread 0 */
    return png_fail(&p->th[0].err, PNG_ERR_WRITE, 0);
}

/* Writes piece j as an IDAT chunk: the zlib header before the first piece, the Adler-32 of
 * all the rows after the last. */
static int png_piece_emit(void *ctx, int j)
{
    png_pixels *p = ctx;
    png_slot *sl = &p->slot[j % p->window];
    /* CMF: deflate, 32 KiB window; FLG: level class 1 ("fast", levels 2 to 5), FCHECK */
    static const unsigned char zhead[2] = {0x78, 0x5e};
    unsigned char ztail[4];
    const unsigned char *part[3];
    size_t len[3] = {2, 0, 4};
    int last = j == p->pieces - 1;
    p->adler = j == 0 ? sl->adler : adler32_combine(p->adler, sl->adler, (z_off_t)sl->raw_bytes);
    put_be32(ztail, p->adler);
    part[0] = j == 0 ? zhead : NULL;
    part[1] = sl->out;
    len[1] = sl->len;
    part[2] = last ? ztail : NULL;
    return png_put_chunk(p, "IDAT", part, len, 3);
}

/* Compresses and writes the pixels to fp (the temporary file tmp), then IEND. Returns 0,
 * or -1 with err. */
static int png_write_pixels(const image *img, const image_write_opts *o, FILE *fp, const char *path,
                            const char *tmp, char *err, size_t errlen)
{
    png_pixels p;
    png_err e = {0, 0, 0};
    int threads, i, rc;
    size_t rows;

    memset(&p, 0, sizeof p);
    image_srgb8_table_init(&p.srgb);
    p.img = img;
    p.scale = pow(2.0, o->exposure);
    p.tonemap = o->tonemap;
    p.exposure = o->exposure;
    p.png16 = o->png16 != 0;
    p.fp = fp;
    p.row_bytes = 1 + (size_t)img->width * (p.png16 ? 6 : 3);
    rows = CW_PNG_PIECE_BYTES / p.row_bytes;
    p.rows = rows < 1 ? 1 : rows > (size_t)img->height ? img->height : (int)rows;
    p.pieces = (img->height - 1) / p.rows + 1;
    threads = image_write_threads();
    p.window = 2 * threads;
    if (!(p.slot = calloc((size_t)p.window, sizeof *p.slot))) {
        image_set_err(err, errlen, "%s: out of memory", path);
        return -1;
    }
    rc = par_ordered(p.pieces, threads, p.window, png_piece_job, png_piece_emit, &p);
    if (rc == 0) {
        const unsigned char *none[1] = {NULL};
        size_t zero[1] = {0};
        rc = png_put_chunk(&p, "IEND", none, zero, 0);
    }
    for (i = 0; i < CW_MAX_WRITE_THREADS; i++) {
        if (p.th[i].z_ready)
            deflateEnd(&p.th[i].z);
        free(p.th[i].rows);
    }
    for (i = 0; i < p.window; i++)
        free(p.slot[i].out);
    free(p.slot);
    if (rc == 0)
        return 0;
    for (i = 0; i < CW_MAX_WRITE_THREADS && !e.kind; i++)
        e = p.th[i].err;
    if (e.kind == PNG_ERR_MEMORY)
        image_set_err(err, errlen, "%s: out of memory", path);
    else if (e.kind == PNG_ERR_ZLIB)
        image_set_err(err, errlen, "%s: PNG encoding failed: zlib error %d", path, e.zerr);
    else
        image_set_err(err, errlen, "%s: writing %s failed: %s", path, tmp, strerror(e.werr));
    return -1;
}

int image_png_write(const image *img, const char *path, const image_write_opts *o, char *err,
                    size_t errlen)
{
    sys_tmpfile t;
    FILE *fp;
    image_png_errctx e;
    png_meta meta;
    int rc, werr;

    if (image_check_writable(img, path, err, errlen) != 0)
        return -1;
    if ((uint64_t)img->width > 0x7fffffffu || (uint64_t)img->height > 0x7fffffffu) {
        image_set_err(err, errlen, "%s: image too large for PNG", path);
        return -1;
    }
    png_meta_fill(&meta, o);

    if (sys_tmp_open(&t, path, err, errlen) != 0)
        return -1;
    fp = fdopen(t.fd, "wb");
    if (!fp) {
        image_set_err(err, errlen, "%s: cannot open stream on %s: %s", path, t.tmp,
                      strerror(errno));
        sys_tmp_abort(&t);
        return -1;
    }
    memset(&e, 0, sizeof e);
    errno = 0;
    rc = png_write_head(fp, img->width, img->height, o->png16 ? 16 : 8, &meta, &e);
    if (rc != 0) {
        int why = ferror(fp) ? (errno ? errno : EIO) : 0; /* libpng says only "Write Error" */
        image_set_err(err, errlen, "%s: PNG encoding failed: %s%s%s", path,
                      e.msg[0] ? e.msg : "libpng error", why ? ": " : "", why ? strerror(why) : "");
    } else
        rc = png_write_pixels(img, o, fp, path, t.tmp, err, errlen);
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
