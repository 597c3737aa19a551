/* libFuzzer target for the mesh reader (host/mesh_scene.c, host/mesh_import.c; assimp
 * itself is not instrumented): see fuzz_mesh.h for the inputs and the property.
 *
 * assimp 5.2 (Debian 12) crashes within a minute of fuzzing on OBJ (a write through a
 * bad pointer in its OBJ parser) and PLY input (a read past a malformed header): its own
 * bugs, which clwhitted turns into an error naming the file (sys_guard_begin) but which
 * would stop every run here. So inputs for those two formats are skipped unless
 * FUZZ_MESH_ALL=1 (or FUZZ_MESH_HINT=obj) is set: by default the target fuzzes STL, glTF
 * and binary glTF, which reach all of clwhitted's code after assimp. The format hint does
 * not keep assimp's other readers away (when the hinted one declines, assimp asks every
 * reader whether it knows the file), so inputs that assimp's OBJ or PLY reader would claim
 * are skipped too: as assimp 5.2 tells (its CanRead), a line starting with an OBJ keyword,
 * or "ply" anywhere, in the first 200 bytes, case and NUL bytes aside. */
#include "fuzz_mesh.h"

#include <ctype.h>
#include <stdint.h>
#include <stdlib.h>

/* Whether assimp 5.2's OBJ or PLY reader would take data (their CanRead tests). */
static int obj_or_ply(const uint8_t *data, size_t size)
{
    static const char *const obj[] = {"mtllib", "usemtl", "v ", "vt ", "vn ",
                                      "o ",     "g ",     "s ", "f "};
    char head[201];
    size_t n = 0, i, k;
    for (i = 0; i < size && i < 200; i++)
        if (data[i])
            head[n++] = (char)tolower(data[i]);
    head[n] = '\0';
    if (strstr(head, "ply"))
        return 1;
    for (i = 0; i < n; i++) {
        if (i > 0 && head[i - 1] != '\n' && head[i - 1] != '\r')
            continue;
        for (k = 0; k < sizeof obj / sizeof obj[0]; k++)
            if (strncmp(head + i, obj[k], strlen(obj[k])) == 0)
                return 1;
    }
    return 0;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    char why[1536];
    static int all = -1;
    size_t skip;
    const char *hint = fuzz_mesh_split(data, size, &skip);
    if (all < 0)
        all = (getenv("FUZZ_MESH_ALL") && strcmp(getenv("FUZZ_MESH_ALL"), "1") == 0) ||
              getenv("FUZZ_MESH_HINT");
    if (!all && (strcmp(hint, "obj") == 0 || strcmp(hint, "ply") == 0 ||
                 obj_or_ply(data + skip, size - skip)))
        return 0;
    if (fuzz_check_mesh(data, size, why, sizeof why) != 0) {
        fprintf(stderr, "fuzz_mesh: %s\n", why);
        abort();
    }
    return 0;
}
