/* Tests for host/image*.c: EXR and PNG I/O, the temp+rename guarantee, comparison, diffs. */
#include "testutil.h"

#include "image.h"
#include "image_diff.h"
#include "image_read.h"

#include <dirent.h>
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include <openexr.h>
#include <png.h>

#define PATHLEN 4096

static char g_dir[PATHLEN]; /* per-run temporary directory */

/* ------------------------------------------------------------------------------------ */
/* Helpers                                                                               */

static void tpath(char *out, const char *name)
{
    int n = snprintf(out, PATHLEN, "%s/%s", g_dir, name);
    assert_true(n > 0 && n < PATHLEN);
}

static int file_exists(const char *path)
{
    struct stat sb;
    return stat(path, &sb) == 0;
}

static void write_text(const char *path, const char *text)
{
    FILE *f = fopen(path, "wb");
    assert_non_null(f);
    assert_int_equal(fputs(text, f) >= 0, 1);
    assert_int_equal(fclose(f), 0);
}

/* Reads up to cap-1 bytes of a file into buf (NUL-terminated); returns the byte count. */
static size_t read_bytes(const char *path, char *buf, size_t cap)
{
    FILE *f = fopen(path, "rb");
    size_t n;
    assert_non_null(f);
    n = fread(buf, 1, cap - 1, f);
    buf[n] = '\0';
    fclose(f);
    return n;
}

/* Number of entries in the test directory whose name contains ".tmp-". */
static int count_tmp_leftovers(void)
{
    DIR *d = opendir(g_dir);
    struct dirent *e;
    int n = 0;
    assert_non_null(d);
    while ((e = readdir(d)) != NULL)
        if (strstr(e->d_name, ".tmp-"))
            n++;
    closedir(d);
    return n;
}

static int remove_tree(const char *path)
{
    struct stat sb;
    if (lstat(path, &sb) != 0)
        return errno == ENOENT ? 0 : -1;
    if (S_ISDIR(sb.st_mode)) {
        DIR *d = opendir(path);
        struct dirent *e;
        char sub[PATHLEN];
        if (!d)
            return -1;
        while ((e = readdir(d)) != NULL) {
            if (strcmp(e->d_name, ".") == 0 || strcmp(e->d_name, "..") == 0)
                continue;
            if (snprintf(sub, sizeof sub, "%s/%s", path, e->d_name) >= (int)sizeof sub)
                continue;
            remove_tree(sub);
        }
        closedir(d);
        return rmdir(path);
    }
    return unlink(path);
}

static int group_setup(void **state)
{
    (void)state;
    snprintf(g_dir, sizeof g_dir, "/tmp/cw_test_image-XXXXXX");
    return mkdtemp(g_dir) ? 0 : -1;
}

static int group_teardown(void **state)
{
    (void)state;
    return remove_tree(g_dir);
}

static void make_image(image *img, int w, int h)
{
    assert_int_equal(image_alloc(img, w, h), 0);
    assert_non_null(img->rgb);
    assert_int_equal(img->width, w);
    assert_int_equal(img->height, h);
}

static float *px(image *img, int x, int y)
{
    return img->rgb + ((size_t)y * (size_t)img->width + (size_t)x) * 3;
}

static void set_px(image *img, int x, int y, float r, float g, float b)
{
    float *p = px(img, x, y);
    p[0] = r;
    p[1] = g;
    p[2] = b;
}

/* Reference sRGB transfer functions (independent of image.c). */
static double ref_encode(double x)
{
    if (x <= 0.0031308)
        return 12.92 * x;
    return 1.055 * pow(x, 1.0 / 2.4) - 0.055;
}

static double ref_decode(double v)
{
    if (v <= 0.04045)
        return v / 12.92;
    return pow((v + 0.055) / 1.055, 2.4);
}

/* ------------------------------------------------------------------------------------ */
/* Allocation                                                                            */

static void test_alloc(void **state)
{
    image img;
    (void)state;
    make_image(&img, 5, 4);
    for (size_t i = 0; i < 5 * 4 * 3; i++)
        assert_true(img.rgb[i] == 0.0f);
    image_free(&img);
    assert_null(img.rgb);
    assert_int_equal(img.width, 0);
    image_free(&img); /* twice is harmless */
    image_free(NULL);
    assert_int_equal(image_alloc(&img, 0, 4), -1);
    assert_null(img.rgb);
    assert_int_equal(image_alloc(&img, 4, -1), -1);
    assert_int_equal(image_alloc(NULL, 4, 4), -1);
}

/* ------------------------------------------------------------------------------------ */
/* EXR                                                                                   */

static void test_exr_roundtrip_exact(void **state)
{
    static const float special[] = {0.0f,   -0.0f,   1.0f,    1.5f,     7.25f,   1e6f,
                                    3e38f,  -1.0f,   -0.125f, -4096.5f, 1e-7f,   1e-30f,
                                    1e-40f, -1e-38f, 0.1f,    0.3333f,  65504.f, 65520.f};
    const int w = 37, h = 45; /* several 16-line ZIP chunks, the last one partial */
    char path[PATHLEN], err[512] = "";
    image a, b;
    size_t ns = sizeof special / sizeof special[0];
    (void)state;

    make_image(&a, w, h);
    for (size_t i = 0; i < (size_t)w * h * 3; i++)
        a.rgb[i] = (i < ns) ? special[i] : (float)((double)(i * 7919 % 1000) / 37.0 - 9.0);
    tpath(path, "round.exr");
    assert_int_equal(image_write(&a, path, err, sizeof err), 0);
    assert_int_equal(image_read_exr(path, &b, err, sizeof err), 0);
    assert_int_equal(b.width, w);
    assert_int_equal(b.height, h);
    assert_memory_equal(a.rgb, b.rgb, (size_t)w * h * 3 * sizeof(float));
    image_free(&b);

    /* Upper-case extension and the direct writer; a 1x1 image. */
    tpath(path, "UPPER.EXR");
    assert_int_equal(image_write(&a, path, err, sizeof err), 0);
    assert_int_equal(image_read_exr(path, &b, err, sizeof err), 0);
    assert_memory_equal(a.rgb, b.rgb, (size_t)w * h * 3 * sizeof(float));
    image_free(&b);
    image_free(&a);

    make_image(&a, 1, 1);
    set_px(&a, 0, 0, 0.25f, -2.0f, 1e-20f);
    tpath(path, "one.exr");
    assert_int_equal(image_write_exr(&a, path, err, sizeof err), 0);
    assert_int_equal(image_read_exr(path, &b, err, sizeof err), 0);
    assert_int_equal(b.width, 1);
    assert_int_equal(b.height, 1);
    assert_memory_equal(a.rgb, b.rgb, 3 * sizeof(float));
    image_free(&b);
    image_free(&a);
    assert_int_equal(count_tmp_leftovers(), 0);
}

/* A value exactly representable as half: multiples of 1/16 in [-1, 3). */
static float pattern(int x, int y, int c)
{
    int k = ((x * 7 + y * 3 + c * 5) % 64 + 64) % 64;
    return (float)k / 16.0f - 1.0f;
}

typedef struct {
    exr_storage_t storage;
    exr_compression_t comp;
    exr_pixel_type_t ptype;
    const char *const *names; /* channel names; "R","G","B","Y" get pattern() channel 0,1,2,0 */
    int nch;
    exr_attr_box2i_t dw, disp;
} exr_layout;

static int chan_slot(const char *name)
{
    if (strcmp(name, "G") == 0)
        return 1;
    if (strcmp(name, "B") == 0)
        return 2;
    if (strcmp(name, "A") == 0)
        return 3;
    return 0; /* R, Y */
}

/* Writes a file the way other tools might, with OpenEXRCore directly. */
static void write_exr_layout(const char *path, const exr_layout *L)
{
    exr_context_t ctx = NULL;
    exr_encode_pipeline_t enc = EXR_ENCODE_PIPELINE_INITIALIZER;
    exr_attr_v2f_t swc = {{{0.0f, 0.0f}}};
    int part = -1, first = 1;
    int dww = L->dw.max.x - L->dw.min.x + 1, dwh = L->dw.max.y - L->dw.min.y + 1;
    const int tile = 8;
    float *buf = malloc((size_t)dww * dwh * (size_t)L->nch * sizeof(float));
    int32_t lines = 0;
    int nchunks_y, nchunks_x;

    assert_non_null(buf);
    for (int y = 0; y < dwh; y++)
        for (int x = 0; x < dww; x++)
            for (int c = 0; c < L->nch; c++)
                buf[((size_t)y * dww + x) * L->nch + c] =
                    pattern(x + L->dw.min.x, y + L->dw.min.y, chan_slot(L->names[c]));

    assert_int_equal(exr_start_write(&ctx, path, EXR_WRITE_FILE_DIRECTLY, NULL), 0);
    assert_int_equal(exr_add_part(ctx, NULL, L->storage, &part), 0);
    assert_int_equal(exr_initialize_required_attr(ctx, part, &L->disp, &L->dw, 1.0f, &swc, 1.0f,
                                                  EXR_LINEORDER_INCREASING_Y, L->comp),
                     0);
    if (L->storage == EXR_STORAGE_TILED)
        assert_int_equal(
            exr_set_tile_descriptor(ctx, part, tile, tile, EXR_TILE_ONE_LEVEL, EXR_TILE_ROUND_DOWN),
            0);
    for (int c = 0; c < L->nch; c++)
        assert_int_equal(
            exr_add_channel(ctx, part, L->names[c], L->ptype, EXR_PERCEPTUALLY_LOGARITHMIC, 1, 1),
            0);
    assert_int_equal(exr_write_header(ctx), 0);

    if (L->storage == EXR_STORAGE_TILED) {
        nchunks_x = (dww + tile - 1) / tile;
        nchunks_y = (dwh + tile - 1) / tile;
        lines = tile;
    } else {
        assert_int_equal(exr_get_scanlines_per_chunk(ctx, part, &lines), 0);
        nchunks_x = 1;
        nchunks_y = (dwh + lines - 1) / lines;
    }
    for (int cy = 0; cy < nchunks_y; cy++) {
        for (int cx = 0; cx < nchunks_x; cx++) {
            exr_chunk_info_t cinfo;
            int x0 = cx * tile, y0 = cy * lines; /* relative to the data window */
            if (L->storage == EXR_STORAGE_TILED)
                assert_int_equal(exr_write_tile_chunk_info(ctx, part, cx, cy, 0, 0, &cinfo), 0);
            else
                assert_int_equal(exr_write_scanline_chunk_info(ctx, part, L->dw.min.y + y0, &cinfo),
                                 0);
            if (first)
                assert_int_equal(exr_encoding_initialize(ctx, part, &cinfo, &enc), 0);
            else
                assert_int_equal(exr_encoding_update(ctx, part, &cinfo, &enc), 0);
            for (int c = 0; c < enc.channel_count; c++) {
                exr_coding_channel_info_t *ch = &enc.channels[c];
                int k = -1;
                for (int j = 0; j < L->nch; j++)
                    if (strcmp(ch->channel_name, L->names[j]) == 0)
                        k = j;
                assert_true(k >= 0);
                ch->user_bytes_per_element = 4;
                ch->user_data_type = EXR_PIXEL_FLOAT;
                ch->user_pixel_stride = (int32_t)(L->nch * sizeof(float));
                ch->user_line_stride = (int32_t)((size_t)dww * L->nch * sizeof(float));
                ch->encode_from_ptr =
                    (const uint8_t *)(buf + ((size_t)y0 * dww + (size_t)x0) * L->nch + k);
            }
            if (first)
                assert_int_equal(exr_encoding_choose_default_routines(ctx, part, &enc), 0);
            first = 0;
            assert_int_equal(exr_encoding_run(ctx, part, &enc), 0);
        }
    }
    assert_int_equal(exr_encoding_destroy(ctx, &enc), 0);
    assert_int_equal(exr_finish(&ctx), 0);
    free(buf);
}

static exr_attr_box2i_t box(int x0, int y0, int x1, int y1)
{
    exr_attr_box2i_t b;
    b.min.x = x0;
    b.min.y = y0;
    b.max.x = x1;
    b.max.y = y1;
    return b;
}

/* Reads a file written with `L` and checks every pixel against pattern(). */
static void check_exr_layout(const exr_layout *L, const char *name)
{
    char path[PATHLEN], err[512] = "";
    image img;
    int grey = L->nch >= 1 && strcmp(L->names[0], "Y") == 0;
    tpath(path, name);
    write_exr_layout(path, L);
    if (image_read_exr(path, &img, err, sizeof err) != 0)
        fail_msg("%s: %s", name, err);
    assert_int_equal(img.width, L->disp.max.x - L->disp.min.x + 1);
    assert_int_equal(img.height, L->disp.max.y - L->disp.min.y + 1);
    for (int y = 0; y < img.height; y++) {
        for (int x = 0; x < img.width; x++) {
            int fx = x + L->disp.min.x, fy = y + L->disp.min.y;
            int inside =
                fx >= L->dw.min.x && fx <= L->dw.max.x && fy >= L->dw.min.y && fy <= L->dw.max.y;
            for (int c = 0; c < 3; c++) {
                float want = inside ? pattern(fx, fy, grey ? 0 : c) : 0.0f;
                float got = px(&img, x, y)[c];
                if (got != want)
                    fail_msg("%s: pixel (%d,%d) channel %d: got %g, want %g", name, x, y, c,
                             (double)got, (double)want);
            }
        }
    }
    image_free(&img);
}

static void test_exr_read_other_layouts(void **state)
{
    static const char *const rgb[] = {"R", "G", "B"};
    static const char *const rgba[] = {"A", "B", "G", "R"};
    static const char *const y[] = {"Y"};
    exr_layout L;
    (void)state;

    /* Half RGBA, PIZ, data window == display window. */
    memset(&L, 0, sizeof L);
    L.storage = EXR_STORAGE_SCANLINE;
    L.comp = EXR_COMPRESSION_PIZ;
    L.ptype = EXR_PIXEL_HALF;
    L.names = rgba;
    L.nch = 4;
    L.dw = L.disp = box(0, 0, 40, 70);
    check_exr_layout(&L, "half_piz.exr");

    /* Uncompressed float with a data window inside a larger display window, offsets. */
    L.comp = EXR_COMPRESSION_NONE;
    L.ptype = EXR_PIXEL_FLOAT;
    L.names = rgb;
    L.nch = 3;
    L.disp = box(-4, -3, 30, 20);
    L.dw = box(2, 1, 19, 17);
    check_exr_layout(&L, "offset_dw.exr");

    /* Overscan: data window larger than the display window (cropped on read), RLE. */
    L.comp = EXR_COMPRESSION_RLE;
    L.ptype = EXR_PIXEL_HALF;
    L.disp = box(0, 0, 15, 11);
    L.dw = box(-5, -6, 22, 40);
    check_exr_layout(&L, "overscan.exr");

    /* Tiled half, ZIP, partial edge tiles. */
    L.storage = EXR_STORAGE_TILED;
    L.comp = EXR_COMPRESSION_ZIP;
    L.dw = L.disp = box(0, 0, 20, 13);
    check_exr_layout(&L, "tiled.exr");
    L.disp = box(0, 0, 25, 12);
    L.dw = box(3, -2, 23, 11);
    check_exr_layout(&L, "tiled_offset.exr");

    /* Luminance only: Y replicated to grey. */
    L.storage = EXR_STORAGE_SCANLINE;
    L.comp = EXR_COMPRESSION_ZIPS;
    L.names = y;
    L.nch = 1;
    L.dw = L.disp = box(0, 0, 9, 6);
    check_exr_layout(&L, "luma.exr");
}

static void test_exr_read_errors(void **state)
{
    static const char *const ga[] = {"G", "A"};
    char path[PATHLEN], err[512] = "";
    image img;
    exr_layout L;
    (void)state;

    tpath(path, "missing.exr");
    assert_int_equal(image_read_exr(path, &img, err, sizeof err), -1);
    assert_null(img.rgb);
    assert_non_null(strstr(err, path));

    tpath(path, "garbage.exr");
    write_text(path, "this is not an OpenEXR file at all, just some text\n");
    err[0] = '\0';
    assert_int_equal(image_read_exr(path, &img, err, sizeof err), -1);
    assert_null(img.rgb);
    assert_non_null(strstr(err, path));

    /* A truncated file (a render that died half way without our temp+rename). */
    {
        image a;
        char src[PATHLEN];
        FILE *in, *out;
        long size;
        char *bytes;
        make_image(&a, 40, 40);
        for (size_t i = 0; i < 40 * 40 * 3; i++)
            a.rgb[i] = (float)(i % 13) * 0.37f;
        tpath(src, "whole.exr");
        assert_int_equal(image_write(&a, src, err, sizeof err), 0);
        image_free(&a);
        in = fopen(src, "rb");
        assert_non_null(in);
        assert_int_equal(fseek(in, 0, SEEK_END), 0);
        size = ftell(in);
        rewind(in);
        bytes = malloc((size_t)size);
        assert_non_null(bytes);
        assert_int_equal(fread(bytes, 1, (size_t)size, in), (size_t)size);
        fclose(in);
        tpath(path, "truncated.exr");
        out = fopen(path, "wb");
        assert_non_null(out);
        assert_int_equal(fwrite(bytes, 1, (size_t)size * 2 / 3, out), (size_t)size * 2 / 3);
        assert_int_equal(fclose(out), 0);
        free(bytes);
        err[0] = '\0';
        assert_int_equal(image_read_exr(path, &img, err, sizeof err), -1);
        assert_null(img.rgb);
        assert_non_null(strstr(err, path));
    }

    /* Missing channels: the message lists what the file has. */
    memset(&L, 0, sizeof L);
    L.storage = EXR_STORAGE_SCANLINE;
    L.comp = EXR_COMPRESSION_NONE;
    L.ptype = EXR_PIXEL_HALF;
    L.names = ga;
    L.nch = 2;
    L.dw = L.disp = box(0, 0, 3, 3);
    tpath(path, "ga.exr");
    write_exr_layout(path, &L);
    err[0] = '\0';
    assert_int_equal(image_read_exr(path, &img, err, sizeof err), -1);
    assert_null(img.rgb);
    assert_non_null(strstr(err, "A G"));
}

/* ------------------------------------------------------------------------------------ */
/* PNG                                                                                   */

/* Writes a PNG with libpng directly: `data` holds h rows of `rowbytes` packed samples as
 * libpng wants them (16-bit big-endian). Returns 0 or -1. Nothing is modified after setjmp. */
static int write_png_raw(const char *path, int w, int h, int depth, int ctype,
                         const unsigned char *data, size_t rowbytes, const png_color *palette,
                         int npal)
{
    FILE *f = fopen(path, "wb");
    png_structp png;
    png_infop info;
    if (!f)
        return -1;
    png = png_create_write_struct(PNG_LIBPNG_VER_STRING, NULL, NULL, NULL);
    info = png ? png_create_info_struct(png) : NULL;
    if (!png || !info) {
        png_destroy_write_struct(&png, &info);
        fclose(f);
        return -1;
    }
    if (setjmp(png_jmpbuf(png))) {
        png_destroy_write_struct(&png, &info);
        fclose(f);
        return -1;
    }
    png_init_io(png, f);
    png_set_IHDR(png, info, (png_uint_32)w, (png_uint_32)h, depth, ctype, PNG_INTERLACE_NONE,
                 PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
    if (palette)
        png_set_PLTE(png, info, palette, npal);
    png_write_info(png, info);
    for (int y = 0; y < h; y++)
        png_write_row(png, data + (size_t)y * rowbytes);
    png_write_end(png, info);
    png_destroy_write_struct(&png, &info);
    return fclose(f) == 0 ? 0 : -1;
}

static void test_png_known_encodings(void **state)
{
    /* linear value -> expected 8-bit sRGB code */
    static const struct {
        float v;
        int code;
    } cases[] = {
        {0.0f, 0},        {1.0f, 255},    {0.5f, 188},  {0.0031308f, 10},
        {0.0031309f, 10}, {0.00154f, 5},  {0.2f, 124},  {0.18f, 118},
        {0.001f, 3},      {2.0f, 255},    {-1.0f, 0},   {1e30f, 255},
        {-0.0f, 0},       {0.9999f, 255}, {0.0001f, 0}, {0.00025f, 1},
    };
    const int n = (int)(sizeof cases / sizeof cases[0]);
    char path[PATHLEN], err[512] = "", bytes[65536];
    image a, b;
    size_t nb;
    int found_srgb = 0;
    (void)state;

    make_image(&a, n, 2);
    for (int i = 0; i < n; i++) {
        set_px(&a, i, 0, cases[i].v, cases[i].v, cases[i].v);
        set_px(&a, i, 1, NAN, cases[i].v, -INFINITY); /* NaN -> 0, -inf -> 0 */
    }
    tpath(path, "codes.png");
    assert_int_equal(image_write(&a, path, err, sizeof err), 0);
    assert_int_equal(image_read_png(path, 0, &b, err, sizeof err), 0);
    assert_int_equal(b.width, n);
    assert_int_equal(b.height, 2);
    for (int i = 0; i < n; i++) {
        int want = cases[i].code;
        /* The table agrees with the reference formula. */
        double x = cases[i].v < 0 ? 0 : cases[i].v > 1 ? 1 : cases[i].v;
        assert_int_equal((int)floor(ref_encode(x) * 255.0 + 0.5), want);
        for (int c = 0; c < 3; c++) {
            int got = (int)lround(px(&b, i, 0)[c] * 255.0);
            if (got != want)
                fail_msg("linear %g: code %d, want %d", (double)cases[i].v, got, want);
        }
        assert_int_equal((int)lround(px(&b, i, 1)[0] * 255.0), 0);
        assert_int_equal((int)lround(px(&b, i, 1)[1] * 255.0), want);
        assert_int_equal((int)lround(px(&b, i, 1)[2] * 255.0), 0);
    }
    image_free(&b);

    /* Decoding 8-bit sRGB: code 188 -> ref_decode(188/255). */
    assert_int_equal(image_read_png(path, 1, &b, err, sizeof err), 0);
    assert_float_equal(px(&b, 2, 0)[0], ref_decode(188 / 255.0), 1e-6);
    assert_float_equal(px(&b, 1, 0)[1], 1.0, 1e-6);
    assert_float_equal(px(&b, 0, 0)[2], 0.0, 1e-9);
    image_free(&b);

    /* The file carries an sRGB chunk (before IDAT). */
    nb = read_bytes(path, bytes, sizeof bytes);
    for (size_t i = 0; i + 4 <= nb; i++) {
        if (memcmp(bytes + i, "IDAT", 4) == 0)
            break;
        if (memcmp(bytes + i, "sRGB", 4) == 0)
            found_srgb = 1;
    }
    assert_true(found_srgb);
    image_free(&a);
}

static void test_png_roundtrip(void **state)
{
    const int w = 64, h = 33;
    char path[PATHLEN], err[512] = "";
    image a, b, c;
    (void)state;

    make_image(&a, w, h);
    for (size_t i = 0; i < (size_t)w * h * 3; i++)
        a.rgb[i] = (float)((i * 2654435761u) % 100003u) / 100002.0f; /* spread over [0,1] */
    a.rgb[0] = 0.0f;
    a.rgb[1] = 1.0f;
    tpath(path, "round.PNG");
    assert_int_equal(image_write(&a, path, err, sizeof err), 0);
    assert_int_equal(image_read_png(path, 1, &b, err, sizeof err), 0);
    assert_int_equal(image_read_png(path, 0, &c, err, sizeof err), 0);
    assert_int_equal(b.width, w);
    assert_int_equal(b.height, h);
    for (size_t i = 0; i < (size_t)w * h * 3; i++) {
        double want_enc = ref_encode(a.rgb[i]);
        /* In the encoded domain: within half a code (rounded to nearest)... */
        assert_float_equal(c.rgb[i], want_enc, 0.5 / 255.0 + 1e-6);
        /* ...re-encoding the decoded value lands within 1/255 of the original... */
        assert_float_equal(ref_encode(b.rgb[i]), want_enc, 1.0 / 255.0);
        /* ...and linear values are within half a code times the steepest slope (~2.3). */
        assert_float_equal(b.rgb[i], a.rgb[i], 0.0045);
    }
    assert_true(b.rgb[0] == 0.0f);
    assert_true(b.rgb[1] == 1.0f);
    image_free(&a);
    image_free(&b);
    image_free(&c);
}

/* --png16: the file says 16 bits, every value comes back within half of 1/65535 in the
 * encoded domain (8 bits could not: 1/510), exposure and tone map applied, and rows over
 * several compressed pieces. */
static void test_png16_roundtrip(void **state)
{
    const int w = 301, h = 250; /* 301 * 6 + 1 bytes a row: 36 rows a piece, 7 pieces */
    char path[PATHLEN], err[512] = "";
    unsigned char head[32];
    image a, b, c;
    image_write_opts o;
    FILE *f;
    int k;
    (void)state;

    make_image(&a, w, h);
    for (size_t i = 0; i < (size_t)w * h * 3; i++)
        a.rgb[i] = (float)((i * 2654435761u) % 1000003u) / 1000002.0f; /* spread over [0,1] */
    a.rgb[0] = 0.0f;
    a.rgb[1] = 1.0f;
    for (k = 0; k < 2; k++) {
        image_write_opts_default(&o);
        o.png16 = 1;
        o.exposure = k ? 0.5 : 0.0;
        o.tonemap = k ? IMAGE_TONEMAP_REINHARD : IMAGE_TONEMAP_CLAMP;
        tpath(path, "round16.png");
        assert_int_equal(image_write_ex(&a, path, &o, err, sizeof err), 0);
        f = fopen(path, "rb");
        assert_non_null(f);
        assert_int_equal(fread(head, 1, sizeof head, f), sizeof head);
        fclose(f);
        assert_int_equal(head[24], 16); /* IHDR bit depth */
        assert_int_equal(head[25], 2);  /* RGB */
        assert_int_equal(image_read_png(path, 1, &b, err, sizeof err), 0);
        assert_int_equal(image_read_png(path, 0, &c, err, sizeof err), 0);
        assert_int_equal(b.width, w);
        assert_int_equal(b.height, h);
        for (size_t i = 0; i < (size_t)w * h * 3; i++) {
            double d = a.rgb[i] * pow(2.0, o.exposure);
            double want_enc = ref_encode(k ? d / (1.0 + d) : d > 1 ? 1 : d);
            assert_float_equal(c.rgb[i], want_enc, 0.5 / 65535.0 + 1e-7);
            if (!k) /* linear values within half a code times the steepest slope (~2.3) */
                assert_float_equal(b.rgb[i], a.rgb[i], 1.8e-5);
        }
        if (!k) {
            assert_true(b.rgb[0] == 0.0f);
            assert_true(b.rgb[1] == 1.0f);
        }
        image_free(&b);
        image_free(&c);
    }
    image_free(&a);
}

static void test_png_16bit_read(void **state)
{
    enum { W = 7, H = 5 };
    static const unsigned short special[] = {0, 65535, 1, 0x0102, 0x1234, 0xfeff, 32768, 257};
    unsigned char data[H * W * 3 * 2], grey[H * W * 2 * 2];
    unsigned short val[H * W * 3];
    char path[PATHLEN], err[512] = "";
    image img;
    (void)state;

    for (int i = 0; i < H * W * 3; i++) {
        unsigned short v = i < 8 ? special[i] : (unsigned short)((i * 40503u) & 0xffff);
        val[i] = v;
        data[2 * i] = (unsigned char)(v >> 8); /* PNG is big-endian */
        data[2 * i + 1] = (unsigned char)(v & 0xff);
    }
    tpath(path, "sixteen.png");
    assert_int_equal(write_png_raw(path, W, H, 16, PNG_COLOR_TYPE_RGB, data, W * 6, NULL, 0), 0);
    assert_int_equal(image_read_png(path, 0, &img, err, sizeof err), 0);
    assert_int_equal(img.width, W);
    assert_int_equal(img.height, H);
    for (int i = 0; i < H * W * 3; i++)
        assert_float_equal(img.rgb[i], val[i] / 65535.0, 0.5 / 65535.0);
    image_free(&img);

    /* sRGB decode of 16-bit values uses the full precision. */
    assert_int_equal(image_read_png(path, 1, &img, err, sizeof err), 0);
    for (int i = 0; i < H * W * 3; i++)
        assert_float_equal(img.rgb[i], ref_decode(val[i] / 65535.0), 1e-6);
    image_free(&img);

    /* 16-bit grey + alpha: grey replicated, alpha dropped, 16-bit precision kept. */
    for (int i = 0; i < H * W; i++) {
        unsigned short g = val[i], al = (unsigned short)(0xffff - val[i]);
        grey[4 * i] = (unsigned char)(g >> 8);
        grey[4 * i + 1] = (unsigned char)(g & 0xff);
        grey[4 * i + 2] = (unsigned char)(al >> 8);
        grey[4 * i + 3] = (unsigned char)(al & 0xff);
    }
    tpath(path, "grey16.png");
    assert_int_equal(write_png_raw(path, W, H, 16, PNG_COLOR_TYPE_GRAY_ALPHA, grey, W * 4, NULL, 0),
                     0);
    assert_int_equal(image_read_png(path, 0, &img, err, sizeof err), 0);
    for (int i = 0; i < H * W; i++)
        for (int c = 0; c < 3; c++)
            assert_float_equal(img.rgb[i * 3 + c], val[i] / 65535.0, 0.5 / 65535.0);
    image_free(&img);
}

static void test_png_other_formats(void **state)
{
    static const png_color pal[4] = {{0, 0, 0}, {255, 0, 0}, {10, 128, 250}, {255, 255, 255}};
    unsigned char idx[2 * 1] = {0x1b, 0xe4}; /* 2-bit indices: 0 1 2 3 / 3 2 1 0 */
    unsigned char g8[2 * 3] = {0, 128, 255, 7, 8, 9};
    char path[PATHLEN], err[512] = "";
    image img;
    (void)state;

    tpath(path, "palette.png");
    assert_int_equal(write_png_raw(path, 4, 2, 2, PNG_COLOR_TYPE_PALETTE, idx, 1, pal, 4), 0);
    assert_int_equal(image_read_png(path, 0, &img, err, sizeof err), 0);
    assert_int_equal(img.width, 4);
    assert_int_equal(img.height, 2);
    for (int x = 0; x < 4; x++) {
        const png_color *p0 = &pal[x], *p1 = &pal[3 - x];
        assert_float_equal(px(&img, x, 0)[0], p0->red / 255.0, 1e-7);
        assert_float_equal(px(&img, x, 0)[1], p0->green / 255.0, 1e-7);
        assert_float_equal(px(&img, x, 0)[2], p0->blue / 255.0, 1e-7);
        assert_float_equal(px(&img, x, 1)[2], p1->blue / 255.0, 1e-7);
    }
    image_free(&img);

    tpath(path, "grey8.png");
    assert_int_equal(write_png_raw(path, 3, 2, 8, PNG_COLOR_TYPE_GRAY, g8, 3, NULL, 0), 0);
    assert_int_equal(image_read_png(path, 0, &img, err, sizeof err), 0);
    for (int i = 0; i < 6; i++)
        for (int c = 0; c < 3; c++)
            assert_float_equal(img.rgb[i * 3 + c], g8[i] / 255.0, 1e-7);
    image_free(&img);

    /* Not a PNG, and a missing file. */
    tpath(path, "text.png");
    write_text(path, "hello");
    assert_int_equal(image_read_png(path, 0, &img, err, sizeof err), -1);
    assert_null(img.rgb);
    assert_non_null(strstr(err, path));
    tpath(path, "absent.png");
    assert_int_equal(image_read_png(path, 0, &img, err, sizeof err), -1);
    assert_non_null(strstr(err, "No such file"));
}

/* ------------------------------------------------------------------------------------ */
/* Temporary file + rename                                                               */

static void test_write_is_atomic(void **state)
{
    char path[PATHLEN], dir[PATHLEN], err[512], buf[256];
    image img, back;
    (void)state;
    make_image(&img, 4, 3);
    set_px(&img, 1, 1, 0.5f, 1.0f, 2.0f);

    /* A folder that does not exist: error with the reason, nothing created. */
    tpath(dir, "no-such-dir");
    tpath(path, "no-such-dir/out.exr");
    err[0] = '\0';
    assert_int_equal(image_write(&img, path, err, sizeof err), -1);
    assert_non_null(strstr(err, path));
    assert_non_null(strstr(err, strerror(ENOENT)));
    assert_false(file_exists(dir));
    tpath(path, "no-such-dir/out.png");
    err[0] = '\0';
    assert_int_equal(image_write(&img, path, err, sizeof err), -1);
    assert_non_null(strstr(err, strerror(ENOENT)));
    assert_false(file_exists(dir));

    /* A bad extension over an existing file: error naming the accepted ones, old intact. */
    tpath(path, "old.tif");
    write_text(path, "old contents");
    err[0] = '\0';
    assert_int_equal(image_write(&img, path, err, sizeof err), -1);
    assert_non_null(strstr(err, path));
    assert_non_null(strstr(err, ".exr"));
    assert_non_null(strstr(err, ".png"));
    read_bytes(path, buf, sizeof buf);
    assert_string_equal(buf, "old contents");
    tpath(path, "noext");
    assert_int_equal(image_write(&img, path, err, sizeof err), -1);
    assert_false(file_exists(path));

    /* Failing after the data was written (rename over a directory): the temporary file is
     * removed and the target is untouched. */
    tpath(path, "adir.exr");
    assert_int_equal(mkdir(path, 0755), 0);
    err[0] = '\0';
    assert_int_equal(image_write(&img, path, err, sizeof err), -1);
    assert_non_null(strstr(err, "rename"));
    tpath(path, "adir.png");
    assert_int_equal(mkdir(path, 0755), 0);
    assert_int_equal(image_write(&img, path, err, sizeof err), -1);
    assert_non_null(strstr(err, "rename"));

    /* An invalid image over an existing good file: old file intact and readable. */
    tpath(path, "keep.exr");
    assert_int_equal(image_write(&img, path, err, sizeof err), 0);
    {
        image empty = {0, 0, NULL};
        assert_int_equal(image_write(&empty, path, err, sizeof err), -1);
        assert_int_equal(image_write_png(&empty, path, err, sizeof err), -1);
    }
    assert_int_equal(image_read_exr(path, &back, err, sizeof err), 0);
    assert_memory_equal(back.rgb, img.rgb, 4 * 3 * 3 * sizeof(float));
    image_free(&back);

    /* A successful write replaces an existing file (and gets ordinary permissions). */
    tpath(path, "replace.png");
    write_text(path, "stale");
    assert_int_equal(image_write(&img, path, err, sizeof err), 0);
    assert_int_equal(image_read_png(path, 0, &back, err, sizeof err), 0);
    assert_int_equal(back.width, 4);
    assert_int_equal(back.height, 3);
    image_free(&back);
    {
        struct stat sb;
        assert_int_equal(stat(path, &sb), 0);
        assert_true((sb.st_mode & 0444) != 0 && (sb.st_mode & S_IRGRP));
    }

    assert_int_equal(count_tmp_leftovers(), 0);
    image_free(&img);
}

/* ------------------------------------------------------------------------------------ */
/* Comparison and diff images                                                            */

/* 4x3 pair: a is 0.5 everywhere; b differs at a few pixels. */
static void make_pair(image *a, image *b)
{
    make_image(a, 4, 3);
    make_image(b, 4, 3);
    for (size_t i = 0; i < 4 * 3 * 3; i++)
        a->rgb[i] = b->rgb[i] = 0.5f;
    px(b, 1, 0)[0] = 0.75f;      /* diff 0.25 in R */
    px(b, 2, 1)[1] = 0.4375f;    /* diff 0.0625 in G */
    px(b, 3, 2)[2] = 1.5f;       /* diff 1.0 in B: the worst */
    px(b, 0, 2)[0] = 0.5078125f; /* diff 1/128, under tol */
}

static void test_compare(void **state)
{
    image a, b, c;
    image_diff_stats st;
    unsigned char mask[12];
    (void)state;
    make_pair(&a, &b);

    assert_int_equal(image_compare(&a, &b, NULL, 0.05, &st), 0);
    assert_int_equal(st.compared, 12);
    assert_int_equal(st.over, 3);
    assert_float_equal(st.max_abs, 1.0, 1e-12);
    assert_int_equal(st.worst_x, 3);
    assert_int_equal(st.worst_y, 2);
    assert_float_equal(st.mean_abs, (0.25 + 0.0625 + 1.0 + 1.0 / 128) / 36.0, 1e-12);

    /* Tolerance is exclusive: a difference equal to tol is not over. */
    assert_int_equal(image_compare(&a, &b, NULL, 0.25, &st), 0);
    assert_int_equal(st.over, 1);

    /* Mask out the worst pixel and one of the others. */
    memset(mask, 1, sizeof mask);
    mask[2 * 4 + 3] = 0; /* (3,2) */
    mask[0 * 4 + 1] = 0; /* (1,0) */
    assert_int_equal(image_compare(&a, &b, mask, 0.05, &st), 0);
    assert_int_equal(st.compared, 10);
    assert_int_equal(st.over, 1);
    assert_float_equal(st.max_abs, 0.0625, 1e-12);
    assert_int_equal(st.worst_x, 2);
    assert_int_equal(st.worst_y, 1);
    assert_float_equal(st.mean_abs, (0.0625 + 1.0 / 128) / 30.0, 1e-12);

    /* Identical images. */
    assert_int_equal(image_compare(&a, &a, NULL, 0.0, &st), 0);
    assert_int_equal(st.over, 0);
    assert_true(st.max_abs == 0.0 && st.mean_abs == 0.0);

    /* A NaN against a number is a difference; NaN against NaN is not. */
    px(&b, 0, 0)[1] = NAN;
    assert_int_equal(image_compare(&a, &b, NULL, 10.0, &st), 0);
    assert_int_equal(st.over, 1);
    assert_int_equal(st.worst_x, 0);
    assert_int_equal(st.worst_y, 0);
    assert_int_equal(image_compare(&b, &b, NULL, 0.0, &st), 0);
    assert_int_equal(st.over, 0);

    /* Size mismatch. */
    make_image(&c, 3, 4);
    assert_int_equal(image_compare(&a, &c, NULL, 0.1, &st), -1);
    image_free(&a);
    image_free(&b);
    image_free(&c);
}

static void test_write_diff(void **state)
{
    image a, b, c, d;
    unsigned char mask[12];
    char path[PATHLEN], err[512] = "";
    (void)state;
    make_pair(&a, &b);
    set_px(&a, 0, 1, 0.8f, 0.8f, 0.8f); /* masked-out pixel: grey 0.25 * 0.8 */
    set_px(&b, 0, 1, 0.1f, 0.1f, 0.1f); /* a big difference, but masked */
    memset(mask, 1, sizeof mask);
    mask[1 * 4 + 0] = 0; /* (0,1) */

    tpath(path, "diff.exr");
    assert_int_equal(image_write_diff(&a, &b, mask, 0.1, 4.0, path, err, sizeof err), 0);
    assert_int_equal(image_read_exr(path, &d, err, sizeof err), 0);
    assert_int_equal(d.width, 4);
    assert_int_equal(d.height, 3);
    /* Over tol (0.25 R, 1.0 B): pure red. */
    assert_true(px(&d, 1, 0)[0] == 1.0f && px(&d, 1, 0)[1] == 0.0f && px(&d, 1, 0)[2] == 0.0f);
    assert_true(px(&d, 3, 2)[0] == 1.0f && px(&d, 3, 2)[1] == 0.0f && px(&d, 3, 2)[2] == 0.0f);
    /* Under tol: |a-b| * gain per channel. */
    assert_float_equal(px(&d, 2, 1)[0], 0.0, 1e-7);
    assert_float_equal(px(&d, 2, 1)[1], 0.0625 * 4.0, 1e-7);
    assert_float_equal(px(&d, 0, 2)[0], 4.0 / 128, 1e-7);
    /* Identical: black. */
    assert_true(px(&d, 3, 0)[0] == 0.0f && px(&d, 3, 0)[1] == 0.0f && px(&d, 3, 0)[2] == 0.0f);
    /* Masked out: dimmed grey of a. */
    for (int k = 0; k < 3; k++)
        assert_float_equal(px(&d, 0, 1)[k], 0.25 * 0.8, 1e-6);
    image_free(&d);

    /* Gain large enough to clamp. */
    assert_int_equal(image_write_diff(&a, &b, NULL, 0.1, 100.0, path, err, sizeof err), 0);
    assert_int_equal(image_read_exr(path, &d, err, sizeof err), 0);
    assert_true(px(&d, 2, 1)[1] == 1.0f);
    assert_true(px(&d, 0, 1)[0] == 1.0f && px(&d, 0, 1)[1] == 0.0f); /* now compared: red */
    image_free(&d);

    /* PNG works too. */
    tpath(path, "diff.png");
    assert_int_equal(image_write_diff(&a, &b, mask, 0.1, 4.0, path, err, sizeof err), 0);
    assert_int_equal(image_read_png(path, 1, &d, err, sizeof err), 0);
    assert_int_equal(d.width, 4);
    assert_int_equal(d.height, 3);
    assert_float_equal(px(&d, 1, 0)[0], 1.0, 1e-6);
    assert_float_equal(px(&d, 1, 0)[1], 0.0, 1e-6);
    assert_float_equal(px(&d, 0, 1)[1], 0.2, 0.004);
    image_free(&d);

    /* Size mismatch: an error, no file. */
    make_image(&c, 2, 2);
    tpath(path, "diff-bad.png");
    err[0] = '\0';
    assert_int_equal(image_write_diff(&a, &c, NULL, 0.1, 1.0, path, err, sizeof err), -1);
    assert_true(err[0] != '\0');
    assert_false(file_exists(path));
    image_free(&a);
    image_free(&b);
    image_free(&c);
    assert_int_equal(count_tmp_leftovers(), 0);
}

/* ------------------------------------------------------------------------------------ */
/* Write options: exposure, tone mapping, half floats, metadata                         */

static double ref_tonemap(double x, int tonemap)
{
    if (tonemap == IMAGE_TONEMAP_REINHARD)
        x = x / (1.0 + x);
    else if (tonemap == IMAGE_TONEMAP_ACES)
        x = x * (2.51 * x + 0.03) / (x * (2.43 * x + 0.59) + 0.14);
    return x < 0 ? 0 : x > 1 ? 1 : x;
}

static void test_display_values(void **state)
{
    (void)state;
    /* exposure: times 2^EV, then the curve */
    assert_float_equal(image_display_value(0.25, 1.0, IMAGE_TONEMAP_CLAMP), 0.5, 1e-12);
    assert_float_equal(image_display_value(1.0, -1.0, IMAGE_TONEMAP_CLAMP), 0.5, 1e-12);
    assert_float_equal(image_display_value(0.3, 0.5, IMAGE_TONEMAP_CLAMP), 0.3 * sqrt(2.0), 1e-12);
    assert_float_equal(image_display_value(2.0, 0.0, IMAGE_TONEMAP_CLAMP), 1.0, 0);
    /* reinhard: c / (1 + c) */
    assert_float_equal(image_display_value(1.0, 0.0, IMAGE_TONEMAP_REINHARD), 0.5, 1e-12);
    assert_float_equal(image_display_value(3.0, 0.0, IMAGE_TONEMAP_REINHARD), 0.75, 1e-12);
    assert_float_equal(image_display_value(1.5, 1.0, IMAGE_TONEMAP_REINHARD), 0.75, 1e-12);
    assert_float_equal(image_display_value(1e30, 0.0, IMAGE_TONEMAP_REINHARD), 1.0, 1e-12);
    /* aces: x(2.51x + 0.03) / (x(2.43x + 0.59) + 0.14), clamped */
    assert_float_equal(image_display_value(1.0, 0.0, IMAGE_TONEMAP_ACES), 2.54 / 3.16, 1e-12);
    assert_float_equal(image_display_value(0.18, 0.0, IMAGE_TONEMAP_ACES),
                       0.18 * (2.51 * 0.18 + 0.03) / (0.18 * (2.43 * 0.18 + 0.59) + 0.14), 1e-12);
    assert_float_equal(image_display_value(100.0, 0.0, IMAGE_TONEMAP_ACES), 1.0, 0);
    /* every curve: NaN and negatives are 0, infinity is 1 */
    for (int tm = IMAGE_TONEMAP_CLAMP; tm <= IMAGE_TONEMAP_ACES; tm++) {
        assert_float_equal(image_display_value(NAN, 0.0, tm), 0.0, 0);
        assert_float_equal(image_display_value(-1.0, 2.0, tm), 0.0, 0);
        assert_float_equal(image_display_value(0.0, 2.0, tm), 0.0, 0);
        assert_float_equal(image_display_value(INFINITY, 0.0, tm), 1.0, 0);
    }
    /* names */
    assert_int_equal(image_tonemap_parse("clamp"), IMAGE_TONEMAP_CLAMP);
    assert_int_equal(image_tonemap_parse("reinhard"), IMAGE_TONEMAP_REINHARD);
    assert_int_equal(image_tonemap_parse("aces"), IMAGE_TONEMAP_ACES);
    assert_int_equal(image_tonemap_parse("Reinhard"), -1);
    assert_int_equal(image_tonemap_parse(""), -1);
    assert_string_equal(image_tonemap_name(IMAGE_TONEMAP_REINHARD), "reinhard");
    assert_string_equal(image_tonemap_name(IMAGE_TONEMAP_ACES), "aces");
    assert_string_equal(image_tonemap_name(IMAGE_TONEMAP_CLAMP), "clamp");
}

/* The stored PNG bytes follow the formulas: round(255 * srgb(curve(x * 2^EV))). */
static void test_png_exposure_tonemap(void **state)
{
    static const float values[] = {0.0f, 0.01f, 0.1f, 0.18f, 0.25f, 0.5f, 1.0f, 2.0f, 4.0f, 16.0f};
    const int n = (int)(sizeof values / sizeof values[0]);
    const double evs[] = {0.0, 1.0, -1.5};
    char path[PATHLEN], err[512] = "";
    image a, b, c;
    image_write_opts o;
    (void)state;

    make_image(&a, n, 1);
    for (int i = 0; i < n; i++)
        set_px(&a, i, 0, values[i], values[i] * 0.5f, values[i] * 0.25f);
    tpath(path, "tonemap.png");
    for (int tm = IMAGE_TONEMAP_CLAMP; tm <= IMAGE_TONEMAP_ACES; tm++) {
        for (size_t e = 0; e < sizeof evs / sizeof evs[0]; e++) {
            image_write_opts_default(&o);
            o.exposure = evs[e];
            o.tonemap = tm;
            assert_int_equal(image_write_ex(&a, path, &o, err, sizeof err), 0);
            assert_int_equal(image_read_png(path, 0, &b, err, sizeof err), 0);
            for (int i = 0; i < n * 3; i++) {
                double want =
                    floor(ref_encode(ref_tonemap(a.rgb[i] * pow(2.0, evs[e]), tm)) * 255.0 + 0.5);
                if (fabs(b.rgb[i] * 255.0 - want) > 1e-3)
                    fail_msg("tonemap %d, EV %g, value %g: stored %g, expected %g", tm, evs[e],
                             (double)a.rgb[i], b.rgb[i] * 255.0, want);
            }
            image_free(&b);
        }
    }
    /* the defaults are the plain writer's: clamp at exposure 0 */
    tpath(path, "plain.png");
    assert_int_equal(image_write(&a, path, err, sizeof err), 0);
    assert_int_equal(image_read_png(path, 0, &b, err, sizeof err), 0);
    tpath(path, "defaults.png");
    assert_int_equal(image_write_ex(&a, path, NULL, err, sizeof err), 0);
    assert_int_equal(image_read_png(path, 0, &c, err, sizeof err), 0);
    assert_memory_equal(b.rgb, c.rgb, (size_t)n * 3 * sizeof(float));
    image_free(&b);
    image_free(&c);
    /* EXR ignores exposure and tone mapping: the linear values stay */
    image_write_opts_default(&o);
    o.exposure = 3;
    o.tonemap = IMAGE_TONEMAP_REINHARD;
    tpath(path, "linear.exr");
    assert_int_equal(image_write_ex(&a, path, &o, err, sizeof err), 0);
    assert_int_equal(image_read_exr(path, &b, err, sizeof err), 0);
    assert_memory_equal(a.rgb, b.rgb, (size_t)n * 3 * sizeof(float));
    image_free(&b);
    image_free(&a);
}

/* Pixel type of every channel of part 0. */
static exr_pixel_type_t exr_channel_type(const char *path)
{
    exr_context_t ctx = NULL;
    exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
    const exr_attr_chlist_t *chl = NULL;
    exr_pixel_type_t t;
    assert_int_equal(exr_start_read(&ctx, path, &init), EXR_ERR_SUCCESS);
    assert_int_equal(exr_get_channels(ctx, 0, &chl), EXR_ERR_SUCCESS);
    assert_int_equal(chl->num_channels, 3);
    t = chl->entries[0].pixel_type;
    for (int c = 1; c < chl->num_channels; c++)
        assert_int_equal(chl->entries[c].pixel_type, t);
    exr_finish(&ctx);
    return t;
}

static void test_exr_half(void **state)
{
    /* value, and what it must read back as (rounded to nearest even half) */
    static const struct {
        float in, out;
    } exact[] = {
        {1.0f, 1.0f},
        {-2.5f, -2.5f},
        {0.1f, 0.0999755859375f},
        {1.0f / 3.0f, 0.333251953125f},
        {2049.0f, 2048.0f},                               /* tie: to the even 2048 */
        {2051.0f, 2052.0f},                               /* tie: to the even 2052 */
        {65504.0f, 65504.0f},                             /* the largest half */
        {65519.0f, 65504.0f},                             /* below the tie with infinity */
        {5.9604644775390625e-8f, 5.9604644775390625e-8f}, /* 2^-24: the smallest subnormal */
        {2.98023223876953125e-8f, 0.0f},                  /* 2^-25: a tie, to the even 0 */
        {4.470348358154297e-8f, 5.9604644775390625e-8f},  /* 1.5 * 2^-25: up */
        {6.103515625e-5f, 6.103515625e-5f},               /* 2^-14: the smallest normal */
        {0.0f, 0.0f},
    };
    const int ne = (int)(sizeof exact / sizeof exact[0]);
    const int w = 29, h = 37; /* several chunks, the last partial */
    char path[PATHLEN], err[512] = "";
    image a, b;
    image_write_opts o;
    (void)state;

    make_image(&a, w, h);
    for (size_t i = 0; i < (size_t)w * h * 3; i++)
        a.rgb[i] = (float)((double)(i * 7919 % 100003) / 1000.0 - 20.0); /* -20..80 */
    for (int k = 0; k < ne; k++)
        a.rgb[k] = exact[k].in;
    a.rgb[ne] = 65520.0f; /* the tie with infinity: to infinity */
    a.rgb[ne + 1] = 1e6f;
    a.rgb[ne + 2] = -1e6f;
    a.rgb[ne + 3] = NAN;
    image_write_opts_default(&o);
    o.half = 1;
    tpath(path, "half.exr");
    assert_int_equal(image_write_ex(&a, path, &o, err, sizeof err), 0);
    assert_int_equal(exr_channel_type(path), EXR_PIXEL_HALF);
    assert_int_equal(image_read_exr(path, &b, err, sizeof err), 0);
    assert_int_equal(b.width, w);
    assert_int_equal(b.height, h);
    for (int k = 0; k < ne; k++)
        if (b.rgb[k] != exact[k].out)
            fail_msg("half of %.9g read back as %.9g, expected %.9g", (double)exact[k].in,
                     (double)b.rgb[k], (double)exact[k].out);
    assert_true(isinf(b.rgb[ne]) && b.rgb[ne] > 0);
    assert_true(isinf(b.rgb[ne + 1]) && b.rgb[ne + 1] > 0);
    assert_true(isinf(b.rgb[ne + 2]) && b.rgb[ne + 2] < 0);
    assert_true(isnan(b.rgb[ne + 3]));
    /* everything else within half precision: relative 2^-11 */
    for (size_t i = (size_t)ne + 4; i < (size_t)w * h * 3; i++) {
        double d = fabs((double)b.rgb[i] - (double)a.rgb[i]);
        if (d > fabs((double)a.rgb[i]) / 2048.0 + 1e-7)
            fail_msg("half round trip of %.9g: %.9g", (double)a.rgb[i], (double)b.rgb[i]);
    }
    image_free(&b);
    /* without --half: floats */
    tpath(path, "float.exr");
    assert_int_equal(image_write_ex(&a, path, NULL, err, sizeof err), 0);
    assert_int_equal(exr_channel_type(path), EXR_PIXEL_FLOAT);
    image_free(&a);
    assert_int_equal(count_tmp_leftovers(), 0);
}

static void fill_meta(image_write_opts *o)
{
    image_write_opts_default(o);
    o->title = "tetra.nff";
    o->software = "clwhitted 9.8.7";
    o->source = "Some Device";
    o->comment = "64x48, depth 5, spp 1, precision robust";
    o->render_s = 1.5;
}

static void test_exr_metadata(void **state)
{
    static const char *const names[] = {"scene", "software", "device", "comments"};
    char path[PATHLEN], err[512] = "";
    image a;
    image_write_opts o;
    exr_context_t ctx = NULL;
    exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
    const char *v = NULL;
    int32_t len = 0;
    float f = 0;
    (void)state;

    make_image(&a, 4, 3);
    fill_meta(&o);
    o.half = 1;
    tpath(path, "meta.exr");
    assert_int_equal(image_write_ex(&a, path, &o, err, sizeof err), 0);
    assert_int_equal(exr_start_read(&ctx, path, &init), EXR_ERR_SUCCESS);
    const char *want[] = {o.title, o.software, o.source, o.comment};
    for (int i = 0; i < 4; i++) {
        v = NULL;
        assert_int_equal(exr_attr_get_string(ctx, 0, names[i], &len, &v), EXR_ERR_SUCCESS);
        assert_non_null(v);
        assert_int_equal(len, (int32_t)strlen(want[i]));
        assert_memory_equal(v, want[i], strlen(want[i]));
    }
    assert_int_equal(exr_attr_get_float(ctx, 0, "renderTime", &f), EXR_ERR_SUCCESS);
    assert_true(f == 1.5f);
    /* capDate "YYYY:MM:DD hh:mm:ss" and a utcOffset within a day */
    assert_int_equal(exr_attr_get_string(ctx, 0, "capDate", &len, &v), EXR_ERR_SUCCESS);
    assert_int_equal(len, 19);
    assert_true(v[4] == ':' && v[7] == ':' && v[10] == ' ' && v[13] == ':' && v[16] == ':');
    assert_int_equal(exr_attr_get_float(ctx, 0, "utcOffset", &f), EXR_ERR_SUCCESS);
    assert_true(fabsf(f) <= 86400.0f);
    exr_finish(&ctx);

    /* no metadata asked for: none written */
    tpath(path, "nometa.exr");
    assert_int_equal(image_write(&a, path, err, sizeof err), 0);
    assert_int_equal(exr_start_read(&ctx, path, &init), EXR_ERR_SUCCESS);
    assert_int_not_equal(exr_attr_get_string(ctx, 0, "software", &len, &v), EXR_ERR_SUCCESS);
    assert_int_not_equal(exr_attr_get_float(ctx, 0, "renderTime", &f), EXR_ERR_SUCCESS);
    exr_finish(&ctx);
    image_free(&a);
}

/* Reads the text chunks and tIME of a PNG with libpng; returns the number of chunks. */
typedef struct {
    char key[8][80], text[8][256];
    int count, has_time;
    png_time mtime;
} png_texts;

static void read_png_texts(const char *path, png_texts *out)
{
    FILE *f = fopen(path, "rb");
    png_structp png;
    png_infop info;
    png_textp text = NULL;
    png_timep t = NULL;
    int n = 0;
    assert_non_null(f);
    png = png_create_read_struct(PNG_LIBPNG_VER_STRING, NULL, NULL, NULL);
    assert_non_null(png);
    info = png_create_info_struct(png);
    assert_non_null(info);
    if (setjmp(png_jmpbuf(png)))
        fail_msg("libpng error reading %s", path);
    png_init_io(png, f);
    png_read_png(png, info, PNG_TRANSFORM_IDENTITY, NULL);
    memset(out, 0, sizeof *out);
    png_get_text(png, info, &text, &n);
    for (int i = 0; i < n && i < 8; i++) {
        snprintf(out->key[i], sizeof out->key[i], "%s", text[i].key);
        snprintf(out->text[i], sizeof out->text[i], "%s", text[i].text);
    }
    out->count = n;
    if (png_get_tIME(png, info, &t) && t) {
        out->has_time = 1;
        out->mtime = *t;
    }
    png_destroy_read_struct(&png, &info, NULL);
    fclose(f);
}

static const char *png_text_of(const png_texts *t, const char *key)
{
    for (int i = 0; i < t->count && i < 8; i++)
        if (strcmp(t->key[i], key) == 0)
            return t->text[i];
    fail_msg("PNG text chunk '%s' missing", key);
    return NULL;
}

static void test_png_metadata(void **state)
{
    char path[PATHLEN], err[512] = "";
    image a;
    image_write_opts o;
    png_texts t;
    const char *ct;
    (void)state;

    make_image(&a, 4, 3);
    fill_meta(&o);
    o.title = "caf\xc3\xa9.json"; /* UTF-8: an iTXt chunk */
    tpath(path, "meta.png");
    assert_int_equal(image_write_ex(&a, path, &o, err, sizeof err), 0);
    read_png_texts(path, &t);
    assert_string_equal(png_text_of(&t, "Title"), o.title);
    assert_string_equal(png_text_of(&t, "Software"), "clwhitted 9.8.7");
    assert_string_equal(png_text_of(&t, "Source"), "Some Device");
    assert_string_equal(png_text_of(&t, "Comment"), o.comment);
    assert_string_equal(png_text_of(&t, "Render Time"), "1.500 s");
    ct = png_text_of(&t, "Creation Time"); /* ISO 8601, UTC: 2024-05-06T07:08:09Z */
    assert_int_equal(strlen(ct), 20);
    assert_true(ct[4] == '-' && ct[7] == '-' && ct[10] == 'T' && ct[19] == 'Z');
    assert_true(t.has_time);
    assert_true(t.mtime.year >= 2024 && t.mtime.month >= 1 && t.mtime.month <= 12);

    /* no metadata asked for: only the creation time */
    tpath(path, "nometa.png");
    assert_int_equal(image_write(&a, path, err, sizeof err), 0);
    read_png_texts(path, &t);
    assert_int_equal(t.count, 1);
    assert_string_equal(t.key[0], "Creation Time");
    image_free(&a);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_alloc),
        cmocka_unit_test(test_exr_roundtrip_exact),
        cmocka_unit_test(test_exr_read_other_layouts),
        cmocka_unit_test(test_exr_read_errors),
        cmocka_unit_test(test_png_known_encodings),
        cmocka_unit_test(test_png_roundtrip),
        cmocka_unit_test(test_png_16bit_read),
        cmocka_unit_test(test_png16_roundtrip),
        cmocka_unit_test(test_png_other_formats),
        cmocka_unit_test(test_write_is_atomic),
        cmocka_unit_test(test_compare),
        cmocka_unit_test(test_write_diff),
        cmocka_unit_test(test_display_values),
        cmocka_unit_test(test_png_exposure_tonemap),
        cmocka_unit_test(test_exr_half),
        cmocka_unit_test(test_exr_metadata),
        cmocka_unit_test(test_png_metadata),
    };
    return cmocka_run_group_tests(tests, group_setup, group_teardown);
}
