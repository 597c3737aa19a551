/* Every limit and default of clwhitted in one place (like Lua's luaconf.h). The readers,
 * the scene checks, the command line, the renderer and the preview all take their bounds
 * from here; messages print these values. */
#ifndef CW_CONFIG_H
#define CW_CONFIG_H

/* Image size: pixels per side and per image (the per-image bound keeps the ~44 bytes of
 * device and host memory per pixel within reach). */
#define CW_MAX_SIDE 65536
#define CW_MAX_PIXELS (1L << 28)

/* Ray depth: the eye ray is depth 1; at most CW_MAX_DEPTH, CW_DEFAULT_DEPTH when the scene
 * and the command line say nothing. */
#define CW_MAX_DEPTH 64
#define CW_DEFAULT_DEPTH 5

/* Samples per pixel (--spp): 1..CW_MAX_SPP. */
#define CW_MAX_SPP 65536

/* PNG exposure (--exposure EV): -CW_MAX_EXPOSURE..CW_MAX_EXPOSURE. */
#define CW_MAX_EXPOSURE 64

/* Scene files: bytes per file, magnitude of any number, vertices per polygon or patch. */
#define CW_MAX_FILE_BYTES (1L << 30)
#define CW_MAX_ABS 1e18
#define CW_MAX_VERTS 10000000

/* Image writing: at most CW_MAX_WRITE_THREADS threads (and no more than the online CPUs)
 * compress an image; a PNG is compressed in independent pieces of whole rows, about
 * CW_PNG_PIECE_BYTES of filtered rows each (the file's bytes depend on this, never on the
 * number of threads). */
#define CW_MAX_WRITE_THREADS 8
#define CW_PNG_PIECE_BYTES 65536

/* The NFF reader reads its file this many bytes at a time (a window that stays in the
 * cache, instead of the whole file in memory). */
#define CW_NFF_READ_CHUNK (1L << 18)

/* Threads that build the BVH (0: one per online core), and the most it will use. The tree
 * does not depend on the count. */
#define CW_BVH_THREADS 0
#define CW_BVH_MAX_THREADS 16

/* Scene arrays larger than this are uploaded in pieces of this many bytes, each given back
 * to the system once the device has it (render.c). */
#define CW_UPLOAD_PIECE ((size_t)32 << 20)

/* Rendering in bands of rows: the wavefront's ray queues, hits and shadow rays of a band
 * stay within CW_BAND_BYTES; the per-pixel kernel traces a band in launches of about
 * CW_PIXEL_LAUNCH_PIXELS pixels, each followed by the counters' read and a progress report. */
#define CW_BAND_BYTES ((size_t)64 << 20)
#define CW_PIXEL_LAUNCH_PIXELS 65536

/* The kernel cache (progcache.c) reads entries of at most this many bytes. */
#define CW_PROGCACHE_MAX_BYTES (256LL << 20)

/* --repeat N: 1..CW_MAX_REPEAT. */
#define CW_MAX_REPEAT 1000

/* --threads N: 1..CW_MAX_THREADS. */
#define CW_MAX_THREADS 1024

/* CLWHITTED_PROGRESS=log: a progress line every CW_PROGRESS_LOG_S seconds. */
#define CW_PROGRESS_LOG_S 5

/* The preview's default samples per pixel before it stops refining. */
#define CW_PREVIEW_DEFAULT_SPP 16

#endif
