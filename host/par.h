/* Numbered jobs on a few threads whose results are consumed in order on the calling thread
 * (par.c): the image writers compress pieces of an image in parallel and write them in
 * file order. */
#ifndef CW_PAR_H
#define CW_PAR_H

/* job(ctx, j, thread) computes job j on thread `thread` (0 is the caller; thread indices are
 * below the `threads` given to par_ordered, so per-thread state can be an array); emit(ctx,
 * j) consumes its result on the calling thread (emit NULL: jobs whose results are written
 * in place, nothing to consume). Both return 0, or non-zero to stop. */
typedef int (*par_job_fn)(void *ctx, int job, int thread);
typedef int (*par_emit_fn)(void *ctx, int job);

/* Runs the jobs 0..njobs-1 on up to `threads` threads (the caller and threads - 1 started
 * here; fewer when there are fewer jobs or a thread cannot be started) and emits each one
 * after its job, in order 0, 1, ..., on the calling thread. Job j starts only after job
 * j - window has been emitted, so `window` result slots (job j in slot j % window) are
 * enough, and a slot is never written while it is emitted. After the first non-zero
 * return no more jobs start; the others finish, and par_ordered returns that value (0
 * when all jobs ran and were emitted). */
int par_ordered(int njobs, int threads, int window, par_job_fn job, par_emit_fn emit, void *ctx);

#endif
