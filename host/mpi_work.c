/* clwhitted-mpi's work distribution. Rank 0 holds the tile counter: a rank asks for tiles
 * (TAG_REQ), rank 0 answers each request with the next tile's number or -1 (no more), and
 * the rank sends each tile's rows back (TAG_RESULT) in the order it got them. A rank keeps
 * MWORK_AHEAD requests open, so that its next tile is known before it finishes one: rank 0
 * renders tiles too and answers only between its own kernel launches (from the renderer's
 * progress callback). After its last answer a rank says it is done (TAG_DONE). Waiting
 * ranks poll with short sleeps rather than spinning in MPI, so that ranks sharing cores
 * leave them to the ones rendering.
 * Ranks send a heartbeat with their ray count at least every MWORK_BEAT_S while rendering
 * (also from the progress callback); rank 0 ends the job (MPI_Abort) when a rank with a
 * tile is silent for timeout_s. A rank that dies is normally caught sooner by the MPI
 * runtime, which ends the whole job (Open MPI's mpirun does). */
#include "mpi_work.h"

#include <mpi.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "sys.h"

#define MWORK_BEAT_S 0.25
#define MWORK_AHEAD 2 /* requests a rank keeps open */
#define TAG_REQ 1     /* worker -> 0: a tile, please (no data) */
#define TAG_RESULT 2  /* worker -> 0: the floats of its oldest tile */
#define TAG_BEAT 3    /* worker -> 0: rays traced so far (unsigned long long) */
#define TAG_FAIL 4    /* worker -> 0: its error message (it sends nothing more) */
#define TAG_DONE 5    /* worker -> 0: every answer received, nothing more to send */
#define TAG_TILE 6    /* 0 -> worker: the next tile (int), -1: no more */

/* Rank 0's view of the job. */
typedef struct {
    const mwork_job *j;
    float *acc;
    mwork_rank *mine;
    int ntiles, next, done;
    int *assigned;               /* per rank: MWORK_AHEAD slots, its tiles in order */
    int *nassigned;              /* per rank: how many of them */
    int *active;                 /* per rank: not yet done (nor failed) */
    double *last_seen;           /* per rank: sys_now() of its last message */
    unsigned long long *rays;    /* per rank: the rays of its last heartbeat */
    unsigned long long own_rays; /* rank 0's */
    double own_fraction;         /* of rank 0's current tile */
    int failed;                  /* a rank failed: hand out no more tiles */
    char *err;
    size_t errlen;
} master;

int mwork_tile_rows(int width, int height, int ranks, int env_rows)
{
    long long rows;
    if (env_rows > 0)
        return env_rows < height ? env_rows : height;
    rows = (height + 8LL * ranks - 1) / (8LL * ranks);
    if (rows * width < MWORK_MIN_TILE_PIXELS)
        rows = (MWORK_MIN_TILE_PIXELS + width - 1) / width;
    return rows < height ? (int)rows : height;
}

static void nap(void)
{
    struct timespec ts = {0, 200000}; /* 0.2 ms */
    nanosleep(&ts, NULL);
}

static int tile_span(const mwork_job *j, int tile, int *row0)
{
    *row0 = tile * j->tile_rows;
    return *row0 + j->tile_rows > j->height ? j->height - *row0 : j->tile_rows;
}

static size_t tile_floats(const mwork_job *j, int nrows)
{
    return (size_t)nrows * (size_t)j->width * 4;
}

static int mpi_failed(int e, const char *call, char *err, size_t errlen)
{
    char msg[MPI_MAX_ERROR_STRING];
    int len = 0;
    if (MPI_Error_string(e, msg, &len) != MPI_SUCCESS)
        snprintf(msg, sizeof msg, "error %d", e);
    snprintf(err, errlen, "%s failed: %s", call, msg);
    return -1;
}

/* ---- rank 0 -------------------------------------------------------------------------- */

static void master_progress(master *m)
{
    unsigned long long rays = m->own_rays;
    int w;
    for (w = 1; w < m->j->size; w++)
        rays += m->rays[w];
    progress_update(m->j->bar, ((double)m->done + m->own_fraction) / m->ntiles, rays);
}

/* Answers rank w's request: the next tile, or -1. */
static int master_answer(master *m, int w)
{
    int tile = -1, e;
    if (!m->failed && m->next < m->ntiles && m->nassigned[w] < MWORK_AHEAD) {
        tile = m->next++;
        m->assigned[w * MWORK_AHEAD + m->nassigned[w]++] = tile;
    }
    e = MPI_Send(&tile, 1, MPI_INT, w, TAG_TILE, MPI_COMM_WORLD);
    return e == MPI_SUCCESS ? 0 : mpi_failed(e, "MPI_Send(tile)", m->err, m->errlen);
}

/* Receives rank w's oldest tile (probed: st). */
static int master_result(master *m, MPI_Status *st)
{
    int w = st->MPI_SOURCE, count = 0, row0 = 0, nrows = 0, tile = -1, k, e;
    if (m->nassigned[w] > 0) {
        tile = m->assigned[w * MWORK_AHEAD];
        nrows = tile_span(m->j, tile, &row0);
    }
    MPI_Get_count(st, MPI_FLOAT, &count);
    if (tile < 0 || (size_t)count != tile_floats(m->j, nrows)) {
        snprintf(m->err, m->errlen, "rank %d sent %d floats for tile %d (%d rows)", w, count, tile,
                 nrows);
        return -1;
    }
    e = MPI_Recv(m->acc + tile_floats(m->j, row0), count, MPI_FLOAT, w, TAG_RESULT, MPI_COMM_WORLD,
                 MPI_STATUS_IGNORE);
    if (e != MPI_SUCCESS)
        return mpi_failed(e, "MPI_Recv(tile)", m->err, m->errlen);
    for (k = 1; k < m->nassigned[w]; k++)
        m->assigned[w * MWORK_AHEAD + k - 1] = m->assigned[w * MWORK_AHEAD + k];
    m->nassigned[w]--;
    m->done++;
    return 0;
}

/* Receives one message from rank w (probed: st). */
static int master_receive(master *m, MPI_Status *st)
{
    int w = st->MPI_SOURCE, count = 0, e = MPI_SUCCESS;
    m->last_seen[w] = sys_now();
    if (st->MPI_TAG == TAG_BEAT) {
        e = MPI_Recv(&m->rays[w], 1, MPI_UNSIGNED_LONG_LONG, w, TAG_BEAT, MPI_COMM_WORLD,
                     MPI_STATUS_IGNORE);
    } else if (st->MPI_TAG == TAG_FAIL) {
        char *msg;
        MPI_Get_count(st, MPI_CHAR, &count);
        msg = calloc((size_t)(count > 0 ? count : 0) + 1, 1);
        e = MPI_Recv(msg, msg ? count : 0, MPI_CHAR, w, TAG_FAIL, MPI_COMM_WORLD,
                     MPI_STATUS_IGNORE);
        m->active[w] = 0;
        if (!m->failed)
            snprintf(m->err, m->errlen, "rank %d: %s", w, msg ? msg : "failed (out of memory)");
        m->failed = 1;
        free(msg);
    } else if (st->MPI_TAG == TAG_RESULT) {
        return master_result(m, st);
    } else if (st->MPI_TAG == TAG_REQ || st->MPI_TAG == TAG_DONE) {
        e = MPI_Recv(NULL, 0, MPI_INT, w, st->MPI_TAG, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
        if (e == MPI_SUCCESS && st->MPI_TAG == TAG_DONE)
            m->active[w] = 0;
        if (e == MPI_SUCCESS && st->MPI_TAG == TAG_REQ)
            return master_answer(m, w);
    } else {
        snprintf(m->err, m->errlen, "rank %d sent an unknown message (tag %d)", w, st->MPI_TAG);
        return -1;
    }
    return e == MPI_SUCCESS ? 0 : mpi_failed(e, "MPI_Recv", m->err, m->errlen);
}

/* Ends the job from rank 0 with err: the other ranks cannot be stopped cleanly (MPI failed,
 * a rank broke the protocol, or a rank is silent). */
static void master_abort(master *m)
{
    char shown[1024];
    progress_clear(m->j->bar);
    fprintf(stderr, "clwhitted-mpi: %s\n", sys_escape(shown, sizeof shown, m->err));
    fflush(stderr);
    MPI_Abort(MPI_COMM_WORLD, 1);
}

/* A busy rank silent for longer than the timeout: the job cannot end cleanly (the rank may
 * hang in a driver), so it is aborted here. */
static void master_watchdog(master *m)
{
    double now = sys_now();
    int w;
    if (m->j->timeout_s <= 0)
        return;
    for (w = 1; w < m->j->size; w++)
        if (m->active[w] && m->nassigned[w] > 0 && now - m->last_seen[w] > m->j->timeout_s) {
            snprintf(m->err, m->errlen,
                     "rank %d sent nothing for %.0f s (killed or hung?); ending the job with no "
                     "image",
                     w, now - m->last_seen[w]);
            master_abort(m);
        }
}

/* Handles every message waiting. Returns 0, or -1 with err. */
static int master_serve(master *m)
{
    for (;;) {
        MPI_Status st;
        int flag = 0, e = MPI_Iprobe(MPI_ANY_SOURCE, MPI_ANY_TAG, MPI_COMM_WORLD, &flag, &st);
        if (e != MPI_SUCCESS)
            return mpi_failed(e, "MPI_Iprobe", m->err, m->errlen);
        if (!flag)
            break;
        if (master_receive(m, &st) != 0)
            return -1;
    }
    master_watchdog(m);
    return 0;
}

/* rank 0's progress callback: serves the other ranks between its own launches. */
static int master_callback(void *ctx, double fraction, unsigned long long rays)
{
    master *m = ctx;
    m->own_fraction = fraction;
    m->own_rays = rays;
    if (master_serve(m) != 0)
        master_abort(m);
    master_progress(m);
    return m->failed != 0;
}

static int any_active(const master *m)
{
    int w;
    for (w = 1; w < m->j->size; w++)
        if (m->active[w])
            return 1;
    return 0;
}

int mwork_master(const mwork_job *j, float *acc, mwork_rank *mine, char *err, size_t errlen)
{
    master m;
    char own_err[1024];
    int w, rc = -1;
    double now = sys_now();

    memset(&m, 0, sizeof m);
    m.j = j;
    m.acc = acc;
    m.mine = mine;
    m.err = err;
    m.errlen = errlen;
    m.ntiles = (j->height + j->tile_rows - 1) / j->tile_rows;
    m.assigned = malloc((size_t)j->size * MWORK_AHEAD * sizeof *m.assigned);
    m.nassigned = calloc((size_t)j->size, sizeof *m.nassigned);
    m.active = malloc((size_t)j->size * sizeof *m.active);
    m.last_seen = malloc((size_t)j->size * sizeof *m.last_seen);
    m.rays = calloc((size_t)j->size, sizeof *m.rays);
    if (!m.assigned || !m.nassigned || !m.active || !m.last_seen || !m.rays) {
        snprintf(err, errlen, "out of memory");
        master_abort(&m);
    }
    for (w = 0; w < j->size; w++) {
        m.active[w] = w > 0;
        m.last_seen[w] = now;
    }
    renderer_set_progress(j->r, master_callback, &m);
    while (!m.failed && m.next < m.ntiles) {
        int tile = m.next++, row0, nrows = tile_span(j, tile, &row0);
        double t0 = sys_now();
        m.own_fraction = 0;
        if (renderer_render_rows(j->r, row0, nrows, acc + tile_floats(j, row0), own_err,
                                 sizeof own_err) != 0) {
            if (!m.failed) /* else a rank's failure cancelled it: err says which */
                snprintf(err, errlen, "rank 0: %s", own_err);
            m.failed = m.failed ? m.failed : 1;
            break;
        }
        mine->render_s += sys_now() - t0;
        mine->tiles++;
        m.done++;
        m.own_fraction = 0;
        master_progress(&m);
    }
    renderer_set_progress(j->r, NULL, NULL);
    /* the other ranks' last tiles, then every rank done */
    while (any_active(&m)) {
        if (master_serve(&m) != 0)
            master_abort(&m);
        master_progress(&m);
        nap();
    }
    rc = m.failed ? -1 : 0;
    free(m.assigned);
    free(m.nassigned);
    free(m.active);
    free(m.last_seen);
    free(m.rays);
    return rc;
}

/* ---- the other ranks -------------------------------------------------------------------- */

typedef struct {
    double last_beat;
    int mpi_error;
} worker;

/* A worker's progress callback: the heartbeat. */
static int worker_callback(void *ctx, double fraction, unsigned long long rays)
{
    worker *wk = ctx;
    double now = sys_now();
    (void)fraction;
    if (now - wk->last_beat >= MWORK_BEAT_S) {
        wk->last_beat = now;
        if (MPI_Send(&rays, 1, MPI_UNSIGNED_LONG_LONG, 0, TAG_BEAT, MPI_COMM_WORLD) != MPI_SUCCESS)
            wk->mpi_error = 1;
    }
    return wk->mpi_error;
}

/* Waits (polling, with naps) for rank 0's answer. Returns 0, or -1 with err. */
static int worker_next_tile(int *tile, char *err, size_t errlen)
{
    int flag = 0, e;
    MPI_Status st;
    while ((e = MPI_Iprobe(0, TAG_TILE, MPI_COMM_WORLD, &flag, &st)) == MPI_SUCCESS && !flag)
        nap();
    if (e == MPI_SUCCESS)
        e = MPI_Recv(tile, 1, MPI_INT, 0, TAG_TILE, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
    return e == MPI_SUCCESS ? 0 : mpi_failed(e, "waiting for a tile", err, errlen);
}

int mwork_worker(const mwork_job *j, mwork_rank *mine, char *err, size_t errlen)
{
    worker wk = {0, 0};
    float *buf = malloc(tile_floats(j, j->tile_rows) * sizeof *buf);
    int tile = -1, open = 0, more = 1, rc = -1, e;

    if (!buf) {
        snprintf(err, errlen, "out of memory for a %d-row tile", j->tile_rows);
        goto out_fail;
    }
    renderer_set_progress(j->r, worker_callback, &wk);
    for (;;) {
        int row0 = 0, nrows;
        double t0;
        for (e = MPI_SUCCESS; more && open < MWORK_AHEAD && e == MPI_SUCCESS; open++)
            e = MPI_Send(NULL, 0, MPI_INT, 0, TAG_REQ, MPI_COMM_WORLD);
        if (e != MPI_SUCCESS) {
            mpi_failed(e, "MPI_Send(request)", err, errlen);
            goto out_free; /* rank 0 cannot be told */
        }
        if (open == 0)
            break;
        if (worker_next_tile(&tile, err, errlen) != 0)
            goto out_free;
        open--;
        if (tile < 0) {
            more = 0; /* every later answer is -1 too */
            continue;
        }
        nrows = tile_span(j, tile, &row0);
        t0 = sys_now();
        wk.last_beat = t0;
        if (renderer_render_rows(j->r, row0, nrows, buf, err, errlen) != 0)
            goto out_fail;
        mine->render_s += sys_now() - t0;
        mine->tiles++;
        e = MPI_Send(buf, (int)tile_floats(j, nrows), MPI_FLOAT, 0, TAG_RESULT, MPI_COMM_WORLD);
        if (e != MPI_SUCCESS) {
            mpi_failed(e, "MPI_Send(tile)", err, errlen);
            goto out_free;
        }
    }
    rc = 0;
    if (MPI_Send(NULL, 0, MPI_INT, 0, TAG_DONE, MPI_COMM_WORLD) != MPI_SUCCESS)
        rc = -1;
    goto out_free;
out_fail:
    mine->failed = 1;
    MPI_Send(err, (int)strlen(err) + 1, MPI_CHAR, 0, TAG_FAIL, MPI_COMM_WORLD);
out_free:
    renderer_set_progress(j->r, NULL, NULL);
    free(buf);
    return rc;
}
