/* A cache of built kernel programs: the device binary (CL_PROGRAM_BINARIES) of each
 * (kernel source, build options, device, driver) in CLWHITTED_CACHE_DIR (default
 * $XDG_CACHE_HOME/clwhitted or ~/.cache/clwhitted; an empty value turns it off). */
#ifndef CW_PROGCACHE_H
#define CW_PROGCACHE_H

#include <CL/cl.h>

/* A program built from the cached binary, or NULL (no entry, or it did not load or
 * build: the caller then builds from source). */
cl_program progcache_load(cl_context ctx, cl_device_id dev, const char *source,
                          const char *options);

/* Saves the binary of a program built from source (temporary file + rename; failures are
 * ignored). */
void progcache_store(cl_program p, cl_device_id dev, const char *source, const char *options);

#endif
