/* clwhitted: the batch front end. main() parses the command line (cli.c), loads the scene,
 * then either opens the preview (preview.c) or renders once and writes the image. A batch
 * render loads the scene on a second thread while OpenCL starts (platform, device,
 * context, queue), and a successful one ends without tearing anything down. */
#include <errno.h>
#include <pthread.h>
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

/* Full teardown at exit only where a leak checker looks: sanitizer builds (LeakSanitizer
 * checks at exit) or -DCW_FULL_TEARDOWN=1. Otherwise a successful batch render ends with
 * sys_exit_now: the scene, the image and the renderer are not freed, the OpenCL objects not
 * released, and the libraries' exit-time destructors (PoCL's, LLVM's) do not run. */
#ifndef CW_FULL_TEARDOWN
#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_LEAK__)
#define CW_FULL_TEARDOWN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer) || __has_feature(leak_sanitizer)
#define CW_FULL_TEARDOWN 1
#endif
#endif
#endif
#ifndef CW_FULL_TEARDOWN
#define CW_FULL_TEARDOWN 0
#endif

/* Times of the phases of a batch render, from sys_now(). */
typedef struct {
    double start, loaded, set_up, rendered, written;
    double opencl; /* the OpenCL start-up's duration (beside the scene load) */
} batch_times;

/* The scene load of a batch render (scene_load, scene_finish), on a thread of its own
 * while the main thread starts OpenCL, or on the main thread before it when no thread can
 * be started. OpenCL starts on the main thread because LLVM, inside PoCL, sets up its
 * signal handling there (AddressSanitizer cannot free an LLVM alternate signal stack when
 * the thread that set it exits). */
typedef struct {
    const cli_options *o;
    scene *s;
    int rc; /* 0, or -1 with err */
    char err[2048];
    double done_at; /* sys_now() at the end */
    pthread_t tid;
    int threaded;
} scene_job;

/* Reads the scene file and finishes the scene at the command line's size and depth.
 * Returns 0, or -1 with err. */
static int load_scene(const cli_options *o, scene *s, char *err, size_t errlen)
{
    if (scene_load(o->scene, s, err, errlen) != 0 ||
        scene_finish(s, o->width, o->height, o->depth, err, errlen) != 0)
        return -1;
    return 0;
}

static void *scene_job_main(void *arg)
{
    scene_job *j = arg;
    j->rc = load_scene(j->o, j->s, j->err, sizeof j->err);
    j->done_at = sys_now();
    return NULL;
}

/* Starts the load, or does it now when no thread can be started. */
static void scene_job_begin(scene_job *j, const cli_options *o, scene *s)
{
    memset(j, 0, sizeof *j);
    j->o = o;
    j->s = s;
    j->threaded = pthread_create(&j->tid, NULL, scene_job_main, j) == 0;
    if (!j->threaded)
        scene_job_main(j);
}

/* Waits for the load. Returns 0, or -1 with j->err. */
static int scene_job_end(scene_job *j)
{
    if (j->threaded)
        pthread_join(j->tid, NULL);
    j->threaded = 0;
    return j->rc;
}

/* Prints an error (control characters escaped: messages quote paths and other untrusted
 * text), clearing the progress line first. */
static void fail_msg(progress_bar *bar, const char *msg)
{
    char shown[4096];
    progress_clear(bar);
    fprintf(stderr, "clwhitted: %s\n", sys_escape(shown, sizeof shown, msg));
}

/* "dir/name.nff" -> "name.exr" in the current folder (the name as scene_set_name makes
 * it from the scene's path). */
static char *default_output(const char *scene_path)
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

/* The summary on stdout reached it: fails on a write error other than a closed pipe
 * (whose reader no longer wants it). Returns the exit status. */
static int summary_written(void)
{
    if (fflush(stdout) == 0 && !ferror(stdout))
        return 0;
    if (errno == EPIPE)
        return 0;
    fprintf(stderr, "clwhitted: cannot write the summary to the standard output: %s\n",
            strerror(errno));
    return 1;
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
    char rate[32], shown[1024];
    progress_format_rate(rate, sizeof rate, trace_s > 0 ? (double)rays / trace_s * 1e-6 : 0.0);
    if (!o->quiet)
        printf("clwhitted: wrote %s (%dx%d, depth %d) in %.3f s on %s: load %.3f s, setup %.3f s, "
               "render %.3f s, %s Mrays/s\n",
               sys_escape(shown, sizeof shown, output), s->width, s->height, s->max_depth,
               t->written - t->start, renderer_device_name(r), t->loaded - t->start,
               t->set_up - t->loaded, t->rendered - t->set_up, rate);
    if (o->settings.stats) {
        printf("rays: eye %llu (hit %llu), shadow %llu (blocked %llu), secondary %llu "
               "(hit %llu)\n",
               st->eye_rays, st->eye_hits, st->shadow_rays, st->shadow_blocked, st->secondary_rays,
               st->secondary_hits);
        printf("time: parse %.3f s, build %.3f s, compile %.3f s, upload %.3f s, trace %.3f s "
               "(%d passes)\n",
               t->loaded - t->start, st->build_s, st->compile_s, st->upload_s, st->trace_s,
               st->passes);
        printf("program: %s\n", st->program_cached ? "from the cache" : "built from source");
        if (renderer_strategy(r) == RENDER_PIXEL)
            printf("kernels: pixel %.3f s\n", st->pixel_s);
        else
            printf("kernels: raygen %.3f s, intersect %.3f s, shade %.3f s, occlude %.3f s\n",
                   st->raygen_s, st->intersect_s, st->shade_s, st->occlude_s);
        printf("fixed: opencl %.3f s (beside the parse), write %.3f s\n", t->opencl,
               t->written - t->rendered);
    }
}

/* What a batch render holds until the end of the process. */
typedef struct {
    scene s;
    renderer *r; /* NULL until created */
    int r_rc;    /* renderer_create and renderer_set_settings: 0, or -1 with r_err */
    char r_err[2048];
    image img;
    char *default_out;
} batch;

/* Renders the finished scene b->s once and writes it to o->output (or the default name).
 * Returns the exit status. */
static int render_batch(cli_options *o, batch *b, progress_bar *bar, batch_times *t)
{
    char err[2048], title[256], software[64], settings[256];
    const char *output = o->output ? o->output : b->default_out;
    const scene *s = &b->s;
    renderer *r;
    render_stats st;
    double trace_s;
    int is_exr;

    is_exr = sys_has_ext(output, ".exr");
    if (!o->quiet) {
        if (is_exr && (o->write.exposure != 0 || o->write.tonemap != IMAGE_TONEMAP_CLAMP))
            fprintf(stderr, "clwhitted: warning: --exposure and --tonemap apply to PNG output "
                            "only; EXR keeps the linear values\n");
        if (!is_exr && o->write.half)
            fprintf(stderr, "clwhitted: warning: --half applies to EXR output only\n");
    }
    progress_status(bar, "building the kernels ...");
    if (b->r_rc != 0) {
        fail_msg(bar, b->r_err);
        return 1;
    }
    r = b->r;
    if (renderer_check_memory(r, s->width, s->height, err, sizeof err) != 0 ||
        renderer_set_scene(r, s, err, sizeof err) != 0) {
        fail_msg(bar, err);
        return 1;
    }
    t->set_up = sys_now();
    renderer_set_progress(r, progress_update, bar);
    progress_begin(bar);
    progress_update(bar, 0.0, 0);
    if (renderer_render(r, &b->img, err, sizeof err) != 0) {
        fail_msg(bar, err);
        return 1;
    }
    progress_clear(bar);
    t->rendered = sys_now();
    renderer_get_stats(r, &st);
    trace_s = st.trace_s > 0 ? st.trace_s : t->rendered - t->set_up;
    set_metadata(o, s, r, is_exr, trace_s, &o->write, title, sizeof title, software,
                 sizeof software, settings, sizeof settings);
    if (image_write_ex(&b->img, output, &o->write, err, sizeof err) != 0) {
        fail_msg(bar, err);
        return 1;
    }
    t->written = sys_now();
    report(o, s, r, output, t, &st, trace_s);
    return summary_written();
}

/* Loads the scene while OpenCL starts, renders it, and ends the process (see
 * CW_FULL_TEARDOWN). Errors come in the order of the steps: the scene's, then the
 * device's. Returns the exit status. */
static int run_batch(cli_options *o, progress_bar *bar, batch_times *t)
{
    char err[2048];
    scene_job load;
    batch b;
    int rc = 1;

    memset(&b, 0, sizeof b);
    scene_init(&b.s);
    /* the output's place first: a render that cannot be saved is not started */
    if (!o->output && !(b.default_out = default_output(o->scene))) {
        fail_msg(bar, "out of memory");
        return 1;
    }
    if (sys_check_output(o->output ? o->output : b.default_out, err, sizeof err) != 0) {
        fail_msg(bar, err);
        free(b.default_out);
        return 1;
    }
    progress_status(bar, "loading the scene ...");
    scene_job_begin(&load, o, &b.s);
    if (load.threaded || load.rc == 0) /* without a thread, a failed load ends it here */
        b.r_rc = renderer_create(&b.r, o->device, b.r_err, sizeof b.r_err) == 0 &&
                         renderer_set_settings(b.r, &o->settings, b.r_err, sizeof b.r_err) == 0
                     ? 0
                     : -1;
    t->opencl = sys_now() - t->start;
    if (scene_job_end(&load) != 0) {
        fail_msg(bar, load.err);
    } else {
        t->loaded = load.done_at;
        progress_clear(bar);
        rc = render_batch(o, &b, bar, t);
    }
    if (rc == 0 && !CW_FULL_TEARDOWN)
        sys_exit_now(0);
    renderer_destroy(b.r);
    image_free(&b.img);
    free(b.default_out);
    scene_free(&b.s);
    return rc;
}

/* Loads the scene and opens the preview. Returns the exit status. */
static int run_preview(const cli_options *o, progress_bar *bar)
{
    char err[2048];
    scene s;
    int rc;

    scene_init(&s);
    progress_status(bar, "loading the scene ...");
    if (load_scene(o, &s, err, sizeof err) != 0) {
        fail_msg(bar, err);
        rc = 1;
    } else {
        preview_options po = {o->device, o->settings, o->preview_script, o->quiet};
        progress_clear(bar);
        rc = preview_run(&s, &po);
    }
    scene_free(&s);
    return rc;
}

int main(int argc, char **argv)
{
    cli_options o;
    char err[2048], shown[2048];
    progress_bar bar;
    batch_times t;
    int rc;

    if (cli_parse(argc, argv, &o, &rc) != CLI_RUN)
        return rc;
    sys_signals_install();
    if (o.list_devices) {
        if (renderer_list_devices(err, sizeof err) != 0) {
            fprintf(stderr, "clwhitted: %s\n", sys_escape(shown, sizeof shown, err));
            return 1;
        }
        return summary_written();
    }
    progress_init(&bar, stderr,
                  progress_wanted(o.quiet, getenv("CLWHITTED_PROGRESS"), isatty(STDERR_FILENO)));
    t.start = sys_now();
    return o.preview ? run_preview(&o, &bar) : run_batch(&o, &bar, &t);
}
