/* libFuzzer target for the NFF reader (host/scene_nff.c): see fuzz_check.h for the property. */
#include "fuzz_check.h"

#include "scene_nff.h"

FUZZ_TARGET("fuzz_nff", nff_parse, "fuzz.nff")
