/* imgtool: small image conversions for the tools written in other languages (the quality
 * report reads clwhitted's EXR output through it).
 *   imgtool raw IN OUT       IN (.exr linear, .png sRGB-decoded) to OUT: the linear RGB
 *                            values as float32 in the machine's byte order, row 0 at the top,
 *                            width*height*3 values; prints "WIDTH HEIGHT" on stdout
 *   imgtool convert IN OUT   IN to OUT (.exr or .png, as clwhitted writes them) */
#include <stdio.h>
#include <string.h>

#include "image.h"
#include "image_read.h"
#include "sys.h"

static void usage(FILE *f)
{
    fprintf(f, "usage: imgtool raw IN OUT       write IN's linear RGB as raw float32 to OUT\n"
               "                                (OUT '-' for standard output); prints\n"
               "                                'WIDTH HEIGHT' on stdout (stderr for '-')\n"
               "       imgtool convert IN OUT   convert IN to OUT (.exr or .png)\n"
               "IN: .exr (linear values) or .png (decoded from sRGB).\n"
               "Exit status: 0 success, 1 input or output error, 2 usage error.\n");
}

static int read_any(const char *path, image *img, char *err, size_t errlen)
{
    if (sys_has_ext(path, ".exr"))
        return image_read_exr(path, img, err, errlen);
    if (sys_has_ext(path, ".png"))
        return image_read_png(path, 1, img, err, errlen);
    snprintf(err, errlen, "%s: unsupported image extension (expected .exr or .png)", path);
    return -1;
}

static int write_raw(const image *img, const char *path, char *err, size_t errlen)
{
    size_t n = (size_t)img->width * (size_t)img->height * 3;
    int to_stdout = strcmp(path, "-") == 0;
    FILE *f = to_stdout ? stdout : fopen(path, "wb");
    if (!f) {
        snprintf(err, errlen, "%s: cannot open for writing", path);
        return -1;
    }
    if (fwrite(img->rgb, sizeof(float), n, f) != n) {
        snprintf(err, errlen, "%s: write failed", path);
        if (!to_stdout)
            fclose(f);
        return -1;
    }
    if (to_stdout ? fflush(f) != 0 : fclose(f) != 0) {
        snprintf(err, errlen, "%s: write failed", path);
        return -1;
    }
    return 0;
}

int main(int argc, char **argv)
{
    char err[1024];
    image img = {0, 0, NULL};
    int rc = 1;

    if (argc == 2 && (strcmp(argv[1], "-h") == 0 || strcmp(argv[1], "--help") == 0)) {
        usage(stdout);
        return 0;
    }
    if (argc != 4 || (strcmp(argv[1], "raw") != 0 && strcmp(argv[1], "convert") != 0)) {
        usage(stderr);
        return 2;
    }
    if (read_any(argv[2], &img, err, sizeof err) != 0) {
        fprintf(stderr, "imgtool: %s\n", err);
        return 1;
    }
    if (strcmp(argv[1], "raw") == 0) {
        if (write_raw(&img, argv[3], err, sizeof err) == 0) {
            fprintf(strcmp(argv[3], "-") == 0 ? stderr : stdout, "%d %d\n", img.width, img.height);
            rc = 0;
        }
    } else if (image_write(&img, argv[3], err, sizeof err) == 0) {
        rc = 0;
    }
    if (rc != 0)
        fprintf(stderr, "imgtool: %s\n", err);
    image_free(&img);
    return rc;
}
