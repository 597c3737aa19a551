/* clwhitted: the batch front end. main() parses the command line (cli.c), loads the scene,
 * then either opens the preview (preview.c) or renders once and writes the image. A batch
 * render loads the scene on a second thread while OpenCL starts (platform, device,
 * context, queue), and a successful one ends without tearing anything down. */
#include <errno.h>
#include <limits.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "batch.h"
#include "cli.h"
#include "cli_num.h"
#include "image.h"
#include "preview.h"
#include "progress.h"
#include "render.h"
#include "scene.h"
#include "scene_load.h"
#include "sys.h"

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

/* The scene load of a batch render (scene_load, scene_finish) and, with prepare, the part
 * of the upload that needs no device (renderer_prepare_scene: the conversion and the BVH
 * build), on a thread of its own while the main thread starts OpenCL, or on the main thread
 * before it when no thread can be started. OpenCL starts on the main thread because LLVM, inside
 * PoCL, sets up its signal handling there (AddressSanitizer cannot free an LLVM alternate signal
 * stack when the thread that set it exits). */
typedef struct {
    const cli_options *o;
    const char *path; /* the scene file */
    scene *s;
    int rc; /* 0, or -1 with err */
    char err[2048];
    double done_at;    /* sys_now() at the end of the load */
    int prepare;       /* also renderer_prepare_scene */
    render_prep *prep; /* its result, until render_batch takes it */
    pthread_t tid;
    int threaded;
} scene_job;

/* What --stats says of PoCL's threads: pinned or not (pin_threads). */
static const char *pin_note = "";

/* Reads the scene file and finishes the scene at the command line's size and depth.
 * Returns 0, or -1 with err. */
static int load_scene(const cli_options *o, const char *path, scene *s, char *err, size_t errlen)
{
    return scene_load_for_render(path, o->camera, &o->view, o->width, o->height, o->depth, s, err,
                                 errlen);
}

static void *scene_job_main(void *arg)
{
    scene_job *j = arg;
    j->rc = load_scene(j->o, j->path, j->s, j->err, sizeof j->err);
    j->done_at = sys_now();
    if (j->rc == 0 && j->prepare &&
        !(j->prep = renderer_prepare_scene(j->s, j->err, sizeof j->err)))
        j->rc = -1;
    return NULL;
}

/* Starts the load (and with prepare renderer_prepare_scene), or does it now when no thread
 * can be started. */
static void scene_job_begin(scene_job *j, const cli_options *o, const char *path, scene *s,
                            int prepare)
{
    memset(j, 0, sizeof *j);
    j->o = o;
    j->path = path;
    j->s = s;
    j->prepare = prepare;
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

/* The summary line (short: the output, its size, the time, the rate, and the kernel
 * compile apart when there was one; CLWHITTED_SUMMARY=long: every phase) and, with
 * --stats, the device, the ray counts and the phase times. */
static void report(const cli_options *o, const image *img, const scene *s, const renderer *r,
                   const char *output, const batch_times *t, const render_stats *st, double trace_s)
{
    unsigned long long rays = st->eye_rays + st->secondary_rays + st->shadow_rays;
    double compile = st->compile_s + st->warmup_s;
    char rate[32], comp[64] = "", shown[1024];
    progress_format_rate(rate, sizeof rate, trace_s > 0 ? (double)rays / trace_s * 1e-6 : 0.0);
    if (compile >= 0.05)
        snprintf(comp, sizeof comp, "; compile %.2f s", compile);
    sys_escape(shown, sizeof shown, output);
    if (!o->quiet && o->summary_long) /* every phase, for scripts */
        printf("clwhitted: wrote %s (%dx%d, depth %d) in %.3f s on %s: load %.3f s, setup %.3f s, "
               "render %.3f s, %s Mrays/s\n",
               shown, img->width, img->height, s->max_depth, t->written - t->start,
               renderer_device_name(r), t->loaded - t->start, t->set_up - t->loaded,
               t->rendered - t->set_up, rate);
    else if (!o->quiet)
        printf("clwhitted: wrote %s (%dx%d) in %.2f s, %s Mrays/s%s\n", shown, img->width,
               img->height, t->written - t->start - compile, rate, comp);
    if (o->settings.stats) {
        printf("device: %s, %d compute unit%s, %s kernel; image %dx%d, depth %d\n",
               renderer_device_name(r), renderer_compute_units(r),
               renderer_compute_units(r) == 1 ? "" : "s",
               render_strategy_name(renderer_strategy(r)), s->width, s->height, s->max_depth);
        printf("scene: %d sphere%s, %d triangle%s, %d polygon%s, %d cone%s; %d instance%s of %d "
               "mesh%s; BVH %d nodes\n",
               st->spheres, st->spheres == 1 ? "" : "s", st->triangles,
               st->triangles == 1 ? "" : "s", st->polygons, st->polygons == 1 ? "" : "s", st->cones,
               st->cones == 1 ? "" : "s", st->instances, st->instances == 1 ? "" : "s", st->meshes,
               st->meshes == 1 ? "" : "es", st->nodes);
        printf("rays: eye %llu (hit %llu), shadow %llu (blocked %llu), secondary %llu "
               "(hit %llu)\n",
               st->eye_rays, st->eye_hits, st->shadow_rays, st->shadow_blocked, st->secondary_rays,
               st->secondary_hits);
        {
            char walk[256];
            render_format_walk(st, walk, sizeof walk);
            printf("%s\n", walk);
        }
        printf("time: parse %.3f s, build %.3f s, compile %.3f s, upload %.3f s, trace %.3f s "
               "(%d passes), first launch %.3f s\n",
               t->loaded - t->start, st->build_s, st->compile_s, st->upload_s, st->trace_s,
               st->passes, st->warmup_s);
        printf("program: %s\n", st->program_cached ? "from the cache" : "built from source");
        printf("upload: %.3f MB of scene arrays used in place, %.3f MB copied\n",
               (double)st->upload_in_place * 1e-6, (double)st->upload_copied * 1e-6);
        if (renderer_strategy(r) == RENDER_PIXEL)
            printf("kernels: pixel %.3f s\n", st->pixel_s);
        else
            printf("kernels: raygen %.3f s, intersect %.3f s, shade %.3f s, occlude %.3f s\n",
                   st->raygen_s, st->intersect_s, st->shade_s, st->occlude_s);
        printf("fixed: opencl %.3f s (beside the parse), write %.3f s\n", t->opencl,
               t->written - t->rendered);
        printf("threads: %s\n", pin_note);
    }
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

/* --repeat N: renders the scene N - 1 more times after the first (trace_s) on the same
 * renderer, into a scratch image, and prints every render's time with their least and
 * median (unless -q). Returns 0, or -1 after printing an error. */
static int repeat_renders(const cli_options *o, renderer *r, double trace_s, progress_bar *bar)
{
    char err[2048];
    double *times = malloc(2 * (size_t)o->repeat * sizeof *times), *sorted;
    int k, rc = -1;
    if (!times) {
        fail_msg(bar, "out of memory for --repeat");
        return -1;
    }
    sorted = times + o->repeat; /* the same times, in order */
    times[0] = trace_s;
    renderer_set_progress(r, NULL, NULL);
    for (k = 1; k < o->repeat; k++) {
        image scratch;
        render_stats st;
        memset(&scratch, 0, sizeof scratch);
        if (renderer_render(r, &scratch, err, sizeof err) != 0) {
            fail_msg(bar, err);
            goto out_free_times;
        }
        image_free(&scratch);
        renderer_get_stats(r, &st);
        times[k] = st.trace_s;
    }
    memcpy(sorted, times, (size_t)o->repeat * sizeof *sorted);
    qsort(sorted, (size_t)o->repeat, sizeof *sorted, cmp_double);
    if (!o->quiet) {
        printf("repeat: %d renders, render least %.4f s, median %.4f s:", o->repeat, sorted[0],
               o->repeat % 2 ? sorted[o->repeat / 2]
                             : 0.5 * (sorted[o->repeat / 2 - 1] + sorted[o->repeat / 2]));
        for (k = 0; k < o->repeat; k++)
            printf(" %.4f", times[k]);
        printf("\n");
    }
    rc = 0;
out_free_times:
    free(times);
    return rc;
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

/* Renders the finished scene b->s (from the file path) once and writes it to o->output (or
 * b->default_out); with *prep (renderer_prepare_scene of b->s) the upload starts from it
 * (*prep is then taken: NULL). Returns the exit status. */
static int render_batch(cli_options *o, const char *path, batch *b, render_prep **prep,
                        progress_bar *bar, batch_times *t)
{
    char err[2048];
    batch_meta meta;
    const char *output = o->output ? o->output : b->default_out;
    const scene *s = &b->s;
    renderer *r;
    render_stats st;
    double trace_s;
    int is_exr;

    if (render_check_crop(&o->settings, s->width, s->height, err, sizeof err) != 0) {
        fprintf(stderr, "clwhitted: %s\n" CLI_HINT, err);
        return 2;
    }
    is_exr = sys_has_ext(output, ".exr");
    progress_status(bar, "building the kernels ...");
    if (b->r_rc != 0) {
        fail_msg(bar, b->r_err);
        return 1;
    }
    r = b->r;
    if (renderer_check_memory(r, s->width, s->height, err, sizeof err) != 0) {
        fail_msg(bar, err);
        return 1;
    }
    if (prep && *prep) {
        render_prep *p = *prep;
        *prep = NULL;
        if (renderer_set_prepared(r, p, s, err, sizeof err) != 0) {
            fail_msg(bar, err);
            return 1;
        }
    } else if (renderer_set_scene_dropping(r, &b->s, err, sizeof err) != 0) {
        fail_msg(bar, err);
        return 1;
    }
    t->set_up = sys_now();
    renderer_set_progress(r, progress_update, bar);
    progress_begin(bar);
    progress_update(bar, 0.0, 0);
    image_free(&b->img);
    if (renderer_render(r, &b->img, err, sizeof err) != 0) {
        fail_msg(bar, err);
        return 1;
    }
    progress_clear(bar);
    t->rendered = sys_now();
    renderer_get_stats(r, &st);
    trace_s = st.trace_s > 0 ? st.trace_s : t->rendered - t->set_up;
    batch_metadata(o, path, s, r, is_exr, trace_s, NULL, &o->write, &meta);
    if (image_write_ex(&b->img, output, &o->write, err, sizeof err) != 0) {
        fail_msg(bar, err);
        return 1;
    }
    t->written = sys_now();
    report(o, &b->img, s, r, output, t, &st, trace_s);
    if (o->repeat > 1 && repeat_renders(o, r, trace_s, bar) != 0)
        return 1;
    return summary_written();
}

/* The output of scene k (o->output, or the scene's NAME.exr) into b->default_out, checked
 * before the scene is read: a render that cannot be saved is not started. Returns 0, or -1
 * after printing the error. */
static int check_output(const cli_options *o, int k, batch *b, progress_bar *bar)
{
    char err[2048];
    free(b->default_out);
    b->default_out = NULL;
    if (!o->output && !(b->default_out = batch_default_output(o->scenes[k]))) {
        fail_msg(bar, "out of memory");
        return -1;
    }
    if (sys_check_output(o->output ? o->output : b->default_out, err, sizeof err) != 0) {
        fail_msg(bar, err);
        return -1;
    }
    return 0;
}

/* Loads the first scene while OpenCL starts, renders it, then each further scene in turn
 * on the same device (a failed one is reported and the others still render), and ends the
 * process (see CW_FULL_TEARDOWN). Errors come in the order of the steps: the scene's, then
 * the device's. Returns the exit status: the worst of the scenes'. */
static int run_batch(cli_options *o, progress_bar *bar, batch_times *t)
{
    char err[2048];
    scene_job load;
    batch b;
    int rc = 0, one, k;

    memset(&b, 0, sizeof b);
    scene_init(&b.s);
    if (check_output(o, 0, &b, bar) != 0) {
        free(b.default_out);
        return 1;
    }
    progress_status(bar, "loading the scene ...");
    scene_job_begin(&load, o, o->scenes[0], &b.s, 1);
    if (load.threaded || load.rc == 0) /* without a thread, a failed load ends it here */
        b.r_rc = renderer_create(&b.r, o->device, b.r_err, sizeof b.r_err) == 0 &&
                         renderer_set_settings(b.r, &o->settings, b.r_err, sizeof b.r_err) == 0
                     ? 0
                     : -1;
    t->opencl = sys_now() - t->start;
    for (k = 0; k < o->nscenes; k++) {
        if (k > 0) {
            scene_free(&b.s);
            scene_init(&b.s);
            t->start = sys_now();
            t->opencl = 0;
        }
        if (k == 0 ? scene_job_end(&load) != 0
            : check_output(o, k, &b, bar) != 0
                ? (err[0] = '\0', 1)
                : load_scene(o, o->scenes[k], &b.s, err, sizeof err) != 0) {
            if (k == 0 || err[0])
                fail_msg(bar, k == 0 ? load.err : err);
            one = 1;
        } else {
            t->loaded = k == 0 ? load.done_at : sys_now();
            progress_clear(bar);
            one = render_batch(o, o->scenes[k], &b, k == 0 ? &load.prep : NULL, bar, t);
        }
        if (one > rc)
            rc = one;
        if (b.r_rc != 0) /* no device: nothing more can render */
            break;
    }
    if (rc == 0 && !CW_FULL_TEARDOWN)
        sys_exit_now(0);
    renderer_prep_free(load.prep);
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
    if (load_scene(o, o->scene, &s, err, sizeof err) != 0) {
        fail_msg(bar, err);
        rc = 1;
    } else {
        preview_options po = {o->device, o->settings, o->preview_script, o->quiet, o->scene};
        progress_clear(bar);
        rc = preview_run(&s, &po);
    }
    scene_free(&s);
    return rc;
}

/* --threads N: PoCL's CPU device (read when OpenCL starts), the BVH build and the image
 * writers. Returns 0, or -1 after printing an error. */
static int set_threads(int n)
{
    char v[16];
    if (n <= 0)
        return 0;
    snprintf(v, sizeof v, "%d", n);
    if (setenv("POCL_MAX_PTHREAD_COUNT", v, 1) != 0) {
        perror("clwhitted: setenv");
        return -1;
    }
    sys_set_cpu_limit(n);
    return 0;
}

/* Pins PoCL's pthread device threads one per CPU (POCL_AFFINITY=1, read when OpenCL
 * starts) where that covers every CPU this process may use. Unpinned, the scheduler woke
 * both threads of the first launch on one core of two, the main thread still running on
 * the other, and took 4-20 ms to move one: the first render of 1M random triangles ran
 * 0.147 s unpinned, 0.140 s pinned (medians of 16 alternating runs). Left alone when the
 * user set POCL_AFFINITY, when the threads are not one per CPU (fewer: other processes may
 * want the other CPUs; more: PoCL pins thread i to CPU i and aborts where that CPU is
 * missing), and when a taskset or cpuset narrows the CPUs; the user's POCL_AFFINITY with
 * more threads than CPUs is refused (PoCL would abort). clwhitted-mpi, whose ranks may
 * share a node, never pins. Returns 0, or -1 after printing an error. */
static int pin_threads(void)
{
    const char *set = getenv("POCL_AFFINITY"), *count = getenv("POCL_MAX_PTHREAD_COUNT");
    long n = 0;
    if (set) {
        /* PoCL reads a value starting with 1 as on, and a count as atoi does: more threads
         * than CPUs would abort it ("PTHREAD ERROR ... Invalid argument") at the first
         * launch, so say so now instead */
        long want = count ? atol(count) : 0, online = sysconf(_SC_NPROCESSORS_ONLN);
        if (set[0] == '1' && online > 0 && want > online) {
            fprintf(stderr,
                    "clwhitted: POCL_AFFINITY=%s pins PoCL's thread i to CPU i, and %ld threads "
                    "(POCL_MAX_PTHREAD_COUNT or --threads) are more than the %ld CPUs here: use "
                    "at most %ld threads or unset POCL_AFFINITY\n",
                    set, want, online, online);
            return -1;
        }
        pin_note = "POCL_AFFINITY as the environment set it";
        return 0;
    }
    if (count && *count && cli_parse_long(count, 1, INT_MAX, &n) != 0)
        n = -1; /* PoCL's own reading of it is not ours to guess */
    if (!sys_pin_covers_cpus((int)n)) {
        pin_note = "not pinned (not one thread per CPU, or a narrowed CPU set)";
        return 0;
    }
    if (setenv("POCL_AFFINITY", "1", 0) != 0) {
        perror("clwhitted: setenv");
        return -1;
    }
    pin_note = "pinned one per CPU (POCL_AFFINITY=1)";
    return 0;
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
    if (set_threads(o.threads) != 0 || pin_threads() != 0)
        return 1;
    if (o.list_devices) {
        if (renderer_list_devices(err, sizeof err) != 0) {
            fprintf(stderr, "clwhitted: %s\n", sys_escape(shown, sizeof shown, err));
            return 1;
        }
        return summary_written();
    }
    progress_init(&bar, stderr, progress_wanted(o.quiet, o.progress, isatty(STDERR_FILENO)));
    t.start = sys_now();
    return o.preview ? run_preview(&o, &bar) : run_batch(&o, &bar, &t);
}
