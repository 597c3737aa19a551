/* What a batch render writes beside its pixels, the same for clwhitted and clwhitted-mpi:
 * the default output name and the image's metadata. */
#ifndef CW_BATCH_H
#define CW_BATCH_H

#include "cli.h"
#include "image.h"
#include "render.h"
#include "scene.h"

/* "dir/name.nff" -> "name.exr" in the current folder (the name as scene_set_name makes it
 * from the scene's path); malloc'd, NULL when out of memory. */
char *batch_default_output(const char *scene_path);

/* The strings behind the metadata of one image. */
typedef struct {
    char title[256], software[64], settings[320];
} batch_meta;

/* Fills w's metadata: title (the scene file's base name), software, device, the settings
 * (as the format uses them; `extra`, if not NULL, appended) and the render time. The
 * strings live in *m. */
void batch_metadata(const cli_options *o, const char *path, const scene *s, const renderer *r,
                    int is_exr, double render_s, const char *extra, image_write_opts *w,
                    batch_meta *m);

#endif
