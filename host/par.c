/* Numbered jobs on a few threads, their results consumed in order on the calling thread.
 * One mutex and one condition variable: workers take the next job while it is within the
 * window of the next one to emit; the caller emits whatever is next when it is done and
 * otherwise takes jobs too. See par.h. */
#include "par.h"

#include <pthread.h>
#include <stdlib.h>

#include "config.h"

typedef struct {
    pthread_mutex_t mu;
    pthread_cond_t cv;
    int njobs, window;
    int next_job, next_emit; /* the next job to start; the next to emit */
    int rc;                  /* the first non-zero return */
    unsigned char *done;     /* per slot: its job has finished and is not yet emitted */
    par_job_fn job;
    void *ctx;
} par_state;

typedef struct {
    par_state *s;
    int thread;
} par_worker;

/* With the mutex held: the next job to start, or -1 (none left, stopped, or the window is
 * full). */
static int take_job(par_state *s)
{
    if (s->rc || s->next_job >= s->njobs || s->next_job >= s->next_emit + s->window)
        return -1;
    return s->next_job++;
}

/* Runs job j without the mutex (held on entry and on return) and marks its slot done. */
static void run_job(par_state *s, int j, int thread)
{
    int rc;
    pthread_mutex_unlock(&s->mu);
    rc = s->job(s->ctx, j, thread);
    pthread_mutex_lock(&s->mu);
    if (rc && !s->rc)
        s->rc = rc;
    s->done[j % s->window] = 1;
    pthread_cond_broadcast(&s->cv);
}

static void *worker_main(void *arg)
{
    par_worker *w = arg;
    par_state *s = w->s;
    pthread_mutex_lock(&s->mu);
    for (;;) {
        int j = take_job(s);
        if (j >= 0)
            run_job(s, j, w->thread);
        else if (s->rc || s->next_job >= s->njobs)
            break;
        else
            pthread_cond_wait(&s->cv, &s->mu);
    }
    pthread_mutex_unlock(&s->mu);
    return NULL;
}

/* The caller's loop: emit the next job when it is done, else run a job, else wait. */
static void caller_loop(par_state *s, par_emit_fn emit)
{
    pthread_mutex_lock(&s->mu);
    while (s->next_emit < s->njobs && !s->rc) {
        int slot = s->next_emit % s->window, j;
        if (s->done[slot]) {
            int rc;
            pthread_mutex_unlock(&s->mu);
            rc = emit ? emit(s->ctx, s->next_emit) : 0; /* next_emit changes only here */
            pthread_mutex_lock(&s->mu);
            if (rc && !s->rc)
                s->rc = rc;
            s->done[slot] = 0;
            s->next_emit++;
            pthread_cond_broadcast(&s->cv);
        } else if ((j = take_job(s)) >= 0) {
            run_job(s, j, 0);
        } else {
            pthread_cond_wait(&s->cv, &s->mu);
        }
    }
    pthread_mutex_unlock(&s->mu);
}

/* Without other threads: job, emit, job, emit, ... */
static int run_serial(int njobs, par_job_fn job, par_emit_fn emit, void *ctx)
{
    int j, rc;
    for (j = 0; j < njobs; j++)
        if ((rc = job(ctx, j, 0)) != 0 || (emit && (rc = emit(ctx, j)) != 0))
            return rc;
    return 0;
}

int par_ordered(int njobs, int threads, int window, par_job_fn job, par_emit_fn emit, void *ctx)
{
    par_state s;
    par_worker w[CW_MAX_WRITE_THREADS];
    pthread_t tid[CW_MAX_WRITE_THREADS];
    int started = 0, i;

    if (threads > CW_MAX_WRITE_THREADS)
        threads = CW_MAX_WRITE_THREADS;
    if (threads > njobs)
        threads = njobs;
    if (window < 1)
        window = 1;
    if (threads <= 1 || window == 1)
        return run_serial(njobs, job, emit, ctx);
    s.done = calloc((size_t)window, 1);
    if (!s.done)
        return run_serial(njobs, job, emit, ctx);
    if (pthread_mutex_init(&s.mu, NULL) != 0) {
        free(s.done);
        return run_serial(njobs, job, emit, ctx);
    }
    if (pthread_cond_init(&s.cv, NULL) != 0) {
        pthread_mutex_destroy(&s.mu);
        free(s.done);
        return run_serial(njobs, job, emit, ctx);
    }
    s.njobs = njobs;
    s.window = window;
    s.next_job = s.next_emit = s.rc = 0;
    s.job = job;
    s.ctx = ctx;
    for (i = 1; i < threads; i++) {
        w[started].s = &s;
        w[started].thread = i;
        if (pthread_create(&tid[started], NULL, worker_main, &w[started]) != 0)
            break; /* fewer threads; the caller alone is enough */
        started++;
    }
    caller_loop(&s, emit);
    for (i = 0; i < started; i++)
        pthread_join(tid[i], NULL);
    pthread_cond_destroy(&s.cv);
    pthread_mutex_destroy(&s.mu);
    free(s.done);
    return s.rc;
}
