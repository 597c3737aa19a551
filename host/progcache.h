/* The cache of built kernel programs (see progcache.c). */
#ifndef CW_PROGCACHE_H
#define CW_PROGCACHE_H

#include <stddef.h>

#include <CL/cl.h>

/* The header of a cache file, before the device binary: all fields little-endian. */
#define PROGCACHE_MAGIC "CWKCACHE"
#define PROGCACHE_VERSION 1u
#define PROGCACHE_HEADER_BYTES 48

/* What a cache file must match: the device and driver (progcache_identity) and the
 * program (kernel source and build options), as 64-bit hashes. */
typedef struct {
    unsigned long long device; /* device and driver identity */
    unsigned long long build;  /* kernel source and build options */
} progcache_key;

/* The key of the embedded source built with options for dev. */
void progcache_key_of(cl_device_id dev, const char *source, const char *options, progcache_key *k);

/* The header of a payload of len bytes for key k, into h[PROGCACHE_HEADER_BYTES]. */
void progcache_header(const progcache_key *k, const unsigned char *payload, size_t len,
                      unsigned char *h);

/* Checks a whole cache file (header and payload) against k. Returns 0, or -1 with the
 * reason in why ("bad magic", "checksum mismatch", ...). */
int progcache_check(const unsigned char *file, size_t len, const progcache_key *k, char *why,
                    size_t whylen);

/* A program built from the cache, or NULL: no entry (silently), or an entry that does not
 * verify or that the driver refuses (one warning on stderr; the caller then builds from
 * source and progcache_store replaces the entry). */
cl_program progcache_load(cl_context ctx, cl_device_id dev, const char *source,
                          const char *options);

/* Saves the binary of a program built from source: a temporary file in the cache folder
 * (created exclusively, never through a link) renamed over the entry. Failures are
 * ignored: the cache only saves time. */
void progcache_store(cl_program p, cl_device_id dev, const char *source, const char *options);

#endif
