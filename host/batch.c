/* The default output name and the image metadata of a batch render (see batch.h). */
#include "batch.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "version.h"

char *batch_default_output(const char *scene_path)
{
    scene tmp;
    char *out = NULL;
    size_t n;
    scene_init(&tmp);
    if (scene_set_name(&tmp, scene_path) == 0) {
        n = strlen(tmp.name) + 5;
        out = malloc(n);
        if (out)
            snprintf(out, n, "%s.exr", tmp.name);
    }
    scene_free(&tmp);
    return out;
}

void batch_metadata(const cli_options *o, const char *path, const scene *s, const renderer *r,
                    int is_exr, double render_s, const char *extra, image_write_opts *w,
                    batch_meta *m)
{
    const char *slash = strrchr(path, '/');
    const render_settings *st = &o->settings;
    const char *precision = st->precision == RENDER_FAST ? "fast" : "robust";
    char samples[32], crop[64] = "";
    if (!extra)
        extra = "";
    snprintf(m->software, sizeof m->software, "clwhitted %s", CW_VERSION);
    snprintf(m->title, sizeof m->title, "%s", slash ? slash + 1 : path);
    if (st->spd) /* the corners; --spp is rejected with --spd */
        snprintf(samples, sizeof samples, "spd");
    else
        snprintf(samples, sizeof samples, "spp %d", st->spp);
    if (st->crop[1] != 0)
        snprintf(crop, sizeof crop, ", crop %d,%d,%d,%d", st->crop[0], st->crop[1], st->crop[2],
                 st->crop[3]);
    if (is_exr)
        snprintf(m->settings, sizeof m->settings, "%dx%d%s, depth %d, %s, precision %s%s%s",
                 s->width, s->height, crop, s->max_depth, samples, precision,
                 w->half ? ", half floats" : "", extra);
    else
        snprintf(m->settings, sizeof m->settings,
                 "%dx%d%s, depth %d, %s, precision %s, exposure %+g EV, tonemap %s%s%s", s->width,
                 s->height, crop, s->max_depth, samples, precision, w->exposure,
                 image_tonemap_name(w->tonemap), w->png16 ? ", 16-bit" : "", extra);
    w->title = m->title;
    w->software = m->software;
    w->source = renderer_device_name(r);
    w->comment = m->settings;
    w->render_s = render_s;
}
