/* libFuzzer target for the JSON reader (host/scene_json.c): see fuzz_check.h for the property. */
#include "fuzz_check.h"

#include "scene_json.h"

FUZZ_TARGET("fuzz_json", json_scene_parse, "fuzz.json")
