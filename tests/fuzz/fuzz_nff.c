/* libFuzzer target for the NFF reader (host/scene_nff.c): see fuzz_check.h for the property.
 * One more for this reader: the file read in pieces (nff_load_chunked, the path nff_load
 * takes) gives what parsing the whole text gives: the same result, scene and message. */
#include "fuzz_check.h"

#include "scene_nff.h"

#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

/* Aborts unless reading data from a file in pieces of each size agrees with nff_parse. */
static void check_pieces(const uint8_t *data, size_t size)
{
    static char path[64];
    static const size_t chunks[] = {5, 64};
    scene whole;
    char whole_err[1024] = "";
    int whole_rc;
    size_t c;
    FILE *f;
    if (!path[0]) {
        int fd;
        snprintf(path, sizeof path, "/tmp/fuzz_nff-XXXXXX");
        fd = mkstemp(path);
        if (fd < 0) {
            perror("fuzz_nff: mkstemp");
            abort();
        }
        close(fd);
    }
    f = fopen(path, "wb");
    if (!f || fwrite(data, 1, size, f) != size || fclose(f) != 0) {
        perror("fuzz_nff: writing the input");
        abort();
    }
    scene_init(&whole);
    whole_rc = nff_parse((const char *)data, size, path, &whole, whole_err, sizeof whole_err);
    for (c = 0; c < sizeof chunks / sizeof chunks[0]; c++) {
        scene s;
        char err[1024] = "";
        int rc, same;
        scene_init(&s);
        rc = nff_load_chunked(path, chunks[c], &s, err, sizeof err);
        same = rc == whole_rc && strcmp(err, whole_err) == 0;
        if (same && rc == 0) {
            same = s.triangles.count == whole.triangles.count &&
                   s.spheres.count == whole.spheres.count &&
                   s.polygons.count == whole.polygons.count &&
                   s.poly_verts.count == whole.poly_verts.count &&
                   s.cones.count == whole.cones.count && s.lights.count == whole.lights.count &&
                   s.tri_normals.count == whole.tri_normals.count &&
                   s.materials.count == whole.materials.count &&
                   memcmp(&s.camera, &whole.camera, sizeof s.camera) == 0 &&
                   (s.triangles.count == 0 ||
                    memcmp(s.triangles.data, whole.triangles.data,
                           s.triangles.count * sizeof(scene_triangle)) == 0) &&
                   (s.spheres.count == 0 || memcmp(s.spheres.data, whole.spheres.data,
                                                   s.spheres.count * sizeof(scene_sphere)) == 0);
        }
        if (!same) {
            fprintf(stderr, "fuzz_nff: in pieces of %zu bytes: %d \"%s\"; whole: %d \"%s\"\n",
                    chunks[c], rc, err, whole_rc, whole_err);
            abort();
        }
        scene_free(&s);
    }
    scene_free(&whole);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    char why[1536];
    if (fuzz_check(nff_parse, "fuzz.nff", data, size, why, sizeof why) != 0) {
        fprintf(stderr, "fuzz_nff: %s\n", why);
        abort();
    }
    check_pieces(data, size);
    return 0;
}
