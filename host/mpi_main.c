/* clwhitted-mpi: one image rendered across the ranks of an MPI job (docs/mpi.md). Every
 * rank parses the same command line (clwhitted's, cli.c), loads the scene and builds its
 * kernels on its own device; rank 0 gathers every rank's set-up (any failure ends the job
 * with that rank's message), hands out tiles and gathers the accumulation image
 * (mpi_work.c), makes the image as clwhitted does (renderer_resolve) and writes it. */
#include <mpi.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "batch.h"
#include "cli.h"
#include "image.h"
#include "mpi_work.h"
#include "progress.h"
#include "render.h"
#include "scene.h"
#include "scene_load.h"
#include "sys.h"

/* What a rank reports after its set-up. */
typedef struct {
    int ok;
    int shape[6]; /* accumulation width, height; depth, spp, spd, precision */
    char err[1024];
} setup_report;

typedef struct {
    cli_options o;
    const char *output;
    char *default_out;
    scene s;
    renderer *r;
    int rank, size, local_rank;
    double start;
    mwork_rank mine;
} job;

static void say(const char *msg)
{
    char shown[4096];
    fprintf(stderr, "clwhitted-mpi: %s\n", sys_escape(shown, sizeof shown, msg));
}

/* --device A,B,C: this node's local rank L takes entry L modulo the count. */
static const char *device_spec(const char *spec, int local_rank, char *buf, size_t n)
{
    int k = 0, count = 1;
    const char *p, *end;
    if (!spec || !strchr(spec, ','))
        return spec;
    for (p = spec; *p; p++)
        count += *p == ',';
    for (p = spec; k < local_rank % count; p = strchr(p, ',') + 1)
        k++;
    end = strchr(p, ',');
    snprintf(buf, n, "%.*s", (int)(end ? (size_t)(end - p) : strlen(p)), p);
    return buf;
}

/* This rank's set-up for scene o->scene: scene, device (the first time), settings, memory
 * check, upload and kernels. */
static int setup(job *j, setup_report *rep)
{
    char spec[256], *err = rep->err;
    size_t errlen = sizeof rep->err;
    const cli_options *o = &j->o;
    double t0 = sys_now();

    if (j->rank == 0) {
        if (!o->output && !(j->default_out = batch_default_output(o->scene))) {
            snprintf(err, errlen, "out of memory");
            return -1;
        }
        j->output = o->output ? o->output : j->default_out;
        if (sys_check_output(j->output, err, errlen) != 0)
            return -1;
    }
    if (scene_load_for_render(o->scene, o->camera, &o->view, o->width, o->height, o->depth, &j->s,
                              err, errlen) != 0 ||
        (!j->r && renderer_create(&j->r, device_spec(o->device, j->local_rank, spec, sizeof spec),
                                  err, errlen) != 0) ||
        renderer_set_settings(j->r, &o->settings, err, errlen) != 0 ||
        renderer_check_memory(j->r, j->s.width, j->s.height, err, errlen) != 0 ||
        renderer_set_scene(j->r, &j->s, err, errlen) != 0)
        return -1;
    renderer_accum_size(j->r, &rep->shape[0], &rep->shape[1]);
    rep->shape[2] = j->s.max_depth;
    rep->shape[3] = o->settings.spp;
    rep->shape[4] = o->settings.spd;
    rep->shape[5] = o->settings.precision;
    snprintf(j->mine.device, sizeof j->mine.device, "%s", renderer_device_name(j->r));
    j->mine.setup_s = sys_now() - t0;
    return 0;
}

/* Gathers every rank's set-up on rank 0: 0 when all are ready and render the same image
 * shape, else -1 (rank 0 has printed why). Every rank gets the verdict. */
static int gather_setups(const job *j, const setup_report *mine)
{
    setup_report *all = NULL;
    char msg[1200];
    int ok = 1, r, failed = 0;
    if (j->rank == 0 && !(all = malloc((size_t)j->size * sizeof *all))) {
        say("out of memory");
        MPI_Abort(MPI_COMM_WORLD, 1);
    }
    MPI_Gather(mine, (int)sizeof *mine, MPI_BYTE, all, (int)sizeof *mine, MPI_BYTE, 0,
               MPI_COMM_WORLD);
    for (r = 0; j->rank == 0 && r < j->size; r++) {
        if (all[r].ok && all[0].ok && memcmp(all[r].shape, all[0].shape, sizeof all[0].shape)) {
            snprintf(all[r].err, sizeof all[r].err,
                     "renders %dx%d (depth %d, spp %d, spd %d, precision %d), rank 0 %dx%d "
                     "(depth %d, spp %d, spd %d, precision %d): give every rank the same scene "
                     "and options",
                     all[r].shape[0], all[r].shape[1], all[r].shape[2], all[r].shape[3],
                     all[r].shape[4], all[r].shape[5], all[0].shape[0], all[0].shape[1],
                     all[0].shape[2], all[0].shape[3], all[0].shape[4], all[0].shape[5]);
            all[r].ok = 0;
        }
        if (!all[r].ok) {
            ok = 0;
            /* the same failure everywhere (a bad scene): said once */
            if (failed++ == 0 || strcmp(all[r].err, all[0].err) != 0) {
                snprintf(msg, sizeof msg, "rank %d: %s", r, all[r].err);
                say(msg);
            }
        }
    }
    free(all);
    MPI_Bcast(&ok, 1, MPI_INT, 0, MPI_COMM_WORLD);
    return ok ? 0 : -1;
}

/* The summary and, with --stats, the ray counts over the ranks and each rank's share. */
static void report(const job *j, const mwork_rank *all, double render_s, double total_s)
{
    render_stats sum;
    char rate[32], shown[1024], walk[256];
    unsigned long long rays;
    int r;
    memset(&sum, 0, sizeof sum);
    for (r = 0; r < j->size; r++) {
        sum.eye_rays += all[r].st.eye_rays;
        sum.eye_hits += all[r].st.eye_hits;
        sum.shadow_rays += all[r].st.shadow_rays;
        sum.shadow_blocked += all[r].st.shadow_blocked;
        sum.secondary_rays += all[r].st.secondary_rays;
        sum.secondary_hits += all[r].st.secondary_hits;
        sum.closest_nodes += all[r].st.closest_nodes;
        sum.closest_tests += all[r].st.closest_tests;
        sum.any_nodes += all[r].st.any_nodes;
        sum.any_tests += all[r].st.any_tests;
    }
    rays = sum.eye_rays + sum.shadow_rays + sum.secondary_rays;
    progress_format_rate(rate, sizeof rate, render_s > 0 ? (double)rays / render_s * 1e-6 : 0);
    if (!j->o.quiet)
        printf("clwhitted-mpi: wrote %s (%dx%d, depth %d) in %.3f s on %d rank%s: render %.3f "
               "s, %s Mrays/s\n",
               sys_escape(shown, sizeof shown, j->output), j->s.width, j->s.height, j->s.max_depth,
               total_s, j->size, j->size == 1 ? "" : "s", render_s, rate);
    if (!j->o.settings.stats)
        return;
    printf("rays: eye %llu (hit %llu), shadow %llu (blocked %llu), secondary %llu (hit %llu)\n",
           sum.eye_rays, sum.eye_hits, sum.shadow_rays, sum.shadow_blocked, sum.secondary_rays,
           sum.secondary_hits);
    render_format_walk(&sum, walk, sizeof walk);
    printf("%s\n", walk);
    for (r = 0; r < j->size; r++)
        printf("rank %d: %d tiles, set-up %.3f s, render %.3f s, %llu rays, %s\n", r, all[r].tiles,
               all[r].setup_s, all[r].render_s,
               all[r].st.eye_rays + all[r].st.shadow_rays + all[r].st.secondary_rays,
               sys_escape(shown, sizeof shown, all[r].device));
}

/* Rank 0 after the render: the image from the accumulation, written atomically. */
static int finish(job *j, const float *acc, const mwork_rank *all, double render_s)
{
    char err[2048], ranks[32];
    batch_meta meta;
    image img = {0, 0, NULL};
    int rc = 1;
    if (renderer_resolve(j->r, acc, &img, err, sizeof err) != 0) {
        say(err);
        return 1;
    }
    snprintf(ranks, sizeof ranks, ", %d MPI ranks", j->size);
    batch_metadata(&j->o, j->o.scene, &j->s, j->r, sys_has_ext(j->output, ".exr"), render_s, ranks,
                   &j->o.write, &meta);
    if (image_write_ex(&img, j->output, &j->o.write, err, sizeof err) != 0) {
        say(err);
    } else {
        report(j, all, render_s, sys_now() - j->start);
        rc = fflush(stdout) == 0 ? 0 : 1;
    }
    image_free(&img);
    return rc;
}

/* The render, once every rank is set up. Returns rank 0's exit status (others: 0/1). */
static int render(job *j, progress_bar *bar)
{
    char err[2048], *env = getenv("CLWHITTED_MPI_TIMEOUT");
    mwork_job mj;
    mwork_rank *all = NULL;
    float *acc = NULL;
    double t0;
    int rc = 0;

    memset(&mj, 0, sizeof mj);
    mj.r = j->r;
    mj.rank = j->rank;
    mj.size = j->size;
    mj.bar = bar;
    mj.timeout_s = env ? atof(env) : 60.0;
    renderer_accum_size(j->r, &mj.width, &mj.height);
    env = getenv("CLWHITTED_MPI_TILE_ROWS");
    mj.tile_rows = mwork_tile_rows(mj.width, mj.height, j->size, env ? atoi(env) : 0);
    renderer_reset_trace_stats(j->r);
    t0 = sys_now();
    if (j->rank == 0) {
        acc = malloc((size_t)mj.width * (size_t)mj.height * 4 * sizeof *acc);
        all = malloc((size_t)j->size * sizeof *all);
        if (!acc || !all) {
            say("out of memory for the accumulation image");
            MPI_Abort(MPI_COMM_WORLD, 1);
        }
        progress_begin(bar);
        rc = mwork_master(&mj, acc, &j->mine, err, sizeof err) != 0;
        progress_clear(bar);
        if (rc)
            say(err);
    } else {
        rc = mwork_worker(&mj, &j->mine, err, sizeof err) != 0;
    }
    renderer_get_stats(j->r, &j->mine.st);
    MPI_Gather(&j->mine, (int)sizeof j->mine, MPI_BYTE, all, (int)sizeof j->mine, MPI_BYTE, 0,
               MPI_COMM_WORLD);
    if (j->rank == 0 && rc == 0)
        rc = finish(j, acc, all, sys_now() - t0);
    free(acc);
    free(all);
    return rc;
}

static void usage(void)
{
    printf("usage: mpirun [-np N] clwhitted-mpi [options] SCENE...\n"
           "Renders SCENE across the ranks of an MPI job: the image is the one clwhitted\n"
           "renders with the same options, bit for bit; several scenes one after the other,\n"
           "each to its own NAME.exr. The options are clwhitted's (clwhitted --help) but\n"
           "--preview and --crop; --device A,B,... gives a node's local rank L\n"
           "entry L modulo their count. Environment: CLWHITTED_MPI_TILE_ROWS (rows per tile),\n"
           "CLWHITTED_MPI_TIMEOUT (seconds a busy rank may stay silent; default 60, 0 off).\n"
           "See docs/mpi.md.\n");
}

/* Parses on every rank; only rank 0 prints (--version, usage errors). */
static int parse(job *j, int argc, char **argv, int *status)
{
    int saved_out = -1, saved_err = -1, rc, k;
    for (k = 1; k < argc; k++)
        if (strcmp(argv[k], "--help") == 0 || strcmp(argv[k], "-h") == 0) {
            if (j->rank == 0)
                usage();
            *status = 0;
            return CLI_EXIT;
        }
    if (j->rank != 0) {
        FILE *null = fopen("/dev/null", "w");
        fflush(stdout);
        fflush(stderr);
        saved_out = dup(STDOUT_FILENO);
        saved_err = dup(STDERR_FILENO);
        if (null) {
            dup2(fileno(null), STDOUT_FILENO);
            dup2(fileno(null), STDERR_FILENO);
            fclose(null);
        }
    }
    rc = cli_parse(argc, argv, &j->o, status);
    if (saved_out >= 0) {
        fflush(stdout);
        fflush(stderr);
        dup2(saved_out, STDOUT_FILENO);
        dup2(saved_err, STDERR_FILENO);
        close(saved_out);
        close(saved_err);
    }
    if (rc == CLI_RUN && (j->o.preview || j->o.settings.crop[1] != 0 || j->o.repeat > 1)) {
        if (j->rank == 0)
            fprintf(stderr, "clwhitted-mpi: %s is not available over MPI\n" CLI_HINT,
                    j->o.preview                 ? "--preview"
                    : j->o.settings.crop[1] != 0 ? "--crop"
                                                 : "--repeat");
        *status = 2;
        return CLI_EXIT;
    }
    return rc;
}

int main(int argc, char **argv)
{
    char err[2048];
    setup_report rep;
    progress_bar bar;
    MPI_Comm local;
    job j;
    int status = 1, k;

    memset(&j, 0, sizeof j);
    j.start = sys_now();
    if (MPI_Init(&argc, &argv) != MPI_SUCCESS) {
        say("MPI_Init failed");
        return 1;
    }
    MPI_Comm_set_errhandler(MPI_COMM_WORLD, MPI_ERRORS_RETURN);
    MPI_Comm_rank(MPI_COMM_WORLD, &j.rank);
    MPI_Comm_size(MPI_COMM_WORLD, &j.size);
    MPI_Comm_split_type(MPI_COMM_WORLD, MPI_COMM_TYPE_SHARED, j.rank, MPI_INFO_NULL, &local);
    MPI_Comm_rank(local, &j.local_rank);
    MPI_Comm_free(&local);
    scene_init(&j.s);
    if (parse(&j, argc, argv, &status) != CLI_RUN)
        goto out_finalize;
    sys_signals_install();
    if (j.o.list_devices) {
        status = 0;
        if (j.rank == 0 && renderer_list_devices(err, sizeof err) != 0) {
            say(err);
            status = 1;
        }
        goto out_finalize;
    }
    progress_init(&bar, stderr,
                  j.rank == 0 && progress_wanted(j.o.quiet, j.o.progress, isatty(STDERR_FILENO)));
    /* Several scenes: one after the other, each across every rank, each to its own
     * NAME.exr (as clwhitted); a scene that fails is reported and the next still renders,
     * the exit status is the worst. */
    status = 0;
    for (k = 0; k < j.o.nscenes; k++) {
        int st;
        j.o.scene = j.o.scenes[k];
        j.start = sys_now();
        scene_free(&j.s);
        scene_init(&j.s);
        free(j.default_out);
        j.default_out = NULL;
        j.output = NULL;
        memset(&j.mine, 0, sizeof j.mine);
        memset(&rep, 0, sizeof rep);
        if (j.rank == 0)
            progress_status(&bar, "loading the scene and building the kernels ...");
        rep.ok = setup(&j, &rep) == 0;
        progress_clear(&bar);
        st = gather_setups(&j, &rep) == 0 ? render(&j, &bar) : 1;
        MPI_Bcast(&st, 1, MPI_INT, 0, MPI_COMM_WORLD);
        if (st > status)
            status = st;
    }
out_finalize:
    renderer_destroy(j.r);
    scene_free(&j.s);
    free(j.default_out);
    MPI_Finalize();
    return status;
}
