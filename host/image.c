/* Images: linear float RGB in memory; OpenEXR (OpenEXRCore C API) and PNG (libpng) I/O,
 * comparison and diff images. See image.h. */
#include "image.h"

#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <math.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/types.h>
#include <time.h>
#include <unistd.h>

#include <openexr.h>
#include <png.h>

/* ------------------------------------------------------------------------------------ */
/* Small helpers                                                                         */

static void set_err(char *err, size_t errlen, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;

static void set_err(char *err, size_t errlen, const char *fmt, ...)
{
    va_list ap;
    if (!err || errlen == 0)
        return;
    va_start(ap, fmt);
    vsnprintf(err, errlen, fmt, ap);
    va_end(ap);
}

/* Rejects images that cannot be written or whose size overflows. */
static int check_image(const image *img, const char *path, char *err, size_t errlen)
{
    if (!path || !*path) {
        set_err(err, errlen, "image: no output path given");
        return -1;
    }
    if (!img || !img->rgb || img->width <= 0 || img->height <= 0) {
        set_err(err, errlen, "%s: no image data to write", path);
        return -1;
    }
    if ((size_t)img->width > SIZE_MAX / 3 / sizeof(float) / (size_t)img->height) {
        set_err(err, errlen, "%s: image size %dx%d too large", path, img->width, img->height);
        return -1;
    }
    return 0;
}

/* Case-insensitive check that the file name (after the last '/') ends in `ext` (".exr"). */
static int has_ext(const char *path, const char *ext)
{
    const char *base = strrchr(path, '/');
    const char *dot;
    base = base ? base + 1 : path;
    dot = strrchr(base, '.');
    if (!dot || dot == base)
        return 0;
    for (; *dot && *ext; dot++, ext++) {
        char c = *dot;
        if (c >= 'A' && c <= 'Z')
            c = (char)(c - 'A' + 'a');
        if (c != *ext)
            return 0;
    }
    return *dot == '\0' && *ext == '\0';
}

/* ------------------------------------------------------------------------------------ */
/* Options, tone mapping, metadata times                                                 */

void image_write_opts_default(image_write_opts *o)
{
    memset(o, 0, sizeof *o);
    o->exposure = 0.0;
    o->tonemap = IMAGE_TONEMAP_CLAMP;
    o->render_s = -1.0;
}

int image_tonemap_parse(const char *name)
{
    if (strcmp(name, "clamp") == 0)
        return IMAGE_TONEMAP_CLAMP;
    if (strcmp(name, "reinhard") == 0)
        return IMAGE_TONEMAP_REINHARD;
    if (strcmp(name, "aces") == 0)
        return IMAGE_TONEMAP_ACES;
    return -1;
}

const char *image_tonemap_name(int tonemap)
{
    switch (tonemap) {
    case IMAGE_TONEMAP_REINHARD:
        return "reinhard";
    case IMAGE_TONEMAP_ACES:
        return "aces";
    default:
        return "clamp";
    }
}

/* Tone maps an exposed linear value to [0,1]; NaN and non-positive values give 0. */
static double tonemap_value(double x, int tonemap)
{
    if (!(x > 0.0))
        return 0.0;
    if (x > 1e100) /* also +inf: every curve is at (or clamped to) 1 there */
        return 1.0;
    if (tonemap == IMAGE_TONEMAP_REINHARD)
        x = x / (1.0 + x);
    else if (tonemap == IMAGE_TONEMAP_ACES)
        x = x * (2.51 * x + 0.03) / (x * (2.43 * x + 0.59) + 0.14);
    return x > 1.0 ? 1.0 : x;
}

double image_display_value(double linear, double exposure, int tonemap)
{
    return tonemap_value(linear * pow(2.0, exposure), tonemap);
}

const char *image_library_versions(void)
{
    static char buf[128];
    int maj = 0, min = 0, patch = 0;
    const char *extra = NULL;
    exr_get_library_version(&maj, &min, &patch, &extra);
    snprintf(buf, sizeof buf, "libpng %s, OpenEXR %d.%d.%d%s", png_get_libpng_ver(NULL), maj, min,
             patch, extra ? extra : "");
    return buf;
}

static const image_write_opts *opts_or_default(const image_write_opts *o, image_write_opts *def)
{
    if (o)
        return o;
    image_write_opts_default(def);
    return def;
}

/* ------------------------------------------------------------------------------------ */
/* Temporary file beside the destination, renamed over it on success                     */

typedef struct {
    char *tmp; /* "path.tmp-XXXXXX" */
    int fd;
} tmpfile_t;

static int tmp_open(tmpfile_t *t, const char *path, char *err, size_t errlen)
{
    size_t n = strlen(path);
    mode_t um;
    t->fd = -1;
    t->tmp = malloc(n + sizeof(".tmp-XXXXXX"));
    if (!t->tmp) {
        set_err(err, errlen, "%s: out of memory", path);
        return -1;
    }
    memcpy(t->tmp, path, n);
    memcpy(t->tmp + n, ".tmp-XXXXXX", sizeof(".tmp-XXXXXX"));
    t->fd = mkstemp(t->tmp);
    if (t->fd < 0) {
        set_err(err, errlen, "%s: cannot create temporary file %s: %s", path, t->tmp,
                strerror(errno));
        free(t->tmp);
        t->tmp = NULL;
        return -1;
    }
    /* mkstemp creates the file 0600; give the image the usual 0666 & ~umask. */
    um = umask(022);
    umask(um);
    (void)fchmod(t->fd, (mode_t)(0666 & ~um));
    return 0;
}

/* Removes the temporary file (failure path). Closes the descriptor if still open. */
static void tmp_abort(tmpfile_t *t)
{
    if (t->fd >= 0)
        close(t->fd);
    t->fd = -1;
    if (t->tmp) {
        unlink(t->tmp);
        free(t->tmp);
        t->tmp = NULL;
    }
}

/* Flushes the descriptor to disk, closes it (unless already closed, fd < 0) and renames
 * the temporary file over path. On failure the temporary file is removed. */
static int tmp_commit(tmpfile_t *t, const char *path, char *err, size_t errlen)
{
    if (t->fd >= 0) {
        int fd = t->fd;
        t->fd = -1;
        if (fsync(fd) != 0 && errno != EINVAL && errno != EROFS) {
            set_err(err, errlen, "%s: cannot flush %s: %s", path, t->tmp, strerror(errno));
            close(fd);
            tmp_abort(t);
            return -1;
        }
        if (close(fd) != 0) {
            set_err(err, errlen, "%s: cannot close %s: %s", path, t->tmp, strerror(errno));
            tmp_abort(t);
            return -1;
        }
    }
    if (rename(t->tmp, path) != 0) {
        set_err(err, errlen, "%s: cannot rename %s over it: %s", path, t->tmp, strerror(errno));
        tmp_abort(t);
        return -1;
    }
    free(t->tmp);
    t->tmp = NULL;
    return 0;
}

/* ------------------------------------------------------------------------------------ */
/* Allocation                                                                            */

int image_alloc(image *img, int width, int height)
{
    if (!img)
        return -1;
    img->width = img->height = 0;
    img->rgb = NULL;
    if (width <= 0 || height <= 0 || (size_t)width > SIZE_MAX / 3 / sizeof(float) / (size_t)height)
        return -1;
    img->rgb = calloc((size_t)width * (size_t)height * 3, sizeof(float));
    if (!img->rgb)
        return -1;
    img->width = width;
    img->height = height;
    return 0;
}

void image_free(image *img)
{
    if (!img)
        return;
    free(img->rgb);
    img->rgb = NULL;
    img->width = img->height = 0;
}

/* ------------------------------------------------------------------------------------ */
/* OpenEXR (OpenEXRCore)                                                                 */

/* Per-context state: the last message OpenEXRCore reported, and (for writing) our own
 * output stream on the temporary file's descriptor, so that every write error is ours to
 * see and the library never opens or unlinks files itself. */
typedef struct {
    char msg[512];
    int fd;
    int write_errno;
} exr_state;

static void exr_error_cb(exr_const_context_t ctxt, exr_result_t code, const char *msg)
{
    void *ud = NULL;
    exr_state *st;
    if (!ctxt || exr_get_user_data(ctxt, &ud) != EXR_ERR_SUCCESS || !ud)
        return; /* no context: nowhere to store it; the code is still returned */
    st = ud;
    snprintf(st->msg, sizeof st->msg, "%s", msg ? msg : exr_get_default_error_message(code));
}

static int64_t exr_stream_write(exr_const_context_t ctxt, void *userdata, const void *buffer,
                                uint64_t sz, uint64_t offset, exr_stream_error_func_ptr_t error_cb)
{
    exr_state *st = userdata;
    const unsigned char *p = buffer;
    uint64_t left = sz;
    (void)ctxt;
    (void)error_cb;
    while (left > 0) {
        size_t chunk = left > (uint64_t)(SIZE_MAX / 2) ? SIZE_MAX / 2 : (size_t)left;
        ssize_t n;
        if (offset > (uint64_t)INT64_MAX) {
            st->write_errno = EFBIG;
            return -1;
        }
        n = pwrite(st->fd, p, chunk, (off_t)offset);
        if (n < 0) {
            if (errno == EINTR)
                continue;
            st->write_errno = errno;
            return -1;
        }
        if (n == 0) {
            st->write_errno = EIO;
            return -1;
        }
        p += n;
        left -= (uint64_t)n;
        offset += (uint64_t)n;
    }
    return (int64_t)sz;
}

static void exr_stream_destroy(exr_const_context_t ctxt, void *userdata, int failed)
{
    /* The descriptor belongs to the caller, who closes it and removes the file on failure. */
    (void)ctxt;
    (void)userdata;
    (void)failed;
}

/* Formats "path: what failed: CODE (message)" for an OpenEXRCore result. */
static void exr_fail(char *err, size_t errlen, const char *path, const char *what, exr_result_t rv,
                     const exr_state *st)
{
    const char *detail = st && st->msg[0] ? st->msg : exr_get_default_error_message(rv);
    if (st && st->write_errno)
        set_err(err, errlen, "%s: %s failed: %s (%s; write error: %s)", path, what,
                exr_get_error_code_as_string(rv), detail, strerror(st->write_errno));
    else
        set_err(err, errlen, "%s: %s failed: %s (%s)", path, what, exr_get_error_code_as_string(rv),
                detail);
}

/* Checks the result of an OpenEXRCore call: on failure names the step in *what and
 * returns 1; on success clears the stored library message, so that a later failure's
 * message is its own. */
static int exr_failed(exr_state *st, exr_result_t rv, const char *desc, const char **what)
{
    if (rv != EXR_ERR_SUCCESS) {
        *what = desc;
        return 1;
    }
    st->msg[0] = '\0';
    return 0;
}

/* IEEE 754 binary32 -> binary16, rounding to nearest even; overflow gives infinity, NaN
 * stays NaN. */
static uint16_t float_to_half(float f)
{
    uint32_t x, sign, mant, h, rem, halfway;
    int e, shift;
    memcpy(&x, &f, sizeof x);
    sign = (x >> 16) & 0x8000u;
    mant = x & 0x7fffffu;
    e = (int)((x >> 23) & 0xffu);
    if (e == 0xff) /* infinity or NaN (kept quiet and non-zero) */
        return (uint16_t)(sign | 0x7c00u | (mant ? 0x200u | (mant >> 13) : 0u));
    e = e - 127 + 15;
    if (e >= 31)
        return (uint16_t)(sign | 0x7c00u);
    if (e <= 0) { /* a half subnormal, or zero */
        if (e < -10)
            return (uint16_t)sign;
        mant |= 0x800000u;
        shift = 14 - e;
        h = mant >> shift;
        rem = mant & ((1u << shift) - 1u);
        halfway = 1u << (shift - 1);
    } else {
        h = ((uint32_t)e << 10) | (mant >> 13);
        rem = mant & 0x1fffu;
        halfway = 0x1000u;
    }
    if (rem > halfway || (rem == halfway && (h & 1u)))
        h++; /* a carry into the exponent is right, up to infinity */
    return (uint16_t)(sign | h);
}

/* Local time as "YYYY:MM:DD hh:mm:ss" (the EXR capDate form) or ISO 8601 UTC, and UTC
 * minus local time in seconds (the EXR utcOffset). */
static void exr_cap_date(time_t t, char *buf, size_t n, float *utc_offset)
{
    struct tm local, utc;
    time_t as_local;
    buf[0] = '\0';
    *utc_offset = 0.0f;
    if (!localtime_r(&t, &local) || !gmtime_r(&t, &utc))
        return;
    strftime(buf, n, "%Y:%m:%d %H:%M:%S", &local);
    utc.tm_isdst = -1;
    as_local = mktime(&utc); /* the UTC wall time read as local time */
    if (as_local != (time_t)-1)
        *utc_offset = (float)difftime(as_local, t);
}

static void iso8601_utc(time_t t, char *buf, size_t n)
{
    struct tm utc;
    buf[0] = '\0';
    if (gmtime_r(&t, &utc))
        strftime(buf, n, "%Y-%m-%dT%H:%M:%SZ", &utc);
}

/* Sets the metadata attributes of part 0 (before the header is written). */
static exr_result_t exr_set_meta(exr_context_t ctx, const image_write_opts *o, const char **what)
{
    const struct {
        const char *name, *value;
    } strs[] = {{"scene", o->title},
                {"software", o->software},
                {"device", o->source},
                {"comments", o->comment}};
    char date[32];
    float utc_offset;
    exr_result_t rv;
    for (size_t i = 0; i < sizeof strs / sizeof strs[0]; i++) {
        if (!strs[i].value)
            continue;
        rv = exr_attr_set_string(ctx, 0, strs[i].name, strs[i].value);
        if (rv != EXR_ERR_SUCCESS) {
            *what = "exr_attr_set_string";
            return rv;
        }
    }
    if (o->render_s >= 0) {
        rv = exr_attr_set_float(ctx, 0, "renderTime", (float)o->render_s);
        if (rv != EXR_ERR_SUCCESS) {
            *what = "exr_attr_set_float(renderTime)";
            return rv;
        }
    }
    exr_cap_date(time(NULL), date, sizeof date, &utc_offset);
    if (date[0]) {
        rv = exr_attr_set_string(ctx, 0, "capDate", date);
        if (rv == EXR_ERR_SUCCESS)
            rv = exr_attr_set_float(ctx, 0, "utcOffset", utc_offset);
        if (rv != EXR_ERR_SUCCESS) {
            *what = "exr_attr_set (capDate, utcOffset)";
            return rv;
        }
    }
    return EXR_ERR_SUCCESS;
}

static int write_exr(const image *img, const char *path, const image_write_opts *o, char *err,
                     size_t errlen)
{
    static const char *const names[3] = {"R", "G", "B"};
    exr_state st;
    exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
    exr_context_t ctx = NULL;
    exr_encode_pipeline_t enc = EXR_ENCODE_PIPELINE_INITIALIZER;
    int enc_init = 0;
    tmpfile_t t;
    exr_result_t rv;
    const char *what = NULL;
    int part = 0;
    int32_t lines = 0, chunks = 0;
    size_t w, line_bytes, elem = o->half ? sizeof(uint16_t) : sizeof(float);
    uint16_t *halves = NULL; /* the pixels as half floats, when o->half */
    const unsigned char *pixels = (const unsigned char *)img->rgb;

    if (check_image(img, path, err, errlen) != 0)
        return -1;
    if (img->width > INT32_MAX / 12) { /* user_line_stride is an int32 */
        set_err(err, errlen, "%s: image too wide for EXR output (%d)", path, img->width);
        return -1;
    }
    w = (size_t)img->width;
    line_bytes = w * 3 * elem;
    if (o->half) {
        size_t n = w * (size_t)img->height * 3;
        halves = malloc(n * sizeof *halves);
        if (!halves) {
            set_err(err, errlen, "%s: out of memory", path);
            return -1;
        }
        for (size_t i = 0; i < n; i++)
            halves[i] = float_to_half(img->rgb[i]);
        pixels = (const unsigned char *)halves;
    }
    if (tmp_open(&t, path, err, errlen) != 0) {
        free(halves);
        return -1;
    }

    memset(&st, 0, sizeof st);
    st.fd = t.fd;
    init.error_handler_fn = exr_error_cb;
    init.user_data = &st;
    init.write_fn = exr_stream_write;
    init.destroy_fn = exr_stream_destroy;

    if (exr_failed(&st, (rv = exr_start_write(&ctx, t.tmp, EXR_WRITE_FILE_DIRECTLY, &init)),
                   "exr_start_write", &what))
        goto fail;
    if (exr_failed(&st, (rv = exr_add_part(ctx, NULL, EXR_STORAGE_SCANLINE, &part)), "exr_add_part",
                   &what))
        goto fail;
    /* Sets data and display windows to (0,0)-(w-1,h-1), pixel aspect 1, screen window,
     * increasing line order and the compression. */
    if (exr_failed(&st,
                   (rv = exr_initialize_required_attr_simple(ctx, part, img->width, img->height,
                                                             EXR_COMPRESSION_ZIP)),
                   "exr_initialize_required_attr_simple", &what))
        goto fail;
    /* zlib level 1: a few percent bigger than the default level, several times faster */
    if (exr_failed(&st, (rv = exr_set_zip_compression_level(ctx, part, 1)),
                   "exr_set_zip_compression_level", &what))
        goto fail;
    for (int c = 0; c < 3; c++)
        if (exr_failed(&st,
                       (rv = exr_add_channel(ctx, part, names[c],
                                             o->half ? EXR_PIXEL_HALF : EXR_PIXEL_FLOAT,
                                             EXR_PERCEPTUALLY_LOGARITHMIC, 1, 1)),
                       "exr_add_channel", &what))
            goto fail;
    rv = exr_set_meta(ctx, o, &what); /* names the failed step in what */
    if (rv != EXR_ERR_SUCCESS)
        goto fail;
    st.msg[0] = '\0';
    if (exr_failed(&st, (rv = exr_write_header(ctx)), "exr_write_header", &what))
        goto fail;
    if (exr_failed(&st, (rv = exr_get_scanlines_per_chunk(ctx, part, &lines)),
                   "exr_get_scanlines_per_chunk", &what))
        goto fail;
    if (exr_failed(&st, (rv = exr_get_chunk_count(ctx, part, &chunks)), "exr_get_chunk_count",
                   &what))
        goto fail;
    if (lines <= 0 || chunks <= 0 || (int64_t)lines * chunks < img->height) {
        set_err(err, errlen, "%s: unexpected EXR chunk layout (%d chunks of %d lines)", path,
                (int)chunks, (int)lines);
        goto fail_quiet;
    }

    for (int32_t ci = 0; ci < chunks; ci++) {
        exr_chunk_info_t cinfo;
        int y = ci * lines;
        const unsigned char *row = pixels + (size_t)y * line_bytes;
        if (exr_failed(&st, (rv = exr_write_scanline_chunk_info(ctx, part, y, &cinfo)),
                       "exr_write_scanline_chunk_info", &what))
            goto fail;
        if (!enc_init) {
            if (exr_failed(&st, (rv = exr_encoding_initialize(ctx, part, &cinfo, &enc)),
                           "exr_encoding_initialize", &what))
                goto fail;
            enc_init = 1;
        } else {
            if (exr_failed(&st, (rv = exr_encoding_update(ctx, part, &cinfo, &enc)),
                           "exr_encoding_update", &what))
                goto fail;
        }
        /* The pipeline's channels are in file order (alphabetical: B, G, R); match by name
         * rather than by position. */
        for (int c = 0; c < enc.channel_count; c++) {
            exr_coding_channel_info_t *ch = &enc.channels[c];
            int comp = -1;
            for (int k = 0; k < 3; k++)
                if (ch->channel_name && strcmp(ch->channel_name, names[k]) == 0)
                    comp = k;
            if (comp < 0) {
                set_err(err, errlen, "%s: unexpected channel '%s' in EXR encoder", path,
                        ch->channel_name ? ch->channel_name : "?");
                goto fail_quiet;
            }
            ch->user_bytes_per_element = (int16_t)elem;
            ch->user_data_type = o->half ? EXR_PIXEL_HALF : EXR_PIXEL_FLOAT;
            ch->user_pixel_stride = (int32_t)(3 * elem);
            ch->user_line_stride = (int32_t)line_bytes;
            ch->encode_from_ptr = row + (size_t)comp * elem;
        }
        if (ci == 0)
            if (exr_failed(&st, (rv = exr_encoding_choose_default_routines(ctx, part, &enc)),
                           "exr_encoding_choose_default_routines", &what))
                goto fail;
        if (exr_failed(&st, (rv = exr_encoding_run(ctx, part, &enc)), "exr_encoding_run", &what))
            goto fail;
    }
    enc_init = 0;
    if (exr_failed(&st, (rv = exr_encoding_destroy(ctx, &enc)), "exr_encoding_destroy", &what))
        goto fail;
    /* exr_finish writes the chunk offset table; it must succeed for a valid file. */
    st.msg[0] = '\0';
    rv = exr_finish(&ctx);
    if (rv != EXR_ERR_SUCCESS || st.write_errno) {
        what = "exr_finish";
        if (rv == EXR_ERR_SUCCESS)
            rv = EXR_ERR_WRITE_IO;
        goto fail;
    }
    free(halves);
    return tmp_commit(&t, path, err, errlen);

fail:
    exr_fail(err, errlen, path, what, rv, &st);
fail_quiet:
    if (enc_init)
        exr_encoding_destroy(ctx, &enc);
    if (ctx)
        exr_finish(&ctx);
    tmp_abort(&t);
    free(halves);
    return -1;
}

int image_write_exr(const image *img, const char *path, char *err, size_t errlen)
{
    image_write_opts def;
    image_write_opts_default(&def);
    return write_exr(img, path, &def, err, errlen);
}

/* Reads R, G, B (or Y, as grey) from part 0 of a scanline or tiled EXR. The result covers
 * the display window; data outside it is dropped, display pixels without data are 0. */

typedef struct {
    exr_context_t ctx;
    int part;
    int comp_of[3]; /* file channel index decoded into slot 0, 1, 2 (-1: none) */
    int grey;       /* only a Y channel, decoded into slot 0 and replicated */
    exr_attr_box2i_t dw, disp;
    float *scratch; /* one chunk, 3 floats per pixel */
    size_t scratch_pixels;
    exr_decode_pipeline_t dec;
    int dec_init;
    image *out;
    exr_state *st; /* its message is cleared before each call, so it belongs to the failure */
} exr_reader;

/* Decodes one chunk (whose pixels start at data-window coordinates x0, y0) into the
 * scratch buffer and copies the part inside the display window into the output image. */
static exr_result_t exr_read_chunk_into(exr_reader *r, const exr_chunk_info_t *cinfo, int x0,
                                        int y0, const char **what)
{
    exr_result_t rv;
    int cw = cinfo->width, chh = cinfo->height;

    if (cw <= 0 || chh <= 0)
        return EXR_ERR_SUCCESS;
    if ((size_t)cw * (size_t)chh > r->scratch_pixels) {
        *what = "chunk size check";
        return EXR_ERR_CORRUPT_CHUNK;
    }
    r->st->msg[0] = '\0';
    if (!r->dec_init) {
        rv = exr_decoding_initialize(r->ctx, r->part, cinfo, &r->dec);
        if (rv != EXR_ERR_SUCCESS) {
            *what = "exr_decoding_initialize";
            return rv;
        }
        r->dec_init = 1;
    } else {
        rv = exr_decoding_update(r->ctx, r->part, cinfo, &r->dec);
        if (rv != EXR_ERR_SUCCESS) {
            *what = "exr_decoding_update";
            return rv;
        }
    }
    for (int c = 0; c < r->dec.channel_count; c++) {
        exr_coding_channel_info_t *ch = &r->dec.channels[c];
        int slot = -1;
        for (int k = 0; k < 3; k++)
            if (r->comp_of[k] == c) {
                slot = k;
                break;
            }
        if (slot < 0) {
            ch->decode_to_ptr = NULL; /* not wanted: skipped by the decoder */
            continue;
        }
        ch->user_bytes_per_element = (int16_t)sizeof(float);
        ch->user_data_type = EXR_PIXEL_FLOAT;
        ch->user_pixel_stride = (int32_t)(3 * sizeof(float));
        ch->user_line_stride = (int32_t)((size_t)cw * 3 * sizeof(float));
        ch->decode_to_ptr = (uint8_t *)(r->scratch + slot);
    }
    /* Chosen per chunk: the routines depend on the chunk (e.g. its compression state). */
    r->st->msg[0] = '\0';
    rv = exr_decoding_choose_default_routines(r->ctx, r->part, &r->dec);
    if (rv != EXR_ERR_SUCCESS) {
        *what = "exr_decoding_choose_default_routines";
        return rv;
    }
    r->st->msg[0] = '\0';
    rv = exr_decoding_run(r->ctx, r->part, &r->dec);
    if (rv != EXR_ERR_SUCCESS) {
        *what = "exr_decoding_run";
        return rv;
    }

    /* Grey files decode Y into slot 0 only; replicate it. */
    int grey = r->grey;
    for (int j = 0; j < chh; j++) {
        int64_t py = (int64_t)y0 + j - r->disp.min.y;
        if (py < 0 || py >= r->out->height)
            continue;
        for (int i = 0; i < cw; i++) {
            int64_t px = (int64_t)x0 + i - r->disp.min.x;
            const float *s;
            float *d;
            if (px < 0 || px >= r->out->width)
                continue;
            s = r->scratch + ((size_t)j * (size_t)cw + (size_t)i) * 3;
            d = r->out->rgb + ((size_t)py * (size_t)r->out->width + (size_t)px) * 3;
            d[0] = s[0];
            d[1] = grey ? s[0] : s[1];
            d[2] = grey ? s[0] : s[2];
        }
    }
    return EXR_ERR_SUCCESS;
}

int image_read_exr(const char *path, image *img, char *err, size_t errlen)
{
    exr_state st;
    exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
    exr_reader r;
    exr_result_t rv = EXR_ERR_SUCCESS;
    const char *what = NULL;
    exr_storage_t storage;
    const exr_attr_chlist_t *chl = NULL;
    int nparts = 0, idx_y = -1;
    int64_t dw_w, dw_h, out_w, out_h;

    if (img) {
        img->width = img->height = 0;
        img->rgb = NULL;
    }
    if (!path || !img) {
        set_err(err, errlen, "image_read_exr: no path or image given");
        return -1;
    }
    memset(&st, 0, sizeof st);
    memset(&r, 0, sizeof r);
    r.out = img;
    r.st = &st;
    st.fd = -1;
    init.error_handler_fn = exr_error_cb;
    init.user_data = &st;

    if (exr_failed(r.st, (rv = exr_start_read(&r.ctx, path, &init)),
                   "opening the EXR file (exr_start_read)", &what))
        goto fail;
    if (exr_failed(r.st, (rv = exr_get_count(r.ctx, &nparts)), "exr_get_count", &what))
        goto fail;
    if (nparts < 1) {
        set_err(err, errlen, "%s: EXR file has no parts", path);
        goto fail_quiet;
    }
    if (exr_failed(r.st, (rv = exr_get_storage(r.ctx, r.part, &storage)), "exr_get_storage", &what))
        goto fail;
    if (storage != EXR_STORAGE_SCANLINE && storage != EXR_STORAGE_TILED) {
        set_err(err, errlen, "%s: deep EXR images are not supported", path);
        goto fail_quiet;
    }
    if (exr_failed(r.st, (rv = exr_get_data_window(r.ctx, r.part, &r.dw)), "exr_get_data_window",
                   &what))
        goto fail;
    if (exr_failed(r.st, (rv = exr_get_display_window(r.ctx, r.part, &r.disp)),
                   "exr_get_display_window", &what))
        goto fail;
    if (exr_failed(r.st, (rv = exr_get_channels(r.ctx, r.part, &chl)), "exr_get_channels", &what))
        goto fail;

    dw_w = (int64_t)r.dw.max.x - r.dw.min.x + 1;
    dw_h = (int64_t)r.dw.max.y - r.dw.min.y + 1;
    out_w = (int64_t)r.disp.max.x - r.disp.min.x + 1;
    out_h = (int64_t)r.disp.max.y - r.disp.min.y + 1;
    if (dw_w <= 0 || dw_h <= 0 || out_w <= 0 || out_h <= 0 || out_w > INT_MAX || out_h > INT_MAX) {
        set_err(err, errlen, "%s: invalid EXR data or display window", path);
        goto fail_quiet;
    }

    /* Find R, G, B (or Y), half or float, not subsampled. */
    r.comp_of[0] = r.comp_of[1] = r.comp_of[2] = -1;
    for (int c = 0; chl && c < chl->num_channels; c++) {
        const exr_attr_chlist_entry_t *e = &chl->entries[c];
        const char *n = e->name.str;
        int slot = -1;
        if (!n)
            continue;
        if (strcmp(n, "R") == 0)
            slot = 0;
        else if (strcmp(n, "G") == 0)
            slot = 1;
        else if (strcmp(n, "B") == 0)
            slot = 2;
        else if (strcmp(n, "Y") == 0)
            slot = 3;
        if (slot < 0)
            continue;
        if (e->pixel_type != EXR_PIXEL_HALF && e->pixel_type != EXR_PIXEL_FLOAT) {
            set_err(err, errlen, "%s: channel %s is not half or float (unsupported)", path, n);
            goto fail_quiet;
        }
        if (e->x_sampling != 1 || e->y_sampling != 1) {
            set_err(err, errlen, "%s: channel %s is subsampled (unsupported)", path, n);
            goto fail_quiet;
        }
        if (slot == 3)
            idx_y = c;
        else
            r.comp_of[slot] = c;
    }
    if (r.comp_of[0] < 0 || r.comp_of[1] < 0 || r.comp_of[2] < 0) {
        if (idx_y >= 0 && r.comp_of[0] < 0 && r.comp_of[1] < 0 && r.comp_of[2] < 0) {
            r.comp_of[0] = idx_y; /* decoded into slot 0, replicated to G and B */
            r.grey = 1;
        } else {
            char found[256] = "";
            size_t used = 0;
            for (int c = 0; chl && c < chl->num_channels && used + 2 < sizeof found; c++) {
                int n = snprintf(found + used, sizeof found - used, "%s%s", c ? " " : "",
                                 chl->entries[c].name.str ? chl->entries[c].name.str : "?");
                if (n < 0)
                    break;
                used += (size_t)n < sizeof found - used ? (size_t)n : sizeof found - used - 1;
            }
            set_err(err, errlen, "%s: EXR file lacks R, G and B channels (has: %s)", path,
                    found[0] ? found : "none");
            goto fail_quiet;
        }
    }

    if (image_alloc(img, (int)out_w, (int)out_h) != 0) {
        set_err(err, errlen, "%s: out of memory for a %lldx%lld image", path, (long long)out_w,
                (long long)out_h);
        goto fail_quiet;
    }

    if (storage == EXR_STORAGE_SCANLINE) {
        int32_t lines = 0, chunks = 0;
        if (exr_failed(r.st, (rv = exr_get_scanlines_per_chunk(r.ctx, r.part, &lines)),
                       "exr_get_scanlines_per_chunk", &what))
            goto fail;
        if (exr_failed(r.st, (rv = exr_get_chunk_count(r.ctx, r.part, &chunks)),
                       "exr_get_chunk_count", &what))
            goto fail;
        if (lines <= 0 || chunks <= 0 || (uint64_t)dw_w * (uint64_t)lines > SIZE_MAX / 12) {
            set_err(err, errlen, "%s: invalid EXR chunk layout", path);
            goto fail_quiet;
        }
        r.scratch_pixels = (size_t)dw_w * (size_t)lines;
        r.scratch = malloc(r.scratch_pixels * 3 * sizeof(float));
        if (!r.scratch) {
            set_err(err, errlen, "%s: out of memory", path);
            goto fail_quiet;
        }
        for (int32_t ci = 0; ci < chunks; ci++) {
            exr_chunk_info_t cinfo;
            int y = r.dw.min.y + ci * lines;
            if (exr_failed(r.st, (rv = exr_read_scanline_chunk_info(r.ctx, r.part, y, &cinfo)),
                           "exr_read_scanline_chunk_info", &what))
                goto fail;
            rv = exr_read_chunk_into(&r, &cinfo, r.dw.min.x, cinfo.start_y, &what);
            if (rv != EXR_ERR_SUCCESS)
                goto fail;
        }
    } else {
        uint32_t tw = 0, th = 0;
        exr_tile_level_mode_t lm;
        exr_tile_round_mode_t rm;
        int64_t ntx, nty;
        if (exr_failed(r.st, (rv = exr_get_tile_descriptor(r.ctx, r.part, &tw, &th, &lm, &rm)),
                       "exr_get_tile_descriptor", &what))
            goto fail;
        if (tw == 0 || th == 0 || (uint64_t)tw * th > SIZE_MAX / 12) {
            set_err(err, errlen, "%s: invalid EXR tile size", path);
            goto fail_quiet;
        }
        r.scratch_pixels = (size_t)tw * th;
        r.scratch = malloc(r.scratch_pixels * 3 * sizeof(float));
        if (!r.scratch) {
            set_err(err, errlen, "%s: out of memory", path);
            goto fail_quiet;
        }
        ntx = (dw_w + tw - 1) / tw;
        nty = (dw_h + th - 1) / th;
        /* Level 0 (full resolution) only; mipmap/ripmap levels are ignored. */
        for (int64_t ty = 0; ty < nty; ty++) {
            for (int64_t tx = 0; tx < ntx; tx++) {
                exr_chunk_info_t cinfo;
                if (exr_failed(r.st,
                               (rv = exr_read_tile_chunk_info(r.ctx, r.part, (int)tx, (int)ty, 0, 0,
                                                              &cinfo)),
                               "exr_read_tile_chunk_info", &what))
                    goto fail;
                rv = exr_read_chunk_into(&r, &cinfo, (int)(r.dw.min.x + tx * (int64_t)tw),
                                         (int)(r.dw.min.y + ty * (int64_t)th), &what);
                if (rv != EXR_ERR_SUCCESS)
                    goto fail;
            }
        }
    }

    if (r.dec_init)
        exr_decoding_destroy(r.ctx, &r.dec);
    free(r.scratch);
    exr_finish(&r.ctx);
    return 0;

fail:
    exr_fail(err, errlen, path, what, rv, &st);
fail_quiet:
    if (r.dec_init)
        exr_decoding_destroy(r.ctx, &r.dec);
    free(r.scratch);
    if (r.ctx)
        exr_finish(&r.ctx);
    image_free(img);
    return -1;
}

/* ------------------------------------------------------------------------------------ */
/* PNG (libpng)                                                                          */

/* libpng error handling: the error callback records the message and longjmps back to the
 * setjmp in the function that owns the png struct. Those functions only modify state in
 * objects owned by their callers after setjmp, so nothing of theirs can be clobbered. */
typedef struct {
    char msg[256];
} png_errctx;

static void png_error_cb(png_structp png, png_const_charp msg)
{
    png_errctx *e = png_get_error_ptr(png);
    if (e)
        snprintf(e->msg, sizeof e->msg, "%s", msg ? msg : "unknown libpng error");
    png_longjmp(png, 1);
}

static void png_warning_cb(png_structp png, png_const_charp msg)
{
    (void)png;
    (void)msg; /* warnings (e.g. about ancillary chunks) are not errors for us */
}

double image_srgb_encode(double x)
{
    return x <= 0.0031308 ? 12.92 * x : 1.055 * pow(x, 1.0 / 2.4) - 0.055;
}

double image_srgb_decode(double v)
{
    return v <= 0.04045 ? v / 12.92 : pow((v + 0.055) / 1.055, 2.4);
}

/* Display value (see tonemap_value) -> 8-bit sRGB: NaN -> 0, clamp to [0,1], encode,
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
    iso8601_utc(now, m->created, sizeof m->created);
    png_meta_add(m, "Creation Time", m->created);
    png_convert_from_time_t(&m->mtime, now);
}

/* Writes an 8-bit RGB PNG from `data` (h rows of 3*w bytes) to fp. */
static int png_write_rgb8(FILE *fp, const unsigned char *data, int w, int h, const png_meta *m,
                          png_errctx *e)
{
    png_structp png =
        png_create_write_struct(PNG_LIBPNG_VER_STRING, e, png_error_cb, png_warning_cb);
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

static int write_png(const image *img, const char *path, const image_write_opts *o, char *err,
                     size_t errlen)
{
    size_t n;
    unsigned char *data;
    tmpfile_t t;
    FILE *fp;
    png_errctx e;
    png_meta meta;
    int rc, werr;
    double scale = pow(2.0, o->exposure);

    if (check_image(img, path, err, errlen) != 0)
        return -1;
    if ((uint64_t)img->width > 0x7fffffffu || (uint64_t)img->height > 0x7fffffffu) {
        set_err(err, errlen, "%s: image too large for PNG", path);
        return -1;
    }
    n = (size_t)img->width * (size_t)img->height * 3;
    data = malloc(n);
    if (!data) {
        set_err(err, errlen, "%s: out of memory", path);
        return -1;
    }
    for (size_t i = 0; i < n; i++)
        data[i] = to_srgb8(tonemap_value(img->rgb[i] * scale, o->tonemap));
    png_meta_fill(&meta, o);

    if (tmp_open(&t, path, err, errlen) != 0) {
        free(data);
        return -1;
    }
    fp = fdopen(t.fd, "wb");
    if (!fp) {
        set_err(err, errlen, "%s: cannot open stream on %s: %s", path, t.tmp, strerror(errno));
        free(data);
        tmp_abort(&t);
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
        set_err(err, errlen, "%s: PNG encoding failed: %s", path,
                e.msg[0] ? e.msg : "libpng error");
        tmp_abort(&t);
        return -1;
    }
    if (werr) {
        set_err(err, errlen, "%s: writing %s failed: %s", path, t.tmp, strerror(werr));
        tmp_abort(&t);
        return -1;
    }
    return tmp_commit(&t, path, err, errlen);
}

int image_write_png(const image *img, const char *path, char *err, size_t errlen)
{
    image_write_opts def;
    image_write_opts_default(&def);
    return write_png(img, path, &def, err, errlen);
}

int image_check_path(const char *path, char *err, size_t errlen)
{
    if (!path || !*path) {
        set_err(err, errlen, "image: no output path given");
        return -1;
    }
    if (has_ext(path, ".exr") || has_ext(path, ".png"))
        return 0;
    set_err(err, errlen, "%s: unsupported image extension (accepted: .exr, .png)", path);
    return -1;
}

int image_write_ex(const image *img, const char *path, const image_write_opts *o, char *err,
                   size_t errlen)
{
    image_write_opts def;
    o = opts_or_default(o, &def);
    if (image_check_path(path, err, errlen) != 0)
        return -1;
    if (has_ext(path, ".exr"))
        return write_exr(img, path, o, err, errlen);
    return write_png(img, path, o, err, errlen);
}

int image_write(const image *img, const char *path, char *err, size_t errlen)
{
    return image_write_ex(img, path, NULL, err, errlen);
}

/* Decoded PNG: RGB samples, 8- or 16-bit (16-bit in host byte order). Owned by the caller
 * of png_read_rgb so that png_read_rgb never modifies its own locals after setjmp. */
typedef struct {
    unsigned char *data;
    png_bytep *rows;
    int width, height, depth;
    png_errctx e;
} png_decoded;

static int host_is_little_endian(void)
{
    const uint16_t one = 1;
    unsigned char b;
    memcpy(&b, &one, 1);
    return b == 1;
}

static int png_read_rgb(FILE *fp, png_decoded *out)
{
    png_structp png =
        png_create_read_struct(PNG_LIBPNG_VER_STRING, &out->e, png_error_cb, png_warning_cb);
    png_infop info;
    if (!png) {
        snprintf(out->e.msg, sizeof out->e.msg, "cannot create libpng read struct");
        return -1;
    }
    info = png_create_info_struct(png);
    if (!info) {
        png_destroy_read_struct(&png, NULL, NULL);
        snprintf(out->e.msg, sizeof out->e.msg, "cannot create libpng info struct");
        return -1;
    }
    if (setjmp(png_jmpbuf(png))) {
        png_destroy_read_struct(&png, &info, NULL);
        return -1; /* the caller frees out->data and out->rows */
    }
    png_init_io(png, fp);
    png_read_info(png, info);
    {
        png_uint_32 w = png_get_image_width(png, info);
        png_uint_32 h = png_get_image_height(png, info);
        int ctype = png_get_color_type(png, info);
        int depth = png_get_bit_depth(png, info);
        size_t rowbytes;

        if (ctype == PNG_COLOR_TYPE_PALETTE)
            png_set_palette_to_rgb(png);
        if (ctype == PNG_COLOR_TYPE_GRAY && depth < 8)
            png_set_expand_gray_1_2_4_to_8(png);
        if (png_get_valid(png, info, PNG_INFO_tRNS))
            png_set_tRNS_to_alpha(png); /* then stripped below with the other alpha */
        if (ctype == PNG_COLOR_TYPE_GRAY || ctype == PNG_COLOR_TYPE_GRAY_ALPHA)
            png_set_gray_to_rgb(png);
        png_set_strip_alpha(png);
        if (depth == 16 && host_is_little_endian())
            png_set_swap(png);
        png_set_interlace_handling(png);
        png_read_update_info(png, info);

        out->depth = png_get_bit_depth(png, info);
        if (png_get_channels(png, info) != 3 || (out->depth != 8 && out->depth != 16))
            png_error(png, "unexpected layout after transforms");
        if (w == 0 || h == 0 || w > INT_MAX / 6 || h > INT_MAX)
            png_error(png, "image size out of range");
        rowbytes = png_get_rowbytes(png, info);
        if (rowbytes != (size_t)w * 3 * (size_t)(out->depth / 8))
            png_error(png, "unexpected row size");
        if ((size_t)h > SIZE_MAX / rowbytes)
            png_error(png, "image too large");
        out->data = malloc(rowbytes * h);
        out->rows = malloc(sizeof(png_bytep) * h);
        if (!out->data || !out->rows)
            png_error(png, "out of memory");
        for (png_uint_32 y = 0; y < h; y++)
            out->rows[y] = out->data + (size_t)y * rowbytes;
        png_read_image(png, out->rows);
        png_read_end(png, NULL);
        out->width = (int)w;
        out->height = (int)h;
    }
    png_destroy_read_struct(&png, &info, NULL);
    return 0;
}

int image_read_png(const char *path, int srgb_dec, image *img, char *err, size_t errlen)
{
    FILE *fp;
    png_decoded d;
    unsigned char sig[8];
    int rc;

    if (img) {
        img->width = img->height = 0;
        img->rgb = NULL;
    }
    if (!path || !img) {
        set_err(err, errlen, "image_read_png: no path or image given");
        return -1;
    }
    fp = fopen(path, "rb");
    if (!fp) {
        set_err(err, errlen, "%s: cannot open: %s", path, strerror(errno));
        return -1;
    }
    if (fread(sig, 1, sizeof sig, fp) != sizeof sig || png_sig_cmp(sig, 0, sizeof sig) != 0) {
        set_err(err, errlen, "%s: not a PNG file", path);
        fclose(fp);
        return -1;
    }
    rewind(fp);
    memset(&d, 0, sizeof d);
    rc = png_read_rgb(fp, &d);
    fclose(fp);
    if (rc != 0) {
        set_err(err, errlen, "%s: PNG decoding failed: %s", path,
                d.e.msg[0] ? d.e.msg : "libpng error");
        free(d.data);
        free(d.rows);
        return -1;
    }
    free(d.rows);
    if (image_alloc(img, d.width, d.height) != 0) {
        set_err(err, errlen, "%s: out of memory", path);
        free(d.data);
        return -1;
    }
    {
        size_t n = (size_t)d.width * (size_t)d.height * 3;
        if (d.depth == 8) {
            float lut[256];
            for (int v = 0; v < 256; v++)
                lut[v] = (float)(srgb_dec ? image_srgb_decode(v / 255.0) : v / 255.0);
            for (size_t i = 0; i < n; i++)
                img->rgb[i] = lut[d.data[i]];
        } else {
            const uint16_t *s = (const uint16_t *)(const void *)d.data;
            for (size_t i = 0; i < n; i++) {
                double v = s[i] / 65535.0;
                img->rgb[i] = (float)(srgb_dec ? image_srgb_decode(v) : v);
            }
        }
    }
    free(d.data);
    return 0;
}

/* ------------------------------------------------------------------------------------ */
/* Comparison                                                                            */

/* Absolute difference of two channel values; equal values (including equal infinities)
 * differ by 0, two NaNs by 0, a NaN against a number by +infinity. */
static double chan_diff(float a, float b)
{
    double d;
    if (a == b || (isnan(a) && isnan(b)))
        return 0.0;
    d = fabs((double)a - (double)b);
    return isnan(d) ? INFINITY : d;
}

int image_compare(const image *a, const image *b, const unsigned char *mask, double tol,
                  image_diff_stats *st)
{
    image_diff_stats s;
    double sum = 0.0;
    memset(&s, 0, sizeof s);
    s.worst_x = s.worst_y = -1;
    if (st)
        *st = s;
    if (!a || !b || a->width != b->width || a->height != b->height || a->width < 0 || a->height < 0)
        return -1;
    if ((size_t)a->width * (size_t)a->height > 0 && (!a->rgb || !b->rgb))
        return -1;
    for (int y = 0; y < a->height; y++) {
        for (int x = 0; x < a->width; x++) {
            size_t p = (size_t)y * (size_t)a->width + (size_t)x;
            int over = 0;
            if (mask && !mask[p])
                continue;
            s.compared++;
            for (int c = 0; c < 3; c++) {
                double d = chan_diff(a->rgb[p * 3 + c], b->rgb[p * 3 + c]);
                sum += d;
                if (d > tol)
                    over = 1;
                if (d > s.max_abs || s.worst_x < 0) {
                    if (d > s.max_abs)
                        s.max_abs = d;
                    s.worst_x = x;
                    s.worst_y = y;
                }
            }
            if (over)
                s.over++;
        }
    }
    s.mean_abs = s.compared ? sum / (3.0 * (double)s.compared) : 0.0;
    if (st)
        *st = s;
    return 0;
}

int image_write_diff(const image *a, const image *b, const unsigned char *mask, double tol,
                     double gain, const char *path, char *err, size_t errlen)
{
    image d;
    int rc;
    if (!a || !b || !a->rgb || !b->rgb || a->width != b->width || a->height != b->height) {
        set_err(err, errlen, "%s: cannot diff images of different sizes (%dx%d vs %dx%d)",
                path ? path : "(null)", a ? a->width : 0, a ? a->height : 0, b ? b->width : 0,
                b ? b->height : 0);
        return -1;
    }
    if (image_alloc(&d, a->width, a->height) != 0) {
        set_err(err, errlen, "%s: out of memory for the diff image", path ? path : "(null)");
        return -1;
    }
    for (size_t p = 0; p < (size_t)a->width * (size_t)a->height; p++) {
        const float *pa = a->rgb + p * 3, *pb = b->rgb + p * 3;
        float *o = d.rgb + p * 3;
        if (mask && !mask[p]) {
            /* Masked out: a's luminance, clamped to [0,1], dimmed to a quarter, as grey. */
            double l = 0.2126 * pa[0] + 0.7152 * pa[1] + 0.0722 * pa[2];
            if (!(l > 0.0))
                l = 0.0;
            if (l > 1.0)
                l = 1.0;
            o[0] = o[1] = o[2] = (float)(0.25 * l);
            continue;
        }
        double dd[3];
        int over = 0;
        for (int c = 0; c < 3; c++) {
            dd[c] = chan_diff(pa[c], pb[c]);
            if (dd[c] > tol)
                over = 1;
        }
        if (over) {
            o[0] = 1.0f;
            o[1] = o[2] = 0.0f;
        } else {
            for (int c = 0; c < 3; c++) {
                double v = dd[c] * gain;
                o[c] = (float)(!(v > 0.0) ? 0.0 : v > 1.0 ? 1.0 : v);
            }
        }
    }
    rc = image_write(&d, path, err, errlen);
    image_free(&d);
    return rc;
}
