/* The NFF reader (Eric Haines' Neutral File Format, as the SPD generators write it); the
 * mapping into the scene model is described in scene_nff.c. */
#ifndef CW_SCENE_NFF_H
#define CW_SCENE_NFF_H

#include <stddef.h>

#include "scene.h"

/* nff_load reads a file (in pieces: never all of it in memory); nff_parse reads text in memory,
 * naming it `name` in errors. Both return 0, or -1 with "name:line: message" in err. */
int nff_load(const char *path, scene *s, char *err, size_t errlen);
int nff_parse(const char *text, size_t len, const char *name, scene *s, char *err, size_t errlen);

/* nff_load reading the file chunk bytes at a time (nff_load: CW_NFF_READ_CHUNK), for tests:
 * the result never depends on chunk. */
int nff_load_chunked(const char *path, size_t chunk, scene *s, char *err, size_t errlen);

#endif
