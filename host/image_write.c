/* image_write: checks the output path and hands the image to the OpenEXR (image_exr.c) or
 * PNG (image_png.c) writer by its extension. See image.h. */
#include "image.h"

#include <stddef.h>

#include "image_internal.h"
#include "sys.h"

static const image_write_opts *opts_or_default(const image_write_opts *o, image_write_opts *def)
{
    if (o)
        return o;
    image_write_opts_default(def);
    return def;
}

int image_check_path(const char *path, char *err, size_t errlen)
{
    if (!path || !*path) {
        image_set_err(err, errlen, "image: no output path given");
        return -1;
    }
    if (sys_has_ext(path, ".exr") || sys_has_ext(path, ".png"))
        return 0;
    image_set_err(err, errlen, "%s: unsupported image extension (accepted: .exr, .png)", path);
    return -1;
}

int image_write_ex(const image *img, const char *path, const image_write_opts *o, char *err,
                   size_t errlen)
{
    image_write_opts def;
    o = opts_or_default(o, &def);
    if (image_check_path(path, err, errlen) != 0)
        return -1;
    if (sys_has_ext(path, ".exr"))
        return image_exr_write(img, path, o, err, errlen);
    return image_png_write(img, path, o, err, errlen);
}

int image_write(const image *img, const char *path, char *err, size_t errlen)
{
    return image_write_ex(img, path, NULL, err, errlen);
}
