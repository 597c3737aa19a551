# clwhitted — an OpenCL Whitted ray tracer with a C99 host.
#   make          build build/clwhitted
#   make render   install missing packages, build, render the default scene
#   make test     build and run the whole test suite (on PoCL)

CC      ?= cc
BUILD   := build
PREFIX  ?= /usr/local

# Strict warnings: every host file, every test.
WARN    := -std=c99 -Wall -Wextra -Werror -Wshadow -Wstrict-prototypes \
           -Wmissing-prototypes -Wpointer-arith -Wvla -Wformat=2 -Wundef
OPT     ?= -O2 -g
CPPFLAGS += -D_POSIX_C_SOURCE=200809L -DCL_TARGET_OPENCL_VERSION=120 \
           -Ihost -Ikernels -I$(BUILD)
# Recursively expanded on purpose: pkg-config runs only when a rule needs it, so that
# `make render` can install the packages before anything asks for them.
PKG_CFLAGS = $(shell pkg-config --cflags libpng libcjson OpenEXR 2>/dev/null)
EXR_CORE   = $(or $(filter -lOpenEXRCore%,$(shell pkg-config --libs OpenEXR 2>/dev/null)),-lOpenEXRCore)
LDLIBS     = -lOpenCL $(shell pkg-config --libs libpng libcjson 2>/dev/null) $(EXR_CORE) -lm
CFLAGS  += $(WARN) $(OPT) $(PKG_CFLAGS)

KERNEL_SRC := kernels/compat.h kernels/types.h kernels/camera.h kernels/intersect.h \
              kernels/shade.h kernels/clwhitted.cl
LIB_SRC := $(filter-out host/main.c,$(wildcard host/*.c))
LIB_OBJ := $(patsubst host/%.c,$(BUILD)/%.o,$(LIB_SRC)) $(BUILD)/kernels_src.o
TEST_SRC := $(wildcard tests/test_*.c)
TEST_BIN := $(patsubst tests/%.c,$(BUILD)/%,$(TEST_SRC))
DEFAULT_SCENE := scenes/default.json

.PHONY: all render test clean deps format format-check
all: $(BUILD)/clwhitted $(BUILD)/scene2pov

$(BUILD):
	mkdir -p $(BUILD)

# The kernel sources are embedded in the binary, concatenated with #line markers.
$(BUILD)/kernels_src.c: $(KERNEL_SRC) tools/embed-kernels.sh | $(BUILD)
	sh tools/embed-kernels.sh $(KERNEL_SRC) > $@.tmp && mv $@.tmp $@

$(BUILD)/kernels_src.o: $(BUILD)/kernels_src.c
	$(CC) $(CPPFLAGS) $(CFLAGS) -c $< -o $@

$(BUILD)/%.o: host/%.c $(wildcard host/*.h) kernels/types.h kernels/compat.h | $(BUILD)
	$(CC) $(CPPFLAGS) $(CFLAGS) -c $< -o $@

$(BUILD)/clwhitted: $(BUILD)/main.o $(LIB_OBJ)
	$(CC) $(LDFLAGS) $^ $(LDLIBS) -o $@

# Converts a scene to POV-Ray SDL with the same model (for comparisons and benchmarks).
$(BUILD)/scene2pov: tools/scene2pov.c $(LIB_OBJ)
	$(CC) $(CPPFLAGS) $(CFLAGS) $< $(LIB_OBJ) $(LDLIBS) -o $@

$(BUILD)/test_%: tests/test_%.c tests/testutil.h $(LIB_OBJ) $(KERNEL_SRC) $(wildcard host/*.h)
	$(CC) $(CPPFLAGS) -Itests $(CFLAGS) $< $(LIB_OBJ) $(LDLIBS) -lcmocka -o $@

deps:
	sh tools/install-deps

render: deps
	$(MAKE) all
	$(BUILD)/clwhitted -o $(BUILD)/default.exr $(DEFAULT_SCENE)
	$(BUILD)/clwhitted -o $(BUILD)/default.png $(DEFAULT_SCENE)
	@echo "Rendered $(DEFAULT_SCENE): $(BUILD)/default.exr (linear) and $(BUILD)/default.png (sRGB)"

# Each test binary runs from the repository root; all of them run even if one fails.
test: $(BUILD)/clwhitted $(TEST_BIN)
	@fail=0; for t in $(TEST_BIN); do \
	    echo "== $$t"; $$t || fail=1; \
	done; \
	sh tests/cli.sh $(BUILD)/clwhitted || fail=1; \
	sh tests/quality.sh $(BUILD)/clwhitted $(BUILD)/imgtool || fail=1; \
	if [ $$fail -ne 0 ]; then echo "make test: FAILED"; exit 1; fi; echo "make test: all passed"

format:
	clang-format -i host/*.c host/*.h tests/*.c tests/*.h

format-check:
	clang-format --dry-run -Werror host/*.c host/*.h tests/*.c tests/*.h

clean:
	rm -rf $(BUILD)

# --- Speed against error (tools/quality-report) ---
# build/imgtool: image conversions for the report (EXR to raw float32). `make quality` runs
# the report on three SPD scenes (they live outside the repository: QUALITY_SCENES), writes
# the figure and the tables to docs/quality/ and the README's table (about 20 minutes on two
# cores). QUALITY_ARGS="--replot" redoes the outputs from the last run without rendering.
QUALITY_SCENES ?= ../shared/scenes/spd/tetra.nff ../shared/scenes/spd/balls.nff \
                  ../shared/scenes/spd/teapot.nff
QUALITY_ARGS   ?=
.PHONY: quality
all: $(BUILD)/imgtool
test: $(BUILD)/imgtool

$(BUILD)/imgtool: tools/imgtool.c $(LIB_OBJ)
	$(CC) $(CPPFLAGS) $(CFLAGS) $< $(LIB_OBJ) $(LDLIBS) -o $@

quality: $(BUILD)/clwhitted $(BUILD)/imgtool
	tools/quality-report --figure docs/quality/quality.png --table docs/quality/quality.md \
	    --readme README.md $(QUALITY_ARGS) $(QUALITY_SCENES)
