/* Writing OpenEXR (OpenEXRCore C API): linear RGB as 32-bit or half floats, ZIP
 * compressed (chunks compressed on several threads, written in order), with the metadata
 * of image_write_opts; and the OpenEXRCore error handling that the reader (image_read.c)
 * shares. See image.h and image_internal.h. */
#include <errno.h>
#include <limits.h>
#include <pthread.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/types.h>
#include <time.h>
#include <unistd.h>

#include <openexr.h>

#include "image.h"
#include "config.h"
#include "image_internal.h"
#include "par.h"
#include "sys.h"

/* ------------------------------------------------------------------------------------ */
/* Error handling (shared with the reader)                                               */

void image_exr_error_cb(exr_const_context_t ctxt, exr_result_t code, const char *msg)
{
    /* the writer's jobs can fail on several threads at once */
    static pthread_mutex_t lock = PTHREAD_MUTEX_INITIALIZER;
    void *ud = NULL;
    image_exr_state *st;
    if (!ctxt || exr_get_user_data(ctxt, &ud) != EXR_ERR_SUCCESS || !ud)
        return; /* no context: nowhere to store it; the code is still returned */
    st = ud;
    pthread_mutex_lock(&lock);
    snprintf(st->msg, sizeof st->msg, "%s", msg ? msg : exr_get_default_error_message(code));
    pthread_mutex_unlock(&lock);
}

void image_exr_fail(char *err, size_t errlen, const char *path, const char *what, exr_result_t rv,
                    const image_exr_state *st)
{
    const char *detail = st && st->msg[0] ? st->msg : exr_get_default_error_message(rv);
    if (st && st->write_errno)
        image_set_err(err, errlen, "%s: %s failed: %s (%s; write error: %s)", path, what,
                      exr_get_error_code_as_string(rv), detail, strerror(st->write_errno));
    else
        image_set_err(err, errlen, "%s: %s failed: %s (%s)", path, what,
                      exr_get_error_code_as_string(rv), detail);
}

int image_exr_failed(image_exr_state *st, exr_result_t rv, const char *desc, const char **what)
{
    if (rv != EXR_ERR_SUCCESS) {
        *what = desc;
        return 1;
    }
    st->msg[0] = '\0';
    return 0;
}

/* ------------------------------------------------------------------------------------ */
/* Writing                                                                               */

/* The output stream: pwrite on the temporary file's descriptor, recording the errno of a
 * failed write in the state. */
static int64_t exr_stream_write(exr_const_context_t ctxt, void *userdata, const void *buffer,
                                uint64_t sz, uint64_t offset, exr_stream_error_func_ptr_t error_cb)
{
    image_exr_state *st = userdata;
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
    image_local_date(time(NULL), date, sizeof date, &utc_offset);
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

/* The chunks of one image, compressed on several threads (par.c) and written in order:
 * each slot has its own encoding pipeline, whose write step is left out (the caller
 * writes the compressed chunk when its turn comes), as is the library's wait for the
 * chunk's turn. OpenEXRCore locks the context inside the calls the jobs make. */
typedef struct {
    exr_encode_pipeline_t enc;
    int ready; /* enc initialised */
    int32_t y; /* the chunk's first row */
    exr_result_t rv;
    const char *what; /* the failed step */
} exr_slot;

typedef struct {
    exr_context_t ctx;
    int part, half;
    int32_t lines;           /* rows per chunk */
    const unsigned char *px; /* the pixels, as the file's type */
    size_t elem, line_bytes; /* bytes per value and per row */
    exr_slot *slot;
    int window;
    const char *bad_channel; /* a channel we do not write, when a job found one */
} exr_chunks;

static int exr_slot_fail(exr_slot *sl, exr_result_t rv, const char *what)
{
    sl->rv = rv;
    sl->what = what;
    return 1;
}

/* Compresses chunk j into its slot's pipeline. */
static int exr_chunk_job(void *ctx, int j, int thread)
{
    static const char *const names[3] = {"R", "G", "B"};
    exr_chunks *x = ctx;
    exr_slot *sl = &x->slot[j % x->window];
    exr_chunk_info_t cinfo;
    exr_result_t rv;
    const unsigned char *row;
    (void)thread;
    sl->y = j * x->lines;
    row = x->px + (size_t)sl->y * x->line_bytes;
    if ((rv = exr_write_scanline_chunk_info(x->ctx, x->part, sl->y, &cinfo)) != EXR_ERR_SUCCESS)
        return exr_slot_fail(sl, rv, "exr_write_scanline_chunk_info");
    if (!sl->ready) {
        if ((rv = exr_encoding_initialize(x->ctx, x->part, &cinfo, &sl->enc)) != EXR_ERR_SUCCESS)
            return exr_slot_fail(sl, rv, "exr_encoding_initialize");
        sl->ready = 1;
    } else if ((rv = exr_encoding_update(x->ctx, x->part, &cinfo, &sl->enc)) != EXR_ERR_SUCCESS) {
        return exr_slot_fail(sl, rv, "exr_encoding_update");
    }
    /* The pipeline's channels are in file order (alphabetical: B, G, R); match by name
     * rather than by position. */
    for (int c = 0; c < sl->enc.channel_count; c++) {
        exr_coding_channel_info_t *ch = &sl->enc.channels[c];
        int comp = -1;
        for (int k = 0; k < 3; k++)
            if (ch->channel_name && strcmp(ch->channel_name, names[k]) == 0)
                comp = k;
        if (comp < 0) {
            x->bad_channel = ch->channel_name ? ch->channel_name : "?";
            return exr_slot_fail(sl, EXR_ERR_INVALID_ARGUMENT, NULL);
        }
        ch->user_bytes_per_element = (int16_t)x->elem;
        ch->user_data_type = x->half ? EXR_PIXEL_HALF : EXR_PIXEL_FLOAT;
        ch->user_pixel_stride = (int32_t)(3 * x->elem);
        ch->user_line_stride = (int32_t)x->line_bytes;
        ch->encode_from_ptr = row + (size_t)comp * x->elem;
    }
    if (!sl->enc.convert_and_pack_fn) {
        rv = exr_encoding_choose_default_routines(x->ctx, x->part, &sl->enc);
        if (rv != EXR_ERR_SUCCESS)
            return exr_slot_fail(sl, rv, "exr_encoding_choose_default_routines");
        sl->enc.yield_until_ready_fn = NULL; /* the order is ours to keep */
        sl->enc.write_fn = NULL;             /* exr_chunk_emit writes */
    }
    if ((rv = exr_encoding_run(x->ctx, x->part, &sl->enc)) != EXR_ERR_SUCCESS)
        return exr_slot_fail(sl, rv, "exr_encoding_run");
    return 0;
}

/* Writes chunk j (what the library's own write step writes: the compressed buffer). */
static int exr_chunk_emit(void *ctx, int j)
{
    exr_chunks *x = ctx;
    exr_slot *sl = &x->slot[j % x->window];
    exr_result_t rv = exr_write_scanline_chunk(x->ctx, x->part, sl->y, sl->enc.compressed_buffer,
                                               sl->enc.compressed_bytes);
    return rv != EXR_ERR_SUCCESS ? exr_slot_fail(sl, rv, "exr_write_scanline_chunk") : 0;
}

/* Compresses and writes every chunk. Returns EXR_ERR_SUCCESS, or the failure with *what
 * (NULL with *bad_channel set when the encoder showed a channel we do not write). */
static exr_result_t exr_write_chunks(exr_chunks *x, int32_t chunks, const char **what,
                                     const char **bad_channel)
{
    int threads = image_write_threads(), i;
    exr_result_t rv = EXR_ERR_SUCCESS;
    x->window = 2 * threads;
    x->slot = calloc((size_t)x->window, sizeof *x->slot);
    *bad_channel = NULL;
    if (!x->slot) {
        *what = "allocating the encoders";
        return EXR_ERR_OUT_OF_MEMORY;
    }
    if (par_ordered(chunks, threads, x->window, exr_chunk_job, exr_chunk_emit, x) != 0) {
        rv = EXR_ERR_UNKNOWN;
        *what = "writing the chunks";
        for (i = x->window - 1; i >= 0; i--) /* the failed slot (any one, if several) */
            if (x->slot[i].rv != EXR_ERR_SUCCESS) {
                rv = x->slot[i].rv;
                *what = x->slot[i].what;
            }
    }
    *bad_channel = x->bad_channel;
    for (i = 0; i < x->window; i++)
        if (x->slot[i].ready)
            exr_encoding_destroy(x->ctx, &x->slot[i].enc);
    free(x->slot);
    return rv;
}

int image_exr_write(const image *img, const char *path, const image_write_opts *o, char *err,
                    size_t errlen)
{
    static const char *const names[3] = {"R", "G", "B"};
    image_exr_state st;
    exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
    exr_context_t ctx = NULL;
    exr_chunks x;
    const char *bad_channel;
    sys_tmpfile t;
    exr_result_t rv;
    const char *what = NULL;
    int part = 0;
    int32_t lines = 0, chunks = 0;
    size_t w, line_bytes, elem = o->half ? sizeof(uint16_t) : sizeof(float);
    uint16_t *halves = NULL; /* the pixels as half floats, when o->half */
    const unsigned char *pixels = (const unsigned char *)img->rgb;

    if (image_check_writable(img, path, err, errlen) != 0)
        return -1;
    if (img->width > INT32_MAX / 12) { /* user_line_stride is an int32 */
        image_set_err(err, errlen, "%s: image too wide for EXR output (%d)", path, img->width);
        return -1;
    }
    w = (size_t)img->width;
    line_bytes = w * 3 * elem;
    if (o->half) {
        size_t n = w * (size_t)img->height * 3;
        halves = malloc(n * sizeof *halves);
        if (!halves) {
            image_set_err(err, errlen, "%s: out of memory", path);
            return -1;
        }
        for (size_t i = 0; i < n; i++)
            halves[i] = float_to_half(img->rgb[i]);
        pixels = (const unsigned char *)halves;
    }
    if (sys_tmp_open(&t, path, err, errlen) != 0) {
        free(halves);
        return -1;
    }

    memset(&st, 0, sizeof st);
    st.fd = t.fd;
    init.error_handler_fn = image_exr_error_cb;
    init.user_data = &st;
    init.write_fn = exr_stream_write;
    init.destroy_fn = exr_stream_destroy;

    if (image_exr_failed(&st, (rv = exr_start_write(&ctx, t.tmp, EXR_WRITE_FILE_DIRECTLY, &init)),
                         "exr_start_write", &what))
        goto fail;
    if (image_exr_failed(&st, (rv = exr_add_part(ctx, NULL, EXR_STORAGE_SCANLINE, &part)),
                         "exr_add_part", &what))
        goto fail;
    /* Sets data and display windows to (0,0)-(w-1,h-1), pixel aspect 1, screen window,
     * increasing line order and the compression. */
    if (image_exr_failed(&st,
                         (rv = exr_initialize_required_attr_simple(
                              ctx, part, img->width, img->height, EXR_COMPRESSION_ZIP)),
                         "exr_initialize_required_attr_simple", &what))
        goto fail;
    /* zlib level 1: a few percent bigger than the default level, several times faster */
    if (image_exr_failed(&st, (rv = exr_set_zip_compression_level(ctx, part, 1)),
                         "exr_set_zip_compression_level", &what))
        goto fail;
    for (int c = 0; c < 3; c++)
        if (image_exr_failed(&st,
                             (rv = exr_add_channel(ctx, part, names[c],
                                                   o->half ? EXR_PIXEL_HALF : EXR_PIXEL_FLOAT,
                                                   EXR_PERCEPTUALLY_LOGARITHMIC, 1, 1)),
                             "exr_add_channel", &what))
            goto fail;
    rv = exr_set_meta(ctx, o, &what); /* names the failed step in what */
    if (rv != EXR_ERR_SUCCESS)
        goto fail;
    st.msg[0] = '\0';
    if (image_exr_failed(&st, (rv = exr_write_header(ctx)), "exr_write_header", &what))
        goto fail;
    if (image_exr_failed(&st, (rv = exr_get_scanlines_per_chunk(ctx, part, &lines)),
                         "exr_get_scanlines_per_chunk", &what))
        goto fail;
    if (image_exr_failed(&st, (rv = exr_get_chunk_count(ctx, part, &chunks)), "exr_get_chunk_count",
                         &what))
        goto fail;
    if (lines <= 0 || chunks <= 0 || (int64_t)lines * chunks < img->height) {
        image_set_err(err, errlen, "%s: unexpected EXR chunk layout (%d chunks of %d lines)", path,
                      (int)chunks, (int)lines);
        goto fail_quiet;
    }

    memset(&x, 0, sizeof x);
    x.ctx = ctx;
    x.part = part;
    x.half = o->half;
    x.lines = lines;
    x.px = pixels;
    x.elem = elem;
    x.line_bytes = line_bytes;
    rv = exr_write_chunks(&x, chunks, &what, &bad_channel);
    if (bad_channel) {
        image_set_err(err, errlen, "%s: unexpected channel '%s' in EXR encoder", path, bad_channel);
        goto fail_quiet;
    }
    if (rv != EXR_ERR_SUCCESS)
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
    return sys_tmp_commit(&t, path, err, errlen);

fail:
    image_exr_fail(err, errlen, path, what, rv, &st);
fail_quiet:
    if (ctx)
        exr_finish(&ctx);
    sys_tmp_abort(&t);
    free(halves);
    return -1;
}

int image_write_exr(const image *img, const char *path, char *err, size_t errlen)
{
    image_write_opts def;
    image_write_opts_default(&def);
    return image_exr_write(img, path, &def, err, errlen);
}
