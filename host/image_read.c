/* Reading images into linear float RGB, for tests and tools: OpenEXR (OpenEXRCore;
 * scanline or tiled, half or float, RGB or Y) and PNG (libpng; any layout, 8- or 16-bit).
 * clwhitted itself never reads an image, so it links none of this. See image_read.h. */
#include "image_read.h"

#include <errno.h>
#include <limits.h>
#include <setjmp.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <openexr.h>
#include <png.h>

#include "image.h"
#include "image_internal.h"

/* ------------------------------------------------------------------------------------ */
/* OpenEXR                                                                               */

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
    image_exr_state *st; /* its message is cleared before each call, so it belongs to the failure */
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
    image_exr_state st;
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
        image_set_err(err, errlen, "image_read_exr: no path or image given");
        return -1;
    }
    memset(&st, 0, sizeof st);
    memset(&r, 0, sizeof r);
    r.out = img;
    r.st = &st;
    st.fd = -1;
    init.error_handler_fn = image_exr_error_cb;
    init.user_data = &st;

    if (image_exr_failed(r.st, (rv = exr_start_read(&r.ctx, path, &init)),
                         "opening the EXR file (exr_start_read)", &what))
        goto fail;
    if (image_exr_failed(r.st, (rv = exr_get_count(r.ctx, &nparts)), "exr_get_count", &what))
        goto fail;
    if (nparts < 1) {
        image_set_err(err, errlen, "%s: EXR file has no parts", path);
        goto fail_quiet;
    }
    if (image_exr_failed(r.st, (rv = exr_get_storage(r.ctx, r.part, &storage)), "exr_get_storage",
                         &what))
        goto fail;
    if (storage != EXR_STORAGE_SCANLINE && storage != EXR_STORAGE_TILED) {
        image_set_err(err, errlen, "%s: deep EXR images are not supported", path);
        goto fail_quiet;
    }
    if (image_exr_failed(r.st, (rv = exr_get_data_window(r.ctx, r.part, &r.dw)),
                         "exr_get_data_window", &what))
        goto fail;
    if (image_exr_failed(r.st, (rv = exr_get_display_window(r.ctx, r.part, &r.disp)),
                         "exr_get_display_window", &what))
        goto fail;
    if (image_exr_failed(r.st, (rv = exr_get_channels(r.ctx, r.part, &chl)), "exr_get_channels",
                         &what))
        goto fail;

    dw_w = (int64_t)r.dw.max.x - r.dw.min.x + 1;
    dw_h = (int64_t)r.dw.max.y - r.dw.min.y + 1;
    out_w = (int64_t)r.disp.max.x - r.disp.min.x + 1;
    out_h = (int64_t)r.disp.max.y - r.disp.min.y + 1;
    if (dw_w <= 0 || dw_h <= 0 || out_w <= 0 || out_h <= 0 || out_w > INT_MAX || out_h > INT_MAX) {
        image_set_err(err, errlen, "%s: invalid EXR data or display window", path);
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
            image_set_err(err, errlen, "%s: channel %s is not half or float (unsupported)", path,
                          n);
            goto fail_quiet;
        }
        if (e->x_sampling != 1 || e->y_sampling != 1) {
            image_set_err(err, errlen, "%s: channel %s is subsampled (unsupported)", path, n);
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
            image_set_err(err, errlen, "%s: EXR file lacks R, G and B channels (has: %s)", path,
                          found[0] ? found : "none");
            goto fail_quiet;
        }
    }

    if (image_alloc(img, (int)out_w, (int)out_h) != 0) {
        image_set_err(err, errlen, "%s: out of memory for a %lldx%lld image", path,
                      (long long)out_w, (long long)out_h);
        goto fail_quiet;
    }

    if (storage == EXR_STORAGE_SCANLINE) {
        int32_t lines = 0, chunks = 0;
        if (image_exr_failed(r.st, (rv = exr_get_scanlines_per_chunk(r.ctx, r.part, &lines)),
                             "exr_get_scanlines_per_chunk", &what))
            goto fail;
        if (image_exr_failed(r.st, (rv = exr_get_chunk_count(r.ctx, r.part, &chunks)),
                             "exr_get_chunk_count", &what))
            goto fail;
        if (lines <= 0 || chunks <= 0 || (uint64_t)dw_w * (uint64_t)lines > SIZE_MAX / 12) {
            image_set_err(err, errlen, "%s: invalid EXR chunk layout", path);
            goto fail_quiet;
        }
        r.scratch_pixels = (size_t)dw_w * (size_t)lines;
        r.scratch = malloc(r.scratch_pixels * 3 * sizeof(float));
        if (!r.scratch) {
            image_set_err(err, errlen, "%s: out of memory", path);
            goto fail_quiet;
        }
        for (int32_t ci = 0; ci < chunks; ci++) {
            exr_chunk_info_t cinfo;
            int y = r.dw.min.y + ci * lines;
            if (image_exr_failed(r.st,
                                 (rv = exr_read_scanline_chunk_info(r.ctx, r.part, y, &cinfo)),
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
        if (image_exr_failed(r.st,
                             (rv = exr_get_tile_descriptor(r.ctx, r.part, &tw, &th, &lm, &rm)),
                             "exr_get_tile_descriptor", &what))
            goto fail;
        if (tw == 0 || th == 0 || (uint64_t)tw * th > SIZE_MAX / 12) {
            image_set_err(err, errlen, "%s: invalid EXR tile size", path);
            goto fail_quiet;
        }
        r.scratch_pixels = (size_t)tw * th;
        r.scratch = malloc(r.scratch_pixels * 3 * sizeof(float));
        if (!r.scratch) {
            image_set_err(err, errlen, "%s: out of memory", path);
            goto fail_quiet;
        }
        ntx = (dw_w + tw - 1) / tw;
        nty = (dw_h + th - 1) / th;
        /* Level 0 (full resolution) only; mipmap/ripmap levels are ignored. */
        for (int64_t ty = 0; ty < nty; ty++) {
            for (int64_t tx = 0; tx < ntx; tx++) {
                exr_chunk_info_t cinfo;
                if (image_exr_failed(r.st,
                                     (rv = exr_read_tile_chunk_info(r.ctx, r.part, (int)tx, (int)ty,
                                                                    0, 0, &cinfo)),
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
    image_exr_fail(err, errlen, path, what, rv, &st);
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
/* PNG                                                                                   */

/* Decoded PNG: RGB samples, 8- or 16-bit (16-bit in host byte order). Owned by the caller
 * of png_read_rgb so that png_read_rgb never modifies its own locals after setjmp. */
typedef struct {
    unsigned char *data;
    png_bytep *rows;
    int width, height, depth;
    image_png_errctx e;
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
    png_structp png = png_create_read_struct(PNG_LIBPNG_VER_STRING, &out->e, image_png_error_cb,
                                             image_png_warning_cb);
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
        image_set_err(err, errlen, "image_read_png: no path or image given");
        return -1;
    }
    fp = fopen(path, "rb");
    if (!fp) {
        image_set_err(err, errlen, "%s: cannot open: %s", path, strerror(errno));
        return -1;
    }
    if (fread(sig, 1, sizeof sig, fp) != sizeof sig || png_sig_cmp(sig, 0, sizeof sig) != 0) {
        image_set_err(err, errlen, "%s: not a PNG file", path);
        fclose(fp);
        return -1;
    }
    rewind(fp);
    memset(&d, 0, sizeof d);
    rc = png_read_rgb(fp, &d);
    fclose(fp);
    if (rc != 0) {
        image_set_err(err, errlen, "%s: PNG decoding failed: %s", path,
                      d.e.msg[0] ? d.e.msg : "libpng error");
        free(d.data);
        free(d.rows);
        return -1;
    }
    free(d.rows);
    if (image_alloc(img, d.width, d.height) != 0) {
        image_set_err(err, errlen, "%s: out of memory", path);
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
