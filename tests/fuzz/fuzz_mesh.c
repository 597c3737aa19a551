/* libFuzzer target for the mesh reader (host/mesh_scene.c, host/mesh_import.c; assimp
 * itself is not instrumented): see fuzz_mesh.h for the inputs and the property. */
#include "fuzz_mesh.h"

#include <stdint.h>
#include <stdlib.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    char why[1536];
    if (fuzz_check_mesh(data, size, why, sizeof why) != 0) {
        fprintf(stderr, "fuzz_mesh: %s\n", why);
        abort();
    }
    return 0;
}
