/* libFuzzer target for the mesh reader (host/mesh_scene.c, host/mesh_import.c; assimp
 * itself is not instrumented): see fuzz_mesh.h for the inputs and the property.
 *
 * assimp 5.2 (Debian 12) crashes within a minute of fuzzing on OBJ (a write through a
 * bad pointer in its OBJ parser) and PLY input (a read past a malformed header): its own
 * bugs, which clwhitted turns into an error naming the file (sys_guard_begin) but which
 * would stop every run here. So inputs for those two formats are skipped unless
 * FUZZ_MESH_ALL=1 (or FUZZ_MESH_HINT=obj) is set: by default the target fuzzes STL, glTF
 * and binary glTF, which reach all of clwhitted's code after assimp. */
#include "fuzz_mesh.h"

#include <stdint.h>
#include <stdlib.h>

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
    if (!all && (strcmp(hint, "obj") == 0 || strcmp(hint, "ply") == 0))
        return 0;
    if (fuzz_check_mesh(data, size, why, sizeof why) != 0) {
        fprintf(stderr, "fuzz_mesh: %s\n", why);
        abort();
    }
    return 0;
}
