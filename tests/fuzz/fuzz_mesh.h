/* The property of the mesh reader (host/mesh_scene.c over host/mesh_import.c, assimp
 * underneath), shared by the fuzz target (fuzz_mesh.c) and test_fuzzcorpus. An input is
 * "HINT\n" then the file's bytes, HINT one of obj, ply, stl, glb, gltf: the format assimp
 * is told (without that first line, the first byte picks one). The reader must
 *
 *   - return 0 or -1, and not crash, hang, leak or read out of bounds;
 *   - on -1 give "fuzz.HINT: message", printable (no control characters);
 *   - on 0 give a scene that scene_finish accepts at its own size.
 *
 * Mesh files have no line numbers to give (assimp reports elements, not lines). */
#ifndef CW_FUZZ_MESH_H
#define CW_FUZZ_MESH_H

#include "mesh_scene.h"
#include "scene.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static const char *const fuzz_mesh_hints[] = {"obj", "ply", "stl", "glb", "gltf"};

/* The hint of an input, and where the file's bytes start. FUZZ_MESH_HINT=ply in the
 * environment forces one format (the first line is then part of the file). */
static const char *fuzz_mesh_split(const unsigned char *data, size_t size, size_t *skip)
{
    size_t i;
    const char *forced = getenv("FUZZ_MESH_HINT");
    if (forced && *forced) {
        *skip = 0;
        return forced;
    }
    for (i = 0; i < sizeof fuzz_mesh_hints / sizeof fuzz_mesh_hints[0]; i++) {
        size_t n = strlen(fuzz_mesh_hints[i]);
        if (size > n && memcmp(data, fuzz_mesh_hints[i], n) == 0 && data[n] == '\n') {
            *skip = n + 1;
            return fuzz_mesh_hints[i];
        }
    }
    *skip = 0;
    return fuzz_mesh_hints[size > 0 ? data[0] % 5 : 0];
}

/* 0 when the mesh reader behaved on data[0..size), else -1 with why. */
static int fuzz_check_mesh(const unsigned char *data, size_t size, char *why, size_t whylen)
{
    scene s;
    char err[1024], name[32];
    size_t skip, n;
    const char *hint = fuzz_mesh_split(data, size, &skip), *p;
    int rc, ok = 0;
    snprintf(name, sizeof name, "fuzz.%s", hint);
    n = strlen(name);
    err[0] = '\0';
    scene_init(&s);
    rc = mesh_scene_memory(data + skip, size - skip, hint, name, &s, err, sizeof err);
    if (rc == 0) {
        if (scene_finish(&s, 0, 0, 0, err, sizeof err) != 0) {
            snprintf(why, whylen, "the reader accepted the mesh, but scene_finish failed: %s", err);
            ok = -1;
        }
    } else if (rc != -1) {
        snprintf(why, whylen, "the reader returned %d (expected 0 or -1)", rc);
        ok = -1;
    } else if (strncmp(err, name, n) != 0 || err[n] != ':' || err[n + 1] != ' ' || !err[n + 2]) {
        snprintf(why, whylen, "the message is not \"%s: message\": \"%.200s\"", name, err);
        ok = -1;
    } else {
        for (p = err; *p; p++)
            if ((unsigned char)*p < 0x20 || *p == 0x7f) {
                snprintf(why, whylen, "control character 0x%02x at offset %ld of the message",
                         (unsigned)(unsigned char)*p, (long)(p - err));
                ok = -1;
                break;
            }
    }
    scene_free(&s);
    return ok;
}

#endif
