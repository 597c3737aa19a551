/* clwhitted: the batch front end. main() parses the command line (cli.c), loads the scene,
 * then either opens the preview (preview.c) or renders once and writes the image. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "cli.h"
#include "image.h"
#include "preview.h"
#include "progress.h"
#include "render.h"
#include "scene.h"
#include "scene_load.h"
#include "sys.h"
#include "version.h"

/* Times of the phases of a batch render, from sys_now(). */
typedef struct {
    double start, loaded, set_up, rendered, written;
} batch_times;

/* Prints an error, clearing the progress line first. */
static void fail_msg(progress_bar *bar, const char *msg)
{
    progress_clear(bar);
    fprintf(stderr, "clwhitted: %s\n", msg);
}

/* "dir/name.nff" -> "name.exr" in the current folder. */
static char *default_output(const scene *s)
{
    const char *name = s->name && *s->name ? s->name : "render";
    size_t n = strlen(name) + 5;
    char *out = malloc(n);
    if (out)
        snprintf(out, n, "%s.exr", name);
    return out;
}

/* The metadata of the image: title (the scene file's base name), software, device, the
 * settings (as the format uses them) and the render time. Strings live in the buffers. */
static void set_metadata(const cli_options *o, const scene *s, const renderer *r, int is_exr,
                         double render_s, image_write_opts *w, char *title, size_t ntitle,
                         char *software, size_t nsoftware, char *settings, size_t nsettings)
{
    const char *slash = strrchr(o->scene, '/');
    const render_settings *st = &o->settings;
    const char *precision = st->precision == RENDER_FAST ? "fast" : "robust";
    snprintf(software, nsoftware, "clwhitted %s", CW_VERSION);
    snprintf(title, ntitle, "%s", slash ? slash + 1 : o->scene);
    if (is_exr)
        snprintf(settings, nsettings, "%dx%d, depth %d, spp %d, precision %s%s%s", s->width,
                 s->height, s->max_depth, st->spp, precision, st->spd ? ", spd" : "",
                 w->half ? ", half floats" : "");
    else
        snprintf(settings, nsettings,
                 "%dx%d, depth %d, spp %d, precision %s%s, exposure %+g EV, tonemap %s", s->width,
                 s->height, s->max_depth, st->spp, precision, st->spd ? ", spd" : "", w->exposure,
                 image_tonemap_name(w->tonemap));
    w->title = title;
    w->software = software;
    w->source = renderer_device_name(r);
    w->comment = settings;
    w->render_s = render_s;
}

/* The summary line and, with --stats, the ray counts and phase times. */
static void report(const cli_options *o, const scene *s, const renderer *r, const char *output,
                   const batch_times *t, const render_stats *st, double trace_s)
{
    unsigned long long rays = st->eye_rays + st->secondary_rays + st->shadow_rays;
    char rate[32];
    progress_format_rate(rate, sizeof rate, trace_s > 0 ? (double)rays / trace_s * 1e-6 : 0.0);
    if (!o->quiet)
        printf("clwhitted: wrote %s (%dx%d, depth %d) in %.3f s on %s: load %.3f s, setup %.3f s, "
               "render %.3f s, %s Mrays/s\n",
               output, s->width, s->height, s->max_depth, t->written - t->start,
               renderer_device_name(r), t->loaded - t->start, t->set_up - t->loaded,
               t->rendered - t->set_up, rate);
    if (o->settings.stats) {
        printf("rays: eye %llu (hit %llu), shadow %llu (blocked %llu), secondary %llu "
               "(hit %llu)\n",
               st->eye_rays, st->eye_hits, st->shadow_rays, st->shadow_blocked, st->secondary_rays,
               st->secondary_hits);
        printf("time: parse %.3f s, build %.3f s, compile %.3f s, upload %.3f s, trace %.3f s "
               "(%d passes)\n",
               t->loaded - t->start, st->build_s, st->compile_s, st->upload_s, st->trace_s,
               st->passes);
        printf("kernels: raygen %.3f s, intersect %.3f s, shade %.3f s, occlude %.3f s\n",
               st->raygen_s, st->intersect_s, st->shade_s, st->occlude_s);
    }
}

/* Renders the finished scene s once and writes it to o->output (or the default name).
 * Returns the exit status. */
static int render_batch(cli_options *o, const scene *s, progress_bar *bar, batch_times *t)
{
    char err[2048], title[256], software[64], settings[256];
    char *default_out = NULL;
    const char *output = o->output;
    renderer *r = NULL;
    image img = {0, 0, NULL};
    render_stats st;
    double trace_s;
    int is_exr, rc = 1;

    if (!output && !(output = default_out = default_output(s))) {
        fprintf(stderr, "clwhitted: out of memory\n");
        return 1;
    }
    is_exr = sys_has_ext(output, ".exr");
    if (!o->quiet) {
        if (is_exr && (o->write.exposure != 0 || o->write.tonemap != IMAGE_TONEMAP_CLAMP))
            fprintf(stderr, "clwhitted: warning: --exposure and --tonemap apply to PNG output "
                            "only; EXR keeps the linear values\n");
        if (!is_exr && o->write.half)
            fprintf(stderr, "clwhitted: warning: --half applies to EXR output only\n");
    }
    t->loaded = sys_now();
    progress_status(bar, "building the kernels ...");
    if (renderer_create(&r, o->device, err, sizeof err) != 0 ||
        renderer_set_settings(r, &o->settings, err, sizeof err) != 0 ||
        renderer_set_scene(r, s, err, sizeof err) != 0) {
        fail_msg(bar, err);
        goto out_destroy;
    }
    t->set_up = sys_now();
    renderer_set_progress(r, progress_update, bar);
    progress_begin(bar);
    progress_update(bar, 0.0, 0);
    if (renderer_render(r, &img, err, sizeof err) != 0) {
        fail_msg(bar, err);
        goto out_destroy;
    }
    progress_clear(bar);
    t->rendered = sys_now();
    renderer_get_stats(r, &st);
    trace_s = st.trace_s > 0 ? st.trace_s : t->rendered - t->set_up;
    set_metadata(o, s, r, is_exr, trace_s, &o->write, title, sizeof title, software,
                 sizeof software, settings, sizeof settings);
    if (image_write_ex(&img, output, &o->write, err, sizeof err) != 0) {
        fprintf(stderr, "clwhitted: %s\n", err);
        goto out_free_image;
    }
    t->written = sys_now();
    report(o, s, r, output, t, &st, trace_s);
    rc = 0;
out_free_image:
    image_free(&img);
out_destroy:
    renderer_destroy(r);
    free(default_out);
    return rc;
}

int main(int argc, char **argv)
{
    cli_options o;
    char err[2048];
    scene s;
    progress_bar bar;
    batch_times t;
    int rc;

    if (cli_parse(argc, argv, &o, &rc) != CLI_RUN)
        return rc;
    if (o.list_devices) {
        if (renderer_list_devices(err, sizeof err) != 0) {
            fprintf(stderr, "clwhitted: %s\n", err);
            return 1;
        }
        return 0;
    }
    progress_init(&bar, stderr,
                  progress_wanted(o.quiet, getenv("CLWHITTED_PROGRESS"), isatty(STDERR_FILENO)));
    t.start = sys_now();
    scene_init(&s);
    progress_status(&bar, "loading the scene ...");
    if (scene_load(o.scene, &s, err, sizeof err) != 0 ||
        scene_finish(&s, o.width, o.height, o.depth, err, sizeof err) != 0) {
        fail_msg(&bar, err);
        rc = 1;
        goto out_free_scene;
    }
    progress_clear(&bar);
    if (o.preview) {
        preview_options po = {o.device, o.settings, o.preview_script, o.quiet};
        rc = preview_run(&s, &po);
    } else {
        rc = render_batch(&o, &s, &bar, &t);
    }
out_free_scene:
    scene_free(&s);
    return rc;
}
