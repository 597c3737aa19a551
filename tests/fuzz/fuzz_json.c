/* libFuzzer target for the JSON reader (host/scene_json.c): see fuzz_check.h for the property. */
#include "fuzz_check.h"

#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    char why[1536];
    if (fuzz_check(json_scene_parse, "fuzz.json", data, size, why, sizeof why) != 0) {
        fprintf(stderr, "fuzz_json: %s\n", why);
        abort();
    }
    return 0;
}
