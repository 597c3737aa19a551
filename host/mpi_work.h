/* clwhitted-mpi's work distribution (mpi_work.c): rank 0 hands out bands of rows (tiles)
 * on request, renders tiles itself between requests, and gathers the accumulation image;
 * the other ranks render the tiles they are given and send them back. */
#ifndef CW_MPI_WORK_H
#define CW_MPI_WORK_H

#include <stddef.h>

#include "progress.h"
#include "render.h"

/* One rank's part of a job, gathered on rank 0 at the end (sent as bytes: every rank runs
 * the same binary). */
typedef struct {
    int tiles;       /* tiles rendered */
    int failed;      /* the rank's render failed (its message went to rank 0) */
    double render_s; /* time in renderer_render_rows */
    double setup_s;  /* scene load, OpenCL start, kernel build and upload */
    render_stats st; /* ray counts over its tiles */
    char device[128];
} mwork_rank;

typedef struct {
    renderer *r;
    int rank, size;
    int width, height; /* the accumulation image (renderer_accum_size) */
    int tile_rows;     /* rows per tile */
    double timeout_s;  /* a busy rank silent for longer ends the job (<= 0: never) */
    progress_bar *bar; /* rank 0's progress bar */
} mwork_job;

/* Rows per tile: about 8 tiles per rank for balance, at least MWORK_MIN_TILE_PIXELS pixels
 * each (per-tile costs), at most the whole image; env_rows (CLWHITTED_MPI_TILE_ROWS) > 0
 * sets it. */
#define MWORK_MIN_TILE_PIXELS 16384
int mwork_tile_rows(int width, int height, int ranks, int env_rows);

/* Rank 0: the whole accumulation image into acc (width * height * 4 floats). Returns 0, or
 * -1 with err (naming the rank at fault) once every other rank has stopped. When the
 * others cannot be stopped (a rank silent for timeout_s, an MPI error, a broken message)
 * it prints why and aborts the job (MPI_Abort). */
int mwork_master(const mwork_job *j, float *acc, mwork_rank *mine, char *err, size_t errlen);

/* Every other rank: renders the tiles rank 0 hands out until told to stop. Returns 0, or
 * -1 after sending err to rank 0. */
int mwork_worker(const mwork_job *j, mwork_rank *mine, char *err, size_t errlen);

#endif
